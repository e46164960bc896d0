//! The plain textbook prioritized inverse kinematics, written from the problem format
//! (`docs/problem-format.md`) and the textbook alone: it shares no code with `stance_ik`.
//!
//! It is the tests' **oracle** (its own forward kinematics, task errors and Jacobians judge
//! whether a posture meets every level: [`Problem::level_residuals`]) and the benchmark's
//! **peer** (`stance-textbook`, compared with `stance bench --suite --peer`).
//!
//! The iteration is the recursion of Siciliano & Slotine as the paper writes it (Baerlocher &
//! Boulic): with `P_0 = I` and `dq_0 = 0`, for each level `k` in priority order,
//! `dq_k = dq_{k-1} + (J_k P_{k-1})^+ (e_k - J_k dq_{k-1})` and
//! `P_k = P_{k-1} - (J_k P_{k-1})^+ (J_k P_{k-1})`, the pseudo-inverses by singular value
//! decomposition (one-sided Jacobi on nalgebra's dynamic matrices), damped by a small constant in the step and
//! exact in the projector (singular values under 1e-9 of the norm of `J_k` count as zero);
//! each task's error clamped to the textbook's 0.1 m / 0.3 rad (Buss
//! & Kim); the joint values clamped into their limits after the step. The Jacobians are
//! analytic; the tests check them against central differences of the forward kinematics.

mod balance;
mod read;

use nalgebra::{DMatrix, DVector, Matrix3, Rotation3, Vector3};
use serde_json::Value;

/// What makes a problem file unreadable here.
#[derive(Debug, thiserror::Error)]
pub enum ProblemError {
    /// Not JSON.
    #[error("not JSON: {0}")]
    Json(#[from] serde_json::Error),
    /// A field is missing or of the wrong shape.
    #[error("{0}")]
    Field(String),
}

fn bad(what: impl Into<String>) -> ProblemError {
    ProblemError::Field(what.into())
}

/// A DOF: translation or rotation-vector component along axis 0, 1 or 2.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Dof {
    Translation(usize),
    Rotation(usize),
}

#[derive(Debug, Clone)]
struct Joint {
    name: String,
    parent: Option<usize>,
    offset: Vector3<f64>,
    /// (DOF, its index in the posture).
    dofs: Vec<(Dof, usize)>,
    mass: f64,
    com: Vector3<f64>,
}

/// A task, in world terms.
#[derive(Debug, Clone)]
enum Goal {
    Position {
        joint: usize,
        point: Vector3<f64>,
        axes: [bool; 3],
        target: Vector3<f64>,
    },
    Orientation {
        joint: usize,
        target: Rotation3<f64>,
    },
    Direction {
        joint: usize,
        axis: Vector3<f64>,
        target: Vector3<f64>,
    },
    Gaze {
        joint: usize,
        point: Vector3<f64>,
        axis: Vector3<f64>,
        target: Vector3<f64>,
    },
    Com {
        axes: [bool; 3],
        target: Vector3<f64>,
    },
    /// The centre of mass over the support polygon (an inequality): support points (joint,
    /// point in its frame) and the margin.
    Balance {
        support: Vec<(usize, Vector3<f64>)>,
        margin: f64,
    },
    /// A point of a segment on a world line (unit `direction`).
    Line {
        joint: usize,
        point: Vector3<f64>,
        origin: Vector3<f64>,
        direction: Vector3<f64>,
    },
    /// A point of a segment on a world plane (unit `normal`); with `above`, on or above it
    /// (an inequality).
    Plane {
        joint: usize,
        point: Vector3<f64>,
        origin: Vector3<f64>,
        normal: Vector3<f64>,
        above: bool,
    },
}

/// The component of `v` across the unit `direction`: `(I - u u^T) v`.
fn across(direction: &Vector3<f64>, v: &Vector3<f64>) -> Vector3<f64> {
    v - direction * direction.dot(v)
}

#[derive(Debug, Clone)]
struct Weighted {
    goal: Goal,
    /// `sqrt(weight)`, the rows' scale.
    scale: f64,
}

/// A problem file, read by this crate's own reader.
#[derive(Debug, Clone)]
pub struct Problem {
    joints: Vec<Joint>,
    /// `ancestor[j][a]`: joint `a` is `j` or one of its ancestors.
    ancestor: Vec<Vec<bool>>,
    lower: Vec<f64>,
    upper: Vec<f64>,
    dof_names: Vec<(String, String)>,
    /// Per DOF: its joint.
    owner: Vec<usize>,
    /// Per DOF: a rotation (else a translation).
    rotational: Vec<bool>,
    /// Levels in priority order.
    levels: Vec<Vec<Weighted>>,
    /// The start posture.
    pub start: Vec<f64>,
    /// The file's tolerance on a level's residual (default 1e-6).
    pub tolerance: f64,
}

/// World frames of one posture.
struct Frames {
    rotation: Vec<Matrix3<f64>>,
    position: Vec<Vector3<f64>>,
    /// Per DOF: the world axis of its rotation (angular velocity per unit change) or
    /// translation.
    axis: Vec<Vector3<f64>>,
}

/// How a solve is taken.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Settings {
    /// Iteration budget.
    pub max_iterations: usize,
    /// Damping of the step's pseudo-inverses.
    pub lambda: f64,
    /// Clamp of position and centre-of-mass errors per iteration (m).
    pub max_linear: f64,
    /// Clamp of orientation, direction and gaze errors per iteration (rad).
    pub max_angular: f64,
    /// Iterations without a new best (in priority order) before giving up.
    pub stall_window: usize,
    /// Largest DOF change of a step (rad or m): a longer step is scaled down as a whole
    /// (Buss & Kim clamp joint changes per iteration the same way).
    pub max_dof_step: f64,
}

impl Default for Settings {
    fn default() -> Self {
        Self {
            max_iterations: 200,
            lambda: 0.01,
            max_linear: 0.1,
            max_angular: 0.3,
            stall_window: 40,
            max_dof_step: std::f64::consts::FRAC_PI_4,
        }
    }
}

/// The end of a solve.
#[derive(Debug, Clone, PartialEq)]
pub struct Solution {
    /// The best posture met, in priority order.
    pub posture: Vec<f64>,
    /// Its residual per level.
    pub residuals: Vec<f64>,
    /// Every level within the tolerance.
    pub met_every_level: bool,
    /// Iterations taken.
    pub iterations: usize,
}

/// `exp` of a rotation vector.
fn exp(r: &Vector3<f64>) -> Matrix3<f64> {
    Rotation3::new(*r).into_inner()
}

fn skew(v: &Vector3<f64>) -> Matrix3<f64> {
    Matrix3::new(0.0, -v.z, v.y, v.z, 0.0, -v.x, -v.y, v.x, 0.0)
}

/// The left Jacobian of SO(3): `d exp(r) / dr_i = skew(J_l(r) e_i) exp(r)`.
fn left_jacobian(r: &Vector3<f64>) -> Matrix3<f64> {
    let theta = r.norm();
    let k = skew(r);
    if theta < 1e-6 {
        return Matrix3::identity() + 0.5 * k + (k * k) / 6.0;
    }
    let t2 = theta * theta;
    Matrix3::identity()
        + ((1.0 - theta.cos()) / t2) * k
        + ((theta - theta.sin()) / (t2 * theta)) * (k * k)
}

/// The inverse of the left Jacobian of SO(3) at `phi`.
fn left_jacobian_inverse(phi: &Vector3<f64>) -> Matrix3<f64> {
    let theta = phi.norm();
    let k = skew(phi);
    let c = if theta < 1e-6 {
        1.0 / 12.0
    } else {
        1.0 / (theta * theta) - (1.0 + theta.cos()) / (2.0 * theta * theta.sin())
    };
    Matrix3::identity() - 0.5 * k + c * (k * k)
}

/// The angle of a rotation matrix (rad, in [0, pi]).
fn angle(m: &Matrix3<f64>) -> f64 {
    (((m.trace() - 1.0) / 2.0).clamp(-1.0, 1.0)).acos()
}

fn unit_angle(a: &Vector3<f64>, b: &Vector3<f64>) -> f64 {
    // atan2 keeps precision near 0 and pi.
    a.cross(b).norm().atan2(a.dot(b))
}

impl Problem {
    /// Number of DOF.
    pub fn dof_count(&self) -> usize {
        self.lower.len()
    }

    /// Number of levels.
    pub fn level_count(&self) -> usize {
        self.levels.len()
    }

    /// A posture in the format's form (`{"joint": {"rx": ..}}`; missing DOF at 0).
    pub fn posture_from_json(&self, v: &Value) -> Result<Vec<f64>, ProblemError> {
        let mut out = vec![0.0; self.dof_count()];
        for (i, (joint, dof)) in self.dof_names.iter().enumerate() {
            if let Some(x) = v.get(joint).and_then(|j| j.get(dof)) {
                out[i] = x
                    .as_f64()
                    .ok_or_else(|| bad(format!("posture.{joint}.{dof}: expected a number")))?;
            }
        }
        Ok(out)
    }

    fn frames(&self, q: &[f64]) -> Frames {
        let n = self.joints.len();
        let mut f = Frames {
            rotation: Vec::with_capacity(n),
            position: Vec::with_capacity(n),
            axis: vec![Vector3::zeros(); self.dof_count()],
        };
        for joint in &self.joints {
            let (parent_rotation, parent_position) = match joint.parent {
                Some(p) => (f.rotation[p], f.position[p]),
                None => (Matrix3::identity(), Vector3::zeros()),
            };
            let mut t = Vector3::zeros();
            let mut r = Vector3::zeros();
            for &(dof, i) in &joint.dofs {
                match dof {
                    Dof::Translation(k) => t[k] = q[i],
                    Dof::Rotation(k) => r[k] = q[i],
                }
            }
            let jl = left_jacobian(&r);
            for &(dof, i) in &joint.dofs {
                f.axis[i] = match dof {
                    Dof::Translation(k) => parent_rotation.column(k).into_owned(),
                    Dof::Rotation(k) => parent_rotation * jl.column(k),
                };
            }
            f.position
                .push(parent_position + parent_rotation * (joint.offset + t));
            f.rotation.push(parent_rotation * exp(&r));
        }
        f
    }

    /// Whether DOF `i` (of joint `owner`) moves joint `j`'s frame.
    fn moves(&self, owner: usize, j: usize) -> bool {
        self.ancestor[j][owner]
    }

    fn is_rotation(&self, i: usize) -> bool {
        self.rotational[i]
    }

    /// Centre of mass (the root's position when massless).
    fn com(&self, f: &Frames) -> Vector3<f64> {
        let mut sum = Vector3::zeros();
        let mut mass = 0.0;
        for (j, joint) in self.joints.iter().enumerate() {
            sum += joint.mass * (f.position[j] + f.rotation[j] * joint.com);
            mass += joint.mass;
        }
        if mass > 0.0 {
            sum / mass
        } else {
            f.position[0]
        }
    }

    /// A task's residual at these frames (m or rad), unscaled.
    fn residual(&self, goal: &Goal, f: &Frames) -> f64 {
        match goal {
            Goal::Position {
                joint,
                point,
                axes,
                target,
            } => {
                let p = f.position[*joint] + f.rotation[*joint] * point;
                (0..3)
                    .filter(|&k| axes[k])
                    .map(|k| (target[k] - p[k]).powi(2))
                    .sum::<f64>()
                    .sqrt()
            }
            Goal::Orientation { joint, target } => {
                angle(&(target.matrix() * f.rotation[*joint].transpose()))
            }
            Goal::Direction {
                joint,
                axis,
                target,
            } => unit_angle(&(f.rotation[*joint] * axis), target),
            Goal::Gaze {
                joint,
                point,
                axis,
                target,
            } => {
                let eye = f.position[*joint] + f.rotation[*joint] * point;
                unit_angle(&(f.rotation[*joint] * axis), &(target - eye))
            }
            Goal::Com { axes, target } => {
                let c = self.com(f);
                (0..3)
                    .filter(|&k| axes[k])
                    .map(|k| (target[k] - c[k]).powi(2))
                    .sum::<f64>()
                    .sqrt()
            }
            Goal::Balance { support, margin } => self
                .standing(f, support, *margin)
                .map_or(0.0, |s| s.violation.max(0.0)),
            Goal::Line {
                joint,
                point,
                origin,
                direction,
            } => {
                let p = f.position[*joint] + f.rotation[*joint] * point;
                across(direction, &(p - origin)).norm()
            }
            Goal::Plane {
                joint,
                point,
                origin,
                normal,
                above,
            } => {
                let p = f.position[*joint] + f.rotation[*joint] * point;
                let s = normal.dot(&(p - origin));
                if *above { (-s).max(0.0) } else { s.abs() }
            }
        }
    }

    /// Every level's residual at posture `q` (m and rad; the norm of its tasks' residuals,
    /// each scaled by `sqrt(weight)`): the judge of whether a posture meets the levels.
    pub fn level_residuals(&self, q: &[f64]) -> Vec<f64> {
        let f = self.frames(q);
        self.levels
            .iter()
            .map(|level| {
                level
                    .iter()
                    .map(|t| (t.scale * self.residual(&t.goal, &f)).powi(2))
                    .sum::<f64>()
                    .sqrt()
            })
            .collect()
    }

    /// The textbook error of a task (clamped) and its rows of the Jacobian of the quantity the
    /// error pulls (`e ~ J dq`).
    fn rows(
        &self,
        goal: &Goal,
        f: &Frames,
        owner: &[usize],
        settings: &Settings,
        clamp: bool,
    ) -> (Vec<f64>, Vec<Vec<f64>>) {
        let n = self.dof_count();
        let clamp_to = |e: &mut Vec<f64>, size: f64, limit: f64| {
            if clamp && size > limit {
                for x in e.iter_mut() {
                    *x *= limit / size;
                }
            }
        };
        // d(point)/dq, per DOF, for a point carried by joint j.
        let point_columns = |j: usize, p: &Vector3<f64>| -> Vec<Vector3<f64>> {
            (0..n)
                .map(|i| {
                    let a = owner[i];
                    if !self.moves(a, j) {
                        Vector3::zeros()
                    } else if self.is_rotation(i) {
                        f.axis[i].cross(&(p - f.position[a]))
                    } else {
                        f.axis[i]
                    }
                })
                .collect()
        };
        let angular_columns = |j: usize| -> Vec<Vector3<f64>> {
            (0..n)
                .map(|i| {
                    if self.moves(owner[i], j) && self.is_rotation(i) {
                        f.axis[i]
                    } else {
                        Vector3::zeros()
                    }
                })
                .collect()
        };
        let select = |axes: &[bool; 3], e: Vector3<f64>, cols: Vec<Vector3<f64>>| {
            let mut err = Vec::new();
            let mut rows = Vec::new();
            for k in (0..3).filter(|&k| axes[k]) {
                err.push(e[k]);
                rows.push(cols.iter().map(|c| c[k]).collect());
            }
            (err, rows)
        };
        let all = [true; 3];
        match goal {
            Goal::Position {
                joint,
                point,
                axes,
                target,
            } => {
                let p = f.position[*joint] + f.rotation[*joint] * point;
                let (mut e, rows) = select(axes, target - p, point_columns(*joint, &p));
                let size = e.iter().map(|x| x * x).sum::<f64>().sqrt();
                clamp_to(&mut e, size, settings.max_linear);
                (e, rows)
            }
            Goal::Orientation { joint, target } => {
                // E = R_t R^T; the error log(E), whose exact derivative is
                // -J_l^-1(log E) E w for a world angular velocity w of the joint.
                let difference = target.matrix() * f.rotation[*joint].transpose();
                let error = Rotation3::from_matrix_unchecked(difference).scaled_axis();
                let map = left_jacobian_inverse(&error) * difference;
                let cols: Vec<Vector3<f64>> =
                    angular_columns(*joint).iter().map(|w| map * w).collect();
                let (mut e, rows) = select(&all, error, cols);
                clamp_to(&mut e, error.norm(), settings.max_angular);
                (e, rows)
            }
            Goal::Direction {
                joint,
                axis,
                target,
            } => {
                let d = f.rotation[*joint] * axis;
                let cols: Vec<Vector3<f64>> = angular_columns(*joint)
                    .iter()
                    .map(|w| w.cross(&d))
                    .collect();
                let (mut e, rows) = select(&all, target - d, cols);
                clamp_to(&mut e, unit_angle(&d, target), settings.max_angular);
                (e, rows)
            }
            Goal::Gaze {
                joint,
                point,
                axis,
                target,
            } => {
                let eye = f.position[*joint] + f.rotation[*joint] * point;
                let d = f.rotation[*joint] * axis;
                let v = target - eye;
                let distance = v.norm().max(1e-9);
                let toward = v / distance;
                let squash = (Matrix3::identity() - toward * toward.transpose()) / distance;
                let eye_cols = point_columns(*joint, &eye);
                // e = toward - d; the quantity pulled is d - toward.
                let cols: Vec<Vector3<f64>> = angular_columns(*joint)
                    .iter()
                    .zip(&eye_cols)
                    .map(|(w, pe)| w.cross(&d) + squash * pe)
                    .collect();
                let (mut e, rows) = select(&all, toward - d, cols);
                clamp_to(&mut e, unit_angle(&d, &toward), settings.max_angular);
                (e, rows)
            }
            Goal::Com { axes, target } => {
                let c = self.com(f);
                let (mut e, rows) = select(axes, target - c, self.com_columns(f));
                let size = e.iter().map(|x| x * x).sum::<f64>().sqrt();
                clamp_to(&mut e, size, settings.max_linear);
                (e, rows)
            }
            Goal::Balance { support, margin } => {
                // The violation's derivative: the centre of mass moving away from the nearest
                // boundary point, which moves with the support points it lies between. In a
                // solve (`clamp`) the row holds from `BAND` inside and pulls back only what is
                // outside; unclamped (for the tests) it is the signed distance everywhere.
                let Some(at) = self.standing(f, support, *margin) else {
                    return (Vec::new(), Vec::new());
                };
                if clamp && at.violation <= -balance::BAND {
                    return (vec![0.0], vec![vec![0.0; n]]);
                }
                let com = self.com_columns(f);
                let point = |k: usize| {
                    let (j, p) = &support[k];
                    point_columns(*j, &(f.position[*j] + f.rotation[*j] * p))
                };
                let (pa, pb) = (point(at.a), point(at.b));
                let row = (0..n)
                    .map(|i| {
                        let d = com[i] - (1.0 - at.t) * pa[i] - at.t * pb[i];
                        at.normal[0] * d.x + at.normal[1] * d.z
                    })
                    .collect();
                let e = if clamp {
                    -at.violation.max(0.0).min(settings.max_linear)
                } else {
                    -at.violation
                };
                (vec![e], vec![row])
            }
            Goal::Line {
                joint,
                point,
                origin,
                direction,
            } => {
                // Three rows of rank two: the offset across the line and its derivative, the
                // point's velocity with its component along the line taken out.
                let p = f.position[*joint] + f.rotation[*joint] * point;
                let off = across(direction, &(p - origin));
                let cols: Vec<Vector3<f64>> = point_columns(*joint, &p)
                    .iter()
                    .map(|c| across(direction, c))
                    .collect();
                let (mut e, rows) = select(&all, -off, cols);
                clamp_to(&mut e, off.norm(), settings.max_linear);
                (e, rows)
            }
            Goal::Plane {
                joint,
                point,
                origin,
                normal,
                above,
            } => {
                // The signed distance; "on or above" in a solve (`clamp`) holds its row from
                // `BAND` over the plane and pulls back only what is under it; unclamped (for
                // the tests) it is the signed distance everywhere.
                let p = f.position[*joint] + f.rotation[*joint] * point;
                let s = normal.dot(&(p - origin));
                if clamp && *above && s > balance::BAND {
                    return (vec![0.0], vec![vec![0.0; n]]);
                }
                let row = point_columns(*joint, &p)
                    .iter()
                    .map(|c| normal.dot(c))
                    .collect();
                let e = if clamp && *above {
                    (-s).max(0.0).min(settings.max_linear)
                } else if clamp {
                    (-s).clamp(-settings.max_linear, settings.max_linear)
                } else {
                    -s
                };
                (vec![e], vec![row])
            }
        }
    }

    /// The centre of mass's derivative per DOF (the root's point's without mass).
    fn com_columns(&self, f: &Frames) -> Vec<Vector3<f64>> {
        let n = self.dof_count();
        let total: f64 = self.joints.iter().map(|j| j.mass).sum();
        if total <= 0.0 {
            return (0..n)
                .map(|i| {
                    if !self.moves(self.owner[i], 0) {
                        Vector3::zeros()
                    } else if self.is_rotation(i) {
                        f.axis[i].cross(&(f.position[0] - f.position[self.owner[i]]))
                    } else {
                        f.axis[i]
                    }
                })
                .collect();
        }
        let centres: Vec<Vector3<f64>> = self
            .joints
            .iter()
            .enumerate()
            .map(|(j, joint)| f.position[j] + f.rotation[j] * joint.com)
            .collect();
        (0..n)
            .map(|i| {
                let a = self.owner[i];
                let mut col = Vector3::zeros();
                for (j, joint) in self.joints.iter().enumerate() {
                    if joint.mass > 0.0 && self.moves(a, j) {
                        col += joint.mass
                            * if self.is_rotation(i) {
                                f.axis[i].cross(&(centres[j] - f.position[a]))
                            } else {
                                f.axis[i]
                            };
                    }
                }
                col / total
            })
            .collect()
    }

    /// Every level's error and Jacobian at `q` (clamped errors when `clamp`).
    fn linearise(
        &self,
        q: &[f64],
        settings: &Settings,
        clamp: bool,
    ) -> Vec<(DVector<f64>, DMatrix<f64>)> {
        let f = self.frames(q);
        let owner = &self.owner;
        let n = self.dof_count();
        self.levels
            .iter()
            .map(|level| {
                let mut e = Vec::new();
                let mut rows: Vec<Vec<f64>> = Vec::new();
                for t in level {
                    let (te, tr) = self.rows(&t.goal, &f, owner, settings, clamp);
                    e.extend(te.iter().map(|x| x * t.scale));
                    rows.extend(
                        tr.into_iter()
                            .map(|r| r.into_iter().map(|x| x * t.scale).collect()),
                    );
                }
                let jacobian = DMatrix::from_fn(rows.len(), n, |r, c| rows[r][c]);
                (DVector::from_vec(e), jacobian)
            })
            .collect()
    }

    /// Every level's Jacobian at `q` (of the quantities the errors pull; for the tests, which
    /// compare it with central differences).
    pub fn jacobians(&self, q: &[f64]) -> Vec<DMatrix<f64>> {
        self.linearise(q, &Settings::default(), false)
            .into_iter()
            .map(|(_, j)| j)
            .collect()
    }

    /// Every level's unclamped error at `q` (for the tests).
    pub fn errors(&self, q: &[f64]) -> Vec<DVector<f64>> {
        self.linearise(q, &Settings::default(), false)
            .into_iter()
            .map(|(e, _)| e)
            .collect()
    }

    /// One textbook iteration's step from `q`, with the paper's joint-limit clamping loop: a
    /// DOF the step would carry past a limit is stopped on it, leaves the Jacobians, and the
    /// step is taken again with what it moved.
    pub fn step(&self, q: &[f64], settings: &Settings) -> DVector<f64> {
        let n = self.dof_count();
        let systems = self.linearise(q, settings, true);
        let mut free = vec![true; n];
        let mut fixed = DVector::zeros(n);
        loop {
            let dq = Self::recursion(&systems, &free, &fixed, settings);
            let mut again = false;
            for i in 0..n {
                let to = q[i] + dq[i];
                if free[i] && (to < self.lower[i] || to > self.upper[i]) {
                    free[i] = false;
                    fixed[i] = to.clamp(self.lower[i], self.upper[i]) - q[i];
                    again = true;
                }
            }
            if !again {
                return dq;
            }
        }
    }

    /// The recursion over the levels, the DOF not `free` held at their `fixed` steps.
    fn recursion(
        systems: &[(DVector<f64>, DMatrix<f64>)],
        free: &[bool],
        fixed: &DVector<f64>,
        settings: &Settings,
    ) -> DVector<f64> {
        let n = free.len();
        let mut dq = fixed.clone();
        let mut projector = DMatrix::<f64>::from_diagonal(&DVector::from_fn(n, |i, _| {
            f64::from(u8::from(free[i]))
        }));
        for (e, j) in systems {
            if e.is_empty() {
                continue;
            }
            let projected = j * &projector;
            let Some((sigma, u, v)) = jacobi_svd(&projected) else {
                break;
            };
            // The numerical rank of `J P` is judged against the level's own scale (the
            // Frobenius norm of `J`), not against the largest singular value of `J P`: a level
            // the levels above already decide leaves `J P` at the projector's rounding
            // (1e-12 to 1e-11 after a few levels), and a cut relative to that noise kept one
            // of its directions and took it out of every lower level's freedom (issue 29:
            // `wide-0088`'s first step 1.24 rad off on one DOF).
            let cut = j.norm() * 1e-9;
            let residual = e - j * &dq;
            let along = u.transpose() * residual;
            for (k, &s) in sigma.iter().enumerate() {
                if s <= cut {
                    continue;
                }
                let v = v.column(k);
                dq += v * (along[k] * s / (s * s + settings.lambda * settings.lambda));
                projector -= v * v.transpose();
            }
        }
        dq
    }

    fn clamp(&self, q: &mut [f64]) {
        for (i, x) in q.iter_mut().enumerate() {
            *x = x.clamp(self.lower[i], self.upper[i]);
        }
    }

    /// Solves from the start posture.
    pub fn solve(&self, settings: &Settings) -> Solution {
        let mut q = self.start.clone();
        self.clamp(&mut q);
        let mut residuals = self.level_residuals(&q);
        let mut best = (q.clone(), residuals.clone());
        let mut since_best = 0;
        let mut iterations = 0;
        let met = |r: &[f64]| r.iter().all(|&x| x <= self.tolerance);
        while !met(&residuals) && iterations < settings.max_iterations {
            let mut dq = self.step(&q, settings);
            if dq.iter().any(|d| !d.is_finite()) {
                break;
            }
            let largest = dq.amax();
            if largest > settings.max_dof_step {
                dq *= settings.max_dof_step / largest;
            }
            for (x, d) in q.iter_mut().zip(dq.iter()) {
                *x += d;
            }
            self.clamp(&mut q);
            iterations += 1;
            residuals = self.level_residuals(&q);
            if better(&residuals, &best.1, self.tolerance) {
                best = (q.clone(), residuals.clone());
                since_best = 0;
            } else {
                since_best += 1;
                if since_best >= settings.stall_window || dq.amax() < 1e-12 {
                    break;
                }
            }
        }
        let (posture, residuals) = if met(&residuals) {
            (q, residuals)
        } else {
            best
        };
        Solution {
            met_every_level: met(&residuals),
            posture,
            residuals,
            iterations,
        }
    }
}

/// `a` beats `b` in priority order: at the first level where they differ meaningfully (met
/// levels count as equal), `a` is lower.
pub fn better(a: &[f64], b: &[f64], tolerance: f64) -> bool {
    for (&x, &y) in a.iter().zip(b) {
        if x <= tolerance && y <= tolerance {
            continue;
        }
        if x < y * (1.0 - 1e-9) - 1e-15 {
            return true;
        }
        if x > y * (1.0 + 1e-9) + 1e-15 {
            return false;
        }
    }
    false
}

/// A singular value decomposition `a = U S V^T` of an `m x n` matrix by one-sided Jacobi
/// rotations (Hestenes; Demmel & Veselic) on the columns of `a^T`: rotations of pairs of
/// columns until every pair is orthogonal to machine precision; then the columns' norms are
/// the singular values and, divided by them, the right singular vectors, and the rotations
/// make `U`. Returns (`S` as `m` values, `U` as `m x m`, `V` as `n x m`). Not nalgebra's SVD:
/// its implicit-shift iteration (0.35) can return a decomposition 1e-9 to 1e-4 off on the
/// rank-deficient `J P` of a level (dimforge/nalgebra#1172), which moved a first step by
/// 4.6e-2 rad (`partial-0008`); Jacobi keeps small singular values accurate to their own
/// size. `None` when the sweeps do not settle (non-finite entries).
fn jacobi_svd(a: &DMatrix<f64>) -> Option<(Vec<f64>, DMatrix<f64>, DMatrix<f64>)> {
    let mut b = a.transpose();
    let m = b.ncols();
    let mut u = DMatrix::<f64>::identity(m, m);
    // A column at rounding size (a row of `J P` the levels above decided) is left as it is:
    // its singular value is noise the rank cut drops, and rotating it against others only
    // chases rounding.
    let negligible = (f64::EPSILON * b.norm()).powi(2);
    for _ in 0..80 {
        let mut rotated = false;
        for p in 0..m {
            for q in p + 1..m {
                let alpha = b.column(p).norm_squared();
                let beta = b.column(q).norm_squared();
                let gamma = b.column(p).dot(&b.column(q));
                if alpha <= negligible
                    || beta <= negligible
                    || gamma.abs() <= f64::EPSILON * (alpha * beta).sqrt()
                {
                    continue;
                }
                rotated = true;
                let zeta = (beta - alpha) / (2.0 * gamma);
                let t = zeta.signum() / (zeta.abs() + (1.0 + zeta * zeta).sqrt());
                let c = 1.0 / (1.0 + t * t).sqrt();
                let s = c * t;
                for matrix in [&mut b, &mut u] {
                    for r in 0..matrix.nrows() {
                        let (x, y) = (matrix[(r, p)], matrix[(r, q)]);
                        matrix[(r, p)] = c * x - s * y;
                        matrix[(r, q)] = s * x + c * y;
                    }
                }
            }
        }
        if !rotated {
            let sigma: Vec<f64> = (0..m).map(|k| b.column(k).norm()).collect();
            for (k, &s) in sigma.iter().enumerate() {
                if s > 0.0 {
                    b.column_mut(k).unscale_mut(s);
                }
            }
            return Some((sigma, u, b));
        }
        if b.iter().any(|x| !x.is_finite()) {
            return None;
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `U S V^T` against `a`, and `U`, `V` orthonormal where `S` is not zero.
    fn check(a: &DMatrix<f64>) -> Vec<f64> {
        let (sigma, u, v) = jacobi_svd(a).unwrap();
        let s = DMatrix::from_diagonal(&DVector::from_vec(sigma.clone()));
        let back = &u * s * v.transpose();
        assert!(
            (back - a).amax() < 1e-14 * a.amax().max(1.0),
            "U S V^T is not a"
        );
        assert!((u.transpose() * &u - DMatrix::identity(u.ncols(), u.ncols())).amax() < 1e-14);
        for (k, &s) in sigma.iter().enumerate() {
            for (l, &t) in sigma.iter().enumerate() {
                if s > 1e-12 && t > 1e-12 {
                    let d = v.column(k).dot(&v.column(l));
                    assert!((d - f64::from(u8::from(k == l))).abs() < 1e-13);
                }
            }
        }
        let mut sorted = sigma;
        sorted.sort_by(|a, b| b.total_cmp(a));
        sorted
    }

    // Catches a decomposition that does not give the matrix back or a wrong singular value:
    // a hand case (rows (3, 0, 0, 4) and (0, 5, 0, 0): singular values 5 and 5, orthogonal
    // rows), and a rank-deficient one with a repeated row, like a level whose task repeats
    // one above it (nalgebra 0.35's SVD with a tolerance of one epsilon gave matrices of this
    // kind back 4e-5 off).
    #[test]
    fn jacobi_svd_gives_the_matrix_back_with_its_singular_values() {
        let a = DMatrix::from_row_slice(2, 4, &[3.0, 0.0, 0.0, 4.0, 0.0, 5.0, 0.0, 0.0]);
        let s = check(&a);
        assert!((s[0] - 5.0).abs() < 1e-14 && (s[1] - 5.0).abs() < 1e-14);
        // Rows r1, r2, r1 again, and r1 + 1e-7 r3: rank 3 with a small singular value.
        let r1 = [0.3, -1.2, 0.8, 0.05, 2.0, -0.7];
        let r2 = [1.1, 0.4, -0.2, 0.9, -0.3, 0.6];
        let r3 = [0.2, 0.2, 1.5, -1.0, 0.1, 0.4];
        let mut rows = Vec::new();
        rows.extend(r1);
        rows.extend(r2);
        rows.extend(r1);
        rows.extend(r1.iter().zip(r3).map(|(a, b)| a + 1e-7 * b));
        let a = DMatrix::from_row_slice(4, 6, &rows);
        let s = check(&a);
        assert!(s[3] < 1e-14, "the repeated row's singular value {}", s[3]);
        assert!(
            s[2] > 1e-8 && s[2] < 1e-6,
            "the small singular value kept: {}",
            s[2]
        );
        // The largest against the Gram matrix's eigenvalues (an independent route).
        let gram = (&a * a.transpose()).symmetric_eigen();
        let largest = gram.eigenvalues.max().sqrt();
        assert!((s[0] - largest).abs() < 1e-12);
    }

    #[test]
    fn jacobi_svd_of_zero_and_of_non_finite_matrices() {
        let (sigma, _, _) = jacobi_svd(&DMatrix::zeros(3, 5)).unwrap();
        assert!(sigma.iter().all(|&s| s == 0.0));
        let mut a = DMatrix::from_element(2, 3, 1.0);
        a[(0, 1)] = f64::NAN;
        a[(1, 2)] = 2.0;
        assert!(jacobi_svd(&a).is_none());
    }
}
