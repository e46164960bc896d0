//! Seeded random documents and comparison within the link quantisation.

#![allow(dead_code)]
#![allow(clippy::expect_used, clippy::unwrap_used, clippy::panic)]

use glam::DQuat;
use rand::rngs::StdRng;
use rand::{RngExt, SeedableRng};
use stance_document::link::{DIRECTION_STEP, POSITION_STEP_M, ROTATION_STEP_RAD};
use stance_document::{
    AvatarReference, Document, DofValues, LimbName, PostureValues, TaskKindSpec, TaskSpec,
};
use stance_hanim::{LevelOfArticulation, all_joints, humanoid_joints};
use stance_ik::{Axes, Dof};

pub fn rng(seed: u64) -> StdRng {
    StdRng::seed_from_u64(seed)
}

pub fn uniform(r: &mut StdRng, lo: f64, hi: f64) -> f64 {
    lo + (hi - lo) * r.random::<f64>()
}

pub fn v3(r: &mut StdRng, s: f64) -> [f64; 3] {
    [uniform(r, -s, s), uniform(r, -s, s), uniform(r, -s, s)]
}

const EXTRA_NAMES: [&str; 4] = ["l_ankle", "Hips", "mixamorig:LeftHand", "tail_1 ü"];

fn random_joint_name(r: &mut StdRng) -> String {
    if r.random_bool(0.9) {
        let t = all_joints();
        t[r.random_range(0..t.len())].name.to_owned()
    } else {
        EXTRA_NAMES[r.random_range(0..EXTRA_NAMES.len())].to_owned()
    }
}

fn random_axes(r: &mut StdRng) -> Axes {
    if r.random_bool(0.5) {
        Axes::XYZ
    } else {
        loop {
            let a = Axes::new(r.random_bool(0.5), r.random_bool(0.5), r.random_bool(0.5));
            if a.count() > 0 {
                return a;
            }
        }
    }
}

pub fn random_posture(r: &mut StdRng) -> PostureValues {
    let mut p = PostureValues::default();
    let table = all_joints();
    let loa = r.random_range(0..5usize);
    let density = uniform(r, 0.0, 1.0);
    for (i, d) in table.iter().enumerate() {
        let base = loa > 0 && usize::from(d.first_loa) <= loa;
        let present = if r.random_bool(0.9) {
            base
        } else {
            r.random_bool(density)
        };
        if !present {
            continue;
        }
        let mut v = DofValues::default();
        let full = r.random_bool(0.8);
        for dof in Dof::ALL {
            let default = if i == 0 { true } else { dof.is_rotation() };
            let keep = if full { default } else { r.random_bool(0.5) };
            if keep {
                let x = match r.random_range(0..4) {
                    0 => 0.0,
                    1 => uniform(r, -0.1, 0.1),
                    2 => uniform(r, -3.2, 3.2),
                    _ => uniform(r, -50.0, 50.0),
                };
                v.set(dof, x);
            }
        }
        p.joints.insert(d.name.to_owned(), v);
    }
    for _ in 0..r.random_range(0..3) {
        let mut v = DofValues::default();
        v.set(Dof::Ry, uniform(r, -1.0, 1.0));
        if r.random_bool(0.5) {
            v.set(Dof::Tx, uniform(r, -1.0, 1.0));
        }
        p.joints.insert(
            EXTRA_NAMES[r.random_range(0..EXTRA_NAMES.len())].to_owned(),
            v,
        );
    }
    p
}

pub fn random_task(r: &mut StdRng) -> TaskSpec {
    let kind = match r.random_range(0..8) {
        0 => TaskKindSpec::Position {
            joint: random_joint_name(r),
            point: if r.random_bool(0.5) {
                [0.0; 3]
            } else {
                v3(r, 0.3)
            },
            axes: random_axes(r),
            target: v3(r, 2.0),
        },
        1 => TaskKindSpec::Orientation {
            joint: random_joint_name(r),
            target: {
                let q = [
                    uniform(r, -1.0, 1.0),
                    uniform(r, -1.0, 1.0),
                    uniform(r, -1.0, 1.0),
                    uniform(r, -1.0, 1.0),
                ];
                if q.iter().map(|x| x * x).sum::<f64>() < 1e-4 {
                    [0.0, 0.0, 0.0, 1.0]
                } else {
                    q
                }
            },
        },
        2 => TaskKindSpec::Gaze {
            joint: random_joint_name(r),
            axis: if r.random_bool(0.5) {
                [0.0, 0.0, 1.0]
            } else {
                let a = v3(r, 1.0);
                if a.iter().map(|x| x * x).sum::<f64>() < 1e-4 {
                    [1.0, 0.0, 0.0]
                } else {
                    a
                }
            },
            point: if r.random_bool(0.5) {
                [0.0; 3]
            } else {
                v3(r, 0.2)
            },
            target: v3(r, 3.0),
        },
        3 => TaskKindSpec::Com {
            axes: random_axes(r),
            target: v3(r, 1.0),
        },
        4 => TaskKindSpec::Posture {
            joints: r.random_bool(0.5).then(|| {
                (0..r.random_range(0..6))
                    .map(|_| random_joint_name(r))
                    .collect()
            }),
            reference: r.random_bool(0.3).then(|| random_posture(r)),
        },
        6 => TaskKindSpec::Direction {
            joint: random_joint_name(r),
            axis: if r.random_bool(0.5) {
                [0.0, 1.0, 0.0]
            } else {
                nonzero3(v3(r, 1.0))
            },
            target: nonzero3(v3(r, 1.0)),
        },
        7 => TaskKindSpec::Balance {
            support: r.random_bool(0.5).then(|| {
                (0..r.random_range(1..5))
                    .map(|_| random_joint_name(r))
                    .collect()
            }),
            margin: if r.random_bool(0.5) {
                0.02
            } else {
                uniform(r, 0.0, 0.1)
            },
        },
        _ => {
            let named = r.random_bool(0.7);
            TaskKindSpec::Limb {
                limb: named.then(|| LimbName::ALL[r.random_range(0..4)]),
                joints: (!named).then(|| {
                    [
                        random_joint_name(r),
                        random_joint_name(r),
                        random_joint_name(r),
                    ]
                }),
                target: v3(r, 1.5),
                swivel: r.random_bool(0.7).then(|| uniform(r, -3.0, 3.0)),
                orientation: r.random_bool(0.3).then(|| {
                    [
                        uniform(r, -1.0, 1.0),
                        uniform(r, -1.0, 1.0),
                        0.5,
                        uniform(r, -1.0, 1.0),
                    ]
                }),
            }
        }
    };
    TaskSpec {
        level: if r.random_bool(0.9) {
            r.random_range(1..6)
        } else {
            r.random_range(1..100_000)
        },
        weight: match r.random_range(0..3) {
            0 => 1.0,
            1 => 0.0,
            _ => uniform(r, 0.0, 100.0),
        },
        active: r.random_bool(0.8),
        kind,
        interval: None,
        on: None,
    }
}

fn nonzero3(a: [f64; 3]) -> [f64; 3] {
    if a.iter().map(|x| x * x).sum::<f64>() < 1e-4 {
        [1.0, 0.0, 0.0]
    } else {
        a
    }
}

pub fn random_document(r: &mut StdRng) -> Document {
    Document {
        rest: Default::default(),
        clip: None,
        avatar: if r.random_bool(0.5) {
            AvatarReference::Default
        } else {
            AvatarReference::Url(format!(
                "https://example.org/avatars/{}.vrm?v={}",
                r.random_range(0..100_000u32),
                r.random_range(0..100u32)
            ))
        },
        posture: random_posture(r),
        tasks: (0..r.random_range(0..10)).map(|_| random_task(r)).collect(),
        motion: None,
        camera: None,
        stiffness: if r.random_bool(0.3) {
            random_stiffness(r)
        } else {
            PostureValues::default()
        },
    }
}

/// Stiffness of a few joints (any name of the H-Anim table), rotation DOF only, in [0, 1).
pub fn random_stiffness(r: &mut StdRng) -> PostureValues {
    let mut p = PostureValues::default();
    let table = all_joints();
    for _ in 0..r.random_range(1..6) {
        let name = table[r.random_range(0..table.len())].name;
        for dof in [Dof::Rx, Dof::Ry, Dof::Rz] {
            if r.random_bool(0.6) {
                let v = match r.random_range(0..3) {
                    0 => 0.0,
                    1 => uniform(r, 0.0, 1.0).min(0.999_999),
                    _ => 0.999_999,
                };
                p.set(name, dof, v);
            }
        }
    }
    p
}

/// A full LOA2 posture: every LOA2 joint with 3 non-zero rotation DOF drawn uniformly in
/// `[-spread, spread]` rad (away from 0), the root with 6 DOF.
pub fn loa2_posture(r: &mut StdRng, spread: f64) -> PostureValues {
    let mut p = PostureValues::default();
    for j in humanoid_joints(LevelOfArticulation::Loa2) {
        let name = j.definition.name;
        for d in [Dof::Rx, Dof::Ry, Dof::Rz] {
            let mut x: f64 = 0.0;
            while x.abs() < 1e-3 {
                x = uniform(r, -spread, spread);
            }
            p.set(name, d, x);
        }
        if name == "humanoid_root" {
            p.set(name, Dof::Tx, uniform(r, -1.0, 1.0));
            p.set(name, Dof::Ty, uniform(r, -0.3, 0.1));
            p.set(name, Dof::Tz, uniform(r, -1.0, 1.0));
            for d in [Dof::Rx, Dof::Ry, Dof::Rz] {
                p.set(name, d, uniform(r, -3.1, 3.1));
            }
        }
    }
    p
}

/// The Table-1 kind of task set: foot, gaze and right hand at level 1, centre of mass at 2,
/// left hand at 3, posture attraction at 4 (6 tasks), with random goals.
pub fn table1_tasks(r: &mut StdRng) -> Vec<TaskSpec> {
    let pos = |r: &mut StdRng, joint: &str, level: u32| TaskSpec {
        level,
        ..TaskSpec::new(TaskKindSpec::Position {
            joint: joint.to_owned(),
            point: [0.0; 3],
            axes: Axes::XYZ,
            target: [
                uniform(r, -0.8, 0.8),
                uniform(r, 0.0, 1.8),
                uniform(r, -0.8, 0.8),
            ],
        })
    };
    vec![
        pos(r, "l_talocrural", 1),
        TaskSpec::new(TaskKindSpec::Gaze {
            joint: "skullbase".to_owned(),
            axis: [0.0, 0.0, 1.0],
            point: [0.0; 3],
            target: [
                uniform(r, -2.0, 2.0),
                uniform(r, 0.0, 2.0),
                uniform(r, 0.5, 3.0),
            ],
        }),
        pos(r, "r_radiocarpal", 1),
        TaskSpec {
            level: 2,
            ..TaskSpec::new(TaskKindSpec::Com {
                axes: Axes::XZ,
                target: [uniform(r, -0.2, 0.2), 0.0, uniform(r, -0.2, 0.2)],
            })
        },
        pos(r, "l_radiocarpal", 3),
        TaskSpec {
            level: 4,
            weight: 0.1,
            ..TaskSpec::new(TaskKindSpec::Posture {
                joints: None,
                reference: None,
            })
        },
    ]
}

fn close(a: f64, b: f64, step: f64) -> bool {
    (a - b).abs() <= step * 0.5 * (1.0 + 1e-9) + 1e-12
}

fn close3(a: [f64; 3], b: [f64; 3], step: f64) -> bool {
    a.iter().zip(b).all(|(x, y)| close(*x, y, step))
}

fn unit(a: [f64; 3]) -> [f64; 3] {
    let n = a.iter().map(|x| x * x).sum::<f64>().sqrt();
    [a[0] / n, a[1] / n, a[2] / n]
}

pub fn posture_close(a: &PostureValues, b: &PostureValues) -> Result<(), String> {
    if a.joints.keys().ne(b.joints.keys()) {
        return Err(format!(
            "joints differ: {:?} vs {:?}",
            a.joints.keys().collect::<Vec<_>>(),
            b.joints.keys().collect::<Vec<_>>()
        ));
    }
    for (name, va) in &a.joints {
        let vb = &b.joints[name];
        for d in Dof::ALL {
            let step = if d.is_rotation() {
                ROTATION_STEP_RAD
            } else {
                POSITION_STEP_M
            };
            match (va.get(d), vb.get(d)) {
                (None, None) => {}
                (Some(x), Some(y)) if close(x, y, step) => {}
                other => return Err(format!("{name}.{}: {other:?}", d.name())),
            }
        }
    }
    Ok(())
}

/// `b` equals `a` within the link quantisation.
pub fn document_close(a: &Document, b: &Document) -> Result<(), String> {
    if a.avatar != b.avatar {
        return Err(format!("avatar {:?} vs {:?}", a.avatar, b.avatar));
    }
    posture_close(&a.posture, &b.posture).map_err(|e| format!("posture: {e}"))?;
    posture_close(&a.stiffness, &b.stiffness).map_err(|e| format!("stiffness: {e}"))?;
    if a.tasks.len() != b.tasks.len() {
        return Err("task count".into());
    }
    for (i, (x, y)) in a.tasks.iter().zip(&b.tasks).enumerate() {
        let bad = |what: &str| Err(format!("tasks[{i}] {what}: {x:?} vs {y:?}"));
        if x.level != y.level || x.active != y.active || x.weight.to_bits() != y.weight.to_bits() {
            return bad("header");
        }
        let ok = match (&x.kind, &y.kind) {
            (
                TaskKindSpec::Position {
                    joint: j1,
                    point: p1,
                    axes: a1,
                    target: t1,
                },
                TaskKindSpec::Position {
                    joint: j2,
                    point: p2,
                    axes: a2,
                    target: t2,
                },
            ) => {
                j1 == j2
                    && a1 == a2
                    && close3(*p1, *p2, POSITION_STEP_M)
                    && close3(*t1, *t2, POSITION_STEP_M)
            }
            (
                TaskKindSpec::Orientation {
                    joint: j1,
                    target: q1,
                },
                TaskKindSpec::Orientation {
                    joint: j2,
                    target: q2,
                },
            ) => {
                let q1 = DQuat::from_array(*q1).normalize();
                let q2 = DQuat::from_array(*q2).normalize();
                // Each rotation-vector component within half a step: the rotation within
                // sqrt(3)/2 steps (plus the slack of the exponential map's Jacobian).
                j1 == j2 && q1.angle_between(q2) <= ROTATION_STEP_RAD * 1.0 + 1e-9
            }
            (
                TaskKindSpec::Gaze {
                    joint: j1,
                    axis: a1,
                    point: p1,
                    target: t1,
                },
                TaskKindSpec::Gaze {
                    joint: j2,
                    axis: a2,
                    point: p2,
                    target: t2,
                },
            ) => {
                j1 == j2
                    && close3(unit(*a1), *a2, DIRECTION_STEP)
                    && close3(*p1, *p2, POSITION_STEP_M)
                    && close3(*t1, *t2, POSITION_STEP_M)
            }
            (
                TaskKindSpec::Direction {
                    joint: j1,
                    axis: a1,
                    target: t1,
                },
                TaskKindSpec::Direction {
                    joint: j2,
                    axis: a2,
                    target: t2,
                },
            ) => {
                j1 == j2
                    && close3(unit(*a1), *a2, DIRECTION_STEP)
                    && close3(unit(*t1), *t2, DIRECTION_STEP)
            }
            (
                TaskKindSpec::Balance {
                    support: s1,
                    margin: m1,
                },
                TaskKindSpec::Balance {
                    support: s2,
                    margin: m2,
                },
            ) => s1 == s2 && close(*m1, *m2, POSITION_STEP_M),
            (
                TaskKindSpec::Com {
                    axes: a1,
                    target: t1,
                },
                TaskKindSpec::Com {
                    axes: a2,
                    target: t2,
                },
            ) => a1 == a2 && close3(*t1, *t2, POSITION_STEP_M),
            (a @ TaskKindSpec::Comfort { .. }, b @ TaskKindSpec::Comfort { .. }) => a == b,
            (
                TaskKindSpec::Collision {
                    margin: m1,
                    self_collision: s1,
                    floor: f1,
                },
                TaskKindSpec::Collision {
                    margin: m2,
                    self_collision: s2,
                    floor: f2,
                },
            ) => s1 == s2 && f1 == f2 && (m1 - m2).abs() <= POSITION_STEP_M / 2.0,
            (
                TaskKindSpec::Posture {
                    joints: j1,
                    reference: r1,
                },
                TaskKindSpec::Posture {
                    joints: j2,
                    reference: r2,
                },
            ) => {
                j1 == j2
                    && match (r1, r2) {
                        (None, None) => true,
                        (Some(a), Some(b)) => posture_close(a, b).is_ok(),
                        _ => false,
                    }
            }
            (
                TaskKindSpec::Limb {
                    limb: l1,
                    joints: j1,
                    target: t1,
                    swivel: s1,
                    orientation: o1,
                },
                TaskKindSpec::Limb {
                    limb: l2,
                    joints: j2,
                    target: t2,
                    swivel: s2,
                    orientation: o2,
                },
            ) => {
                let same_rotation = match (o1, o2) {
                    (None, None) => true,
                    (Some(a), Some(b)) => {
                        DQuat::from_array(*a)
                            .normalize()
                            .angle_between(DQuat::from_array(*b).normalize())
                            <= ROTATION_STEP_RAD + 1e-9
                    }
                    _ => false,
                };
                same_rotation
                    && l1 == l2
                    && j1 == j2
                    && close3(*t1, *t2, POSITION_STEP_M)
                    && match (s1, s2) {
                        (None, None) => true,
                        (Some(a), Some(b)) => close(*a, *b, ROTATION_STEP_RAD),
                        _ => false,
                    }
            }
            (
                TaskKindSpec::Line {
                    joint: j1,
                    point: p1,
                    origin: o1,
                    direction: d1,
                },
                TaskKindSpec::Line {
                    joint: j2,
                    point: p2,
                    origin: o2,
                    direction: d2,
                },
            ) => {
                j1 == j2
                    && close3(*p1, *p2, POSITION_STEP_M)
                    && close3(*o1, *o2, POSITION_STEP_M)
                    && close3(unit(*d1), *d2, DIRECTION_STEP)
            }
            (
                TaskKindSpec::Plane {
                    joint: j1,
                    point: p1,
                    origin: o1,
                    normal: n1,
                    above: a1,
                },
                TaskKindSpec::Plane {
                    joint: j2,
                    point: p2,
                    origin: o2,
                    normal: n2,
                    above: a2,
                },
            ) => {
                j1 == j2
                    && a1 == a2
                    && close3(*p1, *p2, POSITION_STEP_M)
                    && close3(*o1, *o2, POSITION_STEP_M)
                    && close3(unit(*n1), *n2, DIRECTION_STEP)
            }
            _ => false,
        };
        if !ok {
            return bad("kind");
        }
    }
    Ok(())
}
