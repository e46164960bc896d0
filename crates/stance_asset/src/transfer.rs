//! An imported [`Avatar`] as bytes, to hand it from the thread that imported it (the page's
//! import worker) to the one that shows it: [`AvatarTransfer`]. The layout is postcard's
//! (serde), with the large arrays (vertex attributes, indices, keyframes) written as one byte
//! run each in the machine's byte order, so that encoding and decoding cost about a copy; the
//! texture pixels travel beside it, one buffer per texture, so that the receiving thread can
//! take them in separate tasks. Both ends are the same build of Stance on the same machine;
//! the bytes are not a file format.
//!
//! Decoding checks what it reads (lengths, enum tags, UTF-8, H-Anim names, pixel counts) and
//! returns an [`AssetError::Transfer`] naming the problem; it never panics.

use crate::{AssetError, Avatar};

/// An avatar split for the trip between threads.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct AvatarTransfer {
    /// Everything but the texture pixels.
    pub avatar: Vec<u8>,
    /// The pixels of texture `i` (RGBA8, `width * height * 4` bytes).
    pub pixels: Vec<Vec<u8>>,
}

impl AvatarTransfer {
    /// `avatar` split for the trip (its pixels moved, not copied).
    pub fn new(mut avatar: Avatar) -> Result<Self, AssetError> {
        // Moved out where the avatar holds the only reference (as an importer's does).
        let pixels = avatar
            .textures
            .iter_mut()
            .map(|texture| {
                std::sync::Arc::try_unwrap(std::mem::take(&mut texture.rgba8))
                    .unwrap_or_else(|shared| (*shared).clone())
            })
            .collect();
        let bytes = postcard::to_allocvec(&avatar)
            .map_err(|error| AssetError::Transfer(error.to_string()))?;
        Ok(Self {
            avatar: bytes,
            pixels,
        })
    }

    /// The avatar again.
    pub fn into_avatar(self) -> Result<Avatar, AssetError> {
        let mut avatar = match postcard::take_from_bytes::<Avatar>(&self.avatar) {
            Ok((avatar, [])) => avatar,
            Ok((_, rest)) => {
                return Err(AssetError::Transfer(format!(
                    "{} bytes after the avatar",
                    rest.len()
                )));
            }
            Err(error) => return Err(AssetError::Transfer(error.to_string())),
        };
        avatar
            .check_structure()
            .map_err(|e| AssetError::Transfer(format!("the avatar is inconsistent: {e}")))?;
        if self.pixels.len() != avatar.textures.len() {
            return Err(AssetError::Transfer(format!(
                "{} textures but pixels for {}",
                avatar.textures.len(),
                self.pixels.len()
            )));
        }
        for (index, (texture, pixels)) in avatar.textures.iter_mut().zip(self.pixels).enumerate() {
            let expected = (texture.width as usize)
                .checked_mul(texture.height as usize)
                .and_then(|n| n.checked_mul(4));
            if expected != Some(pixels.len()) {
                return Err(AssetError::Transfer(format!(
                    "texture {index} is {}x{} but has {} bytes of pixels",
                    texture.width,
                    texture.height,
                    pixels.len()
                )));
            }
            texture.rgba8 = std::sync::Arc::new(pixels);
        }
        Ok(avatar)
    }
}

/// `#[serde(with = "pod_vec")]`: a `Vec` of plain numbers (or arrays of them) as one byte run.
pub(crate) mod pod_vec {
    use std::marker::PhantomData;

    use bytemuck::Pod;
    use serde::de::{Error, Visitor};
    use serde::{Deserializer, Serializer};

    pub(crate) fn serialize<T: Pod, S: Serializer>(
        values: &[T],
        serializer: S,
    ) -> Result<S::Ok, S::Error> {
        serializer.serialize_bytes(bytemuck::cast_slice(values))
    }

    pub(crate) fn deserialize<'de, T: Pod, D: Deserializer<'de>>(
        deserializer: D,
    ) -> Result<Vec<T>, D::Error> {
        deserializer.deserialize_bytes(PodVisitor(PhantomData))
    }

    struct PodVisitor<T>(PhantomData<T>);

    impl<T: Pod> Visitor<'_> for PodVisitor<T> {
        type Value = Vec<T>;

        fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
            write!(f, "a byte run of {}-byte values", size_of::<T>())
        }

        fn visit_bytes<E: Error>(self, bytes: &[u8]) -> Result<Vec<T>, E> {
            if !bytes.len().is_multiple_of(size_of::<T>()) {
                return Err(E::custom(format!(
                    "{} bytes are not a whole number of {}-byte values",
                    bytes.len(),
                    size_of::<T>()
                )));
            }
            // A copy (the input need not be aligned for T).
            Ok(bytemuck::pod_collect_to_vec(bytes))
        }
    }
}

/// `#[serde(with = "byte_vec")]`: shared bytes (texture pixels) as one byte run, read back with a
/// single copy (no zeroing first, as [`pod_vec`] needs for other types).
pub(crate) mod byte_vec {
    use std::sync::Arc;

    use serde::de::{Error, Visitor};
    use serde::{Deserializer, Serializer};

    pub(crate) fn serialize<S: Serializer>(
        bytes: &Arc<Vec<u8>>,
        serializer: S,
    ) -> Result<S::Ok, S::Error> {
        serializer.serialize_bytes(bytes)
    }

    pub(crate) fn deserialize<'de, D: Deserializer<'de>>(
        deserializer: D,
    ) -> Result<Arc<Vec<u8>>, D::Error> {
        deserializer
            .deserialize_byte_buf(BytesVisitor)
            .map(Arc::new)
    }

    struct BytesVisitor;

    impl Visitor<'_> for BytesVisitor {
        type Value = Vec<u8>;

        fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
            f.write_str("a byte run")
        }

        fn visit_bytes<E: Error>(self, bytes: &[u8]) -> Result<Vec<u8>, E> {
            Ok(bytes.to_vec())
        }

        fn visit_byte_buf<E: Error>(self, bytes: Vec<u8>) -> Result<Vec<u8>, E> {
            Ok(bytes)
        }
    }
}

/// `#[serde(with = "json_text")]`: a JSON value as its text (postcard cannot carry
/// self-describing values).
pub(crate) mod json_text {
    use serde::de::Error;
    use serde::{Deserialize, Deserializer, Serializer};

    pub(crate) fn serialize<S: Serializer>(
        value: &serde_json::Value,
        serializer: S,
    ) -> Result<S::Ok, S::Error> {
        serializer.serialize_str(&value.to_string())
    }

    pub(crate) fn deserialize<'de, D: Deserializer<'de>>(
        deserializer: D,
    ) -> Result<serde_json::Value, D::Error> {
        let text = String::deserialize(deserializer)?;
        serde_json::from_str(&text).map_err(D::Error::custom)
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

    use super::*;

    /// 24 bytes nothing else in an avatar looks like.
    fn pattern() -> Vec<u8> {
        (0..24u32).map(|i| (i * 97 + 13) as u8 ^ 0xC3).collect()
    }

    fn textured() -> Avatar {
        let mut avatar = crate::make_default_avatar().unwrap();
        avatar.textures.push(crate::Texture {
            name: "checker".to_owned(),
            width: 2,
            height: 3,
            rgba8: std::sync::Arc::new(pattern()),
            image: Some(0),
            wrap_u: crate::Wrap::Repeat,
            wrap_v: crate::Wrap::Clamp,
        });
        avatar
    }

    #[test]
    fn an_avatar_comes_back_equal_with_its_pixels_beside_it() {
        let avatar = textured();
        let transfer = AvatarTransfer::new(avatar.clone()).unwrap();
        assert_eq!(transfer.pixels.len(), avatar.textures.len());
        assert_eq!(transfer.pixels.last().unwrap().len(), 24);
        // The pixels are not in the avatar's bytes.
        assert!(!transfer.avatar.windows(24).any(|w| w == pattern()));
        assert_eq!(transfer.into_avatar().unwrap(), avatar);
    }

    #[test]
    fn damaged_transfers_are_refused_by_name() {
        let transfer = AvatarTransfer::new(textured()).unwrap();
        for cut in [0, 1, transfer.avatar.len() / 3, transfer.avatar.len() - 1] {
            let mut bad = transfer.clone();
            bad.avatar.truncate(cut);
            let error = bad.into_avatar().unwrap_err();
            assert!(matches!(error, AssetError::Transfer(_)), "{error}");
        }
        let mut longer = transfer.clone();
        longer.avatar.push(0);
        assert!(
            longer
                .into_avatar()
                .unwrap_err()
                .to_string()
                .contains("1 bytes after the avatar")
        );
        let mut missing = transfer.clone();
        missing.pixels.pop();
        assert!(
            missing
                .into_avatar()
                .unwrap_err()
                .to_string()
                .contains("pixels for")
        );
        let mut short = transfer.clone();
        short.pixels.last_mut().unwrap().pop();
        assert!(
            short
                .into_avatar()
                .unwrap_err()
                .to_string()
                .contains("is 2x3 but has 23 bytes")
        );
        // Bytes that decode but do not hang together (found by the transfer's fuzz target:
        // a node's parent beyond the nodes).
        let mut avatar = textured();
        avatar.nodes[1].parent = Some(avatar.nodes.len() + 42);
        let error = AvatarTransfer::new(avatar)
            .unwrap()
            .into_avatar()
            .unwrap_err();
        assert!(error.to_string().contains("node 1's parent"), "{error}");
        let mut avatar = textured();
        avatar.meshes[0].primitives[0].indices[0] = u32::MAX;
        let error = AvatarTransfer::new(avatar)
            .unwrap()
            .into_avatar()
            .unwrap_err();
        assert!(error.to_string().contains("mesh 0 primitive 0"), "{error}");
        // Every byte flipped in turn, over a stride: an error or an avatar, never a panic.
        for at in (0..transfer.avatar.len()).step_by(997) {
            let mut bad = transfer.clone();
            bad.avatar[at] ^= 0xA5;
            let _ = bad.into_avatar();
        }
    }
}
