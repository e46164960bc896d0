//! `stance bench --collision`: the collision task's cost per iteration (issue 32) on the H-Anim
//! default body at LOA 2: both ankles pinned (level 1), self and floor collision
//! (`stance_hanim::capsules::BodyCollision`, level 2), both wrists pulled 10 cm forward
//! (level 3). Postures are drawn (seeded) until one has the number of constraints asked
//! within the margin and the band (0, about 4, about 10); from each, the time per iteration
//! of a solve forced to take 10 textbook iterations (as `stance bench` times an iteration:
//! every level linearised and stepped every iteration) with and without the collision level,
//! and the search alone at that posture (the task's residual: the broad phase and the
//! closest points of the pairs it lets through).

use std::collections::BTreeMap;
use std::time::{Duration, Instant};

use anyhow::{Result, bail};
use glam::DVec3;
use rand::rngs::StdRng;
use rand::{RngExt, SeedableRng};
use serde::Serialize;
use stance_hanim::capsules::BodyCollision;
use stance_hanim::{LevelOfArticulation, SkeletonOptions, default_skeleton};
use stance_ik::{
    COLLISION_BAND, Frames, Posture, Skeleton, SolverSettings, Task, TaskFeature, TaskKind,
};

use crate::bench::median;

/// Iterations per timed solve (as `stance bench` times an iteration).
const ITERATIONS: usize = 10;

/// One posture's figures.
#[derive(Debug, Serialize)]
struct Row {
    /// Constraints within the margin and the band at the posture.
    constraints: usize,
    us_without: f64,
    us_with: f64,
    /// `us_with / us_without - 1`, in per cent.
    extra_percent: f64,
    /// The constraint search alone (us).
    us_search: f64,
}

/// The constraints the task holds at `posture` (its feature's distances under the margin
/// plus the band).
fn held(s: &Skeleton, task: &Task, posture: &Posture) -> usize {
    let TaskKind::Collision(c) = &task.kind else {
        return 0;
    };
    match task.feature(s, &Frames::new(s, posture), posture.values()) {
        TaskFeature::Vector(d) => d
            .iter()
            .filter(|&&d| d < c.margin() + COLLISION_BAND)
            .count(),
        TaskFeature::Rotation(_) => 0,
    }
}

/// A posture of the arms, the spine and the legs drawn at `amplitude` (radians, within the
/// limits), the root where it stands.
fn random_posture(s: &Skeleton, r: &mut StdRng, amplitude: f64) -> Posture {
    let mut p = Posture::rest(s);
    let (lo, hi) = (s.lower_limits(), s.upper_limits());
    for joint in s.joints().iter().skip(1) {
        for d in joint.dof_range() {
            let v: f64 = r.random_range(-amplitude..amplitude);
            p.values_mut()[d] = v.clamp(lo[d], hi[d]);
        }
    }
    p
}

/// The problem at `posture`: ankles pinned where they are, wrists 10 cm forward of where
/// they are, and the collision task at level 2 when given.
fn tasks(s: &Skeleton, posture: &Posture, collision: Option<&Task>) -> Result<Vec<Task>> {
    let frames = Frames::new(s, posture);
    let mut tasks = Vec::new();
    for foot in ["l_talocrural", "r_talocrural"] {
        let j = s.require_joint(foot)?;
        tasks.push(Task::position(j, DVec3::ZERO, frames.joint_position[j]));
    }
    if let Some(c) = collision {
        tasks.push(c.clone().at_level(2));
    }
    for wrist in ["l_radiocarpal", "r_radiocarpal"] {
        let j = s.require_joint(wrist)?;
        let goal = frames.joint_position[j] + DVec3::Z * 0.1;
        tasks.push(Task::position(j, DVec3::ZERO, goal).at_level(3));
    }
    Ok(tasks)
}

/// Median time (us) of `f`, in batches, over `budget`.
fn timed(budget: Duration, mut f: impl FnMut() -> Result<()>) -> Result<f64> {
    const BATCH: usize = 20;
    for _ in 0..BATCH {
        f()?;
    }
    let mut samples = Vec::new();
    let start = Instant::now();
    while start.elapsed() < budget || samples.len() < 5 {
        let t = Instant::now();
        for _ in 0..BATCH {
            f()?;
        }
        samples.push(t.elapsed().as_secs_f64() * 1e6 / BATCH as f64);
    }
    Ok(median(samples))
}

pub fn run(budget: Duration, json: bool) -> Result<()> {
    let body = default_skeleton(&SkeletonOptions {
        loa: LevelOfArticulation::Loa2,
        ..SkeletonOptions::default()
    })?;
    let s = &body.skeleton;
    let spec = BodyCollision::default();
    let c = spec.collision(s);
    let (capsules, pairs, floor) = (c.capsules().len(), c.pairs().len(), c.floor().len());
    let collision = Task::new(TaskKind::Collision(c));
    let mut r = StdRng::seed_from_u64(32);
    let mut rows = Vec::new();
    for wanted in [0usize, 4, 10] {
        // Postures drawn wider and wider until one holds about as many constraints as asked.
        let mut found = None;
        for attempt in 0..20_000 {
            let amplitude = 0.3 + 0.9 * (attempt % 10) as f64 / 10.0;
            let p = random_posture(s, &mut r, amplitude);
            let k = held(s, &collision, &p);
            if k == wanted || (wanted > 0 && k.abs_diff(wanted) <= 1) {
                found = Some((p, k));
                break;
            }
        }
        let Some((posture, k)) = found else {
            bail!("no posture with {wanted} constraints held");
        };
        let without = tasks(s, &posture, None)?;
        let with = tasks(s, &posture, Some(&collision))?;
        let per_iteration = |tasks: &[Task]| -> Result<f64> {
            Ok(crate::bench::bench(
                s,
                tasks,
                &posture,
                SolverSettings::default(),
                &BTreeMap::new(),
                budget,
                ITERATIONS,
            )?
            .us_per_iteration)
        };
        let us_without = per_iteration(&without)?;
        let us_with = per_iteration(&with)?;
        let frames = Frames::new(s, &posture);
        let us_search = timed(budget, || {
            std::hint::black_box(collision.residual(s, &frames, posture.values()));
            Ok(())
        })?;
        rows.push(Row {
            constraints: k,
            us_without,
            us_with,
            extra_percent: (us_with / us_without - 1.0) * 100.0,
            us_search,
        });
    }
    if json {
        println!("{}", serde_json::to_string(&rows)?);
        return Ok(());
    }
    println!(
        "collision on the H-Anim LOA 2 body ({} DOF): {capsules} capsules, {pairs} pairs, \
         {floor} above the floor; feet pinned (1), collision (2), two reaches (3)",
        s.dof_count()
    );
    println!(
        "{:>11} {:>12} {:>12} {:>8} {:>10}",
        "constraints", "us/iter w/o", "us/iter with", "extra", "us search"
    );
    for row in &rows {
        println!(
            "{:>11} {:>12.2} {:>12.2} {:>7.0}% {:>10.2}",
            row.constraints, row.us_without, row.us_with, row.extra_percent, row.us_search
        );
    }
    Ok(())
}
