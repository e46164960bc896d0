//! The fuzz targets' framing of several byte strings in one input: each part a 4-byte
//! little-endian length then its bytes (a short last part is taken as it is). Included with
//! `#[path]` by the targets and by the tests that write their seeds.

/// The parts of `data`.
pub fn split_parts(mut data: &[u8]) -> Vec<Vec<u8>> {
    let mut parts = Vec::new();
    while let Some((length, tail)) = data.split_first_chunk::<4>() {
        let length = u32::from_le_bytes(*length) as usize;
        let part = &tail[..length.min(tail.len())];
        parts.push(part.to_vec());
        data = &tail[part.len()..];
    }
    parts
}

/// `parts` framed for [`split_parts`] (the seeds' writing).
pub fn join_parts<'a>(parts: impl IntoIterator<Item = &'a Vec<u8>>) -> Vec<u8> {
    let mut data = Vec::new();
    for part in parts {
        let length = u32::try_from(part.len()).unwrap_or(u32::MAX);
        data.extend_from_slice(&length.to_le_bytes());
        data.extend_from_slice(part);
    }
    data
}
