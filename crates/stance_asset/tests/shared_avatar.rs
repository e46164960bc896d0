//! The vendored real avatar (`tests/fixtures/avatars`, VALID avatars, MIT;
//! EXT_meshopt_compression, KHR_mesh_quantization, WebP textures): loads, maps the 18 LOA1
//! joints, and a hand-reach task moves its hand.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

#[cfg(target_arch = "wasm32")]
use wasm_bindgen_test::wasm_bindgen_test as test;

use crate::common;

use glam::DVec3;
use stance_asset::{LoadOptions, export_glb, load_avatar};
use stance_hanim::{LevelOfArticulation, SkeletonOptions};
use stance_ik::{Axes, Effector, Frames, Posture, Solver, SolverSettings, Task, TaskKind};

const AVATAR: &[u8] = include_bytes!("../../../tests/fixtures/avatars/Black_F_2_Casual.glb");

#[test]
fn shared_avatar_loads_and_maps_loa1() {
    let avatar = load_avatar(AVATAR, &LoadOptions::default()).unwrap();
    assert!(
        avatar
            .extensions
            .iter()
            .any(|e| e == "EXT_meshopt_compression")
    );
    let missing = avatar.mapping.missing(LevelOfArticulation::Loa1);
    assert!(missing.is_empty(), "missing {missing:?}");
    assert!(avatar.vertex_count() > 10_000);
    assert_eq!(avatar.textures.len(), 3);
    // Several skins and meshes (one per part of the body, hair, eyes, teeth).
    assert_eq!((avatar.skins.len(), avatar.meshes.len()), (8, 8));
    assert!(avatar.meshes.iter().all(|m| m.primitives.iter().all(|p| {
        p.joints.len() == p.positions.len()
            && p.weights
                .iter()
                .all(|w| (w.iter().sum::<f32>() - 1.0).abs() < 1e-4)
            && p.normals
                .iter()
                .all(|n| ((n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt() - 1.0).abs() < 1e-3)
    })));
    // The base-colour textures (WebP) are decoded; the normal map is not drawn.
    for m in &avatar.materials {
        let t = &avatar.textures[m.base_color_texture.unwrap()];
        assert!(t.width >= 64 && t.rgba8.len() == (t.width * t.height * 4) as usize);
    }
    // Normalised: a standing person about 1.5-1.9 m tall, left on +X, facing +Z.
    let p = avatar.hanim_rest_positions();
    let at = |h: &str| p[avatar.mapping.source_of(h).unwrap()];
    let head = at("skullbase");
    assert!((1.3..1.8).contains(&head.y), "skullbase at {head}");
    assert!(at("l_hip").x > at("r_hip").x);
    assert!(at("l_shoulder").x > 0.1);
    let toe = at("l_metatarsophalangeal_2");
    let ankle = at("l_talocrural");
    assert!(toe.z > ankle.z, "toes point +Z: {toe} vs {ankle}");
    for (src, m) in avatar
        .mapping
        .matches()
        .iter()
        .map(|m| (avatar.nodes[m.source].name.clone(), m))
    {
        eprintln!("{src} -> {} {:?} {}", m.hanim, m.method, m.confidence);
    }
}

#[test]
fn hand_reach_moves_the_hand_at_loa1_and_loa2() {
    let mut avatar = load_avatar(
        AVATAR,
        &LoadOptions {
            decode_textures: false,
            ..Default::default()
        },
    )
    .unwrap();
    for loa in [LevelOfArticulation::Loa1, LevelOfArticulation::Loa2] {
        let body = avatar
            .skeleton(&SkeletonOptions {
                loa,
                ..Default::default()
            })
            .unwrap();
        let s = &body.skeleton;
        let hand = s.joint_index("l_radiocarpal").unwrap();
        let rest = Posture::rest(s);
        let start = Frames::new(s, &rest).joint_position[hand];
        // In front of the left shoulder, within reach whatever the rest pose (a T-pose here).
        let shoulder = Frames::new(s, &rest).joint_position[s.joint_index("l_shoulder").unwrap()];
        let target = shoulder + DVec3::new(0.1, -0.05, 0.35);
        assert!((start - target).length() > 0.2);
        let root = s.joint_index("humanoid_root").unwrap();
        let root_pos = Frames::new(s, &rest).joint_position[root];
        let tasks = vec![
            Task {
                level: 1,
                ..Task::new(TaskKind::Position {
                    effector: Effector {
                        joint: root,
                        point: DVec3::ZERO,
                    },
                    axes: Axes::XYZ,
                    target: root_pos,
                })
            },
            Task {
                level: 2,
                ..Task::new(TaskKind::Position {
                    effector: Effector {
                        joint: hand,
                        point: DVec3::ZERO,
                    },
                    axes: Axes::XYZ,
                    target,
                })
            },
        ];
        let mut posture = rest.clone();
        let mut solver = Solver::new(SolverSettings::default()).unwrap();
        solver
            .solve_with_clock(s, &tasks, &mut posture, None)
            .unwrap();
        let reached = Frames::new(s, &posture).joint_position[hand];
        assert!(
            (reached - target).length() < 0.02,
            "{loa:?}: hand at {reached}, target {target}"
        );
        // The posed nodes move the hand node too.
        avatar.apply_posture(&body, &posture).unwrap();
        let world = avatar.world_from_locals(&avatar.pose_locals());
        let node = avatar.mapping.source_of("l_radiocarpal").unwrap();
        let moved = avatar
            .hanim_from_file
            .transform_point3(world[node].w_axis.truncate());
        assert!(
            (moved - target).length() < 0.02,
            "node at {moved}, target {target}"
        );
        // Export and re-import give the same posture.
        let bytes = export_glb(&avatar).unwrap();
        let again = load_avatar(&bytes, &LoadOptions::default()).unwrap();
        let body2 = again
            .skeleton(&SkeletonOptions {
                loa,
                ..Default::default()
            })
            .unwrap();
        let back = again.current_posture(&body2).unwrap();
        let err = back
            .values()
            .iter()
            .zip(posture.values())
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        assert!(err < 1e-5, "{loa:?}: re-imported posture differs by {err}");
    }
}

#[cfg(not(target_arch = "wasm32"))]
#[test]
fn load_time_and_memory_report() {
    let rss_before = common::status_kb("VmRSS:");
    let t = std::time::Instant::now();
    let geometry_only = load_avatar(
        AVATAR,
        &LoadOptions {
            decode_textures: false,
            ..Default::default()
        },
    )
    .unwrap();
    let geometry_secs = t.elapsed().as_secs_f64();
    drop(geometry_only);
    let t = std::time::Instant::now();
    let avatar = load_avatar(AVATAR, &LoadOptions::default()).unwrap();
    let secs = t.elapsed().as_secs_f64();
    let rss_after = common::status_kb("VmRSS:");
    let mesh_bytes: usize = avatar
        .meshes
        .iter()
        .flat_map(|m| &m.primitives)
        .map(|p| p.positions.len() * (12 + 12 + 8 + 8 + 16) + p.indices.len() * 4)
        .sum();
    let tex_bytes: usize = avatar.textures.iter().map(|t| t.rgba8.len()).sum();
    eprintln!(
        "shared avatar: load {:.1} ms ({:.1} ms without texture decoding), {} vertices, {} triangles, \
         meshes {:.1} MB, textures {:.1} MB RGBA8, RSS +{:.1} MB (peak {:.1} MB)",
        secs * 1e3,
        geometry_secs * 1e3,
        avatar.vertex_count(),
        avatar
            .meshes
            .iter()
            .flat_map(|m| &m.primitives)
            .map(|p| p.indices.len() / 3)
            .sum::<usize>(),
        mesh_bytes as f64 / 1e6,
        tex_bytes as f64 / 1e6,
        (rss_after.saturating_sub(rss_before)) as f64 / 1e3,
        common::status_kb("VmHWM:") as f64 / 1e3,
    );
}

/// The EXT_meshopt_compression views of the real avatar: (bufferView index, compressed
/// byteLength).
#[cfg(not(target_arch = "wasm32"))]
fn meshopt_views(json: &serde_json::Value) -> Vec<(usize, u64)> {
    json["bufferViews"]
        .as_array()
        .unwrap()
        .iter()
        .enumerate()
        .filter_map(|(i, v)| {
            let ext = v.get("extensions")?.get("EXT_meshopt_compression")?;
            Some((i, ext["byteLength"].as_u64().unwrap()))
        })
        .collect()
}

/// Each compressed stream cut short (the GLB container and the JSON stay valid, only the
/// compressed range shrinks): the decoder itself runs out of data and the error names the
/// view.
#[cfg(not(target_arch = "wasm32"))]
#[test]
fn truncated_meshopt_streams_fail_in_the_decoder() {
    let (json, bin) = common::split(AVATAR);
    let views = meshopt_views(&json);
    assert_eq!(views.len(), 5);
    for &(view, len) in &views {
        for cut in [0, 1, len / 2, len - 1] {
            let mut j = json.clone();
            j["bufferViews"][view]["extensions"]["EXT_meshopt_compression"]["byteLength"] =
                cut.into();
            let e = load_avatar(
                &common::join(&j, &bin),
                &LoadOptions {
                    decode_textures: false,
                    ..Default::default()
                },
            )
            .err()
            .unwrap_or_else(|| panic!("view {view} cut to {cut} of {len} bytes loaded"))
            .to_string();
            assert!(
                e.starts_with(&format!("buffer view {view}: meshopt decoding failed")),
                "view {view} cut to {cut}: {e}"
            );
        }
    }
}

/// The EXT_meshopt_compression streams of the real avatar, mutated and/or cut short inside
/// a valid container: errors or garbage geometry, never a panic.
#[cfg(not(target_arch = "wasm32"))]
mod meshopt_fuzz {
    use proptest::prelude::*;

    use super::*;

    proptest! {
        #![proptest_config(ProptestConfig { cases: 40, ..ProptestConfig::default() })]

        #[test]
        fn mutated_meshopt_streams_never_panic(
            edits in prop::collection::vec((any::<prop::sample::Index>(), any::<u8>()), 1..16),
            which in any::<prop::sample::Index>(),
            cut in any::<prop::sample::Index>(),
            truncate in any::<bool>(),
        ) {
            let (mut json, mut bin) = common::split(AVATAR);
            let views = meshopt_views(&json);
            // Byte edits anywhere in the compressed streams (they lie contiguously in buffer 0).
            let start = views
                .iter()
                .map(|&(v, _)| json["bufferViews"][v]["extensions"]["EXT_meshopt_compression"]["byteOffset"].as_u64().unwrap())
                .min()
                .unwrap() as usize;
            let end = views
                .iter()
                .map(|&(v, len)| json["bufferViews"][v]["extensions"]["EXT_meshopt_compression"]["byteOffset"].as_u64().unwrap() + len)
                .max()
                .unwrap() as usize;
            for (at, byte) in &edits {
                bin[start + at.index(end - start)] = *byte;
            }
            // Truncation of one stream, inside a valid container: reaches the decoder.
            if truncate {
                let (view, len) = views[which.index(views.len())];
                json["bufferViews"][view]["extensions"]["EXT_meshopt_compression"]["byteLength"] =
                    (cut.index(len as usize) as u64).into();
            }
            let result = load_avatar(
                &common::join(&json, &bin),
                &LoadOptions { decode_textures: false, ..Default::default() },
            );
            if truncate {
                prop_assert!(result.is_err(), "a truncated stream loaded");
            }
        }
    }
}

/// The committed `public/default-avatar.glb` is what `stance make-avatar` writes.
#[cfg(not(target_arch = "wasm32"))]
#[test]
fn committed_default_avatar_is_up_to_date() {
    let committed = include_bytes!("../../../public/default-avatar.glb");
    let fresh = export_glb(&stance_asset::make_default_avatar().unwrap()).unwrap();
    assert!(
        committed[..] == fresh[..],
        "public/default-avatar.glb is stale: run `cargo run -p stance_cli -- make-avatar public/default-avatar.glb`"
    );
}
