//! `stance bench`: time the solver on the scenarios S1..S7 (or on one problem file).
//!
//! Per scenario: `us_per_iteration` is the median, over many runs, of the time of a solve forced
//! to take exactly `--iterations` iterations from the start posture (tolerance and stall tests
//! off, and the textbook iteration so that every iteration computes every level: the cost of one
//! full prioritized iteration) divided by that count; `us_per_solve` is the
//! median time of a normal solve (default settings) from the start posture, which takes
//! `iterations` iterations and ends with `status`.
//!
//! S7 is one closed-form limb solve (no iterations): `us_per_solve` (= `us_per_iteration`) is
//! the median over many batches of the time of `Limb::solve` + `Limb::apply`, divided by the
//! batch size; `status` is `converged` when the goal was reached.

use std::path::PathBuf;
use std::time::Instant;

use std::collections::BTreeMap;

use anyhow::Result;
use serde::Serialize;
use stance_hanim::scenarios;
use stance_ik::{Damping, Iteration, Posture, Skeleton, SolveStatus, Solver, SolverSettings, Task};

#[derive(clap::Args, Debug)]
pub struct BenchArgs {
    /// Print JSON instead of a table.
    #[arg(long)]
    pub json: bool,
    /// Time this problem file instead of the built-in scenarios.
    #[arg(long)]
    pub problem: Option<PathBuf>,
    /// Solve every problem file (`*.json`) of this directory and its sub-folders (one per
    /// family, as `stance families` writes them): per family, how many met every level, the
    /// median and 90th-percentile iterations, the median time per solve and per iteration.
    #[arg(long)]
    pub suite: Option<PathBuf>,
    /// With `--suite`: a peer's results on the same files (JSON lines with `family`,
    /// `problem`, `met_every_level`, `iterations`, `us_per_solve`, as `stance-textbook`
    /// prints them): the counts and ratios side by side.
    #[arg(long, requires = "suite")]
    pub peer: Option<PathBuf>,
    /// With `--suite`: solve without the restarts of a stalled solve.
    #[arg(long, requires = "suite")]
    pub no_restarts: bool,
    /// Only these scenarios (e.g. `--scenario S2 --scenario S6`).
    #[arg(long)]
    pub scenario: Vec<String>,
    /// Minimum measuring time per figure, in milliseconds.
    #[arg(long, default_value_t = 300)]
    pub millis: u64,
    /// Iterations per timed run for `us_per_iteration`.
    #[arg(long, default_value_t = 10)]
    pub iterations: usize,
    /// Comfort on N reach problems (feet pinned, balance, right hand): RULA and the shoulder
    /// and lower-back loads without and with a comfort level, and its cost per iteration.
    #[arg(long, value_name = "N", num_args = 0..=1, default_missing_value = "40")]
    pub comfort: Option<usize>,
    /// The collision task's cost per iteration on the LOA 2 body (feet pinned, self and floor
    /// collision, two reaches) at postures holding 0, about 4 and about 10 constraints, with
    /// and without it.
    #[arg(long)]
    pub collision: bool,
    /// Time retargeting this clip (.bvh, .glb) onto the H-Anim default body at LOA2 (50
    /// DOF): the plain rotation copy and the five-level problem with contacts, frames per
    /// second on one core.
    #[arg(long)]
    pub clip: Option<PathBuf>,
}

#[derive(Debug, Clone, Serialize)]
pub struct BenchResult {
    pub us_per_iteration: f64,
    pub us_per_solve: f64,
    pub iterations: usize,
    pub status: SolveStatus,
    pub dof: usize,
    pub rows: usize,
    pub levels: usize,
    /// Final residual norm of every level, highest priority first.
    pub residuals: Vec<f64>,
    /// Every level (posture attraction aside) within the tolerance.
    pub met_every_level: bool,
}

/// Native targets of the issue (us per iteration; S6: us per converged sample).
fn target_us(name: &str) -> Option<f64> {
    match name {
        "S1" => Some(1.0),
        "S2" => Some(60.0),
        "S3" => Some(120.0),
        "S4" => Some(80.0),
        "S5" => Some(15.0),
        "S6" => Some(2000.0),
        "S7" => Some(0.5),
        _ => None,
    }
}

pub fn run(args: BenchArgs) -> Result<()> {
    let budget = std::time::Duration::from_millis(args.millis);
    if let Some(dir) = &args.suite {
        return crate::bench_suite::run(dir, args.peer.as_deref(), args.no_restarts, args.json);
    }
    if let Some(cases) = args.comfort {
        return crate::bench_comfort::run(cases, args.json);
    }
    if args.collision {
        return crate::bench_collision::run(budget, args.json);
    }
    if let Some(path) = &args.clip {
        return bench_clip(path, budget, args.json);
    }
    if let Some(path) = &args.problem {
        let r = bench_file(path, budget, args.iterations)?;
        if args.json {
            println!("{}", serde_json::to_string(&r)?);
        } else {
            println!(
                "{}: {:.2} us/iteration, {:.1} us/solve ({} iterations, {:?}; residuals {:?})",
                path.display(),
                r.us_per_iteration,
                r.us_per_solve,
                r.iterations,
                r.status,
                r.residuals
            );
        }
        return Ok(());
    }
    let mut results = serde_json::Map::new();
    if !args.json {
        println!(
            "{:<4} {:>4} {:>5} {:>6} {:>12} {:>12} {:>6} {:>10}  description",
            "", "DOF", "rows", "levels", "us/iter", "us/solve", "iters", "target"
        );
    }
    for s in scenarios::all()? {
        if !args.scenario.is_empty()
            && !args.scenario.iter().any(|n| n.eq_ignore_ascii_case(s.name))
        {
            continue;
        }
        let settings = SolverSettings::default();
        let r = bench(
            &s.skeleton,
            &s.tasks,
            &s.start,
            settings,
            &BTreeMap::new(),
            budget,
            args.iterations,
        )?;
        if args.json {
            results.insert(s.name.to_owned(), serde_json::to_value(&r)?);
        } else {
            let measured = if s.name == "S6" {
                r.us_per_solve
            } else {
                r.us_per_iteration
            };
            let target = target_us(s.name)
                .map(|t| format!("{}{t}", if measured <= t { "ok <= " } else { "MISS " }))
                .unwrap_or_default();
            println!(
                "{:<4} {:>4} {:>5} {:>6} {:>12.2} {:>12.1} {:>6} {:>10}  {} ({:?})",
                s.name,
                r.dof,
                r.rows,
                r.levels,
                r.us_per_iteration,
                r.us_per_solve,
                r.iterations,
                target,
                s.description,
                r.status
            );
        }
    }
    let s7 = scenarios::s7()?;
    if args.scenario.is_empty()
        || args
            .scenario
            .iter()
            .any(|n| n.eq_ignore_ascii_case(s7.name))
    {
        let r = bench_limb(&s7, budget);
        if args.json {
            results.insert(s7.name.to_owned(), serde_json::to_value(&r)?);
        } else {
            let target = target_us(s7.name)
                .map(|t| {
                    let verdict = if r.us_per_solve <= t {
                        "ok <= "
                    } else {
                        "MISS "
                    };
                    format!("{verdict}{t}")
                })
                .unwrap_or_default();
            println!(
                "{:<4} {:>4} {:>5} {:>6} {:>12.3} {:>12.3} {:>6} {:>10}  {} ({:?})",
                s7.name,
                r.dof,
                r.rows,
                r.levels,
                r.us_per_iteration,
                r.us_per_solve,
                r.iterations,
                target,
                s7.description,
                r.status
            );
        }
    }
    if args.json {
        println!("{}", serde_json::Value::Object(results));
    }
    Ok(())
}

/// Frames per second of retargeting `path` onto the H-Anim default body (one core), with
/// and without contacts; the target is 2,000 frames per second with contacts.
fn bench_clip(path: &std::path::Path, budget: std::time::Duration, json: bool) -> Result<()> {
    use stance_hanim::{LevelOfArticulation, SkeletonOptions, default_skeleton};
    use stance_motion::{ContactSettings, RetargetOptions, retarget};
    let clip = crate::retarget::load_clip(path)?;
    let mut figures = serde_json::Map::new();
    for loa in [LevelOfArticulation::Loa1, LevelOfArticulation::Loa2] {
        let body = default_skeleton(&SkeletonOptions {
            loa,
            ..SkeletonOptions::default()
        })?;
        for (name, contacts) in [
            ("copy", None),
            ("contacts", Some(ContactSettings::default())),
        ] {
            let options = RetargetOptions {
                contacts,
                ..RetargetOptions::default()
            };
            let mut runs = Vec::new();
            let started = Instant::now();
            let mut iterations = 0;
            while runs.is_empty() || started.elapsed() < budget {
                let t = Instant::now();
                let r = retarget(&clip, &body, &options)?;
                runs.push(t.elapsed().as_secs_f64());
                iterations = r.iterations;
            }
            let fps = clip.frame_count() as f64 / median(runs);
            let key = format!("loa{}_{name}", loa.number());
            figures.insert(
                key,
                serde_json::json!({"frames_per_second": fps, "iterations": iterations,
                    "dof": body.skeleton.dof_count()}),
            );
            if !json {
                let verdict = match contacts {
                    Some(_) if fps >= 2000.0 => "  (target >= 2000: ok)",
                    Some(_) => "  (target >= 2000: MISS)",
                    None => "",
                };
                println!(
                    "{}: {} frames onto the H-Anim LOA{} body ({} DOF), {name}: {fps:.0} frames/s \
                     on one core, {:.2} iterations/frame{verdict}",
                    path.display(),
                    clip.frame_count(),
                    loa.number(),
                    body.skeleton.dof_count(),
                    iterations as f64 / clip.frame_count() as f64,
                );
            }
        }
    }
    if json {
        println!("{}", serde_json::Value::Object(figures));
    }
    Ok(())
}

/// Times one problem file from its start posture, with its settings and per-level damping.
fn bench_file(
    path: &std::path::Path,
    budget: std::time::Duration,
    iterations: usize,
) -> Result<BenchResult> {
    let problem = crate::solve::load_problem(path)?;
    bench(
        &problem.skeleton,
        &problem.tasks,
        &problem.start_posture().0,
        problem.settings,
        &problem.level_damping,
        budget,
        iterations,
    )
}

/// Times S7 (see the module docs).
pub fn bench_limb(s: &scenarios::LimbScenario, budget: std::time::Duration) -> BenchResult {
    const BATCH: usize = 1000;
    let mut posture = s.start.clone();
    let mut per_solve = Vec::new();
    let mut reached = true;
    let t0 = Instant::now();
    while t0.elapsed() < budget || per_solve.len() < 5 {
        let t = Instant::now();
        for _ in 0..BATCH {
            let goal = std::hint::black_box(s.goal);
            let solution = s
                .limb
                .solve(s.base, &goal, std::hint::black_box(s.swivel_angle));
            s.limb.apply(&solution, &mut posture);
            reached &= solution.reached;
        }
        per_solve.push(t.elapsed().as_secs_f64() * 1e6 / BATCH as f64);
        std::hint::black_box(&posture);
    }
    let us = median(per_solve);
    BenchResult {
        us_per_iteration: us,
        us_per_solve: us,
        iterations: 1,
        status: if reached {
            SolveStatus::Converged
        } else {
            SolveStatus::Stalled
        },
        dof: s.skeleton.dof_count(),
        rows: 3,
        levels: 1,
        residuals: Vec::new(),
        met_every_level: reached,
    }
}

pub fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    match v.len() {
        0 => f64::NAN,
        n if n % 2 == 1 => v[n / 2],
        n => 0.5 * (v[n / 2 - 1] + v[n / 2]),
    }
}

/// Times one problem (see the module docs).
pub fn bench(
    skeleton: &Skeleton,
    tasks: &[Task],
    start: &Posture,
    settings: SolverSettings,
    level_damping: &BTreeMap<u32, Damping>,
    budget: std::time::Duration,
    iterations: usize,
) -> Result<BenchResult> {
    let iterations = iterations.max(1);
    // Fixed iteration count: tolerance 0 and stall tests off.
    let fixed = SolverSettings {
        max_iterations: iterations,
        tolerance: 0.0,
        stall_step: 0.0,
        stall_improvement: 0.0,
        time_budget_secs: None,
        restarts: false,
        iteration: Iteration::Textbook,
        ..settings
    };
    let mut solver = Solver::new(fixed)?;
    solver.level_damping = level_damping.clone();
    let mut per_iteration = Vec::new();
    let t0 = Instant::now();
    while t0.elapsed() < budget || per_iteration.len() < 5 {
        let mut p = start.clone();
        let t = Instant::now();
        let report = solver.solve(skeleton, tasks, &mut p)?;
        let dt = t.elapsed().as_secs_f64();
        per_iteration.push(dt * 1e6 / report.iterations.max(1) as f64);
    }
    let mut solver = Solver::new(settings)?;
    solver.level_damping = level_damping.clone();
    let mut per_solve = Vec::new();
    let mut last = None;
    let t0 = Instant::now();
    while t0.elapsed() < budget || per_solve.len() < 5 {
        let mut p = start.clone();
        let t = Instant::now();
        let report = solver.solve(skeleton, tasks, &mut p)?;
        per_solve.push(t.elapsed().as_secs_f64() * 1e6);
        last = Some(report);
    }
    let (iters, status, levels, residuals, met) = last
        .map(|r| {
            (
                r.iterations,
                r.status,
                r.levels.len(),
                r.levels.iter().map(|l| l.residual_after).collect(),
                r.levels.iter().all(|l| l.met || l.posture_only),
            )
        })
        .unwrap_or((0, SolveStatus::Converged, 0, Vec::new(), true));
    Ok(BenchResult {
        us_per_iteration: median(per_iteration),
        us_per_solve: median(per_solve),
        iterations: iters,
        status,
        dof: skeleton.dof_count(),
        rows: tasks.iter().filter(|t| t.active).map(Task::rows).sum(),
        levels,
        residuals,
        met_every_level: met,
    })
}
