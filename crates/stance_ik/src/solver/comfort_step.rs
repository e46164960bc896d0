//! A comfort level's share of a step kept inside the joint limits without taking every
//! level's step again (see `Solver::comfort_within_limits`).

use nalgebra::DVector;

use super::{Backend, Solver};
use crate::kernel::project_last_again;

/// The least share of a comfort level's step kept by shortening it to stay inside the joint
/// limits; below it the DOF in the way are held out of the share (the kernel backend, up to
/// twice), then clamped and the step taken again.
const COMFORT_SHARE_KEPT: f64 = 0.5;

/// A step's joint limits and what is already decided (see `compute_step`): the DOF values,
/// their limits, the stiffness scale of the kernel's coordinates, the moves of the clamped DOF.
pub(super) struct StepLimitsAt<'a> {
    pub(super) values: &'a [f64],
    pub(super) lo: &'a [f64],
    pub(super) hi: &'a [f64],
    pub(super) scale: Option<&'a [f64]>,
    pub(super) fixed: &'a DVector<f64>,
    pub(super) clamped: &'a [bool],
}

impl StepLimitsAt<'_> {
    /// DOF `i`'s move by the levels above (`above`, a kernel step) and the last level's share
    /// (`whole` less `above`), in the DOF's own coordinates.
    fn moves(&self, above: &DVector<f64>, whole: &DVector<f64>, i: usize) -> (f64, f64) {
        let unweigh = self.scale.map_or(1.0, |s| s[i]);
        (
            above[i] * unweigh + self.fixed[i],
            (whole[i] - above[i]) * unweigh,
        )
    }

    /// The largest `alpha` (above 1 when nothing is in the way) with the levels above's move
    /// plus `alpha` times the last level's share inside the limits on the unclamped DOF, and
    /// the DOF that would cut it below [`COMFORT_SHARE_KEPT`]. `None` where the levels above
    /// alone leave the limits.
    fn share_room(&self, above: &DVector<f64>, whole: &DVector<f64>) -> Option<(f64, Vec<usize>)> {
        let mut alpha: f64 = 2.0;
        let mut blocking = Vec::new();
        for i in 0..self.values.len() {
            if self.clamped[i] {
                continue;
            }
            let (moved, share) = self.moves(above, whole, i);
            let (lo, hi) = (self.lo[i], self.hi[i]);
            let base = self.values[i] + moved;
            if !(lo <= base && base <= hi) {
                return None;
            }
            let next = base + share;
            let room = if next > hi {
                (hi - base) / share
            } else if next < lo {
                (lo - base) / share
            } else {
                continue;
            };
            alpha = alpha.min(room);
            if room < COMFORT_SHARE_KEPT {
                blocking.push(i);
            }
        }
        Some((alpha, blocking))
    }

    /// The whole step: the levels above's move plus `alpha` times the last level's share.
    fn step_with_share(
        &self,
        above: &DVector<f64>,
        whole: &DVector<f64>,
        alpha: f64,
    ) -> DVector<f64> {
        DVector::from_fn(self.values.len(), |i, _| {
            let (moved, share) = self.moves(above, whole, i);
            moved + alpha * share
        })
    }
}

impl Solver {
    /// Where the last level is a comfort level that steps and the step of the levels above
    /// it stays inside the joint limits: the whole step `total` (`step + fixed`) with the
    /// comfort level's share kept inside them too, without taking the levels' steps again.
    /// The DOF that would cut the share below [`COMFORT_SHARE_KEPT`] are held out of it
    /// (`project_last_again`), twice at most; what is still in the way shortens it. False
    /// (`total` as it was): clamp and step again.
    pub(super) fn comfort_within_limits(
        &mut self,
        limits: &StepLimitsAt<'_>,
        used: usize,
        params: &crate::StepParams,
        total: &mut DVector<f64>,
    ) -> bool {
        const HOLDS: usize = 2;
        if !(used >= 2 && self.comfort_stepping && self.layout[used - 1].comfort) {
            return false;
        }
        let mut held = Vec::new();
        for hold in 0..=HOLDS {
            let partial = self.workspace.partial_steps();
            let (Some(above), Some(whole)) = (partial.get(used - 2), partial.get(used - 1)) else {
                return false;
            };
            let Some((alpha, blocking)) = limits.share_room(above, whole) else {
                return false;
            };
            if alpha >= 1.0 && hold == 0 {
                // Nothing in the way: the step as the kernel gave it.
                return true;
            }
            if alpha >= COMFORT_SHARE_KEPT {
                *total = limits.step_with_share(above, whole, alpha.min(1.0));
                return true;
            }
            if hold == HOLDS || self.settings.backend != Backend::Kernel {
                return false;
            }
            held.extend(blocking);
            let systems = if limits.scale.is_some() {
                &self.weighted[..used]
            } else {
                &self.systems[..used]
            };
            if project_last_again(
                systems,
                used - 1,
                limits.values.len(),
                params,
                &held,
                &mut self.workspace,
            )
            .is_none()
            {
                return false;
            }
        }
        false
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

    use nalgebra::DVector;

    use super::StepLimitsAt;

    /// Three DOF in [-1, 1]: the levels above move each by `above` (kernel coordinates), the
    /// last level's share by `share`.
    fn room(
        values: [f64; 3],
        above: [f64; 3],
        share: [f64; 3],
        scale: Option<&[f64]>,
        clamped: [bool; 3],
    ) -> Option<(f64, Vec<usize>)> {
        let (lo, hi) = ([-1.0; 3], [1.0; 3]);
        let fixed = DVector::zeros(3);
        let limits = StepLimitsAt {
            values: &values,
            lo: &lo,
            hi: &hi,
            scale,
            fixed: &fixed,
            clamped: &clamped,
        };
        let above = DVector::from_row_slice(&above);
        let whole = &above + DVector::from_row_slice(&share);
        limits.share_room(&above, &whole)
    }

    #[test]
    fn the_room_a_share_has_is_what_the_nearest_limit_leaves() {
        let free = [false; 3];
        // Nothing in the way: above 1.
        let (alpha, blocking) = room([0.0; 3], [0.1; 3], [0.2; 3], None, free).unwrap();
        assert!(alpha > 1.0 && blocking.is_empty());
        // DOF 1 reaches its upper limit after 0.3 of its 0.4 share (0.5 + 0.2 + 0.3 = 1).
        let (alpha, blocking) = room(
            [0.0, 0.5, 0.0],
            [0.0, 0.2, 0.0],
            [0.1, 0.4, -0.1],
            None,
            free,
        )
        .unwrap();
        assert!((alpha - 0.75).abs() < 1e-12 && blocking.is_empty());
        // DOF 2 on its lower limit, pushed further: no room, and it is in the way.
        let (alpha, blocking) =
            room([0.0, 0.0, -1.0], [0.0; 3], [0.1, 0.1, -0.1], None, free).unwrap();
        assert!(alpha == 0.0 && blocking == vec![2]);
        // A clamped DOF is not asked.
        let (alpha, _) = room(
            [0.0, 0.0, -1.0],
            [0.0; 3],
            [0.1, 0.1, -0.1],
            None,
            [false, false, true],
        )
        .unwrap();
        assert!(alpha > 1.0);
        // The kernel's coordinates are scaled back: a share of 0.8 at scale 0.5 is 0.4.
        let (alpha, _) = room(
            [0.8, 0.0, 0.0],
            [0.0; 3],
            [0.8, 0.0, 0.0],
            Some(&[0.5, 1.0, 1.0]),
            free,
        )
        .unwrap();
        assert!((alpha - 0.5).abs() < 1e-12);
        // The levels above alone leave the limits: none.
        assert!(room([0.9, 0.0, 0.0], [0.2, 0.0, 0.0], [0.0; 3], None, free).is_none());
    }
}
