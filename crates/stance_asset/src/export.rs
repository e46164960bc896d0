//! GLB export: the rest skeleton (inverse bind matrices, `extras.stance_rest` per node) and
//! the current node transforms (the pose), meshes as float attributes, textures as PNG.
//! The output passes the Khronos glTF-Validator with no errors (tested in
//! `tests/avatar-export.test.mjs`).
//!
//! [`export_with`] writes the document and the GLB container; [`export_glb`] and
//! `export_animation::export_glb_animation` (which adds an animation through the same
//! [`Bin`]) call it.

use serde_json::{Map, Value, json};

use crate::AssetError;
use crate::model::{AlphaMode, Avatar, Trs, Wrap};

/// The binary chunk being written, with its buffer views and accessors.
pub(crate) struct Bin {
    data: Vec<u8>,
    views: Vec<Value>,
    accessors: Vec<Value>,
}

impl Bin {
    /// Appends a buffer view (4-byte aligned) holding `bytes`; returns its index.
    pub(crate) fn view(
        &mut self,
        bytes: &[u8],
        target: Option<u32>,
        stride: Option<usize>,
    ) -> usize {
        while !self.data.len().is_multiple_of(4) {
            self.data.push(0);
        }
        let mut v = Map::new();
        v.insert("buffer".into(), json!(0));
        v.insert("byteOffset".into(), json!(self.data.len()));
        v.insert("byteLength".into(), json!(bytes.len()));
        if let Some(t) = target {
            v.insert("target".into(), json!(t));
        }
        if let Some(s) = stride {
            v.insert("byteStride".into(), json!(s));
        }
        self.data.extend_from_slice(bytes);
        self.views.push(Value::Object(v));
        self.views.len() - 1
    }

    /// Appends a buffer view holding `bytes` and an accessor over it; returns the accessor.
    pub(crate) fn accessor(
        &mut self,
        bytes: &[u8],
        target: Option<u32>,
        component_type: u32,
        count: usize,
        type_: &str,
        min_max: Option<(Vec<f32>, Vec<f32>)>,
    ) -> usize {
        let view = self.view(bytes, target, None);
        let mut a = Map::new();
        a.insert("bufferView".into(), json!(view));
        a.insert("componentType".into(), json!(component_type));
        a.insert("count".into(), json!(count));
        a.insert("type".into(), json!(type_));
        if let Some((min, max)) = min_max {
            a.insert("min".into(), json!(min));
            a.insert("max".into(), json!(max));
        }
        self.accessors.push(Value::Object(a));
        self.accessors.len() - 1
    }
}

pub(crate) const FLOAT: u32 = 5126;
const UNSIGNED_SHORT: u32 = 5123;
const UNSIGNED_INT: u32 = 5125;
const ARRAY_BUFFER: u32 = 34962;
const ELEMENT_ARRAY_BUFFER: u32 = 34963;

pub(crate) fn f32s<const N: usize>(v: &[[f32; N]]) -> Vec<u8> {
    let mut out = Vec::with_capacity(v.len() * N * 4);
    for e in v {
        for x in e {
            out.extend_from_slice(&x.to_le_bytes());
        }
    }
    out
}

fn trs_json(t: &Trs) -> (Vec<f32>, Vec<f32>, Vec<f32>) {
    let q = t.rotation.normalize();
    let r = [q.x as f32, q.y as f32, q.z as f32, q.w as f32];
    let n = r.iter().map(|x| x * x).sum::<f32>().sqrt();
    let r = if n > 0.0 && n.is_finite() {
        r.map(|x| x / n)
    } else {
        [0.0, 0.0, 0.0, 1.0]
    };
    (
        t.translation.to_array().map(|x| x as f32).to_vec(),
        r.to_vec(),
        t.scale.to_array().map(|x| x as f32).to_vec(),
    )
}

/// Skin weights fit for the validator: duplicates merged, exactly normalised in f32.
fn clean_skin(joints: &[u16; 4], weights: &[f32; 4]) -> ([u16; 4], [f32; 4]) {
    let mut j = *joints;
    let mut w = *weights;
    for a in 0..4 {
        for b in a + 1..4 {
            if j[b] == j[a] && w[b] > 0.0 {
                w[a] += w[b];
                w[b] = 0.0;
            }
        }
    }
    for k in 0..4 {
        if w[k] <= 0.0 || !w[k].is_finite() {
            w[k] = 0.0;
            j[k] = 0;
        }
    }
    let sum: f32 = w.iter().sum();
    if sum <= 0.0 {
        return ([0; 4], [1.0, 0.0, 0.0, 0.0]);
    }
    for x in &mut w {
        *x /= sum;
    }
    let big = (0..4).max_by(|&a, &b| w[a].total_cmp(&w[b])).unwrap_or(0);
    let others: f32 = (0..4).filter(|&k| k != big).map(|k| w[k]).sum();
    w[big] = 1.0 - others;
    // Zero-weight slots after the first must not repeat a used joint with weight.
    (j, w)
}

fn encode_png(width: u32, height: u32, rgba: &[u8]) -> Result<Vec<u8>, AssetError> {
    let error = |e: png::EncodingError| AssetError::Export(format!("PNG encoding: {e}"));
    let mut out = Vec::new();
    let mut encoder = png::Encoder::new(&mut out, width, height);
    encoder.set_color(png::ColorType::Rgba);
    encoder.set_depth(png::BitDepth::Eight);
    let mut writer = encoder.write_header().map_err(error)?;
    writer.write_image_data(rgba).map_err(error)?;
    writer.finish().map_err(error)?;
    Ok(out)
}

/// Writes the avatar as GLB with its nodes' current transforms (`Node::pose`).
pub fn export_glb(avatar: &Avatar) -> Result<Vec<u8>, AssetError> {
    export_with(avatar, |_| Ok(Vec::new()))
}

/// Writes the avatar as GLB; `animations` adds its data to the binary chunk and returns the
/// document's `animations` array (left out when empty).
pub(crate) fn export_with(
    avatar: &Avatar,
    animations: impl FnOnce(&mut Bin) -> Result<Vec<Value>, AssetError>,
) -> Result<Vec<u8>, AssetError> {
    let mut bin = Bin {
        data: Vec::new(),
        views: Vec::new(),
        accessors: Vec::new(),
    };
    // Meshes.
    let mut meshes = Vec::new();
    for mesh in &avatar.meshes {
        let mut prims = Vec::new();
        for p in &mesh.primitives {
            if p.positions.is_empty() || p.indices.is_empty() {
                continue;
            }
            let mut min = [f32::MAX; 3];
            let mut max = [f32::MIN; 3];
            for v in &p.positions {
                for k in 0..3 {
                    min[k] = min[k].min(v[k]);
                    max[k] = max[k].max(v[k]);
                }
            }
            let count = p.positions.len();
            let mut attrs = Map::new();
            let pos = bin.accessor(
                &f32s(&p.positions),
                Some(ARRAY_BUFFER),
                FLOAT,
                count,
                "VEC3",
                Some((min.to_vec(), max.to_vec())),
            );
            attrs.insert("POSITION".into(), json!(pos));
            if p.normals.len() == count {
                let n = bin.accessor(
                    &f32s(&p.normals),
                    Some(ARRAY_BUFFER),
                    FLOAT,
                    count,
                    "VEC3",
                    None,
                );
                attrs.insert("NORMAL".into(), json!(n));
            }
            if p.uvs.len() == count {
                let t = bin.accessor(
                    &f32s(&p.uvs),
                    Some(ARRAY_BUFFER),
                    FLOAT,
                    count,
                    "VEC2",
                    None,
                );
                attrs.insert("TEXCOORD_0".into(), json!(t));
            }
            if p.joints.len() == count && p.weights.len() == count {
                let mut jb = Vec::with_capacity(count * 8);
                let mut wv = Vec::with_capacity(count);
                for (j, w) in p.joints.iter().zip(&p.weights) {
                    let (j, w) = clean_skin(j, w);
                    for x in j {
                        jb.extend_from_slice(&x.to_le_bytes());
                    }
                    wv.push(w);
                }
                let j = bin.accessor(&jb, Some(ARRAY_BUFFER), UNSIGNED_SHORT, count, "VEC4", None);
                let w = bin.accessor(&f32s(&wv), Some(ARRAY_BUFFER), FLOAT, count, "VEC4", None);
                attrs.insert("JOINTS_0".into(), json!(j));
                attrs.insert("WEIGHTS_0".into(), json!(w));
            }
            let mut ib = Vec::with_capacity(p.indices.len() * 4);
            for i in &p.indices {
                ib.extend_from_slice(&i.to_le_bytes());
            }
            let idx = bin.accessor(
                &ib,
                Some(ELEMENT_ARRAY_BUFFER),
                UNSIGNED_INT,
                p.indices.len(),
                "SCALAR",
                None,
            );
            let mut prim = Map::new();
            prim.insert("attributes".into(), Value::Object(attrs));
            prim.insert("indices".into(), json!(idx));
            prim.insert("mode".into(), json!(4));
            if let Some(m) = p.material {
                prim.insert("material".into(), json!(m));
            }
            prims.push(Value::Object(prim));
        }
        meshes.push(json!({"name": mesh.name, "primitives": prims}));
    }
    // Skins.
    let mut skins = Vec::new();
    for skin in &avatar.skins {
        let mut b = Vec::with_capacity(skin.inverse_bind_matrices.len() * 64);
        for m in &skin.inverse_bind_matrices {
            let mut a = m.to_cols_array();
            // Exactly affine, as the validator requires.
            a[3] = 0.0;
            a[7] = 0.0;
            a[11] = 0.0;
            a[15] = 1.0;
            for x in a {
                b.extend_from_slice(&x.to_le_bytes());
            }
        }
        let acc = bin.accessor(
            &b,
            None,
            FLOAT,
            skin.inverse_bind_matrices.len(),
            "MAT4",
            None,
        );
        skins.push(json!({"name": skin.name, "joints": skin.joints, "inverseBindMatrices": acc}));
    }
    // Textures (PNG), one image per texture.
    let mut images = Vec::new();
    let mut textures = Vec::new();
    let mut samplers = Vec::new();
    for (i, t) in avatar.textures.iter().enumerate() {
        let png = encode_png(t.width, t.height, &t.rgba8)?;
        let view = bin.view(&png, None, None);
        images.push(json!({"name": t.name, "bufferView": view, "mimeType": "image/png"}));
        let wrap = |w: Wrap| match w {
            Wrap::Repeat => 10497,
            Wrap::Clamp => 33071,
            Wrap::Mirror => 33648,
        };
        samplers.push(json!({"wrapS": wrap(t.wrap_u), "wrapT": wrap(t.wrap_v)}));
        textures.push(json!({"source": i, "sampler": i}));
    }
    let mut any_unlit = false;
    let materials: Vec<Value> = avatar
        .materials
        .iter()
        .map(|m| {
            let mut pbr = Map::new();
            pbr.insert(
                "baseColorFactor".into(),
                json!(m.base_color_factor.map(|x| x.clamp(0.0, 1.0))),
            );
            pbr.insert("metallicFactor".into(), json!(0.0));
            pbr.insert("roughnessFactor".into(), json!(0.8));
            if let Some(t) = m.base_color_texture.filter(|&t| t < avatar.textures.len()) {
                pbr.insert("baseColorTexture".into(), json!({"index": t}));
            }
            let mut o = Map::new();
            o.insert("name".into(), json!(m.name));
            o.insert("pbrMetallicRoughness".into(), Value::Object(pbr));
            if m.double_sided {
                o.insert("doubleSided".into(), json!(true));
            }
            match m.alpha_mode {
                AlphaMode::Opaque => {}
                AlphaMode::Mask => {
                    o.insert("alphaMode".into(), json!("MASK"));
                    o.insert("alphaCutoff".into(), json!(m.alpha_cutoff.max(0.0)));
                }
                AlphaMode::Blend => {
                    o.insert("alphaMode".into(), json!("BLEND"));
                }
            }
            if m.unlit {
                any_unlit = true;
                o.insert("extensions".into(), json!({"KHR_materials_unlit": {}}));
            }
            Value::Object(o)
        })
        .collect();
    // Nodes.
    let nodes: Vec<Value> = avatar
        .nodes
        .iter()
        .map(|n| {
            let (t, r, s) = trs_json(&n.pose);
            let (rt, rr, rs) = trs_json(&n.rest);
            let mut o = Map::new();
            o.insert("name".into(), json!(n.name));
            if !n.children.is_empty() {
                o.insert("children".into(), json!(n.children));
            }
            if let Some(m) = n.mesh {
                o.insert("mesh".into(), json!(m));
            }
            if let Some(s) = n.skin {
                o.insert("skin".into(), json!(s));
            }
            o.insert("translation".into(), json!(t));
            o.insert("rotation".into(), json!(r));
            o.insert("scale".into(), json!(s));
            o.insert(
                "extras".into(),
                json!({"stance_rest": {"translation": rt, "rotation": rr, "scale": rs}}),
            );
            Value::Object(o)
        })
        .collect();
    let animations = animations(&mut bin)?;
    while !bin.data.len().is_multiple_of(4) {
        bin.data.push(0);
    }
    let mut root = Map::new();
    root.insert(
        "asset".into(),
        json!({"version": "2.0", "generator": "Stance (stance_asset)"}),
    );
    root.insert("scene".into(), json!(0));
    root.insert("scenes".into(), json!([{"nodes": avatar.scene_roots}]));
    root.insert("nodes".into(), Value::Array(nodes));
    let mut put = |k: &str, v: Vec<Value>| {
        if !v.is_empty() {
            root.insert(k.into(), Value::Array(v));
        }
    };
    put("meshes", meshes);
    put("skins", skins);
    put("animations", animations);
    put("materials", materials);
    put("textures", textures);
    put("samplers", samplers);
    put("images", images);
    put("accessors", std::mem::take(&mut bin.accessors));
    put("bufferViews", std::mem::take(&mut bin.views));
    if !bin.data.is_empty() {
        root.insert("buffers".into(), json!([{"byteLength": bin.data.len()}]));
    }
    let mut used = Vec::new();
    if any_unlit {
        used.push("KHR_materials_unlit".to_owned());
    }
    if let Some(vrm) = &avatar.vrm {
        root.insert(
            "extensions".into(),
            json!({ vrm.name.clone(): vrm_for_export(vrm, avatar.textures.len()) }),
        );
        used.push(vrm.name.clone());
    }
    if !used.is_empty() {
        root.insert("extensionsUsed".into(), json!(used));
    }
    let mut json_bytes =
        serde_json::to_vec(&Value::Object(root)).map_err(|e| AssetError::Export(e.to_string()))?;
    while !json_bytes.len().is_multiple_of(4) {
        json_bytes.push(b' ');
    }
    let bin_chunk = if bin.data.is_empty() {
        0
    } else {
        8 + bin.data.len()
    };
    let total = 12 + 8 + json_bytes.len() + bin_chunk;
    let total32 =
        u32::try_from(total).map_err(|_| AssetError::Export("output over 4 GiB".into()))?;
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&total32.to_le_bytes());
    out.extend_from_slice(&(json_bytes.len() as u32).to_le_bytes());
    out.extend_from_slice(&0x4E4F_534Au32.to_le_bytes());
    out.extend_from_slice(&json_bytes);
    if !bin.data.is_empty() {
        out.extend_from_slice(&(bin.data.len() as u32).to_le_bytes());
        out.extend_from_slice(&0x004E_4942u32.to_le_bytes());
        out.extend_from_slice(&bin.data);
    }
    Ok(out)
}

/// The VRM extension as written back. Nodes, meshes and materials keep their file order on
/// export, so the humanoid's bones, the first-person settings and VRM 0.x's material
/// properties stay valid as they are. Morph targets are not kept (the importer reads the rest
/// shape only): the expressions keep their names and material binds, without morph-target
/// binds; a thumbnail outside the written images is left out.
fn vrm_for_export(vrm: &crate::VrmExtension, images: usize) -> Value {
    let mut value = vrm.value.clone();
    let (thumbnail, expressions): (&str, &[(&str, &str)]) = if vrm.name == "VRM" {
        (
            "texture",
            &[("/blendShapeMaster/blendShapeGroups", "binds")],
        )
    } else {
        (
            "thumbnailImage",
            &[
                ("/expressions/preset", "morphTargetBinds"),
                ("/expressions/custom", "morphTargetBinds"),
            ],
        )
    };
    for (path, binds) in expressions {
        // VRM 0.x's groups are an array, VRM 1.0's expressions objects by name.
        let groups: Vec<&mut Value> = match value.pointer_mut(path) {
            Some(Value::Array(groups)) => groups.iter_mut().collect(),
            Some(Value::Object(groups)) => groups.values_mut().collect(),
            _ => Vec::new(),
        };
        for group in groups {
            if let Some(bound) = group.get_mut(*binds) {
                *bound = json!([]);
            }
        }
    }
    if let Some(meta) = value.get_mut("meta").and_then(Value::as_object_mut)
        && meta
            .get(thumbnail)
            .and_then(Value::as_u64)
            .is_some_and(|t| t as usize >= images)
    {
        meta.remove(thumbnail);
    }
    value
}
