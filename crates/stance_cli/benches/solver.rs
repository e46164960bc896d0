//! Criterion benches of the scenarios S1..S6: one full prioritized iteration, the step alone
//! with the slice kernel and with nalgebra (the comparison behind the kernel), S6's solve, and
//! S7: one closed-form arm solve.

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use stance_hanim::scenarios;
use stance_ik::{
    Iteration, Solver, SolverSettings, StepParams, StepWorkspace, prioritized_step,
    prioritized_step_nalgebra,
};

fn benches(c: &mut Criterion) {
    let all = scenarios::all().unwrap_or_default();
    for s in &all {
        let n = s.skeleton.dof_count();
        let full = SolverSettings {
            restarts: false,
            iteration: Iteration::Textbook,
            ..SolverSettings::default()
        };
        let mut solver = Solver::new(full).unwrap_or_default();
        if s.name != "S6" {
            c.bench_function(&format!("{}/iteration", s.name), |b| {
                b.iter(|| {
                    let mut p = s.start.clone();
                    black_box(solver.iterate(&s.skeleton, &s.tasks, &mut p).ok())
                })
            });
            let Ok(systems) = Solver::default().linear_systems(&s.skeleton, &s.tasks, &s.start)
            else {
                continue;
            };
            let params = StepParams::default();
            let mut ws = StepWorkspace::default();
            c.bench_function(&format!("{}/step_kernel", s.name), |b| {
                b.iter(|| {
                    black_box(prioritized_step(
                        &systems, n, &params, None, None, &mut ws, None,
                    ))
                })
            });
            c.bench_function(&format!("{}/step_nalgebra", s.name), |b| {
                b.iter(|| {
                    black_box(prioritized_step_nalgebra(
                        &systems, n, &params, None, None, &mut ws, None,
                    ))
                })
            });
        } else {
            let mut solver = Solver::default();
            c.bench_function("S6/solve", |b| {
                b.iter(|| {
                    let mut p = s.start.clone();
                    black_box(solver.solve(&s.skeleton, &s.tasks, &mut p).ok())
                })
            });
        }
    }
}

fn limb_bench(c: &mut Criterion) {
    let Ok(s) = scenarios::s7() else {
        return;
    };
    let mut posture = s.start.clone();
    c.bench_function("S7/analytic_arm_solve", |b| {
        b.iter(|| {
            let solution = s
                .limb
                .solve(s.base, black_box(&s.goal), black_box(s.swivel_angle));
            s.limb.apply(&solution, &mut posture);
            black_box(&posture);
        })
    });
}

criterion_group!(solver, benches, limb_bench);
criterion_main!(solver);
