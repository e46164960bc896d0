//! New tasks made from where the body stands: a position, orientation or direction held where
//! the joint is, a gaze straight ahead, a limb at its present swivel, balance, comfort, the
//! paper's Table 1.

use glam::{DQuat, DVec3};
use stance_document::{LimbName, TaskKindSpec, TaskSpec};
use stance_ik::Axes;

use crate::posing::{PosingSession, joint_rotation};

/// Distance of a new gaze target in front of the eyes (m).
const GAZE_DISTANCE_M: f64 = 1.5;

/// A task to add, made from the current posture.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum NewTask {
    /// The joint held where it is (below every task but the comfort).
    Position(usize),
    /// The joint's orientation held as it is.
    Orientation(usize),
    /// The joint's up axis held along its present direction, the turn about it free.
    Direction(usize),
    /// The head looks at a point straight ahead.
    Gaze,
    /// The limb's end held where it is, at its present swivel angle.
    Limb(LimbName),
    /// The centre of mass over the support polygon of the pinned feet (level 2).
    Balance,
    /// The centre of mass over the floor point under it now (level 2).
    CentreOfMass,
    /// Comfort (effort, joint ranges, RULA), at the lowest level.
    Comfort,
    /// The attraction to the rest posture, at the lowest level.
    RestPosture,
}

/// The level for a new task: below every task but the posture attraction and comfort.
fn next_level(session: &PosingSession) -> u32 {
    stance_document::level_below_hard_tasks(session.tasks())
}

/// The task `what` on `session`'s body as it stands; `Err` says why it cannot be made.
pub fn make_task(session: &PosingSession, what: NewTask) -> Result<TaskSpec, String> {
    let skeleton = session.skeleton();
    let frames = session.frames();
    let joint_name = |joint: usize| {
        skeleton
            .joints()
            .get(joint)
            .map(|definition| definition.name.clone())
            .ok_or_else(|| format!("this body has no joint {joint}"))
    };
    let (kind, level) = match what {
        NewTask::Position(joint) => {
            let position = frames
                .joint_position
                .get(joint)
                .copied()
                .unwrap_or_default();
            let kind = TaskKindSpec::Position {
                joint: joint_name(joint)?,
                point: [0.0; 3],
                axes: Axes::XYZ,
                target: position.to_array(),
            };
            (kind, next_level(session))
        }
        NewTask::Orientation(joint) => {
            let kind = TaskKindSpec::Orientation {
                joint: joint_name(joint)?,
                target: joint_rotation(frames, joint).to_array(),
            };
            (kind, next_level(session))
        }
        NewTask::Direction(joint) => {
            let kind = TaskKindSpec::Direction {
                joint: joint_name(joint)?,
                axis: [0.0, 1.0, 0.0],
                target: (joint_rotation(frames, joint) * DVec3::Y).to_array(),
            };
            (kind, next_level(session))
        }
        NewTask::Gaze => (gaze_ahead(session)?, next_level(session)),
        NewTask::Limb(limb) => (limb_as_it_stands(session, limb)?, next_level(session)),
        NewTask::Balance => return Ok(TaskSpec::balance()),
        NewTask::CentreOfMass => {
            let com = frames.center_of_mass();
            let kind = TaskKindSpec::Com {
                axes: Axes::XZ,
                target: [com.x, 0.0, com.z],
            };
            (kind, 2)
        }
        NewTask::Comfort => return Ok(TaskSpec::comfort()),
        NewTask::RestPosture => return Ok(TaskSpec::rest_attraction()),
    };
    let mut task = TaskSpec::new(kind);
    task.level = level;
    Ok(task)
}

/// The head looks at a point straight ahead.
fn gaze_ahead(session: &PosingSession) -> Result<TaskKindSpec, String> {
    let frames = session.frames();
    let head = session
        .skeleton()
        .joint_index("skullbase")
        .ok_or("this body has no head joint (skullbase) to aim")?;
    let position = frames.joint_position.get(head).copied().unwrap_or_default();
    let forward = joint_rotation(frames, head) * DVec3::Z;
    Ok(TaskKindSpec::Gaze {
        joint: "skullbase".to_owned(),
        axis: [0.0, 0.0, 1.0],
        point: [0.0; 3],
        target: (position + forward * GAZE_DISTANCE_M).to_array(),
    })
}

/// The limb's end held where it is, at its present swivel angle.
fn limb_as_it_stands(session: &PosingSession, limb: LimbName) -> Result<TaskKindSpec, String> {
    let end = limb.joints()[2];
    let position = session
        .joint_position(end)
        .ok_or_else(|| format!("this body has no {end} joint"))?;
    Ok(TaskKindSpec::Limb {
        limb: Some(limb),
        joints: None,
        target: position.to_array(),
        swivel: session.limb_swivel(limb).map(|(swivel, _)| swivel),
        orientation: None,
    })
}

/// Where Table 1's right hand reaches and the gaze looks (the character's frame, m): the
/// sphere's near side.
pub const TABLE1_SPHERE: [f64; 3] = [-0.3, 1.15, 0.4];
/// Where Table 1's left hand holds the vertical bar (its axis, the character's frame, m).
pub const TABLE1_BAR: [f64; 3] = [0.35, 1.0, 0.2];
/// The radius of Table 1's sphere (m).
pub const TABLE1_SPHERE_RADIUS: f64 = 0.11;

/// The paper's Table 1: left foot on the floor, gaze and right hand on a sphere (level 1);
/// the centre of mass over a point between the feet (level 2); left hand on a vertical bar
/// (level 3); the rest-posture attraction.
pub fn table1_example(session: &PosingSession) -> Vec<TaskSpec> {
    let position = |name: &str| session.joint_position(name).unwrap_or_default();
    let sphere = TABLE1_SPHERE;
    let bar = TABLE1_BAR;
    let left = position("l_talocrural");
    let right = position("r_talocrural");
    let between = (left + right) * 0.5;
    let com_goal = between + (left - between) * 0.3;
    let mut balance = TaskSpec::new(TaskKindSpec::Com {
        axes: Axes::XZ,
        target: [com_goal.x, 0.0, com_goal.z],
    });
    balance.level = 2;
    let mut bar_task = TaskSpec::new(TaskKindSpec::Position {
        joint: "l_radiocarpal".to_owned(),
        point: [0.0; 3],
        axes: Axes::XZ,
        target: bar,
    });
    bar_task.level = 3;
    vec![
        TaskSpec::pin("l_talocrural", left.to_array()),
        TaskSpec::new(TaskKindSpec::Orientation {
            joint: "l_talocrural".to_owned(),
            target: DQuat::IDENTITY.to_array(),
        }),
        TaskSpec::new(TaskKindSpec::Gaze {
            joint: "skullbase".to_owned(),
            axis: [0.0, 0.0, 1.0],
            point: [0.0; 3],
            target: sphere,
        }),
        TaskSpec::pin("r_radiocarpal", sphere),
        balance,
        bar_task,
        TaskSpec::rest_attraction(),
    ]
}

/// The task that puts `joint` of `session`'s body on `prop` (in the scene; the character stands
/// at `scene_from_character`), at the level below the hard tasks: on a cylinder's axis (a hand
/// on a bar), on a box's top face or a plane (the joint's centre on the surface), on a ball's
/// surface at the point nearest the joint now.
pub fn task_on_prop(
    session: &PosingSession,
    joint: usize,
    prop: &stance_document::Prop,
    scene_from_character: glam::DAffine3,
) -> Result<TaskSpec, String> {
    use stance_document::PropShape;
    let skeleton = session.skeleton();
    let name = skeleton
        .joints()
        .get(joint)
        .map(|definition| definition.name.clone())
        .ok_or_else(|| format!("this body has no joint {joint}"))?;
    // The prop's frame in the character's (where its tasks are).
    let character_from_prop = scene_from_character.inverse() * prop.scene_from_prop();
    let up = character_from_prop.transform_vector3(DVec3::Y).normalize();
    let centre = character_from_prop.transform_point3(DVec3::ZERO);
    let kind = match prop.shape {
        PropShape::Cylinder { .. } => TaskKindSpec::Line {
            joint: name,
            point: [0.0; 3],
            origin: centre.to_array(),
            direction: up.to_array(),
        },
        PropShape::Box { size } | PropShape::Mesh { size, .. } => TaskKindSpec::Plane {
            joint: name,
            point: [0.0; 3],
            origin: (centre + up * (size[1] / 2.0)).to_array(),
            normal: up.to_array(),
            above: false,
        },
        PropShape::Plane { .. } => TaskKindSpec::Plane {
            joint: name,
            point: [0.0; 3],
            origin: centre.to_array(),
            normal: up.to_array(),
            above: false,
        },
        PropShape::Sphere { radius } => {
            let at = session
                .frames()
                .joint_position
                .get(joint)
                .copied()
                .unwrap_or_default();
            let outward = (at - centre).try_normalize().unwrap_or(DVec3::Y);
            TaskKindSpec::Position {
                joint: name,
                point: [0.0; 3],
                axes: Axes::XYZ,
                target: (centre + outward * radius).to_array(),
            }
        }
    };
    let mut task = TaskSpec::new(kind);
    task.level = next_level(session);
    task.on = Some(prop.name.clone());
    Ok(task)
}

#[cfg(test)]
mod tests {
    use stance_hanim::LevelOfArticulation;

    use super::*;

    #[test]
    fn a_new_task_holds_the_body_where_it_stands_below_the_others() {
        let Ok(session) = PosingSession::new(LevelOfArticulation::Loa2) else {
            panic!("the mannequin builds");
        };
        let Some(wrist) = session.skeleton().joint_index("l_radiocarpal") else {
            panic!("the mannequin has a left wrist");
        };
        let Ok(task) = make_task(&session, NewTask::Position(wrist)) else {
            panic!("a position task can be made");
        };
        let Some(position) = session.joint_position("l_radiocarpal") else {
            panic!("the wrist has a position");
        };
        let TaskKindSpec::Position { target, .. } = task.kind else {
            panic!("a position task");
        };
        assert_eq!(target, position.to_array());
        // The default tasks stop at level 2 (balance) before the comfort.
        assert_eq!(task.level, 3);
        let Ok(limb) = make_task(&session, NewTask::Limb(LimbName::RightArm)) else {
            panic!("a limb task can be made");
        };
        assert!(matches!(
            limb.kind,
            TaskKindSpec::Limb {
                swivel: Some(_),
                ..
            }
        ));
        assert!(make_task(&session, NewTask::Position(10_000)).is_err());
    }
}
