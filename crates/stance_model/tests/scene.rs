//! Several characters in one scene, driven by commands alone: add, duplicate, remove, rename,
//! select and place them; every tool works on the selected one and leaves the others as they
//! were; undo covers all of it (selecting the character a step changes); the scene is saved,
//! opened and autosaved as one document.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use stance_document::{Placement, Scene};
use stance_model::model::{FileCommand, HistoryCommand, PostureCommand, SceneCommand};
use stance_model::{Change, Command, MemoryHost};

use crate::clocked::Clocked;

/// The names in the scene's order, and the selected one's.
fn names(editor: &Clocked) -> (Vec<String>, String) {
    let names = editor
        .model
        .characters()
        .map(|(c, _)| c.name().to_owned())
        .collect();
    (names, editor.model.character().name().to_owned())
}

fn undo(editor: &mut Clocked) -> Change {
    editor.apply(Command::History(HistoryCommand::Undo))
}

fn redo(editor: &mut Clocked) -> Change {
    editor.apply(Command::History(HistoryCommand::Redo))
}

/// Bends the selected character's left elbow to `value` (rad).
fn bend_elbow(editor: &mut Clocked, value: f64) {
    let elbow = editor.joint("l_elbow");
    let dof = editor.model.session().skeleton().joints()[elbow].dof_start;
    editor.apply(Command::Posture(PostureCommand::SetDof { dof, value }));
}

fn elbow(editor: &Clocked) -> f64 {
    let elbow = editor.joint("l_elbow");
    let dof = editor.model.session().skeleton().joints()[elbow].dof_start;
    editor.model.session().posture().values()[dof]
}

fn id_of(editor: &Clocked, name: &str) -> u64 {
    editor
        .model
        .characters()
        .find(|(c, _)| c.name() == name)
        .map(|(c, _)| c.id())
        .unwrap_or_else(|| panic!("{name} is in the scene"))
}

#[test]
fn an_added_character_stands_beside_the_first_is_selected_and_undo_takes_it_away() {
    // Catches: a character added on top of the other, not selected, or not undoable.
    let mut editor = Clocked::new();
    assert_eq!(editor.model.character_count(), 1);
    assert_eq!(
        editor.apply(Command::Scene(SceneCommand::Add)),
        Change::Document
    );
    editor.settle();
    assert_eq!(
        names(&editor),
        (
            vec!["Character 1".into(), "Character 2".into()],
            "Character 2".into()
        )
    );
    let placement = editor.model.character().placement();
    assert!(
        (placement.position[0] - stance_model::model::CHARACTER_SPACING_M).abs() < 1e-12,
        "{placement:?}"
    );
    // The new one has a body of its own, drawn from its own bones.
    assert!(!editor.model.character().bones().is_empty());
    let added = editor.model.character().id();
    assert_eq!(undo(&mut editor), Change::Document);
    assert_eq!(
        names(&editor),
        (vec!["Character 1".into()], "Character 1".into())
    );
    assert_eq!(redo(&mut editor), Change::Document);
    assert_eq!(
        editor.model.character().id(),
        added,
        "redo brings the same character back"
    );
    assert_eq!(editor.model.character_count(), 2);
}

#[test]
fn the_tools_work_on_the_selected_character_and_undo_selects_the_one_it_changes() {
    // Catches: an edit reaching another character's posture, a switch that loses a posture,
    // undo applied to whichever character is selected.
    let mut editor = Clocked::new();
    bend_elbow(&mut editor, -0.5);
    let first = editor.model.character().id();
    editor.apply(Command::Scene(SceneCommand::Add));
    let second = editor.model.character().id();
    assert!(
        elbow(&editor).abs() < 1e-12,
        "the new character stands at rest"
    );
    bend_elbow(&mut editor, -1.1);
    editor.apply(Command::Scene(SceneCommand::Select(first)));
    assert_eq!(editor.model.character().id(), first);
    assert!(
        (elbow(&editor) + 0.5).abs() < 1e-12,
        "the first kept its elbow"
    );
    // The last edit was the second's elbow: undo selects it and takes the bend back.
    assert_eq!(undo(&mut editor), Change::Document);
    assert_eq!(editor.model.character().id(), second);
    assert!(elbow(&editor).abs() < 1e-12);
    // Next, the addition itself; then the first one's bend.
    undo(&mut editor);
    assert_eq!(editor.model.character_count(), 1);
    undo(&mut editor);
    assert_eq!(editor.model.character().id(), first);
    assert!(elbow(&editor).abs() < 1e-12);
    // And forward again, to the second's bend.
    redo(&mut editor);
    redo(&mut editor);
    redo(&mut editor);
    assert_eq!(editor.model.character().id(), second);
    assert!((elbow(&editor) + 1.1).abs() < 1e-12);
}

#[test]
fn a_duplicate_copies_posture_and_tasks_under_a_name_of_its_own() {
    let mut editor = Clocked::new();
    bend_elbow(&mut editor, -0.7);
    let tasks = editor.model.session().tasks().to_vec();
    editor.apply(Command::Scene(SceneCommand::Duplicate));
    assert_eq!(names(&editor).1, "Character 1 2");
    assert!((elbow(&editor) + 0.7).abs() < 1e-12);
    assert_eq!(editor.model.session().tasks(), tasks.as_slice());
    assert_ne!(editor.model.character().placement(), Placement::default());
    // The copy's edits stay its own.
    bend_elbow(&mut editor, 0.0);
    let first = id_of(&editor, "Character 1");
    editor.apply(Command::Scene(SceneCommand::Select(first)));
    assert!((elbow(&editor) + 0.7).abs() < 1e-12);
}

#[test]
fn removing_selects_the_next_keeps_the_last_and_undo_brings_it_back_as_it_was() {
    let mut editor = Clocked::new();
    editor.apply(Command::Scene(SceneCommand::Add));
    editor.apply(Command::Scene(SceneCommand::Add));
    let second = id_of(&editor, "Character 2");
    editor.apply(Command::Scene(SceneCommand::Select(second)));
    bend_elbow(&mut editor, -0.9);
    assert_eq!(
        editor.apply(Command::Scene(SceneCommand::Remove(second))),
        Change::Document
    );
    assert_eq!(
        names(&editor),
        (
            vec!["Character 1".into(), "Character 3".into()],
            "Character 3".into()
        )
    );
    assert_eq!(undo(&mut editor), Change::Document);
    assert_eq!(
        names(&editor),
        (
            vec![
                "Character 1".into(),
                "Character 2".into(),
                "Character 3".into()
            ],
            "Character 2".into()
        )
    );
    assert!(
        (elbow(&editor) + 0.9).abs() < 1e-12,
        "it comes back with its posture"
    );
    // The last character stays.
    for (id, _) in editor
        .model
        .characters()
        .map(|(c, s)| (c.id(), s))
        .collect::<Vec<_>>()
    {
        editor.apply(Command::Scene(SceneCommand::Remove(id)));
    }
    assert_eq!(editor.model.character_count(), 1);
    assert!(editor.model.notice().is_some_and(|n| n.is_error));
}

#[test]
fn renaming_trims_refuses_an_empty_name_and_is_undone() {
    let mut editor = Clocked::new();
    let id = editor.model.character().id();
    assert_eq!(
        editor.apply(Command::Scene(SceneCommand::Rename(
            id,
            "  Dancer \n".into()
        ))),
        Change::Document
    );
    assert_eq!(editor.model.character().name(), "Dancer");
    assert_eq!(
        editor.apply(Command::Scene(SceneCommand::Rename(id, "   ".into()))),
        Change::Nothing
    );
    assert_eq!(editor.model.character().name(), "Dancer");
    undo(&mut editor);
    assert_eq!(editor.model.character().name(), "Character 1");
}

#[test]
fn a_scene_saved_opens_as_it_was_and_opening_it_is_one_undo_step() {
    // Catches: characters, names, placements or postures lost on the way through the file;
    // an opened scene that cannot be taken back.
    let host = MemoryHost::default();
    let storage = host.inner.clone();
    let mut editor = Clocked::with_host(host);
    bend_elbow(&mut editor, -0.4);
    editor.apply(Command::Scene(SceneCommand::Duplicate));
    let id = editor.model.character().id();
    let placement = Placement {
        position: [1.5, 0.0, -0.25],
        yaw_degrees: 30.0,
    };
    editor.apply(Command::Scene(SceneCommand::Place(id, placement)));
    bend_elbow(&mut editor, -1.2);
    editor.apply(Command::File(FileCommand::ExportDocument));
    let (_, text) = storage
        .borrow()
        .downloads
        .last()
        .cloned()
        .expect("a download");
    let saved = Scene::from_json(&text).expect("the export is a scene");
    assert_eq!(saved.characters.len(), 2);
    assert_eq!(saved.selected, 1);

    let mut other = Clocked::new();
    other.apply(Command::File(FileCommand::OpenFile {
        name: "scene.json".into(),
        bytes: text.into_bytes(),
    }));
    other.settle();
    assert_eq!(
        names(&other),
        (
            vec!["Character 1".into(), "Character 1 2".into()],
            "Character 1 2".into()
        )
    );
    assert_eq!(other.model.character().placement(), placement);
    assert!((elbow(&other) + 1.2).abs() < 1e-6);
    assert_eq!(other.model.scene(), editor.model.scene());
    undo(&mut other);
    assert_eq!(other.model.character_count(), 1);
    assert!(elbow(&other).abs() < 1e-12);
}

#[test]
fn the_autosave_keeps_the_whole_scene() {
    let host = MemoryHost::default();
    let mut editor = Clocked::with_host(host.clone());
    editor.apply(Command::Scene(SceneCommand::Add));
    bend_elbow(&mut editor, -0.6);
    editor.frames(90);
    // The page reloaded: a new editor on the same storage.
    let mut model = stance_model::EditorModel::new(Box::new(host)).expect("the editor starts");
    model.open_startup(None);
    let mut reloaded = Clocked { model, now: 0.0 };
    reloaded.frames(1);
    assert_eq!(reloaded.model.character_count(), 2);
    assert_eq!(reloaded.model.scene(), editor.model.scene());
}

#[test]
fn a_scene_link_opens_every_character_where_it_stood() {
    // Catches: a share link that carries the selected character alone.
    let mut editor = Clocked::new();
    bend_elbow(&mut editor, -0.4);
    editor.apply(Command::Scene(SceneCommand::Duplicate));
    bend_elbow(&mut editor, -1.0);
    let link = editor.model.share_link();
    assert!(link.keys_left_out.is_none());
    let mut other = Clocked::new();
    other.model.open_startup(Some(&link.url));
    other.settle();
    assert_eq!(names(&other), names(&editor));
    let placement = other.model.character().placement();
    assert_eq!(placement, editor.model.character().placement());
    assert!((elbow(&other) + 1.0).abs() < 1e-4);
    let first = id_of(&other, "Character 1");
    other.apply(Command::Scene(SceneCommand::Select(first)));
    assert!((elbow(&other) + 0.4).abs() < 1e-4);
    // One character at the origin still shares the link older versions read.
    let single = Clocked::new().model.share_link();
    assert!(stance_document::link::decode(&single.url).is_ok());
}

#[test]
fn props_are_added_in_front_edited_removed_and_undone_with_the_scene() {
    use stance_document::PropShape;
    let mut editor = Clocked::new();
    editor.apply(Command::Scene(SceneCommand::Add));
    editor.apply(Command::Scene(SceneCommand::AddProp(PropShape::Sphere {
        radius: 0.11,
    })));
    let ball = editor.model.props()[0].clone();
    assert_eq!(ball.name, "Sphere 1");
    // In front of the selected character (+Z of its frame), at chest height.
    let at = editor.model.character().placement().position;
    assert!((ball.position[0] - at[0]).abs() < 1e-9, "{ball:?}");
    assert!(
        ball.position[2] > at[2] + 0.3 && ball.position[1] > 0.8,
        "{ball:?}"
    );
    // A drag of its height over frames is one step.
    for step in 1..=10 {
        let mut moved = ball.clone();
        moved.position[1] += 0.01 * f64::from(step);
        editor.apply(Command::Scene(SceneCommand::EditProp(0, moved)));
    }
    assert!((editor.model.props()[0].position[1] - ball.position[1] - 0.1).abs() < 1e-12);
    undo(&mut editor);
    assert_eq!(editor.model.props()[0], ball);
    // A size of zero is refused, nothing changes.
    let flat = stance_document::Prop {
        shape: PropShape::Sphere { radius: 0.0 },
        ..ball.clone()
    };
    assert_eq!(
        editor.apply(Command::Scene(SceneCommand::EditProp(0, flat))),
        Change::Nothing
    );
    editor.apply(Command::Scene(SceneCommand::AddProp(PropShape::Cylinder {
        radius: 0.02,
        height: 2.0,
    })));
    assert_eq!(editor.model.props().len(), 2);
    // Saved and shared with the scene.
    let scene = editor.model.scene();
    assert_eq!(scene.props.len(), 2);
    let link = stance_document::link::decode_scene(&editor.model.share_link().url).expect("opens");
    assert_eq!(link.props.len(), 2);
    editor.apply(Command::Scene(SceneCommand::RemoveProp(0)));
    assert_eq!(editor.model.props()[0].name, "Cylinder 1");
    undo(&mut editor);
    assert_eq!(editor.model.props().len(), 2);
    assert_eq!(editor.model.props()[0], ball);
}

/// The selected character's joint `name` in the scene (its placement applied).
fn in_scene(editor: &Clocked, name: &str) -> glam::DVec3 {
    let placement = editor.model.character().placement();
    placement
        .scene_from_character()
        .transform_point3(editor.position(name))
}

#[test]
fn a_hand_put_on_a_bar_reaches_its_axis_and_one_put_on_a_table_rests_on_it() {
    // Catches: a prop's geometry taken in the wrong frame (the character is moved and turned
    // here), the bar's axis or the box's top misplaced, the task not added at all. The oracle
    // is the props' own scene geometry, not the tasks made from them.
    use stance_document::PropShape;
    use stance_model::model::TaskCommand;
    let mut editor = Clocked::new();
    let id = editor.model.character().id();
    editor.apply(Command::Scene(SceneCommand::Place(
        id,
        Placement {
            position: [0.4, 0.0, 0.2],
            yaw_degrees: 30.0,
        },
    )));
    editor.settle();
    // A vertical bar 12 cm beside the right wrist (in the scene).
    editor.apply(Command::Scene(SceneCommand::AddProp(PropShape::Cylinder {
        radius: 0.02,
        height: 2.0,
    })));
    let wrist = in_scene(&editor, "r_radiocarpal");
    let mut bar = editor.model.props()[0].clone();
    bar.position = [wrist.x - 0.12, 1.0, wrist.z + 0.05];
    bar.rotation = [0.0, 0.0, 0.0, 1.0];
    editor.apply(Command::Scene(SceneCommand::EditProp(0, bar.clone())));
    let r_wrist = editor.joint("r_radiocarpal");
    let feet = (
        in_scene(&editor, "l_talocrural"),
        in_scene(&editor, "r_talocrural"),
    );
    let added = editor.apply(Command::Task(TaskCommand::AddOnProp {
        joint: r_wrist,
        prop: 0,
    }));
    assert_eq!(added, Change::Document);
    editor.settle();
    let wrist = in_scene(&editor, "r_radiocarpal");
    let off_axis = glam::DVec2::new(wrist.x - bar.position[0], wrist.z - bar.position[2]).length();
    assert!(
        off_axis < 1e-3,
        "the wrist is {off_axis} m from the bar's axis"
    );
    assert!((in_scene(&editor, "l_talocrural") - feet.0).length() < 1e-3);
    assert!((in_scene(&editor, "r_talocrural") - feet.1).length() < 1e-3);

    // A table top 8 cm under the left hand: the hand put on it.
    editor.apply(Command::Scene(SceneCommand::AddProp(PropShape::Plane {
        size: [0.6, 0.4],
    })));
    let hand = in_scene(&editor, "l_radiocarpal");
    let mut table = editor.model.props()[1].clone();
    table.position = [hand.x + 0.05, hand.y - 0.08, hand.z + 0.1];
    table.rotation = [0.0, 0.0, 0.0, 1.0];
    editor.apply(Command::Scene(SceneCommand::EditProp(1, table.clone())));
    let l_wrist = editor.joint("l_radiocarpal");
    editor.apply(Command::Task(TaskCommand::AddOnProp {
        joint: l_wrist,
        prop: 1,
    }));
    editor.settle();
    let hand = in_scene(&editor, "l_radiocarpal");
    assert!(
        (hand.y - table.position[1]).abs() < 1e-3,
        "the hand at {} m, the table at {} m",
        hand.y,
        table.position[1]
    );
    // The bar still held.
    let wrist = in_scene(&editor, "r_radiocarpal");
    let off_axis = glam::DVec2::new(wrist.x - bar.position[0], wrist.z - bar.position[2]).length();
    assert!(off_axis < 1e-3);
    // A prop that is not there is refused by name, nothing added.
    let before = editor.model.session().tasks().len();
    editor.apply(Command::Task(TaskCommand::AddOnProp {
        joint: l_wrist,
        prop: 9,
    }));
    assert_eq!(editor.model.session().tasks().len(), before);
    assert!(
        editor
            .model
            .notice()
            .is_some_and(|n| n.text.contains("no prop 9"))
    );
}

/// Every node's world matrix in a glTF document, by index.
fn world_matrices(document: &gltf::Document) -> Vec<glam::DMat4> {
    let mut world = vec![glam::DMat4::IDENTITY; document.nodes().len()];
    fn walk(node: gltf::Node<'_>, parent: glam::DMat4, world: &mut [glam::DMat4]) {
        let local = glam::Mat4::from_cols_array_2d(&node.transform().matrix()).as_dmat4();
        world[node.index()] = parent * local;
        for child in node.children() {
            walk(child, world[node.index()], world);
        }
    }
    for scene in document.scenes() {
        for node in scene.nodes() {
            walk(node, glam::DMat4::IDENTITY, &mut world);
        }
    }
    world
}

#[test]
fn the_scene_exports_as_one_glb_with_every_character_posed_where_it_stands_and_the_props() {
    // Catches: only the selected character exported, a placement (or its turn) dropped, the
    // mannequin left out, a prop missing or misplaced, nodes not named as in the outliner,
    // indices of the second avatar not moved along (its skin on the first's joints).
    use stance_document::{Prop, PropShape};
    use stance_model::model::AvatarCommand;
    let host = MemoryHost::default();
    let storage = host.inner.clone();
    let mut editor = Clocked::with_host(host);
    // The first on an avatar file, the second on the mannequin (drawn as its figure).
    editor.apply(Command::Avatar(AvatarCommand::LoadAvatar {
        name: "figure.glb".to_owned(),
        bytes: stance_asset::export_glb(&stance_asset::make_default_avatar().unwrap()).unwrap(),
    }));
    assert!(editor.model.avatar().is_some());
    let first = editor.model.character().id();
    editor.apply(Command::Scene(SceneCommand::Add));
    let second = editor.model.character().id();
    bend_elbow(&mut editor, -1.1);
    let placements = [
        Placement {
            position: [-0.6, 0.0, 0.25],
            yaw_degrees: 0.0,
        },
        Placement {
            position: [1.2, 0.1, -0.4],
            yaw_degrees: 90.0,
        },
    ];
    editor.apply(Command::Scene(SceneCommand::Place(first, placements[0])));
    editor.apply(Command::Scene(SceneCommand::Place(second, placements[1])));
    editor.apply(Command::Scene(SceneCommand::AddProp(PropShape::Box {
        size: [0.4, 0.3, 0.5],
    })));
    let mut prop: Prop = editor.model.props()[0].clone();
    prop.position = [0.3, 0.15, 0.9];
    prop.rotation = glam::DQuat::from_rotation_y(0.5).to_array();
    editor.apply(Command::Scene(SceneCommand::EditProp(0, prop.clone())));
    editor.settle();

    editor.apply(Command::Avatar(AvatarCommand::ExportPosedAvatar));
    let notice = editor.model.notice().unwrap();
    assert!(!notice.is_error, "{}", notice.text);
    let (name, bytes) = storage.borrow().binary_downloads.last().cloned().unwrap();
    assert_eq!(name, "stance-scene.glb");
    let glb = gltf::Gltf::from_slice(&bytes).expect("a GLB the gltf crate reads");
    let document = &glb.document;
    let world = world_matrices(document);
    let roots: Vec<gltf::Node<'_>> = document.scenes().next().unwrap().nodes().collect();
    let names: Vec<&str> = roots.iter().map(|n| n.name().unwrap()).collect();
    let expected: Vec<String> = editor
        .model
        .characters()
        .map(|(c, _)| c.name().to_owned())
        .chain([prop.name.clone()])
        .collect();
    assert_eq!(names, expected);
    // Two skinned bodies and the box: three meshes at least, two skins, one mesh at the prop.
    assert_eq!(document.skins().len(), 2);
    assert!(roots[2].mesh().is_some() && roots[2].children().len() == 0);

    // Each character's joints where its posture puts them, in the scene (within 1 mm).
    for ((character, _), (root, placement)) in
        editor.model.characters().zip(roots.iter().zip(placements))
    {
        let place = placement.scene_from_character();
        let origin = world[root.index()].transform_point3(glam::DVec3::ZERO);
        assert!(
            (origin - glam::DVec3::from_array(placement.position)).length() < 1e-3,
            "{}: its node at {origin}",
            character.name()
        );
        let mut below = Vec::new();
        let mut stack = vec![root.clone()];
        while let Some(node) = stack.pop() {
            stack.extend(node.children());
            below.push(node);
        }
        for joint in [
            "humanoid_root",
            "l_radiocarpal",
            "r_talocrural",
            "skullbase",
        ] {
            let node = below
                .iter()
                .find(|n| n.name() == Some(joint))
                .unwrap_or_else(|| panic!("{}: no {joint} node", character.name()));
            let exported = world[node.index()].transform_point3(glam::DVec3::ZERO);
            let posed = place.transform_point3(character.session().joint_position(joint).unwrap());
            assert!(
                (exported - posed).length() < 1e-3,
                "{} {joint}: exported at {exported}, posed at {posed}",
                character.name()
            );
        }
    }
    // The box: placed and turned as the prop, its mesh its size.
    let box_world = world[roots[2].index()];
    let (scale, rotation, translation) = box_world.to_scale_rotation_translation();
    assert!((translation - glam::DVec3::from_array(prop.position)).length() < 1e-6);
    assert!(rotation.angle_between(glam::DQuat::from_array(prop.rotation)) < 1e-6);
    assert!((scale - glam::DVec3::ONE).length() < 1e-6);
    let bounds = roots[2]
        .mesh()
        .unwrap()
        .primitives()
        .next()
        .unwrap()
        .bounding_box();
    for axis in 0..3 {
        let extent = f64::from(bounds.max[axis] - bounds.min[axis]);
        assert!((extent - [0.4, 0.3, 0.5][axis]).abs() < 1e-6, "{bounds:?}");
    }
}

#[test]
fn the_openpose_map_has_every_character_in_view_placed_in_the_scene() {
    // Catches: only the selected character in the map, or its keypoints left in its own
    // frame (the second character standing 1.2 m to the right and turned to face +X would
    // then be drawn on top of the first, facing the camera).
    use stance_render::{HiddenKeypoints, OrbitCamera};
    let mut editor = Clocked::new();
    editor.settle_within(200);
    editor.apply(Command::Scene(SceneCommand::Add));
    editor.settle_within(200);
    let second = editor.model.character().id();
    let placement = Placement {
        position: [1.2, 0.0, 0.0],
        yaw_degrees: 90.0,
    };
    editor.apply(Command::Scene(SceneCommand::Place(second, placement)));
    let front = OrbitCamera {
        target_world: glam::Vec3::new(0.6, 1.0, 0.0),
        yaw: 0.0,
        pitch: 0.0,
        distance_m: 5.0,
        ..OrbitCamera::default()
    };
    let size = [800, 600];
    let pose = editor.model.openpose(&front, size, HiddenKeypoints::Keep);
    assert_eq!(pose.people.len(), 2, "one person per character in view");
    // Each neck (COCO-18's 1) where its character's shoulders' midpoint lands, placed by
    // hand: the character's frame turned about the vertical, then moved.
    let neck_of = |index: usize, place: Placement| {
        let (character, _) = editor.model.characters().nth(index).unwrap();
        let session = character.session();
        let frames = session.frames();
        let joint = |name: &str| {
            let j = session.skeleton().joint_index(name).unwrap();
            frames.joint_position[j]
        };
        let mid = (joint("l_shoulder") + joint("r_shoulder")) * 0.5;
        let turn = place.yaw_degrees.to_radians();
        let turned = glam::DVec3::new(
            mid.x * turn.cos() + mid.z * turn.sin(),
            mid.y,
            -mid.x * turn.sin() + mid.z * turn.cos(),
        );
        let world = turned + glam::DVec3::from_array(place.position);
        front
            .project(world.as_vec3(), glam::Vec2::new(800.0, 600.0))
            .unwrap()
            .as_dvec2()
    };
    let expected = [neck_of(0, Placement::default()), neck_of(1, placement)];
    for (person, expected) in pose.people.iter().zip(expected) {
        let neck = person.body[1].expect("the neck is seen");
        assert!((neck - expected).length() < 0.5, "{neck} vs {expected}");
    }
    assert!(
        expected[1].x - expected[0].x > 100.0,
        "the second stands to the right"
    );
}

#[test]
fn table1_places_its_sphere_and_bar_where_its_hands_reach_them() {
    // Catches: Table 1's hands reaching into empty space, props left at the origin when the
    // character stands elsewhere, a second click adding a second pair.
    use stance_document::PropShape;
    use stance_model::model::TaskCommand;
    let mut editor = Clocked::new();
    let id = editor.model.character().id();
    let placement = Placement {
        position: [1.0, 0.0, -0.5],
        yaw_degrees: 30.0,
    };
    editor.apply(Command::Scene(SceneCommand::Place(id, placement)));
    editor.apply(Command::Task(TaskCommand::LoadTable1Example));
    editor.apply(Command::Task(TaskCommand::LoadTable1Example));
    editor.settle();
    let props = editor.model.props();
    assert_eq!(props.len(), 2, "{props:?}");
    let right = in_scene(&editor, "r_radiocarpal");
    let left = in_scene(&editor, "l_radiocarpal");
    for prop in props {
        let centre = glam::DVec3::from_array(prop.position);
        match prop.shape {
            PropShape::Sphere { radius } => {
                let gap = (right - centre).length() - radius;
                assert!(gap.abs() < 1e-3, "the right hand is {gap} m off the sphere");
            }
            PropShape::Cylinder { radius, .. } => {
                let off = glam::DVec2::new(left.x - centre.x, left.z - centre.z).length();
                assert!(off < radius, "the left hand is {off} m from the bar's axis");
            }
            _ => panic!("{prop:?}"),
        }
    }
    // One undo takes the tasks back, the next the props.
    editor.apply(Command::History(HistoryCommand::Undo));
    editor.apply(Command::History(HistoryCommand::Undo));
    editor.apply(Command::History(HistoryCommand::Undo));
    assert!(editor.model.props().is_empty());
}

#[test]
fn a_hand_on_a_bar_follows_the_bar_and_stays_on_it_when_the_character_moves() {
    // Catches: a goal left where the prop was (not attached), a goal moved with the character
    // instead of staying on the prop, an undo that moves the bar back but not the hand, the
    // attachment lost in the link.
    use stance_document::PropShape;
    use stance_model::model::TaskCommand;
    let mut editor = Clocked::new();
    editor.apply(Command::Scene(SceneCommand::AddProp(PropShape::Cylinder {
        radius: 0.02,
        height: 2.0,
    })));
    let wrist = in_scene(&editor, "r_radiocarpal");
    let mut bar = editor.model.props()[0].clone();
    bar.position = [wrist.x - 0.1, 1.0, wrist.z + 0.1];
    editor.apply(Command::Scene(SceneCommand::EditProp(0, bar.clone())));
    let r_wrist = editor.joint("r_radiocarpal");
    editor.apply(Command::Task(TaskCommand::AddOnProp {
        joint: r_wrist,
        prop: 0,
    }));
    editor.settle();
    let on_bar = |editor: &Clocked| {
        let bar = &editor.model.props()[0];
        let wrist = in_scene(editor, "r_radiocarpal");
        glam::DVec2::new(wrist.x - bar.position[0], wrist.z - bar.position[2]).length()
    };
    assert!(on_bar(&editor) < 1e-3);
    // The bar moved 8 cm aside and renamed: the hand follows it.
    let mut moved = bar.clone();
    moved.position[2] += 0.08;
    moved.name = "Rail".into();
    editor.apply(Command::Scene(SceneCommand::EditProp(0, moved)));
    editor.settle();
    assert!(
        on_bar(&editor) < 1e-3,
        "{} m off the moved bar",
        on_bar(&editor)
    );
    // The character moved 5 cm: the hand stays on the bar (in the scene).
    let id = editor.model.character().id();
    editor.apply(Command::Scene(SceneCommand::Place(
        id,
        Placement {
            position: [0.05, 0.0, 0.0],
            yaw_degrees: 10.0,
        },
    )));
    editor.settle();
    assert!(
        on_bar(&editor) < 1e-3,
        "{} m off after the move",
        on_bar(&editor)
    );
    // Undo (the move and the bar's edit, one step when made in quick succession): the hand
    // stays on the bar wherever undo puts it.
    editor.apply(Command::History(HistoryCommand::Undo));
    editor.settle();
    assert!(
        on_bar(&editor) < 1e-3,
        "{} m off after undo",
        on_bar(&editor)
    );
    editor.apply(Command::History(HistoryCommand::Redo));
    editor.settle();
    assert!(
        on_bar(&editor) < 1e-3,
        "{} m off after redo",
        on_bar(&editor)
    );
    // The link keeps the attachment: moved in another editor, the hand follows.
    let link = editor.model.share_link();
    let mut other = Clocked::new();
    other.model.open_startup(Some(&link.url));
    other.settle();
    let attached: Vec<_> = other
        .model
        .session()
        .tasks()
        .iter()
        .filter_map(|t| t.on.clone())
        .collect();
    assert_eq!(attached, vec![other.model.props()[0].name.clone()]);
    let mut again = other.model.props()[0].clone();
    again.position[0] -= 0.06;
    other.apply(Command::Scene(SceneCommand::EditProp(0, again)));
    other.settle();
    assert!(
        on_bar(&other) < 1e-3,
        "{} m off in the other editor",
        on_bar(&other)
    );
}
