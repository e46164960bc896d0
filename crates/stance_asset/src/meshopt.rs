//! EXT_meshopt_compression buffer views, decoded with the pure-Rust `meshopt-rs` port of
//! meshoptimizer's decoders (no C compiler needed, builds for wasm32-unknown-unknown).
//!
//! Every parameter is checked against the extension specification before the decoder sees
//! it, so the decoder's own assertions cannot fire on hostile input.

use meshopt_rs::index::buffer::decode_index_buffer;
use meshopt_rs::index::sequence::decode_index_sequence;
use meshopt_rs::vertex::buffer::decode_vertex_buffer;
use meshopt_rs::vertex::filter::{
    decode_filter_exp, decode_filter_oct_8, decode_filter_oct_16, decode_filter_quat,
};

/// Compression mode of a view.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Mode {
    /// Vertex attributes.
    Attributes,
    /// Triangle indices.
    Triangles,
    /// Index sequences.
    Indices,
}

/// Filter applied after decoding attributes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Filter {
    /// None.
    None,
    /// Octahedral normals/tangents.
    Octahedral,
    /// Quaternions.
    Quaternion,
    /// Exponential floats.
    Exponential,
}

/// Decodes `count` elements of `stride` bytes from `source`. `max_bytes` bounds the output.
pub fn decode(
    source: &[u8],
    count: usize,
    stride: usize,
    mode: Mode,
    filter: Filter,
    max_bytes: usize,
) -> Result<Vec<u8>, String> {
    let total = count
        .checked_mul(stride)
        .ok_or_else(|| "count * byteStride overflows".to_owned())?;
    if total > max_bytes {
        return Err(format!(
            "decoded size {total} exceeds the limit {max_bytes}"
        ));
    }
    match mode {
        Mode::Attributes => {
            if stride == 0 || stride > 256 || !stride.is_multiple_of(4) {
                return Err(format!(
                    "ATTRIBUTES byteStride {stride} must be a multiple of 4 in 4..=256"
                ));
            }
            let mut out = decode_attributes(source, count, stride)?;
            apply_filter(&mut out, stride, filter)?;
            Ok(out)
        }
        Mode::Triangles | Mode::Indices => {
            if filter != Filter::None {
                return Err("index data cannot have a filter".into());
            }
            if stride != 2 && stride != 4 {
                return Err(format!("index byteStride {stride} must be 2 or 4"));
            }
            let mut indices = vec![0u32; count];
            let result = if mode == Mode::Triangles {
                if !count.is_multiple_of(3) {
                    return Err(format!("TRIANGLES count {count} is not a multiple of 3"));
                }
                decode_index_buffer(&mut indices, source)
            } else {
                decode_index_sequence(&mut indices, source)
            };
            result.map_err(|e| format!("{e:?}"))?;
            let mut out = Vec::with_capacity(total);
            for i in indices {
                if stride == 2 {
                    out.extend_from_slice(&(i as u16).to_le_bytes());
                } else {
                    out.extend_from_slice(&i.to_le_bytes());
                }
            }
            Ok(out)
        }
    }
}

macro_rules! decode_strides {
    ($source:expr, $count:expr, $stride:expr; $($n:literal)*) => {
        match $stride {
            $(
                $n => {
                    let mut v = vec![[0u8; $n]; $count];
                    decode_vertex_buffer(&mut v, $source).map_err(|e| format!("{e:?}"))?;
                    Ok(v.into_iter().flatten().collect())
                }
            )*
            other => Err(format!("unsupported byteStride {other}")),
        }
    };
}

fn decode_attributes(source: &[u8], count: usize, stride: usize) -> Result<Vec<u8>, String> {
    decode_strides!(source, count, stride;
        4 8 12 16 20 24 28 32 36 40 44 48 52 56 60 64 68 72 76 80 84 88 92 96 100 104 108 112
        116 120 124 128 132 136 140 144 148 152 156 160 164 168 172 176 180 184 188 192 196
        200 204 208 212 216 220 224 228 232 236 240 244 248 252 256)
}

fn apply_filter(data: &mut [u8], stride: usize, filter: Filter) -> Result<(), String> {
    match filter {
        Filter::None => Ok(()),
        Filter::Octahedral => match stride {
            4 => {
                let mut v: Vec<[u8; 4]> = data
                    .chunks_exact(4)
                    .map(|c| [c[0], c[1], c[2], c[3]])
                    .collect();
                decode_filter_oct_8(&mut v);
                for (d, s) in data.chunks_exact_mut(4).zip(v) {
                    d.copy_from_slice(&s);
                }
                Ok(())
            }
            8 => {
                let mut v = to_u16x4(data);
                decode_filter_oct_16(&mut v);
                from_u16x4(data, &v);
                Ok(())
            }
            _ => Err(format!(
                "OCTAHEDRAL filter needs byteStride 4 or 8, not {stride}"
            )),
        },
        Filter::Quaternion => {
            if stride != 8 {
                return Err(format!(
                    "QUATERNION filter needs byteStride 8, not {stride}"
                ));
            }
            let mut v = to_u16x4(data);
            decode_filter_quat(&mut v);
            from_u16x4(data, &v);
            Ok(())
        }
        Filter::Exponential => {
            let mut v: Vec<u32> = data
                .chunks_exact(4)
                .map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]]))
                .collect();
            decode_filter_exp(&mut v);
            for (d, s) in data.chunks_exact_mut(4).zip(v) {
                d.copy_from_slice(&s.to_le_bytes());
            }
            Ok(())
        }
    }
}

fn to_u16x4(data: &[u8]) -> Vec<[u16; 4]> {
    data.chunks_exact(8)
        .map(|c| {
            [
                u16::from_le_bytes([c[0], c[1]]),
                u16::from_le_bytes([c[2], c[3]]),
                u16::from_le_bytes([c[4], c[5]]),
                u16::from_le_bytes([c[6], c[7]]),
            ]
        })
        .collect()
}

fn from_u16x4(data: &mut [u8], v: &[[u16; 4]]) {
    for (d, s) in data.chunks_exact_mut(8).zip(v) {
        for k in 0..4 {
            d[2 * k..2 * k + 2].copy_from_slice(&s[k].to_le_bytes());
        }
    }
}
