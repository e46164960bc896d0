//! Renders the viewport scene offscreen on whatever adapter the machine has (lavapipe on
//! CI) and checks its pixels: body colour where the body is, background elsewhere.

// A test crate: fixture helpers fail loudly on purpose.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use glam::{Vec2, Vec3};
use stance_hanim::LevelOfArticulation;
use stance_render::{
    BACKGROUND_SRGB, CastPose, OrbitCamera, Pixels, RenderTarget, Scene, SceneRenderer,
    SkinnedMaterial, SkinnedModel, SkinnedPrimitive, SkinnedVertex, read_pixels,
    rest_pose_capsules,
};

fn device() -> (wgpu::Device, wgpu::Queue, wgpu::AdapterInfo) {
    let instance = wgpu::Instance::new(wgpu::InstanceDescriptor {
        backends: wgpu::Backends::VULKAN | wgpu::Backends::GL,
        ..wgpu::InstanceDescriptor::new_without_display_handle()
    });
    let adapter = pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
        force_fallback_adapter: false,
        ..Default::default()
    }))
    .expect("no wgpu adapter: install mesa-vulkan-drivers (lavapipe)");
    let info = adapter.get_info();
    let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
        label: Some("stance offscreen test"),
        required_limits: wgpu::Limits::downlevel_webgl2_defaults(),
        ..Default::default()
    }))
    .expect("device");
    (device, queue, info)
}

fn render(camera: &OrbitCamera, size: [u32; 2]) -> Pixels {
    let (device, queue, info) = device();
    eprintln!("adapter: {} ({:?})", info.name, info.backend);
    let mut renderer = SceneRenderer::new(&device);
    let target = RenderTarget::new(&device, size);
    let scene = Scene {
        capsules: rest_pose_capsules(LevelOfArticulation::Loa2),
        show_floor: true,
        ..Scene::default()
    };
    renderer.render(&device, &queue, &target, camera, &scene);
    read_pixels(&device, &queue, &target).expect("read back")
}

fn is_body_colour([r, g, b, _]: [u8; 4]) -> bool {
    // The clay tone: red dominant, clearly warmer than the grey floor and blue background.
    r > 90 && f32::from(r) > 1.35 * f32::from(g) && g > b
}

fn background() -> [u8; 3] {
    BACKGROUND_SRGB.map(|c| (c * 255.0).round() as u8)[..3]
        .try_into()
        .unwrap()
}

fn save_artifact(pixels: &Pixels, name: &str) {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../artifacts");
    let _ = std::fs::create_dir_all(&dir);
    let path = dir.join(name);
    // A binary PPM: no image crate needed to look at it.
    let mut bytes = format!("P6\n{} {}\n255\n", pixels.width, pixels.height).into_bytes();
    for rgba in pixels.rgba.chunks(4) {
        bytes.extend_from_slice(&rgba[..3]);
    }
    let _ = std::fs::write(path, bytes);
}

#[test]
fn the_standing_humanoid_is_drawn_where_its_joints_project() {
    let camera = OrbitCamera::default();
    let size = [320u32, 240u32];
    let pixels = render(&camera, size);
    save_artifact(&pixels, "offscreen-rest-pose.ppm");
    let size_px = Vec2::new(size[0] as f32, size[1] as f32);
    let joints = stance_hanim::humanoid_joints(LevelOfArticulation::Loa2);
    for name in ["vt6", "vl3", "l_knee", "r_knee", "skullbase", "l_elbow"] {
        let joint = joints
            .iter()
            .find(|joint| joint.definition.name == name)
            .unwrap();
        let at = camera
            .project(joint.rest_centre.as_vec3(), size_px)
            .unwrap();
        let pixel = pixels.get(at.x as u32, at.y as u32).unwrap();
        assert!(
            is_body_colour(pixel),
            "{name} at {at}: {pixel:?} is not body-coloured"
        );
    }
    // Above the head and beside the body: background (above the horizon of the floor).
    let above_head = camera.project(Vec3::new(0.0, 2.05, 0.0), size_px).unwrap();
    let pixel = pixels
        .get(above_head.x as u32, above_head.y as u32)
        .unwrap();
    let bg = background();
    for channel in 0..3 {
        assert!(
            pixel[channel].abs_diff(bg[channel]) <= 3,
            "above the head: {pixel:?} vs {bg:?}"
        );
    }
    let body_pixels = pixels
        .rgba
        .chunks(4)
        .filter(|p| is_body_colour([p[0], p[1], p[2], p[3]]))
        .count();
    let share = body_pixels as f32 / (size[0] * size[1]) as f32;
    assert!(
        (0.03..0.4).contains(&share),
        "body covers {share} of the frame"
    );
}

#[test]
fn the_floor_grid_shows_below_the_feet_and_orbiting_changes_the_picture() {
    let camera = OrbitCamera::default();
    let size = [200u32, 150u32];
    let front = render(&camera, size);
    let size_px = Vec2::new(size[0] as f32, size[1] as f32);
    let floor = camera.project(Vec3::new(0.6, 0.0, 0.6), size_px).unwrap();
    let pixel = front.get(floor.x as u32, floor.y as u32).unwrap();
    assert!(!is_body_colour(pixel));
    assert_ne!(
        &pixel[..3],
        &background()[..],
        "the floor differs from the sky"
    );

    let mut turned = camera;
    turned.orbit(Vec2::new(200.0, 0.0));
    let side = render(&turned, size);
    let differing = front
        .rgba
        .chunks(4)
        .zip(side.rgba.chunks(4))
        .filter(|(a, b)| a != b)
        .count();
    assert!(
        differing > 500,
        "only {differing} pixels changed after orbiting"
    );
}

/// A skinned model of one unlit square, 0.4 m a side, facing +Z about its origin, all its
/// vertices on the palette's first matrix, of colour `color` (linear).
fn square(color: [f32; 3]) -> SkinnedModel {
    let vertex = |x: f32, y: f32| SkinnedVertex {
        position: [x, y, 0.0],
        normal: [0.0, 0.0, 1.0],
        uv: [0.0, 0.0],
        joints: [0; 4],
        weights: [1.0, 0.0, 0.0, 0.0],
    };
    SkinnedModel {
        primitives: vec![SkinnedPrimitive {
            vertices: vec![
                vertex(-0.2, -0.2),
                vertex(0.2, -0.2),
                vertex(0.2, 0.2),
                vertex(-0.2, 0.2),
            ],
            indices: vec![0, 1, 2, 0, 2, 3],
            material: 0,
            palette: 0,
        }],
        materials: vec![SkinnedMaterial {
            base_color_factor: [color[0], color[1], color[2], 1.0],
            texture: None,
            unlit: true,
            alpha_cutoff: None,
        }],
        textures: Vec::new(),
        palette_sizes: vec![1],
    }
}

#[test]
fn the_casts_poses_are_each_drawn_on_their_own_model() {
    // Catches: every pose drawn on one model, a model's second pose overwriting its first,
    // poses of a frame before drawn again in the next.
    let (device, queue, _) = device();
    let mut renderer = SceneRenderer::new(&device);
    let size = [240u32, 160u32];
    let target = RenderTarget::new(&device, size);
    let camera = OrbitCamera::saved([0.0, 1.0, 0.0], 0.0, 0.0, 4.0, false);
    let (red, green) = (square([1.0, 0.0, 0.0]), square([0.0, 1.0, 0.0]));
    renderer.set_cast_models(&device, &queue, &[&red, &green]);
    let at = |model: usize, x: f32, y: f32| CastPose {
        model,
        palettes: vec![vec![glam::Mat4::from_translation(Vec3::new(x, y, 0.0))]],
    };
    let left = at(0, -0.8, 1.0);
    let right = at(1, 0.8, 1.0);
    let above = at(0, 0.0, 1.6);
    let mut draw = |poses: Vec<CastPose>| {
        let scene = Scene {
            cast_poses: poses,
            ..Scene::default()
        };
        renderer.render(&device, &queue, &target, &camera, &scene);
        let pixels = read_pixels(&device, &queue, &target).expect("read back");
        move |x: f32, y: f32| {
            let at = camera
                .project(
                    Vec3::new(x, y, 0.0),
                    Vec2::new(size[0] as f32, size[1] as f32),
                )
                .unwrap();
            let offset = ((at.y as u32 * pixels.width + at.x as u32) * 4) as usize;
            <[u8; 3]>::try_from(&pixels.rgba[offset..offset + 3]).unwrap()
        }
    };
    let pixel = draw(vec![left, right, above.clone()]);
    assert_eq!(pixel(-0.8, 1.0), [255, 0, 0]);
    assert_eq!(pixel(0.8, 1.0), [0, 255, 0]);
    assert_eq!(pixel(0.0, 1.6), [255, 0, 0], "the red model's second pose");
    assert_eq!(pixel(0.0, 1.0), background());
    // The next frame draws its own poses alone.
    let pixel = draw(vec![above, at(1, -0.8, 1.0)]);
    assert_eq!(pixel(-0.8, 1.0), [0, 255, 0]);
    assert_eq!(pixel(0.8, 1.0), background());
    assert_eq!(pixel(0.0, 1.6), [255, 0, 0]);
}

/// `model` uploaded step by step, as the editor steps the cast's models.
fn stepped_up(
    renderer: &SceneRenderer,
    model: &SkinnedModel,
    device: &wgpu::Device,
    queue: &wgpu::Queue,
) -> stance_render::AvatarGpu {
    let mut upload = stance_render::AvatarUpload::new(std::sync::Arc::new(model.clone()));
    (0..10)
        .find_map(|_| renderer.step_upload(&mut upload, device, queue))
        .expect("a small model is up in a few steps")
}

#[test]
fn the_casts_models_are_kept_by_key_and_pass_to_and_from_the_avatars_place() {
    // Catches: a model's index not following its key after another is removed, a model
    // stepped up not drawn, the avatar's model lost on its way to the cast (or drawn from
    // there twice), the avatar's first pose drawn without palettes of its own.
    let (device, queue, _) = device();
    let mut renderer = SceneRenderer::new(&device);
    let size = [240u32, 160u32];
    let target = RenderTarget::new(&device, size);
    let camera = OrbitCamera::saved([0.0, 1.0, 0.0], 0.0, 0.0, 4.0, false);
    for (key, colour) in [(10, [1.0, 0.0, 0.0]), (20, [0.0, 1.0, 0.0])] {
        let model = stepped_up(&renderer, &square(colour), &device, &queue);
        renderer.insert_cast_model(key, model);
    }
    renderer.set_avatar(&device, &queue, Some(&square([0.0, 0.0, 1.0])));
    assert_eq!(renderer.cast_model_keys().collect::<Vec<_>>(), [10, 20]);
    // The red one dropped: the green one's index follows its key.
    assert!(renderer.remove_cast_model(10).is_some());
    assert_eq!(renderer.cast_model_index(20), Some(0));
    assert_eq!(renderer.cast_model_index(10), None);
    let pose = |x: f32| vec![vec![glam::Mat4::from_translation(Vec3::new(x, 1.0, 0.0))]];
    let draw = |renderer: &mut SceneRenderer, scene: Scene| {
        renderer.render(&device, &queue, &target, &camera, &scene);
        let pixels = read_pixels(&device, &queue, &target).expect("read back");
        move |x: f32| {
            let at = camera
                .project(
                    Vec3::new(x, 1.0, 0.0),
                    Vec2::new(size[0] as f32, size[1] as f32),
                )
                .unwrap();
            let offset = ((at.y as u32 * pixels.width + at.x as u32) * 4) as usize;
            <[u8; 3]>::try_from(&pixels.rgba[offset..offset + 3]).unwrap()
        }
    };
    let green_model = |x: f32| CastPose {
        model: 0,
        palettes: pose(x),
    };
    let pixel = draw(
        &mut renderer,
        Scene {
            show_avatar: true,
            avatar_palettes: pose(0.0),
            cast_poses: vec![green_model(-0.8)],
            ..Scene::default()
        },
    );
    assert_eq!(pixel(0.0), [0, 0, 255]);
    assert_eq!(pixel(-0.8), [0, 255, 0]);
    // The avatar without palettes of its own: only its second pose (at the right) is drawn,
    // not the first where the frame before left it.
    let pixel = draw(
        &mut renderer,
        Scene {
            show_avatar: true,
            more_avatar_poses: vec![pose(0.8)],
            cast_poses: vec![green_model(-0.8)],
            ..Scene::default()
        },
    );
    assert_eq!(pixel(-0.8), [0, 255, 0]);
    assert_eq!(pixel(0.8), [0, 0, 255]);
    assert_eq!(pixel(0.0), background());
    // The blue avatar goes to the cast and the green model takes its place: nothing uploaded
    // again, each drawn from its new place.
    let blue = renderer.take_avatar().unwrap();
    let green = renderer.remove_cast_model(20).unwrap();
    renderer.insert_cast_model(30, blue);
    renderer.put_avatar(green);
    assert_eq!(renderer.cast_model_count(), 1);
    let blue_at = renderer.cast_model_index(30).unwrap();
    let pixel = draw(
        &mut renderer,
        Scene {
            show_avatar: true,
            avatar_palettes: pose(0.0),
            cast_poses: vec![CastPose {
                model: blue_at,
                palettes: pose(-0.8),
            }],
            ..Scene::default()
        },
    );
    assert_eq!(pixel(0.0), [0, 255, 0]);
    assert_eq!(pixel(-0.8), [0, 0, 255]);
    assert_eq!(pixel(0.8), background());
    renderer.retain_cast_models(|key| key != 30);
    assert_eq!(renderer.cast_model_count(), 0);
}
