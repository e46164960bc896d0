//! The prioritized step on plain contiguous slices: the solver's hot path.
//!
//! Same mathematics as [`crate::prioritized_step_nalgebra`] (see `priority.rs` for the
//! derivation): `P_k = I - W_k W_k^T` with `W` an orthonormal basis of the row space of the
//! augmented Jacobian, grown level by level by a column-pivoted, rank-revealing QR of
//! `Jh_k^T`; per-level damped least squares through `G = J P J^T` and a Cholesky solve;
//! sparsity of the Jacobian rows exploited. Here `W` is kept implicitly as Householder
//! reflectors on the free (unclamped) DOF instead of the explicit Gram-Schmidt basis of the
//! nalgebra version: orthogonal to machine precision without re-orthogonalisation, and about
//! half the work per level (`Q^T J^T` gives `P J^T` and `G` at once). The matrices are small
//! (N <= ~100, m_k <= ~60) and reused every iteration; column-major slices with unrolled dot
//! products avoid the per-call allocations and bounds checks of the dynamic-matrix version.

use nalgebra::{DMatrix, DVector};

use crate::priority::{Damping, LevelSystem, StepParams, StepWorkspace, damped_solve};

mod selection;

/// Marks a clamped DOF in `Kernel::pos`.
const NONE: usize = usize::MAX;

/// Buffers of the kernel (all column-major).
///
/// The projector is kept as Householder reflectors: `P_k = Q diag(0_r, I) Q^T` with
/// `Q = H_0 H_1 ... H_{r-1}`, `H_j = I - beta_j v_j v_j^T`, `v_j` zero above entry `j`, in the
/// coordinates of the free (unclamped) DOF. `W_k = Q[:, ..r]` is the orthonormal basis of the
/// row space of the augmented Jacobian of `priority.rs`; it is never formed.
#[derive(Debug, Clone, Default)]
pub(crate) struct Kernel {
    /// Householder vectors, `nf x nf`: column `j` holds `v_j` in rows `j..nf`.
    v: Vec<f64>,
    beta: Vec<f64>,
    /// One past the last nonzero row of each `v_j`: a reflector built from a level whose
    /// support is a few DOF only touches those rows (see `order_free_dof`).
    v_end: Vec<usize>,
    rank: usize,
    /// Free DOF (reduced coordinate -> DOF) and its inverse (`NONE` for clamped DOF).
    free: Vec<usize>,
    pos: Vec<usize>,
    /// The level's support rows of free DOF, and `J^T` on them (`s x m`).
    sup: Vec<usize>,
    /// The reduced coordinate of each support row.
    sup_at: Vec<usize>,
    jts: Vec<f64>,
    /// `Q^T J^T` in reduced coordinates (`nf x m`).
    z: Vec<f64>,
    g: Vec<f64>,
    l: Vec<f64>,
    e: Vec<f64>,
    y: Vec<f64>,
    col_norms: Vec<f64>,
    norms: Vec<f64>,
    used: Vec<bool>,
    theta: Vec<f64>,
    step: Vec<f64>,
    red: Vec<f64>,
    budget: f64,
    /// Where the last level stepped was a projection level that did not extend the basis:
    /// its index and the step budget left before it (see [`project_last_again`]).
    last_projection: Option<(usize, f64)>,
    /// A level stepped without extending the basis, for a projection level after it to pass
    /// through by its Gram matrix (see [`projection_past_deferred`]): its `Z` and `G` stay in
    /// `z` and `g`.
    deferred: Option<Deferred>,
    /// A projection level's rows in the rotated coordinates (`nf x m`), beside `z`.
    zc: Vec<f64>,
}

/// A level whose reflectors are not (yet) in the basis: its row count, rank tolerance and
/// largest row norm.
#[derive(Debug, Clone, Copy)]
struct Deferred {
    m: usize,
    tol: f64,
    row_scale: f64,
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

/// In-place Cholesky `A = U^T U` of the symmetric `m x m` column-major `a` (upper triangle
/// used; `U` overwrites it, so that every inner product reads contiguous columns). False when
/// not positive definite.
fn cholesky(a: &mut [f64], m: usize) -> bool {
    for j in 0..m {
        let (done, rest) = a.split_at_mut(j * m);
        let colj = &mut rest[..m];
        for i in 0..j {
            let coli = &done[i * m..i * m + i + 1];
            let v = colj[i] - dot(&coli[..i], &colj[..i]);
            colj[i] = v / coli[i];
        }
        let d = colj[j] - dot(&colj[..j], &colj[..j]);
        if d.is_nan() || d <= 0.0 || !d.is_finite() {
            return false;
        }
        colj[j] = d.sqrt();
    }
    true
}

/// Solves `U^T U y = b` in place in `b` (`u` from [`cholesky`]).
fn cholesky_solve(u: &[f64], m: usize, b: &mut [f64]) {
    for i in 0..m {
        let col = &u[i * m..i * m + i + 1];
        b[i] = (b[i] - dot(&col[..i], &b[..i])) / col[i];
    }
    for i in (0..m).rev() {
        let col = &u[i * m..i * m + i + 1];
        let yi = b[i] / col[i];
        b[i] = yi;
        if yi != 0.0 {
            axpy(-yi, &col[..i], &mut b[..i]);
        }
    }
}

/// Applies `H = I - beta v v^T` to `x` (same length as `v`).
#[inline]
fn reflect(v: &[f64], beta: f64, x: &mut [f64]) {
    let t = beta * dot(v, x);
    if t != 0.0 {
        axpy(-t, v, x);
    }
}

/// Applies `H = I - beta v v^T` to `x` and returns the squared norm of the result without
/// its first entry (the remaining norm of a column in a pivoted QR step).
#[inline]
fn reflect_norm(v: &[f64], beta: f64, x: &mut [f64]) -> f64 {
    let t = beta * dot(v, x);
    let mut acc = [0.0f64; 2];
    let mut tail = 0.0;
    if let Some((first, rest)) = x.split_first_mut() {
        *first -= t * v[0];
        let vr = &v[1..];
        let mut cx = rest.chunks_exact_mut(2);
        let mut cv = vr.chunks_exact(2);
        for (xs, vs) in (&mut cx).zip(&mut cv) {
            xs[0] -= t * vs[0];
            xs[1] -= t * vs[1];
            acc[0] += xs[0] * xs[0];
            acc[1] += xs[1] * xs[1];
        }
        for (xi, vi) in cx.into_remainder().iter_mut().zip(cv.remainder()) {
            *xi -= t * vi;
            tail += *xi * *xi;
        }
    }
    acc[0] + acc[1] + tail
}

/// Applies `H = I - beta v v^T` to four vectors at once (one pass over `v` per phase).
#[inline]
fn reflect4(v: &[f64], beta: f64, x: [&mut [f64]; 4]) {
    let [x0, x1, x2, x3] = x;
    let n = v
        .len()
        .min(x0.len())
        .min(x1.len())
        .min(x2.len())
        .min(x3.len());
    let (v, x0, x1, x2, x3) = (
        &v[..n],
        &mut x0[..n],
        &mut x1[..n],
        &mut x2[..n],
        &mut x3[..n],
    );
    let mut a = [0.0f64; 8];
    let mut i = 0;
    while i + 2 <= n {
        let (v0, v1) = (v[i], v[i + 1]);
        a[0] += v0 * x0[i];
        a[1] += v1 * x0[i + 1];
        a[2] += v0 * x1[i];
        a[3] += v1 * x1[i + 1];
        a[4] += v0 * x2[i];
        a[5] += v1 * x2[i + 1];
        a[6] += v0 * x3[i];
        a[7] += v1 * x3[i + 1];
        i += 2;
    }
    if i < n {
        let vi = v[i];
        a[0] += vi * x0[i];
        a[2] += vi * x1[i];
        a[4] += vi * x2[i];
        a[6] += vi * x3[i];
    }
    let t = [
        beta * (a[0] + a[1]),
        beta * (a[2] + a[3]),
        beta * (a[4] + a[5]),
        beta * (a[6] + a[7]),
    ];
    for i in 0..n {
        let vi = v[i];
        x0[i] -= t[0] * vi;
        x1[i] -= t[1] * vi;
        x2[i] -= t[2] * vi;
        x3[i] -= t[3] * vi;
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
/// The projector is kept as Householder reflectors on the free DOF (see `Kernel`): the
/// recursive update `P_k = P_{k-1} - Jh_k^+ Jh_k` appends the reflectors of a pivoted,
/// rank-revealing Householder QR of `Jh_k^T` written in the rotated coordinates
/// (`Q^T P_{k-1} J_k^T = [0; Z]`), which keeps `W` orthonormal to machine precision without
/// re-orthogonalisation. `G = Jh Jh^T = Z^T Z`.
///
/// Sparsity: only the rows of `J_k^T` listed in `LevelSystem::support` are read (a Jacobian
/// column is zero for DOF that are not ancestors of the effector); `G` is symmetric and only
/// half is computed. Once the projector has full rank, the remaining levels are skipped (a
/// projection level past a deferred level still runs: its step is then about zero).
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
    order_free_dof(kn, levels, n, clamped);
    let nf = kn.free.len();
    // Column j of `v` is only read in rows j.., which `extend_basis` writes before any read:
    // stale values elsewhere are never seen, so the buffer is not cleared.
    kn.v.resize(nf * nf, 0.0);
    kn.beta.clear();
    kn.beta.resize(nf, 0.0);
    kn.v_end.clear();
    kn.v_end.resize(nf, nf);
    kn.rank = 0;
    kn.theta.clear();
    kn.theta.resize(n, 0.0);
    kn.budget = params.max_dof_step;
    kn.last_projection = None;
    kn.deferred = None;
    let last_with_rows = levels.iter().rposition(has_work);
    // A projection level last, after a regular one: that level's basis is left unbuilt, and
    // the projection passes through it by its Gram matrix (cheaper than its reflectors).
    let deferred = last_with_rows
        .filter(|&k| levels[k].projection && projectors.is_none())
        .and_then(|k| levels[..k].iter().rposition(has_work))
        .filter(|&k| !levels[k].projection);
    for (k, level) in levels.iter().enumerate() {
        let m = level.dx.len();
        let usable = has_work(level) && level.jacobian_t.shape() == (n, m) && kn.rank < nf;
        if usable {
            let extend = Some(k) != last_with_rows || projectors.is_some();
            if level.projection && !extend {
                kn.last_projection = Some((k, kn.budget));
            }
            if Some(k) == deferred {
                level_step(kn, level, n, params, fixed, Step::Deferred);
            } else if level.projection && kn.deferred.is_some() {
                projection_past_deferred(kn, level, n, params);
            } else {
                level_step(kn, level, n, params, fixed, Step::with_basis(extend));
            }
        }
        if let Some(p) = projectors.as_deref_mut() {
            p.push(kn.projector(n));
        }
        partial[k].as_mut_slice().copy_from_slice(&kn.theta);
    }
    *ws.partial_mut() = partial;
    DVector::from_column_slice(&ws.kernel.theta)
}

/// After [`prioritized_step`] whose last level with a step is the projection level `last`
/// (the comfort task): that level's share taken again with the DOF `blocked` also held (their unit
/// rows appended to the basis of the levels above: a share that stays off them and out of the
/// way of the levels above), on top of the step of the levels above, which stays as it was.
/// Returns the whole step; `None` where the workspace holds no such step. Cheaper than
/// clamping the blocked DOF and taking every level's step again.
pub(crate) fn project_last_again(
    levels: &[LevelSystem],
    last: usize,
    n: usize,
    params: &StepParams,
    blocked: &[usize],
    ws: &mut StepWorkspace,
) -> Option<DVector<f64>> {
    let (k, budget) = ws.kernel.last_projection.filter(|&(k, _)| k == last)?;
    let level = levels.get(k)?;
    let above = ws.partial_steps().get(k.checked_sub(1)?)?.clone();
    let kn = &mut ws.kernel;
    if let Some(Deferred { m, tol, .. }) = kn.deferred.take() {
        // The level before goes into the basis after all (its `Z` and `G` are still there).
        kn.extend_basis(m, tol);
    }
    let mut support: Vec<usize> = blocked
        .iter()
        .copied()
        .filter(|&d| kn.pos.get(d).is_some_and(|&p| p != NONE))
        .collect();
    support.sort_unstable();
    support.dedup();
    if above.len() != n || kn.theta.len() != n || support.is_empty() {
        return None;
    }
    let mut jacobian_t = DMatrix::zeros(n, support.len());
    for (c, &d) in support.iter().enumerate() {
        jacobian_t[(d, c)] = 1.0;
    }
    let held = LevelSystem {
        level: level.level,
        jacobian_t,
        dx: DVector::zeros(support.len()),
        support,
        damping: None,
        projection: true,
    };
    kn.theta.copy_from_slice(above.as_slice());
    kn.budget = budget;
    // A projection level with a zero `dx`: no step, the basis extended by the held DOF.
    level_step(kn, &held, n, params, None, Step::Extend);
    if kn.rank < kn.free.len() {
        level_step(kn, level, n, params, None, Step::Last);
    }
    let step = DVector::from_column_slice(&kn.theta);
    if let Some(last) = ws.partial_mut().get_mut(k) {
        last.copy_from(&step);
    }
    Some(step)
}

/// A projection level (a cost's gradient) with a zero step adds nothing: a comfort level
/// waiting for the levels above it.
fn has_work(l: &LevelSystem) -> bool {
    !l.dx.is_empty() && (!l.projection || l.dx.iter().any(|v| *v != 0.0))
}

/// The free (unclamped) DOF in the order the levels first reach them: the support of the
/// first level, then what the second adds, and so on (the DOF no level reaches last). A
/// level's Jacobian columns then live in the leading rows of the reduced coordinates, and so
/// do the reflectors built from them (`Kernel::v_end`): applying the basis of a first level
/// on the feet costs the legs' rows, not the whole body's. (A permutation of coordinates: the
/// projectors and the step are the same.)
fn order_free_dof(kn: &mut Kernel, levels: &[LevelSystem], n: usize, clamped: Option<&[bool]>) {
    let is_clamped = |d: usize| clamped.is_some_and(|mask| mask.get(d).copied().unwrap_or(false));
    kn.pos.clear();
    kn.pos.resize(n, NONE);
    kn.free.clear();
    for level in levels.iter().filter(|l| has_work(l)) {
        if level.support.is_empty() {
            break;
        }
        for &d in &level.support {
            if d < n && kn.pos[d] == NONE && !is_clamped(d) {
                kn.pos[d] = kn.free.len();
                kn.free.push(d);
            }
        }
    }
    for d in 0..n {
        if kn.pos[d] == NONE && !is_clamped(d) {
            kn.pos[d] = kn.free.len();
            kn.free.push(d);
        }
    }
}

/// What a level's step leaves of the basis.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Step {
    /// The basis as it was (the last level).
    Last,
    /// Extended by the level's rows.
    Extend,
    /// As it was, the level's `Z` and `G` kept for a projection level after it.
    Deferred,
}

impl Step {
    fn with_basis(extend: bool) -> Self {
        if extend { Self::Extend } else { Self::Last }
    }
}

fn level_step(
    kn: &mut Kernel,
    level: &LevelSystem,
    n: usize,
    params: &StepParams,
    fixed: Option<&DVector<f64>>,
    basis: Step,
) {
    let extend = basis == Step::Extend;
    // The last level of a retargeting's frame (the clip's posture, one row per DOF): its
    // step in closed form.
    if basis == Step::Last
        && !level.projection
        && let Damping::Constant { lambda } = level
            .damping
            .unwrap_or(params.damping)
            .at_error(level.dx.norm())
        && lambda > 0.0
        && selection::selection_step(kn, level, n, lambda)
    {
        return;
    }
    let m = level.dx.len();
    let r = kn.rank;
    let nf = kn.free.len();
    let jt = level.jacobian_t.as_slice();
    // Support rows of the free DOF.
    kn.sup.clear();
    if level.support.is_empty() {
        kn.sup.extend_from_slice(&kn.free);
    } else {
        kn.sup
            .extend(level.support.iter().copied().filter(|&d| kn.pos[d] != NONE));
    }
    let s = kn.sup.len();
    // J^T on the support rows: jts (s x m).
    kn.jts.clear();
    kn.jts.resize(s * m, 0.0);
    for c in 0..m {
        let src = &jt[c * n..(c + 1) * n];
        let dst = &mut kn.jts[c * s..(c + 1) * s];
        for (x, &d) in dst.iter_mut().zip(&kn.sup) {
            *x = src[d];
        }
    }
    kn.col_norms.clear();
    for c in 0..m {
        let col = &kn.jts[c * s..(c + 1) * s];
        kn.col_norms.push(dot(col, col).sqrt());
    }
    // e = dx - J (theta + fixed): theta lives on the free DOF, `fixed` (the moves of clamped
    // DOF onto their limits) on the clamped ones, whose columns are read from the full J^T. A
    // projection level's rows are scaled by `dx` as they are, never solved for: no `e`.
    kn.e.clear();
    if !level.projection {
        kn.y.clear();
        kn.y.extend(kn.sup.iter().map(|&d| kn.theta[d]));
        kn.e.extend_from_slice(level.dx.as_slice());
        for c in 0..m {
            kn.e[c] -= dot(&kn.jts[c * s..(c + 1) * s], &kn.y);
        }
    }
    if let Some(fixed) = fixed.filter(|_| !level.projection) {
        let clamped_rows = |d: &usize| kn.pos[*d] == NONE && fixed[*d] != 0.0;
        let support: &[usize] = if level.support.is_empty() {
            &[]
        } else {
            &level.support
        };
        for c in 0..m {
            let full = &jt[c * n..(c + 1) * n];
            let moved: f64 = if level.support.is_empty() {
                (0..n)
                    .filter(clamped_rows)
                    .map(|d| full[d] * fixed[d])
                    .sum()
            } else {
                support
                    .iter()
                    .filter(|d| clamped_rows(d))
                    .map(|&d| full[d] * fixed[d])
                    .sum()
            };
            kn.e[c] -= moved;
        }
    }
    let row_scale = kn.col_norms.iter().copied().fold(0.0, f64::max);
    if row_scale.is_nan() || row_scale <= 0.0 || !row_scale.is_finite() {
        return;
    }
    let tol = params.rank_tolerance * row_scale;
    kn.g.clear();
    kn.g.resize(m * m, 0.0);
    let need_z = r > 0 || basis != Step::Last;
    if need_z {
        // Z = Q^T J^T in reduced coordinates; its rows r.. are the coordinates of Jh^T = P J^T.
        kn.z.clear();
        kn.z.resize(nf * m, 0.0);
        // The support rows' reduced coordinates, once (read through locals: the loop then
        // keeps them in registers instead of reloading the kernel's fields per entry).
        kn.sup_at.clear();
        kn.sup_at.extend(kn.sup.iter().map(|&d| kn.pos[d]));
        let (z, jts, sup_at) = (&mut kn.z, &kn.jts, &kn.sup_at);
        for (dst, src) in z.chunks_exact_mut(nf).zip(jts.chunks_exact(s.max(1))) {
            for (&at, &x) in sup_at.iter().zip(src) {
                dst[at] = x;
            }
        }
        for j in 0..r {
            let end = kn.v_end[j];
            let vj = &kn.v[j * nf + j..j * nf + end];
            let bj = kn.beta[j];
            let mut blocks = kn.z.chunks_exact_mut(4 * nf);
            for block in &mut blocks {
                let (a, rest) = block.split_at_mut(nf);
                let (b, rest) = rest.split_at_mut(nf);
                let (c, d) = rest.split_at_mut(nf);
                reflect4(
                    vj,
                    bj,
                    [
                        &mut a[j..end],
                        &mut b[j..end],
                        &mut c[j..end],
                        &mut d[j..end],
                    ],
                );
            }
            for col in blocks.into_remainder().chunks_exact_mut(nf) {
                reflect(vj, bj, &mut col[j..end]);
            }
        }
    }
    // G = Jh Jh^T = Z[r.., :]^T Z[r.., :] (= J J^T on the support when r = 0); a projection
    // level needs it only to extend the basis.
    let need_g = !level.projection || extend;
    for a in (0..m).filter(|_| need_g) {
        for b in a..m {
            let v = if r == 0 {
                dot(&kn.jts[a * s..(a + 1) * s], &kn.jts[b * s..(b + 1) * s])
            } else {
                dot(
                    &kn.z[a * nf + r..(a + 1) * nf],
                    &kn.z[b * nf + r..(b + 1) * nf],
                )
            };
            kn.g[b * m + a] = v;
            kn.g[a * m + b] = v;
        }
    }
    // y = (G + lambda^2 I)^-1 e, or the filtered eigen-solution; for a projection level
    // (cost gradients) y = dx: the rows projected, scaled, not inverted.
    kn.y.clear();
    let mut solved = false;
    if level.projection {
        kn.y.extend_from_slice(level.dx.as_slice());
        solved = true;
    }
    let damping = level
        .damping
        .unwrap_or(params.damping)
        .at_error(level.dx.norm());
    if !solved
        && let Damping::Constant { lambda } = damping
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
        let y = damped_solve(&g, &e, damping, tol);
        kn.y.clear();
        kn.y.extend_from_slice(y.as_slice());
    }
    // step = Jh^T y = Q [0; Z[r.., :] y] (= J^T y when r = 0), scaled into what is left of the
    // step budget.
    if r == 0 {
        kn.step.clear();
        kn.step.resize(n, 0.0);
        for c in 0..m {
            let yc = kn.y[c];
            if yc != 0.0 {
                let col = &kn.jts[c * s..(c + 1) * s];
                for (x, &d) in col.iter().zip(&kn.sup) {
                    kn.step[d] += yc * x;
                }
            }
        }
    } else {
        kn.red.clear();
        kn.red.resize(nf, 0.0);
        for c in 0..m {
            let yc = kn.y[c];
            if yc != 0.0 {
                axpy(yc, &kn.z[c * nf + r..(c + 1) * nf], &mut kn.red[r..]);
            }
        }
        rotate_back_into_step(kn, n);
    }
    add_step_within_budget(kn);
    match basis {
        Step::Extend => kn.extend_basis(m, tol),
        Step::Deferred => {
            kn.deferred = Some(Deferred { m, tol, row_scale });
        }
        Step::Last => {}
    }
}

/// A projection level's step past the deferred level (`kn.deferred`): its rows rotated by
/// the basis of the levels before (`Q^T z`), less their part in the deferred level's row
/// space, solved through that level's Gram matrix `G = Z^T Z` (the same space its pivoted QR
/// would add to the basis), rotated back, times `dx`. Where `G` is near singular, the basis
/// is extended after all and the level takes the plain path. Writes neither `z` nor `g`.
fn projection_past_deferred(kn: &mut Kernel, level: &LevelSystem, n: usize, params: &StepParams) {
    let Some(Deferred {
        m: md,
        tol,
        row_scale,
    }) = kn.deferred
    else {
        return;
    };
    let (r, nf, m) = (kn.rank, kn.free.len(), level.dx.len());
    // The Gram matrix's Cholesky factor, where every pivot (the norm a row keeps past the ones
    // before it) stays above 1e-4 of the largest row norm and far above the rank tolerance:
    // its rounding grows with the square of the level's condition number. Else the pivoted
    // QR's rank decision, through the basis.
    kn.l.clear();
    kn.l.extend_from_slice(&kn.g[..md * md]);
    let floor = (1e-4 * row_scale).max(1e3 * tol);
    if !(cholesky(&mut kn.l, md) && (0..md).all(|i| kn.l[i * md + i] > floor)) {
        kn.extend_basis(md, tol);
        kn.deferred = None;
        level_step(kn, level, n, params, None, Step::Last);
        return;
    }
    // `kn.deferred` stays: `project_last_again` extends the basis by it (`z` and `g` stay).
    let jt = level.jacobian_t.as_slice();
    kn.zc.clear();
    kn.zc.resize(nf * m, 0.0);
    for c in 0..m {
        let (src, dst) = (&jt[c * n..(c + 1) * n], &mut kn.zc[c * nf..(c + 1) * nf]);
        for (&d, x) in kn.free.iter().zip(dst.iter_mut()) {
            *x = src[d];
        }
        for j in 0..r {
            let end = kn.v_end[j];
            reflect(
                &kn.v[j * nf + j..j * nf + end],
                kn.beta[j],
                &mut dst[j..end],
            );
        }
    }
    // red = sum_c dx_c (y_c - Z G^-1 Z^T y_c), y_c = zc[r.., c].
    kn.red.clear();
    kn.red.resize(nf, 0.0);
    for c in 0..m {
        let dx = level.dx[c];
        if dx == 0.0 {
            continue;
        }
        let y = &kn.zc[c * nf + r..(c + 1) * nf];
        kn.y.clear();
        kn.y.extend((0..md).map(|a| dot(&kn.z[a * nf + r..(a + 1) * nf], y)));
        cholesky_solve(&kn.l, md, &mut kn.y);
        axpy(dx, y, &mut kn.red[r..]);
        for a in 0..md {
            axpy(
                -dx * kn.y[a],
                &kn.z[a * nf + r..(a + 1) * nf],
                &mut kn.red[r..],
            );
        }
    }
    rotate_back_into_step(kn, n);
    add_step_within_budget(kn);
}

/// `kn.step` = `Q kn.red`: a step in the rotated coordinates of the free DOF (`kn.red`, its
/// first `rank` entries zero) back in DOF coordinates.
fn rotate_back_into_step(kn: &mut Kernel, n: usize) {
    let nf = kn.free.len();
    for j in (0..kn.rank).rev() {
        let end = kn.v_end[j];
        reflect(
            &kn.v[j * nf + j..j * nf + end],
            kn.beta[j],
            &mut kn.red[j..end],
        );
    }
    kn.step.clear();
    kn.step.resize(n, 0.0);
    for (x, &d) in kn.red.iter().zip(&kn.free) {
        kn.step[d] = *x;
    }
}

/// Adds a level's step (`kn.step`) to `theta`, scaled into what is left of the step budget.
fn add_step_within_budget(kn: &mut Kernel) {
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
}

impl Kernel {
    /// `P = I - W W^T` in full DOF coordinates (`W = Q[:, ..r]`, clamped rows zero).
    fn projector(&self, n: usize) -> DMatrix<f64> {
        let nf = self.free.len();
        let mut p = DMatrix::identity(n, n);
        let mut w = vec![0.0; nf];
        for i in 0..self.rank {
            // Q e_i = H_0 ... H_i e_i.
            w.fill(0.0);
            w[i] = 1.0;
            for j in (0..=i).rev() {
                let end = self.v_end[j];
                reflect(
                    &self.v[j * nf + j..j * nf + end],
                    self.beta[j],
                    &mut w[j..end],
                );
            }
            for (a, &da) in self.free.iter().enumerate() {
                for (b, &db) in self.free.iter().enumerate() {
                    p[(da, db)] -= w[a] * w[b];
                }
            }
        }
        p
    }

    /// Appends to the reflectors a pivoted, rank-revealing Householder QR of the `m` columns
    /// of `Z[rank.., :]` (the coordinates of `Jh^T`): the column with the largest remaining
    /// norm first, stopping when it is at most `tol`. Same rank decision as pivoted
    /// Gram-Schmidt on `Jh^T`, orthogonal to machine precision.
    fn extend_basis(&mut self, m: usize, tol: f64) {
        let nf = self.free.len();
        self.norms.clear();
        self.norms.extend((0..m).map(|c| self.g[c * m + c]));
        self.used.clear();
        self.used.resize(m, false);
        let tol2 = tol * tol;
        while self.rank < nf {
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
            let i = self.rank;
            let x = &self.z[c * nf + i..(c + 1) * nf];
            let sigma = dot(x, x).sqrt();
            if sigma.is_nan() || sigma <= tol || !sigma.is_finite() {
                continue;
            }
            let x0 = x[0];
            let alpha = if x0 >= 0.0 { -sigma } else { sigma };
            let v0 = x0 - alpha;
            let beta = -1.0 / (alpha * v0);
            // The reflector's rows end where the column's nonzero rows end (`v_end`).
            let len = x.iter().rposition(|&e| e != 0.0).map_or(1, |last| last + 1);
            let dst = &mut self.v[i * nf + i..(i + 1) * nf];
            dst.copy_from_slice(x);
            dst[0] = v0;
            self.beta[i] = beta;
            self.v_end[i] = i + len;
            self.rank += 1;
            let vi = &self.v[i * nf + i..i * nf + i + len];
            for c2 in 0..m {
                if !self.used[c2] {
                    let other = &mut self.z[c2 * nf + i..(c2 + 1) * nf];
                    let (head, tail) = other.split_at_mut(len);
                    self.norms[c2] = reflect_norm(vi, beta, head) + dot(tail, tail);
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

    use nalgebra::{DMatrix, DVector};
    use rand::rngs::StdRng;
    use rand::{RngExt, SeedableRng};

    use super::{StepWorkspace, prioritized_step, project_last_again};
    use crate::priority::{Damping, LevelSystem, StepParams};

    fn level(jacobian: DMatrix<f64>, dx: DVector<f64>, projection: bool) -> LevelSystem {
        LevelSystem {
            level: 0,
            jacobian_t: jacobian.transpose(),
            dx,
            support: Vec::new(),
            damping: None,
            projection,
        }
    }

    /// `I - A^+ A`: the projector onto the null space of the rows of `a` (the textbook
    /// oracle, by singular values).
    fn null_space_projector(a: &DMatrix<f64>) -> DMatrix<f64> {
        let n = a.ncols();
        let svd = a.clone().svd(false, true);
        let v_t = svd.v_t.unwrap();
        let mut p = DMatrix::identity(n, n);
        for (k, &sigma) in svd.singular_values.iter().enumerate() {
            if sigma > 1e-9 {
                let v = v_t.row(k).transpose();
                p -= &v * v.transpose();
            }
        }
        p
    }

    #[test]
    fn a_projection_level_past_a_deferred_level_is_the_textbook_step() {
        let params = StepParams {
            damping: Damping::Constant { lambda: 0.01 },
            rank_tolerance: 1e-10,
            max_dof_step: f64::INFINITY,
        };
        let mut r = StdRng::seed_from_u64(12);
        for case in 0..80 {
            let n = r.random_range(8..24);
            let mut random =
                |rows: usize| DMatrix::from_fn(rows, n, |_, _| r.random_range(-1.0..1.0));
            let (j1, j2, mut j3, g) = (random(3), random(2), random(3), random(2));
            let nudge = random(1);
            match case % 4 {
                // A singular level before the projection: two equal rows.
                0 => {
                    let row = j3.row(0).clone_owned();
                    j3.row_mut(1).copy_from(&row);
                }
                // A near-singular one (condition about 1e6): through its basis after all.
                1 => {
                    let row = j3.row(0).clone_owned() + nudge * 1e-6;
                    j3.row_mut(1).copy_from(&row);
                }
                _ => {}
            }
            // Case 2: the deferred level is the first (no basis before it).
            let above_rows: Vec<(DMatrix<f64>, f64)> = if case % 4 == 2 {
                Vec::new()
            } else {
                vec![(j1.clone(), 0.1), (j2.clone(), -0.05)]
            };
            let mut levels: Vec<LevelSystem> = above_rows
                .iter()
                .map(|(j, dx)| level(j.clone(), DVector::from_element(j.nrows(), *dx), false))
                .collect();
            levels.push(level(j3.clone(), DVector::from_element(3, 0.07), false));
            let dx = DVector::from_vec(vec![0.2, -0.1]);
            levels.push(level(g.clone(), dx.clone(), true));
            let mut ws = StepWorkspace::default();
            let step = prioritized_step(&levels, n, &params, None, None, &mut ws, None);
            // The recursion with every level's basis built (as when projectors are asked for).
            let mut projectors = Vec::new();
            let mut oracle_ws = StepWorkspace::default();
            let built = prioritized_step(
                &levels,
                n,
                &params,
                None,
                None,
                &mut oracle_ws,
                Some(&mut projectors),
            );
            assert!(
                (&step - &built).amax() < 1e-10,
                "case {case}: {step} against {built}"
            );
            // The textbook projector of every level above the projection level.
            let mut rows = DMatrix::zeros(0, n);
            for (j, _) in &above_rows {
                rows = DMatrix::from_rows(&rows.row_iter().chain(j.row_iter()).collect::<Vec<_>>());
            }
            rows = DMatrix::from_rows(&rows.row_iter().chain(j3.row_iter()).collect::<Vec<_>>());
            let share = null_space_projector(&rows) * g.transpose() * dx;
            let above = &ws.partial_steps()[levels.len() - 2];
            assert!(
                (&(&step - above) - &share).amax() < 1e-8,
                "case {case}: the projection level's share"
            );
        }
    }

    #[test]
    fn a_projection_level_taken_again_stays_off_the_held_dof_and_out_of_the_way() {
        let params = StepParams {
            damping: Damping::Constant { lambda: 0.0 },
            rank_tolerance: 1e-10,
            max_dof_step: f64::INFINITY,
        };
        let mut r = StdRng::seed_from_u64(17);
        for case in 0..40 {
            let n = r.random_range(8..20);
            let mut random =
                |rows: usize| DMatrix::from_fn(rows, n, |_, _| r.random_range(-1.0..1.0));
            let (j1, j2, g) = (random(3), random(2), random(1));
            let levels = [
                level(j1.clone(), DVector::from_element(3, 0.1), false),
                level(j2.clone(), DVector::from_element(2, -0.05), false),
                level(g.clone(), DVector::from_element(1, 0.2), true),
            ];
            let mut ws = StepWorkspace::default();
            prioritized_step(&levels, n, &params, None, None, &mut ws, None);
            let above = ws.partial_steps()[1].clone();
            let first = &ws.partial_steps()[2] - &above;
            let held = [case % n, (case * 7 + 3) % n];
            // The first share moves the held DOF: holding them changes it.
            assert!(held.iter().any(|&d| first[d].abs() > 1e-6), "case {case}");
            let step = project_last_again(&levels, 2, n, &params, &held, &mut ws).unwrap();
            let share = &step - &above;
            // The oracle: the gradient row through the projector of the levels above and the
            // held DOF's unit rows, scaled by the level's dx.
            let mut rows = DMatrix::zeros(5 + held.len(), n);
            rows.rows_mut(0, 3).copy_from(&j1);
            rows.rows_mut(3, 2).copy_from(&j2);
            for (k, &d) in held.iter().enumerate() {
                rows[(5 + k, d)] = 1.0;
            }
            let expected = null_space_projector(&rows) * g.transpose() * 0.2;
            assert!(
                (&share - &expected).amax() < 1e-10,
                "case {case}: share {share} expected {expected}"
            );
            for &d in &held {
                assert!(share[d].abs() < 1e-12, "case {case}: held DOF {d} moved");
            }
            assert!((&j1 * &share).amax() < 1e-10 && (&j2 * &share).amax() < 1e-10);
            // The workspace's last partial step is the new whole step.
            assert!((&ws.partial_steps()[2] - &step).amax() < 1e-15);
        }
    }
}
