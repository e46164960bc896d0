//! glTF 2.0 / GLB / VRM import into an [`Avatar`].
//!
//! This module holds the container (GLB chunks, JSON), the import context, nodes and skins, and
//! the top-level [`import`]; buffers and accessors are read in `buffers`, textures and
//! materials in `materials`, meshes in `meshes`, animations in `animations`.

mod animations;
mod buffers;
mod materials;
mod meshes;
mod raster;

use animations::import_animations;
use materials::{import_materials, import_textures};
pub(crate) use meshes::compute_normals;
use meshes::import_meshes;

use std::borrow::Cow;
use std::collections::HashMap;

use glam::{DMat4, DQuat, DVec3, Mat4};
use gltf::json;
use serde_json::Value;
use stance_hanim::{LevelOfArticulation, Mapping};

use crate::model::{Avatar, Node, Skin, SourceFormat, Trs, VrmExtension};
use crate::{AssetError, Limits, LoadOptions};

const GLB_MAGIC: &[u8; 4] = b"glTF";
const CHUNK_JSON: u32 = 0x4E4F_534A;
const CHUNK_BIN: u32 = 0x004E_4942;

/// Extensions this importer understands (others listed in `extensionsRequired` are refused).
pub const SUPPORTED_EXTENSIONS: &[&str] = &[
    "KHR_mesh_quantization",
    "EXT_meshopt_compression",
    "KHR_materials_unlit",
    "EXT_texture_webp",
    "KHR_texture_transform",
    "KHR_materials_emissive_strength",
    "KHR_materials_specular",
    "KHR_materials_ior",
    "VRM",
    "VRMC_vrm",
    "VRMC_materials_mtoon",
    "VRMC_springBone",
    "VRMC_node_constraint",
];

/// A file's 64-bit size or index as `usize`, saturating (so that it fails the bounds checks
/// on 32-bit targets instead of wrapping).
fn sz(v: u64) -> usize {
    usize::try_from(v).unwrap_or(usize::MAX)
}

fn le_u32(bytes: &[u8], at: usize) -> Option<u32> {
    let b = bytes.get(at..at.checked_add(4)?)?;
    Some(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
}

/// JSON chunk, BIN chunk, whether it was a GLB.
type Container<'a> = (&'a [u8], Option<&'a [u8]>, bool);

/// Splits a GLB into its JSON and BIN chunks, or returns the whole input as JSON.
fn split_container<'a>(bytes: &'a [u8], limits: &Limits) -> Result<Container<'a>, AssetError> {
    if bytes.len() as u64 > limits.max_file_bytes {
        return Err(AssetError::TooLarge {
            what: "file".into(),
            size: bytes.len() as u64,
            limit: limits.max_file_bytes,
        });
    }
    if bytes.len() >= 4 && &bytes[0..4] == GLB_MAGIC {
        let version = le_u32(bytes, 4)
            .ok_or_else(|| AssetError::BadGlb("truncated header (under 12 bytes)".into()))?;
        if version != 2 {
            return Err(AssetError::BadGlb(format!(
                "container version {version}, expected 2"
            )));
        }
        let length = le_u32(bytes, 8)
            .ok_or_else(|| AssetError::BadGlb("truncated header (under 12 bytes)".into()))?
            as usize;
        if length > bytes.len() {
            return Err(AssetError::BadGlb(format!(
                "header declares {length} bytes but the file has {} (truncated?)",
                bytes.len()
            )));
        }
        let body = &bytes[..length];
        let mut at = 12usize;
        let mut json_chunk = None;
        let mut bin_chunk = None;
        while at < body.len() {
            let (Some(len), Some(kind)) = (le_u32(body, at), le_u32(body, at + 4)) else {
                return Err(AssetError::BadGlb(format!(
                    "truncated chunk header at byte {at}"
                )));
            };
            let start = at + 8;
            let end = start
                .checked_add(len as usize)
                .filter(|&e| e <= body.len())
                .ok_or_else(|| {
                    AssetError::BadGlb(format!(
                        "chunk at byte {at} declares {len} bytes past the end of the file"
                    ))
                })?;
            match kind {
                CHUNK_JSON if json_chunk.is_none() => json_chunk = Some(&body[start..end]),
                CHUNK_BIN if bin_chunk.is_none() && json_chunk.is_some() => {
                    bin_chunk = Some(&body[start..end])
                }
                _ => {}
            }
            at = end.div_ceil(4) * 4;
        }
        let json = json_chunk.ok_or_else(|| AssetError::BadGlb("no JSON chunk".into()))?;
        Ok((json, bin_chunk, true))
    } else {
        let start = bytes.iter().position(|b| !b.is_ascii_whitespace());
        match start.map(|s| bytes[s]) {
            Some(b'{') => Ok((bytes, None, false)),
            _ => Err(AssetError::NotGltf(
                "neither a GLB container (magic `glTF`) nor a JSON object".into(),
            )),
        }
    }
}

/// Resolves external buffer/image URIs (relative paths); returns `None` when unavailable.
pub type Resolver<'a> = dyn FnMut(&str) -> Option<Vec<u8>> + 'a;

struct Ctx<'a> {
    root: json::Root,
    /// Buffer data: the GLB binary chunk is borrowed, data URIs and external files owned.
    buffers: Vec<Option<Cow<'a, [u8]>>>,
    bin: Option<&'a [u8]>,
    /// Decoded EXT_meshopt_compression views (charged once each). Plain views are never
    /// copied: they are borrowed from their buffer, so a file cannot multiply its memory by
    /// pointing many views or accessors at the same bytes.
    decoded_views: HashMap<usize, Vec<u8>>,
    limits: &'a Limits,
    decoded_bytes: u64,
    warnings: Vec<String>,
    /// Images the caller decoded (see [`crate::load_avatar_with_images`]).
    decoded_images: Vec<crate::DecodedImage>,
    /// Images whose pixels the caller gives later (see [`crate::HostImages::to_follow`]).
    images_to_follow: Vec<usize>,
}

fn bad_index(
    what: impl Into<String>,
    kind: &'static str,
    index: usize,
    count: usize,
) -> AssetError {
    AssetError::BadIndex {
        what: what.into(),
        kind,
        index,
        count,
    }
}

fn check_count(what: &str, size: usize, limit: usize) -> Result<(), AssetError> {
    if size > limit {
        return Err(AssetError::TooLarge {
            what: what.into(),
            size: size as u64,
            limit: limit as u64,
        });
    }
    Ok(())
}

fn trs_of(node: &json::Node) -> Trs {
    if let Some(m) = node.matrix {
        let m = Mat4::from_cols_array(&m).as_dmat4();
        if m.is_finite() {
            return Trs::from_matrix(&m);
        }
    }
    let t = node.translation.unwrap_or([0.0; 3]);
    let r = node.rotation.map_or([0.0, 0.0, 0.0, 1.0], |q| q.0);
    let s = node.scale.unwrap_or([1.0; 3]);
    let translation = DVec3::new(t[0] as f64, t[1] as f64, t[2] as f64);
    let rotation = DQuat::from_xyzw(r[0] as f64, r[1] as f64, r[2] as f64, r[3] as f64);
    let rotation = if rotation.is_finite() && rotation.length() > 1e-6 {
        rotation.normalize()
    } else {
        DQuat::IDENTITY
    };
    let scale = DVec3::new(s[0] as f64, s[1] as f64, s[2] as f64);
    Trs {
        translation: if translation.is_finite() {
            translation
        } else {
            DVec3::ZERO
        },
        rotation,
        scale: if scale.is_finite() { scale } else { DVec3::ONE },
    }
}

fn trs_from_value(v: &Value) -> Option<Trs> {
    let arr = |k: &str, n: usize| -> Option<Vec<f64>> {
        let a = v.get(k)?.as_array()?;
        let out: Vec<f64> = a.iter().filter_map(Value::as_f64).collect();
        (out.len() == n && out.iter().all(|x| x.is_finite())).then_some(out)
    };
    let t = arr("translation", 3)?;
    let r = arr("rotation", 4)?;
    let s = arr("scale", 3)?;
    let q = DQuat::from_xyzw(r[0], r[1], r[2], r[3]);
    (q.length() > 1e-6).then(|| Trs {
        translation: DVec3::new(t[0], t[1], t[2]),
        rotation: q.normalize(),
        scale: DVec3::new(s[0], s[1], s[2]),
    })
}

/// Parses and imports. See [`crate::load_avatar`].
pub fn import(
    bytes: &[u8],
    options: &LoadOptions,
    resolve: &mut Resolver<'_>,
    images: crate::HostImages,
) -> Result<Avatar, AssetError> {
    let limits = &options.limits;
    let (json_bytes, bin, is_glb) = split_container(bytes, limits)?;
    if json_bytes.len() as u64 > limits.max_json_bytes {
        return Err(AssetError::TooLarge {
            what: "JSON".into(),
            size: json_bytes.len() as u64,
            limit: limits.max_json_bytes,
        });
    }
    let raw: Value =
        serde_json::from_slice(json_bytes).map_err(|e| AssetError::BadJson(e.to_string()))?;
    let version = raw
        .get("asset")
        .and_then(|a| a.get("version"))
        .and_then(Value::as_str)
        .ok_or_else(|| AssetError::BadJson("missing asset.version".into()))?;
    if !version.starts_with("2.") {
        return Err(AssetError::UnsupportedVersion(version.to_owned()));
    }
    let root: json::Root =
        serde_json::from_value(raw).map_err(|e| AssetError::BadJson(e.to_string()))?;
    for ext in &root.extensions_required {
        if !SUPPORTED_EXTENSIONS.contains(&ext.as_str()) {
            return Err(AssetError::UnsupportedExtension(ext.clone()));
        }
    }
    check_count("nodes", root.nodes.len(), limits.max_nodes)?;
    check_count("meshes", root.meshes.len(), limits.max_meshes)?;
    check_count("accessors", root.accessors.len(), limits.max_accessors)?;
    check_count("bufferViews", root.buffer_views.len(), limits.max_accessors)?;
    check_count("buffers", root.buffers.len(), limits.max_buffers)?;
    check_count("images", root.images.len(), limits.max_images)?;
    check_count("materials", root.materials.len(), limits.max_materials)?;
    check_count(
        "textures",
        root.textures.len(),
        limits.max_images.saturating_mul(4),
    )?;
    check_count("skins", root.skins.len(), limits.max_meshes)?;
    let primitive_count: usize = root.meshes.iter().map(|m| m.primitives.len()).sum();
    check_count("primitives", primitive_count, limits.max_primitives)?;

    let mut ctx = Ctx {
        root,
        buffers: Vec::new(),
        bin,
        decoded_views: HashMap::new(),
        limits,
        decoded_bytes: 0,
        warnings: Vec::new(),
        decoded_images: images.decoded,
        images_to_follow: images.to_follow,
    };
    ctx.load_buffers(resolve)?;

    let nodes = import_nodes(&ctx)?;
    let skins = import_skins(&mut ctx)?;
    let mut nodes = nodes;
    for (i, n) in ctx.root.nodes.iter().enumerate() {
        nodes[i].mesh = n.mesh.map(|m| m.value());
        nodes[i].skin = n.skin.map(|s| s.value());
        if let Some(m) = nodes[i].mesh
            && m >= ctx.root.meshes.len()
        {
            return Err(bad_index(
                format!("node {i}"),
                "mesh",
                m,
                ctx.root.meshes.len(),
            ));
        }
        if let Some(s) = nodes[i].skin
            && s >= skins.len()
        {
            return Err(bad_index(format!("node {i}"), "skin", s, skins.len()));
        }
    }
    let materials = import_materials(&ctx, ctx.root.textures.len())?;
    // Only base-colour textures are drawn: decode those, leave the others as placeholders.
    let used: Vec<usize> = materials
        .iter()
        .filter_map(|m| m.base_color_texture)
        .collect();
    let textures = import_textures(&mut ctx, options.decode_textures, &used, resolve)?;
    let meshes = import_meshes(&mut ctx, &nodes, &skins)?;

    let scene_roots = {
        let scene = ctx.root.scene.map(|s| s.value()).unwrap_or(0);
        match ctx.root.scenes.get(scene) {
            Some(s) => s
                .nodes
                .iter()
                .map(|n| n.value())
                .filter(|&n| n < nodes.len())
                .collect(),
            None => (0..nodes.len())
                .filter(|&i| nodes[i].parent.is_none())
                .collect(),
        }
    };

    // VRM humanoid bones.
    let ext = ctx.root.extensions.as_ref().map(|e| &e.others);
    let mut vrm_bones: Vec<(String, usize)> = Vec::new();
    let vrm = ["VRMC_vrm", "VRM"].iter().find_map(|name| {
        ext.and_then(|e| e.get(*name)).map(|value| VrmExtension {
            name: (*name).to_owned(),
            value: value.clone(),
        })
    });
    let mut format = if is_glb {
        SourceFormat::Glb
    } else {
        SourceFormat::Gltf
    };
    match vrm.as_ref().map(|v| (v.name.as_str(), &v.value)) {
        Some(("VRMC_vrm", vrm1)) => {
            format = SourceFormat::Vrm1;
            let bones = vrm1
                .pointer("/humanoid/humanBones")
                .and_then(Value::as_object);
            for (bone, v) in bones.into_iter().flatten() {
                if let Some(n) = v.get("node").and_then(Value::as_u64) {
                    vrm_bones.push((bone.clone(), sz(n)));
                }
            }
        }
        Some((_, vrm0)) => {
            format = SourceFormat::Vrm0;
            let bones = vrm0
                .pointer("/humanoid/humanBones")
                .and_then(Value::as_array);
            for b in bones.into_iter().flatten() {
                if let (Some(bone), Some(n)) = (
                    b.get("bone").and_then(Value::as_str),
                    b.get("node").and_then(Value::as_u64),
                ) {
                    vrm_bones.push((bone.to_owned(), sz(n)));
                }
            }
        }
        None => {}
    }
    for (bone, n) in &vrm_bones {
        if *n >= nodes.len() {
            return Err(bad_index(
                format!("VRM humanoid bone `{bone}`"),
                "node",
                *n,
                nodes.len(),
            ));
        }
    }
    let has_morphs = ctx
        .root
        .meshes
        .iter()
        .any(|m| m.primitives.iter().any(|p| p.targets.is_some()));
    if has_morphs {
        ctx.warnings
            .push("morph targets are ignored (the rest shape is drawn)".into());
    }
    let animations = import_animations(&mut ctx, nodes.len())?;

    let mut avatar = Avatar {
        format,
        nodes,
        scene_roots,
        skins,
        meshes,
        materials,
        textures,
        hanim_from_file: DMat4::IDENTITY,
        mapping: Mapping::empty(0),
        animations,
        extensions: ctx.root.extensions_used.clone(),
        vrm,
        warnings: std::mem::take(&mut ctx.warnings),
    };
    let vrm0 = format == SourceFormat::Vrm0;
    avatar.mapping = Mapping::auto(&avatar.source_joints(), &vrm_bones, vrm0);
    let (hanim_from_file, scale_warning) = crate::normalize::hanim_from_file(&avatar);
    avatar.hanim_from_file = hanim_from_file;
    avatar.warnings.extend(scale_warning);
    let missing = avatar.mapping.missing(LevelOfArticulation::Loa1);
    if !missing.is_empty() {
        if options.require_humanoid {
            return Err(AssetError::NotHumanoid {
                missing: missing.into_iter().map(str::to_owned).collect(),
            });
        }
        avatar.warnings.push(format!(
            "not a complete humanoid: no joint found for {}",
            missing.join(", ")
        ));
    }
    Ok(avatar)
}

fn import_nodes(ctx: &Ctx<'_>) -> Result<Vec<Node>, AssetError> {
    let n = ctx.root.nodes.len();
    let mut nodes: Vec<Node> = ctx
        .root
        .nodes
        .iter()
        .enumerate()
        .map(|(i, node)| {
            let pose = trs_of(node);
            let rest = node
                .extras
                .as_ref()
                .and_then(|raw| serde_json::from_str::<Value>(raw.get()).ok())
                .and_then(|v| v.get("stance_rest").and_then(trs_from_value))
                .unwrap_or(pose);
            Node {
                name: node.name.clone().unwrap_or_else(|| format!("node{i}")),
                parent: None,
                children: Vec::new(),
                rest,
                pose,
                mesh: None,
                skin: None,
            }
        })
        .collect();
    for (i, node) in ctx.root.nodes.iter().enumerate() {
        for c in node.children.iter().flatten() {
            let c = c.value();
            if c >= n {
                return Err(bad_index(format!("node {i} children"), "node", c, n));
            }
            if c == i {
                return Err(AssetError::BadHierarchy(format!(
                    "node {i} is its own child"
                )));
            }
            if let Some(p) = nodes[c].parent {
                return Err(AssetError::BadHierarchy(format!(
                    "node {c} has two parents ({p} and {i})"
                )));
            }
            nodes[c].parent = Some(i);
            nodes[i].children.push(c);
        }
    }
    // Cycles: every walk up must end within n steps.
    for i in 0..n {
        let mut cur = nodes[i].parent;
        let mut steps = 0;
        while let Some(p) = cur {
            steps += 1;
            if steps > n {
                return Err(AssetError::BadHierarchy(format!("cycle through node {i}")));
            }
            cur = nodes[p].parent;
        }
    }
    Ok(nodes)
}

fn import_skins(ctx: &mut Ctx<'_>) -> Result<Vec<Skin>, AssetError> {
    let mut skins = Vec::new();
    let n = ctx.root.nodes.len();
    for i in 0..ctx.root.skins.len() {
        let skin = ctx.root.skins[i].clone();
        check_count(
            &format!("skin {i} joints"),
            skin.joints.len(),
            ctx.limits.max_joints_per_skin,
        )?;
        let joints: Vec<usize> = skin.joints.iter().map(|j| j.value()).collect();
        if let Some(&bad) = joints.iter().find(|&&j| j >= n) {
            return Err(bad_index(format!("skin {i} joints"), "node", bad, n));
        }
        let ibms = match skin.inverse_bind_matrices {
            Some(acc) => {
                let (v, comps) = ctx.read(acc.value(), &format!("skin {i} inverseBindMatrices"))?;
                if comps != 16 || v.len() / 16 != joints.len() {
                    return Err(AssetError::BadAccessor(format!(
                        "skin {i}: inverseBindMatrices must be {} MAT4, got {} elements of {comps} components",
                        joints.len(),
                        v.len() / comps.max(1)
                    )));
                }
                v.chunks_exact(16)
                    .map(|c| {
                        let mut a = [0f32; 16];
                        a.copy_from_slice(c);
                        let m = Mat4::from_cols_array(&a);
                        if m.is_finite() { m } else { Mat4::IDENTITY }
                    })
                    .collect()
            }
            None => vec![Mat4::IDENTITY; joints.len()],
        };
        skins.push(Skin {
            name: skin.name.clone().unwrap_or_else(|| format!("skin{i}")),
            joints,
            inverse_bind_matrices: ibms,
        });
    }
    Ok(skins)
}
