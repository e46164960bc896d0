//! Benchmark and test scenarios S1..S6 on bodies built from the H-Anim default joint centres.
//!
//! The joint centres are the H-Anim 2.0 defaults of this crate's joint table
//! (`data/hanim_joints.csv`); each joint's parent is its nearest ancestor present in the body.
//! Segment masses: fractions of a 70 kg body after de Leva (1996), rounded.

use glam::{DQuat, DVec3};

use stance_ik::{
    Axes, Dof, Frames, IkError, JointDef, Limb, LimbBase, LimbGoal, Posture, Skeleton, Task,
};

use crate::{all_joints, default_centre, joint_by_name};

/// Default centre of an H-Anim joint (X3DUOM's default, see [`crate::default_centre`]).
pub fn hanim_centre(name: &str) -> Option<DVec3> {
    joint_by_name(name).map(|(_, definition)| default_centre(definition))
}

/// The joint's parent at LOA 4 (the finest chain: every coarser parent is an ancestor on it).
fn hanim_parent(name: &str) -> Option<&'static str> {
    let (_, definition) = joint_by_name(name)?;
    let parent = definition.parent_by_loa[3]?;
    all_joints().get(parent).map(|parent| parent.name)
}

use Dof::{Rx, Ry, Rz, Tx, Ty, Tz};
const ROOT6: &[Dof] = &[Tx, Ty, Tz, Rx, Ry, Rz];
const BALL: &[Dof] = &[Rx, Ry, Rz];

/// One joint of a body spec: name, DOF, limits, mass fraction, the joint whose centre ends
/// the segment (for its centre of mass).
struct Spec {
    name: &'static str,
    dofs: &'static [Dof],
    limits: &'static [(Dof, f64, f64)],
    mass_fraction: f64,
    distal: Option<&'static str>,
}

const fn spec(
    name: &'static str,
    dofs: &'static [Dof],
    limits: &'static [(Dof, f64, f64)],
    mass_fraction: f64,
    distal: Option<&'static str>,
) -> Spec {
    Spec {
        name,
        dofs,
        limits,
        mass_fraction,
        distal,
    }
}

const BODY_MASS: f64 = 70.0;
const KNEE: &[(Dof, f64, f64)] = &[(Rx, 0.0, 2.4)];
const ELBOW: &[(Dof, f64, f64)] = &[(Rx, -2.5, 0.0)];
const HIP: &[(Dof, f64, f64)] = &[(Rx, -2.0, 0.6), (Ry, -0.8, 0.8), (Rz, -0.8, 0.8)];
const SHOULDER: &[(Dof, f64, f64)] = &[(Rx, -2.8, 1.0), (Ry, -1.5, 1.5), (Rz, -2.8, 2.8)];
const ANKLE: &[(Dof, f64, f64)] = &[(Rx, -0.8, 0.6), (Rz, -0.5, 0.5)];
const WRIST: &[(Dof, f64, f64)] = &[(Rx, -1.2, 1.2), (Rz, -0.6, 0.6)];
const SPINE: &[(Dof, f64, f64)] = &[(Rx, -0.5, 0.5), (Ry, -0.5, 0.5), (Rz, -0.4, 0.4)];
const NECK: &[(Dof, f64, f64)] = &[(Rx, -0.7, 0.7), (Ry, -1.2, 1.2), (Rz, -0.6, 0.6)];
const NONE: &[(Dof, f64, f64)] = &[];

fn build(specs: &[Spec]) -> Result<Skeleton, IkError> {
    let included = |n: &str| specs.iter().any(|s| s.name == n);
    let mut defs = Vec::with_capacity(specs.len());
    for s in specs {
        let centre = hanim_centre(s.name).ok_or_else(|| IkError::UnknownJoint(s.name.into()))?;
        // Nearest included ancestor along the LOA2 parent chain.
        let mut parent = hanim_parent(s.name).filter(|p| !p.is_empty());
        while let Some(p) = parent {
            if included(p) {
                break;
            }
            parent = hanim_parent(p).filter(|p| !p.is_empty());
        }
        let offset = match parent {
            Some(p) => centre - hanim_centre(p).unwrap_or(DVec3::ZERO),
            None => centre,
        };
        let com = s
            .distal
            .and_then(hanim_centre)
            .map(|d| (d - centre) * 0.45)
            .unwrap_or(DVec3::ZERO);
        let mut def = JointDef::new(s.name, parent, offset, s.dofs)
            .with_mass(s.mass_fraction * BODY_MASS, com);
        def.limits = s.limits.to_vec();
        defs.push(def);
    }
    Skeleton::new(defs)
}

/// S1: a 7-DOF left arm (shoulder 3, elbow 1, wrist 3) on a fixed base.
pub fn arm7() -> Result<Skeleton, IkError> {
    let shoulder = hanim_centre("l_shoulder").unwrap_or(DVec3::ZERO);
    let elbow = hanim_centre("l_elbow").unwrap_or(DVec3::ZERO);
    let wrist = hanim_centre("l_radiocarpal").unwrap_or(DVec3::ZERO);
    Skeleton::new(vec![
        JointDef::new("l_shoulder", None, shoulder, BALL),
        JointDef::new("l_elbow", Some("l_shoulder"), elbow - shoulder, &[Rx]),
        JointDef::new("l_radiocarpal", Some("l_elbow"), wrist - elbow, BALL),
    ])
}

/// The 50-DOF humanoid (LOA2 joint subset): root 6, sacroiliac 3, legs 2x7, spine and head
/// 5x3, arms 2x6.
pub fn humanoid50() -> Result<Skeleton, IkError> {
    build(&[
        spec("humanoid_root", ROOT6, NONE, 0.0, None),
        spec("sacroiliac", BALL, SPINE, 0.142, Some("vl5")),
        spec("l_hip", BALL, HIP, 0.100, Some("l_knee")),
        spec("l_knee", &[Rx], KNEE, 0.047, Some("l_talocrural")),
        spec(
            "l_talocrural",
            &[Rx, Rz],
            ANKLE,
            0.010,
            Some("l_metatarsophalangeal_2"),
        ),
        spec(
            "l_metatarsophalangeal_2",
            &[Rx],
            &[(Rx, -0.6, 0.6)],
            0.004,
            None,
        ),
        spec("r_hip", BALL, HIP, 0.100, Some("r_knee")),
        spec("r_knee", &[Rx], KNEE, 0.047, Some("r_talocrural")),
        spec(
            "r_talocrural",
            &[Rx, Rz],
            ANKLE,
            0.010,
            Some("r_metatarsophalangeal_2"),
        ),
        spec(
            "r_metatarsophalangeal_2",
            &[Rx],
            &[(Rx, -0.6, 0.6)],
            0.004,
            None,
        ),
        spec("vl5", BALL, SPINE, 0.100, Some("vl1")),
        spec("vl1", BALL, SPINE, 0.100, Some("vt6")),
        spec("vt6", BALL, SPINE, 0.100, Some("vt1")),
        spec("vt1", BALL, SPINE, 0.060, Some("skullbase")),
        spec("skullbase", BALL, NECK, 0.070, None),
        spec("l_shoulder", BALL, SHOULDER, 0.027, Some("l_elbow")),
        spec("l_elbow", &[Rx], ELBOW, 0.016, Some("l_radiocarpal")),
        spec(
            "l_radiocarpal",
            &[Rx, Rz],
            WRIST,
            0.006,
            Some("l_carpal_distal_interphalangeal_3"),
        ),
        spec("r_shoulder", BALL, SHOULDER, 0.027, Some("r_elbow")),
        spec("r_elbow", &[Rx], ELBOW, 0.016, Some("r_radiocarpal")),
        spec(
            "r_radiocarpal",
            &[Rx, Rz],
            WRIST,
            0.006,
            Some("r_carpal_distal_interphalangeal_3"),
        ),
    ])
}

/// The ~40-DOF LOA2-like body of the paper's Table 1: root 6, legs 2x6, spine 2x3,
/// neck 1 + head 3, arms 2x6 (sacroiliac and clavicles present without DOF).
pub fn loa2_body40() -> Result<Skeleton, IkError> {
    build(&[
        spec("humanoid_root", ROOT6, NONE, 0.0, None),
        spec("sacroiliac", &[], NONE, 0.142, Some("vl5")),
        spec("l_hip", BALL, HIP, 0.100, Some("l_knee")),
        spec("l_knee", &[Rx], KNEE, 0.047, Some("l_talocrural")),
        spec(
            "l_talocrural",
            &[Rx, Rz],
            ANKLE,
            0.014,
            Some("l_metatarsophalangeal_2"),
        ),
        spec("r_hip", BALL, HIP, 0.100, Some("r_knee")),
        spec("r_knee", &[Rx], KNEE, 0.047, Some("r_talocrural")),
        spec(
            "r_talocrural",
            &[Rx, Rz],
            ANKLE,
            0.014,
            Some("r_metatarsophalangeal_2"),
        ),
        spec("vl5", BALL, SPINE, 0.150, Some("vt6")),
        spec("vt6", BALL, SPINE, 0.150, Some("vt1")),
        spec("vt1", &[], NONE, 0.060, Some("skullbase")),
        spec("vc4", &[Rx], &[(Rx, -0.6, 0.6)], 0.011, Some("skullbase")),
        spec("skullbase", BALL, NECK, 0.070, None),
        spec("l_sternoclavicular", &[], NONE, 0.0, None),
        spec("l_shoulder", BALL, SHOULDER, 0.027, Some("l_elbow")),
        spec("l_elbow", &[Rx], ELBOW, 0.016, Some("l_radiocarpal")),
        spec(
            "l_radiocarpal",
            &[Rx, Rz],
            WRIST,
            0.006,
            Some("l_carpal_distal_interphalangeal_3"),
        ),
        spec("r_sternoclavicular", &[], NONE, 0.0, None),
        spec("r_shoulder", BALL, SHOULDER, 0.027, Some("r_elbow")),
        spec("r_elbow", &[Rx], ELBOW, 0.016, Some("r_radiocarpal")),
        spec(
            "r_radiocarpal",
            &[Rx, Rz],
            WRIST,
            0.006,
            Some("r_carpal_distal_interphalangeal_3"),
        ),
    ])
}

/// A relaxed standing posture: knees and elbows slightly bent (away from the straight-limb
/// singularity).
pub fn standing_posture(skeleton: &Skeleton) -> Posture {
    let mut p = Posture::rest(skeleton);
    let mut set = |joint: &str, dof: usize, v: f64| {
        if let Some(j) = skeleton.joint_index(joint)
            && let Some(d) = skeleton.joints()[j].rotation_dof[dof]
        {
            p.values_mut()[d] = v;
        }
    };
    for side in ["l_", "r_"] {
        set(&format!("{side}knee"), 0, 0.1);
        set(&format!("{side}hip"), 0, -0.05);
        set(&format!("{side}talocrural"), 0, -0.05);
        set(&format!("{side}elbow"), 0, -0.2);
    }
    p
}

/// A named problem: body, tasks, start posture.
#[derive(Debug, Clone)]
pub struct Scenario {
    /// `S1`..`S6`.
    pub name: &'static str,
    /// What it is.
    pub description: &'static str,
    /// The body.
    pub skeleton: Skeleton,
    /// The tasks.
    pub tasks: Vec<Task>,
    /// Where solving starts.
    pub start: Posture,
}

/// Deterministic pseudo-random numbers in [-1, 1] (SplitMix64; no dependency).
struct Mix(u64);

impl Mix {
    fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        (z >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    }
}

/// The 20 effectors of S2/S3/S4: (joint, point in the joint frame).
fn twenty_effectors(skeleton: &Skeleton) -> Result<Vec<(usize, DVec3)>, IkError> {
    let names: [(&str, [f64; 3]); 20] = [
        ("l_radiocarpal", [0.0, -0.08, 0.0]),
        ("r_radiocarpal", [0.0, -0.08, 0.0]),
        ("l_metatarsophalangeal_2", [0.0, 0.0, 0.04]),
        ("r_metatarsophalangeal_2", [0.0, 0.0, 0.04]),
        ("skullbase", [0.0, 0.1, 0.05]),
        ("l_elbow", [0.0, 0.0, 0.0]),
        ("r_elbow", [0.0, 0.0, 0.0]),
        ("l_knee", [0.0, 0.0, 0.0]),
        ("r_knee", [0.0, 0.0, 0.0]),
        ("sacroiliac", [0.0, 0.0, 0.05]),
        ("l_talocrural", [0.0, -0.05, 0.0]),
        ("r_talocrural", [0.0, -0.05, 0.0]),
        ("vt1", [0.0, 0.0, 0.08]),
        ("vl1", [0.0, 0.0, 0.1]),
        ("l_shoulder", [0.0, -0.1, 0.0]),
        ("r_shoulder", [0.0, -0.1, 0.0]),
        ("l_radiocarpal", [0.03, -0.1, 0.03]),
        ("r_radiocarpal", [-0.03, -0.1, 0.03]),
        ("skullbase", [0.07, 0.08, 0.0]),
        ("vt6", [0.0, 0.0, 0.1]),
    ];
    names
        .iter()
        .map(|(n, p)| Ok((skeleton.require_joint(n)?, DVec3::from_array(*p))))
        .collect()
}

/// Targets reachable all at once: the effector positions in a perturbed posture.
fn feasible_targets(
    skeleton: &Skeleton,
    from: &Posture,
    effectors: &[(usize, DVec3)],
    seed: u64,
    amplitude: f64,
) -> Vec<DVec3> {
    let mut rng = Mix(seed);
    let mut goal = from.clone();
    let (lo, hi) = (skeleton.lower_limits(), skeleton.upper_limits());
    for (i, v) in goal.values_mut().iter_mut().enumerate() {
        let scale = if skeleton.dof_kinds()[i].is_rotation() {
            amplitude
        } else {
            0.3 * amplitude
        };
        *v = (*v + scale * rng.next()).clamp(lo[i], hi[i]);
    }
    let frames = Frames::new(skeleton, &goal);
    effectors.iter().map(|&(j, p)| frames.point(j, p)).collect()
}

fn humanoid_tasks(
    levels_of: impl Fn(usize) -> u32,
) -> Result<(Skeleton, Vec<Task>, Posture), IkError> {
    let skeleton = humanoid50()?;
    let start = standing_posture(&skeleton);
    let effectors = twenty_effectors(&skeleton)?;
    let targets = feasible_targets(&skeleton, &start, &effectors, 7, 0.25);
    let tasks = effectors
        .iter()
        .zip(targets)
        .enumerate()
        .map(|(i, (&(j, p), t))| Task::position(j, p, t).at_level(levels_of(i)))
        .collect();
    Ok((skeleton, tasks, start))
}

/// S1: 7-DOF arm, one 3-D position task.
pub fn s1() -> Result<Scenario, IkError> {
    let skeleton = arm7()?;
    let wrist = skeleton.require_joint("l_radiocarpal")?;
    let mut start = Posture::rest(&skeleton);
    if let Some(d) = skeleton.joints()[1].rotation_dof[0] {
        start.values_mut()[d] = -0.3;
    }
    let tasks = vec![Task::position(
        wrist,
        DVec3::new(0.0, -0.08, 0.0),
        DVec3::new(0.35, 1.05, 0.3),
    )];
    Ok(Scenario {
        name: "S1",
        description: "7-DOF arm, one 3-D position task",
        skeleton,
        tasks,
        start,
    })
}

/// S2: 50-DOF humanoid, 20 position tasks in 4 levels of 15 rows.
pub fn s2() -> Result<Scenario, IkError> {
    let (skeleton, tasks, start) = humanoid_tasks(|i| (i / 5) as u32 + 1)?;
    Ok(Scenario {
        name: "S2",
        description: "50-DOF humanoid, 20 position tasks in 4 levels of 15 rows",
        skeleton,
        tasks,
        start,
    })
}

/// S3: the same body, the 60 rows in one level.
pub fn s3() -> Result<Scenario, IkError> {
    let (skeleton, tasks, start) = humanoid_tasks(|_| 1)?;
    Ok(Scenario {
        name: "S3",
        description: "50-DOF humanoid, 60 rows in one level",
        skeleton,
        tasks,
        start,
    })
}

/// S4: the same body, 20 levels of 3 rows.
pub fn s4() -> Result<Scenario, IkError> {
    let (skeleton, tasks, start) = humanoid_tasks(|i| i as u32 + 1)?;
    Ok(Scenario {
        name: "S4",
        description: "50-DOF humanoid, 20 levels of 3 rows",
        skeleton,
        tasks,
        start,
    })
}

/// Goals of the Table 1 scenario.
#[derive(Debug, Clone, Copy)]
pub struct Table1Goals {
    /// Where the sphere is (right hand reaches it, the gaze looks at it).
    pub sphere: DVec3,
    /// Where the vertical bar held by the left hand stands (x, z).
    pub bar: DVec3,
}

impl Default for Table1Goals {
    fn default() -> Self {
        Self {
            sphere: DVec3::new(-0.3, 1.15, 0.4),
            bar: DVec3::new(0.35, 1.0, 0.2),
        }
    }
}

/// The tasks of the paper's Table 1 on [`loa2_body40`]: left foot on the floor, gaze and
/// right hand at level 1; centre of mass (horizontal, between the feet, toward the left one) at 2; left hand on
/// a vertical bar (horizontal position) at 3; pelvis, elbow and knee drags at 4.
pub fn table1_tasks(skeleton: &Skeleton, goals: Table1Goals) -> Result<Vec<Task>, IkError> {
    let j = |n: &str| skeleton.require_joint(n);
    let ankle = hanim_centre("l_talocrural").unwrap_or(DVec3::ZERO);
    let toe = hanim_centre("l_metatarsophalangeal_2").unwrap_or(DVec3::ZERO);
    let heel = hanim_centre("l_tarsometatarsal_2").unwrap_or(DVec3::ZERO);
    let foot_mid = (toe + heel) * 0.5;
    let r_foot_mid = (hanim_centre("r_metatarsophalangeal_2").unwrap_or(DVec3::ZERO)
        + hanim_centre("r_tarsometatarsal_2").unwrap_or(DVec3::ZERO))
        * 0.5;
    let between = (foot_mid + r_foot_mid) * 0.5;
    let com_goal = between + (foot_mid - between) * 0.3;
    let hand = DVec3::new(0.0, -0.08, 0.0);
    let pelvis = hanim_centre("sacroiliac").unwrap_or(DVec3::ZERO);
    let r_elbow = hanim_centre("r_elbow").unwrap_or(DVec3::ZERO);
    let l_knee = hanim_centre("l_knee").unwrap_or(DVec3::ZERO);
    Ok(vec![
        // Level 1: left foot flat on the floor (sole point and orientation), gaze, right hand.
        Task::position(j("l_talocrural")?, foot_mid - ankle, foot_mid).at_level(1),
        Task::orientation(j("l_talocrural")?, DQuat::IDENTITY).at_level(1),
        Task::gaze(j("skullbase")?, DVec3::Z, goals.sphere).at_level(1),
        Task::position(j("r_radiocarpal")?, hand, goals.sphere).at_level(1),
        // Level 2: centre of mass over the support polygon, shifted toward the left foot.
        Task::center_of_mass(Axes::XZ, com_goal).at_level(2),
        // Level 3: left hand on the vertical bar.
        Task::position(j("l_radiocarpal")?, hand, goals.bar)
            .with_axes(Axes::XZ)
            .at_level(3),
        // Level 4: temporary drags (small pulls, as with the mouse in the paper).
        Task::position(
            j("sacroiliac")?,
            DVec3::ZERO,
            pelvis + DVec3::new(0.0, -0.02, 0.0),
        )
        .at_level(4),
        Task::position(
            j("r_elbow")?,
            DVec3::ZERO,
            r_elbow + DVec3::new(-0.03, 0.0, 0.0),
        )
        .at_level(4),
        Task::position(
            j("l_knee")?,
            DVec3::ZERO,
            l_knee + DVec3::new(0.0, 0.0, 0.03),
        )
        .at_level(4),
    ])
}

/// S5: the Table 1 tasks on the ~40-DOF body.
pub fn s5() -> Result<Scenario, IkError> {
    let skeleton = loa2_body40()?;
    let tasks = table1_tasks(&skeleton, Table1Goals::default())?;
    let start = standing_posture(&skeleton);
    Ok(Scenario {
        name: "S5",
        description: "~40-DOF LOA2 body, the paper's Table 1 tasks in 4 levels",
        skeleton,
        tasks,
        start,
    })
}

/// S6: S2 iterated to convergence from the standing posture.
pub fn s6() -> Result<Scenario, IkError> {
    let mut s = s2()?;
    s.name = "S6";
    s.description = "S2 iterated to convergence from a standing posture";
    Ok(s)
}

/// All six, in order.
pub fn all() -> Result<Vec<Scenario>, IkError> {
    Ok(vec![s1()?, s2()?, s3()?, s4()?, s5()?, s6()?])
}

/// S7: one closed-form solve of the left arm of [`arm7`] (goal position and swivel angle).
#[derive(Debug, Clone)]
pub struct LimbScenario {
    /// `S7`.
    pub name: &'static str,
    /// What it is.
    pub description: &'static str,
    /// The body ([`arm7`]).
    pub skeleton: Skeleton,
    /// Shoulder, elbow, wrist.
    pub limb: Limb,
    /// The limb's base in the rest posture.
    pub base: LimbBase,
    /// The wrist goal (reachable).
    pub goal: LimbGoal,
    /// The swivel angle asked (radians).
    pub swivel_angle: f64,
    /// Where the solution is written.
    pub start: Posture,
}

/// The S7 scenario.
pub fn s7() -> Result<LimbScenario, IkError> {
    let skeleton = arm7()?;
    let limb = Limb::from_names(&skeleton, ["l_shoulder", "l_elbow", "l_radiocarpal"])?;
    let start = Posture::rest(&skeleton);
    let base = limb.base(&skeleton, &Frames::new(&skeleton, &start));
    Ok(LimbScenario {
        name: "S7",
        description: "7-DOF arm, one closed-form solve (wrist position + swivel angle)",
        skeleton,
        limb,
        base,
        goal: LimbGoal::position(DVec3::new(0.35, 1.1, 0.25)),
        swivel_angle: 0.3,
        start,
    })
}
