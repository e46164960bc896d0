//! Normalisation of any up axis, facing and unit to the H-Anim frame: metres, +Y up, +Z the
//! front of the body, +X the body's left, soles on y = 0, the root above the origin.
//!
//! The body's own axes come from the mapped joints (head above ankles, left hip and
//! shoulder on the left); they are snapped to the file's axes when within 30 degrees (so
//! files that follow glTF's +Y up stay exactly upright).
//!
//! Scale: the height of the skull base above the ankles in file units, `h`, is read from the
//! mapped joints. Each standard unit (m, dm, cm, mm, inch) that puts `h` within
//! [`PLAUSIBLE_SKULLBASE`] (0.5 to 2.0 m, people from about 0.6 to 2.25 m tall) is a
//! candidate. The candidate closest to the H-Anim default body (1.55 m, ratio measured on a
//! log scale) wins, and the model keeps its true size. When no standard unit gives a
//! plausible human, as for a model exported at 2.5 times its size, the scale is whatever
//! makes `h` equal to the H-Anim default's, and the import adds a warning.

use glam::{DMat3, DMat4, DQuat, DVec3};

use crate::model::Avatar;

/// Height of the H-Anim default skullbase above the ankles (m).
const SKULLBASE_ABOVE_ANKLES: f64 = 1.6209 - 0.068;

/// Skull base above the ankles (m) that a human body can have at a standard unit.
const PLAUSIBLE_SKULLBASE: std::ops::RangeInclusive<f64> = 0.5..=2.0;

/// Standard units (metres per file unit) and their names.
const UNITS: [(f64, &str); 5] = [
    (1.0, "m"),
    (0.01, "cm"),
    (0.001, "mm"),
    (0.0254, "inch"),
    (0.1, "dm"),
];

/// Metres per file unit, and a warning when the scale is not a standard unit (see the
/// module documentation). `height_file`: skull base above the ankles in file units.
fn unit_scale(height_file: f64) -> (f64, Option<String>) {
    if !(height_file.is_finite() && height_file > 1e-9) {
        return (1.0, None);
    }
    let error = |u: f64| (u * height_file / SKULLBASE_ABOVE_ANKLES).ln().abs();
    let standard = UNITS
        .into_iter()
        .filter(|(u, _)| PLAUSIBLE_SKULLBASE.contains(&(u * height_file)))
        .min_by(|a, b| error(a.0).total_cmp(&error(b.0)));
    if let Some((u, _)) = standard {
        return (u, None);
    }
    let scale = SKULLBASE_ABOVE_ANKLES / height_file;
    let tried: Vec<String> = UNITS
        .iter()
        .map(|(u, name)| format!("{:.3} m in {name}", u * height_file))
        .collect();
    (
        scale,
        Some(format!(
            "model scale: the skull base is {height_file:.4} file units above the ankles, no \
             standard unit makes that a human ({}; plausible {:.1} to {:.1} m); scaled by \
             {scale:.6} to {SKULLBASE_ABOVE_ANKLES:.4} m, the H-Anim default body",
            tried.join(", "),
            PLAUSIBLE_SKULLBASE.start(),
            PLAUSIBLE_SKULLBASE.end(),
        )),
    )
}

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
    let (unit, warning) = unit_scale(height_file);
    let linear = DMat4::from_mat3(rotation) * DMat4::from_scale(DVec3::splat(unit));
    // Floor: the lowest vertex at rest; the root above the origin.
    let min_y = lowest_point(avatar, &world, &linear)
        .or_else(|| ankles.map(|a| linear.transform_point3(a).y - 0.068))
        .unwrap_or(0.0);
    let root = pos("humanoid_root").map_or(DVec3::ZERO, |r| linear.transform_point3(r));
    (
        DMat4::from_translation(DVec3::new(-root.x, -min_y, -root.z)) * linear,
        warning,
    )
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn standard_units_are_kept_and_others_scaled_with_a_warning() {
        let h = SKULLBASE_ABOVE_ANKLES;
        assert_eq!(unit_scale(h), (1.0, None));
        assert_eq!(unit_scale(h * 100.0), (0.01, None));
        assert_eq!(unit_scale(h * 1000.0), (0.001, None));
        assert_eq!(unit_scale(h * 10.0), (0.1, None));
        assert_eq!(unit_scale(h / 0.0254), (0.0254, None));
        // A child or a small stylised avatar keeps its size.
        assert_eq!(unit_scale(0.7), (1.0, None));
        assert_eq!(unit_scale(80.0), (0.01, None));
        // Where cm and inch both give a person, the nearer to the default body wins.
        assert_eq!(unit_scale(70.0), (0.0254, None));
        // 2.5 times too large in metres: 3.9 m is no human, nor 0.39 m in dm.
        let (s, w) = unit_scale(h * 2.5);
        assert!((s - 0.4).abs() < 1e-12, "{s}");
        let w = w.unwrap();
        assert!(
            w.starts_with("model scale:") && w.contains("scaled by 0.400000"),
            "{w}"
        );
        let (s, w) = unit_scale(0.3);
        assert!((s - h / 0.3).abs() < 1e-12 && w.is_some());
        // No head or ankles: nothing to measure.
        assert_eq!(unit_scale(0.0), (1.0, None));
        assert_eq!(unit_scale(f64::NAN), (1.0, None));
    }
}
