//! What crosses between the editor and the page's loading worker for a clip, arbitrary: the
//! first byte chooses a `ClipJob` (the rest is its bytes: the job must decode or say what is
//! wrong, and a decoded job encodes to the same bytes' job again) or a `ClipTransfer` (the
//! second byte is the body's DOF count, the rest the head then each part of frames, each after
//! its length, 4 bytes little-endian: it must decode to an opened clip that fits that many
//! DOF or to an error that says something). Never a panic.
#![no_main]

use libfuzzer_sys::fuzz_target;
use stance_asset::{ClipJob, ClipTransfer};

#[path = "../common/parts.rs"]
mod parts;
use parts::split_parts;

fuzz_target!(|data: &[u8]| {
    let Some((&selector, rest)) = data.split_first() else {
        return;
    };
    if selector & 1 == 0 {
        match ClipJob::from_bytes(rest) {
            Ok(job) => {
                let again = ClipJob::from_bytes(&job.to_bytes().expect("a decoded job encodes"));
                assert_eq!(again.ok(), Some(job), "the job comes back the same");
            }
            Err(e) => assert!(!e.to_string().trim().is_empty(), "empty error: {e:?}"),
        }
        return;
    }
    let Some((&dofs, rest)) = rest.split_first() else {
        return;
    };
    let mut parts = split_parts(rest);
    if parts.is_empty() {
        return;
    }
    let head = parts.remove(0);
    match (ClipTransfer { head, parts }).into_opened(usize::from(dofs)) {
        Ok(opened) => {
            assert!(
                opened
                    .retargeted
                    .postures
                    .iter()
                    .all(|p| p.values().len() == usize::from(dofs))
            );
            assert_eq!(opened.retargeted.postures.len(), opened.clip.frames.len());
        }
        Err(e) => assert!(!e.to_string().trim().is_empty(), "empty error: {e:?}"),
    }
});
