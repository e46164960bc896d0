//! Binary data: buffers (GLB chunk, data URIs, external files), buffer views (plain or
//! `EXT_meshopt_compression`), and accessors (dense, sparse, quantised) read as `f32` or
//! index lists, every byte charged against the decoded-bytes limit.

use std::borrow::Cow;

use base64::Engine as _;
use gltf::json::{self, accessor::ComponentType, accessor::Type as AccType, validation::Checked};
use serde_json::Value;

use super::{Ctx, Resolver, bad_index, check_count, sz};
use crate::AssetError;
use crate::meshopt::{self, Filter, Mode};

/// The EXT_meshopt_compression object of a buffer view, if any.
fn meshopt_ext(view: &json::buffer::View) -> Option<&Value> {
    view.extensions
        .as_ref()
        .and_then(|e| e.others.get("EXT_meshopt_compression"))
}

pub(super) fn decode_data_uri(uri: &str) -> Option<Result<Vec<u8>, String>> {
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
    pub(super) fn charge(&mut self, bytes: usize, what: &str) -> Result<(), AssetError> {
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

    pub(super) fn load_buffers(&mut self, resolve: &mut Resolver<'_>) -> Result<(), AssetError> {
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
                            reason: format!(
                                "the file `{uri}` is missing (give it together with the .gltf)"
                            ),
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
    pub(super) fn prepare_view(&mut self, index: usize, what: &str) -> Result<(), AssetError> {
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
    pub(super) fn view_data(&self, index: usize, what: &str) -> Result<&[u8], AssetError> {
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
    pub(super) fn read(
        &mut self,
        index: usize,
        what: &str,
    ) -> Result<(Vec<f32>, usize), AssetError> {
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

    pub(super) fn read_indices(
        &mut self,
        index: usize,
        what: &str,
    ) -> Result<Vec<u32>, AssetError> {
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
