//! Normalisation of any up axis, facing and unit to the H-Anim frame (the body frame and
//! unit from [`stance_hanim::frame`]), with the soles on y = 0 and the root above the origin.

use glam::{DMat4, DVec3};
use stance_hanim::frame::{MODEL_UNITS, body_frame, unit_scale};

use crate::model::Avatar;

/// The similarity from file space to the H-Anim frame, and a warning when the model's scale
/// had to be guessed (see the module documentation).
pub(crate) fn hanim_from_file(avatar: &Avatar) -> (DMat4, Option<String>) {
    let world = avatar.rest_world();
    let pos = |h: &str| -> Option<DVec3> {
        avatar
            .mapping
            .source_of(h)
            .and_then(|n| world.get(n))
            .map(|w| w.w_axis.truncate())
    };
    let frame = body_frame(pos);
    let (unit, warning) = unit_scale(frame.height_file, &MODEL_UNITS);
    let linear = DMat4::from_mat3(frame.hanim_from_file) * DMat4::from_scale(DVec3::splat(unit));
    // Floor: the lowest vertex at rest; the root above the origin.
    let min_y = lowest_point(avatar, &world, &linear)
        .or_else(|| frame.ankles.map(|a| linear.transform_point3(a).y - 0.068))
        .unwrap_or(0.0);
    let root = pos("humanoid_root").map_or(DVec3::ZERO, |r| linear.transform_point3(r));
    (
        DMat4::from_translation(DVec3::new(-root.x, -min_y, -root.z)) * linear,
        warning,
    )
}

/// Vertices [`lowest_point`] transforms at most: a file instancing one large mesh from
/// thousands of nodes must not cost thousands of passes over it.
const LOWEST_POINT_BUDGET: usize = 32 << 20;

/// Lowest y of the rest-pose mesh after `linear`. A skinned mesh is placed by its skin
/// alone, so each (mesh, skin) pair is visited once; after [`LOWEST_POINT_BUDGET`] vertices
/// the remaining instances are skipped.
fn lowest_point(avatar: &Avatar, world: &[DMat4], linear: &DMat4) -> Option<f64> {
    let mut min: Option<f64> = None;
    let mut seen_skinned = std::collections::HashSet::new();
    let mut budget = LOWEST_POINT_BUDGET;
    for node in avatar
        .nodes
        .iter()
        .enumerate()
        .filter_map(|(i, n)| n.mesh.map(|m| (i, n, m)))
    {
        let (i, n, m) = node;
        let Some(mesh) = avatar.meshes.get(m) else {
            continue;
        };
        if let Some(s) = n.skin
            && !seen_skinned.insert((m, s))
        {
            continue;
        }
        let vertices: usize = mesh.primitives.iter().map(|p| p.positions.len()).sum();
        let Some(left) = budget.checked_sub(vertices) else {
            break;
        };
        budget = left;
        let skin_mats: Option<Vec<DMat4>> = n.skin.and_then(|s| avatar.skins.get(s)).map(|skin| {
            skin.joints
                .iter()
                .zip(&skin.inverse_bind_matrices)
                .map(|(&j, ibm)| {
                    *linear * world.get(j).copied().unwrap_or(DMat4::IDENTITY) * ibm.as_dmat4()
                })
                .collect()
        });
        let node_mat = *linear * world.get(i).copied().unwrap_or(DMat4::IDENTITY);
        for p in &mesh.primitives {
            for (v, pos) in p.positions.iter().enumerate() {
                let local = DVec3::new(pos[0] as f64, pos[1] as f64, pos[2] as f64);
                let y = match (&skin_mats, p.joints.get(v), p.weights.get(v)) {
                    (Some(mats), Some(j), Some(w)) => {
                        let mut y = 0.0;
                        for k in 0..4 {
                            if w[k] > 0.0
                                && let Some(m) = mats.get(j[k] as usize)
                            {
                                y += w[k] as f64 * m.transform_point3(local).y;
                            }
                        }
                        y
                    }
                    _ => node_mat.transform_point3(local).y,
                };
                if y.is_finite() {
                    min = Some(min.map_or(y, |m: f64| m.min(y)));
                }
            }
        }
    }
    min
}
