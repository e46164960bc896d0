//! glTF 2.0 / GLB / VRM import into an [`Avatar`].

use std::borrow::Cow;
use std::collections::HashMap;

use base64::Engine as _;
use glam::{DMat4, DQuat, DVec3, Mat4};
use gltf::json::{self, accessor::ComponentType, accessor::Type as AccType, validation::Checked};
use serde_json::Value;
use stance_hanim::{LevelOfArticulation, Mapping};

use crate::meshopt::{self, Filter, Mode};
use crate::model::{
    AlphaMode, Avatar, Material, Mesh, Node, Primitive, Skin, SourceFormat, Texture, Trs, Wrap,
};
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

/// The EXT_meshopt_compression object of a buffer view, if any.
fn meshopt_ext(view: &json::buffer::View) -> Option<&Value> {
    view.extensions
        .as_ref()
        .and_then(|e| e.others.get("EXT_meshopt_compression"))
}

fn decode_data_uri(uri: &str) -> Option<Result<Vec<u8>, String>> {
    let rest = uri.strip_prefix("data:")?;
    let Some((header, data)) = rest.split_once(',') else {
        return Some(Err("data URI without a comma".into()));
    };
    if !header.ends_with(";base64") {
        return Some(Err("data URI is not base64".into()));
    }
    Some(
        base64::engine::general_purpose::STANDARD
            .decode(data.trim())
            .map_err(|e| format!("bad base64: {e}")),
    )
}

impl<'a> Ctx<'a> {
    fn charge(&mut self, bytes: usize, what: &str) -> Result<(), AssetError> {
        self.decoded_bytes = self.decoded_bytes.saturating_add(bytes as u64);
        if self.decoded_bytes > self.limits.max_decoded_bytes {
            return Err(AssetError::TooLarge {
                what: format!("decoded data (at {what})"),
                size: self.decoded_bytes,
                limit: self.limits.max_decoded_bytes,
            });
        }
        Ok(())
    }

    fn load_buffers(&mut self, resolve: &mut Resolver<'_>) -> Result<(), AssetError> {
        let count = self.root.buffers.len();
        for i in 0..count {
            let (uri, declared, fallback) = {
                let b = &self.root.buffers[i];
                let fallback = b
                    .extensions
                    .as_ref()
                    .and_then(|e| e.others.get("EXT_meshopt_compression"))
                    .and_then(|v| v.get("fallback"))
                    .and_then(Value::as_bool)
                    .unwrap_or(false);
                (b.uri.clone(), b.byte_length.0, fallback)
            };
            if declared > self.limits.max_buffer_bytes {
                return Err(AssetError::TooLarge {
                    what: format!("buffer {i} byteLength"),
                    size: declared,
                    limit: self.limits.max_buffer_bytes,
                });
            }
            let data = match uri {
                None if i == 0 && self.bin.is_some() => self.bin.map(Cow::Borrowed),
                None if fallback => None,
                None => {
                    return Err(AssetError::Buffer {
                        index: i,
                        reason: "no uri and no GLB binary chunk".into(),
                    });
                }
                Some(uri) => match decode_data_uri(&uri) {
                    Some(Ok(d)) => Some(Cow::Owned(d)),
                    Some(Err(reason)) => return Err(AssetError::Buffer { index: i, reason }),
                    None if fallback => None,
                    None => Some(Cow::Owned(resolve(&uri).ok_or_else(|| {
                        AssetError::Buffer {
                            index: i,
                            reason: format!("external file `{uri}` is not available"),
                        }
                    })?)),
                },
            };
            if let Some(d) = &data {
                if (d.len() as u64) < declared {
                    return Err(AssetError::Buffer {
                        index: i,
                        reason: format!(
                            "byteLength {declared} but only {} bytes of data (truncated?)",
                            d.len()
                        ),
                    });
                }
                if let Cow::Owned(d) = d {
                    self.charge(d.len(), &format!("buffer {i}"))?;
                }
            }
            self.buffers.push(data);
        }
        Ok(())
    }

    /// Decodes a buffer view when it is meshopt-compressed (once; later calls are free), so
    /// that [`Ctx::view_data`] can hand out its bytes.
    fn prepare_view(&mut self, index: usize, what: &str) -> Result<(), AssetError> {
        let count = self.root.buffer_views.len();
        let Some(v) = self.root.buffer_views.get(index) else {
            return Err(bad_index(what, "bufferView", index, count));
        };
        if self.decoded_views.contains_key(&index) || meshopt_ext(v).is_none() {
            return Ok(());
        }
        let data = self.decode_meshopt_view(index)?;
        self.decoded_views.insert(index, data);
        Ok(())
    }

    /// The bytes of a buffer view: the decoded data of a meshopt view (after
    /// [`Ctx::prepare_view`]), otherwise a slice of its buffer (never a copy).
    fn view_data(&self, index: usize, what: &str) -> Result<&[u8], AssetError> {
        let count = self.root.buffer_views.len();
        let Some(v) = self.root.buffer_views.get(index) else {
            return Err(bad_index(what, "bufferView", index, count));
        };
        if meshopt_ext(v).is_some() {
            return self
                .decoded_views
                .get(&index)
                .map(Vec::as_slice)
                .ok_or_else(|| {
                    AssetError::OutOfBounds(format!("bufferView {index} was not decoded"))
                });
        }
        let length = sz(v.byte_length.0);
        let buffer = v.buffer.value();
        let offset = sz(v.byte_offset.map_or(0, |o| o.0));
        let nbuf = self.buffers.len();
        let data = self
            .buffers
            .get(buffer)
            .ok_or_else(|| bad_index(format!("bufferView {index}"), "buffer", buffer, nbuf))?
            .as_deref()
            .ok_or_else(|| AssetError::Buffer {
                index: buffer,
                reason: format!(
                    "has no data (meshopt fallback) but bufferView {index} is not compressed"
                ),
            })?;
        offset
            .checked_add(length)
            .and_then(|end| data.get(offset..end))
            .ok_or_else(|| {
                AssetError::OutOfBounds(format!(
                    "bufferView {index} (offset {offset}, length {length}) is outside buffer {buffer} ({} bytes)",
                    data.len()
                ))
            })
    }

    /// Decodes an EXT_meshopt_compression view, charging its size.
    fn decode_meshopt_view(&mut self, index: usize) -> Result<Vec<u8>, AssetError> {
        let Some(v) = self.root.buffer_views.get(index) else {
            return Err(bad_index(
                "meshopt",
                "bufferView",
                index,
                self.root.buffer_views.len(),
            ));
        };
        let length = sz(v.byte_length.0);
        let Some(ext) = meshopt_ext(v) else {
            return Err(AssetError::Meshopt {
                view: index,
                reason: "not compressed".into(),
            });
        };
        let get = |k: &str| ext.get(k).and_then(Value::as_u64);
        let buffer = sz(get("buffer").unwrap_or(u64::MAX));
        let offset = sz(get("byteOffset").unwrap_or(0));
        let src_len = sz(get("byteLength").unwrap_or(0));
        let stride = sz(get("byteStride").unwrap_or(0));
        let count = sz(get("count").unwrap_or(0));
        let mode = match ext.get("mode").and_then(Value::as_str) {
            Some("ATTRIBUTES") => Mode::Attributes,
            Some("TRIANGLES") => Mode::Triangles,
            Some("INDICES") => Mode::Indices,
            other => {
                return Err(AssetError::Meshopt {
                    view: index,
                    reason: format!("unknown mode {other:?}"),
                });
            }
        };
        let filter = match ext.get("filter").and_then(Value::as_str) {
            None | Some("NONE") => Filter::None,
            Some("OCTAHEDRAL") => Filter::Octahedral,
            Some("QUATERNION") => Filter::Quaternion,
            Some("EXPONENTIAL") => Filter::Exponential,
            Some(other) => {
                return Err(AssetError::Meshopt {
                    view: index,
                    reason: format!("unknown filter `{other}`"),
                });
            }
        };
        let nbuf = self.buffers.len();
        let src = self
            .buffers
            .get(buffer)
            .ok_or_else(|| {
                bad_index(
                    format!("bufferView {index} meshopt"),
                    "buffer",
                    buffer,
                    nbuf,
                )
            })?
            .as_deref()
            .ok_or_else(|| AssetError::Meshopt {
                view: index,
                reason: format!("source buffer {buffer} has no data"),
            })?;
        let src = offset
            .checked_add(src_len)
            .and_then(|end| src.get(offset..end))
            .ok_or_else(|| AssetError::Meshopt {
                view: index,
                reason: format!(
                    "compressed range {offset}+{src_len} is outside buffer {buffer} ({} bytes)",
                    src.len()
                ),
            })?;
        let max = sz(self
            .limits
            .max_decoded_bytes
            .saturating_sub(self.decoded_bytes));
        let out = meshopt::decode(src, count, stride, mode, filter, max).map_err(|reason| {
            AssetError::Meshopt {
                view: index,
                reason,
            }
        })?;
        if out.len() < length {
            return Err(AssetError::Meshopt {
                view: index,
                reason: format!("decoded {} bytes, view declares {length}", out.len()),
            });
        }
        self.charge(out.len(), &format!("bufferView {index}"))?;
        Ok(out)
    }

    /// Reads an accessor as `count x components` floats (normalised integers mapped to
    /// [-1, 1] / [0, 1], other integers as their value).
    fn read(&mut self, index: usize, what: &str) -> Result<(Vec<f32>, usize), AssetError> {
        let count_acc = self.root.accessors.len();
        let acc = self
            .root
            .accessors
            .get(index)
            .ok_or_else(|| bad_index(what, "accessor", index, count_acc))?
            .clone();
        let (Checked::Valid(ct), Checked::Valid(ty)) = (acc.component_type, acc.type_) else {
            return Err(AssetError::BadAccessor(format!(
                "accessor {index} ({what}): invalid componentType or type"
            )));
        };
        let ct = ct.0;
        let comps = ty.multiplicity();
        let csize = ct.size();
        let count = sz(acc.count.0);
        check_count(
            &format!("accessor {index} count"),
            count,
            self.limits.max_accessor_count,
        )?;
        let elems = count * comps;
        self.charge(elems * 4, &format!("accessor {index}"))?;
        let mut out = vec![0f32; elems];
        if let Some(view_index) = acc.buffer_view.map(|v| v.value()) {
            let stride_decl = self
                .root
                .buffer_views
                .get(view_index)
                .and_then(|v| v.byte_stride.map(|s| s.0));
            if matches!(ty, AccType::Mat2 | AccType::Mat3) && csize < 4 {
                return Err(AssetError::BadAccessor(format!(
                    "accessor {index} ({what}): padded small-component matrices are not supported"
                )));
            }
            let elem_size = comps * csize;
            let stride = stride_decl.unwrap_or(elem_size);
            if stride < elem_size {
                return Err(AssetError::BadAccessor(format!(
                    "accessor {index} ({what}): byteStride {stride} is smaller than the element ({elem_size} bytes)"
                )));
            }
            let offset = sz(acc.byte_offset.map_or(0, |o| o.0));
            let normalized = acc.normalized;
            self.prepare_view(view_index, what)?;
            let data = self.view_data(view_index, what)?;
            if count > 0 {
                let needed = (count - 1)
                    .checked_mul(stride)
                    .and_then(|x| x.checked_add(offset))
                    .and_then(|x| x.checked_add(elem_size));
                if needed.is_none_or(|n| n > data.len()) {
                    return Err(AssetError::OutOfBounds(format!(
                        "accessor {index} ({what}): {count} elements of {elem_size} bytes (stride {stride}, offset {offset}) do not fit in bufferView {view_index} ({} bytes)",
                        data.len()
                    )));
                }
            }
            for e in 0..count {
                let base = offset + e * stride;
                for c in 0..comps {
                    let at = base + c * csize;
                    out[e * comps + c] = read_component(data, at, ct, normalized);
                }
            }
        }
        if let Some(sparse) = acc.sparse {
            let n = sz(sparse.count.0);
            if n > count {
                return Err(AssetError::BadAccessor(format!(
                    "accessor {index}: sparse count {n} > count {count}"
                )));
            }
            let Checked::Valid(ict) = sparse.indices.component_type else {
                return Err(AssetError::BadAccessor(format!(
                    "accessor {index}: bad sparse index type"
                )));
            };
            let ict = ict.0;
            let ioff = sz(sparse.indices.byte_offset.0);
            let (iview, vview) = (
                sparse.indices.buffer_view.value(),
                sparse.values.buffer_view.value(),
            );
            self.prepare_view(iview, what)?;
            self.prepare_view(vview, what)?;
            let idata = self.view_data(iview, what)?;
            let voff = sz(sparse.values.byte_offset.0);
            let vdata = self.view_data(vview, what)?;
            for s in 0..n {
                let ia = s
                    .checked_mul(ict.size())
                    .and_then(|x| x.checked_add(ioff))
                    .unwrap_or(usize::MAX);
                if ia.saturating_add(ict.size()) > idata.len() {
                    return Err(AssetError::OutOfBounds(format!(
                        "accessor {index}: sparse indices outside their view"
                    )));
                }
                let target = read_component(idata, ia, ict, false) as usize;
                if target >= count {
                    return Err(AssetError::OutOfBounds(format!(
                        "accessor {index}: sparse index {target} >= count {count}"
                    )));
                }
                for c in 0..comps {
                    let va = s
                        .checked_mul(comps)
                        .and_then(|x| x.checked_add(c))
                        .and_then(|x| x.checked_mul(csize))
                        .and_then(|x| x.checked_add(voff))
                        .unwrap_or(usize::MAX);
                    if va.saturating_add(csize) > vdata.len() {
                        return Err(AssetError::OutOfBounds(format!(
                            "accessor {index}: sparse values outside their view"
                        )));
                    }
                    out[target * comps + c] = read_component(vdata, va, ct, acc.normalized);
                }
            }
        }
        Ok((out, comps))
    }

    fn read_indices(&mut self, index: usize, what: &str) -> Result<Vec<u32>, AssetError> {
        let (v, comps) = self.read(index, what)?;
        if comps != 1 {
            return Err(AssetError::BadAccessor(format!(
                "{what}: accessor {index} must be SCALAR"
            )));
        }
        Ok(v.into_iter().map(|x| x as u32).collect())
    }
}

fn read_component(data: &[u8], at: usize, ct: ComponentType, normalized: bool) -> f32 {
    let b = |k: usize| data.get(at + k).copied().unwrap_or(0);
    match ct {
        ComponentType::I8 => {
            let v = b(0) as i8 as f32;
            if normalized { (v / 127.0).max(-1.0) } else { v }
        }
        ComponentType::U8 => {
            let v = b(0) as f32;
            if normalized { v / 255.0 } else { v }
        }
        ComponentType::I16 => {
            let v = i16::from_le_bytes([b(0), b(1)]) as f32;
            if normalized {
                (v / 32767.0).max(-1.0)
            } else {
                v
            }
        }
        ComponentType::U16 => {
            let v = u16::from_le_bytes([b(0), b(1)]) as f32;
            if normalized { v / 65535.0 } else { v }
        }
        ComponentType::U32 => u32::from_le_bytes([b(0), b(1), b(2), b(3)]) as f32,
        ComponentType::F32 => f32::from_le_bytes([b(0), b(1), b(2), b(3)]),
    }
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
    let textures = import_textures(&mut ctx, options.decode_textures, &used)?;
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
    let mut format = if is_glb {
        SourceFormat::Glb
    } else {
        SourceFormat::Gltf
    };
    if let Some(vrm1) = ext.and_then(|e| e.get("VRMC_vrm")) {
        format = SourceFormat::Vrm1;
        if let Some(bones) = vrm1
            .get("humanoid")
            .and_then(|h| h.get("humanBones"))
            .and_then(Value::as_object)
        {
            for (bone, v) in bones {
                if let Some(n) = v.get("node").and_then(Value::as_u64) {
                    vrm_bones.push((bone.clone(), sz(n)));
                }
            }
        }
    } else if let Some(vrm0) = ext.and_then(|e| e.get("VRM")) {
        format = SourceFormat::Vrm0;
        if let Some(bones) = vrm0
            .get("humanoid")
            .and_then(|h| h.get("humanBones"))
            .and_then(Value::as_array)
        {
            for b in bones {
                if let (Some(bone), Some(n)) = (
                    b.get("bone").and_then(Value::as_str),
                    b.get("node").and_then(Value::as_u64),
                ) {
                    vrm_bones.push((bone.to_owned(), sz(n)));
                }
            }
        }
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
    if !ctx.root.animations.is_empty() {
        ctx.warnings.push(format!(
            "{} animation(s) ignored",
            ctx.root.animations.len()
        ));
    }

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
        extensions: ctx.root.extensions_used.clone(),
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

fn import_textures(
    ctx: &mut Ctx<'_>,
    decode: bool,
    used: &[usize],
) -> Result<Vec<Texture>, AssetError> {
    // Decode each image once; textures refer to images (EXT_texture_webp source first).
    let mut images: Vec<Option<(u32, u32, Vec<u8>)>> = vec![None; ctx.root.images.len()];
    let mut textures = Vec::new();
    for t in 0..ctx.root.textures.len() {
        let tex = ctx.root.textures[t].clone();
        let webp = tex
            .extensions
            .as_ref()
            .and_then(|e| e.others.get("EXT_texture_webp"))
            .and_then(|w| w.get("source"))
            .and_then(Value::as_u64)
            .map(sz);
        let source = webp.unwrap_or(tex.source.value());
        let count = ctx.root.images.len();
        let (wrap_u, wrap_v) = tex
            .sampler
            .and_then(|s| ctx.root.samplers.get(s.value()))
            .map_or((Wrap::Repeat, Wrap::Repeat), |s| {
                (wrap_of(s.wrap_s), wrap_of(s.wrap_t))
            });
        let name = ctx
            .root
            .images
            .get(source)
            .and_then(|i| i.name.clone())
            .unwrap_or_else(|| format!("image{source}"));
        if source >= count {
            ctx.warnings
                .push(format!("texture {t}: image {source} does not exist"));
            textures.push(placeholder(name, wrap_u, wrap_v));
            continue;
        }
        if !decode || !used.contains(&t) {
            textures.push(placeholder(name, wrap_u, wrap_v));
            continue;
        }
        if images[source].is_none() {
            match decode_image(ctx, source) {
                Ok(img) => images[source] = Some(img),
                Err(e @ AssetError::TooLarge { .. }) => return Err(e),
                Err(e) => {
                    ctx.warnings.push(e.to_string());
                    images[source] = Some((1, 1, vec![255; 4]));
                }
            }
        }
        // Each texture holds its own copy of the pixels: charge every copy, so that many
        // textures sharing one large image cannot multiply memory past the limit.
        let bytes = images[source].as_ref().map_or(4, |i| i.2.len());
        ctx.charge(bytes, &format!("texture {t}"))?;
        let (width, height, rgba8) = images[source].clone().unwrap_or((1, 1, vec![255; 4]));
        textures.push(Texture {
            name,
            width,
            height,
            rgba8,
            wrap_u,
            wrap_v,
        });
    }
    Ok(textures)
}

fn placeholder(name: String, wrap_u: Wrap, wrap_v: Wrap) -> Texture {
    Texture {
        name,
        width: 1,
        height: 1,
        rgba8: vec![255; 4],
        wrap_u,
        wrap_v,
    }
}

fn wrap_of(w: Checked<json::texture::WrappingMode>) -> Wrap {
    match w {
        Checked::Valid(json::texture::WrappingMode::ClampToEdge) => Wrap::Clamp,
        Checked::Valid(json::texture::WrappingMode::MirroredRepeat) => Wrap::Mirror,
        _ => Wrap::Repeat,
    }
}

fn decode_image(ctx: &mut Ctx<'_>, index: usize) -> Result<(u32, u32, Vec<u8>), AssetError> {
    let what = format!("image {index}");
    let (view, uri) = {
        let img = &ctx.root.images[index];
        (img.buffer_view.map(|v| v.value()), img.uri.clone())
    };
    let owned;
    let bytes: &[u8] = if let Some(view) = view {
        ctx.prepare_view(view, &what)?;
        ctx.view_data(view, &what)?
    } else if let Some(uri) = &uri {
        match decode_data_uri(uri) {
            Some(Ok(d)) => {
                owned = d;
                &owned
            }
            Some(Err(reason)) => return Err(AssetError::Image { index, reason }),
            None => {
                return Err(AssetError::Image {
                    index,
                    reason: format!("external image `{uri}` not loaded"),
                });
            }
        }
    } else {
        return Err(AssetError::Image {
            index,
            reason: "neither bufferView nor uri".into(),
        });
    };
    let image = decode_image_bytes(bytes, index, ctx.limits, ctx.decoded_bytes)?;
    ctx.charge(image.2.len(), &what)?;
    Ok(image)
}

/// Decodes an encoded image to RGBA8 after checking its declared size against the side
/// limit and against what is left of the decoded-bytes budget (`already` spent).
fn decode_image_bytes(
    bytes: &[u8],
    index: usize,
    limits: &Limits,
    already: u64,
) -> Result<(u32, u32, Vec<u8>), AssetError> {
    let format = image::guess_format(bytes).map_err(|e| AssetError::Image {
        index,
        reason: e.to_string(),
    })?;
    let mut reader = image::ImageReader::with_format(std::io::Cursor::new(bytes), format);
    let mut lim = image::Limits::default();
    lim.max_image_width = Some(limits.max_texture_side);
    lim.max_image_height = Some(limits.max_texture_side);
    lim.max_alloc = Some(
        (limits.max_texture_side as u64)
            .saturating_mul(limits.max_texture_side as u64)
            .saturating_mul(8),
    );
    reader.limits(lim.clone());
    let (w, h) = reader.into_dimensions().map_err(|e| AssetError::Image {
        index,
        reason: e.to_string(),
    })?;
    if w > limits.max_texture_side || h > limits.max_texture_side {
        return Err(AssetError::TooLarge {
            what: format!("image {index} side"),
            size: w.max(h) as u64,
            limit: limits.max_texture_side as u64,
        });
    }
    let total = already.saturating_add(u64::from(w) * u64::from(h) * 4);
    if total > limits.max_decoded_bytes {
        return Err(AssetError::TooLarge {
            what: format!("decoded data (at image {index})"),
            size: total,
            limit: limits.max_decoded_bytes,
        });
    }
    let mut reader = image::ImageReader::with_format(std::io::Cursor::new(bytes), format);
    reader.limits(lim);
    let decoded = reader.decode().map_err(|e| AssetError::Image {
        index,
        reason: e.to_string(),
    })?;
    let rgba = decoded.into_rgba8();
    Ok((rgba.width(), rgba.height(), rgba.into_raw()))
}

fn import_materials(ctx: &Ctx<'_>, texture_count: usize) -> Result<Vec<Material>, AssetError> {
    let vrm0_props = ctx
        .root
        .extensions
        .as_ref()
        .and_then(|e| e.others.get("VRM"))
        .and_then(|v| v.get("materialProperties"))
        .and_then(Value::as_array);
    let mut out = Vec::new();
    for (i, m) in ctx.root.materials.iter().enumerate() {
        let pbr = &m.pbr_metallic_roughness;
        let mut base_color_texture = pbr.base_color_texture.as_ref().map(|t| t.index.value());
        let mut base_color_factor = pbr.base_color_factor.0;
        let others = m.extensions.as_ref().map(|e| &e.others);
        let unlit = m.extensions.as_ref().is_some_and(|e| e.unlit.is_some());
        let mut mtoon = others.is_some_and(|o| o.contains_key("VRMC_materials_mtoon"));
        let name = m.name.clone().unwrap_or_else(|| format!("material{i}"));
        if let Some(props) = vrm0_props.and_then(|p| {
            p.iter()
                .find(|x| x.get("name").and_then(Value::as_str) == Some(name.as_str()))
        }) && props
            .get("shader")
            .and_then(Value::as_str)
            .is_some_and(|s| s.contains("MToon"))
        {
            mtoon = true;
            if let Some(t) = props
                .get("textureProperties")
                .and_then(|t| t.get("_MainTex"))
                .and_then(Value::as_u64)
            {
                base_color_texture = Some(sz(t));
            }
            if let Some(c) = props
                .get("vectorProperties")
                .and_then(|v| v.get("_Color"))
                .and_then(Value::as_array)
            {
                let c: Vec<f32> = c
                    .iter()
                    .filter_map(Value::as_f64)
                    .map(|x| x as f32)
                    .collect();
                if c.len() == 4 {
                    base_color_factor = [c[0], c[1], c[2], c[3]];
                }
            }
        }
        if let Some(t) = base_color_texture
            && t >= texture_count
        {
            return Err(bad_index(
                format!("material {i} baseColorTexture"),
                "texture",
                t,
                texture_count,
            ));
        }
        let alpha_mode = match m.alpha_mode {
            Checked::Valid(json::material::AlphaMode::Mask) => AlphaMode::Mask,
            Checked::Valid(json::material::AlphaMode::Blend) => AlphaMode::Blend,
            _ => AlphaMode::Opaque,
        };
        out.push(Material {
            name,
            base_color_factor: base_color_factor.map(|x| if x.is_finite() { x } else { 1.0 }),
            base_color_texture,
            unlit,
            mtoon,
            double_sided: m.double_sided,
            alpha_mode,
            alpha_cutoff: m.alpha_cutoff.map_or(0.5, |c| c.0),
        });
    }
    Ok(out)
}

fn import_meshes(
    ctx: &mut Ctx<'_>,
    nodes: &[Node],
    skins: &[Skin],
) -> Result<Vec<Mesh>, AssetError> {
    // Joint count of the skin each mesh is drawn with (the smallest, to check JOINTS_0).
    let mut mesh_joints: Vec<Option<usize>> = vec![None; ctx.root.meshes.len()];
    for n in nodes {
        if let (Some(m), Some(s)) = (n.mesh, n.skin)
            && let (Some(slot), Some(skin)) = (mesh_joints.get_mut(m), skins.get(s))
        {
            *slot = Some(slot.map_or(skin.joints.len(), |x: usize| x.min(skin.joints.len())));
        }
    }
    let mut meshes = Vec::new();
    let material_count = ctx.root.materials.len();
    for mi in 0..ctx.root.meshes.len() {
        let mesh = ctx.root.meshes[mi].clone();
        let mut prims = Vec::new();
        for (pi, p) in mesh.primitives.iter().enumerate() {
            let what = format!("mesh {mi} primitive {pi}");
            let mode = match p.mode {
                Checked::Valid(m) => m,
                Checked::Invalid => {
                    return Err(AssetError::BadJson(format!("{what}: invalid mode")));
                }
            };
            use json::mesh::{Mode as M, Semantic as S};
            if !matches!(mode, M::Triangles | M::TriangleStrip | M::TriangleFan) {
                ctx.warnings.push(format!(
                    "{what}: mode {mode:?} skipped (only triangles are drawn)"
                ));
                continue;
            }
            let get = |s: S| p.attributes.get(&Checked::Valid(s)).map(|a| a.value());
            let Some(pos_acc) = get(S::Positions) else {
                ctx.warnings.push(format!("{what}: no POSITION, skipped"));
                continue;
            };
            let (pos, comps) = ctx.read(pos_acc, &format!("{what} POSITION"))?;
            if comps != 3 {
                return Err(AssetError::BadAccessor(format!(
                    "{what}: POSITION must be VEC3"
                )));
            }
            let count = pos.len() / 3;
            let positions: Vec<[f32; 3]> = pos
                .chunks_exact(3)
                .map(|c| {
                    let v = [c[0], c[1], c[2]];
                    if v.iter().all(|x| x.is_finite()) {
                        v
                    } else {
                        [0.0; 3]
                    }
                })
                .collect();
            let attr = |ctx: &mut Ctx<'_>,
                        s: S,
                        name: &str,
                        want: usize|
             -> Result<Option<Vec<f32>>, AssetError> {
                let Some(a) = p.attributes.get(&Checked::Valid(s)).map(|a| a.value()) else {
                    return Ok(None);
                };
                let (v, c) = ctx.read(a, &format!("{what} {name}"))?;
                if c != want && !(name == "WEIGHTS_0" && c == 4) {
                    return Err(AssetError::BadAccessor(format!(
                        "{what}: {name} has {c} components, expected {want}"
                    )));
                }
                if v.len() / c != count {
                    return Err(AssetError::BadAccessor(format!(
                        "{what}: {name} has {} elements but POSITION has {count}",
                        v.len() / c
                    )));
                }
                Ok(Some(v))
            };
            let normals = attr(ctx, S::Normals, "NORMAL", 3)?;
            let uvs = attr(ctx, S::TexCoords(0), "TEXCOORD_0", 2)?;
            let joints = attr(ctx, S::Joints(0), "JOINTS_0", 4)?;
            let weights = attr(ctx, S::Weights(0), "WEIGHTS_0", 4)?;
            let mut indices = match p.indices {
                Some(a) => {
                    let idx = ctx.read_indices(a.value(), &format!("{what} indices"))?;
                    if let Some(&bad) = idx.iter().find(|&&i| i as usize >= count) {
                        return Err(AssetError::OutOfBounds(format!(
                            "{what}: index {bad} out of range (the primitive has {count} vertices)"
                        )));
                    }
                    idx
                }
                None => (0..count as u32).collect(),
            };
            indices = match mode {
                M::TriangleStrip => strip_to_list(&indices),
                M::TriangleFan => fan_to_list(&indices),
                _ => {
                    let whole = indices.len() - indices.len() % 3;
                    indices.truncate(whole);
                    indices
                }
            };
            // The primitive as stored (positions, normals, uvs, joints and weights per vertex,
            // u32 indices), counted before the attributes the file lacks are synthesised.
            let skinned = joints.is_some() && weights.is_some();
            let stored = count
                .saturating_mul(if skinned {
                    12 + 12 + 8 + 8 + 16
                } else {
                    12 + 12 + 8
                })
                .saturating_add(indices.len().saturating_mul(4));
            ctx.charge(stored, &what)?;
            let mut normals: Vec<[f32; 3]> = match normals {
                Some(n) => n
                    .chunks_exact(3)
                    .map(|c| unit([c[0], c[1], c[2]]))
                    .collect(),
                None => compute_normals(&positions, &indices),
            };
            normals.resize(count, [0.0, 1.0, 0.0]);
            let uvs: Vec<[f32; 2]> = match uvs {
                Some(u) => u
                    .chunks_exact(2)
                    .map(|c| {
                        let v = [c[0], c[1]];
                        if v.iter().all(|x| x.is_finite()) {
                            v
                        } else {
                            [0.0; 2]
                        }
                    })
                    .collect(),
                None => vec![[0.0; 2]; count],
            };
            let (joints, weights) = match (joints, weights) {
                (Some(j), Some(w)) => {
                    let limit = mesh_joints[mi].unwrap_or(0);
                    let mut jo = Vec::with_capacity(count);
                    let mut we = Vec::with_capacity(count);
                    for (jc, wc) in j.chunks_exact(4).zip(w.chunks_exact(4)) {
                        let mut ji = [0u16; 4];
                        let mut wi = [0f32; 4];
                        for k in 0..4 {
                            let w = if wc[k].is_finite() {
                                wc[k].max(0.0)
                            } else {
                                0.0
                            };
                            if w > 0.0 && jc[k] as usize >= limit {
                                return Err(AssetError::OutOfBounds(format!(
                                    "{what}: JOINTS_0 value {} out of range (the skin has {limit} joints)",
                                    jc[k]
                                )));
                            }
                            ji[k] = if (jc[k] as usize) < limit {
                                jc[k] as u16
                            } else {
                                0
                            };
                            wi[k] = w;
                        }
                        let sum: f32 = wi.iter().sum();
                        if sum > 1e-6 {
                            wi.iter_mut().for_each(|x| *x /= sum);
                        } else {
                            wi = [1.0, 0.0, 0.0, 0.0];
                            ji = [0; 4];
                        }
                        jo.push(ji);
                        we.push(wi);
                    }
                    if limit == 0 {
                        (Vec::new(), Vec::new())
                    } else {
                        (jo, we)
                    }
                }
                _ => (Vec::new(), Vec::new()),
            };
            let material = p.material.map(|m| m.value());
            if let Some(m) = material
                && m >= material_count
            {
                return Err(bad_index(what, "material", m, material_count));
            }
            prims.push(Primitive {
                positions,
                normals,
                uvs,
                joints,
                weights,
                indices,
                material,
            });
        }
        meshes.push(Mesh {
            name: mesh.name.clone().unwrap_or_else(|| format!("mesh{mi}")),
            primitives: prims,
        });
    }
    Ok(meshes)
}

fn unit(v: [f32; 3]) -> [f32; 3] {
    let l = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    if l.is_finite() && l > 1e-8 {
        [v[0] / l, v[1] / l, v[2] / l]
    } else {
        [0.0, 1.0, 0.0]
    }
}

fn strip_to_list(s: &[u32]) -> Vec<u32> {
    let mut out = Vec::new();
    for i in 2..s.len() {
        if i % 2 == 0 {
            out.extend_from_slice(&[s[i - 2], s[i - 1], s[i]]);
        } else {
            out.extend_from_slice(&[s[i - 1], s[i - 2], s[i]]);
        }
    }
    out
}

fn fan_to_list(s: &[u32]) -> Vec<u32> {
    let mut out = Vec::new();
    for i in 2..s.len() {
        out.extend_from_slice(&[s[0], s[i - 1], s[i]]);
    }
    out
}

/// Area-weighted vertex normals.
pub(crate) fn compute_normals(positions: &[[f32; 3]], indices: &[u32]) -> Vec<[f32; 3]> {
    let mut acc = vec![DVec3::ZERO; positions.len()];
    for t in indices.chunks_exact(3) {
        let p = |k: usize| {
            positions.get(t[k] as usize).map_or(DVec3::ZERO, |v| {
                DVec3::new(v[0] as f64, v[1] as f64, v[2] as f64)
            })
        };
        let n = (p(1) - p(0)).cross(p(2) - p(0));
        for k in 0..3 {
            if let Some(a) = acc.get_mut(t[k] as usize) {
                *a += n;
            }
        }
    }
    acc.into_iter()
        .map(|n| {
            let n = n.normalize_or(DVec3::Y);
            [n.x as f32, n.y as f32, n.z as f32]
        })
        .collect()
}
