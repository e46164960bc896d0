//! Static meshes for props: every triangle primitive of a glTF/GLB file's default scene, its
//! node transforms baked in, read by the avatar importer ([`crate::load_avatar`], not
//! required to be humanoid, textures not decoded) so that a prop file is read by the same
//! code (and within the same [`crate::Limits`]) as an avatar.
//!
//! glTF's units are metres and its up axis +Y: a prop's points are the file's scene space as
//! it is. A skinned mesh is baked at its node, as it stands without its skin.

use glam::{DAffine3, DMat3, DMat4, DVec3};

use crate::AssetError;
use crate::export_scene::StaticMesh;
use crate::model::Avatar;
use crate::{LoadOptions, load_avatar_with};

/// The most vertices a prop's mesh may have, over all its primitives and instances once baked
/// (a prop is drawn beside the characters in a browser: a chair, a table, a step).
pub const MAX_PROP_VERTICES: usize = 200_000;

/// The colour of a primitive without a material (glTF's default material: white).
const DEFAULT_COLOR_LINEAR: [f32; 4] = [1.0, 1.0, 1.0, 1.0];

/// A prop's triangles: one part per primitive and node that draws it, in the file's scene
/// space (m, +Y up), with its bounding box.
#[derive(Debug, Clone, PartialEq)]
pub struct PropMesh {
    /// The parts: positions and unit normals baked, triangles counter-clockwise seen from
    /// outside, the material's base colour factor (linear).
    pub parts: Vec<StaticMesh>,
    /// The box's least corner (m).
    pub min: DVec3,
    /// The box's greatest corner (m).
    pub max: DVec3,
}

impl PropMesh {
    /// Its box's extents along X, Y and Z (m).
    pub fn extents(&self) -> DVec3 {
        self.max - self.min
    }

    /// Its box's centre (m).
    pub fn centre(&self) -> DVec3 {
        (self.min + self.max) / 2.0
    }

    /// Vertices over all parts.
    pub fn vertex_count(&self) -> usize {
        self.parts.iter().map(|p| p.positions.len()).sum()
    }

    /// Triangles over all parts.
    pub fn triangle_count(&self) -> usize {
        self.parts.iter().map(|p| p.indices.len() / 3).sum()
    }

    /// The scale along X, Y and Z that makes the box's extents `size` (1 along an axis where
    /// the mesh is flat).
    pub fn scale_to(&self, size: [f64; 3]) -> DVec3 {
        let extents = self.extents();
        DVec3::select(
            extents.cmpgt(DVec3::splat(1e-9)),
            DVec3::from_array(size) / extents,
            DVec3::ONE,
        )
    }

    /// The transform from the file's scene space to a prop's frame of size `size`: the box's
    /// centre moved to the origin, then scaled by [`Self::scale_to`].
    pub fn prop_from_mesh(&self, size: [f64; 3]) -> DAffine3 {
        DAffine3::from_scale(self.scale_to(size)) * DAffine3::from_translation(-self.centre())
    }

    /// The parts in a prop's frame ([`Self::prop_from_mesh`]); normals follow the scale.
    pub fn fitted(&self, size: [f64; 3]) -> Vec<StaticMesh> {
        let prop_from_mesh = self.prop_from_mesh(size);
        let scale = self.scale_to(size);
        self.parts
            .iter()
            .map(|part| StaticMesh {
                positions: part
                    .positions
                    .iter()
                    .map(|p| {
                        prop_from_mesh
                            .transform_point3(DVec3::from(p.map(f64::from)))
                            .as_vec3()
                            .into()
                    })
                    .collect(),
                normals: part
                    .normals
                    .iter()
                    .map(|n| {
                        (DVec3::from(n.map(f64::from)) / scale)
                            .normalize_or(DVec3::Y)
                            .as_vec3()
                            .into()
                    })
                    .collect(),
                ..part.clone()
            })
            .collect()
    }
}

/// Reads a prop's mesh from a `.glb` or a `.gltf` with its buffers embedded (external files
/// through `resolve`). Errors: not glTF ([`AssetError::NotGltf`] and the importer's other
/// errors), no triangles in the default scene ([`AssetError::NoTriangles`]), more than
/// [`MAX_PROP_VERTICES`] vertices ([`AssetError::TooLarge`]).
pub fn load_prop_mesh(
    bytes: &[u8],
    resolve: &mut crate::Resolver<'_>,
) -> Result<PropMesh, AssetError> {
    let options = LoadOptions {
        require_humanoid: false,
        decode_textures: false,
        ..LoadOptions::default()
    };
    let file = load_avatar_with(bytes, &options, resolve)?;
    let world = file.rest_world();
    let mut parts = Vec::new();
    let mut vertices = 0usize;
    for node in scene_nodes(&file) {
        let (Some(mesh), Some(world_from_mesh)) =
            (file.nodes.get(node).and_then(|n| n.mesh), world.get(node))
        else {
            continue;
        };
        for primitive in file
            .meshes
            .get(mesh)
            .into_iter()
            .flat_map(|m| &m.primitives)
        {
            if primitive.indices.is_empty() {
                continue;
            }
            vertices = vertices.saturating_add(primitive.positions.len());
            if vertices > MAX_PROP_VERTICES {
                return Err(AssetError::TooLarge {
                    what: "a prop's mesh (vertices over all its primitives)".into(),
                    size: vertices as u64,
                    limit: MAX_PROP_VERTICES as u64,
                });
            }
            let color_linear = primitive
                .material
                .and_then(|m| file.materials.get(m))
                .map_or(DEFAULT_COLOR_LINEAR, |m| m.base_color_factor);
            parts.push(baked(primitive, world_from_mesh, color_linear));
        }
    }
    let mut points = parts.iter().flat_map(|p| &p.positions);
    let Some(first) = points.next() else {
        return Err(AssetError::NoTriangles);
    };
    let first = DVec3::from(first.map(f64::from));
    let (min, max) = points.fold((first, first), |(min, max), p| {
        let p = DVec3::from(p.map(f64::from));
        (min.min(p), max.max(p))
    });
    if !(min.is_finite() && max.is_finite()) {
        return Err(AssetError::BadAccessor(
            "the mesh's points are not finite once its node transforms are applied".into(),
        ));
    }
    Ok(PropMesh { parts, min, max })
}

/// The nodes of the default scene, parents before children (each once).
fn scene_nodes(file: &Avatar) -> Vec<usize> {
    let mut seen = vec![false; file.nodes.len()];
    let mut order = Vec::new();
    let mut stack: Vec<usize> = file.scene_roots.iter().rev().copied().collect();
    while let Some(node) = stack.pop() {
        match seen.get_mut(node) {
            Some(visited) if !*visited => *visited = true,
            _ => continue,
        }
        order.push(node);
        if let Some(n) = file.nodes.get(node) {
            stack.extend(n.children.iter().rev());
        }
    }
    order
}

/// `primitive` with `world_from_mesh` baked in: points moved, normals by the inverse
/// transpose, triangles turned over where the transform mirrors.
fn baked(
    primitive: &crate::Primitive,
    world_from_mesh: &DMat4,
    color_linear: [f32; 4],
) -> StaticMesh {
    let normal_matrix = DMat3::from_mat4(*world_from_mesh).inverse().transpose();
    let mirrored = world_from_mesh.determinant() < 0.0;
    let positions = primitive
        .positions
        .iter()
        .map(|p| {
            world_from_mesh
                .transform_point3(DVec3::from(p.map(f64::from)))
                .as_vec3()
                .into()
        })
        .collect();
    let normals = if primitive.normals.len() == primitive.positions.len() {
        primitive
            .normals
            .iter()
            .map(|n| {
                let n = normal_matrix * DVec3::from(n.map(f64::from));
                n.normalize_or(DVec3::Y).as_vec3().into()
            })
            .collect()
    } else {
        Vec::new()
    };
    let mut indices = primitive.indices.clone();
    if mirrored {
        for triangle in indices.chunks_exact_mut(3) {
            triangle.swap(1, 2);
        }
    }
    let mut part = StaticMesh {
        positions,
        normals,
        indices,
        color_linear,
    };
    if part.normals.is_empty() {
        part.normals = crate::import::compute_normals(&part.positions, &part.indices);
    }
    part
}
