//! Props as the renderer draws them: unit shapes (a box, a sphere, a cylinder along +Y), each
//! instance placed, turned and sized by its `world_from_unit` matrix. The meshes are plain
//! data (built without wgpu); the pipeline that draws them is in `renderer.rs`.

use glam::{Mat3, Mat4, Vec3};

/// Which unit shape an instance draws.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PropTemplate {
    /// The cube from -0.5 to 0.5 along each axis.
    Box,
    /// The sphere of radius 1.
    Sphere,
    /// The cylinder of radius 1 from y = -0.5 to 0.5, capped.
    Cylinder,
}

impl PropTemplate {
    /// Every template, in the order of the renderer's combined mesh.
    pub const ALL: [Self; 3] = [Self::Box, Self::Sphere, Self::Cylinder];
}

/// One prop to draw.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PropInstance {
    /// Its unit shape.
    pub template: PropTemplate,
    /// The unit shape to the world: the prop's place and turn times its size.
    pub world_from_unit: Mat4,
    /// Linear RGBA.
    pub color_linear: [f32; 4],
}

/// A prop drawn with its own triangles: a mesh prop whose file is loaded. Two are equal when
/// they draw the same mesh (the same `Arc`, not a copy) at the same place.
#[derive(Debug, Clone)]
pub struct MeshPropInstance {
    /// The file's triangles (the renderer keeps them on the GPU while a frame draws them).
    pub mesh: std::sync::Arc<stance_asset::PropMesh>,
    /// The file's scene space to the world: the prop's place and turn times
    /// [`stance_asset::PropMesh::prop_from_mesh`].
    pub world_from_mesh: Mat4,
}

impl PartialEq for MeshPropInstance {
    fn eq(&self, other: &Self) -> bool {
        std::sync::Arc::ptr_eq(&self.mesh, &other.mesh)
            && self.world_from_mesh == other.world_from_mesh
    }
}

/// A unit shape's mesh: points, outward normals, triangles counter-clockwise seen from
/// outside.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct PropMesh {
    /// Points.
    pub positions: Vec<Vec3>,
    /// Outward unit normals, one per point.
    pub normals: Vec<Vec3>,
    /// Triangles.
    pub indices: Vec<u16>,
}

impl PropMesh {
    fn push(&mut self, position: Vec3, normal: Vec3) -> u16 {
        let index = u16::try_from(self.positions.len()).unwrap_or(u16::MAX);
        self.positions.push(position);
        self.normals.push(normal);
        index
    }

    /// A quad `a b c d` (counter-clockwise seen from where `normal` points).
    fn quad(&mut self, corners: [Vec3; 4], normal: Vec3) {
        let [a, b, c, d] = corners.map(|corner| self.push(corner, normal));
        self.indices.extend_from_slice(&[a, b, c, a, c, d]);
    }
}

/// The unit mesh of `template`.
pub fn prop_mesh(template: PropTemplate) -> PropMesh {
    match template {
        PropTemplate::Box => box_mesh(),
        PropTemplate::Sphere => sphere_mesh(12, 24),
        PropTemplate::Cylinder => cylinder_mesh(32),
    }
}

fn box_mesh() -> PropMesh {
    let mut mesh = PropMesh::default();
    for axis in 0..3 {
        for sign in [1.0f32, -1.0] {
            let mut normal = Vec3::ZERO;
            normal[axis] = sign;
            // Two axes across the face, so that u x v = normal.
            let mut u = Vec3::ZERO;
            u[(axis + 1) % 3] = 1.0;
            let mut v = Vec3::ZERO;
            v[(axis + 2) % 3] = 1.0;
            if sign < 0.0 {
                std::mem::swap(&mut u, &mut v);
            }
            let centre = normal * 0.5;
            let corners = [
                centre - u * 0.5 - v * 0.5,
                centre + u * 0.5 - v * 0.5,
                centre + u * 0.5 + v * 0.5,
                centre - u * 0.5 + v * 0.5,
            ];
            mesh.quad(corners, normal);
        }
    }
    mesh
}

fn sphere_mesh(rings: u16, segments: u16) -> PropMesh {
    let mut mesh = PropMesh::default();
    for ring in 0..=rings {
        let polar = std::f32::consts::PI * f32::from(ring) / f32::from(rings);
        for segment in 0..=segments {
            let azimuth = std::f32::consts::TAU * f32::from(segment) / f32::from(segments);
            let direction = Vec3::new(
                polar.sin() * azimuth.cos(),
                polar.cos(),
                -polar.sin() * azimuth.sin(),
            );
            mesh.push(direction, direction);
        }
    }
    let stride = segments + 1;
    for ring in 0..rings {
        for segment in 0..segments {
            let a = ring * stride + segment;
            let b = a + stride;
            mesh.indices
                .extend_from_slice(&[a, b, a + 1, a + 1, b, b + 1]);
        }
    }
    mesh
}

fn cylinder_mesh(segments: u16) -> PropMesh {
    let mut mesh = PropMesh::default();
    let around = |segment: u16| {
        let azimuth = std::f32::consts::TAU * f32::from(segment) / f32::from(segments);
        Vec3::new(azimuth.cos(), 0.0, -azimuth.sin())
    };
    for segment in 0..segments {
        let (a, b) = (around(segment), around(segment + 1));
        let side = [
            a - Vec3::Y * 0.5,
            b - Vec3::Y * 0.5,
            b + Vec3::Y * 0.5,
            a + Vec3::Y * 0.5,
        ];
        let [i0, i1, i2, i3] = [(side[0], a), (side[1], b), (side[2], b), (side[3], a)]
            .map(|(position, normal)| mesh.push(position, normal));
        mesh.indices.extend_from_slice(&[i0, i1, i2, i0, i2, i3]);
        for (y, normal) in [(0.5, Vec3::Y), (-0.5, Vec3::NEG_Y)] {
            let centre = mesh.push(Vec3::Y * y, normal);
            let p = mesh.push(a + Vec3::Y * y, normal);
            let q = mesh.push(b + Vec3::Y * y, normal);
            if y > 0.0 {
                mesh.indices.extend_from_slice(&[centre, p, q]);
            } else {
                mesh.indices.extend_from_slice(&[centre, q, p]);
            }
        }
    }
    mesh
}

/// The matrix that turns a unit shape's normals into the world's (the inverse transpose of
/// `world_from_unit`'s 3x3).
pub fn normal_matrix(world_from_unit: Mat4) -> Mat3 {
    Mat3::from_mat4(world_from_unit).inverse().transpose()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every triangle turns counter-clockwise seen from outside: its winding normal agrees
    /// with the points' normals (else the renderer culls the outside).
    #[test]
    fn every_triangle_faces_outward() {
        for template in PropTemplate::ALL {
            let mesh = prop_mesh(template);
            assert!(!mesh.indices.is_empty());
            for triangle in mesh.indices.chunks(3) {
                let [a, b, c] = [0, 1, 2].map(|i| mesh.positions[usize::from(triangle[i])]);
                let winding = (b - a).cross(c - a);
                if winding.length() < 1e-6 {
                    continue; // a sphere's pole
                }
                let normal = mesh.normals[usize::from(triangle[0])]
                    + mesh.normals[usize::from(triangle[1])]
                    + mesh.normals[usize::from(triangle[2])];
                assert!(winding.dot(normal) > 0.0, "{template:?} {triangle:?}");
            }
        }
    }

    #[test]
    fn the_unit_shapes_have_their_documented_extents() {
        for (template, extent) in [
            (PropTemplate::Box, Vec3::splat(0.5)),
            (PropTemplate::Sphere, Vec3::splat(1.0)),
            (PropTemplate::Cylinder, Vec3::new(1.0, 0.5, 1.0)),
        ] {
            let mesh = prop_mesh(template);
            let most = mesh
                .positions
                .iter()
                .fold(Vec3::ZERO, |most, p| most.max(p.abs()));
            assert!(
                (most - extent).abs().max_element() < 1e-5,
                "{template:?} {most}"
            );
        }
    }
}

#[cfg(test)]
mod shadow_tests {
    use crate::ContactShadow;
    use glam::Vec3;

    /// A thing on the floor casts its darkest shadow under its middle, as wide as it spreads;
    /// the same thing lifted casts a fainter one, none once it is `fade_m` up.
    #[test]
    fn a_shadow_fades_as_its_thing_rises() {
        let block = |lift: f32| {
            [(-0.2, 0.0), (0.2, 0.0), (0.0, 0.4)]
                .map(|(x, z)| Vec3::new(x + 1.0, lift, z))
                .into_iter()
                .chain([Vec3::new(1.0, lift + 1.0, 0.2)])
        };
        let resting = ContactShadow::under(block(0.0), 0.05, 0.6).unwrap();
        assert_eq!(resting.centre_xz, [1.0, 0.2]);
        assert!((resting.radius_m - 0.2 * 1.3).abs() < 1e-6);
        assert!((resting.strength - 1.0).abs() < 1e-6);
        let lifted = ContactShadow::under(block(0.3), 0.05, 0.6).unwrap();
        assert!((lifted.strength - 0.5).abs() < 1e-6);
        assert_eq!(
            ContactShadow::under(block(0.7), 0.05, 0.6)
                .unwrap()
                .strength,
            0.0
        );
        assert!(ContactShadow::under(std::iter::empty(), 0.05, 0.6).is_none());
    }
}
