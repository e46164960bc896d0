//! The step of a last level whose rows each select one DOF (posture attraction: `J = A S`,
//! `S` one unit row per DOF, `A = diag(a)` the rows' scale: the task's weight times the DOF's
//! stiffness scale), in closed form: O(k r nf + k^2 nf) instead of the Gram matrix and its
//! Cholesky of the general step (O(m^2 nf + m^3): with the 129 rows of retargeting's posture
//! level on the LOA 2 body, most of an iteration).
//!
//! In the coordinates of the free DOF, with `P` the projector the levels above leave and
//! `B = A S P`, the damped step `B^T (B B^T + l^2 I)^-1 e` is `(B^T B + l^2 I)^-1 P e~`, with
//! `e~ = S^T A e` (the level's scaled errors on the DOF its rows select). `S^T A^2 S = D` is
//! diagonal: `a_c^2` on the DOF row `c` selects, 0 on the free DOF no row selects. With `d`
//! its largest entry, `D = d I - E C E^T`, `E` the `k` free DOF whose `D_i` is not `d` and
//! `C = diag(d - D_i)`, so `B^T B = P D P = d P - U U^T`, `U = P E C^(1/2)`. Because `P` is
//! a projector, `(d P + l^2 I)^-1 = P / (d + l^2) + (I - P) / l^2`, and `U` and `u = P e~`
//! lie in its range: by Woodbury, with `s = 1 / (d + l^2)`,
//! `step = s u + s^2 U (I_k - s U^T U)^-1 U^T u`.
//!
//! A free DOF beyond every reflector of the basis (no level above reaches it) that no row
//! selects drops out: its column of `U` is a unit vector orthogonal to `u` and to the other
//! columns, and its share of the step is zero. Retargeting's posture level selects the
//! chains of the tasks above it; the head and the fingers are such DOF.

use super::{
    Kernel, NONE, add_step_within_budget, cholesky, cholesky_solve, dot, reflect,
    rotate_back_into_step,
};
use crate::priority::LevelSystem;

/// Takes the step of `level` by the closed form when its rows select distinct DOF (each
/// column of `J^T` has one nonzero) and `k` is at most a third of the free DOF (on the LOA 2
/// body, retargeting's posture level leaves out the root's translations and scales the stiff
/// spine and hips); damping `lambda > 0`. Returns whether it did (the caller takes the
/// general step if not).
pub(super) fn selection_step(kn: &mut Kernel, level: &LevelSystem, n: usize, lambda: f64) -> bool {
    let m = level.dx.len();
    let nf = kn.free.len();
    let jt = level.jacobian_t.as_slice();
    // Per free coordinate, `D_i` (`kn.norms`, 0 where no row selects it) and whether a row
    // selects it (`kn.used`); per row, its free coordinate (`kn.sup`, `NONE` where its DOF is
    // clamped) and scale (`kn.col_norms`).
    kn.norms.clear();
    kn.norms.resize(nf, 0.0);
    kn.used.clear();
    kn.used.resize(nf, false);
    kn.sup.clear();
    kn.col_norms.clear();
    for c in 0..m {
        let col = &jt[c * n..(c + 1) * n];
        let mut one = None;
        let rows: &mut dyn Iterator<Item = usize> = if level.support.is_empty() {
            &mut (0..n)
        } else {
            &mut level.support.iter().copied()
        };
        for d in rows {
            let a = col[d];
            if a == 0.0 {
                continue;
            }
            if one.is_some() || !a.is_finite() {
                return false;
            }
            one = Some((d, a));
        }
        let Some((d, a)) = one else { return false };
        let at = kn.pos[d];
        if at != NONE {
            if kn.used[at] {
                return false;
            }
            kn.used[at] = true;
            kn.norms[at] = a * a;
        }
        kn.sup.push(at);
        kn.col_norms.push(a);
    }
    let most = kn.norms.iter().copied().fold(0.0, f64::max);
    let reach = kn.v_end[..kn.rank].iter().copied().max().unwrap_or(0);
    let left_out = |i: usize, kn: &Kernel| kn.norms[i] != most && (i < reach || kn.used[i]);
    let k = (0..nf).filter(|&i| left_out(i, kn)).count();
    if most <= 0.0 || 3 * k > nf {
        return false;
    }
    let shrink = 1.0 / (most + lambda * lambda);
    // u = P e~, in the rotated coordinates (Q^T, its first r entries zero).
    kn.red.clear();
    kn.red.resize(nf, 0.0);
    for c in 0..m {
        let at = kn.sup[c];
        if at != NONE {
            let a = kn.col_norms[c];
            kn.red[at] = a * (level.dx[c] - a * kn.theta[kn.free[at]]);
        }
    }
    rotate(kn, Column::Red);
    // U = P E C^(1/2), column by column in `kn.z` (nf x k).
    kn.z.clear();
    kn.z.resize(nf * k, 0.0);
    let mut col = 0;
    for i in 0..nf {
        if left_out(i, kn) {
            kn.z[col * nf + i] = (most - kn.norms[i]).sqrt();
            rotate(kn, Column::Z(col));
            col += 1;
        }
    }
    // (I_k - s U^T U) b = s^2 U^T u.
    kn.l.clear();
    kn.l.resize(k * k, 0.0);
    kn.y.clear();
    for a in 0..k {
        let ua = &kn.z[a * nf..(a + 1) * nf];
        for b in a..k {
            let v = -shrink * dot(ua, &kn.z[b * nf..(b + 1) * nf]);
            kn.l[b * k + a] = v;
            kn.l[a * k + b] = v;
        }
        kn.l[a * k + a] += 1.0;
        kn.y.push(shrink * shrink * dot(ua, &kn.red));
    }
    if !cholesky(&mut kn.l, k) {
        return false;
    }
    cholesky_solve(&kn.l, k, &mut kn.y);
    for x in &mut kn.red {
        *x *= shrink;
    }
    for a in 0..k {
        let b = kn.y[a];
        for (x, u) in kn.red.iter_mut().zip(&kn.z[a * nf..(a + 1) * nf]) {
            *x += b * u;
        }
    }
    rotate_back_into_step(kn, n);
    add_step_within_budget(kn);
    #[cfg(test)]
    TAKEN.with(|taken| taken.set(taken.get() + 1));
    true
}

/// Which buffer [`rotate`] turns.
enum Column {
    Red,
    Z(usize),
}

/// `Q^T x` with its first `r` entries zeroed: `x` written in the rotated coordinates, then
/// projected (`P x` there).
fn rotate(kn: &mut Kernel, which: Column) {
    let nf = kn.free.len();
    let x = match which {
        Column::Red => &mut kn.red[..],
        Column::Z(col) => &mut kn.z[col * nf..(col + 1) * nf],
    };
    for j in 0..kn.rank {
        let end = kn.v_end[j];
        reflect(&kn.v[j * nf + j..j * nf + end], kn.beta[j], &mut x[j..end]);
    }
    x[..kn.rank].fill(0.0);
}

#[cfg(test)]
thread_local! {
    /// Steps taken by the closed form (tests: the general step gives the same numbers).
    pub(super) static TAKEN: std::cell::Cell<usize> = const { std::cell::Cell::new(0) };
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

    use nalgebra::{DMatrix, DVector};
    use rand::rngs::StdRng;
    use rand::{RngExt, SeedableRng};

    use super::TAKEN;
    use crate::kernel::{StepWorkspace, prioritized_step};
    use crate::priority::{Damping, LevelSystem, StepParams};

    /// The textbook recursion, dense, from the formulas alone: `dtheta_k = dtheta_{k-1} +
    /// (J_k P_{k-1})^+ (e_k - J_k dtheta_{k-1})` with the damped pseudo-inverse
    /// `A^T (A A^T + l^2 I)^-1` and `P_k` the projector onto the null space of the rows of the
    /// levels so far (by singular values); clamped DOF have zero columns and their fixed
    /// moves are taken from every level's error.
    fn textbook(
        levels: &[(DMatrix<f64>, DVector<f64>)],
        lambda: f64,
        clamped: &[bool],
        fixed: &DVector<f64>,
    ) -> DVector<f64> {
        let n = clamped.len();
        let free = DMatrix::from_fn(n, n, |i, j| if i == j && !clamped[i] { 1.0 } else { 0.0 });
        let mut theta = DVector::zeros(n);
        let mut p = free.clone();
        let mut stacked = DMatrix::zeros(0, n);
        for (j, dx) in levels {
            let e = dx - j * fixed - j * &theta;
            let jf = j * &free;
            let a = &jf * &p;
            let g = &a * a.transpose() + DMatrix::identity(j.nrows(), j.nrows()) * lambda * lambda;
            theta += a.transpose() * g.lu().solve(&e).unwrap();
            stacked = DMatrix::from_fn(stacked.nrows() + j.nrows(), n, |r, c| {
                if r < stacked.nrows() {
                    stacked[(r, c)]
                } else {
                    jf[(r - stacked.nrows(), c)]
                }
            });
            let svd = stacked.clone().svd(false, true);
            let v_t = svd.v_t.unwrap();
            p = free.clone();
            for (k, &sigma) in svd.singular_values.iter().enumerate() {
                if sigma > 1e-9 {
                    let v = v_t.row(k).transpose();
                    p -= &v * v.transpose();
                }
            }
        }
        theta
    }

    /// Catches a closed form that is not the damped step of the posture level (a wrong sign
    /// or scale in the Woodbury correction, a left-out DOF forgotten, the rows' scale applied
    /// once instead of twice, a clamped DOF's fixed move not taken from the error): random
    /// bodies with one or two levels above on part of the DOF, a last level selecting most
    /// DOF with scales like stiffness gives them, some DOF clamped, against the textbook
    /// recursion; the closed form must have been taken.
    #[test]
    fn the_closed_form_is_the_textbook_step_of_a_selection_level() {
        let lambda = 0.05;
        let params = StepParams {
            damping: Damping::Constant { lambda },
            rank_tolerance: 1e-10,
            max_dof_step: f64::INFINITY,
        };
        let mut r = StdRng::seed_from_u64(7);
        let before = TAKEN.with(std::cell::Cell::get);
        for case in 0..60 {
            let n = r.random_range(12..40);
            // The levels above reach the first `reach` DOF only (the head's DOF stay out).
            let reach = r.random_range(n / 2..=n);
            let mut above = Vec::new();
            for _ in 0..1 + case % 2 {
                let rows = r.random_range(2..5);
                let j = DMatrix::from_fn(rows, n, |_, c| {
                    if c < reach {
                        r.random_range(-1.0..1.0)
                    } else {
                        0.0
                    }
                });
                let dx = DVector::from_fn(rows, |_, _| r.random_range(-0.2..0.2));
                above.push((j, dx));
            }
            // The selection: every DOF but a few, scale 1 but for a few stiff ones; the
            // largest scale below 1 in some cases (a task weight).
            let top = if case % 3 == 0 { 0.7 } else { 1.0 };
            let mut rows: Vec<(usize, f64)> = Vec::new();
            for d in 0..n {
                if r.random_range(0.0..1.0) < 0.1 {
                    continue;
                }
                let a = if r.random_range(0.0..1.0) < 0.12 {
                    r.random_range(0.2..top)
                } else {
                    top
                };
                rows.push((d, if case % 5 == 0 { -a } else { a }));
            }
            let mut select = DMatrix::zeros(rows.len(), n);
            for (row, &(d, a)) in rows.iter().enumerate() {
                select[(row, d)] = a;
            }
            let target = DVector::from_fn(rows.len(), |_, _| r.random_range(-0.3..0.3));
            let clamped: Vec<bool> = (0..n).map(|d| case % 4 == 1 && d % 7 == 3).collect();
            let fixed = DVector::from_fn(n, |d, _| if clamped[d] { 0.02 } else { 0.0 });
            let mut levels: Vec<LevelSystem> = above
                .iter()
                .map(|(j, dx)| LevelSystem {
                    level: 0,
                    jacobian_t: j.transpose(),
                    dx: dx.clone(),
                    support: (0..reach).collect(),
                    damping: None,
                    projection: false,
                })
                .collect();
            levels.push(LevelSystem {
                level: 0,
                jacobian_t: select.transpose(),
                dx: target.clone(),
                support: rows.iter().map(|&(d, _)| d).collect(),
                damping: None,
                projection: false,
            });
            let any_clamped = clamped.iter().any(|&c| c);
            let mut ws = StepWorkspace::default();
            let step = prioritized_step(
                &levels,
                n,
                &params,
                any_clamped.then_some(clamped.as_slice()),
                any_clamped.then_some(&fixed),
                &mut ws,
                None,
            );
            let mut all = above.clone();
            all.push((select, target));
            let expected = textbook(&all, lambda, &clamped, &fixed);
            let off = (&step - &expected).amax();
            assert!(
                off < 1e-9 * expected.amax().max(1.0),
                "case {case}: {off:e}"
            );
        }
        // Where more than a third of the free DOF are left out or scaled, the general step
        // runs (a few small bodies here).
        let taken = TAKEN.with(std::cell::Cell::get) - before;
        assert!(taken >= 50, "the closed form took {taken} of 60 steps");
    }
}
