//! *Save image* without egui: the export beside the views, the offscreen render on whatever
//! adapter the machine has (lavapipe on CI), the asynchronous read-back polled frame by frame,
//! and the PNG handed to the host.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use crate::clocked;
use clocked::Clocked;

use stance_editor::cast_models::CastModels;
use stance_editor::image::{IMAGE_FILE_NAME, ImageExport, ImageRequest};
use stance_editor::model::Outbox;
use stance_editor::{MemoryHost, OTHER_COLOR_LINEAR};
use stance_render::{ImageOptions, OrbitCamera, SceneRenderer, headless_gpu};

/// A decoded PNG: width, height, RGBA.
fn decode(bytes: &[u8]) -> (u32, u32, Vec<u8>) {
    let mut reader = png::Decoder::new(std::io::Cursor::new(bytes.to_vec()))
        .read_info()
        .unwrap();
    let mut rgba = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut rgba).unwrap();
    (info.width, info.height, rgba)
}

/// Moves the export's requests along, frame by frame (a millisecond apart), until none is
/// left; the outbox with what it sent. Fails after 4,000 frames.
fn run(
    image: &mut ImageExport,
    editor: &Clocked,
    gpu: &stance_render::HeadlessGpu,
    renderer: &mut SceneRenderer,
    cast: &CastModels,
) -> Outbox {
    let mut outbox = Outbox::default();
    let mut frames = 0;
    while image.advance(
        &editor.model,
        &mut outbox,
        &gpu.device,
        &gpu.queue,
        renderer,
        cast,
    ) {
        frames += 1;
        assert!(frames < 4000, "the export never came back");
        std::thread::sleep(std::time::Duration::from_millis(1));
    }
    outbox
}

/// Asks for an image with `options` and moves it along, frame by frame, until the host has
/// it; returns the PNG's bytes.
fn save_image(editor: &mut Clocked, host: &MemoryHost, options: ImageOptions) -> Vec<u8> {
    save_image_with(editor, host, options, false)
}

/// The models the characters of `editor` are drawn on, on the GPU as the viewport puts them
/// there (the mannequin's figure when `figure`, else capsules; the characters' avatars), every
/// upload stepped to its end.
fn models_up(
    editor: &Clocked,
    gpu: &stance_render::HeadlessGpu,
    renderer: &mut SceneRenderer,
    cast: &mut CastModels,
    figure: bool,
) {
    cast.update(&editor.model, renderer, &gpu.device, &gpu.queue, figure)
        .expect("the figure");
    while cast.upload_share(renderer, &gpu.device, &gpu.queue, usize::MAX, f64::INFINITY) {}
}

/// [`save_image`], with the mannequin drawn as its figure (uploaded as the viewport does) when
/// `figure`.
fn save_image_with(
    editor: &mut Clocked,
    host: &MemoryHost,
    options: ImageOptions,
    figure: bool,
) -> Vec<u8> {
    let gpu = headless_gpu().expect("an adapter (lavapipe)");
    let mut renderer = SceneRenderer::new(&gpu.device);
    let mut cast = CastModels::default();
    models_up(editor, &gpu, &mut renderer, &mut cast, figure);
    save_image_on(editor, host, options, (&gpu, &mut renderer, &cast))
}

/// [`save_image`] on `renderer`, whose models `cast` says.
fn save_image_on(
    editor: &mut Clocked,
    host: &MemoryHost,
    options: ImageOptions,
    (gpu, renderer, cast): (&stance_render::HeadlessGpu, &mut SceneRenderer, &CastModels),
) -> Vec<u8> {
    let before = host.inner.borrow().binary_downloads.len();
    let mut image = ImageExport::default();
    image.request(ImageRequest {
        options,
        camera: OrbitCamera::default(),
        map: None,
    });
    let mut outbox = run(&mut image, editor, gpu, renderer, cast);
    editor.model.apply_outbox(&mut outbox);
    let downloads = &host.inner.borrow().binary_downloads;
    assert_eq!(downloads.len(), before + 1, "{:?}", editor.model.notice());
    let (name, bytes) = downloads.last().unwrap();
    assert_eq!(name, IMAGE_FILE_NAME);
    bytes.clone()
}

#[test]
fn save_image_downloads_a_png_of_the_chosen_size_and_overlays_change_its_pixels() {
    // Catches: the command lost, the read-back never polled to completion, the size not
    // honoured, the overlays switch ignored.
    let host = MemoryHost::default();
    let mut editor = Clocked::with_host(host.clone());
    editor.settle();
    let options = ImageOptions {
        size_px: [240, 180],
        transparent: false,
        overlays: true,
    };
    let with = decode(&save_image(&mut editor, &host, options));
    let without = decode(&save_image(
        &mut editor,
        &host,
        ImageOptions {
            overlays: false,
            ..options
        },
    ));
    assert_eq!((with.0, with.1), (240, 180));
    assert_eq!((without.0, without.1), (240, 180));
    let differing = with
        .2
        .chunks(4)
        .zip(without.2.chunks(4))
        .filter(|(a, b)| a != b)
        .count();
    // The floor covers the lower part of the picture.
    assert!(differing > 240 * 180 / 10, "{differing} pixels differ");
    // Both opaque, and the body is in both.
    assert!(with.2.chunks(4).all(|p| p[3] == 255));
    let middle = ((90 * 240 + 120) * 4) as usize;
    assert_eq!(with.2[middle..middle + 4], without.2[middle..middle + 4]);
}

#[test]
fn a_transparent_image_without_overlays_is_clear_around_the_figure() {
    // Catches: the transparent option dropped between the dialog's command and the render.
    let host = MemoryHost::default();
    let mut editor = Clocked::with_host(host.clone());
    let (width, height, rgba) = decode(&save_image(
        &mut editor,
        &host,
        ImageOptions {
            size_px: [160, 160],
            transparent: true,
            overlays: false,
        },
    ));
    let alpha = |x: u32, y: u32| rgba[((y * width + x) * 4 + 3) as usize];
    assert_eq!(alpha(0, 0), 0);
    assert_eq!(alpha(width - 1, height - 1), 0);
    assert_eq!(alpha(width / 2, height / 2), 255, "the body's middle");
}

#[test]
fn an_impossible_size_is_refused_with_a_notice_and_nothing_downloads() {
    // Catches: a panic or a clamped image when the size is beyond the GPU's limits.
    let host = MemoryHost::default();
    let mut editor = Clocked::with_host(host.clone());
    let gpu = headless_gpu().unwrap();
    let mut renderer = SceneRenderer::new(&gpu.device);
    let mut image = ImageExport::default();
    image.request(ImageRequest {
        options: ImageOptions {
            size_px: [0, 100],
            ..ImageOptions::default()
        },
        camera: OrbitCamera::default(),
        map: None,
    });
    let mut outbox = Outbox::default();
    assert!(!image.advance(
        &editor.model,
        &mut outbox,
        &gpu.device,
        &gpu.queue,
        &mut renderer,
        &CastModels::default()
    ));
    editor.model.apply_outbox(&mut outbox);
    assert!(host.inner.borrow().binary_downloads.is_empty());
    let notice = editor.model.notice().unwrap();
    assert!(
        notice.is_error && notice.text.contains("0x100"),
        "{notice:?}"
    );
}

#[test]
fn file_export_control_maps_downloads_the_openpose_image_and_its_keypoints() {
    // Catches: the menu entry or the window's button not wired, the size asked ignored, the
    // JSON or the PNG not handed to the host. No GPU: the OpenPose map is drawn on the CPU.
    use egui_kittest::kittest::Queryable;
    let host = MemoryHost::default();
    let app = stance_editor::StanceApp::without_gpu(Box::new(host.clone())).unwrap();
    let mut harness = crate::common::harness_for(app);
    crate::common::settle(&mut harness);
    harness.get_by_label("File").click();
    harness.run_steps(2);
    harness.get_by_label("Export control maps…").click();
    harness.run_steps(2);
    harness.get_by_label("Export").click();
    harness.run_steps(2);
    let downloads = host.inner.borrow().binary_downloads.clone();
    let names: Vec<&str> = downloads.iter().map(|(name, _)| name.as_str()).collect();
    assert_eq!(names, ["stance-openpose.png", "stance-openpose.json"]);
    let (width, height, rgba) = decode(&downloads[0].1);
    assert_eq!((width, height), (1024, 1024));
    assert!(
        rgba.chunks(4).any(|pixel| pixel[..3] != [0, 0, 0]),
        "a skeleton is drawn"
    );
    let json: serde_json::Value = serde_json::from_slice(&downloads[1].1).unwrap();
    assert_eq!(json["canvas_width"], 1024);
    let body = json["people"][0]["pose_keypoints_2d"].as_array().unwrap();
    assert_eq!(body.len(), 54);
}

#[test]
fn the_rendered_control_maps_come_one_after_another_as_their_own_downloads() {
    // Catches: a queued map lost after the first, a map drawn shaded or on the grey
    // background, the files misnamed, line art's second pass lost. Timed: the four maps at
    // 1024x1024 (software GL here).
    use stance_editor::model::RenderedMap;
    let host = MemoryHost::default();
    let mut editor = Clocked::with_host(host.clone());
    editor.settle();
    let gpu = headless_gpu().expect("an adapter (lavapipe)");
    let mut renderer = SceneRenderer::new(&gpu.device);
    let mut image = ImageExport::default();
    let started = std::time::Instant::now();
    image.request_all(
        RenderedMap::ALL
            .into_iter()
            .map(|map| ImageRequest {
                options: ImageOptions {
                    size_px: [1024, 1024],
                    transparent: false,
                    overlays: false,
                },
                camera: OrbitCamera::default(),
                map: Some(map),
            })
            .collect(),
    );
    let mut outbox = run(
        &mut image,
        &editor,
        &gpu,
        &mut renderer,
        &CastModels::default(),
    );
    eprintln!(
        "depth, normal, mask and line-art maps at 1024x1024 in {:.2} s on {}",
        started.elapsed().as_secs_f64(),
        gpu.adapter.name
    );
    editor.model.apply_outbox(&mut outbox);
    let downloads = host.inner.borrow().binary_downloads.clone();
    let names: Vec<&str> = downloads.iter().map(|(name, _)| name.as_str()).collect();
    assert_eq!(
        names,
        [
            "stance-depth.png",
            "stance-normal.png",
            "stance-mask.png",
            "stance-lines.png"
        ]
    );
    for (name, bytes) in &downloads {
        let (width, height, rgba) = decode(bytes);
        assert_eq!((width, height), (1024, 1024));
        assert_eq!(&rgba[..4], &[0, 0, 0, 255], "{name}: black background");
        let covered = rgba.chunks(4).filter(|p| p[..3] != [0, 0, 0]).count();
        assert!(covered > 5000, "{name}: {covered} pixels of figure");
        if name.contains("mask") || name.contains("lines") {
            assert!(
                rgba.chunks(4).all(|p| p[0] == p[1] && p[1] == p[2]),
                "grey levels"
            );
        }
        if name.contains("normal") {
            // Some of the body faces the camera: about (128, 128, 255).
            let facing = rgba
                .chunks(4)
                .filter(|p| p[0].abs_diff(128) < 20 && p[1].abs_diff(128) < 20 && p[2] > 235)
                .count();
            assert!(facing > 500, "{facing} pixels face the camera");
        }
    }
}

/// The editor with a second character added and placed 0.7 m to the first one's right (-X),
/// and that placement.
fn two_characters(host: &MemoryHost) -> (Clocked, stance_document::Placement) {
    use stance_editor::Command;
    use stance_editor::model::SceneCommand;
    let mut editor = Clocked::with_host(host.clone());
    editor.apply(Command::Scene(SceneCommand::Add));
    let second = editor.model.character().id();
    let placement = stance_document::Placement::at([-0.7, 0.0, 0.0]);
    editor.apply(Command::Scene(SceneCommand::Place(second, placement)));
    (editor, placement)
}

/// A 320x240 image's pixel (RGBA) where the default camera sees `point`; with the environment
/// variable `keep` set to a file name the PNG is kept there, to look at.
fn seen_at(png: &[u8], keep: &str) -> impl Fn(glam::Vec3) -> [u8; 4] {
    if let Ok(path) = std::env::var(keep) {
        std::fs::write(path, png).unwrap();
    }
    let (width, _, rgba) = decode(png);
    move |point| {
        let at = OrbitCamera::default()
            .project(point, glam::Vec2::new(320.0, 240.0))
            .expect("in front of the camera");
        let i = ((at.y.round() as u32 * width + at.x.round() as u32) * 4) as usize;
        [rgba[i], rgba[i + 1], rgba[i + 2], rgba[i + 3]]
    }
}

#[test]
fn the_image_shows_every_character_and_prop_where_they_stand() {
    // Catches: other characters or props left out of the picture, a placement ignored.
    use stance_document::PropShape;
    use stance_editor::Command;
    use stance_editor::model::SceneCommand;
    let host = MemoryHost::default();
    let (mut editor, placement) = two_characters(&host);
    editor.apply(Command::Scene(SceneCommand::AddProp(PropShape::Box {
        size: [0.3, 0.3, 0.3],
    })));
    let mut prop = editor.model.props()[0].clone();
    prop.position = [0.7, 0.15, 0.0];
    editor.apply(Command::Scene(SceneCommand::EditProp(0, prop)));
    editor.settle();
    let png = save_image(
        &mut editor,
        &host,
        ImageOptions {
            size_px: [320, 240],
            transparent: true,
            overlays: false,
        },
    );
    let pixel = seen_at(&png, "STANCE_SCENE_PNG");
    // The box: opaque, wood-coloured (more red than blue).
    let box_pixel = pixel(glam::Vec3::new(0.7, 0.15, 0.15));
    assert_eq!(box_pixel[3], 255, "{box_pixel:?}");
    assert!(box_pixel[0] > box_pixel[2] + 20, "{box_pixel:?}");
    // The second character stands where it was placed: its pelvis is drawn there, and the
    // first one's (at the origin) too.
    let pelvis = editor
        .model
        .character()
        .session()
        .joint_position("sacroiliac")
        .unwrap();
    let placed = placement.scene_from_character().transform_point3(pelvis);
    assert_eq!(pixel(placed.as_vec3())[3], 255);
    assert_eq!(pixel(pelvis.as_vec3())[3], 255);
    // Between them, at pelvis height, nothing.
    assert_eq!(
        pixel(glam::Vec3::new(-0.35, pelvis.y as f32 + 0.3, 0.0))[3],
        0
    );
}

#[test]
fn characters_on_the_mannequin_are_all_drawn_as_its_figure() {
    // Catches: a second pose of the uploaded model not drawn (the other character would be
    // missing, or grey capsules in the figure's place).
    let host = MemoryHost::default();
    let (mut editor, placement) = two_characters(&host);
    editor.settle();
    let options = ImageOptions {
        size_px: [320, 240],
        transparent: true,
        overlays: false,
    };
    let png = save_image_with(&mut editor, &host, options, true);
    let colour = seen_at(&png, "STANCE_FIGURES_PNG");
    let pelvis = editor
        .model
        .character()
        .session()
        .joint_position("sacroiliac")
        .unwrap();
    let first = colour(pelvis.as_vec3());
    let placed = colour(
        placement
            .scene_from_character()
            .transform_point3(pelvis)
            .as_vec3(),
    );
    assert_eq!((first[3], placed[3]), (255, 255), "{first:?} {placed:?}");
    // Both drawn by the figure's materials: not the grey of the other characters' capsules.
    let grey = |p: [u8; 4]| p[0].abs_diff(p[2]) < 12 && p[0].abs_diff(p[1]) < 12;
    assert!(!grey(first) && !grey(placed), "{first:?} {placed:?}");
}

#[test]
fn a_mesh_prop_is_drawn_with_its_own_triangles_where_it_stands() {
    // Catches: a mesh prop drawn as its box (the props' wood colour) or not at all, its
    // placement or size ignored. The file is a green box written by the scene exporter.
    use stance_asset::{SceneContent, SceneNode, StaticMesh, export_scene_glb};
    use stance_document::{Prop, PropShape};
    use stance_editor::Command;
    use stance_editor::model::SceneCommand;
    let unit = Prop::new(
        "crate".into(),
        PropShape::Box {
            size: [1.0, 1.0, 1.0],
        },
        [0.0; 3],
    );
    let green = StaticMesh {
        color_linear: [0.05, 0.6, 0.05, 1.0],
        ..stance_render::prop_static_mesh(&unit)
    };
    let glb = export_scene_glb(&[SceneNode {
        name: "crate".into(),
        scene_from_node: glam::DAffine3::IDENTITY,
        content: SceneContent::Mesh(std::slice::from_ref(&green)),
    }])
    .unwrap();
    let host = MemoryHost::default();
    let (mut editor, _) = two_characters(&host);
    editor.apply(Command::Scene(SceneCommand::AddMeshProp {
        file: "crate.glb".into(),
        bytes: glb,
    }));
    let mut prop = editor.model.props()[0].clone();
    prop.position = [0.7, 0.15, 0.0];
    prop.shape = prop.shape.with_dimensions(&[0.3, 0.3, 0.3]).unwrap();
    editor.apply(Command::Scene(SceneCommand::EditProp(0, prop)));
    editor.settle();
    let png = save_image(
        &mut editor,
        &host,
        ImageOptions {
            size_px: [320, 240],
            transparent: true,
            overlays: false,
        },
    );
    let pixel = seen_at(&png, "STANCE_MESH_PROP_PNG");
    // Its front face: opaque and green.
    let front = pixel(glam::Vec3::new(0.7, 0.15, 0.15));
    assert_eq!(front[3], 255, "{front:?}");
    assert!(
        front[1] > front[0] + 20 && front[1] > front[2] + 20,
        "{front:?}"
    );
    // Above it (0.3 m wide, 0.3 m high from the floor): not green.
    let above = pixel(glam::Vec3::new(0.7, 0.45, 0.15));
    assert!(above[3] == 0 || above[1] <= above[0] + 20, "{above:?}");
}

const SHARED_AVATAR: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../../tests/fixtures/avatars/Black_F_2_Casual.glb"
);

/// The editor with a character on the shared avatar at the origin and, selected, one on the
/// mannequin placed 0.7 m to its right (-X); the first one's id.
fn avatar_beside_the_mannequin(host: &MemoryHost) -> (Clocked, u64) {
    use stance_editor::Command;
    use stance_editor::model::SceneCommand;
    let mut editor = Clocked::with_host(host.clone());
    let bytes = std::fs::read(SHARED_AVATAR).expect("the avatar is in tests/fixtures/avatars");
    crate::clocked::open(&mut editor.model, "Black_F_2_Casual.glb", &bytes);
    assert!(
        editor.model.avatar().is_some(),
        "{:?}",
        editor.model.notice()
    );
    let on_avatar = editor.model.character().id();
    editor.apply(Command::Scene(SceneCommand::Add));
    let mannequin = editor.model.character().id();
    let placement = stance_document::Placement::at([-0.7, 0.0, 0.0]);
    editor.apply(Command::Scene(SceneCommand::Place(mannequin, placement)));
    editor.settle();
    assert!(editor.model.avatar().is_none(), "the mannequin is selected");
    (editor, on_avatar)
}

/// Whether an image's pixel has the hue of the other characters' capsules
/// ([`OTHER_COLOR_LINEAR`], lit: its channels in the same ratios, a highlight nearer white).
fn capsule_grey(pixel: [u8; 4]) -> bool {
    let linear = |c: u8| {
        let c = f32::from(c) / 255.0;
        if c <= 0.04045 {
            c / 12.92
        } else {
            ((c + 0.055) / 1.055).powf(2.4)
        }
    };
    let [r, g, b] = [pixel[0], pixel[1], pixel[2]].map(linear);
    let [r0, g0, b0, _] = OTHER_COLOR_LINEAR;
    r > 0.005 && (g / r - g0 / r0).abs() < 0.05 && (0.98..b0 / r0 + 0.05).contains(&(b / r))
}

/// What an image shows of a character: of its opaque pixels, how many have the capsules' hue
/// and how many the shared avatar's skin (brown: red over green over blue) and jeans (blue
/// over red), which no capsule or figure has.
#[derive(Debug, Default)]
struct Seen {
    opaque: usize,
    grey: usize,
    skin: usize,
    jeans: usize,
}

/// [`Seen`] in an image of `size_px` seen by the default camera, over the character not
/// selected whose id is `id`: from its head down to its knees, as wide as half that.
fn seen_of(png: &[u8], editor: &Clocked, id: u64, size_px: [u32; 2]) -> Seen {
    let (width, height, rgba) = decode(png);
    assert_eq!([width, height], size_px);
    let character = editor
        .model
        .other_characters()
        .iter()
        .find(|c| c.id() == id)
        .unwrap();
    let place = character.placement().scene_from_character();
    let at = |joint: &str| {
        let point = place.transform_point3(character.session().joint_position(joint).unwrap());
        OrbitCamera::default()
            .project(
                point.as_vec3(),
                glam::Vec2::new(width as f32, height as f32),
            )
            .expect("in front of the camera")
    };
    let (pelvis, knee, head) = (at("sacroiliac"), at("l_knee"), at("skullbase"));
    let tall = (knee.y - head.y).abs();
    let top = (head.y.min(knee.y) - 0.15 * tall).max(0.0);
    let mut seen = Seen::default();
    for y in top as u32..head.y.max(knee.y) as u32 {
        for x in (pelvis.x - tall / 4.0).max(0.0) as u32..(pelvis.x + tall / 4.0) as u32 {
            let i = ((y * width + x) * 4) as usize;
            let pixel: [u8; 4] = rgba[i..i + 4].try_into().unwrap();
            if pixel[3] < 255 {
                continue;
            }
            let [r, g, b, _] = pixel.map(i32::from);
            seen.opaque += 1;
            seen.grey += usize::from(capsule_grey(pixel));
            seen.skin += usize::from(r > g && g > b && r >= b + 25);
            seen.jeans += usize::from(b >= r + 20);
        }
    }
    seen
}

#[test]
fn characters_on_an_avatar_not_the_selected_ones_are_drawn_on_it_and_its_model_goes_with_them() {
    // Catches: a character drawn as grey capsules because its avatar is not the selected
    // one's body (here the mannequin), its avatar uploaded once per character on it, its
    // model kept on the GPU after the last character on it is removed.
    use stance_editor::Command;
    use stance_editor::model::SceneCommand;
    let host = MemoryHost::default();
    let (mut editor, on_avatar) = avatar_beside_the_mannequin(&host);
    // A second character on the same avatar file, 0.7 m to the left (+X); the mannequin
    // selected again.
    let mannequin = editor.model.character().id();
    editor.apply(Command::Scene(SceneCommand::Select(on_avatar)));
    editor.apply(Command::Scene(SceneCommand::Duplicate));
    let copy = editor.model.character().id();
    let placement = stance_document::Placement::at([0.7, 0.0, 0.0]);
    editor.apply(Command::Scene(SceneCommand::Place(copy, placement)));
    editor.apply(Command::Scene(SceneCommand::Select(mannequin)));
    editor.settle();
    let gpu = headless_gpu().expect("an adapter (lavapipe)");
    let mut renderer = SceneRenderer::new(&gpu.device);
    let mut cast = CastModels::default();
    models_up(&editor, &gpu, &mut renderer, &mut cast, true);
    assert_eq!(
        renderer.cast_model_count(),
        1,
        "one model for the avatar file"
    );
    // Nothing more to upload the next frame.
    models_up(&editor, &gpu, &mut renderer, &mut cast, true);
    cast.update(&editor.model, &mut renderer, &gpu.device, &gpu.queue, true)
        .unwrap();
    assert!(!cast.is_uploading());
    assert_eq!(renderer.cast_model_count(), 1);
    let started = std::time::Instant::now();
    let others = cast.others(&editor.model, Some(&renderer));
    eprintln!(
        "the others' poses (two on the avatar) in {:.2} ms",
        started.elapsed().as_secs_f64() * 1e3
    );
    assert_eq!(
        (others.cast_poses.len(), others.capsules.len()),
        (2, 0),
        "both characters on the avatar drawn on its model"
    );
    let size_px = [480, 360];
    let options = ImageOptions {
        size_px,
        transparent: true,
        overlays: false,
    };
    let png = save_image_on(&mut editor, &host, options, (&gpu, &mut renderer, &cast));
    if let Ok(path) = std::env::var("STANCE_CAST_PNG") {
        std::fs::write(path, &png).unwrap();
    }
    for id in [on_avatar, copy] {
        let seen = seen_of(&png, &editor, id, size_px);
        eprintln!("character {id}: {seen:?}");
        // Drawn as capsules, every opaque pixel there would have their hue.
        assert!(
            seen.skin > 100 && seen.jeans > 300 && seen.grey * 2 < seen.opaque,
            "character {id}, not drawn on its avatar: {seen:?}"
        );
    }
    // The model stays while a character is on it, and goes with the last one.
    editor.apply(Command::Scene(SceneCommand::Remove(copy)));
    models_up(&editor, &gpu, &mut renderer, &mut cast, true);
    assert_eq!(renderer.cast_model_count(), 1);
    editor.apply(Command::Scene(SceneCommand::Remove(on_avatar)));
    models_up(&editor, &gpu, &mut renderer, &mut cast, true);
    assert_eq!(renderer.cast_model_count(), 0, "the avatar's model dropped");
    assert!(!cast.is_uploading());
}

#[test]
fn selecting_another_character_hands_the_models_over_without_uploading_them_again() {
    // Catches: the selected character's avatar uploaded again when it is on the GPU already
    // (among the cast's models), the figure lost from the GPU (uploaded again) when an avatar
    // takes the avatar's place, a model drawn from both places.
    use stance_editor::Command;
    use stance_editor::cast_models::ModelKey;
    use stance_editor::model::SceneCommand;
    let host = MemoryHost::default();
    let (mut editor, on_avatar) = avatar_beside_the_mannequin(&host);
    let gpu = headless_gpu().expect("an adapter (lavapipe)");
    let mut renderer = SceneRenderer::new(&gpu.device);
    let mut cast = CastModels::default();
    models_up(&editor, &gpu, &mut renderer, &mut cast, true);
    assert!(
        renderer.avatar().is_some(),
        "the figure in the avatar's place"
    );
    assert_eq!(
        renderer.cast_model_count(),
        1,
        "the avatar among the cast's"
    );
    // The avatar's character selected: its model, made again by the model, is handed over
    // as the viewport hands it (`begin_avatar_upload`).
    editor.apply(Command::Scene(SceneCommand::Select(on_avatar)));
    let avatar = editor.model.avatar().unwrap();
    let mesh = avatar.mesh().cloned().expect("its model, to upload");
    let uploading = cast.begin_selected(&mut renderer, ModelKey::of_avatar(avatar), mesh);
    assert!(!uploading, "taken from the cast's models");
    assert!(!renderer.is_uploading_avatar());
    assert_eq!(
        renderer.avatar().map(|gpu| gpu.triangle_count()),
        Some(avatar.triangle_count)
    );
    // The figure, now the other character's, went to the cast's models: nothing to upload.
    cast.update(&editor.model, &mut renderer, &gpu.device, &gpu.queue, true)
        .unwrap();
    assert!(!cast.is_uploading(), "the figure uploaded again");
    assert_eq!(renderer.cast_model_count(), 1);
    let others = cast.others(&editor.model, Some(&renderer));
    assert_eq!(
        (others.cast_poses.len(), others.more_avatar_poses.len()),
        (1, 0)
    );
}

#[test]
fn an_avatar_on_its_way_when_another_character_is_selected_goes_on_among_the_casts() {
    // Catches: the upload of the avatar left dropped (begun again from the start, its model
    // made again from the file) when the selection changes before it is complete.
    use stance_editor::Command;
    use stance_editor::cast_models::ModelKey;
    use stance_editor::model::SceneCommand;
    let host = MemoryHost::default();
    let (mut editor, on_avatar) = avatar_beside_the_mannequin(&host);
    let mannequin = editor.model.character().id();
    let gpu = headless_gpu().expect("an adapter (lavapipe)");
    let (device, queue) = (&gpu.device, &gpu.queue);
    let mut renderer = SceneRenderer::new(device);
    let mut cast = CastModels::default();
    editor.apply(Command::Scene(SceneCommand::Select(on_avatar)));
    let avatar = editor.model.avatar().unwrap();
    let mesh = avatar.mesh().cloned().unwrap();
    // The steps of its whole upload.
    let mut fresh = stance_render::AvatarUpload::new(mesh.clone());
    let whole = (1..100)
        .find(|_| renderer.step_upload(&mut fresh, device, queue).is_some())
        .unwrap();
    assert!(cast.begin_selected(&mut renderer, ModelKey::of_avatar(avatar), mesh));
    for _ in 0..2 {
        assert!(!renderer.continue_avatar_upload(device, queue));
    }
    // The mannequin selected: the figure takes the avatar's place, the avatar goes on.
    editor.apply(Command::Scene(SceneCommand::Select(mannequin)));
    cast.update(&editor.model, &mut renderer, device, queue, true)
        .unwrap();
    assert!(renderer.avatar().is_some() && !renderer.is_uploading_avatar());
    let mut steps = 0;
    while cast.upload_share(&mut renderer, device, queue, 1, f64::INFINITY) {
        steps += 1;
        assert!(steps < 100, "the upload never ends");
    }
    assert_eq!(steps + 1, whole - 2, "the steps left, of {whole}");
    assert_eq!(renderer.cast_model_count(), 1);
    let others = cast.others(&editor.model, Some(&renderer));
    assert_eq!(others.cast_poses.len(), 1);
}
