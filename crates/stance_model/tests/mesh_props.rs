//! Mesh props driven by commands alone: a static GLB imported as a prop (*File > Import
//! prop...*) stands on the floor in front of the selected character, sized from its bounds,
//! in one undo step; links name its file (documents carry it: `kept_prop_files.rs`); one
//! opened without the file keeps the prop as its box and says which file to load; loading it
//! then draws that prop with it.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use glam::{DAffine3, DVec3};
use stance_asset::{SceneContent, SceneNode, StaticMesh, export_scene_glb};
use stance_document::{Prop, PropShape};
use stance_model::Command;
use stance_model::model::{FileCommand, HistoryCommand, SceneCommand};

use crate::clocked::Clocked;

/// A GLB holding one box, 0.4 m wide, 0.8 m high and 0.6 m deep, centred on (2, 5, -1) (its
/// node moved there), written by the scene exporter: 8 corners, 12 triangles.
fn box_glb() -> Vec<u8> {
    let half = DVec3::new(0.2, 0.4, 0.3);
    let positions: Vec<[f32; 3]> = (0..8)
        .map(|i| {
            let sign = |bit: i32| if i & bit == 0 { -1.0 } else { 1.0 };
            (half * DVec3::new(sign(1), sign(2), sign(4)))
                .as_vec3()
                .into()
        })
        .collect();
    let indices = vec![
        0, 2, 1, 1, 2, 3, 4, 5, 6, 5, 7, 6, 0, 1, 4, 1, 5, 4, 2, 6, 3, 3, 6, 7, 0, 4, 2, 2, 4, 6,
        1, 3, 5, 3, 7, 5,
    ];
    let mesh = StaticMesh {
        positions,
        normals: Vec::new(),
        indices,
        color_linear: [0.1, 0.5, 0.2, 1.0],
    };
    let node = SceneNode {
        name: "Box".into(),
        scene_from_node: DAffine3::from_translation(DVec3::new(2.0, 5.0, -1.0)),
        content: SceneContent::Mesh(std::slice::from_ref(&mesh)),
    };
    export_scene_glb(&[node]).unwrap()
}

/// Imports `bytes` as the prop file `name`, as *File > Import prop...* does.
fn import_prop(editor: &mut Clocked, name: &str, bytes: Vec<u8>) {
    editor.apply(Command::File(FileCommand::PickProp));
    editor.apply(Command::File(FileCommand::OpenFile {
        name: name.into(),
        bytes,
    }));
}

fn notice(editor: &Clocked) -> String {
    editor
        .model
        .notice()
        .map(|n| n.text.clone())
        .unwrap_or_default()
}

fn near(a: [f64; 3], b: [f64; 3], tolerance: f64) -> bool {
    a.iter().zip(b).all(|(x, y)| (x - y).abs() <= tolerance)
}

#[test]
fn an_imported_mesh_stands_in_front_sized_from_its_bounds_in_one_undo_step() {
    let mut editor = Clocked::new();
    import_prop(&mut editor, "props/chair.glb", box_glb());
    let props = editor.model.props().to_vec();
    assert_eq!(props.len(), 1, "{}", notice(&editor));
    let chair = &props[0];
    assert_eq!(chair.name, "chair");
    // Named by its file (the folder left out), sized from its bounds.
    let PropShape::Mesh { file, size } = &chair.shape else {
        panic!("a mesh prop: {chair:?}")
    };
    assert_eq!(file, "chair.glb");
    assert!(near(*size, [0.4, 0.8, 0.6], 1e-6), "{size:?}");
    // On the floor (its bottom at y = 0, wherever the file put it), in front of the character
    // at the origin facing +Z: its box begins 0.3 m ahead, so its centre is 0.3 + 0.3 ahead.
    assert!(near(chair.position, [0.0, 0.4, 0.6], 1e-6), "{chair:?}");
    let mesh = editor.model.prop_mesh(chair).expect("drawn with its file");
    assert_eq!((mesh.vertex_count(), mesh.triangle_count()), (8, 12));
    // One undo step takes it away, redo brings it back.
    editor.apply(Command::History(HistoryCommand::Undo));
    assert!(editor.model.props().is_empty());
    editor.apply(Command::History(HistoryCommand::Redo));
    assert_eq!(editor.model.props(), &props[..]);
    // The gizmo's scale and move edit it as a box; its file stays.
    let mut moved = chair.clone();
    moved.shape = chair.shape.with_dimensions(&[0.8, 1.6, 1.2]).unwrap();
    moved.position = [1.0, 0.8, 0.0];
    editor.apply(Command::Scene(SceneCommand::EditProp(0, moved.clone())));
    assert_eq!(editor.model.props()[0], moved);
    assert!(editor.model.prop_mesh(&moved).is_some());
    // A second import of the same file is a second prop, named apart.
    import_prop(&mut editor, "chair.glb", box_glb());
    assert_eq!(editor.model.props()[1].name, "chair 2");
}

#[test]
fn a_file_that_is_not_a_mesh_says_why_and_changes_nothing() {
    let mut editor = Clocked::new();
    import_prop(&mut editor, "notes.glb", b"hello".to_vec());
    assert!(editor.model.props().is_empty());
    let text = notice(&editor);
    assert!(
        text.contains("notes.glb could not be imported as a prop") && text.contains("not a glTF"),
        "{text}"
    );
    // A glTF file without triangles.
    let empty = br#"{"asset": {"version": "2.0"}, "scenes": [{"nodes": [0]}], "nodes": [{}]}"#;
    import_prop(&mut editor, "empty.gltf", empty.to_vec());
    assert!(editor.model.props().is_empty());
    assert!(
        notice(&editor).contains("no triangles"),
        "{}",
        notice(&editor)
    );
}

#[test]
fn a_link_without_the_file_keeps_the_box_says_which_file_and_attaches_it_once_loaded() {
    let mut made = Clocked::new();
    import_prop(&mut made, "chair.glb", box_glb());
    let url = made.model.share_link().url;
    // A document without its files (written before they were kept, or by hand).
    let mut document = made.model.scene().to_json_value();
    document.as_object_mut().unwrap().remove("files");
    let document = document.to_string();
    assert!(document.contains(r#""file":"chair.glb""#), "{document}");
    for (how, command) in [
        ("link", FileCommand::OpenLink(url)),
        (
            "document",
            FileCommand::OpenFile {
                name: "scene.json".into(),
                bytes: document.into_bytes(),
            },
        ),
    ] {
        let mut editor = Clocked::new();
        editor.apply(Command::File(command));
        let props: Vec<Prop> = editor.model.props().to_vec();
        assert_eq!(props.len(), 1, "{how}: {}", notice(&editor));
        assert_eq!(props[0].shape.file(), Some("chair.glb"), "{how}");
        assert!(
            near(props[0].shape.extents(), [0.4, 0.8, 0.6], 1e-4),
            "{how}"
        );
        assert!(editor.model.prop_mesh(&props[0]).is_none(), "{how}");
        assert_eq!(editor.model.missing_prop_files(), ["chair.glb"], "{how}");
        let text = notice(&editor);
        assert!(
            text.contains("Load chair.glb to show this prop (chair)"),
            "{how}: {text}"
        );
        // Loaded now: that prop is drawn with it, no new prop.
        import_prop(&mut editor, "chair.glb", box_glb());
        assert_eq!(editor.model.props(), &props[..], "{how}");
        assert!(editor.model.prop_mesh(&props[0]).is_some(), "{how}");
        assert!(editor.model.missing_prop_files().is_empty(), "{how}");
    }
}

#[test]
fn the_scene_glb_holds_a_mesh_prop_at_its_placement_with_its_own_triangles() {
    // Catches: a mesh prop exported as its box (24 corners of the unit box instead of the
    // file's 8), its size or placement dropped, its node not named as in the outliner.
    use stance_model::MemoryHost;
    use stance_model::model::AvatarCommand;
    let host = MemoryHost::default();
    let storage = host.inner.clone();
    let mut editor = Clocked::with_host(host);
    import_prop(&mut editor, "chair.glb", box_glb());
    let mut chair = editor.model.props()[0].clone();
    chair.position = [0.5, 0.8, 1.0];
    chair.rotation = glam::DQuat::from_rotation_y(0.5).to_array();
    chair.shape = chair.shape.with_dimensions(&[0.8, 1.6, 0.6]).unwrap();
    editor.apply(Command::Scene(SceneCommand::EditProp(0, chair.clone())));
    editor.apply(Command::Avatar(AvatarCommand::ExportPosedAvatar));
    let (name, bytes) = storage.borrow().binary_downloads.last().cloned().unwrap();
    assert_eq!(name, "stance-scene.glb");
    let glb = gltf::Gltf::from_slice(&bytes).expect("a GLB the gltf crate reads");
    let roots: Vec<gltf::Node<'_>> = glb.document.scenes().next().unwrap().nodes().collect();
    let names: Vec<&str> = roots.iter().map(|n| n.name().unwrap()).collect();
    assert_eq!(names, ["Character 1", "chair"]);
    let (translation, rotation, scale) = roots[1].transform().decomposed();
    assert!(
        near(translation.map(f64::from), chair.position, 1e-6),
        "{translation:?}"
    );
    let turn = glam::Quat::from_array(rotation).as_dquat();
    assert!(turn.angle_between(glam::DQuat::from_array(chair.rotation)) < 1e-6);
    assert!(near(scale.map(f64::from), [1.0; 3], 1e-6));
    let primitive = roots[1].mesh().unwrap().primitives().next().unwrap();
    let positions = primitive.get(&gltf::Semantic::Positions).unwrap();
    assert_eq!(positions.count(), 8);
    // Its box 0.8 x 1.6 x 0.6, centred on the node.
    let bounds = primitive.bounding_box();
    for axis in 0..3 {
        let half = [0.4, 0.8, 0.3][axis];
        assert!(
            (f64::from(bounds.min[axis]) + half).abs() < 1e-6,
            "{bounds:?}"
        );
        assert!(
            (f64::from(bounds.max[axis]) - half).abs() < 1e-6,
            "{bounds:?}"
        );
    }
    // Its own colour.
    let color = primitive
        .material()
        .pbr_metallic_roughness()
        .base_color_factor();
    assert!((color[1] - 0.5).abs() < 1e-6, "{color:?}");
}
