//! Closed-form IK of a limb ([TOL 96] Tolani & Badler, [KOR 86] Korein,
//! IKAN): an upper joint with 3 rotational DOF (shoulder, hip), a middle hinge (elbow, knee)
//! and an end joint (wrist, ankle). The goal position of the end joint fixes 3 of the 4 DOF;
//! the **swivel angle** of the middle joint around the upper-end axis fixes the fourth. An
//! optional goal orientation fixes the end joint's rotation (as far as its DOF allow).
//!
//! # Geometry taken from the skeleton
//! Nothing assumes a straight rest pose or a hinge axis perpendicular to the segments. With `u`
//! the middle joint's rest offset (upper frame), `w` the end joint's rest offset (middle frame)
//! and `a` the hinge axis (the middle joint's rotational DOF), the end joint sits at
//! `v(theta) = u + exp(theta a) w` in the upper frame, and
//! `|v|^2 = K + 2 rho cos(theta - theta_ext)` (the law of cosines, generalised): `theta_ext` is
//! the fully extended hinge value. The hinge value for a distance `d` is
//! `theta_ext + s * acos((d^2 - K) / (2 rho))`, `s` the flexion side (a fixed branch: the limb
//! never flips from one side of full extension to the other). The hinge limits restrict the
//! branch and therefore the reachable distances `[reach_min, reach_max]`.
//!
//! # The swivel angle
//! Measured in the upper joint's parent frame (the torso), around the unit direction `n` from
//! the upper joint to the end joint: the angle of the middle joint's offset from that axis,
//! counted right-handed about `n` from a reference direction `r(n)`. `r(n)` is a fixed
//! direction `r0` (perpendicular to the pole `p`) carried along by the shortest rotation from
//! `p` to `n`; by default `p` is the limb's rest direction and `r0` the side its middle joint
//! moves to when it flexes, so swivel 0 is the natural, rest-like bend. `r(n)` is continuous
//! everywhere except at `n = -p` (the limb pointing opposite to its rest direction), where a
//! fixed perpendicular is used. When the middle joint lies on the axis (a straight limb), the
//! bend side is read from the hinge axis instead, so the swivel stays defined.
//!
//! # Joint limits
//! For one goal the hinge value is fixed and the upper (and end) rotations are functions of the
//! swivel angle only. [`Limb::swivel_intervals`] finds the swivel angles for which every limb
//! DOF is within its limits: a dense scan (360 samples), every sign change of the limit margin
//! refined by bisection, and every near-zero local extremum of the margin between samples
//! refined by golden-section search (so intervals narrower than the sampling step are found
//! too: the margin changes at most about pi/2 per radian of swivel, except across the
//! rotation-vector branch cut at angle pi).
//!
//! With a goal orientation the end joint counts with the rotation of its DOF nearest to the
//! goal. When that leaves the end joint's limits at every swivel angle,
//! [`Limb::solve_within_limits`] gives the end joint the nearest rotation *within* its limits
//! and picks the swivel angle for the other joints' limits alone.

use std::f64::consts::{PI, TAU};

use glam::{DMat3, DQuat, DVec3};

use crate::joint_rotation::{nearest_rotation_vector, rotation_vector};
use crate::{Frames, IkError, Posture, Skeleton};

/// Samples of the swivel circle scanned by [`Limb::swivel_intervals`].
const SWIVEL_SAMPLES: usize = 360;
/// Below this fraction of the upper segment length the middle joint counts as on the axis.
const ON_AXIS: f64 = 1e-9;
/// Largest rounding violation of a limit that the limit-aware solve snaps back (rad).
const LIMIT_SNAP: f64 = 1e-9;

/// Where the limb hangs: its upper joint's parent frame and the upper joint's centre, in the
/// world. Read it from forward kinematics with [`Limb::base`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LimbBase {
    /// `world_from_parent` rotation of the upper joint's parent (identity for a root).
    pub world_from_parent: DQuat,
    /// World position of the upper joint centre (m).
    pub upper_position: DVec3,
}

impl Default for LimbBase {
    fn default() -> Self {
        Self {
            world_from_parent: DQuat::IDENTITY,
            upper_position: DVec3::ZERO,
        }
    }
}

/// What the limb should reach.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LimbGoal {
    /// World position of the end joint centre (wrist, ankle), m.
    pub position: DVec3,
    /// Optional `world_from_joint` rotation of the end joint.
    pub orientation: Option<DQuat>,
}

impl LimbGoal {
    /// A position goal.
    pub fn position(position: DVec3) -> Self {
        Self {
            position,
            orientation: None,
        }
    }
}

/// The closed-form result, ready for [`Limb::apply`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LimbSolution {
    /// Rotation vector of the upper joint (its rx, ry, rz values), radians.
    pub upper_rotation: DVec3,
    /// Value of the middle joint's hinge DOF (its other rotational DOF are set to 0), radians.
    pub hinge_angle: f64,
    /// Rotation vector of the end joint (when an orientation was asked), radians: the rotation
    /// of its rotational DOF nearest to the goal orientation ([`nearest_rotation_vector`]).
    pub end_rotation: Option<DVec3>,
    /// The swivel angle of the solution, radians in (-pi, pi].
    pub swivel_angle: f64,
    /// World position the end joint reaches (the goal, or the nearest reachable point).
    pub end_position: DVec3,
    /// Whether the goal position was within reach (otherwise `end_position` is the nearest
    /// reachable point on the ray from the upper joint to the goal: fully extended when too
    /// far, fully folded when too close).
    pub reached: bool,
    /// Whether every DOF of the limb is within its limits.
    pub within_limits: bool,
}

/// An interval of feasible swivel angles: `start` in [-pi, pi], `start < end <= start + 2 pi`
/// (`end > pi` when it wraps around).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SwivelInterval {
    /// Lower end (radians).
    pub start: f64,
    /// Upper end (radians).
    pub end: f64,
}

impl SwivelInterval {
    /// Whether `swivel_angle` (any multiple of 2 pi apart) lies in the interval (ends
    /// included, up to 1e-12 rad of rounding).
    pub fn contains(&self, swivel_angle: f64) -> bool {
        const EPS: f64 = 1e-12;
        if self.end - self.start >= TAU - EPS {
            return true;
        }
        let offset = (swivel_angle - self.start).rem_euclid(TAU);
        offset <= self.end - self.start + EPS || offset >= TAU - EPS
    }

    /// Length in radians.
    pub fn length(&self) -> f64 {
        self.end - self.start
    }
}

/// A 3-joint limb of a skeleton with everything the closed form needs precomputed.
#[derive(Debug, Clone, PartialEq)]
pub struct Limb {
    joints: [usize; 3],
    upper_dofs: [usize; 3],
    upper_lower: DVec3,
    upper_upper: DVec3,
    hinge_dof: usize,
    /// The middle joint's other rotational DOF (set to 0 by the closed form).
    middle_other_dofs: Vec<usize>,
    /// Limit margin of those DOF at 0 (constant).
    middle_other_margin: f64,
    end_dofs: [Option<usize>; 3],
    end_lower: DVec3,
    end_upper: DVec3,
    hinge_axis: DVec3,
    upper_to_middle: DVec3,
    middle_to_end: DVec3,
    w_parallel: DVec3,
    w_perpendicular: DVec3,
    axis_cross_w: DVec3,
    upper_length: f64,
    k: f64,
    two_rho: f64,
    theta_extended: f64,
    flexion_sign: f64,
    alpha_min: f64,
    alpha_max: f64,
    reach_min: f64,
    reach_floor: f64,
    reach_max: f64,
    bend_sign: f64,
    pole: DVec3,
    zero_reference: DVec3,
}

fn bad(reason: impl Into<String>) -> IkError {
    IkError::BadLimb(reason.into())
}

/// `x` wrapped into (-pi, pi].
fn wrap_angle(x: f64) -> f64 {
    let y = (x + PI).rem_euclid(TAU) - PI;
    if y <= -PI { y + TAU } else { y }
}

fn margin(v: f64, lo: f64, hi: f64) -> f64 {
    (v - lo).min(hi - v)
}

fn rotation_margin(r: DVec3, lo: DVec3, hi: DVec3) -> f64 {
    margin(r.x, lo.x, hi.x)
        .min(margin(r.y, lo.y, hi.y))
        .min(margin(r.z, lo.z, hi.z))
}

/// Per-goal quantities shared by the swivel scan and the final solve.
#[derive(Debug, Clone, Copy)]
struct Prepared {
    base: LimbBase,
    orientation: Option<DQuat>,
    /// Unit upper-to-end direction, parent frame.
    n: DVec3,
    /// Swivel reference direction `r(n)`.
    r: DVec3,
    hinge_angle: f64,
    /// `[nv, bv, nv x bv]^T` in the upper frame.
    upper_frame_t: DMat3,
    /// Upper-to-end distance actually reached.
    reach: f64,
    reached: bool,
}

/// Which rotations the end joint may take: the nearest to the goal orientation among all of
/// its DOF's rotations, or among those within its limits.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum End {
    Free,
    WithinLimits,
}

impl Limb {
    /// The limb `upper` (3 rotational DOF) - `middle` (child of `upper`, at least one
    /// rotational DOF; with several, the one that changes the limb's length most is the hinge
    /// and the others are set to 0) - `end` (child of `middle`).
    pub fn new(
        skeleton: &Skeleton,
        upper: usize,
        middle: usize,
        end: usize,
    ) -> Result<Self, IkError> {
        let joints = skeleton.joints();
        let count = joints.len();
        if upper >= count || middle >= count || end >= count {
            return Err(bad("joint index out of range"));
        }
        let (ju, jm, je) = (&joints[upper], &joints[middle], &joints[end]);
        if jm.parent != Some(upper) || je.parent != Some(middle) {
            return Err(bad(format!(
                "`{}`, `{}`, `{}` are not a parent-child chain",
                ju.name, jm.name, je.name
            )));
        }
        let [Some(ux), Some(uy), Some(uz)] = ju.rotation_dof else {
            return Err(bad(format!(
                "the upper joint `{}` needs the three rotational DOF rx, ry, rz",
                ju.name
            )));
        };
        let (lo, hi) = (skeleton.lower_limits(), skeleton.upper_limits());
        let u = jm.offset;
        let w = je.offset;
        if u.length() < 1e-9 || w.length() < 1e-9 {
            return Err(bad("a limb segment has zero length"));
        }
        // The hinge: the middle joint's rotational DOF that changes |v| most (largest rho).
        let mut best: Option<(usize, f64)> = None;
        for axis in 0..3 {
            if jm.rotation_dof[axis].is_some() {
                let a = DVec3::AXES[axis];
                let rho = u.dot(w - a * a.dot(w)).hypot(u.dot(a.cross(w)));
                if best.is_none_or(|(_, r)| rho > r) {
                    best = Some((axis, rho));
                }
            }
        }
        let Some((hinge_axis_index, rho)) = best else {
            return Err(bad(format!(
                "the middle joint `{}` has no rotational DOF",
                jm.name
            )));
        };
        if rho < 1e-9 * u.length() * w.length() {
            return Err(bad(format!(
                "the hinge of `{}` cannot change the limb's length",
                jm.name
            )));
        }
        let Some(hinge_dof) = jm.rotation_dof[hinge_axis_index] else {
            return Err(bad("no hinge DOF"));
        };
        let middle_other_dofs: Vec<usize> = jm
            .rotation_dof
            .iter()
            .flatten()
            .copied()
            .filter(|&d| d != hinge_dof)
            .collect();
        let middle_other_margin = middle_other_dofs
            .iter()
            .map(|&d| margin(0.0, lo[d], hi[d]))
            .fold(f64::INFINITY, f64::min);
        let a = DVec3::AXES[hinge_axis_index];
        let w_parallel = a * a.dot(w);
        let w_perpendicular = w - w_parallel;
        let axis_cross_w = a.cross(w);
        let big_a = u.dot(w_perpendicular);
        let big_b = u.dot(axis_cross_w);
        let theta0 = big_b.atan2(big_a);
        let k = u.length_squared() + w.length_squared() + 2.0 * u.dot(w_parallel);
        // Branch and 2 pi wrap with the widest range of flexion inside the hinge limits.
        let (hlo, hhi) = (lo[hinge_dof], hi[hinge_dof]);
        let mut choice: Option<(f64, f64, f64, f64)> = None; // (theta_ext, s, alpha_lo, alpha_hi)
        for wrap in [0.0, -TAU, TAU] {
            for s in [1.0, -1.0] {
                let theta_ext = theta0 + wrap;
                let (a_lo, a_hi) = if s > 0.0 {
                    (hlo - theta_ext, hhi - theta_ext)
                } else {
                    (theta_ext - hhi, theta_ext - hlo)
                };
                let (a_lo, a_hi) = (a_lo.max(0.0), a_hi.min(PI));
                if a_lo <= a_hi && choice.is_none_or(|c| a_hi - a_lo > c.3 - c.2) {
                    choice = Some((theta_ext, s, a_lo, a_hi));
                }
            }
        }
        let Some((theta_extended, flexion_sign, alpha_min, alpha_max)) = choice else {
            return Err(bad(format!(
                "the limits of `{}` leave no hinge value",
                jm.name
            )));
        };
        let end_dofs = je.rotation_dof;
        let mut end_lower = DVec3::NEG_INFINITY;
        let mut end_upper = DVec3::INFINITY;
        for axis in 0..3 {
            if let Some(d) = end_dofs[axis] {
                end_lower[axis] = lo[d];
                end_upper[axis] = hi[d];
            }
        }
        let reach_at = |alpha: f64| (k + 2.0 * rho * alpha.cos()).max(0.0).sqrt();
        let reach_max = reach_at(alpha_min);
        let reach_min = reach_at(alpha_max);
        let mut limb = Self {
            joints: [upper, middle, end],
            upper_dofs: [ux, uy, uz],
            upper_lower: DVec3::new(lo[ux], lo[uy], lo[uz]),
            upper_upper: DVec3::new(hi[ux], hi[uy], hi[uz]),
            hinge_dof,
            middle_other_dofs,
            middle_other_margin,
            end_dofs,
            end_lower,
            end_upper,
            hinge_axis: a,
            upper_to_middle: u,
            middle_to_end: w,
            w_parallel,
            w_perpendicular,
            axis_cross_w,
            upper_length: u.length(),
            k,
            two_rho: 2.0 * rho,
            theta_extended,
            flexion_sign,
            alpha_min,
            alpha_max,
            reach_min,
            reach_floor: reach_min.max(1e-6 * (u.length() + w.length())),
            reach_max,
            bend_sign: 1.0,
            pole: DVec3::NEG_Y,
            zero_reference: DVec3::Z,
        };
        // Bend side relative to the hinge axis, from a clearly bent configuration.
        let bent = limb.end_offset(
            theta_extended + flexion_sign * (0.5 * (alpha_min + alpha_max)).max(alpha_min),
        );
        let dir = bent.normalize_or_zero();
        let perp = u - dir * u.dot(dir);
        let side = perp.dot(bent.cross(a));
        limb.bend_sign = if side < 0.0 { -1.0 } else { 1.0 };
        // Default swivel reference: the rest direction as pole, the bend side as zero.
        let rest = u + w;
        let pole = if rest.length() > 1e-9 { rest } else { u };
        let zero = limb.bend_sign * pole.cross(a);
        limb.set_swivel_reference(pole, zero);
        Ok(limb)
    }

    /// The limb from three joint names (upper, middle, end).
    pub fn from_names(skeleton: &Skeleton, names: [&str; 3]) -> Result<Self, IkError> {
        Self::new(
            skeleton,
            skeleton.require_joint(names[0])?,
            skeleton.require_joint(names[1])?,
            skeleton.require_joint(names[2])?,
        )
    }

    /// Changes the swivel reference: `pole` (upper joint's parent frame) is the limb direction
    /// at which `zero` (projected perpendicular to `pole`) is the swivel-0 side; the swivel is
    /// discontinuous only where the limb points along `-pole`. Degenerate inputs are ignored.
    pub fn set_swivel_reference(&mut self, pole: DVec3, zero: DVec3) {
        let p = pole.normalize_or_zero();
        if p == DVec3::ZERO || !p.is_finite() {
            return;
        }
        let z = (zero - p * zero.dot(p)).normalize_or_zero();
        self.pole = p;
        self.zero_reference = if z == DVec3::ZERO || !z.is_finite() {
            p.any_orthonormal_vector()
        } else {
            z
        };
    }

    /// Joint indices (upper, middle, end).
    pub fn joints(&self) -> [usize; 3] {
        self.joints
    }

    /// Posture index of the middle joint's hinge DOF.
    pub fn hinge_dof(&self) -> usize {
        self.hinge_dof
    }

    /// The fully extended hinge value (without limits) and the flexion side (+1 or -1): the
    /// closed form's hinge values are `theta_extended + side * alpha`, `alpha >= 0`.
    pub fn flexion(&self) -> (f64, f64) {
        (self.theta_extended, self.flexion_sign)
    }

    /// Reachable upper-to-end distances within the hinge limits (m).
    pub fn reach(&self) -> (f64, f64) {
        (self.reach_min, self.reach_max)
    }

    /// The limb's base in a posture's forward kinematics.
    pub fn base(&self, skeleton: &Skeleton, frames: &Frames) -> LimbBase {
        let upper = self.joints[0];
        let world_from_parent = skeleton.joints()[upper]
            .parent
            .and_then(|p| frames.world_from_joint_rotation.get(p))
            .map_or(DQuat::IDENTITY, |m| DQuat::from_mat3(m).normalize());
        LimbBase {
            world_from_parent,
            upper_position: frames
                .joint_position
                .get(upper)
                .copied()
                .unwrap_or(DVec3::ZERO),
        }
    }

    /// End joint offset from the upper joint (upper frame) for a hinge value.
    fn end_offset(&self, theta: f64) -> DVec3 {
        let (s, c) = theta.sin_cos();
        self.upper_to_middle + self.w_parallel + self.w_perpendicular * c + self.axis_cross_w * s
    }

    /// Swivel reference `r(n)` for a unit direction `n` (parent frame).
    fn reference(&self, n: DVec3) -> DVec3 {
        let (p, r0) = (self.pole, self.zero_reference);
        let c = 1.0 + p.dot(n);
        let r = if c > 1e-9 {
            r0 - (p + n) * (n.dot(r0) / c)
        } else {
            r0
        };
        let r = r - n * r.dot(n);
        let len = r.length();
        if len > 1e-9 {
            r / len
        } else {
            n.any_orthonormal_vector()
        }
    }

    /// Unit side of the middle joint relative to the unit limb direction `dir`; `middle` is the
    /// middle joint's offset and `hinge` the hinge axis, in the same frame.
    fn bend_direction(&self, dir: DVec3, middle: DVec3, hinge: DVec3) -> DVec3 {
        let perp = middle - dir * middle.dot(dir);
        let len = perp.length();
        if len > ON_AXIS * self.upper_length {
            return perp / len;
        }
        let side = (dir.cross(hinge) * self.bend_sign).normalize_or_zero();
        if side == DVec3::ZERO || !side.is_finite() {
            dir.any_orthonormal_vector()
        } else {
            side
        }
    }

    /// The swivel angle of the limb in a posture (radians in (-pi, pi]).
    pub fn swivel_angle(&self, skeleton: &Skeleton, posture: &Posture) -> f64 {
        let upper = DQuat::from_scaled_axis(posture.rotation_vector(skeleton, self.joints[0]));
        let middle = DQuat::from_scaled_axis(posture.rotation_vector(skeleton, self.joints[1]));
        let elbow = upper * self.upper_to_middle;
        let end = upper * (self.upper_to_middle + middle * self.middle_to_end);
        let n = end.normalize_or_zero();
        let n = if n == DVec3::ZERO || !n.is_finite() {
            self.pole
        } else {
            n
        };
        let bend = self.bend_direction(n, elbow, upper * self.hinge_axis);
        let r = self.reference(n);
        bend.dot(n.cross(r)).atan2(bend.dot(r))
    }

    fn prepare(&self, base: LimbBase, goal: &LimbGoal) -> Prepared {
        let g = base.world_from_parent.inverse() * (goal.position - base.upper_position);
        let dist = g.length();
        let n = if dist > 1e-12 * self.upper_length && g.is_finite() {
            g / dist
        } else {
            self.pole
        };
        let tol = 1e-12 * (self.reach_max + 1.0);
        let reached = dist >= self.reach_min - tol && dist <= self.reach_max + tol;
        let reach = if dist.is_finite() {
            dist.clamp(self.reach_floor, self.reach_max)
        } else {
            self.reach_max
        };
        let cos_alpha = ((reach * reach - self.k) / self.two_rho).clamp(-1.0, 1.0);
        let alpha = cos_alpha.acos().clamp(self.alpha_min, self.alpha_max);
        let hinge_angle = self.theta_extended + self.flexion_sign * alpha;
        let v = self.end_offset(hinge_angle);
        let reach = v.length();
        let nv = v / reach;
        let bv = self.bend_direction(nv, self.upper_to_middle, self.hinge_axis);
        let upper_frame_t = DMat3::from_cols(nv, bv, nv.cross(bv)).transpose();
        Prepared {
            base,
            orientation: goal.orientation,
            n,
            r: self.reference(n),
            hinge_angle,
            upper_frame_t,
            reach,
            reached,
        }
    }

    /// Upper joint rotation (parent_from_upper) for a swivel angle.
    fn upper_rotation(&self, prep: &Prepared, swivel_angle: f64) -> DQuat {
        let (s, c) = swivel_angle.sin_cos();
        let n = prep.n;
        let bg = prep.r * c + n.cross(prep.r) * s;
        let m = DMat3::from_cols(n, bg, n.cross(bg)) * prep.upper_frame_t;
        DQuat::from_mat3(&m).normalize()
    }

    fn hinge_rotation(&self, prep: &Prepared) -> DQuat {
        DQuat::from_axis_angle(self.hinge_axis, prep.hinge_angle)
    }

    /// End joint rotation vector for an upper rotation: the rotation of the end joint's DOF
    /// nearest to the goal orientation (see [`nearest_rotation_vector`]), among all of them
    /// (`End::Free`) or those within the end joint's limits (`End::WithinLimits`).
    fn end_rotation(&self, prep: &Prepared, upper: DQuat, end: End) -> Option<DVec3> {
        prep.orientation.map(|target| {
            let world_from_middle = prep.base.world_from_parent * upper * self.hinge_rotation(prep);
            let local = world_from_middle.inverse() * target.normalize();
            let dofs = self.end_dofs.map(|d| d.is_some());
            match end {
                End::Free => {
                    nearest_rotation_vector(local, dofs, DVec3::NEG_INFINITY, DVec3::INFINITY)
                }
                End::WithinLimits => {
                    nearest_rotation_vector(local, dofs, self.end_lower, self.end_upper)
                }
            }
        })
    }

    /// Limit margin (radians; >= 0 inside every limit) of the limb for a swivel angle; with
    /// `End::WithinLimits` the end joint (kept within its limits) does not count.
    fn limit_margin(&self, prep: &Prepared, swivel_angle: f64, end: End) -> f64 {
        let q = self.upper_rotation(prep, swivel_angle);
        let mut m = rotation_margin(rotation_vector(q), self.upper_lower, self.upper_upper)
            .min(self.middle_other_margin);
        if end == End::Free
            && let Some(r) = self.end_rotation(prep, q, End::Free)
        {
            m = m.min(rotation_margin(r, self.end_lower, self.end_upper));
        }
        m
    }

    fn finish(&self, prep: &Prepared, swivel_angle: f64, end: End) -> LimbSolution {
        let q = self.upper_rotation(prep, swivel_angle);
        let upper_rotation = rotation_vector(q);
        let end_rotation = self.end_rotation(prep, q, end);
        let mut m = rotation_margin(upper_rotation, self.upper_lower, self.upper_upper)
            .min(self.middle_other_margin);
        if let Some(r) = end_rotation {
            m = m.min(rotation_margin(r, self.end_lower, self.end_upper));
        }
        let end_position =
            prep.base.upper_position + prep.base.world_from_parent * (prep.n * prep.reach);
        LimbSolution {
            upper_rotation,
            hinge_angle: prep.hinge_angle,
            end_rotation,
            swivel_angle: wrap_angle(swivel_angle),
            end_position,
            reached: prep.reached,
            within_limits: m >= -1e-12,
        }
    }

    /// The closed-form solution for a goal and a swivel angle (the upper and end joint limits
    /// are reported in `within_limits`, not enforced; the hinge always is). Never NaN for
    /// finite inputs: an unreachable goal gives the nearest reachable point, a goal at the
    /// upper joint the fully folded limb along the swivel pole.
    pub fn solve(&self, base: LimbBase, goal: &LimbGoal, swivel_angle: f64) -> LimbSolution {
        let swivel_angle = if swivel_angle.is_finite() {
            swivel_angle
        } else {
            0.0
        };
        let prep = self.prepare(base, goal);
        self.finish(&prep, swivel_angle, End::Free)
    }

    /// Like [`Limb::solve`] with the feasible swivel angle nearest to `preferred_swivel`.
    /// With a goal orientation whose nearest end-joint rotation leaves the end joint's limits
    /// at every swivel angle, the end joint takes the rotation within its limits nearest to
    /// the goal and the swivel angle is the one nearest to `preferred_swivel` that keeps the
    /// other joints within theirs. When no swivel angle satisfies the limits, the one that
    /// violates them least (`within_limits` is then false).
    pub fn solve_within_limits(
        &self,
        base: LimbBase,
        goal: &LimbGoal,
        preferred_swivel: f64,
    ) -> LimbSolution {
        let preferred = if preferred_swivel.is_finite() {
            preferred_swivel
        } else {
            0.0
        };
        let prep = self.prepare(base, goal);
        let (intervals, least_violating) = self.scan(&prep, End::Free);
        let (swivel, end, feasible) = match nearest_swivel(&intervals, preferred) {
            Some(swivel) => (swivel, End::Free, true),
            None if prep.orientation.is_some() => {
                // The end joint's limits alone may rule out every swivel: keep it within them.
                let (intervals, least_violating) = self.scan(&prep, End::WithinLimits);
                match nearest_swivel(&intervals, preferred) {
                    Some(swivel) => (swivel, End::WithinLimits, true),
                    None => (least_violating, End::WithinLimits, false),
                }
            }
            None => (least_violating, End::Free, false),
        };
        let mut sol = self.finish(&prep, swivel, end);
        if feasible {
            // The interval ends are feasible up to rounding; snap the last 1e-16 rad in.
            let snap = |v: &mut DVec3, lo: DVec3, hi: DVec3| {
                for axis in 0..3 {
                    if v[axis] < lo[axis] && v[axis] > lo[axis] - LIMIT_SNAP {
                        v[axis] = lo[axis];
                    }
                    if v[axis] > hi[axis] && v[axis] < hi[axis] + LIMIT_SNAP {
                        v[axis] = hi[axis];
                    }
                }
            };
            snap(&mut sol.upper_rotation, self.upper_lower, self.upper_upper);
            if let Some(r) = sol.end_rotation.as_mut() {
                snap(r, self.end_lower, self.end_upper);
            }
            sol.within_limits = true;
        }
        sol
    }

    /// The swivel angles for which every DOF of the limb stays within its limits, for a goal
    /// (sorted by `start`; empty when none; one interval of length 2 pi when all are).
    pub fn swivel_intervals(&self, base: LimbBase, goal: &LimbGoal) -> Vec<SwivelInterval> {
        let prep = self.prepare(base, goal);
        self.scan(&prep, End::Free).0
    }

    /// Scan + refinement; also returns the least-violating sample.
    fn scan(&self, prep: &Prepared, end: End) -> (Vec<SwivelInterval>, f64) {
        let h = TAU / SWIVEL_SAMPLES as f64;
        let angle = |i: usize| -PI + i as f64 * h;
        let m: Vec<f64> = (0..SWIVEL_SAMPLES)
            .map(|i| self.limit_margin(prep, angle(i), end))
            .collect();
        let mut best = 0;
        for i in 1..SWIVEL_SAMPLES {
            if m[i] > m[best] {
                best = i;
            }
        }
        let least_violating = angle(best);
        if self.middle_other_margin < 0.0 {
            return (Vec::new(), least_violating);
        }
        let feasible = |phi: f64| self.limit_margin(prep, phi, end) >= 0.0;
        // Transition between `a` (feasibility `fa`) and `b`: the feasible end of the bracket.
        let bisect = |mut a: f64, mut b: f64, fa: bool| {
            for _ in 0..60 {
                if b - a < 1e-14 {
                    break;
                }
                let mid = 0.5 * (a + b);
                if feasible(mid) == fa {
                    a = mid;
                } else {
                    b = mid;
                }
            }
            if fa { a } else { b }
        };
        // Golden-section search for a maximum (sign +1) or minimum (-1) of the margin.
        let extremum = |mut a: f64, mut b: f64, sign: f64| {
            let g = 0.5 * (5f64.sqrt() - 1.0);
            let mut x1 = b - g * (b - a);
            let mut x2 = a + g * (b - a);
            let mut f1 = sign * self.limit_margin(prep, x1, end);
            let mut f2 = sign * self.limit_margin(prep, x2, end);
            for _ in 0..80 {
                if b - a < 1e-13 {
                    break;
                }
                if f1 > f2 {
                    b = x2;
                    x2 = x1;
                    f2 = f1;
                    x1 = b - g * (b - a);
                    f1 = sign * self.limit_margin(prep, x1, end);
                } else {
                    a = x1;
                    x1 = x2;
                    f1 = f2;
                    x2 = a + g * (b - a);
                    f2 = sign * self.limit_margin(prep, x2, end);
                }
            }
            let x = 0.5 * (a + b);
            (x, self.limit_margin(prep, x, end))
        };
        // (angle, entering the feasible set)
        let mut transitions: Vec<(f64, bool)> = Vec::new();
        let near = 2.0 * h;
        for i in 0..SWIVEL_SAMPLES {
            let prev = m[(i + SWIVEL_SAMPLES - 1) % SWIVEL_SAMPLES];
            let next = m[(i + 1) % SWIVEL_SAMPLES];
            let here = m[i];
            let (a, b) = (angle(i), angle(i) + h);
            if (here >= 0.0) != (next >= 0.0) {
                transitions.push((bisect(a, b, here >= 0.0), next >= 0.0));
            }
            // A feasible island hidden between infeasible samples.
            if here < 0.0 && prev < 0.0 && next < 0.0 && here > prev && here >= next && here > -near
            {
                let (x, mx) = extremum(a - h, b, 1.0);
                if mx >= 0.0 {
                    transitions.push((bisect(a - h, x, false), true));
                    transitions.push((bisect(x, b, true), false));
                }
            }
            // An infeasible gap hidden between feasible samples.
            if here >= 0.0
                && prev >= 0.0
                && next >= 0.0
                && here < prev
                && here <= next
                && here < near
            {
                let (x, mx) = extremum(a - h, b, -1.0);
                if mx < 0.0 {
                    transitions.push((bisect(a - h, x, true), false));
                    transitions.push((bisect(x, b, false), true));
                }
            }
        }
        transitions.sort_by(|x, y| x.0.total_cmp(&y.0));
        let mut inside = m[0] >= 0.0;
        let mut open = inside.then_some(-PI);
        let mut out: Vec<SwivelInterval> = Vec::new();
        for (t, entering) in transitions {
            if entering && !inside {
                open = Some(t);
                inside = true;
            } else if !entering && inside {
                if let Some(start) = open.take() {
                    out.push(SwivelInterval { start, end: t });
                }
                inside = false;
            }
        }
        if let Some(start) = open {
            match out.first() {
                Some(first) if first.start == -PI && start > -PI => {
                    let end = first.end + TAU;
                    out.remove(0);
                    out.push(SwivelInterval { start, end });
                }
                _ => out.push(SwivelInterval { start, end: PI }),
            }
        }
        out.retain(|iv| iv.end >= iv.start);
        (out, least_violating)
    }

    /// Writes a solution into a posture.
    pub fn apply(&self, solution: &LimbSolution, posture: &mut Posture) {
        self.apply_values(solution, posture.values_mut());
    }

    pub(crate) fn apply_values(&self, solution: &LimbSolution, values: &mut [f64]) {
        if values.len() <= self.upper_dofs.iter().copied().max().unwrap_or(0) {
            return;
        }
        for (axis, &d) in self.upper_dofs.iter().enumerate() {
            values[d] = solution.upper_rotation[axis];
        }
        if let Some(v) = values.get_mut(self.hinge_dof) {
            *v = solution.hinge_angle;
        }
        for &d in &self.middle_other_dofs {
            if let Some(v) = values.get_mut(d) {
                *v = 0.0;
            }
        }
        if let Some(r) = solution.end_rotation {
            for axis in 0..3 {
                if let Some(v) = self.end_dofs[axis].and_then(|d| values.get_mut(d)) {
                    *v = r[axis];
                }
            }
        }
    }
}

/// The swivel angle nearest to `preferred` (circular distance) inside one of `intervals`
/// (`preferred` itself when it is feasible), wrapped into (-pi, pi]; `None` when there are no
/// intervals.
pub fn nearest_swivel(intervals: &[SwivelInterval], preferred: f64) -> Option<f64> {
    if intervals.iter().any(|iv| iv.contains(preferred)) {
        return Some(wrap_angle(preferred));
    }
    let mut best: Option<(f64, f64)> = None;
    for iv in intervals {
        for end in [iv.start, iv.end] {
            let dist = wrap_angle(end - preferred).abs();
            if best.is_none_or(|(_, d)| dist < d) {
                best = Some((end, dist));
            }
        }
    }
    best.map(|(x, _)| wrap_angle(x))
}
