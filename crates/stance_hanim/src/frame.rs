//! The H-Anim frame of a mapped humanoid given in some file's space: any up axis, facing and
//! unit become metres, +Y up, +Z the front of the body, +X the body's left.
//!
//! The body's own axes come from the mapped joints (head above ankles, left hip and
//! shoulder on the left); they are snapped to the file's axes when within 30 degrees (so
//! files that follow glTF's +Y up stay exactly upright).
//!
//! Scale: the height of the skull base above the ankles in file units, `h`, is read from the
//! mapped joints. Each standard unit (m, dm, cm, mm, inch; and for motion files the CMU
//! database's 0.45-inch unit) that puts `h` within [`PLAUSIBLE_SKULLBASE`] (0.5 to 2.0 m,
//! people from about 0.6 to 2.25 m tall) is a candidate. The candidate closest to the H-Anim
//! default body (1.55 m, ratio measured on a log scale) wins, and the body keeps its true
//! size. When no standard unit gives a plausible human, as for a model exported at 2.5 times
//! its size, the scale is whatever makes `h` equal to the H-Anim default's, with a warning.

use glam::{DMat3, DVec3};

use crate::builder::snap_to_axes;

/// Height of the H-Anim default skullbase above the ankles (m).
pub const SKULLBASE_ABOVE_ANKLES: f64 = 1.6209 - 0.068;

/// Skull base above the ankles (m) that a human body can have at a standard unit.
pub const PLAUSIBLE_SKULLBASE: std::ops::RangeInclusive<f64> = 0.5..=2.0;

/// Standard units of model files (metres per file unit) and their names.
pub const MODEL_UNITS: [(f64, &str); 5] = [
    (1.0, "m"),
    (0.01, "cm"),
    (0.001, "mm"),
    (0.0254, "inch"),
    (0.1, "dm"),
];

/// The CMU motion-capture database's unit (its ASF `length 0.45`: one unit is 1/0.45 inch),
/// which its BVH conversions keep.
pub const CMU_UNIT: (f64, &str) = (0.0254 / 0.45, "CMU unit (1/0.45 inch)");

/// Units of motion files: the model units and the CMU unit.
pub const MOTION_UNITS: [(f64, &str); 6] = [
    MODEL_UNITS[0],
    MODEL_UNITS[1],
    MODEL_UNITS[2],
    MODEL_UNITS[3],
    MODEL_UNITS[4],
    CMU_UNIT,
];

/// How a humanoid in file space maps onto the H-Anim frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BodyFrame {
    /// Rotation taking file directions to H-Anim directions (rows: left, up, front; snapped
    /// to a signed permutation when within 30 degrees of one).
    pub hanim_from_file: DMat3,
    /// Skull base (or the highest spine joint found) above the ankles, file units; 0 when
    /// the joints are missing.
    pub height_file: f64,
    /// Mid-point of the ankles in file space, when found.
    pub ankles: Option<DVec3>,
}

/// The body frame from the file-space rest positions of the mapped H-Anim joints
/// (`position("l_hip")`...).
pub fn body_frame(position: impl Fn(&str) -> Option<DVec3>) -> BodyFrame {
    let ankles = match (position("l_talocrural"), position("r_talocrural")) {
        (Some(l), Some(r)) => Some((l + r) * 0.5),
        (l, r) => l.or(r),
    };
    let head = position("skullbase")
        .or_else(|| position("vc4"))
        .or_else(|| position("vt1"));
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
        if let (Some(l), Some(r)) = (position(l), position(r)) {
            left += l - r;
        }
    }
    let left = (left - up * up.dot(left)).normalize_or(DVec3::X);
    let front = left.cross(up);
    // Rows: left, up, front.
    let body = DMat3::from_cols(left, up, front).transpose();
    let height_file = match (head, ankles) {
        (Some(h), Some(a)) => (h - a).length(),
        _ => 0.0,
    };
    BodyFrame {
        hanim_from_file: snap_to_axes(body, 30.0).unwrap_or(body),
        height_file,
        ankles,
    }
}

/// Metres per file unit among `units`, and a warning when no unit gives a human and the
/// scale is guessed (see the module documentation). `height_file`: skull base above the
/// ankles in file units.
pub fn unit_scale(height_file: f64, units: &[(f64, &str)]) -> (f64, Option<String>) {
    if !(height_file.is_finite() && height_file > 1e-9) {
        return (1.0, None);
    }
    let error = |u: f64| (u * height_file / SKULLBASE_ABOVE_ANKLES).ln().abs();
    let standard = units
        .iter()
        .filter(|(u, _)| PLAUSIBLE_SKULLBASE.contains(&(u * height_file)))
        .min_by(|a, b| error(a.0).total_cmp(&error(b.0)));
    if let Some(&(u, _)) = standard {
        return (u, None);
    }
    let scale = SKULLBASE_ABOVE_ANKLES / height_file;
    let tried: Vec<String> = units
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

/// The name of a unit of `units` (metres per unit), if it is one of them.
pub fn unit_name(scale: f64, units: &[(f64, &'static str)]) -> Option<&'static str> {
    units.iter().find(|(u, _)| *u == scale).map(|(_, n)| *n)
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;

    fn unit(h: f64) -> (f64, Option<String>) {
        unit_scale(h, &MODEL_UNITS)
    }

    #[test]
    fn standard_units_are_kept_and_others_scaled_with_a_warning() {
        let h = SKULLBASE_ABOVE_ANKLES;
        assert_eq!(unit(h), (1.0, None));
        assert_eq!(unit(h * 100.0), (0.01, None));
        assert_eq!(unit(h * 1000.0), (0.001, None));
        assert_eq!(unit(h * 10.0), (0.1, None));
        assert_eq!(unit(h / 0.0254), (0.0254, None));
        // A child or a small stylised avatar keeps its size.
        assert_eq!(unit(0.7), (1.0, None));
        assert_eq!(unit(80.0), (0.01, None));
        // Where cm and inch both give a person, the nearer to the default body wins.
        assert_eq!(unit(70.0), (0.0254, None));
        // 2.5 times too large in metres: 3.9 m is no human, nor 0.39 m in dm.
        let (s, w) = unit(h * 2.5);
        assert!((s - 0.4).abs() < 1e-12, "{s}");
        let w = w.unwrap();
        assert!(
            w.starts_with("model scale:") && w.contains("scaled by 0.400000"),
            "{w}"
        );
        let (s, w) = unit(0.3);
        assert!((s - h / 0.3).abs() < 1e-12 && w.is_some());
        // No head or ankles: nothing to measure.
        assert_eq!(unit(0.0), (1.0, None));
        assert_eq!(unit(f64::NAN), (1.0, None));
    }

    #[test]
    fn a_cmu_sized_skeleton_is_read_in_cmu_units() {
        // CMU subjects: skull base about 27 units above the ankles.
        let (s, w) = unit_scale(27.0, &MOTION_UNITS);
        assert_eq!((s, w), (0.0254 / 0.45, None));
        assert_eq!(unit_name(s, &MOTION_UNITS), Some("CMU unit (1/0.45 inch)"));
    }

    #[test]
    fn a_z_up_body_facing_minus_x_gets_its_axes() {
        // Up = +Z, left = +Y, front = left x up = +X... in file space.
        let pos = |n: &str| -> Option<DVec3> {
            Some(match n {
                "skullbase" => DVec3::new(0.0, 0.0, 1.6),
                "l_talocrural" => DVec3::new(0.0, 0.1, 0.07),
                "r_talocrural" => DVec3::new(0.0, -0.1, 0.07),
                "l_hip" => DVec3::new(0.0, 0.1, 0.9),
                "r_hip" => DVec3::new(0.0, -0.1, 0.9),
                _ => return None,
            })
        };
        let f = body_frame(pos);
        assert!((f.hanim_from_file * DVec3::Z - DVec3::Y).length() < 1e-12);
        assert!((f.hanim_from_file * DVec3::Y - DVec3::X).length() < 1e-12);
        assert!((f.height_file - 1.53).abs() < 1e-12);
    }
}
