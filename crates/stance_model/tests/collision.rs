//! Collision avoidance in the editor, by commands alone: the toggle adds the body's collision
//! task just below the pins, turns it off and on (undoable); a hand pulled across the chest
//! stays out of the torso, frame by frame.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use glam::DVec3;
use stance_document::TaskKindSpec;
use stance_hanim::capsules::body_capsules;
use stance_ik::{Capsule, Frames, Skeleton};
use stance_model::model::{GestureCommand, HistoryCommand, TaskCommand, ViewCommand};
use stance_model::{Command, EditorModel};

use crate::clocked::Clocked;

/// The distance from the point `p` to the segment `a b` (its clamped projection).
fn to_segment(p: DVec3, a: DVec3, b: DVec3) -> f64 {
    let ab = b - a;
    let t = if ab.length_squared() > 0.0 {
        ((p - a).dot(ab) / ab.length_squared()).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (p - (a + ab * t)).length()
}

/// How deep (m; negative: a gap) the capsule `a` goes into the capsule `b` at `frames`, by
/// another route than the solver's closest points: 2,000 points along `a`'s axis, each
/// projected onto `b`'s.
fn depth(a: &Capsule, b: &Capsule, frames: &Frames) -> f64 {
    const SAMPLES: usize = 2000;
    let (a0, a1) = a.world(frames);
    let (b0, b1) = b.world(frames);
    let nearest = (0..=SAMPLES)
        .map(|k| to_segment(a0.lerp(a1, k as f64 / SAMPLES as f64), b0, b1))
        .fold(f64::INFINITY, f64::min);
    a.radius + b.radius - nearest
}

/// The right forearm's capsule and the torso's (the spine's and the chest's: every capsule
/// carried by a lumbar or thoracic vertebra; the pelvis's, which the hanging hand touches at
/// rest, is one body with the arm).
fn forearm_and_torso(skeleton: &Skeleton) -> (Capsule, Vec<Capsule>) {
    let capsules = body_capsules(skeleton);
    let name = |c: &Capsule| skeleton.joints()[c.joint].name.clone();
    let forearm = capsules
        .iter()
        .find(|c| name(c) == "r_elbow")
        .copied()
        .unwrap();
    let torso = capsules
        .iter()
        .filter(|c| {
            let n = name(c);
            n.starts_with("vl") || n.starts_with("vt")
        })
        .copied()
        .collect();
    (forearm, torso)
}

/// The deepest the right forearm goes into the torso in `model`'s posture (m).
fn forearm_in_torso(model: &EditorModel) -> f64 {
    let session = model.session();
    let (forearm, torso) = forearm_and_torso(session.skeleton());
    torso
        .iter()
        .map(|t| depth(&forearm, t, session.frames()))
        .fold(f64::NEG_INFINITY, f64::max)
}

/// A pull of the right forearm from where it hangs across the body to the belly's left side, through
/// the torso, in 40 frames and 20 more held: the deepest the forearm went into the torso in any
/// frame, the solver's time per frame (ms, sorted) and the hand's last distance from the
/// pointer's goal.
fn pull_across_the_chest(editor: &mut Clocked) -> (f64, Vec<f64>, f64) {
    let elbow = editor.position("r_elbow");
    let wrist = editor.position("r_radiocarpal");
    let grabbed = elbow.lerp(wrist, 0.6);
    let chest = editor
        .position("l_sternoclavicular")
        .lerp(editor.position("r_sternoclavicular"), 0.5);
    // The left side of the belly (+X is the body's left), at the chest's depth: the straight
    // way there runs through the torso.
    let goal = DVec3::new(chest.x + 0.2, chest.y - 0.3, chest.z);
    editor.apply(Command::Gesture(GestureCommand::BeginPull {
        joint: editor.joint("r_elbow"),
        point_world: grabbed,
    }));
    assert!(editor.model.is_pulling());
    let mut deepest = f64::NEG_INFINITY;
    let mut solver_ms = Vec::new();
    for step in 1..=60 {
        let along = grabbed.lerp(goal, (f64::from(step) / 40.0).min(1.0));
        editor.apply(Command::Gesture(GestureCommand::MoveGrab {
            target_world: along,
        }));
        editor.frames(1);
        solver_ms.push(editor.model.solver_ms());
        deepest = deepest.max(forearm_in_torso(&editor.model));
    }
    let session = editor.model.session();
    let reached = session.grabbed_point_world().unwrap();
    editor.apply(Command::Gesture(GestureCommand::EndGesture));
    solver_ms.sort_by(f64::total_cmp);
    (deepest, solver_ms, (reached - goal).length())
}

/// Catches a toggle that does nothing or adds the task elsewhere: on a new character the
/// toggle adds the body's collision task just below the pins (level 2, self and floor), in
/// the list's priority order; off keeps it in the list, inactive; undo turns it back on. The
/// capsules are shown on request, a view setting outside the document.
#[test]
fn the_collision_toggle_adds_the_body_s_task_below_the_pins_and_switches_it() {
    let mut editor = Clocked::new();
    let before = editor.model.session().tasks().to_vec();
    assert!(!editor.model.session().collision_on());
    editor.apply(Command::Task(TaskCommand::SetCollision(true)));
    let tasks = editor.model.session().tasks().to_vec();
    assert!(editor.model.session().collision_on());
    assert_eq!(tasks.len(), before.len() + 1);
    let at = tasks
        .iter()
        .position(|t| matches!(t.kind, TaskKindSpec::Collision { .. }))
        .unwrap();
    assert_eq!(tasks[at].level, 2, "just below the pins");
    assert!(
        tasks[..at].iter().all(|t| t.level == 1),
        "after the pins: {tasks:?}"
    );
    assert!(matches!(
        tasks[at].kind,
        TaskKindSpec::Collision {
            self_collision: true,
            floor: true,
            ..
        }
    ));

    editor.apply(Command::Task(TaskCommand::SetCollision(false)));
    assert!(!editor.model.session().collision_on());
    assert_eq!(editor.model.session().tasks().len(), tasks.len(), "kept");
    assert!(!editor.model.session().tasks()[at].active);
    editor.apply(Command::History(HistoryCommand::Undo));
    assert!(
        editor.model.session().collision_on(),
        "undo turns it back on"
    );
    editor.apply(Command::Task(TaskCommand::SetCollision(false)));
    editor.apply(Command::Task(TaskCommand::SetCollision(true)));
    assert_eq!(
        editor.model.session().tasks(),
        tasks.as_slice(),
        "the same one"
    );

    assert!(!editor.model.show_capsules());
    let document = editor.model.document();
    editor.apply(Command::View(ViewCommand::ShowCapsules(true)));
    assert!(editor.model.show_capsules());
    assert_eq!(editor.model.document(), document);
}

/// Catches a pull that takes the forearm through the torso: the right forearm pulled from
/// where it hangs across the chest to the left side, frame by frame through the posing
/// session. With collision on (the toggle) the forearm never enters the torso's capsules by
/// more than a millimetre in any frame; with collision off it goes through (the test fails
/// without the task). The solver's time per frame is printed both ways (no timed assert), and
/// how far the hand got: at least 15 cm toward the left, round the front of the belly (it
/// stops some way short of the pointer, as the free pull does too).
#[test]
fn a_hand_pulled_across_the_chest_slides_around_the_torso() {
    let mut editor = Clocked::new();
    editor.apply(Command::Task(TaskCommand::SetCollision(true)));
    editor.settle();
    let start = editor.position("r_radiocarpal");
    let (deepest, solver_ms, left) = pull_across_the_chest(&mut editor);
    let contacts_seen = editor.model.session().contacts().len();
    let end = editor.position("r_radiocarpal");

    let mut free = Clocked::new();
    free.settle();
    let (through, free_ms, free_left) = pull_across_the_chest(&mut free);

    let median = |ms: &[f64]| ms[ms.len() / 2];
    println!(
        "collision pull: forearm into the torso at most {:.2} mm with the task, {:.1} mm without; \
         solver per frame median {:.2} ms, max {:.2} ms with it (median {:.2}, max {:.2} without); \
         grabbed point {:.3} m from the goal with, {:.3} without; {contacts_seen} contacts at the end",
        deepest * 1e3,
        through * 1e3,
        median(&solver_ms),
        solver_ms.last().unwrap(),
        median(&free_ms),
        free_ms.last().unwrap(),
        left,
        free_left
    );
    assert!(
        through > 0.02,
        "without the task the forearm goes in: {through} m"
    );
    assert!(deepest < 0.001, "the forearm {deepest} m into the torso");
    println!(
        "collision pull: the wrist moved {:.3} m toward the left with the task",
        end.x - start.x
    );
    // Not held where it hung: the hand followed the pull up to the body.
    assert!(
        end.x > start.x + 0.05,
        "the wrist moved {:.3} m",
        end.x - start.x
    );
    assert!(contacts_seen >= 1, "the arm rests against the body");
}

/// Catches a collision task blind to the scene's props, or one that sees them in the wrong
/// frame: a box (a table top) stands before the character's right hand and the hand is pulled
/// down through it. The character stands placed and turned in the scene (the prop is placed in
/// the scene's frame, the tasks in the character's). With collision on, no capsule the props
/// hold off (all but the feet) goes more than a millimetre into the box in any frame, measured
/// by sampling along each capsule against the box in the scene; with it off, the hand goes
/// through.
#[test]
fn a_hand_pulled_through_a_table_stays_on_it() {
    use stance_document::{Placement, Prop, PropShape};
    use stance_model::model::SceneCommand;

    let run = |collision: bool| -> f64 {
        let mut editor = Clocked::new();
        let id = editor.model.character().id();
        let placement = Placement {
            position: [1.0, 0.0, -0.5],
            yaw_degrees: 90.0,
        };
        editor.apply(Command::Scene(SceneCommand::Place(id, placement)));
        editor.apply(Command::Task(TaskCommand::SetCollision(collision)));
        editor.settle();
        let scene_from_character = placement.scene_from_character();
        let wrist = editor.position("r_radiocarpal");
        // A 60 x 4 x 40 cm top, 12 cm over the hand and 25 cm before it, in the scene.
        let top = scene_from_character.transform_point3(wrist + DVec3::new(0.0, 0.12, 0.25));
        editor.apply(Command::Scene(SceneCommand::AddProp(PropShape::Box {
            size: [0.6, 0.04, 0.4],
        })));
        let mut table = Prop::new(
            "table".into(),
            PropShape::Box {
                size: [0.6, 0.04, 0.4],
            },
            top.to_array(),
        );
        let turn = glam::DQuat::from_rotation_y(placement.yaw_degrees.to_radians());
        table.rotation = turn.to_array();
        editor.apply(Command::Scene(SceneCommand::EditProp(0, table.clone())));
        editor.settle();
        // From above the top to under it, through its middle, in the character's frame.
        let middle = wrist + DVec3::new(0.0, 0.12, 0.25);
        let (above, below) = (middle + DVec3::Y * 0.2, middle - DVec3::Y * 0.25);
        let grabbed = editor.position("r_radiocarpal");
        editor.apply(Command::Gesture(GestureCommand::BeginPull {
            joint: editor.joint("r_radiocarpal"),
            point_world: grabbed,
        }));
        let skeleton = editor.model.session().skeleton().clone();
        let capsules = body_capsules(&skeleton);
        let rest = Frames::new(&skeleton, &stance_ik::Posture::rest(&skeleton));
        let held: Vec<&Capsule> = capsules
            .iter()
            .filter(|c| {
                let (a, b) = c.world(&rest);
                a.y.min(b.y) - c.radius > 0.0
            })
            .collect();
        let box_frame = table.scene_from_prop().inverse();
        let half = DVec3::new(0.3, 0.02, 0.2);
        // Signed distance of a scene point from the box: its clamp in the box's frame.
        let to_box = |p: DVec3| {
            let q = box_frame.transform_point3(p);
            let c = q.clamp(-half, half);
            if c == q {
                -(half - q.abs()).min_element()
            } else {
                (q - c).length()
            }
        };
        let mut deepest = f64::NEG_INFINITY;
        for step in 1..=60 {
            let t = f64::from(step) / 20.0;
            let target = if t <= 1.0 {
                grabbed.lerp(above, t)
            } else {
                above.lerp(below, (t - 1.0).min(1.0))
            };
            editor.apply(Command::Gesture(GestureCommand::MoveGrab {
                target_world: target,
            }));
            editor.frames(1);
            let frames = editor.model.session().frames();
            for c in &held {
                let (a, b) = c.world(frames);
                let (a, b) = (
                    scene_from_character.transform_point3(a),
                    scene_from_character.transform_point3(b),
                );
                let nearest = (0..=400)
                    .map(|k| to_box(a.lerp(b, f64::from(k) / 400.0)))
                    .fold(f64::INFINITY, f64::min);
                deepest = deepest.max(c.radius - nearest);
            }
        }
        editor.apply(Command::Gesture(GestureCommand::EndGesture));
        deepest
    };
    let without = run(false);
    let with = run(true);
    println!(
        "collision with props: the arm into the table at most {:.2} mm with collision on, {:.1} mm off",
        with * 1e3,
        without * 1e3
    );
    assert!(without > 0.02, "off, the hand goes through: {without} m");
    assert!(with < 0.001, "on, {with} m into the table");
}
