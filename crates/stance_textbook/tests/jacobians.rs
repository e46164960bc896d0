//! The oracle's analytic Jacobians against central differences of its own errors (the
//! quantity a task pulls is minus its unclamped error), on every family's problems at their
//! start postures and at random postures near them.

use crate::common::{all_families, problems};

#[test]
fn analytic_jacobians_match_central_differences_on_every_family() {
    let h = 1e-6;
    for family in all_families() {
        for (problem, _, _) in problems(&family, 4) {
            let mut q = problem.start.clone();
            for (i, x) in q.iter_mut().enumerate() {
                *x += 0.05 * ((i * 7919) % 13) as f64 / 13.0;
            }
            let analytic = problem.jacobians(&q);
            for (level, jacobian) in analytic.iter().enumerate() {
                for dof in 0..problem.dof_count() {
                    let mut plus = q.clone();
                    let mut minus = q.clone();
                    plus[dof] += h;
                    minus[dof] -= h;
                    let (ep, em) = (
                        &problem.errors(&plus)[level],
                        &problem.errors(&minus)[level],
                    );
                    for row in 0..jacobian.nrows() {
                        let numeric = -(ep[row] - em[row]) / (2.0 * h);
                        let a = jacobian[(row, dof)];
                        assert!(
                            (numeric - a).abs() <= 1e-5 * (1.0 + a.abs()),
                            "{}: level {level} row {row} dof {dof}: analytic {a}, central {numeric}",
                            family.name
                        );
                    }
                }
            }
        }
    }
}
