//! `stance render` end to end on whatever adapter the machine has (lavapipe on CI): the
//! pixels of the PNG it writes, not only the file.

#![allow(clippy::expect_used, clippy::unwrap_used, clippy::panic)]

use std::path::PathBuf;
use std::process::Command;

pub(crate) fn stance(args: &[&str]) -> (bool, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_stance"))
        .args(args)
        .output()
        .expect("runs");
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

pub(crate) fn temp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("stance-render-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

pub(crate) fn write(name: &str, text: &str) -> String {
    let path = temp(name);
    std::fs::write(&path, text).unwrap();
    path.to_string_lossy().into_owned()
}

/// A decoded PNG: width, height, RGBA rows.
pub(crate) struct Image {
    pub(crate) width: u32,
    pub(crate) height: u32,
    pub(crate) rgba: Vec<u8>,
}

impl Image {
    pub(crate) fn alpha(&self, x: u32, y: u32) -> u8 {
        self.rgba[((y * self.width + x) * 4 + 3) as usize]
    }

    /// The bounding box (x0, y0, x1, y1) of the pixels with any coverage.
    fn covered_box(&self) -> (u32, u32, u32, u32) {
        let mut bounds = (u32::MAX, u32::MAX, 0, 0);
        for y in 0..self.height {
            for x in 0..self.width {
                if self.alpha(x, y) > 0 {
                    bounds = (
                        bounds.0.min(x),
                        bounds.1.min(y),
                        bounds.2.max(x),
                        bounds.3.max(y),
                    );
                }
            }
        }
        assert!(bounds.0 <= bounds.2, "nothing drawn");
        bounds
    }

    fn covered_count(&self) -> usize {
        self.rgba.chunks(4).filter(|p| p[3] > 0).count()
    }
}

pub(crate) fn decode(path: &PathBuf) -> Image {
    let bytes = std::fs::read(path).unwrap();
    let mut reader = png::Decoder::new(std::io::Cursor::new(bytes))
        .read_info()
        .unwrap();
    let mut rgba = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut rgba).unwrap();
    assert_eq!(info.color_type, png::ColorType::Rgba);
    Image {
        width: info.width,
        height: info.height,
        rgba,
    }
}

/// Renders `document` with `args` into a new PNG and decodes it.
pub(crate) fn render(document: &str, name: &str, args: &[&str]) -> Image {
    let out = temp(name);
    let out_text = out.to_string_lossy().into_owned();
    let mut all = vec!["render", document, "--out", &out_text];
    all.extend_from_slice(args);
    let (ok, err) = stance(&all);
    assert!(ok, "{err}");
    decode(&out)
}

const DEFAULT_DOCUMENT: &str = r#"{"version": 1}"#;

#[test]
fn the_front_view_is_wider_than_the_side_view_and_the_figure_is_centred() {
    // Catches: a view preset ignored (same picture), a figure framed off-centre or cropped.
    let doc = write("default.json", DEFAULT_DOCUMENT);
    let front = render(
        &doc,
        "front.png",
        &["--view", "front", "--size", "300x300", "--transparent"],
    );
    let side = render(
        &doc,
        "side.png",
        &["--view", "left", "--size", "300x300", "--transparent"],
    );
    let (f0, fy0, f1, fy1) = front.covered_box();
    let (s0, sy0, s1, sy1) = side.covered_box();
    let (front_width, side_width) = (f1 - f0, s1 - s0);
    assert!(
        front_width as f32 > 1.4 * side_width as f32,
        "front {front_width} px wide, side {side_width} px"
    );
    for (image, (x0, y0, x1, y1)) in [(&front, (f0, fy0, f1, fy1)), (&side, (s0, sy0, s1, sy1))] {
        let centre = ((x0 + x1) as f32 / 2.0, (y0 + y1) as f32 / 2.0);
        let middle = (image.width as f32 / 2.0, image.height as f32 / 2.0);
        assert!(
            (centre.0 - middle.0).abs() < 25.0 && (centre.1 - middle.1).abs() < 25.0,
            "figure centred at {centre:?}"
        );
        // Framed on the body: tall, but not cropped at the top or bottom.
        assert!(y1 - y0 > image.height / 2 && y0 > 0 && y1 < image.height - 1);
    }
}

#[test]
fn a_transparent_image_is_clear_in_the_corners_and_opaque_in_the_figure() {
    // Catches: the background drawn anyway, alpha lost or left premultiplied in the PNG.
    let doc = write("default-t.json", DEFAULT_DOCUMENT);
    let image = render(
        &doc,
        "t.png",
        &["--view", "front", "--size", "200x260", "--transparent"],
    );
    let (w, h) = (image.width, image.height);
    for (x, y) in [(0, 0), (w - 1, 0), (0, h - 1), (w - 1, h - 1)] {
        assert_eq!(image.alpha(x, y), 0, "corner {x},{y}");
    }
    // The camera aims at the body's middle: the pelvis is at the centre of the image.
    assert_eq!(image.alpha(w / 2, h / 2), 255);
    let middle = ((h / 2 * w + w / 2) * 4) as usize;
    let [r, g, b] = [
        image.rgba[middle],
        image.rgba[middle + 1],
        image.rgba[middle + 2],
    ];
    // The mannequin's figure, as the editor draws it: grey-blue clothes at the pelvis.
    assert!(
        b > r && b > 90,
        "the figure's clothes at the pelvis: {r} {g} {b}"
    );
    // The capsule view: clay-coloured capsules.
    let capsules = render(
        &doc,
        "tc.png",
        &[
            "--view",
            "front",
            "--size",
            "200x260",
            "--transparent",
            "--capsules",
        ],
    );
    let [r, g, b] = [
        capsules.rgba[middle],
        capsules.rgba[middle + 1],
        capsules.rgba[middle + 2],
    ];
    assert!(
        r > 90 && r > g && g > b,
        "clay-coloured capsules: {r} {g} {b}"
    );
    // Without --transparent the background is opaque.
    let opaque = render(&doc, "o.png", &["--view", "front", "--size", "200x260"]);
    assert_eq!(opaque.alpha(0, 0), 255);
}

#[test]
fn the_image_has_exactly_the_size_asked() {
    // Catches: width and height swapped, a row padding leaking into the image.
    let doc = write("default-s.json", DEFAULT_DOCUMENT);
    let image = render(&doc, "size.png", &["--size", "320x200"]);
    assert_eq!((image.width, image.height), (320, 200));
    assert_eq!(image.rgba.len(), 320 * 200 * 4);
}

#[test]
fn raised_arms_reach_above_the_head_where_the_rest_posture_has_nothing() {
    // Catches: the document's posture (or its saved camera) not reaching the picture.
    let camera = r#""camera": {"target": [0, 1.0, 0], "yaw": 0, "pitch": 0, "distance": 4.5}"#;
    let rest = write("rest.json", &format!(r#"{{"version": 1, {camera}}}"#));
    let raised = write(
        "raised.json",
        &format!(
            r#"{{"version": 1, {camera}, "posture": {{"l_shoulder": {{"rz": 2.9}}, "r_shoulder": {{"rz": -2.9}}}}}}"#
        ),
    );
    let rest = render(&rest, "rest.png", &["--size", "240x240", "--transparent"]);
    let raised = render(
        &raised,
        "raised.png",
        &["--size", "240x240", "--transparent"],
    );
    let (_, rest_top, _, rest_bottom) = rest.covered_box();
    let (_, raised_top, _, raised_bottom) = raised.covered_box();
    // The same camera: the feet stay where they were, the hands rise well above the head.
    assert!(
        rest_bottom.abs_diff(raised_bottom) <= 2,
        "{rest_bottom} {raised_bottom}"
    );
    let body_height = rest_bottom - rest_top;
    assert!(
        raised_top + body_height / 10 < rest_top,
        "raised arms top at {raised_top}, the head at {rest_top}"
    );
}

#[test]
fn overlays_add_the_floor_and_the_goals() {
    // Catches: --overlays ignored, or the floor drawn without it.
    let doc = write(
        "goal.json",
        r#"{"version": 1, "tasks": [{"kind": "position", "joint": "l_wrist", "target": [0.5, 1.8, 0.3]}]}"#,
    );
    let plain = render(
        &doc,
        "plain.png",
        &["--view", "front", "--size", "200x200", "--transparent"],
    );
    let overlaid = render(
        &doc,
        "overlaid.png",
        &[
            "--view",
            "front",
            "--size",
            "200x200",
            "--transparent",
            "--overlays",
        ],
    );
    assert!(
        overlaid.covered_count() > plain.covered_count() + 2000,
        "{} vs {}",
        overlaid.covered_count(),
        plain.covered_count()
    );
}

#[test]
fn an_avatar_is_drawn_with_its_skinned_mesh() {
    // Catches: --avatar ignored, palettes that leave the mesh at the origin or collapsed; the
    // default figure not being the editor's (the generated avatar that the site ships as
    // public/default-avatar.glb), or --capsules ignored.
    let avatar = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../public/default-avatar.glb"
    );
    let doc = write(
        "avatar.json",
        r#"{"version": 1, "posture": {"r_shoulder": {"rz": -1.2}, "l_elbow": {"rx": -1.0}}}"#,
    );
    let view = ["--view", "front", "--size", "200x200", "--transparent"];
    let with = |extra: &[&'static str]| -> Vec<&'static str> { [&view[..], extra].concat() };
    let capsules = render(&doc, "m.png", &with(&["--capsules"]));
    let figure = render(&doc, "f.png", &view);
    let image = render(&doc, "a.png", &with(&["--avatar", avatar]));
    let (_, y0, _, y1) = image.covered_box();
    assert!(y1 - y0 > 100, "a standing figure: {y0}..{y1}");
    let differing = |a: &Image, b: &Image| {
        a.rgba
            .chunks(4)
            .zip(b.rgba.chunks(4))
            .filter(|(a, b)| a != b)
            .count()
    };
    assert!(
        differing(&image, &capsules) > 1000,
        "the avatar looks like the capsules"
    );
    // The default figure is that avatar, in the same posture: (nearly) the same picture.
    let same = differing(&figure, &image);
    assert!(
        same < image.covered_count() / 50,
        "{same} pixels differ between the default figure and the avatar it is made of"
    );
    assert!(differing(&figure, &capsules) > 1000);
}

#[test]
fn bad_documents_sizes_and_outputs_fail_with_a_reason_and_write_nothing() {
    // Catches: a panic or a silent success on bad input, a half-written file.
    let good = write("good.json", DEFAULT_DOCUMENT);
    let bad_json = write("bad.json", "{ not json");
    let bad_doc = write(
        "bad-doc.json",
        r#"{"version": 1, "posture": {"l_knee": {"rx": "bent"}}}"#,
    );
    let missing_dir = temp("no-such-dir").join("x.png");
    let missing_dir = missing_dir.to_string_lossy().into_owned();
    let cases: [(&str, &[&str], &str); 6] = [
        (&bad_json, &[], "invalid document"),
        (&bad_doc, &[], "l_knee"),
        (&good, &["--size", "0x200"], "1 to 8192"),
        (&good, &["--size", "9000x100"], "1 to 8192"),
        (&good, &["--size", "big"], "WIDTHxHEIGHT"),
        (&good, &["--out", &missing_dir], "cannot write"),
    ];
    for (index, (document, extra, expected)) in cases.iter().enumerate() {
        let out = temp(&format!("fail-{index}.png"));
        let out_text = out.to_string_lossy().into_owned();
        let mut args = vec!["render", document];
        if !extra.contains(&"--out") {
            args.extend(["--out", &out_text]);
        }
        args.extend_from_slice(extra);
        let (ok, err) = stance(&args);
        assert!(!ok, "case {index} succeeded");
        assert!(err.contains(expected), "case {index}: {err}");
        assert!(!err.contains("panicked"), "case {index}: {err}");
        assert!(!out.exists(), "case {index} wrote {}", out.display());
        assert!(!std::path::Path::new(&missing_dir).exists());
    }
}

/// Runs `stance render DOC --map openpose` with `args`: the decoded skeleton image and the
/// keypoints' JSON.
pub(crate) fn openpose(document: &str, name: &str, args: &[&str]) -> (Image, serde_json::Value) {
    let keypoints = temp(&format!("{name}.json"));
    let keypoints_text = keypoints.to_string_lossy().into_owned();
    let mut all = vec!["--map", "openpose", "--keypoints-out", &keypoints_text];
    all.extend_from_slice(args);
    let image = render(document, &format!("{name}.png"), &all);
    let json = serde_json::from_str(&std::fs::read_to_string(&keypoints).unwrap()).unwrap();
    (image, json)
}

pub(crate) fn numbers(value: &serde_json::Value) -> Vec<f64> {
    value
        .as_array()
        .unwrap()
        .iter()
        .map(|n| n.as_f64().unwrap())
        .collect()
}

#[test]
fn the_openpose_keypoints_land_where_the_camera_projects_the_joints() {
    // By hand: the saved camera at (0, 1, 4.5) looks down -Z at (0, 1, 0) with a 40 degree
    // vertical field of view; H-Anim's default l_shoulder is at (0.2029, 1.4376, -0.0387),
    // l_elbow at (0.2014, 1.1357, -0.0682). A point at depth d = 4.5 - z lands at
    // x = W/2 (1 + X / (d tan 20 deg aspect)), y = H/2 (1 - (Y - 1) / (d tan 20 deg)).
    // Catches: a flipped axis or side (the body's left is on the image's right seen from the
    // front), keypoints from the wrong joints, the size or aspect ignored.
    let doc = write(
        "openpose-doc.json",
        r#"{"version": 1, "camera": {"target": [0, 1.0, 0], "yaw": 0, "pitch": 0, "distance": 4.5}}"#,
    );
    let (width, height) = (600.0, 400.0);
    let (image, json) = openpose(&doc, "openpose", &["--size", "600x400"]);
    assert_eq!((image.width, image.height), (600, 400));
    assert_eq!(
        (
            json["canvas_width"].as_u64(),
            json["canvas_height"].as_u64()
        ),
        (Some(600), Some(400))
    );
    let people = json["people"].as_array().unwrap();
    assert_eq!(people.len(), 1);
    let body = numbers(&people[0]["pose_keypoints_2d"]);
    assert_eq!(body.len(), 18 * 3);
    assert_eq!(numbers(&people[0]["hand_left_keypoints_2d"]).len(), 21 * 3);
    assert_eq!(numbers(&people[0]["hand_right_keypoints_2d"]).len(), 21 * 3);
    assert!(
        people[0]["face_keypoints_2d"]
            .as_array()
            .unwrap()
            .is_empty()
    );
    let tan = 20f64.to_radians().tan();
    let project = |[x, y, z]: [f64; 3]| {
        let depth = 4.5 - z;
        (
            width / 2.0 * (1.0 + x / (depth * tan * width / height)),
            height / 2.0 * (1.0 - (y - 1.0) / (depth * tan)),
        )
    };
    // COCO-18: 5 is the left shoulder, 6 the left elbow, 2 the right shoulder.
    for (index, joint) in [
        (5, [0.2029, 1.4376, -0.0387]),
        (6, [0.2014, 1.1357, -0.0682]),
    ] {
        let expected = project(joint);
        let (x, y, c) = (body[index * 3], body[index * 3 + 1], body[index * 3 + 2]);
        assert_eq!(c, 1.0);
        assert!(
            (x - expected.0).abs() < 0.5 && (y - expected.1).abs() < 0.5,
            "keypoint {index} at ({x}, {y}), projected at {expected:?}"
        );
    }
    assert!(body[2 * 3] < width / 2.0 && body[5 * 3] > width / 2.0);
    // The skeleton is drawn where the keypoints are: the left shoulder's point in its colour.
    let at = |x: f64, y: f64| {
        let offset = ((y as u32 * image.width + x as u32) * 4) as usize;
        image.rgba[offset..offset + 3].to_vec()
    };
    assert_eq!(at(body[15], body[16]), vec![85, 255, 0]);
    // Normalised: the same points as fractions of the size.
    let (_, normalized) = openpose(&doc, "openpose-n", &["--size", "600x400", "--normalized"]);
    let fractions = numbers(&normalized["people"][0]["pose_keypoints_2d"]);
    assert!((fractions[15] * width - body[15]).abs() < 0.01);
    assert!((fractions[16] * height - body[16]).abs() < 0.01);
}

#[test]
fn hidden_keypoints_go_missing_on_request_and_a_body_without_fingers_has_no_hands() {
    // Catches: --hidden ignored; hand points made up for a body without finger joints.
    let doc = write("openpose-side.json", DEFAULT_DOCUMENT);
    let side = ["--view", "left", "--size", "400x400"];
    let (_, kept) = openpose(&doc, "side-kept", &side);
    let missing_args = [&side[..], &["--hidden", "missing"]].concat();
    let (_, missing) = openpose(&doc, "side-missing", &missing_args);
    let body = |json: &serde_json::Value| numbers(&json["people"][0]["pose_keypoints_2d"]);
    let seen = |values: &[f64]| values.chunks(3).filter(|p| p[2] > 0.0).count();
    assert_eq!(seen(&body(&kept)), 18);
    // Seen from the left: the right shoulder, hip, eye and ear are behind the body, and left
    // out as 0, 0, 0; the neck and the left side stay.
    let hidden = body(&missing);
    for index in [2, 8, 14, 16] {
        assert_eq!(
            &hidden[index * 3..index * 3 + 3],
            &[0.0, 0.0, 0.0],
            "keypoint {index}"
        );
    }
    for index in [1, 5, 11, 15, 17] {
        assert_eq!(hidden[index * 3 + 2], 1.0, "keypoint {index}");
    }
    let (_, loa1) = openpose(&doc, "loa1", &["--size", "300x300", "--loa", "1"]);
    for hand in ["hand_left_keypoints_2d", "hand_right_keypoints_2d"] {
        assert!(
            numbers(&loa1["people"][0][hand]).iter().all(|v| *v == 0.0),
            "{hand}"
        );
    }
}

#[test]
fn control_map_options_out_of_place_fail_with_a_reason_and_write_nothing() {
    let good = write("map-good.json", DEFAULT_DOCUMENT);
    let keypoints = temp("map-k.json").to_string_lossy().into_owned();
    let cases: [(&[&str], &str); 5] = [
        (
            &["--keypoints-out", &keypoints],
            "--keypoints-out goes with --map openpose",
        ),
        (
            &["--hidden", "missing"],
            "--hidden goes with --map openpose",
        ),
        (
            &["--map", "openpose", "--transparent"],
            "--transparent does not go with --map",
        ),
        (&["--map", "sketch"], "invalid value 'sketch'"),
        (
            &["--map", "openpose", "--keypoints-out", &good],
            "the document itself",
        ),
    ];
    for (index, (extra, expected)) in cases.iter().enumerate() {
        let out = temp(&format!("map-fail-{index}.png"));
        let out_text = out.to_string_lossy().into_owned();
        let mut args = vec!["render", &good, "--out", &out_text];
        args.extend_from_slice(extra);
        let (ok, err) = stance(&args);
        assert!(!ok, "case {index} succeeded");
        assert!(err.contains(expected), "case {index}: {err}");
        assert!(
            !out.exists() && !std::path::Path::new(&keypoints).exists(),
            "case {index} wrote"
        );
    }
    // The document is still there, unchanged (not overwritten by --keypoints-out).
    assert_eq!(std::fs::read_to_string(&good).unwrap(), DEFAULT_DOCUMENT);
}

/// The pixel of `image` at `point_world` seen by `camera`.
pub(crate) fn pixel_at(
    image: &Image,
    camera: &stance_render::OrbitCamera,
    point_world: [f32; 3],
) -> [u8; 4] {
    let size = glam::Vec2::new(image.width as f32, image.height as f32);
    let at = camera
        .project(glam::Vec3::from_array(point_world), size)
        .unwrap();
    let offset = ((at.y as u32 * image.width + at.x as u32) * 4) as usize;
    image.rgba[offset..offset + 4].try_into().unwrap()
}

#[test]
fn the_depth_map_is_bright_near_and_the_normal_map_uses_controlnets_colours() {
    // Catches: depth drawn far-bright (the convention reversed), normals in world rather than
    // view space, a flipped red (left) or green (up) axis, a map drawn on the grey background.
    let turned_camera =
        r#""camera": {"target": [0, 1.0, 0], "yaw": 0.6, "pitch": 0, "distance": 3.0}"#;
    let turned = write(
        "turned.json",
        &format!(r#"{{"version": 1, {turned_camera}}}"#),
    );
    let front = write(
        "front-maps.json",
        r#"{"version": 1, "camera": {"target": [0, 1.45, 0], "yaw": 0, "pitch": 0, "distance": 1.2}}"#,
    );
    let saved = |target: [f64; 3], yaw, distance| {
        stance_render::OrbitCamera::saved(target, yaw, 0.0, distance, false)
    };
    let depth = render(
        &turned,
        "depth.png",
        &["--map", "depth", "--size", "300x300"],
    );
    let camera = saved([0.0, 1.0, 0.0], 0.6, 3.0);
    // Turned toward the body's left: the left shoulder (H-Anim default centre) is nearer.
    let near = pixel_at(&depth, &camera, [0.2029, 1.4376, -0.0387]);
    let far = pixel_at(&depth, &camera, [-0.1907, 1.4407, -0.0325]);
    assert!(
        near[0] > far[0] + 10 && far[0] > 0,
        "near {near:?}, far {far:?}"
    );
    assert_eq!(near[0], near[1]);
    assert_eq!(&depth.rgba[..4], &[0, 0, 0, 255], "the background is black");
    // The head seen from the front: its middle faces the camera, its side on the image's
    // left (the body's right) faces left (red), its top faces up (green).
    let normal = render(
        &front,
        "normal.png",
        &["--map", "normal", "--size", "300x300"],
    );
    let camera = saved([0.0, 1.45, 0.0], 0.0, 1.2);
    let head = [0.0044, 1.6209 + 0.085, 0.0236 + 0.1];
    let facing = pixel_at(&normal, &camera, head);
    assert!(
        facing[0].abs_diff(128) < 25 && facing[1].abs_diff(128) < 25 && facing[2] > 225,
        "{facing:?}"
    );
    let left = pixel_at(&normal, &camera, [head[0] - 0.065, head[1], head[2] - 0.05]);
    assert!(left[0] > 170 && left[2] > 128, "{left:?}");
    let top = pixel_at(&normal, &camera, [head[0], head[1] + 0.1, head[2] - 0.06]);
    assert!(top[1] > 170, "{top:?}");
}

#[test]
fn the_mask_covers_exactly_the_figure_of_the_picture() {
    // Catches: a mask of the capsules rather than of the figure drawn, or with the floor.
    let doc = write("mask.json", DEFAULT_DOCUMENT);
    let mask = render(&doc, "mask.png", &["--map", "mask", "--size", "200x200"]);
    let picture = render(
        &doc,
        "mask-picture.png",
        &["--size", "200x200", "--transparent"],
    );
    let mut differing = 0;
    for (m, p) in mask.rgba.chunks(4).zip(picture.rgba.chunks(4)) {
        assert_eq!((m[0], m[3]), (m[2], 255));
        if (m[0] > 0) != (p[3] > 0) {
            differing += 1;
        }
    }
    let covered = picture.covered_count();
    assert!(covered > 2000, "{covered}");
    assert!(
        differing * 200 <= covered,
        "{differing} of {covered} pixels differ"
    );
}

#[test]
fn line_art_outlines_the_figure_inside_its_mask() {
    // Catches: lines drawn on the background side of the silhouette, a filled figure instead
    // of lines, no inner lines (contours, creases) at all.
    let doc = write("lines.json", DEFAULT_DOCUMENT);
    let size = ["--size", "256x256"];
    let lines = render(
        &doc,
        "lines.png",
        &[&["--map", "lines"][..], &size].concat(),
    );
    let mask = render(
        &doc,
        "lines-mask.png",
        &[&["--map", "mask"][..], &size].concat(),
    );
    let white = |image: &Image, at: usize| image.rgba[at * 4] > 127;
    let count = (lines.width * lines.height) as usize;
    let on_lines: Vec<usize> = (0..count).filter(|&at| white(&lines, at)).collect();
    let figure = (0..count).filter(|&at| white(&mask, at)).count();
    assert!(
        on_lines.iter().all(|&at| mask.rgba[at * 4] > 0),
        "a line off the figure"
    );
    assert!(
        on_lines.len() * 20 > figure && on_lines.len() * 2 < figure,
        "{} line pixels for a figure of {figure}",
        on_lines.len()
    );
    // Inner lines: some line pixels have figure all round them (not on the silhouette).
    let inner = on_lines.iter().filter(|&&at| {
        let (x, y) = (at % 256, at / 256);
        x > 0
            && y > 0
            && x < 255
            && y < 255
            && [at - 1, at + 1, at - 256, at + 256]
                .iter()
                .all(|&n| white(&mask, n))
    });
    assert!(inner.count() > 20);
}

/// A scene of two characters standing 2 m apart (the first on the right, at x = +1, the
/// second turned to face +X at x = -1) and a 0.3 m box on the floor in front between them;
/// `camera`: the first character's saved camera (JSON fields), or none.
fn two_character_scene(name: &str, camera: &str) -> String {
    write(
        name,
        &format!(
            r#"{{"characters": [
                {{"name": "Ann", "placement": {{"position": [1.0, 0, 0], "yaw": 0}}, "version": 1 {camera}}},
                {{"name": "Bob", "placement": {{"position": [-1.0, 0, 0], "yaw": 90}}, "version": 1}}
            ],
            "props": [{{"name": "Crate", "shape": "box", "size": [0.3, 0.3, 0.3], "position": [0, 0.15, 0.6]}}],
            "selected": 0}}"#
        ),
    )
}

pub(crate) const SCENE_CAMERA: &str =
    r#", "camera": {"target": [0, 1.0, 0], "yaw": 0, "pitch": 0, "distance": 6.0}"#;

#[test]
fn a_scene_draws_every_character_and_its_props_where_they_stand() {
    // Catches: only the selected character drawn, a placement (or its turn) ignored, props
    // left out, a default view framed on one character rather than the scene.
    let scene = two_character_scene("scene.json", SCENE_CAMERA);
    let mask = render(
        &scene,
        "scene-mask.png",
        &["--map", "mask", "--size", "400x300"],
    );
    let camera = stance_render::OrbitCamera::saved([0.0, 1.0, 0.0], 0.0, 0.0, 6.0, false);
    let white = |point: [f32; 3]| pixel_at(&mask, &camera, point)[0] > 128;
    for (what, point) in [
        ("Ann's chest", [1.0, 1.2, 0.0]),
        ("Ann's hips", [1.0, 0.95, 0.0]),
        ("Bob's chest", [-1.0, 1.2, 0.0]),
        ("Bob's knees", [-1.0, 0.5, 0.0]),
        ("the crate", [0.0, 0.15, 0.6]),
    ] {
        assert!(white(point), "{what} is not drawn");
    }
    for (what, point) in [
        ("between them", [0.0, 1.2, 0.0]),
        ("at the origin", [0.0, 0.9, 0.0]),
        ("beside Ann", [2.0, 1.2, 0.0]),
    ] {
        assert!(!white(point), "something is drawn {what}");
    }
    // Bob is turned a quarter: seen from the front he shows his side, narrower than Ann.
    let width_at = |x: f32| {
        let y = camera
            .project(glam::Vec3::new(x, 1.2, 0.0), glam::Vec2::new(400.0, 300.0))
            .unwrap()
            .y as u32;
        let centre = camera
            .project(glam::Vec3::new(x, 1.2, 0.0), glam::Vec2::new(400.0, 300.0))
            .unwrap()
            .x as u32;
        let covered = |px: u32| mask.rgba[((y * mask.width + px) * 4) as usize] > 128;
        let left = (0..centre).rev().take_while(|&px| covered(px)).count();
        let right = (centre..mask.width).take_while(|&px| covered(px)).count();
        left + right
    };
    let (ann, bob) = (width_at(1.0), width_at(-1.0));
    assert!(
        ann as f32 > 1.3 * bob as f32,
        "Ann {ann} px wide, Bob {bob} px"
    );

    // The default view takes in the whole scene: both figures, neither cut by the edges,
    // wider than one character alone.
    let framed = two_character_scene("scene-framed.json", "");
    let picture = render(
        &framed,
        "scene-framed.png",
        &["--size", "400x300", "--transparent"],
    );
    let (x0, y0, x1, y1) = picture.covered_box();
    assert!(
        x0 > 0 && y0 > 0 && x1 < 399 && y1 < 299,
        "cut: {x0} {y0} {x1} {y1}"
    );
    // Centred on the scene (on Ann alone, Bob would be off to the left), with an empty
    // column between the two figures.
    let middle = (x0 + x1) as f32 / 2.0;
    assert!((middle - 200.0).abs() < 30.0, "centred at {middle}");
    let empty = (x0..x1).filter(|&x| (0..picture.height).all(|y| picture.alpha(x, y) == 0));
    assert!(empty.count() > 0, "the figures run together");
}

#[test]
fn a_scenes_openpose_map_has_one_person_per_character_in_the_scenes_order() {
    // Catches: one person only (the selected character), people sorted by place rather than
    // the scene's order, keypoints left in each character's own frame (both at the origin).
    let scene = two_character_scene("scene-openpose-doc.json", SCENE_CAMERA);
    let (width, height) = (600.0, 400.0);
    let (_, json) = openpose(&scene, "scene-openpose", &["--size", "600x400"]);
    let people = json["people"].as_array().unwrap();
    assert_eq!(people.len(), 2);
    let neck = |person: &serde_json::Value| {
        let body = numbers(&person["pose_keypoints_2d"]);
        assert_eq!(body[3 + 2], 1.0, "the neck is seen");
        (body[3], body[4])
    };
    let (ann, bob) = (neck(&people[0]), neck(&people[1]));
    // H-Anim's default neck keypoint (between the shoulders) in a character's frame, put in
    // the scene by each placement by hand: Ann moved 1 m along +X; Bob turned a quarter
    // (x, z) -> (z, -x), then moved 1 m along -X.
    let own = [0.0061, 1.43915, -0.0356];
    let placed = [
        [own[0] + 1.0, own[1], own[2]],
        [own[2] - 1.0, own[1], -own[0]],
    ];
    let camera = stance_render::OrbitCamera::saved([0.0, 1.0, 0.0], 0.0, 0.0, 6.0, false);
    for ((who, seen), point) in [("Ann", ann), ("Bob", bob)].into_iter().zip(placed) {
        let expected = camera
            .project(
                glam::Vec3::from_array(point.map(|v: f64| v as f32)),
                glam::Vec2::new(width as f32, height as f32),
            )
            .unwrap();
        assert!(
            (seen.0 - f64::from(expected.x)).abs() < 0.5
                && (seen.1 - f64::from(expected.y)).abs() < 0.5,
            "{who}'s neck at {seen:?}, placed at {expected}"
        );
    }
    // In the scene's order: Ann, first, stands on the right.
    assert!(
        ann.0 > width / 2.0 && bob.0 < width / 2.0,
        "Ann {ann:?}, Bob {bob:?}"
    );
}

#[test]
fn a_scene_with_a_bad_character_says_which() {
    // Catches: an error that does not name the character whose document is wrong.
    let scene = write(
        "bad-scene.json",
        r#"{"characters": [
            {"name": "Ann", "version": 1},
            {"name": "Bob", "placement": {"position": [1, 0, 0]}, "version": 1, "posture": {"no_such_joint": {"rx": 0.3}}}
        ]}"#,
    );
    let out = temp("bad-scene.png");
    let (ok, err) = stance(&["render", &scene, "--out", &out.to_string_lossy()]);
    assert!(!ok && !out.exists());
    assert!(
        err.contains("Bob") && err.contains("no_such_joint"),
        "{err}"
    );
    let malformed = write(
        "malformed-scene.json",
        r#"{"characters": [{"name": "Ann", "version": 1}, {"name": "Bob", "placement": {"yaw": "left"}}]}"#,
    );
    let (ok, err) = stance(&["render", &malformed, "--out", &out.to_string_lossy()]);
    assert!(!ok && !out.exists());
    assert!(err.contains("characters[1]"), "{err}");
}
