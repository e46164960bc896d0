#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]
//! The real CMU clips in `tests/fixtures/motion`, and export round trips.

#[cfg(target_arch = "wasm32")]
use wasm_bindgen_test::wasm_bindgen_test as test;

use glam::{DQuat, DVec3};
use stance_hanim::LevelOfArticulation;
use stance_motion::{BvhLimits, BvhWriteOptions, Clip, EulerOrder, read_bvh, write_bvh};

fn fixture(name: &str) -> Clip {
    let bytes: &[u8] = match name {
        "walk" => include_bytes!("../../../tests/fixtures/motion/walk.bvh"),
        "run" => include_bytes!("../../../tests/fixtures/motion/run.bvh"),
        _ => panic!("no fixture {name}"),
    };
    read_bvh(bytes, name, &BvhLimits::default()).unwrap()
}

fn reread(clip: &Clip, options: &BvhWriteOptions) -> Clip {
    let text = write_bvh(clip, options);
    read_bvh(text.as_bytes(), &clip.name, &BvhLimits::default()).unwrap()
}

fn angle(a: DQuat, b: DQuat) -> f64 {
    let d = a.conjugate() * b;
    2.0 * DVec3::new(d.x, d.y, d.z).length().atan2(d.w.abs())
}

#[test]
fn the_walk_is_read_in_cmu_units_and_fully_mapped() {
    let c = fixture("walk");
    assert_eq!(c.frame_count(), 260);
    assert_eq!(c.frame_time, 0.0083333);
    assert_eq!(c.joints.len(), 38); // 31 joints and 7 End Sites
    assert_eq!(
        c.notes[0],
        "units: CMU units (1/0.45 inch) (skull base 22.2 units above the ankles)"
    );
    assert!(c.mapping.missing(LevelOfArticulation::Loa1).is_empty());
    let name = |h: &str| c.joints[c.joint_of(h).unwrap()].name.as_str();
    assert_eq!(name("l_shoulder"), "LeftShoulder");
    assert_eq!(name("l_sternoclavicular"), "LeftCollar");
    assert_eq!(name("r_knee"), "RightKnee");
    assert_eq!(name("skullbase"), "Head");
    // The hips' OFFSET is 0 and the channels hold the position (CMU units).
    let hips = c.frames[0].translations[0];
    let unit = 0.0254 / 0.45;
    assert!(
        (hips - DVec3::new(4.2881, 16.4558, -23.9549) * unit).length() < 1e-12,
        "{hips}"
    );
    // Walking forward (+Z, the body's front) about 2 m.
    let last = c.frames[259].translations[0];
    assert!(
        last.z - hips.z > 1.5 && last.z - hips.z < 2.5,
        "{}",
        last.z - hips.z
    );
}

#[test]
fn the_run_with_cmu_asf_names_is_read_and_fully_mapped() {
    let c = fixture("run");
    assert_eq!(c.frame_count(), 173);
    assert!(
        c.notes[0].starts_with("units: CMU units (1/0.45 inch)"),
        "{:?}",
        c.notes
    );
    assert!(c.mapping.missing(LevelOfArticulation::Loa1).is_empty());
    let name = |h: &str| c.joints[c.joint_of(h).unwrap()].name.as_str();
    assert_eq!(name("l_hip"), "lfemur");
    assert_eq!(name("l_knee"), "ltibia");
    assert_eq!(name("l_shoulder"), "lhumerus");
    assert_eq!(name("r_radiocarpal"), "rwrist");
    assert_eq!(name("vt1"), "thorax");
    // Feet below the head in every frame.
    for f in &c.frames {
        let w = c.world(f);
        assert!(
            w[c.joint_of("skullbase").unwrap()].1.y
                > w[c.joint_of("l_talocrural").unwrap()].1.y + 0.8
        );
    }
}

#[test]
fn fixtures_written_and_read_again_keep_every_world_position() {
    for name in ["walk", "run"] {
        let c = fixture(name);
        for options in [
            BvhWriteOptions::default(),
            BvhWriteOptions {
                order: EulerOrder::Zyx,
                metres_per_unit: 0.01,
                hanim_names: true,
            },
        ] {
            let back = reread(&c, &options);
            assert_eq!(back.frame_count(), c.frame_count());
            assert_eq!(back.frame_time, c.frame_time);
            assert_eq!(back.joints.len(), c.joints.len());
            assert_eq!(back.joint_of("l_knee"), c.joint_of("l_knee"));
            assert!(back.mapping.missing(LevelOfArticulation::Loa1).is_empty());
            for (fa, fb) in c.frames.iter().zip(&back.frames) {
                for ((_, a), (_, b)) in c.world(fa).iter().zip(back.world(fb)) {
                    assert!((*a - b).length() < 1e-6, "{name}: {a} != {b}");
                }
            }
        }
    }
}

#[test]
fn all_six_euler_orders_round_trip_through_export_and_import() {
    let c = fixture("run");
    // The unit must read back as metres: written in metres, the run's body is human-sized.
    for order in EulerOrder::ALL {
        let options = BvhWriteOptions {
            order,
            ..BvhWriteOptions::default()
        };
        let text = write_bvh(&c, &options);
        let rot = order.channel_names().join(" ");
        assert!(text.contains(&format!("CHANNELS 3 {rot}")), "{order:?}");
        assert!(text.contains("ROOT humanoid_root"));
        assert!(text.contains("JOINT l_hip"));
        let back = read_bvh(text.as_bytes(), "r", &BvhLimits::default()).unwrap();
        assert!(
            back.notes[0].starts_with("units: metres"),
            "{:?}",
            back.notes
        );
        assert_eq!(back.frame_count(), 173);
        assert_eq!(back.frame_time.to_bits(), c.frame_time.to_bits());
        for (fa, fb) in c.frames.iter().zip(&back.frames) {
            for (a, b) in fa.rotations.iter().zip(&fb.rotations) {
                assert!(angle(*a, *b) < 1e-6, "{order:?}: {}", angle(*a, *b));
            }
        }
    }
}

#[test]
fn the_frame_time_is_written_to_round_trip_exactly() {
    let mut c = fixture("run");
    c.frames.truncate(2);
    for t in [1.0 / 120.0, 1.0 / 30.0, 0.1 + 0.2, 1e-7] {
        c.frame_time = t;
        let back = reread(&c, &BvhWriteOptions::default());
        assert_eq!(back.frame_time.to_bits(), t.to_bits());
    }
}

#[cfg(not(target_arch = "wasm32"))]
#[test]
fn the_fuzz_seeds_are_valid_and_small() {
    let dir = format!("{}/fuzz/seeds/bvh", env!("CARGO_MANIFEST_DIR"));
    let mut count = 0;
    for entry in std::fs::read_dir(dir).unwrap() {
        let bytes = std::fs::read(entry.unwrap().path()).unwrap();
        assert!(bytes.len() < 4096);
        let clip = read_bvh(&bytes, "seed", &BvhLimits::default()).unwrap();
        assert!(clip.frame_count() >= 1);
        count += 1;
    }
    assert!(count >= 4);
}
