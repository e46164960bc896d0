//! Comfort of a posture, from the skeleton alone: the static joint loads due to gravity (as a
//! share of each DOF's maximal voluntary torque), the discomfort of DOF near the ends of their
//! ranges, and smooth penalties on the angles between segments; their weighted sum is the cost
//! of the comfort task ([`crate::TaskKind::Comfort`]), whose analytic gradient is the
//! null-space term `z` of the paper's formula (`dtheta = J+ dx + (I - J+ J) z`).
//!
//! What the DOF and segments mean (which strength belongs to a knee, which angle RULA reads)
//! is the caller's: `stance_hanim::comfort` builds a [`ComfortModel`] for an H-Anim body.
//!
//! The gradient costs O(N): every load is `tau_j = (m_j - M_j p_j) x g` from the subtree mass
//! `M_j` and moment `m_j` that forward kinematics already keeps, and its derivatives sum over
//! the tree in one pass down and one up.

use glam::DVec3;

use crate::{Frames, Skeleton};

/// Gravity (m/s^2), along world -Y (H-Anim's up is +Y).
pub const GRAVITY: DVec3 = DVec3::new(0.0, -9.81, 0.0);

/// Maximal voluntary torque of one rotation DOF (N m), as the muscles produce it about the
/// DOF's +axis and about its -axis (e.g. extension and flexion).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DofStrength {
    /// About the joint frame's +axis.
    pub positive: StrengthCurve,
    /// About its -axis.
    pub negative: StrengthCurve,
}

impl DofStrength {
    /// The same constant strength both ways (N m).
    pub fn symmetric(torque: f64) -> Self {
        Self {
            positive: StrengthCurve::constant(torque),
            negative: StrengthCurve::constant(torque),
        }
    }

    /// Constant strengths about the +axis and the -axis (N m).
    pub fn constant(positive: f64, negative: f64) -> Self {
        Self {
            positive: StrengthCurve::constant(positive),
            negative: StrengthCurve::constant(negative),
        }
    }

    /// The curve that holds a gravity torque `tau` about the axis (the muscles produce
    /// `-tau`).
    pub fn holding(&self, tau: f64) -> &StrengthCurve {
        if tau > 0.0 {
            &self.negative
        } else {
            &self.positive
        }
    }

    fn is_valid(&self) -> bool {
        self.positive.is_valid() && self.negative.is_valid()
    }
}

/// A maximal voluntary torque as a function of the DOF's value `q`: Anderson et al. (2007)'s
/// isometric angle curve `peak * cos(width * (sign * q - centre))`, never below `floor` times
/// the peak (the model's cosine reaches zero outside the tested range of motion). `width = 0`
/// gives a constant.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StrengthCurve {
    /// The torque at the peak angle (N m, > 0).
    pub peak: f64,
    /// Anderson's `C2` (1/rad): the curve's angular frequency; 0 for a constant.
    pub width: f64,
    /// Anderson's `C3` (rad): the anatomical angle of the peak.
    pub centre: f64,
    /// The anatomical angle is `sign * q` (+1 or -1): e.g. hip flexion is `-rx`.
    pub sign: f64,
    /// The least share of the peak the curve keeps (default 0.1).
    pub floor: f64,
}

impl StrengthCurve {
    /// A constant strength (N m).
    pub fn constant(peak: f64) -> Self {
        Self {
            peak,
            width: 0.0,
            centre: 0.0,
            sign: 1.0,
            floor: 0.1,
        }
    }

    /// The strength at DOF value `q` and its derivative in `q`.
    pub fn at(&self, q: f64) -> (f64, f64) {
        if self.width == 0.0 {
            return (self.peak.max(self.floor * self.peak), 0.0);
        }
        let phase = self.width * (self.sign * q - self.centre);
        let value = self.peak * phase.cos();
        let least = self.floor * self.peak;
        if phase.abs() >= std::f64::consts::FRAC_PI_2 || value <= least {
            return (least, 0.0);
        }
        (value, -self.peak * phase.sin() * self.width * self.sign)
    }

    fn is_valid(&self) -> bool {
        self.peak.is_finite()
            && self.peak > 0.0
            && self.width.is_finite()
            && self.centre.is_finite()
            && self.sign.is_finite()
            && self.floor.is_finite()
            && self.floor > 0.0
            && self.floor <= 1.0
    }
}

/// Where an [`AngleBand`] measures its angle from.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum AngleReference {
    /// A fixed world direction (unit), e.g. down.
    World(DVec3),
    /// An axis (joint frame, unit) of another segment, e.g. the trunk's down axis.
    Segment {
        /// The segment's joint.
        joint: usize,
        /// The axis in its frame.
        axis: DVec3,
    },
}

/// A smooth stand-in for a score that steps up with an angle (RULA's bands): the angle between
/// a segment axis and a reference, and `sum step_k * s((angle - edge_k) / width)` with the
/// logistic `s`; the exact score is a step function and gives a solver no direction.
#[derive(Debug, Clone, PartialEq)]
pub struct AngleBand {
    /// Name for reports (e.g. `"r_upper_arm"`).
    pub name: String,
    /// The segment's joint.
    pub joint: usize,
    /// The segment axis in its joint frame (unit).
    pub axis: DVec3,
    /// What the angle is measured from.
    pub reference: AngleReference,
    /// `(edge in rad, score step)` pairs.
    pub edges: Vec<(f64, f64)>,
    /// Smoothing width (rad, > 0).
    pub width: f64,
    /// Past each edge, on its costly side, the cost keeps rising by `ramp * |step|` per width
    /// (a softplus): a posture deep inside a costly band is pushed toward its edge, where the
    /// logistic alone would be flat. 0: steps only.
    pub ramp: f64,
}

/// The cost of the comfort task: weighted effort, range discomfort and angle bands.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ComfortModel {
    /// Weight of the effort: `sum_d (tau_d / strength_d)^2` over the DOF with a strength.
    pub effort_weight: f64,
    /// Per DOF (`None`: not counted): the strength that holds its gravity torque.
    pub strength: Vec<Option<DofStrength>>,
    /// Weight of the joint-range discomfort (Marler et al. 2005) of the rotation DOF with
    /// finite limits.
    pub range_weight: f64,
    /// Weight of the angle bands.
    pub band_weight: f64,
    /// The angle bands.
    pub bands: Vec<AngleBand>,
}

/// The comfort of a posture, term by term (each unweighted) and the weighted total.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ComfortTerms {
    /// `sum_d (tau_d / strength_d)^2`.
    pub effort: f64,
    /// Joint-range discomfort, summed over the limited rotation DOF.
    pub range: f64,
    /// Sum of the smooth band scores.
    pub bands: f64,
    /// `effort_weight * effort + range_weight * range + band_weight * bands`.
    pub total: f64,
}

/// Static torque at every joint due to the weight of the segments it carries (N m, world):
/// `sum over the subtree of (c_s - p_j) x m_s g`; the muscles across the joint hold `-tau`.
pub fn gravity_torques(frames: &Frames) -> Vec<DVec3> {
    frames
        .joint_position
        .iter()
        .zip(frames.subtree_moment.iter().zip(&frames.subtree_mass))
        .map(|(&p, (&moment, &mass))| (moment - mass * p).cross(GRAVITY))
        .collect()
}

/// The gravity torque about each rotation DOF's joint-frame axis (N m; 0 for translations).
pub fn dof_torques(skeleton: &Skeleton, frames: &Frames) -> Vec<f64> {
    let torques = gravity_torques(frames);
    skeleton
        .dof_kinds()
        .iter()
        .enumerate()
        .map(|(d, kind)| {
            if !kind.is_rotation() {
                return 0.0;
            }
            let j = skeleton.dof_joint(d);
            torques[j].dot(frames.world_from_joint_rotation[j].col(kind.axis_index()))
        })
        .collect()
}

/// Marler et al. (2005)'s penalty of a DOF at normalised distance `x = (upper - q) / range`
/// from one end of its range: `(0.5 sin(5 x + 1.571) + 0.5)^100`, 1 at the end, below 1e-2
/// from 7 % of the range inward; and its derivative in `x`.
#[inline]
fn range_wall(x: f64) -> (f64, f64) {
    const FREQUENCY: f64 = 5.0;
    const PHASE: f64 = 1.571;
    const POWER: i32 = 100;
    // The sine peaks (value 1) just past the end, at 5 x + 1.571 = pi / 2; flat beyond.
    if FREQUENCY * x + PHASE <= std::f64::consts::FRAC_PI_2 {
        return (1.0, 0.0);
    }
    // From 24 % of the range inward the penalty is below 1e-16 (base 0.68 at 5 x = 1.2):
    // taken as 0, which spares a sine and a power for nearly every DOF of a posture.
    if x > RANGE_WALL_DEPTH {
        return (0.0, 0.0);
    }
    let (sin, cos) = (FREQUENCY * x + PHASE).sin_cos();
    let base = 0.5 * sin + 0.5;
    let below = base.powi(POWER - 1);
    (
        below * base,
        f64::from(POWER) * below * 0.5 * FREQUENCY * cos,
    )
}

/// How far into a DOF's range (a share of the range) [`range_wall`] is above 1e-16: 0.24.
const RANGE_WALL_DEPTH: f64 = 1.2 / 5.0;

/// One edge of an angle band at `x` (the angle past the edge, in widths): the logistic step
/// and the softplus ramps on either side, from one exponential and one logarithm.
struct BandEdge {
    x: f64,
    /// `s(x) = 1 / (1 + e^-x)`.
    step: f64,
    /// `s'(x) = s (1 - s)`.
    slope: f64,
    /// `ln(1 + e^-x)`, without overflow.
    below: f64,
}

impl BandEdge {
    fn at(x: f64) -> Self {
        let e = (-x).exp();
        let step = 1.0 / (1.0 + e);
        Self {
            x,
            step,
            slope: step * (1.0 - step),
            below: if e.is_finite() { e.ln_1p() } else { -x },
        }
    }

    /// `ln(1 + e^x)` and its derivative `s(x)`.
    fn softplus(&self) -> (f64, f64) {
        (self.x + self.below, self.step)
    }

    /// `ln(1 + e^-x)` and its derivative in `-x`, `s(-x)`.
    fn softplus_below(&self) -> (f64, f64) {
        (self.below, 1.0 - self.step)
    }
}

impl ComfortModel {
    /// Checks the model against a skeleton: one strength or none per DOF (or none at all),
    /// finite non-negative weights, positive strengths, joints in range, positive band widths.
    pub fn validate(&self, skeleton: &Skeleton) -> Result<(), String> {
        let weights = [self.effort_weight, self.range_weight, self.band_weight];
        if weights.iter().any(|w| !(w.is_finite() && *w >= 0.0)) {
            return Err("comfort weights must be finite and >= 0".into());
        }
        if !self.strength.is_empty() && self.strength.len() != skeleton.dof_count() {
            return Err(format!(
                "comfort strengths cover {} DOF, the skeleton has {}",
                self.strength.len(),
                skeleton.dof_count()
            ));
        }
        let positive = |v: f64| v.is_finite() && v > 0.0;
        if let Some(d) = self
            .strength
            .iter()
            .position(|s| s.is_some_and(|s| !s.is_valid()))
        {
            return Err(format!("strength of DOF {d} must be positive and finite"));
        }
        for band in &self.bands {
            let joint_ok = |j: usize| j < skeleton.joint_count();
            let reference_ok = match band.reference {
                AngleReference::World(v) => v.is_finite() && v.length() > 1e-9,
                AngleReference::Segment { joint, axis } => {
                    joint_ok(joint) && axis.is_finite() && axis.length() > 1e-9
                }
            };
            if !(joint_ok(band.joint)
                && reference_ok
                && band.axis.is_finite()
                && band.axis.length() > 1e-9
                && positive(band.width)
                && band
                    .edges
                    .iter()
                    .all(|(e, s)| e.is_finite() && s.is_finite()))
            {
                return Err(format!("angle band `{}` is malformed", band.name));
            }
        }
        Ok(())
    }

    /// The terms at `frames` (forward kinematics of `values`).
    pub fn terms(&self, skeleton: &Skeleton, frames: &Frames, values: &[f64]) -> ComfortTerms {
        self.evaluate(skeleton, frames, values, None)
    }

    /// The terms, and the gradient of the weighted total with respect to every DOF in
    /// `gradient` (length `skeleton.dof_count()`).
    pub fn gradient(
        &self,
        skeleton: &Skeleton,
        frames: &Frames,
        values: &[f64],
        gradient: &mut [f64],
    ) -> ComfortTerms {
        gradient.fill(0.0);
        self.evaluate(skeleton, frames, values, Some(gradient))
    }

    fn evaluate(
        &self,
        skeleton: &Skeleton,
        frames: &Frames,
        values: &[f64],
        mut gradient: Option<&mut [f64]>,
    ) -> ComfortTerms {
        let effort = if self.effort_weight > 0.0 {
            self.effort(skeleton, frames, values, gradient.as_deref_mut())
        } else {
            0.0
        };
        let range = if self.range_weight > 0.0 {
            self.range(skeleton, values, gradient.as_deref_mut())
        } else {
            0.0
        };
        let bands = if self.band_weight > 0.0 {
            self.bands(skeleton, frames, gradient)
        } else {
            0.0
        };
        ComfortTerms {
            effort,
            range,
            bands,
            total: self.effort_weight * effort
                + self.range_weight * range
                + self.band_weight * bands,
        }
    }

    /// `sum_d (tau_d / S_d)^2`, and `effort_weight` times its gradient added to `gradient`.
    ///
    /// With `r_j = m_j - M_j p_j`, `tau_j = r_j x g` and `tau_d = tau_j . e_d` (`e_d` the
    /// joint-frame axis of DOF d in the world), a rotation DOF `i` of joint `a` with world axis
    /// `w_i` moves:
    /// - every joint `j` below `a` rigidly: `d r_j = w_i x r_j`, `d e_d = w_i x e_d`;
    /// - the joints `j` at or above `a`: `d r_j = w_i x (m_a - M_a o_a)` (`o_a = p_a`), and
    ///   `d e_d = w_i x e_d` for `j = a` only.
    ///
    /// With `G_j = dE/d tau_j` and the identity `G . ((w x r) x g) = w . (g (G . r) - G (r . g))`,
    /// every term is `w_i` dotted with a vector summed over the subtree below `a` or the chain
    /// above it: O(N) in all.
    fn effort(
        &self,
        skeleton: &Skeleton,
        frames: &Frames,
        values: &[f64],
        mut gradient: Option<&mut [f64]>,
    ) -> f64 {
        let joints = skeleton.joints();
        let kinds = skeleton.dof_kinds();
        let nj = joints.len();
        let w = self.effort_weight;
        let mut cost = 0.0;
        // Per joint (with a gradient only): dE/d tau_j (G), the axis term
        // sum_d e_d x (dE/d e_d), r_j, and the sums down (chain) and up (below) the tree.
        let per = if gradient.is_some() { nj } else { 0 };
        let mut buffer = vec![DVec3::ZERO; 5 * per];
        let (g_tau, rest) = buffer.split_at_mut(per);
        let (axis_term, rest) = rest.split_at_mut(per);
        let (r, rest) = rest.split_at_mut(per);
        let (chain_g, below) = rest.split_at_mut(per);
        for (j, joint) in joints.iter().enumerate() {
            let rj = frames.subtree_moment[j] - frames.subtree_mass[j] * frames.joint_position[j];
            let tau = rj.cross(GRAVITY);
            if let Some(slot) = r.get_mut(j) {
                *slot = rj;
            }
            for d in joint.dof_range() {
                let Some(Some(strength)) = self.strength.get(d) else {
                    continue;
                };
                if !kinds[d].is_rotation() {
                    continue;
                }
                let e = frames.world_from_joint_rotation[j].col(kinds[d].axis_index());
                let t = tau.dot(e);
                let (s, slope) = strength
                    .holding(t)
                    .at(values.get(d).copied().unwrap_or(0.0));
                if !(s > 0.0 && s.is_finite()) {
                    continue;
                }
                let share = t / s;
                cost += share * share;
                let Some(gradient) = gradient.as_deref_mut() else {
                    continue;
                };
                // Through the strength's angle curve.
                if slope != 0.0 {
                    gradient[d] += w * (-2.0 * share * share / s * slope);
                }
                // d(share^2) = 2 share / s (d tau . e + tau . d e).
                let k = 2.0 * share / s;
                g_tau[j] += k * e;
                axis_term[j] += e.cross(k * tau);
            }
            // Down the tree (parents come first): the sum of G over the chain from the root to
            // the joint (inclusive).
            if gradient.is_some() {
                chain_g[j] = g_tau[j] + joint.parent.map_or(DVec3::ZERO, |p| chain_g[p]);
            }
        }
        let Some(gradient) = gradient else {
            return cost;
        };
        // Up the tree (children come first): the sum over the strict subtree of the
        // rigid-motion vectors U_j = g (G_j . r_j) - G_j (r_j . g) + axis_term_j.
        for j in (0..nj).rev() {
            if let Some(p) = joints[j].parent {
                let own =
                    GRAVITY * g_tau[j].dot(r[j]) - g_tau[j] * r[j].dot(GRAVITY) + axis_term[j];
                let carried = below[j] + own;
                below[p] += carried;
            }
        }
        for (a, joint) in joints.iter().enumerate() {
            // Joints at or above `a`: their torque changes with the subtree of `a` moved.
            let (q, chain) = (r[a], chain_g[a]);
            let above = GRAVITY * chain.dot(q) - chain * q.dot(GRAVITY);
            let v = above + below[a] + axis_term[a];
            for d in joint.dof_range() {
                if kinds[d].is_rotation() {
                    gradient[d] += w * frames.dof_axis[d].dot(v);
                }
            }
        }
        cost
    }

    /// Marler et al. (2005)'s joint-range discomfort over the rotation DOF with finite limits
    /// (both walls), and `range_weight` times its gradient added to `gradient`.
    fn range(&self, skeleton: &Skeleton, values: &[f64], mut gradient: Option<&mut [f64]>) -> f64 {
        let (lo, hi) = (skeleton.lower_limits(), skeleton.upper_limits());
        let mut cost = 0.0;
        for (d, kind) in skeleton.dof_kinds().iter().enumerate() {
            let span = hi[d] - lo[d];
            if !kind.is_rotation() || !span.is_finite() || span <= 0.0 {
                continue;
            }
            let q = values.get(d).copied().unwrap_or(0.0);
            // Away from a wall its penalty is 0 (see `range_wall`): only the walls near are
            // weighed, and the middle of the range costs no division.
            let (to_upper, to_lower) = (hi[d] - q, q - lo[d]);
            let near = RANGE_WALL_DEPTH * span;
            if to_upper > near && to_lower > near {
                continue;
            }
            let per_span = 1.0 / span;
            let mut slope = 0.0;
            if to_upper <= near {
                let (upper, d_upper) = range_wall(to_upper * per_span);
                cost += upper;
                slope -= d_upper;
            }
            if to_lower <= near {
                let (lower, d_lower) = range_wall(to_lower * per_span);
                cost += lower;
                slope += d_lower;
            }
            if let Some(g) = gradient.as_deref_mut() {
                g[d] += self.range_weight * slope * per_span;
            }
        }
        cost
    }

    /// The smooth band scores, and `band_weight` times their gradient added to `gradient`.
    ///
    /// For unit `u` (the segment axis) and `v` (the reference) at angle `phi` with the unit
    /// normal `n = u x v / |u x v|`, a rotation DOF with world axis `w` moves the angle by
    /// `-w . n` when it carries `u`, by `+w . n` when it carries `v` (both: no change).
    fn bands(&self, skeleton: &Skeleton, frames: &Frames, mut gradient: Option<&mut [f64]>) -> f64 {
        let mut cost = 0.0;
        let kinds = skeleton.dof_kinds();
        for band in &self.bands {
            let Some(rotation) = frames.world_from_joint_rotation.get(band.joint) else {
                continue;
            };
            let u = (*rotation * band.axis).normalize_or_zero();
            let (v, reference_joint) = match band.reference {
                AngleReference::World(v) => (v.normalize_or_zero(), None),
                AngleReference::Segment { joint, axis } => {
                    match frames.world_from_joint_rotation.get(joint) {
                        Some(r) => ((*r * axis).normalize_or_zero(), Some(joint)),
                        None => continue,
                    }
                }
            };
            let cross = u.cross(v);
            let phi = cross.length().atan2(u.dot(v));
            let width = band.width.max(1e-6);
            let mut slope = 0.0;
            for &(edge, step) in &band.edges {
                let x = (phi - edge) / width;
                let edge = BandEdge::at(x);
                cost += step * edge.step;
                slope += step * edge.slope / width;
                if band.ramp > 0.0 {
                    // The costly side: above a rising edge, below a falling one.
                    let (soft, dsoft) = if step >= 0.0 {
                        edge.softplus()
                    } else {
                        edge.softplus_below()
                    };
                    let side = step.signum();
                    cost += band.ramp * step.abs() * soft;
                    slope += band.ramp * step.abs() * dsoft * side / width;
                }
            }
            let Some(g) = gradient.as_deref_mut() else {
                continue;
            };
            let sin = cross.length();
            if sin < 1e-9 || slope == 0.0 {
                continue;
            }
            let n = cross / sin;
            let k = self.band_weight * slope;
            // The DOF above the segment turn `u`, those above the reference turn `v`; those
            // above both (from their lowest common ancestor up) turn the two together.
            let common =
                reference_joint.and_then(|b| lowest_common_ancestor(skeleton, band.joint, b));
            let mut turn = |from: Option<usize>, sign: f64| {
                let mut j = from;
                while let Some(i) = j.filter(|&i| Some(i) != common) {
                    for d in skeleton.joints()[i].dof_range() {
                        if kinds[d].is_rotation() {
                            g[d] += sign * k * frames.dof_axis[d].dot(n);
                        }
                    }
                    j = skeleton.joints()[i].parent;
                }
            };
            turn(Some(band.joint), -1.0);
            turn(reference_joint, 1.0);
        }
        cost
    }
}

/// The deepest joint that is `a` or an ancestor of `a` and also `b` or an ancestor of `b`.
/// Every parent comes before its children ([`Skeleton`]): the later of the two is never an
/// ancestor of the other, so it moves up until they meet.
fn lowest_common_ancestor(skeleton: &Skeleton, a: usize, b: usize) -> Option<usize> {
    let parent = |j: usize| skeleton.joints().get(j).and_then(|jt| jt.parent);
    let (mut a, mut b) = (a, b);
    while a != b {
        if a > b {
            a = parent(a)?;
        } else {
            b = parent(b)?;
        }
    }
    Some(a)
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

    use super::{RANGE_WALL_DEPTH, range_wall};

    /// Marler et al.'s wall as written, through the C library's sine, cosine and power.
    fn marler(x: f64) -> (f64, f64) {
        let y = 5.0 * x + 1.571;
        if y <= std::f64::consts::FRAC_PI_2 {
            return (1.0, 0.0);
        }
        let base = 0.5 * y.sin() + 0.5;
        (base.powi(100), 100.0 * base.powi(99) * 0.5 * 5.0 * y.cos())
    }

    #[test]
    fn the_range_wall_is_marlers_formula() {
        for i in 0..=2500 {
            let x = -0.001 + f64::from(i) * 1e-4;
            let (value, slope) = range_wall(x);
            let (expected, expected_slope) = if x > RANGE_WALL_DEPTH {
                // Beyond the depth the formula is below 1e-16 and taken as 0.
                let (v, d) = marler(x);
                assert!(v < 1e-16 && d.abs() < 1e-13, "x {x}: {v} {d}");
                (0.0, 0.0)
            } else {
                marler(x)
            };
            assert!(
                (value - expected).abs() <= 1e-13 * expected.max(1e-3),
                "x {x}: {value} against {expected}"
            );
            assert!(
                (slope - expected_slope).abs() <= 1e-12 * expected_slope.abs().max(1e-3),
                "x {x}: slope {slope} against {expected_slope}"
            );
        }
    }
}
