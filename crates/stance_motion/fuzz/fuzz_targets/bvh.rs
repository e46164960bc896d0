//! The BVH reader on arbitrary bytes. Must never panic; every error must name its line and
//! field. What loads is written again and read back.
//!
//! Seeds: `fuzz/seeds/bvh/` (small valid files in several dialects); `scripts/fuzz.sh bvh` runs
//! it from them.
#![no_main]

use libfuzzer_sys::fuzz_target;
use stance_motion::{BvhLimits, BvhWriteOptions, read_bvh, write_bvh};

fuzz_target!(|data: &[u8]| {
    // Tighter limits than the defaults keep each run fast.
    let limits = BvhLimits {
        max_bytes: 1 << 20,
        max_frames: 10_000,
        max_values: 1_000_000,
        ..BvhLimits::default()
    };
    let clip = match read_bvh(data, "fuzz", &limits) {
        Ok(clip) => clip,
        Err(e) => {
            assert!(e.line() >= 1 && !e.field().is_empty(), "{e:?}");
            return;
        }
    };
    let text = write_bvh(&clip, &BvhWriteOptions::default());
    let again = read_bvh(text.as_bytes(), "fuzz", &BvhLimits::default());
    assert!(again.is_ok(), "{again:?}");
});
