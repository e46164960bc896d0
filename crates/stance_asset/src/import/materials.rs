//! Textures (images decoded to RGBA8, or placeholders) and materials (base colour, alpha
//! mode, unlit, MToon).

use gltf::json::{self, validation::Checked};
use serde_json::Value;

use super::buffers::decode_data_uri;
use super::raster::decode_image_bytes;
use super::{Ctx, Resolver, bad_index, sz};
use crate::AssetError;
use crate::model::{AlphaMode, Material, Texture, Wrap};

pub(super) fn import_textures(
    ctx: &mut Ctx<'_>,
    decode: bool,
    used: &[usize],
    resolve: &mut Resolver<'_>,
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
            images[source] = given_image(ctx, source)?;
        }
        // Pixels that follow: the header's size now, no pixels.
        let size_only = ctx.images_to_follow.contains(&source);
        if images[source].is_none() {
            match decode_image(ctx, source, resolve, size_only) {
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
        // (Pixels that follow are charged at their size.)
        let bytes = images[source].as_ref().map_or(4, |i| {
            (i.0 as usize)
                .saturating_mul(i.1 as usize)
                .saturating_mul(4)
        });
        ctx.charge(bytes, &format!("texture {t}"))?;
        let (width, height, rgba8) = images[source].clone().unwrap_or((1, 1, vec![255; 4]));
        textures.push(Texture {
            name,
            width,
            height,
            rgba8: std::sync::Arc::new(rgba8),
            image: Some(source),
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
        rgba8: std::sync::Arc::new(vec![255; 4]),
        image: None,
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

/// The caller's decoded pixels of image `index`, checked against the limits and charged;
/// `None` (with a warning when they were wrong) to decode the file's own bytes.
fn given_image(ctx: &mut Ctx<'_>, index: usize) -> Result<Option<(u32, u32, Vec<u8>)>, AssetError> {
    let Some(at) = ctx.decoded_images.iter().position(|d| d.index == index) else {
        return Ok(None);
    };
    let given = ctx.decoded_images.swap_remove(at);
    let side = ctx.limits.max_texture_side;
    let expected = u64::from(given.width) * u64::from(given.height) * 4;
    if given.width == 0 || given.height == 0 || expected != given.rgba8.len() as u64 {
        ctx.warnings.push(format!(
            "image {index}: the decoded pixels ({} bytes) do not fit {}x{}; decoded again",
            given.rgba8.len(),
            given.width,
            given.height
        ));
        return Ok(None);
    }
    if given.width > side || given.height > side {
        return Err(AssetError::TooLarge {
            what: format!("image {index} side"),
            size: u64::from(given.width.max(given.height)),
            limit: u64::from(side),
        });
    }
    ctx.charge(given.rgba8.len(), &format!("image {index}"))?;
    Ok(Some((given.width, given.height, given.rgba8)))
}

/// Image `index` decoded, or with `size_only` its header's size and no pixels.
fn decode_image(
    ctx: &mut Ctx<'_>,
    index: usize,
    resolve: &mut Resolver<'_>,
    size_only: bool,
) -> Result<(u32, u32, Vec<u8>), AssetError> {
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
            None => match resolve(uri) {
                Some(d) => {
                    owned = d;
                    &owned
                }
                None => {
                    return Err(AssetError::Image {
                        index,
                        reason: format!(
                            "the image file `{uri}` is missing (give it with the .gltf); drawn white"
                        ),
                    });
                }
            },
        }
    } else {
        return Err(AssetError::Image {
            index,
            reason: "neither bufferView nor uri".into(),
        });
    };
    let image = decode_image_bytes(bytes, index, ctx.limits, ctx.decoded_bytes, size_only)?;
    ctx.charge(image.2.len(), &what)?;
    Ok(image)
}

pub(super) fn import_materials(
    ctx: &Ctx<'_>,
    texture_count: usize,
) -> Result<Vec<Material>, AssetError> {
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
