//! The vendored third-party avatar (tests/fixtures/avatars, MIT) loaded, mapped onto H-Anim, posed by
//! the solver and drawn skinned on the GPU offscreen (lavapipe on CI): pixels checked.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use glam::{DVec3, Vec2};
use stance_document::{TaskKindSpec, TaskSpec};
use stance_editor::avatar::LoadedAvatar;
use stance_editor::posing::PosingSession;
use stance_hanim::LevelOfArticulation;
use stance_render::{
    BACKGROUND_SRGB, OrbitCamera, Pixels, RenderTarget, Scene, SceneRenderer, read_pixels,
};

const SHARED_AVATAR: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../../tests/fixtures/avatars/Black_F_2_Casual.glb"
);

fn device() -> (wgpu::Device, wgpu::Queue) {
    let instance = wgpu::Instance::new(wgpu::InstanceDescriptor {
        backends: wgpu::Backends::VULKAN | wgpu::Backends::GL,
        ..wgpu::InstanceDescriptor::new_without_display_handle()
    });
    let adapter =
        pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions::default()))
            .expect("no wgpu adapter: install mesa-vulkan-drivers (lavapipe)");
    pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
        label: Some("stance avatar test"),
        required_limits: wgpu::Limits::downlevel_webgl2_defaults(),
        ..Default::default()
    }))
    .expect("device")
}

fn is_background([r, g, b, _]: [u8; 4]) -> bool {
    let expected = BACKGROUND_SRGB.map(|c| (c * 255.0).round() as i32);
    (i32::from(r) - expected[0]).abs() <= 3
        && (i32::from(g) - expected[1]).abs() <= 3
        && (i32::from(b) - expected[2]).abs() <= 3
}

#[test]
fn the_shared_avatar_maps_renders_skinned_and_reaches_with_its_hand() {
    let bytes = std::fs::read(SHARED_AVATAR).expect("the avatar is in tests/fixtures/avatars");
    let (mut loaded, humanoid) =
        LoadedAvatar::load("Black_F_2_Casual.glb", &bytes, LevelOfArticulation::Loa2).unwrap();
    let (mapped, _) = loaded.mapping_summary();
    assert!(mapped >= 18, "only {mapped} joints mapped onto H-Anim");
    for joint in stance_hanim::humanoid_joints(LevelOfArticulation::Loa1) {
        assert!(
            humanoid
                .skeleton
                .joint_index(joint.definition.name)
                .is_some(),
            "LOA1 joint {} is missing",
            joint.definition.name
        );
    }

    let (device, queue) = device();
    let mut renderer = SceneRenderer::new(&device);
    let model = loaded.take_mesh().unwrap();
    renderer.set_avatar(&device, &queue, Some(&*model));
    // The same avatar uploaded over frames, as the editor does it.
    let mut staged = SceneRenderer::new(&device);
    staged.begin_avatar_upload(model.clone());
    let mut steps = 1;
    while !staged.continue_avatar_upload(&device, &queue) {
        steps += 1;
        assert!(steps < 100, "the upload never ends");
    }
    // Each texture in bands of 4 MB of rows, then the buffers.
    let bands: usize = model
        .textures
        .iter()
        .map(|t| {
            let rows = (4 << 20) / (t.width as usize * 4);
            (t.height as usize).div_ceil(rows)
        })
        .sum();
    assert!(bands > model.textures.len(), "{bands} bands");
    assert_eq!(steps, bands + 1);
    let size = [320u32, 320u32];
    let target = RenderTarget::new(&device, size);
    let camera = OrbitCamera {
        yaw: 0.0,
        pitch: 0.0,
        ..OrbitCamera::default()
    };
    let mut session = PosingSession::with_humanoid(humanoid).unwrap();
    let mut draw = |session: &PosingSession| -> Pixels {
        let palettes = loaded
            .palettes(session.humanoid(), session.posture())
            .unwrap();
        let scene = Scene {
            show_avatar: true,
            avatar_palettes: palettes,
            ..Scene::default()
        };
        renderer.render(&device, &queue, &target, &camera, &scene);
        read_pixels(&device, &queue, &target).unwrap()
    };
    let project = |point: DVec3| {
        camera
            .project(point.as_vec3(), Vec2::new(size[0] as f32, size[1] as f32))
            .unwrap()
    };

    let rest = draw(&session);
    let scene = Scene {
        show_avatar: true,
        avatar_palettes: loaded
            .palettes(session.humanoid(), session.posture())
            .unwrap(),
        ..Scene::default()
    };
    staged.render(&device, &queue, &target, &camera, &scene);
    let staged_pixels = read_pixels(&device, &queue, &target).unwrap();
    assert!(
        staged_pixels == rest,
        "the avatar uploaded over frames draws as the one uploaded at once"
    );
    let covered = (0..size[1])
        .flat_map(|y| (0..size[0]).map(move |x| (x, y)))
        .filter(|&(x, y)| !is_background(rest.get(x, y).unwrap()))
        .count();
    assert!(covered > 3000, "only {covered} pixels of avatar");
    let pelvis = project(session.joint_position("sacroiliac").unwrap());
    assert!(
        !is_background(rest.get(pelvis.x as u32, pelvis.y as u32).unwrap()),
        "the body covers its pelvis"
    );
    assert!(
        is_background(rest.get(3, 3).unwrap()),
        "the corner is background"
    );

    // Reach up with the right hand, feet pinned.
    let wrist_before = session.joint_position("r_radiocarpal").unwrap();
    // Up and forward, within the arm's reach from the shoulder (the avatar rests in a T-pose).
    let shoulder = session.joint_position("r_shoulder").unwrap();
    let arm_length = (wrist_before - shoulder).length();
    let goal = shoulder + DVec3::new(-0.2, 0.3, 0.9).normalize() * arm_length * 0.85;
    let mut tasks = session.tasks().to_vec();
    let mut reach = TaskSpec::pin("r_radiocarpal", goal.to_array());
    reach.level = 3;
    tasks.push(reach);
    tasks.retain(|task: &TaskSpec| !matches!(task.kind, TaskKindSpec::Limb { .. }));
    session.set_tasks(tasks);
    for _ in 0..300 {
        session.solve_frame(None);
        if session.is_settled() {
            break;
        }
    }
    // A reach still on its way after 300 frames is a solver problem, not a render one.
    assert!(
        session.is_settled(),
        "the reach did not settle within 300 frames: {:?}",
        session.report()
    );
    let wrist_after = session.joint_position("r_radiocarpal").unwrap();
    assert!(
        (wrist_after - goal).length() < 0.02,
        "the hand reached {wrist_after} for {goal}: {:?}",
        session.report()
    );
    let raised = draw(&session);
    let hand = project(wrist_after);
    assert!(
        is_background(rest.get(hand.x as u32, hand.y as u32).unwrap()),
        "nothing was there at rest"
    );
    let near_hand = (-4..=4)
        .flat_map(|dy| (-4..=4).map(move |dx| (dx, dy)))
        .filter(|(dx, dy)| {
            let (x, y) = ((hand.x as i32 + dx) as u32, (hand.y as i32 + dy) as u32);
            raised.get(x, y).is_some_and(|pixel| !is_background(pixel))
        })
        .count();
    assert!(
        near_hand > 20,
        "the skinned hand is drawn where the wrist went ({near_hand} pixels)"
    );
}
