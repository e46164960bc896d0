//! `stance bench --comfort [N]`: issue 17's targets on reach problems of the H-Anim default body
//! (LOA 2): both feet pinned (level 1), balance inside their support polygon (level 2), the
//! right wrist on a goal it can reach (level 3, taken from a random posture of the right arm
//! and a little of the trunk), solved from the rest posture without and with a comfort level
//! (level 4). Prints how often the comfort level lowers the RULA score by at least 1, the change
//! of the summed gravity torque at the shoulders and the lower back, whether the levels above
//! stay met, and the cost of the comfort level per iteration.

use std::time::Instant;

use anyhow::Result;
use glam::DVec3;
use rand::rngs::StdRng;
use rand::{RngExt, SeedableRng};
use stance_hanim::comfort::{ComfortSettings, comfort_model, comfort_report};
use stance_hanim::strength::built_axes;
use stance_hanim::{HumanoidSkeleton, LevelOfArticulation, SkeletonOptions, default_skeleton};
use stance_ik::comfort::{ComfortModel, gravity_torques};
use stance_ik::{Effector, Frames, Posture, Solver, SolverSettings, Task};

/// One reach problem's outcome.
struct Outcome {
    rula: (u8, u8),
    load: (f64, f64),
    met: bool,
    /// The lowest RULA score the oracle found with levels 1-3 met (see `lowest_rula`).
    lowest: u8,
}

/// Starts of the oracle's multi-start search.
const ORACLE_STARTS: usize = 8;

/// The oracle of "the posture leaves the body free redundancy": the lowest RULA score among
/// solves of the same levels 1-3 with a RULA-weighted comfort level, from the rest posture and
/// from random postures (within the limits), each kept only with levels 1-3 met.
fn lowest_rula(
    body: &HumanoidSkeleton,
    tasks: &[Task],
    rula: &dyn Fn(&Posture) -> u8,
    r: &mut StdRng,
) -> Result<Option<u8>> {
    let s = &body.skeleton;
    let settings = ComfortSettings {
        effort: 0.1,
        range: 0.1,
        rula: 2.0,
        ..ComfortSettings::default()
    };
    let mut with = tasks.to_vec();
    with.push(Task::comfort(comfort_model(s, &built_axes(body), &settings)).at_level(4));
    let (lo, hi) = (s.lower_limits(), s.upper_limits());
    let mut lowest = None;
    for start in 0..ORACLE_STARTS {
        let mut p = Posture::rest(s);
        if start > 0 {
            for d in 0..s.dof_count() {
                if s.dof_kinds()[d].is_rotation() && lo[d].is_finite() && hi[d].is_finite() {
                    let t: f64 = r.random_range(-0.3..0.3);
                    p.values_mut()[d] = (t * (hi[d] - lo[d])).clamp(lo[d], hi[d]);
                }
            }
        }
        let report = Solver::new(SolverSettings {
            max_iterations: 400,
            ..SolverSettings::default()
        })?
        .solve(s, &with, &mut p)?;
        if report
            .levels
            .iter()
            .take(3)
            .all(|l| l.met || l.posture_only)
        {
            let score = rula(&p);
            lowest = Some(lowest.map_or(score, |l: u8| l.min(score)));
        }
    }
    Ok(lowest)
}

/// The joints whose gravity torque the target sums: both shoulders and the lower back.
const LOADED: [&str; 3] = ["l_shoulder", "r_shoulder", "vl5"];

fn reach_tasks(body: &HumanoidSkeleton, goal: DVec3) -> Result<Vec<Task>> {
    let s = &body.skeleton;
    let rest = Posture::rest(s);
    let frames = Frames::new(s, &rest);
    let mut tasks = Vec::new();
    let mut support = Vec::new();
    for foot in ["l_talocrural", "r_talocrural"] {
        let j = s.require_joint(foot)?;
        tasks.push(Task::position(j, DVec3::ZERO, frames.joint_position[j]));
        tasks.push(Task::orientation(j, frames.rotation(j)));
        for corner in stance_hanim::anatomy::sole(s, j) {
            support.push(Effector {
                joint: j,
                point: corner,
            });
        }
    }
    tasks.push(Task::balance(support, 0.02).at_level(2));
    let wrist = s.require_joint("r_radiocarpal")?;
    tasks.push(Task::position(wrist, DVec3::ZERO, goal).at_level(3));
    Ok(tasks)
}

/// A reachable goal: the right wrist where a random posture of the right arm, the spine and
/// the hips (within their limits) puts it.
fn random_goal(body: &HumanoidSkeleton, r: &mut StdRng) -> DVec3 {
    let s = &body.skeleton;
    let mut p = Posture::rest(s);
    let (lo, hi) = (s.lower_limits(), s.upper_limits());
    for (j, joint) in s.joints().iter().enumerate() {
        let moved = match joint.name.as_str() {
            "r_shoulder" | "r_elbow" | "r_radiocarpal" => 0.8,
            "vl5" | "vt6" | "vt1" | "sacroiliac" | "l_hip" | "r_hip" => 0.2,
            _ => 0.0,
        };
        if moved == 0.0 {
            continue;
        }
        for d in s.joints()[j].dof_range() {
            let span = (hi[d] - lo[d]).min(2.0 * std::f64::consts::PI);
            let v: f64 = r.random_range(-0.5..0.5);
            p.values_mut()[d] = (v * span * moved).clamp(lo[d], hi[d]);
        }
    }
    let frames = Frames::new(s, &p);
    s.joint_index("r_radiocarpal")
        .map_or(DVec3::ZERO, |w| frames.joint_position[w])
}

fn shoulder_and_back_torque(body: &HumanoidSkeleton, posture: &Posture) -> f64 {
    let s = &body.skeleton;
    let torques = gravity_torques(&Frames::new(s, posture));
    LOADED
        .iter()
        .filter_map(|n| s.joint_index(n))
        .map(|j| torques[j].length())
        .sum()
}

/// The comfort level's own cost per iteration, at the postures its settling run goes through
/// (every 4th, from the posture solved without comfort): at each, one iteration of the levels
/// with the comfort level (stepping where the levels above are met, as the run does) against
/// one of the levels without it, each timed as a solve of one iteration less a solve of none.
/// Unlike the run-against-run figures, the postures are the same on both sides. Returns the
/// summed times (without, with) in seconds and the postures measured.
fn same_posture_cost(
    s: &stance_ik::Skeleton,
    tasks: &[Task],
    with: &[Task],
    start: &Posture,
) -> Result<(f64, f64, usize)> {
    const REPEATS: usize = 15;
    let settings = |tolerance: Option<f64>, max_iterations: usize| SolverSettings {
        max_iterations,
        tolerance: tolerance.unwrap_or(SolverSettings::default().tolerance),
        stall_step: 0.0,
        stall_improvement: 0.0,
        stall_window: usize::MAX,
        restarts: false,
        ..SolverSettings::default()
    };
    // A solve's mean time from `p` (seconds).
    let timed = |tasks: &[Task], settings: SolverSettings, p: &Posture| -> Result<f64> {
        let mut solver = Solver::new(settings)?;
        let start = Instant::now();
        for _ in 0..REPEATS {
            let mut q = p.clone();
            solver.solve_with_clock(s, tasks, &mut q, None)?;
        }
        Ok(start.elapsed().as_secs_f64() / REPEATS as f64)
    };
    let settled = Solver::new(SolverSettings {
        restarts: false,
        ..SolverSettings::default()
    })?
    .solve(s, with, &mut start.clone())?
    .iterations;
    let (mut without_sum, mut with_sum, mut postures) = (0.0, 0.0, 0);
    for k in (0..settled.min(160)).step_by(4) {
        let mut p = start.clone();
        if k > 0 {
            Solver::new(SolverSettings {
                max_iterations: k,
                restarts: false,
                ..SolverSettings::default()
            })?
            .solve(s, with, &mut p)?;
        }
        // Without comfort at tolerance 0 (it always iterates); with comfort at the run's
        // tolerance (its level steps where the levels above are met).
        let without =
            timed(tasks, settings(Some(0.0), 1), &p)? - timed(tasks, settings(Some(0.0), 0), &p)?;
        let with_level = timed(with, settings(None, 1), &p)? - timed(with, settings(None, 0), &p)?;
        without_sum += without;
        with_sum += with_level;
        postures += 1;
    }
    Ok((without_sum, with_sum, postures))
}

pub fn run(cases: usize, json: bool) -> Result<()> {
    let body = default_skeleton(&SkeletonOptions {
        loa: LevelOfArticulation::Loa2,
        ..SkeletonOptions::default()
    })?;
    let s = &body.skeleton;
    let settings = ComfortSettings::default();
    let model = comfort_model(s, &built_axes(&body), &settings);
    let mut r = StdRng::seed_from_u64(17);
    // The oracle's own random starts: the cases stay those of `r`.
    let mut oracle_rng = StdRng::seed_from_u64(1993);
    let mut outcomes = Vec::new();
    let mut comfy_postures = Vec::new();
    let (mut iteration_plain, mut iteration_comfort, mut iteration_waiting) = (0.0, 0.0, 0.0);
    let mut timed = 0usize;
    let (mut same_without, mut same_with, mut same_postures) = (0.0, 0.0, 0);
    for _ in 0..cases {
        let tasks = reach_tasks(&body, random_goal(&body, &mut r))?;
        let mut with = tasks.clone();
        with.push(Task::comfort(model.clone()).at_level(4));
        let mut plain = Posture::rest(s);
        let plain_report = Solver::default().solve(s, &tasks, &mut plain)?;
        let mut comfy = Posture::rest(s);
        let comfy_report = Solver::default().solve(s, &with, &mut comfy)?;
        comfy_postures.push(comfy.clone());
        let rula = |p: &Posture| {
            comfort_report(s, &built_axes(&body), p, &settings)
                .rula
                .map_or(0, |r| r.score)
        };
        let met = |report: &stance_ik::SolveReport| {
            report
                .levels
                .iter()
                .take(3)
                .all(|l| l.met || l.posture_only)
        };
        if !met(&plain_report) {
            continue;
        }
        let (before, after) = (rula(&plain), rula(&comfy));
        let found = lowest_rula(&body, &tasks, &rula, &mut oracle_rng)?.unwrap_or(before);
        outcomes.push(Outcome {
            lowest: found
                .min(before)
                .min(if met(&comfy_report) { after } else { before }),
            rula: (before, after),
            load: (
                shoulder_and_back_torque(&body, &plain),
                shoulder_and_back_torque(&body, &comfy),
            ),
            met: met(&comfy_report),
        });
        // The cost of one iteration without and with the comfort level stepping, from the
        // posture solved without comfort (levels 1-3 met): without, a run of iterations that
        // never ends early (tolerance 0, no stall) linearises and steps every level; with,
        // the comfort level settles the posture as it does after a task solve in the editor
        // (every level above met, the comfort level stepping) until its cost stops falling.
        let iteration_time = |tasks: &[Task], settings: SolverSettings| -> Result<Option<f64>> {
            let mut solver = Solver::new(SolverSettings {
                restarts: false,
                ..settings
            })?;
            let (mut elapsed, mut iterations) = (0.0, 0);

            for _ in 0..5 {
                let mut p = plain.clone();
                let start = Instant::now();
                let report = solver.solve_with_clock(s, tasks, &mut p, None)?;
                elapsed += start.elapsed().as_secs_f64();
                iterations += report.iterations;
            }
            Ok((iterations > 0).then(|| elapsed / iterations as f64))
        };
        let endless = SolverSettings {
            max_iterations: 50,
            tolerance: 0.0,
            stall_step: 0.0,
            stall_improvement: 0.0,
            stall_window: usize::MAX,
            ..SolverSettings::default()
        };
        let (without, with_level, postures) = same_posture_cost(s, &tasks, &with, &plain)?;
        same_without += without;
        same_with += with_level;
        same_postures += postures;
        let plain_time = iteration_time(&tasks, endless)?;
        let comfort_time = iteration_time(&with, SolverSettings::default())?;
        // The comfort level waiting (the levels above never count as met at tolerance 0).
        let waiting_time = iteration_time(&with, endless)?;
        if let (Some(plain_time), Some(comfort_time), Some(waiting_time)) =
            (plain_time, comfort_time, waiting_time)
        {
            iteration_plain += plain_time;
            iteration_comfort += comfort_time;
            iteration_waiting += waiting_time;
            timed += 1;
        }
    }
    // The gradient's time at the postures solved with comfort, whole and term by term (the
    // other weights set to 0).
    let solved: Vec<(Frames, &Posture)> = comfy_postures
        .iter()
        .map(|p| (Frames::new(s, p), p))
        .collect();
    let gradient_time = |model: &ComfortModel| {
        let mut g = vec![0.0; s.dof_count()];
        let runs = (20_000 / solved.len().max(1)).max(1);
        let start = Instant::now();
        for _ in 0..runs {
            for (frames, posture) in &solved {
                model.gradient(s, frames, posture.values(), &mut g);
            }
        }
        1e6 * start.elapsed().as_secs_f64() / (runs * solved.len()).max(1) as f64
    };
    let gradient_us = gradient_time(&model);
    let only = |effort: f64, range: f64, band: f64| ComfortModel {
        effort_weight: effort * model.effort_weight,
        range_weight: range * model.range_weight,
        band_weight: band * model.band_weight,
        ..model.clone()
    };
    let term_us = [
        gradient_time(&only(1.0, 0.0, 0.0)),
        gradient_time(&only(0.0, 1.0, 0.0)),
        gradient_time(&only(0.0, 0.0, 1.0)),
    ];
    let n = outcomes.len();
    let lowered = outcomes.iter().filter(|o| o.rula.1 < o.rula.0).count();
    let raised = outcomes.iter().filter(|o| o.rula.1 > o.rula.0).count();
    // Postures that leave the body free redundancy: a lower score exists with levels 1-3 met.
    let free = outcomes.iter().filter(|o| o.lowest < o.rula.0).count();
    let lowered_free = outcomes
        .iter()
        .filter(|o| o.lowest < o.rula.0 && o.rula.1 < o.rula.0)
        .count();
    let met = outcomes.iter().filter(|o| o.met).count();
    let (before, after): (f64, f64) = outcomes
        .iter()
        .fold((0.0, 0.0), |(a, b), o| (a + o.load.0, b + o.load.1));
    let torque_change = if before > 0.0 {
        after / before - 1.0
    } else {
        0.0
    };
    let rula_mean = |f: fn(&Outcome) -> u8| {
        outcomes.iter().map(|o| f64::from(f(o))).sum::<f64>() / n.max(1) as f64
    };
    let overhead = iteration_comfort / iteration_plain.max(f64::MIN_POSITIVE) - 1.0;
    let waiting = iteration_waiting / iteration_plain.max(f64::MIN_POSITIVE) - 1.0;
    let same_share = same_with / same_without.max(f64::MIN_POSITIVE) - 1.0;
    // Per iteration at the settling runs' postures (the levels above move there, and an
    // iteration of theirs costs more than at the posture solved without comfort).
    let same_us = |sum: f64| 1e6 * sum / same_postures.max(1) as f64;
    let per_iteration_us = |sum: f64| 1e6 * sum / timed.max(1) as f64;
    if json {
        println!(
            "{}",
            serde_json::json!({
                "cases": n,
                "rula_lowered_by_1": lowered,
                "rula_raised": raised,
                "free_redundancy": free,
                "rula_lowered_where_free": lowered_free,
                "rula_mean": [rula_mean(|o| o.rula.0), rula_mean(|o| o.rula.1)],
                "shoulder_and_back_torque_change": torque_change,
                "levels_above_met": met,
                "comfort_level_share_of_iteration": overhead,
                "comfort_level_waiting_share_of_iteration": waiting,
                "comfort_level_share_at_same_postures": same_share,
                "same_postures_measured": same_postures,
                "iteration_us": {
                    "without": per_iteration_us(iteration_plain),
                    "comfort_stepping": per_iteration_us(iteration_comfort),
                    "comfort_waiting": per_iteration_us(iteration_waiting),
                    "same_postures_without": same_us(same_without),
                    "same_postures_with": same_us(same_with),
                },
                "gradient_us": gradient_us,
                "gradient_us_by_term": {"effort": term_us[0], "range": term_us[1], "bands": term_us[2]},
            })
        );
    } else {
        println!(
            "reach problems (feet pinned, balance, right hand; LOA 2): {n} solved without comfort"
        );
        println!(
            "  comfort level lowers RULA by >= 1 in {lowered}/{n}, raises it in {raised}; mean \
             {:.2} -> {:.2}",
            rula_mean(|o| o.rula.0),
            rula_mean(|o| o.rula.1)
        );
        println!(
            "  of the {free} postures that leave the body free redundancy (a lower score with \
             levels 1-3 met, best of {ORACLE_STARTS} RULA-weighted starts), comfort lowers RULA \
             in {lowered_free}"
        );
        println!(
            "  shoulders + lower back gravity torque: {:+.1} % (summed over the cases)",
            100.0 * torque_change
        );
        println!("  levels 1-3 still met with the comfort level: {met}/{n}");
        println!(
            "  the comfort cost's gradient at the solved postures: {gradient_us:.1} us (effort {:.1}, range {:.1}, \
             bands {:.1})",
            term_us[0], term_us[1], term_us[2]
        );
        println!(
            "  comfort level stepping: {:+.1} % of an iteration ({:.1} us -> {:.1} us); \
             waiting for the levels above: {:+.1} % ({:.1} us)",
            100.0 * overhead,
            per_iteration_us(iteration_plain),
            per_iteration_us(iteration_comfort),
            100.0 * waiting,
            per_iteration_us(iteration_waiting),
        );
        println!(
            "  the comfort level's own cost at the same postures (its settling run's, {same_postures} \
             measured): {:+.1} % of an iteration ({:.1} us -> {:.1} us)",
            100.0 * same_share,
            same_us(same_without),
            same_us(same_with)
        );
    }
    Ok(())
}
