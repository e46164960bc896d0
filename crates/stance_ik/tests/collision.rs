//! The collision task on the H-Anim body's capsules (`stance_hanim::capsules`): its rows'
//! Jacobian against central differences of the surfaces' distances, and a reach whose goal
//! lies inside the torso: with the task the forearm and hand stay outside every other
//! capsule they may touch, without it they go through.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use glam::DVec3;
use stance_hanim::capsules::body_capsules;
use stance_hanim::{LevelOfArticulation, SkeletonOptions, default_skeleton};
use stance_ik::{
    Capsule, Collision, Frames, Obstacle, ObstacleShape, Posture, Skeleton, Solver, SolverSettings,
    Task, TaskFeature, TaskKind, closest_points, collision_pairs, floor_capsules,
};

use crate::common::{finite_difference_jacobian, random_posture, rng};

fn loa2() -> Skeleton {
    default_skeleton(&SkeletonOptions {
        loa: LevelOfArticulation::Loa2,
        ..SkeletonOptions::default()
    })
    .map(|body| body.skeleton)
    .unwrap_or_else(|e| panic!("{e}"))
}

/// The constraints the tests' collision task holds at once, at most.
const ROWS: usize = 16;

fn collision(skeleton: &Skeleton, margin: f64) -> (Task, Vec<Capsule>, Vec<(usize, usize)>) {
    let capsules = body_capsules(skeleton);
    let rest = Frames::new(skeleton, &Posture::rest(skeleton));
    let pairs = collision_pairs(
        skeleton,
        &capsules,
        &rest,
        margin + stance_ik::COLLISION_BAND,
    );
    let task = Task::new(TaskKind::Collision(Collision::new(
        skeleton,
        capsules.clone(),
        pairs.clone(),
        floor_capsules(&capsules, &rest),
        margin,
        ROWS,
    )));
    (task, capsules, pairs)
}

/// The deepest overlap of the tested pairs at `posture` (m; negative: a gap), from the
/// capsules' world segments.
fn deepest(
    skeleton: &Skeleton,
    capsules: &[Capsule],
    pairs: &[(usize, usize)],
    posture: &Posture,
) -> f64 {
    let frames = Frames::new(skeleton, posture);
    pairs
        .iter()
        .map(|&(i, j)| {
            let (a0, a1) = capsules[i].world(&frames);
            let (b0, b1) = capsules[j].world(&frames);
            let (pa, pb) = closest_points(a0, a1, b0, b1);
            capsules[i].radius + capsules[j].radius - (pa - pb).length()
        })
        .fold(f64::NEG_INFINITY, f64::max)
}

/// Catches a row whose Jacobian is not the distance's derivative (the normal's sign, a closest
/// point moved with the wrong joint, the floor's row along another axis): random postures of
/// the LOA 2 body, a margin wide enough that several constraints hold, each against central
/// differences of the distances the task measures.
#[test]
fn collision_rows_are_the_derivatives_of_the_distances() {
    let s = loa2();
    let (task, _, _) = collision(&s, 0.08);
    let mut solver = Solver::default();
    let mut r = rng(21);
    let mut rows_checked = 0;
    for _ in 0..12 {
        let p = random_posture(&mut r, &s, 0.8);
        let analytic = solver
            .linear_systems(&s, std::slice::from_ref(&task), &p)
            .unwrap_or_else(|e| panic!("{e}"))[0]
            .jacobian_t
            .transpose();
        let numeric = finite_difference_jacobian(&s, &p, &task);
        // The level has the rows of the constraints found, nearest first, as the task
        // measures them; the rest of the task's rows are left out.
        assert!(analytic.nrows() <= task.rows());
        for row in 0..analytic.nrows() {
            let err = (analytic.row(row) - numeric.row(row)).amax();
            assert!(err < 1e-5, "row {row}: |J - FD| = {err}");
            rows_checked += 1;
        }
    }
    println!("collision: {rows_checked} rows checked against central differences");
    assert!(rows_checked >= 12, "{rows_checked} rows held");
}

/// Catches a collision task that does not hold the body apart, or that takes the step from
/// the levels above it: the right wrist pulled to a point inside the chest, the feet and the
/// chest pinned above it. With the collision task at level 2 no tested pair overlaps by more than a
/// millimetre and the feet hold; without it the hand goes into the torso.
#[test]
fn a_hand_pulled_into_the_chest_stays_outside_it() {
    let s = loa2();
    let (task, capsules, pairs) = collision(&s, 0.01);
    let rest = Posture::rest(&s);
    let frames = Frames::new(&s, &rest);
    let at = |name: &str| s.joint_index(name).unwrap_or_else(|| panic!("{name}"));
    // The middle of the bar between the collarbones: on the chest capsule's axis.
    let chest = frames.joint_position[at("l_sternoclavicular")]
        .lerp(frames.joint_position[at("r_sternoclavicular")], 0.5);
    // The feet and the chest held where they stand (the chest cannot lean away from the hand).
    let chest_joint = s.joints()[at("l_sternoclavicular")].parent.unwrap_or(0);
    let feet = [at("l_talocrural"), at("r_talocrural"), chest_joint]
        .map(|j| Task::position(j, DVec3::ZERO, frames.joint_position[j]).at_level(1));
    let reach = Task::position(at("r_radiocarpal"), DVec3::ZERO, chest).at_level(3);
    let solve = |with_collision: bool| {
        let mut tasks = feet.to_vec();
        if with_collision {
            tasks.push(task.clone().at_level(2));
        }
        tasks.push(reach.clone());
        let mut posture = rest.clone();
        let mut solver = Solver::new(SolverSettings {
            max_iterations: 300,
            ..SolverSettings::default()
        })
        .unwrap_or_else(|e| panic!("{e}"));
        let report = solver
            .solve(&s, &tasks, &mut posture)
            .unwrap_or_else(|e| panic!("{e}"));
        (posture, report)
    };
    let (free, _) = solve(false);
    assert!(
        deepest(&s, &capsules, &pairs, &free) > 0.02,
        "without the task the hand goes in: {}",
        deepest(&s, &capsules, &pairs, &free)
    );
    let (held, report) = solve(true);
    let overlap = deepest(&s, &capsules, &pairs, &held);
    println!(
        "collision: deepest overlap {:.1} mm without the task, {:.2} mm with it ({} iterations, {} pairs tested)",
        deepest(&s, &capsules, &pairs, &free) * 1e3,
        overlap * 1e3,
        report.iterations,
        pairs.len()
    );
    assert!(overlap < 0.001, "overlap {overlap} m");
    // The report counts the collision level's rows in use when last linearised (those of the
    // pairs inside the margin: none or a few, the hand resting on the chest just past it), not
    // the most the task may have (`ROWS`, what it said before).
    let level2 = report.levels.iter().find(|l| l.level == 2).map(|l| l.rows);
    println!("collision: {level2:?} rows in use at the end");
    assert!(
        level2.is_some_and(|rows| rows < ROWS),
        "collision rows in use {level2:?}"
    );
    let f = Frames::new(&s, &held);
    for j in [at("l_talocrural"), at("r_talocrural"), chest_joint] {
        assert!((f.joint_position[j] - frames.joint_position[j]).length() < 1e-4);
    }
    // The hand still reaches toward the chest, nearer than it started (the arm hanging at
    // rest slides up the body until it stops on it), and never inside the chest's capsule.
    let start = (frames.joint_position[at("r_radiocarpal")] - chest).length();
    let end = (f.joint_position[at("r_radiocarpal")] - chest).length();
    let bar = capsules
        .iter()
        .filter(|c| c.joint == chest_joint)
        .map(|c| c.radius)
        .fold(0.0, f64::max);
    assert!(
        end > bar,
        "the wrist {end} m from the chest bar's axis, radius {bar}"
    );
    println!(
        "collision: the wrist {:.3} m from the goal inside the chest (started {:.3})",
        end, start
    );
    assert!(end < start - 0.03, "{end} of {start} m left; {report:?}");
}

/// The distance between the segments `p0 p1` and `q0 q1` by another route than
/// `closest_points`: `p` sampled densely (400 points), the nearest sample's neighbourhood
/// sampled again as densely, each sample's distance to the segment `q` by its clamped
/// projection.
fn sampled_distance(p0: DVec3, p1: DVec3, q0: DVec3, q1: DVec3) -> f64 {
    const K: usize = 400;
    let to_q = |t: f64| {
        let p = p0.lerp(p1, t);
        let v = q1 - q0;
        let s = if v.length_squared() > 0.0 {
            ((p - q0).dot(v) / v.length_squared()).clamp(0.0, 1.0)
        } else {
            0.0
        };
        (p - (q0 + v * s)).length()
    };
    let best = (0..=K)
        .map(|k| k as f64 / K as f64)
        .min_by(|a, b| to_q(*a).total_cmp(&to_q(*b)))
        .unwrap_or(0.0);
    let h = 1.0 / K as f64;
    (0..=K)
        .map(|k| (best - h + 2.0 * h * k as f64 / K as f64).clamp(0.0, 1.0))
        .map(to_q)
        .fold(f64::INFINITY, f64::min)
}

/// The deepest overlap (m; negative: a gap) at `posture` of the capsule pairs tested and of
/// the floor capsules with the floor, measured by [`sampled_distance`].
fn deepest_sampled(s: &Skeleton, c: &Collision, posture: &Posture) -> f64 {
    let frames = Frames::new(s, posture);
    let capsules = c.capsules();
    let ends: Vec<_> = capsules.iter().map(|k| k.world(&frames)).collect();
    let pairs = c.pairs().iter().map(|&(i, j)| {
        let ((a0, a1), (b0, b1)) = (ends[i], ends[j]);
        // Bounding spheres first: a pair clearly apart needs no sampling.
        let apart = (a0.lerp(a1, 0.5) - b0.lerp(b1, 0.5)).length()
            - (a1 - a0).length() / 2.0
            - (b1 - b0).length() / 2.0;
        let reach = capsules[i].radius + capsules[j].radius;
        if apart > reach + 0.01 {
            return -apart;
        }
        reach - sampled_distance(a0, a1, b0, b1)
    });
    let floor = c.floor().iter().map(|&i| {
        let (a, b) = ends[i];
        capsules[i].radius - a.y.min(b.y)
    });
    pairs.chain(floor).fold(f64::NEG_INFINITY, f64::max)
}

/// Catches a collision task that lets the body through itself or the floor, or that takes
/// anything from the level above it, on generated reaches (seeded): a wrist pulled to a point
/// inside or behind the torso, across the body onto the other thigh, or below the floor, the
/// feet pinned at level 1. With the body's collision task at level 2 no tested pair (and no
/// floor capsule) overlaps by more than a millimetre and the feet hold; without it each
/// problem ends with an overlap (the goals lie inside the body or under the floor).
#[test]
fn generated_reaches_into_the_body_or_the_floor_stay_clear_with_the_task() {
    use stance_hanim::capsules::BodyCollision;
    let s = loa2();
    let c = BodyCollision::default().collision(&s);
    let collision = Task::new(TaskKind::Collision(c.clone())).at_level(2);
    let rest = Posture::rest(&s);
    let frames = Frames::new(&s, &rest);
    let at = |name: &str| s.joint_index(name).unwrap_or_else(|| panic!("{name}"));
    let position = |name: &str| frames.joint_position[at(name)];
    let feet = ["l_talocrural", "r_talocrural"]
        .map(|n| Task::position(at(n), DVec3::ZERO, position(n)).at_level(1));
    let mut r = rng(32);
    let mut unit = || crate::common::uniform(&mut r, -1.0, 1.0);
    let mut problems = Vec::new();
    for case in 0..9 {
        let (wrist, other) = if case % 2 == 0 {
            ("r_radiocarpal", "l")
        } else {
            ("l_radiocarpal", "r")
        };
        let goal = match case % 3 {
            // Inside the chest or the belly, or behind the back.
            0 => {
                let chest =
                    position("l_sternoclavicular").lerp(position("r_sternoclavicular"), 0.5);
                let belly = position("vl5");
                chest.lerp(belly, 0.5 + 0.5 * unit())
                    + DVec3::new(0.05 * unit(), 0.0, -0.1 - 0.05 * unit())
            }
            // Across the body: into the other thigh.
            1 => position(&format!("{other}_hip"))
                .lerp(position(&format!("{other}_knee")), 0.4 + 0.2 * unit()),
            // Below the floor, in front of the feet.
            _ => DVec3::new(0.15 * unit(), -0.1 + 0.05 * unit(), 0.3 + 0.1 * unit()),
        };
        problems.push((case, wrist, goal));
    }
    for (case, wrist, goal) in problems {
        let reach = Task::position(at(wrist), DVec3::ZERO, goal).at_level(3);
        let solve = |with: bool| {
            let mut tasks = feet.to_vec();
            if with {
                tasks.push(collision.clone());
            }
            tasks.push(reach.clone());
            let mut posture = rest.clone();
            let report = Solver::new(SolverSettings {
                max_iterations: 400,
                ..SolverSettings::default()
            })
            .unwrap_or_else(|e| panic!("{e}"))
            .solve(&s, &tasks, &mut posture)
            .unwrap_or_else(|e| panic!("{e}"));
            (posture, report)
        };
        let (free, free_report) = solve(false);
        let (held, report) = solve(true);
        let (without, with) = (
            deepest_sampled(&s, &c, &free),
            deepest_sampled(&s, &c, &held),
        );
        println!(
            "collision case {case} ({wrist} to {goal:.2}): deepest overlap {:.1} mm without, {:.2} mm with ({} iterations)",
            without * 1e3,
            with * 1e3,
            report.iterations
        );
        assert!(free_report.levels[0].met, "case {case}: {free_report:?}");
        assert!(without > 0.005, "case {case}: without the task {without} m");
        assert!(
            report.levels[0].met,
            "case {case}: the feet gave way: {report:?}"
        );
        assert!(with < 0.001, "case {case}: overlap {with} m with the task");
    }
}

/// The signed distance of the point `p` from `obstacle` by the textbook formulas, in the
/// solid's frame: the clamped point of a box, the radial and axial clamp of a cylinder, the
/// centre of a ball; inside, the nearest face (negative).
fn point_distance(obstacle: &Obstacle, p: DVec3) -> f64 {
    let q = obstacle.world_from_obstacle_rotation.transpose() * (p - obstacle.position);
    match obstacle.shape {
        ObstacleShape::Sphere { radius } => q.length() - radius,
        ObstacleShape::Box { half } => {
            let clamped = q.clamp(-half, half);
            if clamped == q {
                -(half - q.abs()).min_element()
            } else {
                (q - clamped).length()
            }
        }
        ObstacleShape::Cylinder {
            radius,
            half_height,
        } => {
            let r = (q.x * q.x + q.z * q.z).sqrt();
            let (dr, dy) = (r - radius, q.y.abs() - half_height);
            if dr <= 0.0 && dy <= 0.0 {
                dr.max(dy)
            } else {
                (dr.max(0.0).powi(2) + dy.max(0.0).powi(2)).sqrt()
            }
        }
    }
}

/// A random solid near the origin: a box (some flat, as a plane prop is), a ball or a
/// cylinder, turned at random.
fn random_obstacle(r: &mut rand::rngs::StdRng, case: usize) -> Obstacle {
    use crate::common::uniform;
    let size = |r: &mut rand::rngs::StdRng| uniform(r, 0.02, 0.4);
    let shape = match case % 4 {
        0 => ObstacleShape::Box {
            half: DVec3::new(size(r), size(r), size(r)),
        },
        1 => ObstacleShape::Box {
            half: DVec3::new(size(r), 0.0, size(r)),
        },
        2 => ObstacleShape::Sphere { radius: size(r) },
        _ => ObstacleShape::Cylinder {
            radius: size(r),
            half_height: size(r),
        },
    };
    let axis = crate::common::vec3(r, 1.0).normalize_or(DVec3::Y);
    Obstacle {
        shape,
        world_from_obstacle_rotation: glam::DMat3::from_axis_angle(axis, uniform(r, -3.0, 3.0)),
        position: crate::common::vec3(r, 0.2),
    }
}

/// Catches an obstacle distance that misses the nearest point of a capsule's axis (a search
/// that stops in the wrong place, an end left out, a box's inside measured wrongly): random
/// segments against random boxes, flat boxes, balls and cylinders, turned at random, some
/// passing through them; the signed distance equals the least of 4,000 points along the
/// segment and 4,000 more around the best of them, each measured by the solid's textbook
/// formula, within 1e-6 m.
#[test]
fn obstacle_distances_match_dense_sampling_along_the_capsule() {
    let mut r = rng(33);
    let mut through = 0;
    for case in 0..400 {
        let obstacle = random_obstacle(&mut r, case);
        let a = crate::common::vec3(&mut r, 0.6);
        let b = if case % 7 == 0 {
            a
        } else {
            crate::common::vec3(&mut r, 0.6)
        };
        let (point, signed, normal) = obstacle.nearest_on_segment(a, b);
        // 4,000 points along the segment, then 4,000 around the best of them.
        const K: usize = 4000;
        let at = |t: f64| point_distance(&obstacle, a.lerp(b, t));
        let best = (0..=K)
            .map(|k| k as f64 / K as f64)
            .min_by(|x, y| at(*x).total_cmp(&at(*y)))
            .unwrap();
        let h = 1.0 / K as f64;
        let sampled = (0..=K)
            .map(|k| at((best - h + 2.0 * h * k as f64 / K as f64).clamp(0.0, 1.0)))
            .fold(f64::INFINITY, f64::min);
        assert!(
            (signed - sampled).abs() < 1e-6,
            "case {case}: {signed} vs sampled {sampled} ({obstacle:?}, {a} {b})"
        );
        assert!((point_distance(&obstacle, point) - signed).abs() < 1e-9);
        assert!(normal.length() <= 1.0 + 1e-9, "case {case}");
        if signed > 0.0 {
            assert!(
                (normal.length() - 1.0).abs() < 1e-9,
                "case {case}: outside, a unit normal"
            );
        }
        through += usize::from(signed < 0.0);
    }
    println!("obstacles: 400 segments checked, {through} through the solid");
    assert!(through >= 20, "{through} segments through a solid");
}

/// Props near the LOA 2 body at random postures: a box before the chest, a slab under the
/// hands, a ball at the right hand, a bar across the front.
fn props_around(s: &Skeleton) -> Vec<Obstacle> {
    let rest = Frames::new(s, &Posture::rest(s));
    let at = |name: &str| rest.joint_position[s.joint_index(name).unwrap()];
    let turn = glam::DMat3::from_axis_angle(DVec3::new(1.0, 2.0, 0.5).normalize(), 0.4);
    vec![
        Obstacle {
            shape: ObstacleShape::Box {
                half: DVec3::new(0.2, 0.1, 0.05),
            },
            world_from_obstacle_rotation: turn,
            position: at("vt6") + DVec3::new(0.0, 0.0, 0.22),
        },
        Obstacle {
            shape: ObstacleShape::Box {
                half: DVec3::new(0.3, 0.03, 0.2),
            },
            world_from_obstacle_rotation: glam::DMat3::IDENTITY,
            position: at("r_radiocarpal") - DVec3::Y * 0.1,
        },
        Obstacle {
            shape: ObstacleShape::Sphere { radius: 0.1 },
            world_from_obstacle_rotation: glam::DMat3::IDENTITY,
            position: at("r_radiocarpal") + DVec3::new(-0.05, 0.0, 0.14),
        },
        Obstacle {
            shape: ObstacleShape::Cylinder {
                radius: 0.03,
                half_height: 0.5,
            },
            world_from_obstacle_rotation: glam::DMat3::from_rotation_z(std::f64::consts::FRAC_PI_2),
            position: at("l_radiocarpal") + DVec3::new(0.0, 0.05, 0.1),
        },
    ]
}

/// Catches an obstacle row whose Jacobian is not its distance's derivative (the normal's sign
/// or frame, the point moved with the wrong joint): the LOA 2 body's capsules against four
/// props (a turned box, a slab, a ball, a bar) at random postures, with a margin wide
/// enough that several hold, each row against central differences.
#[test]
fn obstacle_rows_are_the_derivatives_of_the_distances() {
    let s = loa2();
    let capsules = body_capsules(&s);
    let c = Collision::new(&s, capsules, Vec::new(), Vec::new(), 0.08, 16)
        .with_obstacles(props_around(&s));
    c.validate(&s).unwrap();
    let task = Task::new(TaskKind::Collision(c));
    let mut solver = Solver::default();
    let mut r = rng(34);
    let mut rows_checked = 0;
    for _ in 0..12 {
        let p = random_posture(&mut r, &s, 0.5);
        let analytic = solver
            .linear_systems(&s, std::slice::from_ref(&task), &p)
            .unwrap_or_else(|e| panic!("{e}"))[0]
            .jacobian_t
            .transpose();
        let numeric = finite_difference_jacobian(&s, &p, &task);
        // Central differences measure a row only where the rows found stay the same a step
        // either side: not at the edge of the reach, nor where two rows' order may swap.
        let frames = Frames::new(&s, &p);
        let TaskFeature::Vector(distances) = task.feature(&s, &frames, p.values()) else {
            panic!("a collision task's feature is its distances");
        };
        let reach = 0.08 + stance_ik::COLLISION_BAND;
        for row in 0..analytic.nrows() {
            let d = distances[row];
            let apart = |other: Option<&f64>| other.is_none_or(|o| (o - d).abs() > 1e-4);
            if d > reach - 1e-4
                || !apart(distances.get(row + 1))
                || !apart(row.checked_sub(1).and_then(|r| distances.get(r)))
            {
                continue;
            }
            let err = (analytic.row(row) - numeric.row(row)).amax();
            assert!(err < 1e-5, "row {row} at {d} m: |J - FD| = {err}");
            rows_checked += 1;
        }
    }
    println!("obstacles: {rows_checked} rows checked against central differences");
    assert!(rows_checked >= 12, "{rows_checked} rows held");
}

/// Catches props that do not push the body out: the right wrist pulled to the middle of a box
/// standing before the body at hip height (a table), the feet pinned. With the collision task
/// (the box among its obstacles) no capsule held off it goes more than a millimetre in,
/// measured by sampling each capsule's axis; without, the hand goes in.
#[test]
fn a_hand_pulled_into_a_box_stays_on_its_surface() {
    use stance_hanim::capsules::BodyCollision;
    let s = loa2();
    let rest = Posture::rest(&s);
    let frames = Frames::new(&s, &rest);
    let at = |name: &str| s.joint_index(name).unwrap();
    let wrist = frames.joint_position[at("r_radiocarpal")];
    let table = Obstacle {
        shape: ObstacleShape::Box {
            half: DVec3::new(0.4, 0.05, 0.15),
        },
        world_from_obstacle_rotation: glam::DMat3::IDENTITY,
        position: DVec3::new(0.0, wrist.y + 0.15, wrist.z + 0.35),
    };
    let c = BodyCollision::default()
        .collision(&s)
        .with_obstacles(vec![table]);
    let feet = ["l_talocrural", "r_talocrural"]
        .map(|n| Task::position(at(n), DVec3::ZERO, frames.joint_position[at(n)]).at_level(1));
    let reach = Task::position(at("r_radiocarpal"), DVec3::ZERO, table.position).at_level(3);
    let deepest = |posture: &Posture| {
        let f = Frames::new(&s, posture);
        c.capsules()
            .iter()
            .filter(|k| {
                let (a, b) = k.world(&rest_frames(&s));
                a.y.min(b.y) - k.radius > 0.0
            })
            .map(|k| {
                let (a, b) = k.world(&f);
                let nearest = (0..=2000)
                    .map(|i| point_distance(&table, a.lerp(b, f64::from(i) / 2000.0)))
                    .fold(f64::INFINITY, f64::min);
                k.radius - nearest
            })
            .fold(f64::NEG_INFINITY, f64::max)
    };
    let solve = |with: bool| {
        let mut tasks = feet.to_vec();
        if with {
            tasks.push(Task::new(TaskKind::Collision(c.clone())).at_level(2));
        }
        tasks.push(reach.clone());
        let mut posture = rest.clone();
        let report = Solver::new(SolverSettings {
            max_iterations: 300,
            ..SolverSettings::default()
        })
        .unwrap()
        .solve(&s, &tasks, &mut posture)
        .unwrap();
        (posture, report)
    };
    let (free, _) = solve(false);
    let (held, report) = solve(true);
    println!(
        "obstacles: the hand into a box: {:.1} mm deep without the task, {:.2} mm with it ({} iterations)",
        deepest(&free) * 1e3,
        deepest(&held) * 1e3,
        report.iterations
    );
    assert!(deepest(&free) > 0.02, "without: {}", deepest(&free));
    assert!(deepest(&held) < 0.001, "with: {}", deepest(&held));
    assert!(report.levels[0].met, "the feet held: {report:?}");
    // The hand reached the box's near face, not stopped short.
    let f = Frames::new(&s, &held);
    let hand = f.joint_position[at("r_radiocarpal")];
    assert!(
        point_distance(&table, hand) < 0.06,
        "the wrist {hand} off the box"
    );
}

fn rest_frames(s: &Skeleton) -> Frames {
    Frames::new(s, &Posture::rest(s))
}

/// Catches a collision task that holds a placed hand off the surface it is put on (the hand
/// hovered 5.6 cm over a table with collision on, its plane task giving way) or stops it
/// sliding there: the right wrist put on a box's top (a point-on-plane task below the
/// collision level) at one point, then moved 15 cm across the top by a goal on the floor's
/// axes. With the collision tasks leaving the placed hand and forearm off that box
/// (`with_placed_parts`), the wrist lies on the top (the box's centre plus its half height,
/// by hand) within a millimetre at both points and reaches each; the rest of the body keeps
/// off the box. Without it, the hand cannot rest on the box at its goals.
#[test]
fn a_hand_put_on_a_box_stays_on_its_top_and_slides() {
    use stance_hanim::capsules::BodyCollision;
    use stance_ik::{Axes, Effector, with_placed_parts};
    let s = loa2();
    let rest = Posture::rest(&s);
    let frames = Frames::new(&s, &rest);
    let at = |name: &str| s.joint_index(name).unwrap();
    let wrist = frames.joint_position[at("r_radiocarpal")];
    let half = DVec3::new(0.3, 0.05, 0.2);
    let centre = DVec3::new(wrist.x, wrist.y + 0.05 - half.y, wrist.z + 0.4);
    let top = centre.y + half.y;
    let table = Obstacle {
        shape: ObstacleShape::Box { half },
        world_from_obstacle_rotation: glam::DMat3::IDENTITY,
        position: centre,
    };
    let collision = Task::new(TaskKind::Collision(
        BodyCollision::default()
            .collision(&s)
            .with_obstacles(vec![table]),
    ))
    .at_level(2);
    let feet = ["l_talocrural", "r_talocrural"]
        .map(|n| Task::position(at(n), DVec3::ZERO, frames.joint_position[at(n)]).at_level(1));
    let on_top = Task::point_on_plane(
        at("r_radiocarpal"),
        DVec3::ZERO,
        DVec3::new(centre.x, top, centre.z),
        DVec3::Y,
        false,
    )
    .at_level(3);
    let across = |goal: DVec3| {
        Task::new(TaskKind::Position {
            effector: Effector {
                joint: at("r_radiocarpal"),
                point: DVec3::ZERO,
            },
            axes: Axes::XZ,
            target: goal,
        })
        .at_level(4)
    };
    let first = DVec3::new(centre.x, top, centre.z - 0.1);
    let second = first + DVec3::new(0.15, 0.0, 0.0);
    // The wrist's height over the top at each goal and its distance from the goal across it.
    let place = |placed: bool| {
        let mut posture = rest.clone();
        let mut solver = Solver::new(SolverSettings {
            max_iterations: 300,
            ..SolverSettings::default()
        })
        .unwrap();
        [first, second].map(|goal| {
            let mut tasks = feet.to_vec();
            tasks.extend([collision.clone(), on_top.clone(), across(goal)]);
            if placed {
                with_placed_parts(&s, &mut tasks);
            }
            solver.solve(&s, &tasks, &mut posture).unwrap();
            let w = Frames::new(&s, &posture).joint_position[at("r_radiocarpal")];
            let off = glam::DVec2::new(w.x - goal.x, w.z - goal.z).length();
            (w.y - top, off, posture.clone())
        })
    };
    let held_off = place(false);
    let placed = place(true);
    for (k, (height, off, _)) in placed.iter().enumerate() {
        println!(
            "placed hand, goal {k}: the wrist {:.2} mm over the top, {:.2} mm from its goal \
             (held off: {:.1} mm over, {:.1} mm from its goal)",
            height * 1e3,
            off * 1e3,
            held_off[k].0 * 1e3,
            held_off[k].1 * 1e3
        );
        assert!(
            height.abs() < 1e-3,
            "goal {k}: the wrist {height} m over the top"
        );
        assert!(*off < 1e-3, "goal {k}: the wrist {off} m from its goal");
    }
    // Without the exemption the hand cannot rest on the box at its goal: the collision level
    // holds it over the top (the constant damping's path: 49 mm) or the plane task puts it on
    // the top's plane beside the box, the goal across given up (the falling damping's path).
    assert!(
        held_off
            .iter()
            .any(|(height, off, _)| *height > 0.01 || *off > 0.01),
        "without the placed hand's exemption the wrist rests on the box at its goals: {:?}",
        held_off.iter().map(|h| (h.0, h.1)).collect::<Vec<_>>()
    );
    // Every capsule held off the box but the right hand's and forearm's stays out of it,
    // by sampling along each capsule.
    let hand = |mut j: usize| loop {
        if j == at("r_radiocarpal") || j == at("r_elbow") {
            break true;
        }
        match s.joints()[j].parent {
            Some(p) if p != at("r_elbow") => j = p,
            _ => break false,
        }
    };
    let rest_frames = rest_frames(&s);
    for (_, _, posture) in &placed {
        let f = Frames::new(&s, posture);
        let c = BodyCollision::default().collision(&s);
        for k in c.capsules() {
            let (a, b) = k.world(&rest_frames);
            if a.y.min(b.y) - k.radius <= 0.0 || hand(k.joint) {
                continue;
            }
            let (a, b) = k.world(&f);
            let nearest = (0..=400)
                .map(|i| point_distance(&table, a.lerp(b, f64::from(i) / 400.0)))
                .fold(f64::INFINITY, f64::min);
            assert!(
                k.radius - nearest < 1e-3,
                "{} into the box by {} m",
                s.joints()[k.joint].name,
                k.radius - nearest
            );
        }
    }
}

/// Two bars on hinges about Z from a fixed base, 10 cm apart and parallel at rest, their
/// capsules 1 mm past a 1 cm margin (within the 2 mm band where a contact still shows), the
/// first bar's tip held (level 1) with the collision task; a goal for the second bar's tip
/// (level 3) on its circle, turned by `angle` (rad: positive away from the first, negative
/// into it). Returns the second tip's distance from its goal and the surfaces' distance by
/// [`sampled_distance`].
fn two_bars(angle: f64) -> (f64, f64) {
    use stance_ik::{Dof, JointDef};
    let hinge =
        |name: &str, y: f64| JointDef::new(name, Some("base"), DVec3::new(0.0, y, 0.0), &[Dof::Rz]);
    let s = Skeleton::new(vec![
        JointDef::new("base", None, DVec3::ZERO, &[]),
        hinge("a", 0.0),
        JointDef::new("a_tip", Some("a"), DVec3::X, &[]),
        hinge("b", 0.1),
        JointDef::new("b_tip", Some("b"), DVec3::X, &[]),
    ])
    .unwrap();
    let (margin, radius) = (0.01, (0.1 - 0.011) / 2.0);
    let bar = |joint: usize| Capsule {
        joint,
        start: DVec3::X * 0.2,
        end: DVec3::X,
        radius,
    };
    let (a, b) = (s.joint_index("a").unwrap(), s.joint_index("b").unwrap());
    let capsules = vec![bar(a), bar(b)];
    let collision = Collision::new(&s, capsules.clone(), vec![(0, 1)], vec![], margin, 4);
    let rest = Posture::rest(&s);
    let frames = Frames::new(&s, &rest);
    let tips = (
        s.joint_index("a_tip").unwrap(),
        s.joint_index("b_tip").unwrap(),
    );
    let goal = DVec3::new(angle.cos(), 0.1 + angle.sin(), 0.0);
    let tasks = vec![
        Task::position(tips.0, DVec3::ZERO, frames.joint_position[tips.0]),
        Task::new(TaskKind::Collision(collision)).at_level(2),
        Task::position(tips.1, DVec3::ZERO, goal).at_level(3),
    ];
    let mut posture = rest.clone();
    Solver::new(SolverSettings {
        max_iterations: 300,
        ..SolverSettings::default()
    })
    .unwrap()
    .solve(&s, &tasks, &mut posture)
    .unwrap();
    let f = Frames::new(&s, &posture);
    let ((a0, a1), (b0, b1)) = (capsules[0].world(&f), capsules[1].world(&f));
    (
        (f.joint_position[tips.1] - goal).length(),
        sampled_distance(a0, a1, b0, b1) - 2.0 * radius,
    )
}

/// Catches an inequality row that holds its surfaces from parting (what the task's rows did
/// within 2 mm past the margin: a zero error there, so a pull away stalled) or lets them
/// meet: a bar pulled away from the other, starting 1 mm past the margin, reaches its goal
/// (the rotation it needs parts them by centimetres); pulled into the other, it stops with
/// the surfaces no nearer than the margin (within 0.1 mm), by sampling.
#[test]
fn an_inequality_row_stops_surfaces_meeting_not_parting() {
    let (away, apart) = two_bars(0.25);
    println!(
        "two bars: pulled apart, the tip {away:.2e} m from its goal, surfaces {apart:.4} m apart"
    );
    assert!(
        away < 1e-4,
        "the tip {away} m from its goal away from the other bar"
    );
    assert!(apart > 0.02, "they parted: {apart} m");
    let (short, gap) = two_bars(-0.2);
    println!(
        "two bars: pulled together, the tip {short:.3} m from its goal, surfaces {gap:.4} m apart"
    );
    assert!(
        gap > 0.01 - 1e-4,
        "the surfaces {gap} m apart, the margin 0.01 m"
    );
    assert!(
        short > 0.05,
        "the goal inside the other bar is not reached: {short} m"
    );
}
