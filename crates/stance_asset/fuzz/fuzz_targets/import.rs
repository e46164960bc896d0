//! The glTF/GLB/VRM importer on arbitrary bytes: the first byte picks the options, the rest
//! is the file. Must never panic; every error must say something. What loads is also built
//! into a solver skeleton, posed at rest, exported and imported again; its short animations
//! become clips.
//!
//! Seeds are files prefixed with the selector byte, e.g. from `crates/stance_asset`:
//! `mkdir -p fuzz/corpus/import && (printf '\x02'; cat ../../public/default-avatar.glb) >
//! fuzz/corpus/import/default-avatar`.
#![no_main]

use libfuzzer_sys::fuzz_target;
use stance_asset::{Limits, LoadOptions, clip_from_animation, export_glb, load_avatar};

fuzz_target!(|data: &[u8]| {
    let Some((&selector, file)) = data.split_first() else {
        return;
    };
    // Tighter limits than the defaults keep each run fast and well under libFuzzer's RSS cap.
    let options = LoadOptions {
        limits: Limits {
            max_decoded_bytes: 256 << 20,
            max_accessor_count: 1 << 20,
            max_texture_side: 1024,
            ..Limits::default()
        },
        require_humanoid: selector & 1 == 0,
        decode_textures: selector & 2 != 0,
    };
    let avatar = match load_avatar(file, &options) {
        Ok(avatar) => avatar,
        Err(e) => {
            assert!(!e.to_string().trim().is_empty(), "empty error: {e:?}");
            return;
        }
    };
    if let Ok(body) = avatar.skeleton(&Default::default())
        && let Ok(posture) = avatar.current_posture(&body)
    {
        let _ = avatar.posed_locals(&body, &posture);
    }
    for (i, animation) in avatar.animations.iter().enumerate() {
        if animation.duration < 10.0 {
            let _ = clip_from_animation(&avatar, i, 30.0);
        }
    }
    if let Ok(bytes) = export_glb(&avatar) {
        let _ = load_avatar(&bytes, &options);
    }
});
