//! glTF animations: reading (LINEAR, STEP, CUBICSPLINE, quantised rotations), sampling by
//! hand-checked values, clips with hand-computed joint positions, malformed animations
//! skipped with a warning, and export then import of postures as an identity.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

#[cfg(target_arch = "wasm32")]
use wasm_bindgen_test::wasm_bindgen_test as test;

use crate::common;

use base64::Engine as _;
use glam::{DQuat, DVec3, DVec4};
use serde_json::{Value, json};
use stance_asset::{
    AnimationPath, AssetError, Avatar, Interpolation, Limits, LoadOptions, clip_from_animation,
    export_glb_animation, load_avatar, make_default_avatar,
};
use stance_hanim::SkeletonOptions;
use stance_ik::Posture;

/// Buffer, views and accessors of a hand-built file.
#[derive(Default)]
struct Builder {
    data: Vec<u8>,
    views: Vec<Value>,
    accessors: Vec<Value>,
}

impl Builder {
    fn add(&mut self, bytes: &[u8], component: u32, count: usize, ty: &str, extra: Value) -> usize {
        while !self.data.len().is_multiple_of(4) {
            self.data.push(0);
        }
        self.views
            .push(json!({"buffer": 0, "byteOffset": self.data.len(), "byteLength": bytes.len()}));
        self.data.extend_from_slice(bytes);
        let mut a = json!({"bufferView": self.views.len() - 1, "componentType": component, "count": count, "type": ty});
        if let (Value::Object(a), Value::Object(extra)) = (&mut a, extra) {
            a.extend(extra);
        }
        self.accessors.push(a);
        self.accessors.len() - 1
    }

    fn floats(&mut self, v: &[f32], ty: &str) -> usize {
        let comps = match ty {
            "SCALAR" => 1,
            "VEC3" => 3,
            _ => 4,
        };
        let bytes: Vec<u8> = v.iter().flat_map(|x| x.to_le_bytes()).collect();
        self.add(&bytes, 5126, v.len() / comps, ty, json!({}))
    }

    fn times(&mut self, v: &[f32]) -> usize {
        let bytes: Vec<u8> = v.iter().flat_map(|x| x.to_le_bytes()).collect();
        let min = v.iter().copied().fold(f32::MAX, f32::min);
        let max = v.iter().copied().fold(f32::MIN, f32::max);
        self.add(
            &bytes,
            5126,
            v.len(),
            "SCALAR",
            json!({"min": [min], "max": [max]}),
        )
    }

    fn shorts(&mut self, v: &[i16]) -> usize {
        let bytes: Vec<u8> = v.iter().flat_map(|x| x.to_le_bytes()).collect();
        self.add(
            &bytes,
            5122,
            v.len() / 4,
            "VEC4",
            json!({"normalized": true}),
        )
    }
}

const S: f32 = std::f32::consts::FRAC_1_SQRT_2;

fn animation(
    name: &str,
    node: usize,
    path: &str,
    interpolation: &str,
    input: usize,
    output: usize,
) -> Value {
    json!({
        "name": name,
        "channels": [{"sampler": 0, "target": {"node": node, "path": path}}],
        "samplers": [{"input": input, "output": output, "interpolation": interpolation}]
    })
}

/// A 3-joint arm along +X (upper at the origin, lower at x = 1, hand at x = 2) and its
/// animations:
/// 0 `turn`: the lower joint turns 90 degrees about Z over 1 s (LINEAR);
/// 1 `step`: the hand's translation (1, 0, 0), (2, 0, 0), (3, 0, 0) at 0, 1, 2 s (STEP);
/// 2 `spline`: the hand's translation, CUBICSPLINE at 0 and 2 s;
/// 3 `quantized`: as `turn`, with normalised i16 rotations;
/// 4 `morph`: a weights channel (ignored) and a rotation of the upper joint.
/// Also returns the extra accessors `[bad times, NaN outputs]` that nothing uses.
fn arm() -> (Value, [usize; 2]) {
    let mut b = Builder::default();
    let t01 = b.times(&[0.0, 1.0]);
    let turn = b.floats(&[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, S, S], "VEC4");
    let t012 = b.times(&[0.0, 1.0, 2.0]);
    let steps = b.floats(&[1.0, 0.0, 0.0, 2.0, 0.0, 0.0, 3.0, 0.0, 0.0], "VEC3");
    let t02 = b.times(&[0.0, 2.0]);
    #[rustfmt::skip]
    let spline = b.floats(&[
        0.0, 0.0, 0.0,  1.0, 0.0, 0.0,  1.0, 0.0, 0.0, // key 0: in-tangent, value, out-tangent
        0.0, 2.0, 0.0,  2.0, 0.0, 0.0,  0.0, 0.0, 0.0, // key 1
    ], "VEC3");
    let quantized = b.shorts(&[0, 0, 0, 32767, 0, 0, 23170, 23170]);
    let weights = b.floats(&[0.0, 1.0], "SCALAR");
    let bad_times = b.times(&[0.0, 2.0, 1.0]);
    let nan = b.floats(&[1.0, 0.0, 0.0, f32::NAN, 0.0, 0.0, 3.0, 0.0, 0.0], "VEC3");
    let mut morph = animation("morph", 0, "weights", "LINEAR", t01, weights);
    morph["channels"]
        .as_array_mut()
        .unwrap()
        .push(json!({"sampler": 1, "target": {"node": 0, "path": "rotation"}}));
    morph["samplers"]
        .as_array_mut()
        .unwrap()
        .push(json!({"input": t01, "output": turn}));
    let uri = format!(
        "data:application/octet-stream;base64,{}",
        base64::engine::general_purpose::STANDARD.encode(&b.data)
    );
    let j = json!({
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [
            {"name": "upper", "children": [1]},
            {"name": "lower", "translation": [1.0, 0.0, 0.0], "children": [2]},
            {"name": "hand", "translation": [1.0, 0.0, 0.0]}
        ],
        "skins": [{"joints": [0, 1, 2]}],
        "animations": [
            animation("turn", 1, "rotation", "LINEAR", t01, turn),
            animation("step", 2, "translation", "STEP", t012, steps),
            animation("spline", 2, "translation", "CUBICSPLINE", t02, spline),
            animation("quantized", 1, "rotation", "LINEAR", t01, quantized),
            morph
        ],
        "accessors": b.accessors,
        "bufferViews": b.views,
        "buffers": [{"byteLength": b.data.len(), "uri": uri}]
    });
    (j, [bad_times, nan])
}

fn options() -> LoadOptions {
    LoadOptions {
        require_humanoid: false,
        ..LoadOptions::default()
    }
}

fn load(j: &Value) -> Result<Avatar, AssetError> {
    load_avatar(&serde_json::to_vec(j).unwrap(), &options())
}

fn close(a: DVec4, b: DVec4, tol: f64) -> bool {
    (a - b).abs().max_element() <= tol
}

#[test]
fn a_valid_file_reads_every_animation() {
    let a = load(&arm().0).unwrap();
    let names: Vec<&str> = a.animations.iter().map(|x| x.name.as_str()).collect();
    assert_eq!(names, ["turn", "step", "spline", "quantized", "morph"]);
    assert!(
        a.warnings.iter().all(|w| !w.contains("skipped")),
        "{:?}",
        a.warnings
    );
    assert!(
        a.warnings
            .iter()
            .any(|w| w.contains("animation 4 `morph`") && w.contains("1 morph-target weights")),
        "{:?}",
        a.warnings
    );
    let durations: Vec<f64> = a.animations.iter().map(|x| x.duration).collect();
    assert_eq!(durations, [1.0, 2.0, 2.0, 1.0, 1.0]);
    let morph = &a.animations[4];
    assert_eq!(morph.channels.len(), 1);
    assert_eq!(
        (morph.channels[0].node, morph.channels[0].path),
        (0, AnimationPath::Rotation)
    );
    assert_eq!(
        a.animations[2].channels[0].interpolation,
        Interpolation::CubicSpline
    );
    assert_eq!(a.animations[2].channels[0].values.len(), 18);
    // A file without animations has none, and no warning about them.
    let glb = common::default_glb();
    let d = load_avatar(&glb, &LoadOptions::default()).unwrap();
    assert!(d.animations.is_empty());
    assert!(d.warnings.iter().all(|w| !w.contains("animation")));
}

#[test]
fn linear_rotations_are_slerped() {
    let a = load(&arm().0).unwrap();
    let c = &a.animations[0].channels[0];
    // Identity to 90 degrees about Z: at a quarter of the time, 22.5 degrees.
    let half = (22.5f64.to_radians() / 2.0).sin_cos();
    let expected = DVec4::new(0.0, 0.0, half.0, half.1);
    assert!(
        close(c.sample(0.25).unwrap(), expected, 1e-12),
        "{}",
        c.sample(0.25).unwrap()
    );
    let q45 = (45f64.to_radians() / 2.0).sin_cos();
    assert!(close(
        c.sample(0.5).unwrap(),
        DVec4::new(0.0, 0.0, q45.0, q45.1),
        1e-12
    ));
    // Before the first key and after the last: clamped.
    assert!(close(c.sample(-1.0).unwrap(), DVec4::W, 0.0));
    let end = DVec4::new(0.0, 0.0, 0.5f64.sqrt(), 0.5f64.sqrt());
    assert!(close(c.sample(7.0).unwrap(), end, 1e-15));
    // The quantised copy (normalised i16) gives the same rotations.
    let q = &a.animations[3].channels[0];
    assert!(close(q.sample(0.25).unwrap(), expected, 1e-12));
    assert!(close(q.sample(1.0).unwrap(), end, 1e-15));
    // The shorter way: keys q and -q' interpolate as q and q'.
    let mut flipped = c.clone();
    for v in &mut flipped.values[4..8] {
        *v = -*v;
    }
    assert!(close(flipped.sample(0.25).unwrap(), expected, 1e-12));
}

#[test]
fn step_holds_and_cubicspline_follows_the_hermite_form() {
    let a = load(&arm().0).unwrap();
    let step = &a.animations[1].channels[0];
    for (t, x) in [
        (0.0, 1.0),
        (0.5, 1.0),
        (0.999, 1.0),
        (1.0, 2.0),
        (1.99, 2.0),
        (2.0, 3.0),
        (9.0, 3.0),
    ] {
        assert_eq!(
            step.sample(t).unwrap(),
            DVec4::new(x, 0.0, 0.0, 0.0),
            "t = {t}"
        );
    }
    let spline = &a.animations[2].channels[0];
    // t = 0.5: td = 2, s = 0.25; p = (2s^3 - 3s^2 + 1) v0 + td (s^3 - 2s^2 + s) b0
    //   + (-2s^3 + 3s^2) v1 + td (s^3 - s^2) a1
    //   = 0.84375 (1,0,0) + 0.28125 (1,0,0) + 0.15625 (2,0,0) - 0.09375 (0,2,0).
    let p = spline.sample(0.5).unwrap();
    assert!(
        close(p, DVec4::new(1.4375, -0.1875, 0.0, 0.0), 1e-12),
        "{p}"
    );
    // The keys themselves are the values, not the tangents.
    assert_eq!(spline.sample(0.0).unwrap(), DVec4::new(1.0, 0.0, 0.0, 0.0));
    assert_eq!(spline.sample(2.0).unwrap(), DVec4::new(2.0, 0.0, 0.0, 0.0));
}

#[test]
fn a_clip_has_the_hand_computed_joint_positions() {
    let a = load(&arm().0).unwrap();
    let h = a.hanim_from_file;
    let clip = clip_from_animation(&a, 0, 4.0).unwrap();
    clip.validate().unwrap();
    // 1 s at 4 fps: round(1 x 4) + 1 frames.
    assert_eq!(clip.frames.len(), 5);
    assert!((clip.frame_time - 0.25).abs() < 1e-15);
    assert!(
        clip.notes.iter().any(|n| n.contains("5 frames")),
        "{:?}",
        clip.notes
    );
    assert!(
        clip.notes
            .iter()
            .any(|n| n.contains("every key falls on a frame"))
    );
    let names: Vec<&str> = clip.joints.iter().map(|j| j.name.as_str()).collect();
    assert_eq!(names, ["upper", "lower", "hand"]);
    assert_eq!(clip.joints[1].parent, Some(0));
    // Frame 2 (t = 0.5 s): the lower joint turned 45 degrees about Z.
    let world = clip.world(&clip.frames[2]);
    let c = 45f64.to_radians().cos();
    let expected_file = [DVec3::ZERO, DVec3::X, DVec3::new(1.0 + c, c, 0.0)];
    for (j, e) in expected_file.iter().enumerate() {
        let e = h.transform_point3(*e);
        assert!(
            world[j].1.distance(e) < 1e-9,
            "joint {j}: {} vs {e}",
            world[j].1
        );
    }
    // World rotation of the lower joint: 45 degrees about Z, seen in the H-Anim frame.
    let rh = DQuat::from_mat3(
        &glam::DMat3::from_mat4(h).mul_scalar(1.0 / glam::DMat3::from_mat4(h).x_axis.length()),
    );
    let expected = rh * DQuat::from_rotation_z(45f64.to_radians()) * rh.inverse();
    assert!(world[1].0.angle_between(expected) < 1e-9);
    assert!(world[0].0.angle_between(DQuat::IDENTITY) < 1e-12);
    // The last frame: 90 degrees; the hand straight above the lower joint.
    let last = clip.world(&clip.frames[4]);
    assert!(
        last[2]
            .1
            .distance(h.transform_point3(DVec3::new(1.0, 1.0, 0.0)))
            < 1e-9
    );

    // STEP and CUBICSPLINE go through the clip too (frames 0.5 s apart here).
    let step = clip_from_animation(&a, 1, 2.0).unwrap();
    assert_eq!(step.frames.len(), 5);
    // The hand at the lower joint (x = 1) plus the held translation.
    let hand = step.world(&step.frames[1])[2].1;
    assert!(hand.distance(h.transform_point3(DVec3::new(2.0, 0.0, 0.0))) < 1e-9);
    let hand = step.world(&step.frames[3])[2].1;
    assert!(hand.distance(h.transform_point3(DVec3::new(3.0, 0.0, 0.0))) < 1e-9);
    let spline = clip_from_animation(&a, 2, 2.0).unwrap();
    let hand = spline.world(&spline.frames[1])[2].1;
    assert!(hand.distance(h.transform_point3(DVec3::new(1.0 + 1.4375, -0.1875, 0.0))) < 1e-9);
    // Off the key grid: 2.5 fps over 2 s, keys at 0, 1, 2 s: 6 frames, at 0.4 s apart.
    let off = clip_from_animation(&a, 1, 2.5).unwrap();
    assert_eq!(off.frames.len(), 6);
    assert!(
        off.notes.iter().any(|n| n.contains("off the 2.5 fps grid")),
        "{:?}",
        off.notes
    );
    let hand = off.world(&off.frames[3])[2].1; // 1.2 s: the key of 1 s held
    assert!(hand.distance(h.transform_point3(DVec3::new(3.0, 0.0, 0.0))) < 1e-9);
    // Bad requests.
    assert!(matches!(
        clip_from_animation(&a, 9, 30.0),
        Err(AssetError::BadIndex { .. })
    ));
    for fps in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        assert!(clip_from_animation(&a, 0, fps).is_err(), "{fps}");
    }
    assert!(matches!(
        clip_from_animation(&a, 0, 1e12),
        Err(AssetError::TooLarge { .. })
    ));
}

/// `edit` applied to the arm's JSON: the avatar still loads, the named animation is gone,
/// and a warning names it, the channel and `what`.
fn skipped(edit: impl Fn(&mut Value, [usize; 2]), animation: &str, what: &str) {
    let (mut j, extra) = arm();
    edit(&mut j, extra);
    let a = load(&j).unwrap();
    assert!(
        a.animations
            .iter()
            .all(|x| x.name != animation[3..animation.len() - 1]),
        "{animation} was kept"
    );
    assert_eq!(a.animations.len(), 4);
    assert!(
        a.warnings
            .iter()
            .any(|w| w.contains(&format!("animation {animation}"))
                && w.contains("channel 0")
                && w.contains(what)
                && w.contains("skipped")),
        "{animation} / {what}: {:?}",
        a.warnings
    );
}

#[test]
fn malformed_animations_are_skipped_with_a_warning() {
    skipped(
        |j, _| j["animations"][0]["channels"][0]["target"]["node"] = json!(7),
        "0 `turn`",
        "node 7",
    );
    skipped(
        |j, [bad, _]| j["animations"][1]["samplers"][0]["input"] = json!(bad),
        "1 `step`",
        "not strictly increasing",
    );
    skipped(
        |j, [_, nan]| j["animations"][1]["samplers"][0]["output"] = json!(nan),
        "1 `step`",
        "not finite",
    );
    skipped(
        |j, _| j["animations"][1]["samplers"][0]["input"] = json!(999),
        "1 `step`",
        "accessor 999",
    );
    skipped(
        |j, _| j["animations"][0]["samplers"][0]["interpolation"] = json!("SMOOTH"),
        "0 `turn`",
        "interpolation",
    );
    skipped(
        |j, _| j["animations"][0]["channels"][0]["sampler"] = json!(3),
        "0 `turn`",
        "sampler 3",
    );
    // A rotation read from a VEC3 accessor; STEP outputs for CUBICSPLINE (count mismatch).
    skipped(
        |j, _| j["animations"][3]["samplers"][0]["output"] = json!(3),
        "3 `quantized`",
        "Vec4",
    );
    skipped(
        |j, _| j["animations"][1]["samplers"][0]["interpolation"] = json!("CUBICSPLINE"),
        "1 `step`",
        "output numbers",
    );
    // Key times below zero.
    skipped(
        |j, _| j["accessors"][2]["byteOffset"] = json!(4),
        "1 `step`",
        "do not fit",
    );
    // Past the view.
    skipped(
        |j, _| j["accessors"][3]["count"] = json!(1000),
        "1 `step`",
        "do not fit",
    );
}

#[test]
fn animation_counts_are_limited() {
    let (j, _) = arm();
    let bytes = serde_json::to_vec(&j).unwrap();
    for limits in [
        Limits {
            max_animations: 4,
            ..Limits::default()
        },
        Limits {
            max_animation_channels: 5,
            ..Limits::default()
        },
    ] {
        let e = load_avatar(
            &bytes,
            &LoadOptions {
                limits,
                ..options()
            },
        )
        .unwrap_err();
        assert!(matches!(e, AssetError::TooLarge { .. }), "{e}");
    }
    // Accessor counts name the animation and channel.
    let limits = Limits {
        max_accessor_count: 2,
        ..Limits::default()
    };
    let e = load_avatar(
        &bytes,
        &LoadOptions {
            limits,
            ..options()
        },
    )
    .unwrap_err();
    assert!(
        e.to_string().contains("animation 1 `step` channel 0 input"),
        "{e}"
    );
}

#[test]
fn exported_postures_come_back_as_the_same_motion() {
    let avatar = make_default_avatar().unwrap();
    let body = avatar.skeleton(&SkeletonOptions::default()).unwrap();
    let s = &body.skeleton;
    let postures: Vec<Posture> = (0..4)
        .map(|k| {
            let mut p = Posture::rest(s);
            for (i, v) in p.values_mut().iter_mut().enumerate() {
                *v = if k == 0 {
                    0.0
                } else {
                    0.35 * ((i as f64) * 0.7 + k as f64).sin()
                };
            }
            p
        })
        .collect();
    let frame_time = 1.0 / 30.0;
    let glb = export_glb_animation(&avatar, &body, &postures, frame_time, "wave").unwrap();

    // The document: one animation, LINEAR, one shared time input with min and max.
    let (j, _) = common::split(&glb);
    let anims = j["animations"].as_array().unwrap();
    assert_eq!(anims.len(), 1);
    assert_eq!(anims[0]["name"], "wave");
    let samplers = anims[0]["samplers"].as_array().unwrap();
    let input = samplers[0]["input"].as_u64().unwrap() as usize;
    assert!(
        samplers
            .iter()
            .all(|s| s["interpolation"] == "LINEAR" && s["input"] == json!(input))
    );
    let acc = &j["accessors"][input];
    assert_eq!(acc["count"], 4);
    assert_eq!(acc["min"], json!([0.0]));
    assert!((acc["max"][0].as_f64().unwrap() - 0.1).abs() < 1e-7);
    let channels = anims[0]["channels"].as_array().unwrap();
    let translated: Vec<u64> = channels
        .iter()
        .filter(|c| c["target"]["path"] == "translation")
        .map(|c| c["target"]["node"].as_u64().unwrap())
        .collect();
    let root = body.joints[0].source.unwrap() as u64;
    assert_eq!(translated, [root], "only the root moves in translation");
    let rotated = channels
        .iter()
        .filter(|c| c["target"]["path"] == "rotation")
        .count();
    assert!(rotated > 30, "{rotated} rotation channels");
    // The rest of the file is export_glb's.
    for key in ["meshes", "skins", "materials", "nodes"] {
        assert_eq!(
            j[key],
            common::split(&stance_asset::export_glb(&avatar).unwrap()).0[key],
            "{key}"
        );
    }

    // Import: one animation of 4 keys over 0.1 s; as a clip at 30 fps, the same positions.
    let back = load_avatar(&glb, &LoadOptions::default()).unwrap();
    assert_eq!(back.animations.len(), 1);
    let anim = &back.animations[0];
    assert!(anim.channels.iter().all(|c| c.times.len() == 4));
    assert!((anim.duration - 0.1).abs() < 1e-7);
    let clip = clip_from_animation(&back, 0, 30.0).unwrap();
    clip.validate().unwrap();
    assert_eq!(clip.frames.len(), 4);
    let mut checked = 0;
    for (k, posture) in postures.iter().enumerate() {
        let world = avatar.world_from_locals(&avatar.posed_locals(&body, posture).unwrap());
        let clip_world = clip.world(&clip.frames[k]);
        for m in avatar.mapping.matches() {
            let expected = back
                .hanim_from_file
                .transform_point3(world[m.source].w_axis.truncate());
            let j = clip.joint_of(m.hanim).unwrap();
            let got = clip_world[j].1;
            assert!(
                got.distance(expected) < 1e-5,
                "frame {k} {}: {got} vs {expected}",
                m.hanim
            );
            checked += 1;
        }
    }
    assert!(checked > 200);
    // Moving joints really moved.
    let first = clip.world(&clip.frames[0]);
    let last = clip.world(&clip.frames[3]);
    let wrist = clip.joint_of("l_radiocarpal").unwrap();
    assert!(first[wrist].1.distance(last[wrist].1) > 0.05);
}

/// The same animation in a Z-up centimetre file facing -X (a new root above everything)
/// gives the same clip in the H-Anim frame: positions and world rotations of every mapped
/// joint, the file's unit scale and axes removed by `hanim_from_file`.
#[test]
fn clips_do_not_depend_on_the_files_axes_and_unit() {
    let avatar = make_default_avatar().unwrap();
    let body = avatar.skeleton(&SkeletonOptions::default()).unwrap();
    let postures: Vec<Posture> = (0..3)
        .map(|k| {
            let mut p = Posture::rest(&body.skeleton);
            for (i, v) in p.values_mut().iter_mut().enumerate() {
                *v = 0.3 * ((i as f64) * 1.3 + k as f64).cos();
            }
            p
        })
        .collect();
    let glb = export_glb_animation(&avatar, &body, &postures, 0.5, "turns").unwrap();
    let reference = load_avatar(&glb, &LoadOptions::default()).unwrap();
    let moved = load_avatar(
        &common::z_up_centimetres_facing_minus_x(&glb),
        &LoadOptions::default(),
    )
    .unwrap();
    let a = clip_from_animation(&reference, 0, 2.0).unwrap();
    let b = clip_from_animation(&moved, 0, 2.0).unwrap();
    assert_eq!(b.joints[0].name, "Armature");
    assert_eq!((a.frames.len(), b.frames.len()), (3, 3));
    for k in 0..3 {
        let (wa, wb) = (a.world(&a.frames[k]), b.world(&b.frames[k]));
        for m in reference.mapping.matches() {
            let (ja, jb) = (a.joint_of(m.hanim).unwrap(), b.joint_of(m.hanim).unwrap());
            assert!(wa[ja].1.distance(wb[jb].1) < 1e-4, "frame {k} {}", m.hanim);
            assert!(
                wa[ja].0.angle_between(wb[jb].0) < 1e-5,
                "frame {k} {}",
                m.hanim
            );
        }
    }
}

#[test]
fn exporting_bad_sequences_fails_clearly() {
    let avatar = make_default_avatar().unwrap();
    let body = avatar.skeleton(&SkeletonOptions::default()).unwrap();
    let rest = Posture::rest(&body.skeleton);
    let e = export_glb_animation(&avatar, &body, &[], 0.1, "x").unwrap_err();
    assert!(e.to_string().contains("no postures"), "{e}");
    for ft in [0.0, -1.0, f64::NAN] {
        assert!(
            export_glb_animation(&avatar, &body, std::slice::from_ref(&rest), ft, "x").is_err()
        );
    }
    // A rest-only sequence still writes a valid animation (one constant channel).
    let glb = export_glb_animation(&avatar, &body, &[rest.clone(), rest], 0.5, "still").unwrap();
    let back = load_avatar(&glb, &LoadOptions::default()).unwrap();
    assert_eq!(back.animations[0].channels.len(), 1);
    assert_eq!(back.animations[0].channels[0].times.len(), 2);
}

#[cfg(not(target_arch = "wasm32"))]
mod fuzz {
    use proptest::prelude::*;

    use super::*;

    /// One edit of the arm file: a JSON field of the animations or accessors, or a byte of
    /// the buffer.
    #[derive(Debug, Clone)]
    enum Edit {
        Field(usize, usize, Value),
        Byte(prop::sample::Index, u8),
    }

    fn value() -> impl Strategy<Value = Value> {
        prop_oneof![
            (0u64..12).prop_map(|v| json!(v)),
            any::<i64>().prop_map(|v| json!(v)),
            Just(json!("CUBICSPLINE")),
            Just(json!("STEP")),
            Just(json!("weights")),
            Just(json!("scale")),
            Just(json!(5121)),
            Just(json!(5122)),
            Just(json!("VEC2")),
            Just(json!(null)),
        ]
    }

    fn edit() -> impl Strategy<Value = Edit> {
        prop_oneof![
            (0usize..5, 0usize..9, value()).prop_map(|(a, f, v)| Edit::Field(a, f, v)),
            (any::<prop::sample::Index>(), any::<u8>()).prop_map(|(i, b)| Edit::Byte(i, b)),
        ]
    }

    fn apply(j: &mut Value, edit: &Edit) {
        match edit {
            Edit::Field(a, f, v) => {
                let anim = &mut j["animations"][*a];
                let acc = *a * 2 % 10;
                match f {
                    0 => anim["channels"][0]["target"]["node"] = v.clone(),
                    1 => anim["channels"][0]["target"]["path"] = v.clone(),
                    2 => anim["channels"][0]["sampler"] = v.clone(),
                    3 => anim["samplers"][0]["input"] = v.clone(),
                    4 => anim["samplers"][0]["output"] = v.clone(),
                    5 => anim["samplers"][0]["interpolation"] = v.clone(),
                    6 => j["accessors"][acc]["count"] = v.clone(),
                    7 => j["accessors"][acc]["componentType"] = v.clone(),
                    _ => j["accessors"][acc]["byteOffset"] = v.clone(),
                }
            }
            Edit::Byte(i, b) => {
                let uri = j["buffers"][0]["uri"].as_str().unwrap().to_owned();
                let (head, data) = uri.split_once(',').unwrap();
                let mut bytes = base64::engine::general_purpose::STANDARD
                    .decode(data)
                    .unwrap();
                let at = i.index(bytes.len());
                bytes[at] = *b;
                let data = base64::engine::general_purpose::STANDARD.encode(&bytes);
                j["buffers"][0]["uri"] = json!(format!("{head},{data}"));
            }
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 64, ..ProptestConfig::default() })]

        /// Random edits of the animations: an avatar (with the readable animations, which
        /// sample to finite values and convert to clips) or an error, never a panic.
        #[test]
        fn mutated_animations_never_panic(edits in prop::collection::vec(edit(), 1..6)) {
            let (mut j, _) = arm();
            for e in &edits {
                apply(&mut j, e);
            }
            if let Ok(a) = load(&j) {
                for (i, anim) in a.animations.iter().enumerate() {
                    for c in &anim.channels {
                        prop_assert!(c.validate().is_ok());
                        for t in [0.0, 0.3, 1.0, 1.7, anim.duration, 1e9] {
                            prop_assert!(c.sample(t).unwrap().is_finite());
                        }
                    }
                    if anim.duration < 100.0 {
                        let clip = clip_from_animation(&a, i, 10.0).unwrap();
                        prop_assert!(clip.validate().is_ok());
                    }
                }
            }
        }
    }
}
