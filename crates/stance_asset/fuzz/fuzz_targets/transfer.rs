//! What the page's import worker hands to the editor (`AvatarTransfer::into_avatar`),
//! arbitrary: the avatar's bytes and each texture's pixels, each part after its length (4
//! bytes, little-endian; a part cut short ends the input). It must decode to an avatar or an
//! error that says something, never a panic; what decodes is used as the editor uses an avatar
//! (its skeleton, posed at rest, exported) and splits again into the same parts.
//!
//! Seeds: `fuzz/seeds/transfer/`, the import seeds' avatars as transfers, written by
//! `cargo test -p stance_asset --test all fuzz_seeds:: -- --ignored`.
#![no_main]

use libfuzzer_sys::fuzz_target;
use stance_asset::{AvatarTransfer, export_glb};

#[path = "../common/parts.rs"]
mod parts;
use parts::split_parts;

fuzz_target!(|data: &[u8]| {
    let mut parts = split_parts(data);
    if parts.is_empty() {
        return;
    }
    let avatar_bytes = parts.remove(0);
    let transfer = AvatarTransfer {
        avatar: avatar_bytes,
        pixels: parts,
    };
    let avatar = match transfer.clone().into_avatar() {
        Ok(avatar) => avatar,
        Err(e) => {
            assert!(!e.to_string().trim().is_empty(), "empty error: {e:?}");
            return;
        }
    };
    let again = AvatarTransfer::new(avatar.clone()).expect("a decoded avatar encodes");
    assert_eq!(again.pixels, transfer.pixels, "the pixels come back as given");
    if let Ok(body) = avatar.skeleton(&Default::default())
        && let Ok(posture) = avatar.current_posture(&body)
    {
        let _ = avatar.posed_locals(&body, &posture);
    }
    let _ = export_glb(&avatar);
});
