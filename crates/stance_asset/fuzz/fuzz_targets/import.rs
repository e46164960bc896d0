//! The glTF/GLB/VRM importer on arbitrary bytes: the first byte picks the options, the rest
//! is the file. Must never panic; every error must say something. With bit 2 of the selector
//! the file is a `.gltf` given with external files (multi-file glTF): its second half is every
//! file its URIs name. With bit 3 the caller gives images 0 and 1 decoded, as the browser does
//! (`load_avatar_with_images`): image 0 at the size bits 4 to 7 pick (a width over the limit
//! among them), image 1 with a pixel too few, and image 2's pixels to follow
//! (`HostImages::to_follow`, filled before the transfer as the page does). What loads is also built into a solver skeleton,
//! posed at rest, exported and imported again (a VRM stays a VRM), and handed through the
//! import worker's transfer bytes (it comes back equal); its short animations become clips.
//! A file loaded without requiring a humanoid is also read as a prop's static mesh
//! (`load_prop_mesh`): its parts whole (every corner a vertex, a normal per vertex) inside
//! its bounds, or an error that says something.
//!
//! Seeds: `fuzz/seeds/import/`, small valid files prefixed with their selector byte (a skinned
//! LOA2 GLB, textured, a `.gltf` with data URIs, a `.gltf` with its `.bin` in the multi-file
//! layout, VRM 0.x and 1.0, EXT_meshopt_compression, an animation, a static triangle, images
//! given decoded), written
//! by `cargo test -p stance_asset --test all fuzz_seeds:: -- --ignored`; `scripts/fuzz.sh import`
//! runs the target from them.
#![no_main]

use libfuzzer_sys::fuzz_target;
use stance_asset::{
    AvatarTransfer, DecodedImage, HostImages, Limits, LoadOptions, clip_from_animation,
    export_glb, find_resource, load_avatar, load_avatar_with_images, load_prop_mesh,
};

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
    let (file, resources) = if selector & 4 != 0 {
        let (main, rest) = file.split_at(file.len() / 2);
        (main, vec![("any".to_owned(), rest.to_vec())])
    } else {
        (file, Vec::new())
    };
    let mut resolve = |uri: &str| {
        let found = find_resource(&resources, uri).map(<[u8]>::to_vec);
        found.or_else(|| resources.first().map(|(_, bytes)| bytes.clone()))
    };
    let decoded = if selector & 8 != 0 {
        // At most 16 KiB of pixels: every input pays for them.
        const WIDTHS: [u32; 4] = [1, 2, 3, 1025];
        let width = WIDTHS[usize::from(selector >> 4) & 3];
        let height = u32::from(selector >> 6) + 1;
        let size = (width * height * 4) as usize;
        vec![
            DecodedImage {
                index: 0,
                width,
                height,
                rgba8: vec![200; size],
            },
            DecodedImage {
                index: 1,
                width,
                height,
                rgba8: vec![100; size - 1],
            },
        ]
    } else {
        Vec::new()
    };
    let to_follow = if selector & 8 != 0 { vec![2] } else { Vec::new() };
    let images = HostImages { decoded, to_follow };
    let mut avatar = match load_avatar_with_images(file, &options, &mut resolve, images) {
        Ok(avatar) => avatar,
        Err(e) => {
            assert!(!e.to_string().trim().is_empty(), "empty error: {e:?}");
            return;
        }
    };
    if !options.require_humanoid {
        match load_prop_mesh(file, &mut resolve) {
            Ok(mesh) => {
                assert!(mesh.min.cmple(mesh.max).all(), "bounds {mesh:?}");
                for part in &mesh.parts {
                    let count = part.positions.len();
                    assert_eq!(part.normals.len(), count, "a normal per vertex");
                    assert!(part.indices.iter().all(|&i| (i as usize) < count));
                }
            }
            Err(e) => assert!(!e.to_string().trim().is_empty(), "empty error: {e:?}"),
        }
    }
    // The pixels that follow, given as the page gives the browser's (of the header's size).
    for texture in &mut avatar.textures {
        if texture.rgba8.is_empty() {
            let size = texture.width as usize * texture.height as usize * 4;
            texture.rgba8 = std::sync::Arc::new(vec![7; size]);
        }
    }
    // Handed to the editor's thread as the page's import worker does, it comes back equal.
    let transfer = AvatarTransfer::new(avatar.clone()).expect("an imported avatar encodes");
    assert_eq!(transfer.into_avatar().as_ref(), Ok(&avatar), "transfer round trip");
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
    if let Ok(bytes) = export_glb(&avatar)
        && let Ok(again) = load_avatar(&bytes, &options)
    {
        assert_eq!(again.vrm.is_some(), avatar.vrm.is_some(), "a VRM stays a VRM");
    }
});
