//! What the payload writer and reader share: the adaptive range-coder contexts (`Models`)
//! and their priors, which are part of the format, the flag indices, the task kind names,
//! and the quantisation and H-Anim joint-table helpers.

use glam::DVec3;
use stance_ik::Dof;

use crate::document::{DofValues, dof_slot};
use crate::range_coder::{Bit, SymbolModel, UintModel};

/// Typical bit lengths of quantised joint angles (about 0.05 to 1.5 rad), the prior of the
/// rotation model. Part of the format: changing it changes every link.
pub(crate) const ROTATION_PRIOR: [u32; 24] = [
    14, 13, 14, 12, 15, 13, 14, 11, 14, 13, 15, 12, 14, 13, 14, 12, 15, 13, 14, 11, 14, 13, 15, 12,
];
/// Typical bit lengths of quantised positions (0.1 to 2 m at 0.1 mm).
pub(super) const POSITION_PRIOR: [u32; 16] = [
    14, 15, 13, 15, 14, 12, 15, 14, 13, 15, 14, 15, 13, 14, 12, 15,
];
/// Typical bit lengths of task angles (orientations, swivel).
pub(super) const ANGLE_PRIOR: [u32; 8] = [15, 16, 14, 15, 16, 13, 15, 14];

/// Adaptive contexts, one per kind of value; the encoder and the decoder evolve them alike.
#[derive(Debug)]
pub(super) struct Models {
    pub(super) flags: [Bit; 23],
    pub(super) rotation: UintModel,
    pub(super) translation: UintModel,
    pub(super) position: UintModel,
    pub(super) direction: UintModel,
    pub(super) angle: UintModel,
    pub(super) count: UintModel,
    pub(super) gap: UintModel,
    pub(super) level: UintModel,
    pub(super) weight: UintModel,
    pub(super) string_len: UintModel,
    pub(super) loa: SymbolModel<8>,
    pub(super) kind: SymbolModel<8>,
    pub(super) kind16: SymbolModel<16>,
    pub(super) limb: SymbolModel<4>,
    pub(super) mask: SymbolModel<64>,
    pub(super) joint: SymbolModel<256>,
    pub(super) byte: SymbolModel<256>,
}

impl Default for Models {
    fn default() -> Self {
        Self {
            flags: Default::default(),
            rotation: UintModel::primed(&ROTATION_PRIOR),
            translation: UintModel::primed(&POSITION_PRIOR),
            position: UintModel::primed(&POSITION_PRIOR),
            direction: UintModel::default(),
            angle: UintModel::primed(&ANGLE_PRIOR),
            count: UintModel::default(),
            gap: UintModel::default(),
            level: UintModel::default(),
            weight: UintModel::default(),
            string_len: UintModel::default(),
            loa: Default::default(),
            kind: Default::default(),
            kind16: Default::default(),
            limb: Default::default(),
            mask: Default::default(),
            joint: Default::default(),
            byte: Default::default(),
        }
    }
}

// Indices into `Models::flags`.
pub(super) const AVATAR_URL: usize = 0;
pub(super) const MASKS_DEFAULT: usize = 1;
pub(super) const JOINT_MASK_DEFAULT: usize = 2;
pub(super) const ACTIVE: usize = 3;
pub(super) const WEIGHT_ONE: usize = 4;
pub(super) const POINT_ZERO: usize = 5;
pub(super) const AXES_XYZ: usize = 6;
pub(super) const AXIS_Z: usize = 7;
pub(super) const HAS_JOINTS: usize = 8;
pub(super) const HAS_REFERENCE: usize = 9;
pub(super) const HAS_LIMB: usize = 10;
pub(super) const HAS_SWIVEL: usize = 11;
pub(super) const HANIM_JOINT: usize = 12;
pub(super) const WEIGHT_DECIMAL: usize = 13;
pub(super) const HAS_ORIENTATION: usize = 14;
pub(super) const AXIS_Y: usize = 15;
// Format 2.
pub(super) const HAS_INTERVAL: usize = 16;
pub(super) const HAS_MOTION: usize = 17;
// Format 5.
pub(super) const STANDARD_REST: usize = 18;
// Format 6.
pub(super) const HAS_CLIP: usize = 19;
// Format 7.
pub(super) const ABOVE: usize = 20;
// Format 8.
pub(super) const COLLISION_SELF: usize = 21;
pub(super) const COLLISION_FLOOR: usize = 22;

/// `m / 10^k`, correctly rounded (both are exact in f64 for the ranges used).
pub(super) fn from_decimal(m: u64, k: i32) -> f64 {
    m as f64 / 10f64.powi(k)
}

/// `(m, k)` with `w == m / 10^k` exactly, m < 2^50 and k <= 15, for weights typed as short
/// decimals (0.1, 2.5, 1000); `None` for the others (written as all 64 bits).
pub(super) fn short_decimal(w: f64) -> Option<(u64, u8)> {
    if !(w.is_finite() && w >= 0.0) {
        return None;
    }
    (0..=15u8).find_map(|k| {
        let m = (w * 10f64.powi(i32::from(k))).round();
        (m < (1u64 << 50) as f64 && from_decimal(m as u64, i32::from(k)) == w)
            .then_some((m as u64, k))
    })
}

/// Task kinds by symbol: formats 1 and 2 code the first eight (an 8-symbol model), formats 3
/// to 6 the first nine (a 16-symbol model), format 7 eleven (`line`, `plane`), format 8 and
/// later all (`collision`).
pub(super) const KINDS: [&str; 12] = [
    "position",
    "orientation",
    "gaze",
    "com",
    "posture",
    "limb",
    "direction",
    "balance",
    "comfort",
    "line",
    "plane",
    "collision",
];

/// Largest quantised value a link holds (2^48: 2.4e10 rad, 2.8e10 m); larger ones are written
/// as this and refused by the reader. Within it `quantise(dequantise(q))` is `q`, so a decoded
/// link written again holds the same values.
pub(super) const MAX_QUANTISED: i64 = 1 << 48;

pub(super) fn quantise(x: f64, step: f64) -> i64 {
    let limit = MAX_QUANTISED as f64;
    let q = (x / step).round();
    if q.is_nan() {
        0
    } else {
        q.clamp(-limit, limit) as i64
    }
}

pub(super) fn dequantise(q: i64, step: f64) -> f64 {
    q as f64 * step
}

pub(super) fn mask_of(v: &DofValues) -> usize {
    Dof::ALL
        .into_iter()
        .filter(|&d| v.get(d).is_some())
        .fold(0, |m, d| m | (1 << dof_slot(d)))
}

/// `tx ty tz rx ry rz` for the root, `rx ry rz` for every other joint.
pub(super) fn default_mask(table_index: usize) -> usize {
    if table_index == 0 {
        0b11_1111
    } else {
        0b11_1000
    }
}

pub(super) fn in_loa_base(table_index: usize, loa: usize) -> bool {
    loa > 0
        && stance_hanim::all_joints()
            .get(table_index)
            .is_some_and(|d| usize::from(d.first_loa) <= loa)
}

pub(super) fn hanim_index(name: &str) -> Option<usize> {
    stance_hanim::all_joints()
        .iter()
        .position(|d| d.name == name)
}

pub(super) fn unit(v: [f64; 3]) -> [f64; 3] {
    let d = DVec3::from_array(v);
    let n = d.length();
    if n.is_finite() && n > 0.0 {
        (d / n).to_array()
    } else {
        [0.0, 0.0, 1.0]
    }
}
