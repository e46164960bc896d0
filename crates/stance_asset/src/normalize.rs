//! Normalisation of any up axis, facing and unit to the H-Anim frame: metres, +Y up, +Z the
//! front of the body, +X the body's left, soles on y = 0, the root above the origin.
//!
//! The body's own axes come from the mapped joints (head above ankles, left hip and
//! shoulder on the left); they are snapped to the file's axes when within 30 degrees (so
//! files that follow glTF's +Y up stay exactly upright). The unit is the one of 1, 0.01,
//! 0.001, 0.0254, 0.1 that makes the body closest to 1.7 m tall.

use glam::{DMat3, DMat4, DQuat, DVec3};

use crate::model::Avatar;

/// Height of the H-Anim default skullbase above the ankles (m).
const SKULLBASE_ABOVE_ANKLES: f64 = 1.6209 - 0.068;

pub(crate) fn hanim_from_file(avatar: &Avatar) -> DMat4 {
    let world = avatar.rest_world();
    let pos = |h: &str| -> Option<DVec3> {
        avatar
            .mapping
            .source_of(h)
            .and_then(|n| world.get(n))
            .map(|w| w.w_axis.truncate())
    };
    let ankles = match (pos("l_talocrural"), pos("r_talocrural")) {
        (Some(l), Some(r)) => Some((l + r) * 0.5),
        (l, r) => l.or(r),
    };
    let head = pos("skullbase")
        .or_else(|| pos("vc4"))
        .or_else(|| pos("vt1"));
    let up = match (head, ankles) {
        (Some(h), Some(a)) if (h - a).length() > 1e-9 => (h - a).normalize(),
        _ => DVec3::Y,
    };
    let mut left = DVec3::ZERO;
    for (l, r) in [
        ("l_hip", "r_hip"),
        ("l_shoulder", "r_shoulder"),
        ("l_talocrural", "r_talocrural"),
    ] {
        if let (Some(l), Some(r)) = (pos(l), pos(r)) {
            left += l - r;
        }
    }
    let left = (left - up * up.dot(left)).normalize_or(DVec3::X);
    let front = left.cross(up);
    // Rows: left, up, front.
    let body = DMat3::from_cols(left, up, front).transpose();
    let rotation = snap(body).unwrap_or(body);
    let height_file = match (head, ankles) {
        (Some(h), Some(a)) => (h - a).length(),
        _ => 0.0,
    };
    let unit = if height_file > 1e-9 {
        [1.0, 0.01, 0.001, 0.0254, 0.1]
            .into_iter()
            .min_by(|a, b| {
                let ea = (a * height_file / SKULLBASE_ABOVE_ANKLES).ln().abs();
                let eb = (b * height_file / SKULLBASE_ABOVE_ANKLES).ln().abs();
                ea.total_cmp(&eb)
            })
            .unwrap_or(1.0)
    } else {
        1.0
    };
    let linear = DMat4::from_mat3(rotation) * DMat4::from_scale(DVec3::splat(unit));
    // Floor: the lowest vertex at rest; the root above the origin.
    let min_y = lowest_point(avatar, &world, &linear)
        .or_else(|| ankles.map(|a| linear.transform_point3(a).y - 0.068))
        .unwrap_or(0.0);
    let root = pos("humanoid_root").map_or(DVec3::ZERO, |r| linear.transform_point3(r));
    DMat4::from_translation(DVec3::new(-root.x, -min_y, -root.z)) * linear
}

/// Signed permutation nearest to `m` when within 30 degrees.
fn snap(m: DMat3) -> Option<DMat3> {
    let mut cols = [DVec3::ZERO; 3];
    let mut used = [false; 3];
    for (k, col) in cols.iter_mut().enumerate() {
        let v = m.col(k);
        let a = v.abs().max_position();
        if used[a] {
            return None;
        }
        used[a] = true;
        let mut e = DVec3::ZERO;
        e[a] = v[a].signum();
        *col = e;
    }
    let p = DMat3::from_cols(cols[0], cols[1], cols[2]);
    if p.determinant() < 0.0 || m.determinant() < 0.0 {
        return None;
    }
    let angle = DQuat::from_mat3(&p).angle_between(DQuat::from_mat3(&m));
    (angle < 30f64.to_radians()).then_some(p)
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
