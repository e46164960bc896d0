//! A scene's things as the renderer draws them: each character's capsules and skinning
//! palettes are in its own frame, put in the scene by its placement
//! ([`stance_document::Placement::scene_from_character`]); each prop is its unit shape
//! sized, turned and placed. The editor's viewport and images and `stance render` all draw a
//! scene through these, so that a scene looks the same in each (and the GLB export meshes a
//! prop from the same unit shape and size).

use glam::{DMat4, DVec3, Mat4, Vec3};
use stance_document::{Placement, Prop, PropShape};

use crate::{Capsule, ContactShadow, MeshPropInstance, PropInstance, PropTemplate};

/// The colour of the props (linear RGB): a light wood.
pub const PROP_COLOR_LINEAR: [f32; 4] = [0.52, 0.40, 0.28, 1.0];
/// How thick a plane prop is drawn (m): a plane has no thickness of its own.
pub const PLANE_THICKNESS_M: f64 = 0.01;

/// The unit shape a prop is drawn with and its size along the shape's X, Y and Z (the scale
/// that makes the unit shape the prop, before its turn and place).
pub fn prop_template(prop: &Prop) -> (PropTemplate, DVec3) {
    match prop.shape {
        // A mesh not drawn as its own triangles (its file not loaded) is its box.
        PropShape::Box { size } | PropShape::Mesh { size, .. } => {
            (PropTemplate::Box, DVec3::from_array(size))
        }
        PropShape::Sphere { radius } => (PropTemplate::Sphere, DVec3::splat(radius)),
        PropShape::Cylinder { radius, height } => {
            (PropTemplate::Cylinder, DVec3::new(radius, height, radius))
        }
        PropShape::Plane { size } => (
            PropTemplate::Box,
            DVec3::new(size[0], PLANE_THICKNESS_M, size[1]),
        ),
    }
}

/// How the renderer draws `prop`: its unit shape, sized, turned and placed.
pub fn prop_instance(prop: &Prop) -> PropInstance {
    let (template, size) = prop_template(prop);
    let world_from_unit = DMat4::from(prop.scene_from_prop()) * DMat4::from_scale(size);
    PropInstance {
        template,
        world_from_unit: world_from_unit.as_mat4(),
        color_linear: PROP_COLOR_LINEAR,
    }
}

/// How the renderer draws `prop` with `mesh`, its file's triangles: fitted to its box, turned
/// and placed.
pub fn mesh_prop_instance(
    prop: &Prop,
    mesh: &std::sync::Arc<stance_asset::PropMesh>,
) -> MeshPropInstance {
    let world_from_mesh = prop.scene_from_prop() * mesh.prop_from_mesh(prop.shape.extents());
    MeshPropInstance {
        mesh: mesh.clone(),
        world_from_mesh: DMat4::from(world_from_mesh).as_mat4(),
    }
}

/// The corners of the box around `prop` in the scene (a sphere's and a cylinder's bounding
/// box): what frames a camera on it and casts its shadow.
pub fn prop_corners(prop: &Prop) -> impl Iterator<Item = Vec3> {
    let instance = prop_instance(prop);
    // The unit sphere has radius 1; the unit box and cylinder reach 0.5 along each axis.
    let half = match instance.template {
        PropTemplate::Box | PropTemplate::Cylinder => 0.5,
        PropTemplate::Sphere => 1.0,
    };
    (0..8).map(move |i| {
        let corner = Vec3::new(
            if i & 1 == 0 { -half } else { half },
            if i & 2 == 0 { -half } else { half },
            if i & 4 == 0 { -half } else { half },
        );
        instance.world_from_unit.transform_point3(corner)
    })
}

/// The contact shadow under `prop`.
pub fn prop_shadow(prop: &Prop) -> Option<ContactShadow> {
    ContactShadow::under(prop_corners(prop), 0.05, 0.6)
}

/// The contact shadow under a character's body, its capsules already in the scene.
pub fn character_shadow(placed_capsules: &[Capsule]) -> Option<ContactShadow> {
    let ends = placed_capsules
        .iter()
        .flat_map(|capsule| [capsule.start_world, capsule.end_world]);
    ContactShadow::under(ends, 0.15, 0.6)
}

/// A character's frame in the scene, for the GPU.
pub fn scene_from_character(placement: &Placement) -> Mat4 {
    placement.scene_from_character().as_affine3a().into()
}

/// `capsule`, in a character's frame, put in the scene.
pub fn placed_capsule(capsule: Capsule, scene_from_character: Mat4) -> Capsule {
    let place = |point: Vec3| scene_from_character.transform_point3(point);
    Capsule {
        start_world: place(capsule.start_world),
        end_world: place(capsule.end_world),
        ..capsule
    }
}

/// Skinning palettes (mesh space to the character's frame) put in the scene.
pub fn placed_palettes(mut palettes: Vec<Vec<Mat4>>, scene_from_character: Mat4) -> Vec<Vec<Mat4>> {
    if scene_from_character != Mat4::IDENTITY {
        for matrix in palettes.iter_mut().flatten() {
            *matrix = scene_from_character * *matrix;
        }
    }
    palettes
}

/// A character's keypoints (in its own frame) put in the scene: the points placed, the head's
/// facing directions turned with it.
pub fn placed_keypoints(
    keypoints: &stance_hanim::keypoints::PoseKeypoints,
    placement: &Placement,
) -> stance_hanim::keypoints::PoseKeypoints {
    let scene_from_character = placement.scene_from_character();
    let point = |p: Option<DVec3>| p.map(|p| scene_from_character.transform_point3(p));
    let direction = |d: Option<DVec3>| d.map(|d| scene_from_character.transform_vector3(d));
    stance_hanim::keypoints::PoseKeypoints {
        body: keypoints.body.map(point),
        body_facing: keypoints.body_facing.map(direction),
        left_hand: keypoints.left_hand.map(point),
        right_hand: keypoints.right_hand.map(point),
    }
}

/// `prop` as a triangle mesh in its own frame (centred on it, unturned: its node takes
/// [`Prop::scene_from_prop`]), the renderer's unit shape sized: what the GLB export writes.
pub fn prop_static_mesh(prop: &Prop) -> stance_asset::StaticMesh {
    let (template, size) = prop_template(prop);
    let size = size.as_vec3();
    let unit = crate::prop_mesh(template);
    stance_asset::StaticMesh {
        positions: unit
            .positions
            .iter()
            .map(|p| (*p * size).to_array())
            .collect(),
        // A normal scales by the inverse of the size (the inverse transpose of a scale).
        normals: unit
            .normals
            .iter()
            .map(|n| (*n / size).normalize_or_zero().to_array())
            .collect(),
        indices: unit.indices.iter().map(|&i| u32::from(i)).collect(),
        color_linear: PROP_COLOR_LINEAR,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A mesh whose box runs from (1, 2, 3) to (3, 6, 4) fitted to a 1 m cube at (10, 0, 0),
    /// turned a quarter about +Y, by hand: the box's centre (2, 4, 3.5) goes to the prop's
    /// centre; its least corner, (-0.5, -0.5, -0.5) once centred and scaled by (1/2, 1/4, 1),
    /// turns to (-0.5, -0.5, 0.5) (x to -z, z to x), then moves to (9.5, -0.5, 0.5).
    #[test]
    fn a_mesh_prop_is_fitted_to_its_box_turned_and_placed() {
        let part = stance_asset::StaticMesh {
            positions: vec![[1.0, 2.0, 3.0], [3.0, 2.0, 3.0], [1.0, 6.0, 4.0]],
            normals: vec![[0.0, 0.0, 1.0]; 3],
            indices: vec![0, 1, 2],
            color_linear: [1.0; 4],
        };
        let mesh = std::sync::Arc::new(stance_asset::PropMesh {
            parts: vec![part],
            min: DVec3::new(1.0, 2.0, 3.0),
            max: DVec3::new(3.0, 6.0, 4.0),
        });
        let mut prop = Prop::new(
            "Crate".into(),
            PropShape::Mesh {
                file: "crate.glb".into(),
                size: [1.0, 1.0, 1.0],
            },
            [10.0, 0.0, 0.0],
        );
        prop.rotation = glam::DQuat::from_rotation_y(std::f64::consts::FRAC_PI_2).to_array();
        let instance = mesh_prop_instance(&prop, &mesh);
        let at = |p: [f32; 3]| {
            instance
                .world_from_mesh
                .transform_point3(Vec3::from_array(p))
        };
        assert!((at([2.0, 4.0, 3.5]) - Vec3::new(10.0, 0.0, 0.0)).length() < 1e-5);
        let corner = at([1.0, 2.0, 3.0]);
        assert!(
            (corner - Vec3::new(9.5, -0.5, 0.5)).length() < 1e-5,
            "{corner}"
        );
        // Its shadow and framing use its box: the same corners as a box prop of that size.
        let boxed = Prop {
            shape: PropShape::Box {
                size: [1.0, 1.0, 1.0],
            },
            ..prop.clone()
        };
        let corners: Vec<Vec3> = prop_corners(&prop).collect();
        assert_eq!(corners, prop_corners(&boxed).collect::<Vec<_>>());
    }
}
