//! Tasks between characters (a scene's `between[]`): read and written in JSON and links (an
//! older scene link still opens), checked against the scene, grouped, and solved as one
//! problem over the joined bodies: two characters hand in hand on the H-Anim default body,
//! each keeping its own pinned feet, checked in the scene through the placements.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use glam::DVec3;
use stance_document::link;
use stance_document::{
    BetweenTask, CharacterPoint, Document, JoinedProblem, Placement, Problem, Scene,
    SceneCharacter, joined_groups,
};
use stance_hanim::{SkeletonOptions, default_skeleton};
use stance_ik::{Frames, Posture, Skeleton};
#[cfg(target_arch = "wasm32")]
use wasm_bindgen_test::wasm_bindgen_test as test;

fn body() -> Skeleton {
    default_skeleton(&SkeletonOptions::default())
        .unwrap()
        .skeleton
}

/// A character's document: both feet pinned where they stand at rest (level 1), balance
/// (level 2), and a comfort task (level 9) when asked.
fn standing(skeleton: &Skeleton, comfort: bool) -> Document {
    let frames = Frames::new(skeleton, &Posture::rest(skeleton));
    let mut tasks = Vec::new();
    for ankle in ["l_talocrural", "r_talocrural"] {
        let p = frames.joint_position[skeleton.joint_index(ankle).unwrap()];
        tasks.push(
            serde_json::json!({"kind": "position", "joint": ankle, "target": [p.x, p.y, p.z]}),
        );
    }
    tasks.push(serde_json::json!({"kind": "balance", "level": 2}));
    if comfort {
        tasks.push(serde_json::json!({"kind": "comfort", "level": 9}));
    }
    Document::from_json(&serde_json::json!({ "tasks": tasks }).to_string()).unwrap()
}

/// The first two characters of `scene`, each on `skeleton` from its own document, joined.
fn joined_first_two(scene: &Scene, skeleton: &Skeleton) -> JoinedProblem {
    let problems: Vec<Problem> = scene.characters[..2]
        .iter()
        .map(|c| Problem::from_document(&c.document, skeleton.clone()).unwrap())
        .collect();
    JoinedProblem::new(scene, &[0, 1], &problems).unwrap()
}

/// Joint `joint` of character `c` posed as `postures[c]`, in the scene through its own
/// placement (not the joined skeleton).
fn in_scene(
    scene: &Scene,
    skeleton: &Skeleton,
    postures: &[Posture],
    c: usize,
    joint: &str,
) -> DVec3 {
    let frames = Frames::new(skeleton, &postures[c]);
    scene.characters[c]
        .placement
        .scene_from_character()
        .transform_point3(frames.joint_position[skeleton.joint_index(joint).unwrap()])
}

fn point(character: usize, joint: &str) -> CharacterPoint {
    CharacterPoint {
        character,
        joint: joint.into(),
        point: [0.0; 3],
    }
}

/// Two characters facing each other `gap` m apart (the first looking along +X, the second
/// along -X), the first's right wrist in the second's left at level 3; a third alone.
fn hand_in_hand(gap: f64) -> Scene {
    let skeleton = body();
    let character = |name: &str, x: f64, yaw: f64, comfort: bool| SceneCharacter {
        name: name.into(),
        placement: Placement {
            position: [x, 0.0, 0.0],
            yaw_degrees: yaw,
        },
        document: standing(&skeleton, comfort),
    };
    Scene {
        characters: vec![
            character("Ann", -gap / 2.0, 90.0, true),
            character("Bo", gap / 2.0, -90.0, false),
            character("Cy", 3.0, 0.0, false),
        ],
        props: Vec::new(),
        selected: 0,
        between: vec![BetweenTask::meet(
            point(0, "r_radiocarpal"),
            point(1, "l_radiocarpal"),
            3,
        )],
        files: Vec::new(),
    }
}

#[test]
fn tasks_between_characters_round_trip_through_json_and_links() {
    let mut scene = hand_in_hand(0.7);
    scene.between[0].a.point = [0.01, -0.05, 0.02];
    scene.between.push(BetweenTask {
        weight: 0.5,
        active: false,
        axes: stance_ik::Axes::XZ,
        ..BetweenTask::meet(point(2, "l_radiocarpal"), point(0, "skullbase"), 4)
    });
    let text = scene.to_json(false);
    assert!(text.contains("\"between\""), "{text}");
    assert_eq!(Scene::from_json(&text).unwrap(), scene);
    let fragment = link::encode_scene(&scene);
    let back = link::decode_scene(&fragment).unwrap();
    assert_eq!(back.between.len(), 2);
    assert_eq!(back.between[1], scene.between[1]);
    for (x, y) in back.between[0].a.point.iter().zip(scene.between[0].a.point) {
        assert!((x - y).abs() <= link::POSITION_STEP_M / 2.0);
    }
    // Written again, the same link; a scene without such tasks keeps the older format.
    assert_eq!(link::encode_scene(&back), fragment);
    let mut plain = scene.clone();
    plain.between.clear();
    let older = link::encode_scene(&plain);
    assert!(link::decode_scene(&older).unwrap().between.is_empty());
    assert_ne!(older[..2], fragment[..2], "the format byte differs");
    // Cut anywhere in the tasks, refused with a reason.
    for cut in [fragment.len() - 8, fragment.len() - 20, fragment.len() - 30] {
        assert!(link::decode_scene(&fragment[..cut]).is_err());
    }
}

#[test]
fn a_task_between_characters_is_checked_against_the_scene() {
    let scene = hand_in_hand(0.7);
    let mut value: serde_json::Value = serde_json::from_str(&scene.to_json(false)).unwrap();
    value["between"][0]["b"]["character"] = 7.into();
    let error = Scene::from_json(&value.to_string())
        .unwrap_err()
        .to_string();
    assert!(error.contains("between[0].b.character"), "{error}");
    value["between"][0]["b"]["character"] = 1.into();
    value["between"][0]["kind"] = "hug".into();
    let error = Scene::from_json(&value.to_string())
        .unwrap_err()
        .to_string();
    assert!(
        error.contains("between[0].kind") && error.contains("hug"),
        "{error}"
    );
    value["between"][0]["kind"] = "meet".into();
    value["between"][0]["a"]["point"] = serde_json::json!([0, "x", 0]);
    let error = Scene::from_json(&value.to_string())
        .unwrap_err()
        .to_string();
    assert!(error.contains("between[0].a.point"), "{error}");
    // A joint the body lacks is named when solved.
    let mut unknown = hand_in_hand(0.7);
    unknown.between[0].b.joint = "l_wing".into();
    let problems: Vec<Problem> = unknown.characters[..2]
        .iter()
        .map(|c| Problem::from_document(&c.document, body()).unwrap())
        .collect();
    let error = JoinedProblem::new(&unknown, &[0, 1], &problems)
        .unwrap_err()
        .to_string();
    assert!(
        error.contains("between[0].b.joint") && error.contains("l_wing"),
        "{error}"
    );
}

#[test]
fn characters_are_grouped_by_the_active_tasks_between_them() {
    let mut scene = hand_in_hand(0.7);
    assert_eq!(joined_groups(&scene), vec![vec![0, 1], vec![2]]);
    scene.between.push(BetweenTask::meet(
        point(2, "l_radiocarpal"),
        point(1, "r_radiocarpal"),
        3,
    ));
    assert_eq!(joined_groups(&scene), vec![vec![0, 1, 2]]);
    scene.between[1].active = false;
    scene.between[0].active = false;
    assert_eq!(joined_groups(&scene), vec![vec![0], vec![1], vec![2]]);
    // A removed character takes its tasks with it; the others' indices follow.
    let kept = BetweenTask::meet(point(2, "l_radiocarpal"), point(1, "r_radiocarpal"), 3);
    assert_eq!(kept.without_character(1), None);
    let moved = kept.without_character(0).unwrap();
    assert_eq!((moved.a.character, moved.b.character), (1, 0));
}

/// The wrists of two characters facing each other 0.7 m apart meet within 1 mm in the scene
/// (each posture placed by its own placement, apart from the joined skeleton), every foot
/// stays where its own task pins it, and the comfort task that cannot join the solve is named.
/// Put 4 m apart, the hands cannot meet: the feet still hold and the meet gives way.
#[test]
fn two_characters_hand_in_hand_each_keep_their_feet() {
    let skeleton = body();
    for (gap, reachable) in [(0.7, true), (4.0, false)] {
        let scene = hand_in_hand(gap);
        let joined = joined_first_two(&scene, &skeleton);
        assert_eq!(joined.left_out.len(), 1, "{:?}", joined.left_out);
        assert!(joined.left_out[0].contains("Ann") && joined.left_out[0].contains("comfort"));
        let (postures, report) = joined.solve().unwrap();
        let placed = |c: usize, joint: &str| in_scene(&scene, &skeleton, &postures, c, joint);
        let rest = Frames::new(&skeleton, &Posture::rest(&skeleton));
        for (c, posture) in postures.iter().enumerate() {
            let frames = Frames::new(&skeleton, posture);
            for ankle in ["l_talocrural", "r_talocrural"] {
                let j = skeleton.joint_index(ankle).unwrap();
                let moved = (frames.joint_position[j] - rest.joint_position[j]).length();
                assert!(
                    moved < 1e-4,
                    "character {c}'s {ankle} moved {moved} m (gap {gap})"
                );
            }
        }
        let apart = (placed(0, "r_radiocarpal") - placed(1, "l_radiocarpal")).length();
        if reachable {
            assert!(apart < 1e-3, "{apart} m apart: {report:?}");
            // They met between the two: neither hand stayed at its rest place.
            let start = placed_at_rest(&scene, &skeleton, 0, "r_radiocarpal");
            assert!((placed(0, "r_radiocarpal") - start).length() > 0.05);
        } else {
            assert!(apart > 1.0, "{apart} m apart");
            assert_eq!(report.gave_way, Some(3), "{report:?}");
        }
    }
}

fn placed_at_rest(scene: &Scene, skeleton: &Skeleton, c: usize, joint: &str) -> DVec3 {
    let frames = Frames::new(skeleton, &Posture::rest(skeleton));
    scene.characters[c]
        .placement
        .scene_from_character()
        .transform_point3(frames.joint_position[skeleton.joint_index(joint).unwrap()])
}

/// A task attached to a prop (`on`): kept by JSON and links, refused when no prop has that
/// name; `TaskSpec::moved` against a turn and a translation done by hand.
#[test]
fn a_task_attached_to_a_prop_is_kept_checked_and_moved() {
    let mut scene = hand_in_hand(0.7);
    scene.between.clear();
    scene.props.push(stance_document::Prop::new(
        "Rail".into(),
        stance_document::PropShape::Cylinder {
            radius: 0.02,
            height: 2.0,
        },
        [0.0, 1.0, 0.5],
    ));
    let mut task = stance_document::TaskSpec::new(stance_document::TaskKindSpec::Line {
        joint: "r_radiocarpal".into(),
        point: [0.0; 3],
        origin: [0.1, 1.0, 0.2],
        direction: [0.0, 1.0, 0.0],
    });
    task.on = Some("Rail".into());
    scene.characters[1].document.tasks.push(task.clone());
    let text = scene.to_json(false);
    assert_eq!(Scene::from_json(&text).unwrap(), scene);
    let back = link::decode_scene(&link::encode_scene(&scene)).unwrap();
    let kept: Vec<_> = back.characters[1]
        .document
        .tasks
        .iter()
        .filter_map(|t| t.on.clone())
        .collect();
    assert_eq!(kept, vec!["Rail".to_owned()]);
    let mut unknown = scene.clone();
    unknown.props.clear();
    let error = Scene::from_json(&unknown.to_json(false))
        .unwrap_err()
        .to_string();
    assert!(
        error.contains("characters[1].tasks[3].on") && error.contains("Rail"),
        "{error}"
    );
    // A quarter turn about +Y then 1 m along +X, by hand: (x, y, z) -> (z + 1, y, -x).
    let m = glam::DAffine3::from_rotation_translation(
        glam::DQuat::from_rotation_y(std::f64::consts::FRAC_PI_2),
        DVec3::X,
    );
    let moved = task.moved(m);
    let stance_document::TaskKindSpec::Line {
        origin, direction, ..
    } = moved.kind
    else {
        panic!("a line")
    };
    for (got, want) in origin.iter().zip([1.2, 1.0, -0.1]) {
        assert!((got - want).abs() < 1e-12, "{origin:?}");
    }
    for (got, want) in direction.iter().zip([0.0, 1.0, 0.0]) {
        assert!((got - want).abs() < 1e-12, "{direction:?}");
    }
}

/// Two characters hand in hand with their collision tasks on, the first's left wrist asked
/// (by a task of its own, level 4) into the second's spine (held where it stands): joined, the held hands still meet
/// (the limbs a task between them joins may touch) while the left wrist stops outside the
/// second's torso; without collision it reaches the spine. Distances in the scene, each
/// character placed by its own placement.
#[test]
fn joined_characters_keep_apart_but_for_the_limbs_that_meet() {
    let skeleton = body();
    let solve = |collision: bool| {
        let mut scene = hand_in_hand(0.55);
        scene.characters.truncate(2);
        // The second's spine (vl1) at rest, in the scene, then in the first's frame.
        let rest = Frames::new(&skeleton, &Posture::rest(&skeleton));
        let spine = scene.characters[1]
            .placement
            .scene_from_character()
            .transform_point3(rest.joint_position[skeleton.joint_index("vl1").unwrap()]);
        let goal = scene.characters[0]
            .placement
            .scene_from_character()
            .inverse()
            .transform_point3(spine);
        for (c, character) in scene.characters.iter_mut().enumerate() {
            character
                .document
                .tasks
                .retain(|t| t.kind.name() != "comfort");
            if collision {
                let task: stance_document::TaskSpec =
                    serde_json::from_str(r#"{"kind": "collision", "level": 2}"#).unwrap();
                character.document.tasks.push(task);
            }
            // The first's left wrist toward the second's spine (level 4); the second's spine
            // held where it stands (level 1), so that only its arm reaches for the hand.
            let (joint, target, level) = if c == 0 {
                ("l_radiocarpal", goal, 4)
            } else {
                (
                    "vl1",
                    rest.joint_position[skeleton.joint_index("vl1").unwrap()],
                    1,
                )
            };
            let task: stance_document::TaskSpec = serde_json::from_str(&format!(
                r#"{{"kind": "position", "joint": "{joint}", "target": [{}, {}, {}], "level": {level}}}"#,
                target.x, target.y, target.z
            ))
            .unwrap();
            character.document.tasks.push(task);
        }
        let joined = joined_first_two(&scene, &skeleton);
        assert!(joined.left_out.is_empty(), "{:?}", joined.left_out);
        let (postures, _) = joined.solve().unwrap();
        let placed = |c: usize, joint: &str| in_scene(&scene, &skeleton, &postures, c, joint);
        (
            (placed(0, "l_radiocarpal") - placed(1, "vl1")).length(),
            (placed(0, "r_radiocarpal") - placed(1, "l_radiocarpal")).length(),
        )
    };
    let (free, _) = solve(false);
    let (held, hands) = solve(true);
    assert!(
        free < 0.02,
        "without collision the left wrist is {free} m from the spine"
    );
    assert!(
        held > 0.08,
        "with collision the left wrist is {held} m from the spine"
    );
    assert!(hands < 1e-3, "the held hands are {hands} m apart");
}

/// With both characters' collision tasks on, hands held still meet: the limbs a task between
/// them joins may touch (they are not kept apart), while each body keeps its own capsules.
#[test]
fn hands_held_meet_with_collision_on() {
    let skeleton = body();
    let mut scene = hand_in_hand(0.7);
    scene.characters.truncate(2);
    for character in &mut scene.characters {
        let task: stance_document::TaskSpec =
            serde_json::from_str(r#"{"kind": "collision", "level": 2}"#).unwrap();
        character.document.tasks.push(task);
    }
    let (postures, report) = joined_first_two(&scene, &skeleton).solve().unwrap();
    let placed = |c: usize, joint: &str| in_scene(&scene, &skeleton, &postures, c, joint);
    let apart = (placed(0, "r_radiocarpal") - placed(1, "l_radiocarpal")).length();
    assert!(apart < 1e-3, "{apart} m apart: {report:?}");
}
