//! Texture images: their size from the header (`imagesize`, for every format), PNG decoded by
//! the `png` crate (the codec the renderer's image export uses too), JPEG and WebP by `image`
//! natively. The page decodes every texture with the browser's own decoders (the loading
//! worker's createImageBitmap) and hands the importer the pixels, so its wasm carries no JPEG or
//! WebP decoder: there, an image the browser could not decode is refused by name.

use crate::{AssetError, Limits};

/// The formats glTF textures come in (the core PNG and JPEG, and EXT_texture_webp).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Format {
    Png,
    Jpeg,
    Webp,
}

impl Format {
    fn name(self) -> &'static str {
        match self {
            Self::Png => "PNG",
            Self::Jpeg => "JPEG",
            Self::Webp => "WebP",
        }
    }
}

fn image_error(index: usize, reason: impl Into<String>) -> AssetError {
    AssetError::Image {
        index,
        reason: reason.into(),
    }
}

/// The format and size the image's header declares.
fn header(bytes: &[u8], index: usize) -> Result<(Format, u32, u32), AssetError> {
    let format = match imagesize::image_type(bytes) {
        Ok(imagesize::ImageType::Png) => Format::Png,
        Ok(imagesize::ImageType::Jpeg) => Format::Jpeg,
        Ok(imagesize::ImageType::Webp) => Format::Webp,
        _ => {
            return Err(image_error(
                index,
                "not a PNG, JPEG or WebP image (the formats glTF textures come in)",
            ));
        }
    };
    let size = imagesize::blob_size(bytes).map_err(|error| {
        image_error(
            index,
            format!("{} header unreadable: {error}", format.name()),
        )
    })?;
    let side = |value: usize| u32::try_from(value).unwrap_or(u32::MAX);
    Ok((format, side(size.width), side(size.height)))
}

/// Decodes an encoded image to RGBA8 after checking its declared size against the side
/// limit and against what is left of the decoded-bytes budget (`already` spent); with
/// `size_only`, the checked size and no pixels.
pub(super) fn decode_image_bytes(
    bytes: &[u8],
    index: usize,
    limits: &Limits,
    already: u64,
    size_only: bool,
) -> Result<(u32, u32, Vec<u8>), AssetError> {
    let (format, w, h) = header(bytes, index)?;
    if w == 0 || h == 0 {
        return Err(image_error(
            index,
            format!("{} of size {w} x {h}", format.name()),
        ));
    }
    // Over the side limit: the texture is drawn white and the import goes on.
    if w > limits.max_texture_side || h > limits.max_texture_side {
        return Err(image_error(
            index,
            format!(
                "{} of {w} x {h} pixels: over the texture side limit of {}",
                format.name(),
                limits.max_texture_side
            ),
        ));
    }
    let total = already.saturating_add(u64::from(w) * u64::from(h) * 4);
    if total > limits.max_decoded_bytes {
        return Err(AssetError::TooLarge {
            what: format!("decoded data (at image {index})"),
            size: total,
            limit: limits.max_decoded_bytes,
        });
    }
    if size_only {
        return Ok((w, h, Vec::new()));
    }
    // What a decoder may allocate: the image at 16 bits a channel, as the header declares it.
    let max_alloc = u64::from(w) * u64::from(h) * 8 + (1 << 20);
    let rgba = match format {
        Format::Png => decode_png(bytes, max_alloc)
            .map_err(|error| image_error(index, format!("PNG: {error}")))?,
        Format::Jpeg | Format::Webp => decode_other(bytes, format, index, max_alloc)?,
    };
    let (decoded_w, decoded_h, pixels) = rgba;
    if (decoded_w, decoded_h) != (w, h) || pixels.len() as u64 != u64::from(w) * u64::from(h) * 4 {
        return Err(image_error(
            index,
            format!(
                "{} header says {w} x {h}, the pixels are {decoded_w} x {decoded_h}",
                format.name()
            ),
        ));
    }
    Ok((w, h, pixels))
}

/// A PNG as RGBA8: palettes and transparency chunks expanded, 16-bit channels to 8.
fn decode_png(bytes: &[u8], max_alloc: u64) -> Result<(u32, u32, Vec<u8>), String> {
    let limits = png::Limits {
        bytes: usize::try_from(max_alloc).unwrap_or(usize::MAX),
    };
    let mut decoder = png::Decoder::new_with_limits(std::io::Cursor::new(bytes), limits);
    decoder.set_transformations(png::Transformations::normalize_to_color8());
    let mut reader = decoder.read_info().map_err(|e| e.to_string())?;
    let size = reader
        .output_buffer_size()
        .ok_or_else(|| "too large to decode".to_owned())?;
    let mut buffer = vec![0; size];
    let info = reader.next_frame(&mut buffer).map_err(|e| e.to_string())?;
    buffer.truncate(info.buffer_size());
    let rgba = match info.color_type {
        png::ColorType::Rgba => buffer,
        png::ColorType::Rgb => buffer
            .chunks_exact(3)
            .flat_map(|p| [p[0], p[1], p[2], 255])
            .collect(),
        png::ColorType::GrayscaleAlpha => buffer
            .chunks_exact(2)
            .flat_map(|p| [p[0], p[0], p[0], p[1]])
            .collect(),
        png::ColorType::Grayscale => buffer.iter().flat_map(|&g| [g, g, g, 255]).collect(),
        png::ColorType::Indexed => return Err("palette left unexpanded".to_owned()),
    };
    Ok((info.width, info.height, rgba))
}

/// JPEG and WebP, natively.
#[cfg(not(target_arch = "wasm32"))]
fn decode_other(
    bytes: &[u8],
    format: Format,
    index: usize,
    max_alloc: u64,
) -> Result<(u32, u32, Vec<u8>), AssetError> {
    let image_format = match format {
        Format::Webp => image::ImageFormat::WebP,
        Format::Jpeg | Format::Png => image::ImageFormat::Jpeg,
    };
    let mut reader = image::ImageReader::with_format(std::io::Cursor::new(bytes), image_format);
    let mut limits = image::Limits::default();
    limits.max_alloc = Some(max_alloc);
    reader.limits(limits);
    let decoded = reader
        .decode()
        .map_err(|error| image_error(index, format!("{}: {error}", format.name())))?;
    let rgba = decoded.into_rgba8();
    Ok((rgba.width(), rgba.height(), rgba.into_raw()))
}

/// In the page the browser decodes JPEG and WebP; the importer is asked only when it could not.
#[cfg(target_arch = "wasm32")]
fn decode_other(
    _bytes: &[u8],
    format: Format,
    index: usize,
    _max_alloc: u64,
) -> Result<(u32, u32, Vec<u8>), AssetError> {
    Err(image_error(
        index,
        format!(
            "{0} not decoded: in the page {0} textures are decoded by the browser, which did \
             not decode this one",
            format.name()
        ),
    ))
}
