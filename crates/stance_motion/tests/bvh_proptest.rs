#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]
//! Mutated files never panic; random clips round-trip through write and read.
// Native only: proptest persists failures in files, which the browser has not.
#![cfg(not(target_arch = "wasm32"))]

use glam::{DQuat, DVec3};
use proptest::prelude::*;
use stance_hanim::Mapping;
use stance_motion::{
    BvhLimits, BvhWriteOptions, Clip, ClipFrame, ClipJoint, EulerOrder, read_bvh, write_bvh,
};

const SEED: &str = "HIERARCHY\nROOT Hips\n{\n\tOFFSET 0 1 0\n\tCHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation\n\tJOINT LeftArm\n\t{\n\t\tOFFSET 0.2 0.0-1e-3 0\n\t\tCHANNELS 3 Yrotation Xrotation Zrotation\n\t\tEnd Site\n\t\t{\n\t\t\tOFFSET 0.3 0 0\n\t\t}\n\t}\n}\nMOTION\nFrames: 2\nFrame Time: 0.04\n0 1 0 10 20 30 1.5e1 -5 2\n0 1.1 0 -10 20 -30 15 5 -2\n";

fn limits() -> BvhLimits {
    BvhLimits {
        max_frames: 1000,
        max_values: 100_000,
        ..BvhLimits::default()
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 300, ..ProptestConfig::default() })]

    #[test]
    fn mutated_files_never_panic(
        cut in 0usize..400,
        flips in proptest::collection::vec((0usize..400, any::<u8>()), 0..4),
        insert in proptest::collection::vec(any::<u8>(), 0..6),
        at in 0usize..400,
    ) {
        let mut bytes = SEED.as_bytes().to_vec();
        for (i, b) in flips {
            if let Some(x) = bytes.get_mut(i) {
                *x = b;
            }
        }
        let at = at.min(bytes.len());
        bytes.splice(at..at, insert);
        bytes.truncate(cut.max(1).min(bytes.len()));
        match read_bvh(&bytes, "m", &limits()) {
            Ok(clip) => {
                let text = write_bvh(&clip, &BvhWriteOptions::default());
                let _ = read_bvh(text.as_bytes(), "m", &limits());
            }
            Err(e) => {
                prop_assert!(e.line() >= 1);
                prop_assert!(!e.field().is_empty());
            }
        }
    }
}

fn random_clip(offsets: &[(f64, f64, f64)], angles: &[Vec<(f64, f64, f64)>]) -> Clip {
    let n = offsets.len();
    let joints: Vec<ClipJoint> = offsets
        .iter()
        .enumerate()
        .map(|(i, &(x, y, z))| ClipJoint {
            name: format!("bone{i}"),
            parent: i.checked_sub(1).map(|p| p / 2),
            offset: DVec3::new(x, y, z),
        })
        .collect();
    let frames = angles
        .iter()
        .map(|frame| ClipFrame {
            translations: joints
                .iter()
                .enumerate()
                .map(|(i, j)| {
                    if i == 0 {
                        j.offset + DVec3::new(frame[0].0, 0.0, 0.0)
                    } else {
                        j.offset
                    }
                })
                .collect(),
            rotations: (0..n)
                .map(|i| {
                    let (a, b, c) = frame[i % frame.len()];
                    EulerOrder::Yxz.to_quat([a, b, c])
                })
                .collect(),
        })
        .collect();
    Clip {
        name: "r".into(),
        frame_time: 1.0 / 60.0,
        joints,
        frames,
        mapping: Mapping::empty(n),
        notes: Vec::new(),
    }
}

fn angle(a: DQuat, b: DQuat) -> f64 {
    let d = a.conjugate() * b;
    2.0 * DVec3::new(d.x, d.y, d.z).length().atan2(d.w.abs())
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 64, ..ProptestConfig::default() })]

    #[test]
    fn random_clips_round_trip(
        offsets in proptest::collection::vec((-1.0f64..1.0, -1.0f64..1.0, -1.0f64..1.0), 1..8),
        angles in proptest::collection::vec(proptest::collection::vec((-3.1f64..3.1, -1.57f64..1.57, -3.1f64..3.1), 1..4), 0..4),
        order in 0usize..6,
    ) {
        let clip = random_clip(&offsets, &angles);
        // Names kept: the writer's depth-first order may differ from the clip's.
        let options = BvhWriteOptions { order: EulerOrder::ALL[order], hanim_names: false, ..BvhWriteOptions::default() };
        let back = read_bvh(write_bvh(&clip, &options).as_bytes(), "r", &BvhLimits::default()).unwrap();
        prop_assert_eq!(back.frame_count(), clip.frame_count());
        prop_assert_eq!(back.joints.len(), clip.joints.len());
        prop_assert_eq!(back.frame_time.to_bits(), clip.frame_time.to_bits());
        let index: Vec<usize> = clip
            .joints
            .iter()
            .map(|j| back.joints.iter().position(|b| b.name == j.name).unwrap())
            .collect();
        for (fa, fb) in clip.frames.iter().zip(&back.frames) {
            let (wa, wb) = (clip.world(fa), back.world(fb));
            for (i, &k) in index.iter().enumerate() {
                prop_assert!(angle(fa.rotations[i], fb.rotations[k]) < 1e-6);
                prop_assert!((wa[i].1 - wb[k].1).length() < 1e-6);
            }
        }
    }
}
