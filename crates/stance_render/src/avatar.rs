//! An imported avatar as the renderer draws it: its meshes as a [`SkinnedModel`] (one palette
//! per skin and per rigid mesh node) and the palettes that pose it like a posture. The editor
//! and `stance render` both draw avatars through this.

use glam::{Mat4, Vec3};
use stance_asset::{AlphaMode, Avatar, Primitive, Wrap};
use stance_hanim::HumanoidSkeleton;
use stance_ik::Posture;

use crate::{
    MAX_PALETTE_MATRICES, SkinnedMaterial, SkinnedModel, SkinnedPrimitive, SkinnedTexture,
    SkinnedVertex,
};

/// What moves a palette: a skin's joints, or one node carrying a rigid mesh.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum PaletteSource {
    Skin(usize),
    Node(usize),
}

/// Which skin or node moves each palette of an avatar's [`SkinnedModel`].
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct AvatarPalettes {
    sources: Vec<PaletteSource>,
}

impl AvatarPalettes {
    /// The palettes that show `posture` (of `humanoid`, built from `avatar`): mesh space ->
    /// H-Anim world, or `None` when the posture does not fit the skeleton.
    pub fn pose(
        &self,
        avatar: &Avatar,
        humanoid: &HumanoidSkeleton,
        posture: &Posture,
    ) -> Option<Vec<Vec<Mat4>>> {
        let locals = avatar.posed_locals(humanoid, posture).ok()?;
        let world = avatar.world_from_locals(&locals);
        Some(
            self.sources
                .iter()
                .map(|source| match *source {
                    PaletteSource::Skin(skin) => avatar.skinning_matrices(skin, &world),
                    PaletteSource::Node(node) => vec![
                        (avatar.hanim_from_file * world.get(node).copied().unwrap_or_default())
                            .as_mat4(),
                    ],
                })
                .collect(),
        )
    }
}

/// The GPU model of an avatar: one palette per skin and per rigid mesh node; with the
/// palettes' sources and what the user should know (skins clamped to
/// [`MAX_PALETTE_MATRICES`]).
pub fn avatar_model(avatar: &Avatar) -> (SkinnedModel, AvatarPalettes, Vec<String>) {
    let mut model = SkinnedModel::default();
    let mut sources: Vec<PaletteSource> = Vec::new();
    let mut warnings = Vec::new();
    for (node_index, node) in avatar.nodes.iter().enumerate() {
        let Some(mesh) = node.mesh.and_then(|mesh| avatar.meshes.get(mesh)) else {
            continue;
        };
        let source = match node.skin {
            Some(skin) if skin < avatar.skins.len() => PaletteSource::Skin(skin),
            _ => PaletteSource::Node(node_index),
        };
        let palette = match sources.iter().position(|known| *known == source) {
            Some(index) => index,
            None => {
                let size = match source {
                    PaletteSource::Skin(skin) => {
                        avatar.skins.get(skin).map_or(1, |s| s.joints.len())
                    }
                    PaletteSource::Node(_) => 1,
                };
                if size > MAX_PALETTE_MATRICES {
                    warnings.push(format!(
                        "a skin has {size} joints; only the first {MAX_PALETTE_MATRICES} move its mesh"
                    ));
                }
                sources.push(source);
                model.palette_sizes.push(size.min(MAX_PALETTE_MATRICES));
                sources.len() - 1
            }
        };
        let skinned = matches!(source, PaletteSource::Skin(_));
        for primitive in &mesh.primitives {
            model
                .primitives
                .push(skinned_primitive(primitive, palette, skinned));
        }
    }
    model.materials = avatar
        .materials
        .iter()
        .map(|material| SkinnedMaterial {
            base_color_factor: material.base_color_factor,
            texture: material.base_color_texture,
            unlit: material.unlit,
            alpha_cutoff: (material.alpha_mode == AlphaMode::Mask).then_some(material.alpha_cutoff),
        })
        .collect();
    model.textures = avatar
        .textures
        .iter()
        .map(|texture| SkinnedTexture {
            width: texture.width,
            height: texture.height,
            rgba8: std::sync::Arc::clone(&texture.rgba8),
            repeat: texture.wrap_u != Wrap::Clamp,
        })
        .collect();
    (model, AvatarPalettes { sources }, warnings)
}

/// One primitive for the GPU: unit normals, weights summing to one (a rigid mesh rides on
/// palette entry 0), indices within the vertices and whole triangles only.
fn skinned_primitive(primitive: &Primitive, palette: usize, skinned: bool) -> SkinnedPrimitive {
    let count = primitive.positions.len();
    let vertices = (0..count)
        .map(|i| {
            let normal = primitive
                .normals
                .get(i)
                .copied()
                .filter(|n| Vec3::from_array(*n).length_squared() > 1e-12)
                .unwrap_or([0.0, 1.0, 0.0]);
            let (joints, weights) = if skinned {
                let joints = primitive.joints.get(i).copied().unwrap_or([0; 4]);
                let weights = primitive
                    .weights
                    .get(i)
                    .copied()
                    .unwrap_or([1.0, 0.0, 0.0, 0.0]);
                let sum: f32 = weights.iter().filter(|w| w.is_finite()).sum();
                let weights = if sum > 1e-6 {
                    weights.map(|w| if w.is_finite() { w / sum } else { 0.0 })
                } else {
                    [1.0, 0.0, 0.0, 0.0]
                };
                (joints.map(u32::from), weights)
            } else {
                ([0; 4], [1.0, 0.0, 0.0, 0.0])
            };
            SkinnedVertex {
                position: primitive.positions.get(i).copied().unwrap_or_default(),
                normal,
                uv: primitive.uvs.get(i).copied().unwrap_or_default(),
                joints,
                weights,
            }
        })
        .collect();
    let indices = if primitive.indices.is_empty() {
        (0..u32::try_from(count - count % 3).unwrap_or(0)).collect()
    } else {
        primitive
            .indices
            .iter()
            .copied()
            .filter(|&index| (index as usize) < count)
            .collect::<Vec<u32>>()
    };
    let indices_len = indices.len() - indices.len() % 3;
    SkinnedPrimitive {
        vertices,
        indices: indices.into_iter().take(indices_len).collect(),
        material: primitive.material.unwrap_or(usize::MAX),
        palette,
    }
}
