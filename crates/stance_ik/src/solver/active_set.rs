//! An inequality's rows as an active set (collision): a level holds rows only for the
//! constraints already violated; those near their bound wait as candidates, and a step that
//! would carry one past its bound is taken again with that constraint's row added at its
//! level, at the bound (see `Solver::compute_step`). A candidate never holds its surfaces from
//! parting: only a step that brings them closer than the bound adds its row.

use nalgebra::{DMatrix, DVector};

use super::Solver;
use crate::Skeleton;
use crate::priority::LevelSystem;

/// Below this predicted value (m) a candidate counts as carried past its bound.
const PAST_BOUND: f64 = 1e-9;

/// One level's candidate rows at its last linearisation, and what its system held then.
#[derive(Debug, Clone, Default)]
pub(super) struct Candidates {
    /// `J^T` of each candidate (`n` entries each, one after another).
    columns: Vec<f64>,
    /// Each candidate's bound: the linear change of its value that brings it to the bound
    /// (`<= 0`: the room left before the bound, negated).
    bounds: Vec<f64>,
    /// Whether each candidate's row is in the system now.
    added: Vec<bool>,
    /// The system's rows and support as linearised (before any candidate was added).
    rows: usize,
    support: Vec<usize>,
}

impl Candidates {
    /// Forgets the candidates before a new linearisation.
    pub(super) fn clear(&mut self) {
        self.columns.clear();
        self.bounds.clear();
        self.added.clear();
    }

    /// Keeps one candidate: its row `column` (`J^T`) and `bound` (see `bounds`).
    pub(super) fn push(&mut self, column: &[f64], bound: f64) {
        self.columns.extend_from_slice(column);
        self.bounds.push(bound);
        self.added.push(false);
    }

    /// Records what the linearised system `sys` holds, so that [`Candidates::restore`] can
    /// take the added rows out again.
    pub(super) fn linearised(&mut self, sys: &LevelSystem) {
        self.rows = sys.dx.len();
        self.support.clone_from(&sys.support);
    }

    fn is_empty(&self) -> bool {
        self.bounds.is_empty()
    }

    /// Takes the rows added to `sys` out again (a step computed afresh starts from the rows
    /// that were linearised).
    pub(super) fn restore(&mut self, sys: &mut LevelSystem) {
        if !self.added.iter().any(|&a| a) {
            return;
        }
        self.added.fill(false);
        let n = sys.jacobian_t.nrows();
        let mut jt: Vec<f64> = std::mem::take(&mut sys.jacobian_t).data.into();
        jt.truncate(self.rows * n);
        sys.jacobian_t = DMatrix::from_vec(n, self.rows, jt);
        let mut dx: Vec<f64> = std::mem::take(&mut sys.dx).data.into();
        dx.truncate(self.rows);
        sys.dx = DVector::from_vec(dx);
        sys.support.clone_from(&self.support);
    }

    /// Adds to `sys`, at their bound, the rows of the candidates that `step` carries past it
    /// (by the linear model); whether any was added.
    pub(super) fn add_crossed(&mut self, sys: &mut LevelSystem, step: &DVector<f64>) -> bool {
        if self.is_empty() {
            return false;
        }
        let n = step.len();
        // The candidate carried furthest past its bound.
        let mut deepest: Option<(usize, f64)> = None;
        for (k, (&bound, &added)) in self.bounds.iter().zip(&self.added).enumerate() {
            let Some(column) = self.columns.get(k * n..(k + 1) * n) else {
                break;
            };
            if added {
                continue;
            }
            let change: f64 = column.iter().zip(step.as_slice()).map(|(j, s)| j * s).sum();
            // The value left above the bound after the step.
            let left = change - bound;
            if left < -PAST_BOUND && deepest.is_none_or(|(_, d)| left < d) {
                deepest = Some((k, left));
            }
        }
        let Some((k, _)) = deepest else {
            return false;
        };
        if let Some(added) = self.added.get_mut(k) {
            *added = true;
        }
        let crossed = [k];
        let m = sys.dx.len();
        let mut jt: Vec<f64> = std::mem::take(&mut sys.jacobian_t).data.into();
        let mut dx: Vec<f64> = std::mem::take(&mut sys.dx).data.into();
        jt.truncate(m * n);
        dx.truncate(m);
        // The support of the rows in use: their nonzero DOF (empty means every DOF, so a
        // level that had no rows starts from none).
        let every = m > 0 && sys.support.is_empty();
        if m == 0 {
            sys.support.clear();
        }
        for &k in &crossed {
            let (Some(column), Some(&bound)) =
                (self.columns.get(k * n..(k + 1) * n), self.bounds.get(k))
            else {
                continue;
            };
            jt.extend_from_slice(column);
            dx.push(bound);
            if !every {
                sys.support.extend((0..n).filter(|&d| column[d] != 0.0));
            }
        }
        sys.support.sort_unstable();
        sys.support.dedup();
        let rows = dx.len();
        sys.jacobian_t = DMatrix::from_vec(n, rows, jt);
        sys.dx = DVector::from_vec(dx);
        true
    }
}

impl Solver {
    /// Prioritized step of the first `levels` levels with the joint-limit clamping loop and
    /// the inequalities' active set: while the step carries a candidate past its bound (by
    /// the linear model), its row joins its level, at the bound, and the step is taken again
    /// (each candidate joins once: the passes end). Returns (step, clamped DOF count);
    /// `values + step` is inside the limits.
    pub(super) fn compute_step(
        &mut self,
        skeleton: &Skeleton,
        values: &[f64],
        levels: usize,
    ) -> (DVector<f64>, usize) {
        for (sys, candidates) in self.systems.iter_mut().zip(&mut self.candidates) {
            candidates.restore(sys);
        }
        loop {
            let (step, clamped) = self.step_within_limits(skeleton, values, levels);
            let mut added = false;
            for (sys, candidates) in self
                .systems
                .iter_mut()
                .zip(&mut self.candidates)
                .take(levels)
            {
                added |= candidates.add_crossed(sys, &step);
            }
            if !added {
                return (step, clamped);
            }
        }
    }
}
