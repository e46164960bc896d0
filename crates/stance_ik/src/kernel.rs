//! The prioritized step on plain contiguous slices: the solver's hot path.
//!
//! Same mathematics as [`crate::prioritized_step_nalgebra`] (see `priority.rs` for the
//! derivation): `P_k = I - W_k W_k^T` with `W` an orthonormal basis grown by pivoted
//! Gram-Schmidt, per-level damped least squares through `G = J P J^T` and a Cholesky solve,
//! sparsity of the Jacobian rows exploited. The matrices here are small (N <= ~100,
//! m_k <= ~60) and reused every iteration; column-major slices with unrolled dot products avoid
//! the per-call allocations and bounds checks of the dynamic-matrix version, which the benchmark
//! shows to matter at these sizes (figures in the closing notes / `stance bench`).

use nalgebra::{DMatrix, DVector};

use crate::priority::{Damping, LevelSystem, StepParams, StepWorkspace, damped_solve};

/// Buffers of the kernel (all column-major).
#[derive(Debug, Clone, Default)]
pub(crate) struct Kernel {
    w: Vec<f64>,
    rank: usize,
    jts: Vec<f64>,
    wg: Vec<f64>,
    coeffs: Vec<f64>,
    jht: Vec<f64>,
    g: Vec<f64>,
    l: Vec<f64>,
    e: Vec<f64>,
    y: Vec<f64>,
    col_norms: Vec<f64>,
    norms: Vec<f64>,
    used: Vec<bool>,
    theta: Vec<f64>,
    step: Vec<f64>,
    all_rows: Vec<usize>,
    budget: f64,
}

#[inline]
fn dot(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len().min(b.len());
    let (a, b) = (&a[..n], &b[..n]);
    let mut acc = [0.0f64; 4];
    let mut ca = a.chunks_exact(4);
    let mut cb = b.chunks_exact(4);
    for (x, y) in (&mut ca).zip(&mut cb) {
        acc[0] += x[0] * y[0];
        acc[1] += x[1] * y[1];
        acc[2] += x[2] * y[2];
        acc[3] += x[3] * y[3];
    }
    let mut tail = 0.0;
    for (x, y) in ca.remainder().iter().zip(cb.remainder()) {
        tail += x * y;
    }
    (acc[0] + acc[1]) + (acc[2] + acc[3]) + tail
}

#[inline]
fn axpy(alpha: f64, x: &[f64], y: &mut [f64]) {
    for (yi, xi) in y.iter_mut().zip(x) {
        *yi += alpha * xi;
    }
}

/// In-place Cholesky of the `m x m` column-major `a` (lower triangle used). False when not
/// positive definite.
fn cholesky(a: &mut [f64], m: usize) -> bool {
    for j in 0..m {
        let mut d = a[j * m + j];
        for k in 0..j {
            let l = a[k * m + j];
            d -= l * l;
        }
        if d.is_nan() || d <= 0.0 || !d.is_finite() {
            return false;
        }
        let d = d.sqrt();
        a[j * m + j] = d;
        for i in j + 1..m {
            let mut v = a[j * m + i];
            for k in 0..j {
                v -= a[k * m + i] * a[k * m + j];
            }
            a[j * m + i] = v / d;
        }
    }
    true
}

/// Solves `L L^T y = b` in place in `b`.
fn cholesky_solve(l: &[f64], m: usize, b: &mut [f64]) {
    for i in 0..m {
        let mut v = b[i];
        for k in 0..i {
            v -= l[k * m + i] * b[k];
        }
        b[i] = v / l[i * m + i];
    }
    for i in (0..m).rev() {
        let mut v = b[i];
        for k in i + 1..m {
            v -= l[i * m + k] * b[k];
        }
        b[i] = v / l[i * m + i];
    }
}

/// Computes `dtheta` for the stacked levels (highest first) by the recursive algorithm of
/// [BAE 98].
///
/// `clamped[i]` removes DOF `i` from the step (its column is zeroed); `fixed` is a DOF change
/// already decided (clamped joints moved onto their limits) whose effect is subtracted from
/// every level's `dx`. When `projectors` is given, `P_k` after each level is pushed into it
/// (for tests). `ws.partial_steps()` then holds `dtheta_k` after each level.
///
/// Sparsity: only the rows of `J_k^T` listed in `LevelSystem::support` are read (a Jacobian
/// column is zero for DOF that are not ancestors of the effector), so `W^T J_k^T` costs
/// `O(r |S| m)` and `J_k P J_k^T` `O(m^2 |S|)`; `G` is symmetric and only half is computed.
/// Once the projector has rank `N`, the remaining levels are skipped.
pub fn prioritized_step(
    levels: &[LevelSystem],
    n: usize,
    params: &StepParams,
    clamped: Option<&[bool]>,
    fixed: Option<&DVector<f64>>,
    ws: &mut StepWorkspace,
    mut projectors: Option<&mut Vec<DMatrix<f64>>>,
) -> DVector<f64> {
    let partial = ws.partial_mut();
    partial.resize_with(levels.len(), || DVector::zeros(n));
    for p in partial.iter_mut() {
        if p.len() != n {
            *p = DVector::zeros(n);
        }
    }
    let mut partial = std::mem::take(ws.partial_mut());
    let kn = &mut ws.kernel;
    kn.w.resize(n * n, 0.0);
    kn.rank = 0;
    if kn.all_rows.len() != n {
        kn.all_rows = (0..n).collect();
    }
    kn.theta.clear();
    kn.theta.resize(n, 0.0);
    kn.budget = params.max_dof_step;
    let last_with_rows = levels.iter().rposition(|l| !l.dx.is_empty());
    for (k, level) in levels.iter().enumerate() {
        let m = level.dx.len();
        let r = kn.rank;
        let usable = m > 0 && level.jacobian_t.shape() == (n, m) && r < n;
        if usable {
            level_step(
                kn,
                level,
                n,
                params,
                clamped,
                fixed,
                Some(k) != last_with_rows || projectors.is_some(),
            );
        }
        if let Some(p) = projectors.as_deref_mut() {
            p.push(kn.projector(n));
        }
        partial[k].as_mut_slice().copy_from_slice(&kn.theta);
    }
    *ws.partial_mut() = partial;
    DVector::from_column_slice(&ws.kernel.theta)
}

fn level_step(
    kn: &mut Kernel,
    level: &LevelSystem,
    n: usize,
    params: &StepParams,
    clamped: Option<&[bool]>,
    fixed: Option<&DVector<f64>>,
    extend: bool,
) {
    let m = level.dx.len();
    let r = kn.rank;
    let all = std::mem::take(&mut kn.all_rows);
    let support: &[usize] = if level.support.is_empty() {
        &all
    } else {
        &level.support
    };
    let s = support.len();
    let jt = level.jacobian_t.as_slice();
    // J^T on the support rows, clamped DOF zeroed: jts (s x m).
    kn.jts.clear();
    kn.jts.resize(s * m, 0.0);
    for c in 0..m {
        let src = &jt[c * n..(c + 1) * n];
        let dst = &mut kn.jts[c * s..(c + 1) * s];
        for (i, &d) in support.iter().enumerate() {
            let off = clamped.is_some_and(|mask| mask.get(d).copied().unwrap_or(false));
            dst[i] = if off { 0.0 } else { src[d] };
        }
    }
    // theta + fixed on the support, then e = dx - J (theta + fixed).
    kn.y.clear();
    kn.y.extend(
        support
            .iter()
            .map(|&d| kn.theta[d] + fixed.map_or(0.0, |f| f[d])),
    );
    kn.e.clear();
    kn.e.extend_from_slice(level.dx.as_slice());
    kn.col_norms.clear();
    for c in 0..m {
        let col = &kn.jts[c * s..(c + 1) * s];
        kn.e[c] -= dot(col, &kn.y);
        kn.col_norms.push(dot(col, col).sqrt());
    }
    let row_scale = kn.col_norms.iter().copied().fold(0.0, f64::max);
    if row_scale.is_nan() || row_scale <= 0.0 || !row_scale.is_finite() {
        kn.all_rows = all;
        return;
    }
    let tol = params.rank_tolerance * row_scale;
    kn.g.clear();
    kn.g.resize(m * m, 0.0);
    // G = J J^T on the support (then minus C^T C below).
    for a in 0..m {
        for b in a..m {
            let v = dot(&kn.jts[a * s..(a + 1) * s], &kn.jts[b * s..(b + 1) * s]);
            kn.g[b * m + a] = v;
            kn.g[a * m + b] = v;
        }
    }
    kn.coeffs.clear();
    if r > 0 {
        // C = W^T J^T, read on the support rows: coeffs (r x m).
        kn.wg.clear();
        kn.wg.resize(s * r, 0.0);
        for j in 0..r {
            let wj = &kn.w[j * n..(j + 1) * n];
            let dst = &mut kn.wg[j * s..(j + 1) * s];
            for (i, &d) in support.iter().enumerate() {
                dst[i] = wj[d];
            }
        }
        kn.coeffs.resize(r * m, 0.0);
        for c in 0..m {
            let col = &kn.jts[c * s..(c + 1) * s];
            for j in 0..r {
                kn.coeffs[c * r + j] = dot(&kn.wg[j * s..(j + 1) * s], col);
            }
        }
        // G = J P J^T = J J^T - C^T C.
        for a in 0..m {
            for b in a..m {
                let v = dot(
                    &kn.coeffs[a * r..(a + 1) * r],
                    &kn.coeffs[b * r..(b + 1) * r],
                );
                kn.g[b * m + a] -= v;
                if a != b {
                    kn.g[a * m + b] -= v;
                }
            }
        }
    }
    if extend {
        // Jh^T = J^T - W C, needed (full length) to extend the basis.
        kn.jht.clear();
        kn.jht.resize(n * m, 0.0);
        for c in 0..m {
            let dst = &mut kn.jht[c * n..(c + 1) * n];
            for (i, &d) in support.iter().enumerate() {
                dst[d] = kn.jts[c * s + i];
            }
            for j in 0..r {
                let a = kn.coeffs[c * r + j];
                if a != 0.0 {
                    axpy(-a, &kn.w[j * n..(j + 1) * n], dst);
                }
            }
        }
    }
    kn.all_rows = all;
    // y = (G + lambda^2 I)^-1 e, or the filtered eigen-solution.
    kn.y.clear();
    let mut solved = false;
    if let Damping::Constant { lambda } = params.damping
        && lambda > 0.0
    {
        kn.y.extend_from_slice(&kn.e);
        kn.l.clear();
        kn.l.extend_from_slice(&kn.g);
        for i in 0..m {
            kn.l[i * m + i] += lambda * lambda;
        }
        if cholesky(&mut kn.l, m) {
            cholesky_solve(&kn.l, m, &mut kn.y);
            solved = true;
        }
    }
    if !solved {
        let g = DMatrix::from_column_slice(m, m, &kn.g);
        let e = DVector::from_column_slice(&kn.e);
        let y = damped_solve(&g, &e, params.damping, tol);
        kn.y.clear();
        kn.y.extend_from_slice(y.as_slice());
    }
    // step = Jh^T y = J^T y - W (C y), scaled into what is left of the step budget.
    kn.step.clear();
    kn.step.resize(n, 0.0);
    let all = std::mem::take(&mut kn.all_rows);
    let support: &[usize] = if level.support.is_empty() {
        &all
    } else {
        &level.support
    };
    for c in 0..m {
        let yc = kn.y[c];
        if yc != 0.0 {
            let col = &kn.jts[c * s..(c + 1) * s];
            for (i, &d) in support.iter().enumerate() {
                kn.step[d] += yc * col[i];
            }
        }
    }
    kn.all_rows = all;
    for j in 0..r {
        let cy: f64 = (0..m).map(|c| kn.coeffs[c * r + j] * kn.y[c]).sum();
        if cy != 0.0 {
            axpy(-cy, &kn.w[j * n..(j + 1) * n], &mut kn.step);
        }
    }
    let max = kn.step.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    if max.is_finite() && kn.budget > 0.0 {
        let scale = if max > kn.budget {
            kn.budget / max
        } else {
            1.0
        };
        axpy(scale, &kn.step, &mut kn.theta);
        kn.budget -= scale * max;
    }
    if extend {
        kn.extend_basis(n, m, tol);
    }
}

impl Kernel {
    fn projector(&self, n: usize) -> DMatrix<f64> {
        let mut p = DMatrix::identity(n, n);
        for j in 0..self.rank {
            let wj = &self.w[j * n..(j + 1) * n];
            for a in 0..n {
                for b in 0..n {
                    p[(a, b)] -= wj[a] * wj[b];
                }
            }
        }
        p
    }

    /// Appends to `W` an orthonormal basis of the numerical column space of `Jh^T` (pivoted
    /// Gram-Schmidt). A column is projected on `W` once more when the projections so far
    /// removed more than `1 - 1/sqrt(2)` of its norm (the classical "twice is enough"
    /// criterion); a looser criterion (1e-3) saved ~15% of S2/S4 but broke the 1e-9 strict
    /// priority test on random trees.
    fn extend_basis(&mut self, n: usize, m: usize, tol: f64) {
        self.norms.clear();
        self.norms.extend((0..m).map(|c| {
            let col = &self.jht[c * n..(c + 1) * n];
            dot(col, col)
        }));
        self.used.clear();
        self.used.resize(m, false);
        let tol2 = tol * tol;
        while self.rank < n {
            let mut best = None;
            let mut best_norm = tol2;
            for c in 0..m {
                if !self.used[c] && self.norms[c] > best_norm {
                    best_norm = self.norms[c];
                    best = Some(c);
                }
            }
            let Some(c) = best else { break };
            self.used[c] = true;
            let r = self.rank;
            let original = self.col_norms.get(c).copied().unwrap_or(0.0);
            let (w_done, rest) = self.w.split_at_mut(r * n);
            let col = &mut self.jht[c * n..(c + 1) * n];
            if best_norm < 0.5 * original * original {
                for j in 0..r {
                    let wj = &w_done[j * n..(j + 1) * n];
                    let a = dot(wj, col);
                    axpy(-a, wj, col);
                }
            }
            let norm = dot(col, col).sqrt();
            if norm.is_nan() || norm <= tol {
                continue;
            }
            let new = &mut rest[..n];
            for (dst, v) in new.iter_mut().zip(col.iter()) {
                *dst = v / norm;
            }
            self.rank += 1;
            for c2 in 0..m {
                if !self.used[c2] {
                    let other = &mut self.jht[c2 * n..(c2 + 1) * n];
                    let a = dot(new, other);
                    axpy(-a, new, other);
                    self.norms[c2] = dot(other, other);
                }
            }
        }
    }
}
