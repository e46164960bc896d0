//! Not a fuzz target: shared by the `document` and `problem` targets (fuzz_targets/ holds
//! only targets, each declared in Cargo.toml; scripts/test.sh checks it).
//!
//! What the `document` and `problem` targets do with a problem that loads: its closed-form
//! limb starts, a few solver iterations and the solution's JSON (joints, posture, report with
//! the comfort). Every error must say something.

use stance_document::Problem;

pub fn solve_briefly(problem: &Problem) {
    let (mut posture, _) = problem.start_posture();
    let mut settings = problem.settings;
    settings.max_iterations = settings.max_iterations.min(3);
    settings.time_budget_secs = None;
    let report = problem
        .solver(settings)
        .and_then(|mut solver| solver.solve(&problem.skeleton, &problem.tasks, &mut posture));
    match report {
        Ok(report) => {
            let _ = problem.solution_json(&posture, &report);
        }
        Err(e) => assert!(!e.to_string().trim().is_empty(), "empty error: {e:?}"),
    }
}
