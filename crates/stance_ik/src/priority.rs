//! The prioritized step of [BAE 98]: damped least squares per level, recursive projector.
//!
//! The projector onto the null space of levels 1..k is kept as `P_k = I - W_k W_k^T` with
//! `W_k` an orthonormal basis of the row space of the augmented Jacobian `J_k^A`. The
//! recursive update `P_k = P_{k-1} - Jh_k^+ Jh_k` (with `Jh_k = J_k P_{k-1}`) is exactly
//! "append an orthonormal basis of the row space of `Jh_k` to `W`": `Jh_k^+ Jh_k` is the
//! orthogonal projector onto that row space, and the row space of `Jh_k` is orthogonal to
//! `W_{k-1}`. The basis is built by Gram-Schmidt with column pivoting on the columns of
//! `Jh_k^T` (a rank-revealing QR), rows whose remaining norm falls below
//! `rank_tolerance * max row norm of J_k` counting as dependent: this is the undamped,
//! rank-decided pseudo-inverse of the contract. Storing `W` instead of the `N x N` matrix `P`
//! keeps it symmetric and idempotent by construction and makes `J_k P` cost `O(m N r)`.

use nalgebra::{DMatrix, DVector};

/// Damping of each level's pseudo-inverse ([MAC 90], Annex I of the paper).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Damping {
    /// `sigma / (sigma^2 + lambda^2)` with a constant `lambda` (units of the task rows).
    Constant {
        /// The damping factor; 0 gives the plain pseudo-inverse.
        lambda: f64,
    },
    /// Numerical filtering (Maciejewski & Klein): only singular values below `epsilon` are
    /// damped, with `lambda_i^2 = lambda_max^2 * (1 - (sigma_i / epsilon)^2)`. Far from
    /// singularities the step is undamped (fast convergence), near them it is bounded.
    Adaptive {
        /// Damping reached at a zero singular value.
        lambda_max: f64,
        /// Width of the singular region.
        epsilon: f64,
    },
    /// Levenberg-Marquardt style: `lambda` while the level's error is at least `error_scale`
    /// (m / rad), falling in proportion with it below: the step near a singularity stays
    /// bounded far from the goal, and the last iterations are the undamped Newton steps that
    /// converge quadratically.
    Levenberg {
        /// The damping far from the goal.
        lambda: f64,
        /// The error below which the damping falls (m / rad, > 0).
        error_scale: f64,
    },
}

impl Default for Damping {
    /// `Constant { lambda: 0.002 }`, the damping of one prioritized step. (A solve's default is
    /// `crate::WHOLE_SOLVE_DAMPING`, which falls with the error; frame-by-frame solves take
    /// `crate::CONSTANT_DAMPING`, this one.)
    fn default() -> Self {
        Damping::Constant { lambda: 0.002 }
    }
}

impl Damping {
    /// The damping of a level whose desired change has norm `error`: a
    /// [`Damping::Levenberg`] becomes the constant it takes there, the others stay.
    pub fn at_error(self, error: f64) -> Self {
        match self {
            Damping::Levenberg {
                lambda,
                error_scale,
            } => Damping::Constant {
                lambda: lambda * (error / error_scale).min(1.0),
            },
            other => other,
        }
    }
}

/// One priority level, linearised: `J` (transposed, `N x m`, rows already weighted) and the
/// desired change `dx` (weighted, clamped).
#[derive(Debug, Clone)]
pub struct LevelSystem {
    /// The level number (1 = highest).
    pub level: u32,
    /// `J_k^T`, `N x m_k`.
    pub jacobian_t: DMatrix<f64>,
    /// `dx_k`, length `m_k`.
    pub dx: DVector<f64>,
    /// Sorted DOF indices of the possibly non-zero rows of `jacobian_t` (empty: all).
    pub support: Vec<usize>,
    /// This level's damping (`None`: the step's `StepParams::damping`).
    pub damping: Option<Damping>,
    /// The rows are cost gradients (the comfort task): the level's step is its rows projected
    /// into what the levels above leave, times `dx` (`P_{k-1} z`, the null-space term of the
    /// paper's formula), with no least-squares inverse: a direction the levels above block
    /// gives less motion, never more.
    pub projection: bool,
}

/// Parameters of one prioritized step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StepParams {
    /// Per-level damping.
    pub damping: Damping,
    /// Relative rank threshold of the undamped projector.
    pub rank_tolerance: f64,
    /// Largest absolute DOF change of a whole step. The levels share it in priority order:
    /// each level's increment is scaled down uniformly into what the levels above left of it
    /// (a scaled increment stays in the null space of the levels above, so the priority stays
    /// strict, and a lower level can never take the step away from a higher one).
    pub max_dof_step: f64,
}

impl Default for StepParams {
    fn default() -> Self {
        Self {
            damping: Damping::default(),
            rank_tolerance: 1e-9,
            max_dof_step: 0.2,
        }
    }
}

/// Reusable buffers of the prioritized step.
#[derive(Debug, Clone, Default)]
pub struct StepWorkspace {
    w: DMatrix<f64>,
    rank: usize,
    jts: DMatrix<f64>,
    jht: DMatrix<f64>,
    gathered: DMatrix<f64>,
    all_rows: Vec<usize>,
    col_norms: Vec<f64>,
    partial: Vec<DVector<f64>>,
    pub(crate) kernel: crate::kernel::Kernel,
}

impl StepWorkspace {
    /// After [`crate::prioritized_step`]: the cumulative step after each level (`dtheta_k`).
    pub fn partial_steps(&self) -> &[DVector<f64>] {
        &self.partial
    }

    pub(crate) fn partial_mut(&mut self) -> &mut Vec<DVector<f64>> {
        &mut self.partial
    }
}

fn reshape(m: &mut DMatrix<f64>, rows: usize, cols: usize) {
    if m.shape() != (rows, cols) {
        *m = DMatrix::zeros(rows, cols);
    }
}

/// The same step as [`crate::prioritized_step`], written with nalgebra's dynamic matrices (kept as
/// the "well-kept crate" reference for the benchmark comparison; see `docs/problem-format.md`
/// and the bench notes).
///
/// `clamped[i]` removes DOF `i` from the step (its column is zeroed); `fixed` is a DOF change
/// already decided (clamped joints moved onto their limits) whose effect is subtracted from
/// every level's `dx`. When `projectors` is given, `P_k` after each level is pushed into it
/// (for tests).
///
/// Sparsity: only the rows of `J_k^T` listed in `LevelSystem::support` are read (a Jacobian
/// column is zero for DOF that are not ancestors of the effector), so `W^T J_k^T` costs
/// `O(r |S| m)` and `J_k P J_k^T` `O(m^2 |S|)`. Once the projector has rank `N`, the remaining
/// levels are skipped (they have no freedom left).
pub fn prioritized_step_nalgebra(
    levels: &[LevelSystem],
    n: usize,
    params: &StepParams,
    clamped: Option<&[bool]>,
    fixed: Option<&DVector<f64>>,
    ws: &mut StepWorkspace,
    mut projectors: Option<&mut Vec<DMatrix<f64>>>,
) -> DVector<f64> {
    let mut dtheta = DVector::zeros(n);
    let mut budget = params.max_dof_step;
    reshape(&mut ws.w, n, n);
    ws.rank = 0;
    if ws.all_rows.len() != n {
        ws.all_rows = (0..n).collect();
    }
    ws.partial.resize_with(levels.len(), || DVector::zeros(n));
    let last_with_rows = levels.iter().rposition(|l| !l.dx.is_empty());
    for (k, level) in levels.iter().enumerate() {
        let m = level.dx.len();
        let r = ws.rank;
        if m == 0 || level.jacobian_t.nrows() != n || level.jacobian_t.ncols() != m || r >= n {
            if let Some(p) = projectors.as_deref_mut() {
                p.push(projector_nalgebra(ws, n));
            }
            ws.partial[k].clone_from(&dtheta);
            continue;
        }
        let all = std::mem::take(&mut ws.all_rows);
        let support: &[usize] = if level.support.is_empty() {
            &all
        } else {
            &level.support
        };
        let s = support.len();
        // J^T on the support rows, clamped DOF zeroed.
        reshape(&mut ws.jts, s, m);
        for c in 0..m {
            let src = level.jacobian_t.column(c);
            let mut dst = ws.jts.column_mut(c);
            for (i, &d) in support.iter().enumerate() {
                let off = clamped.is_some_and(|mask| mask.get(d).copied().unwrap_or(false));
                dst[i] = if off { 0.0 } else { src[d] };
            }
        }
        // e = dx - J (dtheta_{k-1} + fixed); `fixed` lives on clamped DOF, whose columns
        // are zeroed in `jts`, so it is applied with the unmasked Jacobian.
        let mut e = level.dx.clone();
        for c in 0..m {
            let col = ws.jts.column(c);
            let full = level.jacobian_t.column(c);
            let mut acc = 0.0;
            for (i, &d) in support.iter().enumerate() {
                let f = fixed.map_or(0.0, |f| f[d]);
                acc += col[i] * dtheta[d] + full[d] * f;
            }
            e[c] -= acc;
        }
        ws.col_norms.clear();
        ws.col_norms.extend((0..m).map(|c| ws.jts.column(c).norm()));
        let row_scale = ws.col_norms.iter().copied().fold(0.0, f64::max);
        if row_scale <= 0.0 {
            ws.all_rows = all;
            if let Some(p) = projectors.as_deref_mut() {
                p.push(projector_nalgebra(ws, n));
            }
            ws.partial[k].clone_from(&dtheta);
            continue;
        }
        let tol = params.rank_tolerance * row_scale;
        // Jh^T = P J^T = J^T - W (W^T J^T), with W^T J^T read on the support only.
        reshape(&mut ws.jht, n, m);
        ws.jht.fill(0.0);
        for c in 0..m {
            for (i, &d) in support.iter().enumerate() {
                ws.jht[(d, c)] = ws.jts[(i, c)];
            }
        }
        let g = if r > 0 {
            reshape(&mut ws.gathered, s, r);
            for j in 0..r {
                for (i, &d) in support.iter().enumerate() {
                    ws.gathered[(i, j)] = ws.w[(d, j)];
                }
            }
            let coeffs = ws.gathered.tr_mul(&ws.jts);
            ws.jht.gemm(-1.0, &ws.w.columns(0, r), &coeffs, 1.0);
            // G = J P J^T = J (Jh^T) read on the support.
            reshape(&mut ws.gathered, s, m);
            for c in 0..m {
                for (i, &d) in support.iter().enumerate() {
                    ws.gathered[(i, c)] = ws.jht[(d, c)];
                }
            }
            ws.jts.tr_mul(&ws.gathered)
        } else {
            ws.jts.tr_mul(&ws.jts)
        };
        ws.all_rows = all;
        let y = if level.projection {
            level.dx.clone()
        } else {
            let damping = level.damping.unwrap_or(params.damping);
            damped_solve(&g, &e, damping.at_error(level.dx.norm()), tol)
        };
        let mut step = &ws.jht * y;
        let max = step.amax();
        let left = budget.max(0.0);
        if max.is_finite() && max > left {
            step *= left / max;
        }
        if step.iter().all(|v| v.is_finite()) {
            budget -= step.amax();
            dtheta += step;
        }
        if Some(k) != last_with_rows || projectors.is_some() {
            extend_basis(ws, n, tol);
        }
        if let Some(p) = projectors.as_deref_mut() {
            p.push(projector_nalgebra(ws, n));
        }
        ws.partial[k].clone_from(&dtheta);
    }
    dtheta
}

fn projector_nalgebra(ws: &StepWorkspace, n: usize) -> DMatrix<f64> {
    let mut p = DMatrix::identity(n, n);
    if ws.rank > 0 {
        let w = ws.w.columns(0, ws.rank);
        p.gemm(-1.0, &w, &w.transpose(), 1.0);
    }
    p
}

/// `y` with `Jh^{+lambda} e = Jh^T y`, from `G = Jh Jh^T`.
pub(crate) fn damped_solve(
    g: &DMatrix<f64>,
    e: &DVector<f64>,
    damping: Damping,
    tol: f64,
) -> DVector<f64> {
    let m = g.nrows();
    if let Damping::Constant { lambda } = damping
        && lambda > 0.0
    {
        let mut a = g.clone();
        for i in 0..m {
            a[(i, i)] += lambda * lambda;
        }
        if let Some(ch) = a.cholesky() {
            return ch.solve(e);
        }
    }
    let eig = g.clone().symmetric_eigen();
    let mut y = DVector::zeros(m);
    let ut_e = eig.eigenvectors.tr_mul(e);
    for i in 0..m {
        let s2 = eig.eigenvalues[i].max(0.0);
        let s = s2.sqrt();
        if s <= tol {
            continue;
        }
        let l2 = match damping {
            // Callers pass a Levenberg damping through `at_error`; taken at full here.
            Damping::Constant { lambda } | Damping::Levenberg { lambda, .. } => lambda * lambda,
            Damping::Adaptive {
                lambda_max,
                epsilon,
            } => {
                if s < epsilon {
                    lambda_max * lambda_max * (1.0 - (s / epsilon).powi(2))
                } else {
                    0.0
                }
            }
        };
        let f = ut_e[i] / (s2 + l2);
        y.axpy(f, &eig.eigenvectors.column(i), 1.0);
    }
    y
}

/// Appends to `W` an orthonormal basis of the numerical column space of `Jh^T` (Gram-Schmidt
/// with column pivoting; a column is orthogonalised against `W` once more when the projection
/// cancelled more than half of its norm, "twice is enough").
fn extend_basis(ws: &mut StepWorkspace, n: usize, tol: f64) {
    let m = ws.jht.ncols();
    let mut norms: Vec<f64> = (0..m).map(|c| ws.jht.column(c).norm_squared()).collect();
    let mut used = vec![false; m];
    let tol2 = tol * tol;
    while ws.rank < n {
        let mut best = None;
        let mut best_norm = tol2;
        for c in 0..m {
            if !used[c] && norms[c] > best_norm {
                best_norm = norms[c];
                best = Some(c);
            }
        }
        let Some(c) = best else { break };
        used[c] = true;
        let r = ws.rank;
        let original = ws.col_norms.get(c).copied().unwrap_or(0.0);
        if best_norm < 0.25 * original * original && r > 0 {
            let w = ws.w.columns(0, r);
            let coeffs = w.tr_mul(&ws.jht.column(c));
            ws.jht.column_mut(c).gemv(-1.0, &w, &coeffs, 1.0);
        }
        let norm = ws.jht.column(c).norm();
        if norm <= tol {
            continue;
        }
        for i in 0..n {
            ws.w[(i, r)] = ws.jht[(i, c)] / norm;
        }
        ws.rank += 1;
        for c2 in 0..m {
            if !used[c2] {
                let mut d = 0.0;
                for i in 0..n {
                    d += ws.w[(i, r)] * ws.jht[(i, c2)];
                }
                let mut sq = 0.0;
                for i in 0..n {
                    let v = ws.jht[(i, c2)] - d * ws.w[(i, r)];
                    ws.jht[(i, c2)] = v;
                    sq += v * v;
                }
                norms[c2] = sq;
            }
        }
    }
}
