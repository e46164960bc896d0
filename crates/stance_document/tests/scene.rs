//! Scene documents: several characters, each a document with a name and a placement; a plain
//! document reads as a scene of one and a scene of one at the origin is written as a plain
//! document (older versions read it); errors name the field.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use glam::DVec3;
use stance_document::{Document, Placement, Prop, PropShape, Scene, SceneCharacter};
#[cfg(target_arch = "wasm32")]
use wasm_bindgen_test::wasm_bindgen_test as test;

fn two_characters() -> Scene {
    let mut first = Document::default();
    first.posture.set("l_elbow", stance_ik::Dof::Rx, -0.5);
    Scene {
        characters: vec![
            SceneCharacter {
                name: "Ann".into(),
                placement: Placement::default(),
                document: first,
            },
            SceneCharacter {
                name: "Bo".into(),
                placement: Placement {
                    position: [0.8, 0.0, -0.2],
                    yaw_degrees: 90.0,
                },
                document: Document::default(),
            },
        ],
        props: vec![
            Prop::new(
                "Ball".into(),
                PropShape::Sphere { radius: 0.11 },
                [0.3, 0.9, 0.4],
            ),
            Prop {
                rotation: [0.0, (0.25f64).sin(), 0.0, (0.25f64).cos()],
                ..Prop::new(
                    "Bar".into(),
                    PropShape::Cylinder {
                        radius: 0.02,
                        height: 2.0,
                    },
                    [-0.5, 1.0, 0.3],
                )
            },
            Prop::new(
                "Step".into(),
                PropShape::Box {
                    size: [0.6, 0.2, 0.4],
                },
                [0.0, 0.1, 0.6],
            ),
            Prop::new(
                "Table".into(),
                PropShape::Plane { size: [1.2, 0.8] },
                [1.0, 0.75, 0.6],
            ),
        ],
        selected: 1,
        between: Vec::new(),
        files: Vec::new(),
    }
}

#[test]
fn a_scene_round_trips_through_its_json() {
    let scene = two_characters();
    let text = scene.to_json(true);
    assert!(text.contains("\"characters\""), "{text}");
    assert_eq!(Scene::from_json(&text).expect("reads back"), scene);
}

#[test]
fn a_plain_document_is_a_scene_of_one_and_is_written_back_plain() {
    let text = r#"{"version": 1, "posture": {"l_elbow": {"rx": -0.5}}}"#;
    let scene = Scene::from_json(text).expect("an old document opens");
    assert_eq!(scene.characters.len(), 1);
    assert!(scene.is_plain_document());
    let written = scene.to_json(false);
    assert!(!written.contains("characters"), "{written}");
    assert_eq!(
        Document::from_json(&written).expect("older readers read it"),
        scene.characters[0].document
    );
    // Named, or moved off the origin, one character is a scene (nothing lost).
    let mut named = scene.clone();
    named.characters[0].name = "Ann".into();
    assert_eq!(
        Scene::from_json(&named.to_json(false)).expect("reads"),
        named
    );
    let mut moved = scene;
    moved.characters[0].placement = Placement::at([1.0, 0.0, 0.0]);
    assert!(moved.to_json(false).contains("characters"));
}

#[test]
fn the_placement_turns_then_translates() {
    let placement = Placement {
        position: [1.0, 0.0, 2.0],
        yaw_degrees: 90.0,
    };
    // The character's +Z (its front) faces the scene's +X after a quarter turn about +Y.
    let front = placement.scene_from_character().transform_point3(DVec3::Z);
    assert!(
        (front - DVec3::new(2.0, 0.0, 2.0)).length() < 1e-12,
        "{front}"
    );
}

#[test]
fn errors_name_the_field_and_nothing_is_half_read() {
    let cases = [
        (r#"{"characters": []}"#, "characters"),
        (r#"{"characters": {}}"#, "characters"),
        (r#"{"characters": [{}], "selected": 3}"#, "selected"),
        (r#"{"characters": [{}], "selected": -1}"#, "selected"),
        (
            r#"{"characters": [{"placement": {"position": [0, 0]}}]}"#,
            "characters[0].placement.position",
        ),
        (
            r#"{"characters": [{}, {"posture": {"l_elbow": {"rx": "bent"}}}]}"#,
            "characters[1]",
        ),
        (r#"{"characters": [{"name": 3}]}"#, "characters[0].name"),
        (
            r#"{"characters": [{}], "props": [{"shape": "cone"}]}"#,
            "props[0].shape",
        ),
        (
            r#"{"characters": [{}], "props": [{"shape": "sphere", "radius": -1}]}"#,
            "props[0].sphere",
        ),
        (
            r#"{"characters": [{}], "props": [{"shape": "box", "size": [1, 1]}]}"#,
            "props[0].size",
        ),
        (
            r#"{"characters": [{}], "props": [{"shape": "plane", "size": [1, 1], "rotation": [0, 0, 0, 2]}]}"#,
            "props[0].rotation",
        ),
    ];
    for (text, field) in cases {
        let error = Scene::from_json(text).expect_err(text).to_string();
        assert!(error.contains(field), "{text}: {error}");
    }
    let many = format!(r#"{{"characters": [{}]}}"#, vec!["{}"; 40].join(","));
    assert!(Scene::from_json(&many).is_err());
}

#[test]
fn names_are_cleaned_and_defaulted() {
    let scene = Scene::from_json(r#"{"characters": [{"name": "  \u0007 "}, {"name": " Bo\n"}]}"#)
        .expect("reads");
    assert_eq!(scene.characters[0].name, "Character 1");
    assert_eq!(scene.characters[1].name, "Bo");
}

#[test]
fn a_scene_link_carries_every_character_within_the_link_steps() {
    use stance_document::link;
    let scene = two_characters();
    let fragment = link::encode_scene(&scene);
    let back = link::decode_scene(&fragment).expect("opens");
    assert_eq!(back.selected, 1);
    assert_eq!(back.characters.len(), 2);
    for (a, b) in back.characters.iter().zip(&scene.characters) {
        assert_eq!(a.name, b.name);
        for (x, y) in a.placement.position.iter().zip(b.placement.position) {
            assert!((x - y).abs() <= link::POSITION_STEP_M / 2.0, "{x} {y}");
        }
        assert!((a.placement.yaw_degrees - b.placement.yaw_degrees).abs() < 0.003);
    }
    assert_eq!(back.props.len(), scene.props.len());
    for (a, b) in back.props.iter().zip(&scene.props) {
        assert_eq!((&a.name, a.shape.name()), (&b.name, b.shape.name()));
        for (x, y) in a.shape.dimensions().iter().zip(b.shape.dimensions()) {
            assert!((x - y).abs() <= link::POSITION_STEP_M / 2.0);
        }
        for (x, y) in a.rotation.iter().zip(b.rotation) {
            assert!((x - y).abs() < 1e-4, "{:?} {:?}", a.rotation, b.rotation);
        }
    }
    for (a, b) in back.characters.iter().zip(&scene.characters) {
        // Each document as its own link carries it.
        assert_eq!(
            a.document,
            link::decode(&link::encode(&b.document)).expect("the document's link")
        );
    }
    // Written again, the same link.
    assert_eq!(link::encode_scene(&back), fragment);
    // A reader of documents says what it holds.
    let error = link::decode(&fragment)
        .expect_err("not one posture")
        .to_string();
    assert!(error.contains("scene of 2 characters"), "{error}");
}

#[test]
fn a_plain_scene_is_a_document_link_and_document_links_open_as_scenes() {
    use stance_document::link;
    let document = two_characters().characters[0].document.clone();
    let fragment = link::encode(&document);
    assert_eq!(
        link::encode_scene(&Scene::of_one(document.clone())),
        fragment
    );
    let scene = link::decode_scene(&fragment).expect("a document link opens as a scene");
    let read = link::decode(&fragment).expect("the document's link");
    assert_eq!(scene, Scene::of_one(read));
}

#[test]
fn a_cut_or_damaged_scene_link_is_refused_with_a_reason() {
    use base64::Engine as _;
    use base64::engine::general_purpose::URL_SAFE_NO_PAD;
    use stance_document::link;
    let fragment = link::encode_scene(&two_characters());
    let cut = &fragment[..fragment.len() / 2];
    assert!(link::decode_scene(cut).is_err());
    // A valid frame whose payload says 40 characters.
    let mut frame = vec![link::SCENE_FORMAT, 2, 40, 0];
    let crc = crc32fast::hash(&frame);
    frame.extend_from_slice(&crc.to_le_bytes());
    let error = link::decode_scene(&URL_SAFE_NO_PAD.encode(frame))
        .expect_err("too many")
        .to_string();
    assert!(error.contains("40 characters"), "{error}");
}

/// A scene of one character and a chair from `chair.glb`, scaled and turned.
fn with_a_chair() -> Scene {
    let mut scene = two_characters();
    scene.props.push(Prop {
        rotation: [0.0, (0.3f64).sin(), 0.0, (0.3f64).cos()],
        ..Prop::new(
            "Chair".into(),
            PropShape::Mesh {
                file: "chair.glb".into(),
                size: [0.45, 0.9, 0.5],
            },
            [0.2, 0.45, 0.7],
        )
    });
    scene
}

#[test]
fn a_mesh_prop_is_named_by_its_file_and_keeps_its_box_in_the_json() {
    let scene = with_a_chair();
    let value = scene.to_json_value();
    let chair = &value["props"][4];
    assert_eq!(chair["shape"], "mesh");
    assert_eq!(chair["file"], "chair.glb");
    assert_eq!(chair["size"], serde_json::json!([0.45, 0.9, 0.5]));
    assert_eq!(
        Scene::from_json(&scene.to_json(false)).expect("reads"),
        scene
    );
    // As an obstacle it is its box, turned with it: a point 1 cm out from the middle of its
    // +X face (x = 0.45 / 2 in the prop's frame) is 1 cm away.
    let prop = &scene.props[4];
    let obstacle = prop.obstacle(glam::DAffine3::IDENTITY);
    let out = prop
        .scene_from_prop()
        .transform_point3(DVec3::new(0.225 + 0.01, 0.0, 0.0));
    let (distance, _) = obstacle.signed_distance(out);
    assert!((distance - 0.01).abs() < 1e-9, "{distance}");
}

#[test]
fn mesh_prop_errors_name_the_field() {
    let cases = [
        (
            r#"{"characters": [{}], "props": [{"shape": "mesh", "size": [1, 1, 1]}]}"#,
            "props[0].file",
        ),
        (
            r#"{"characters": [{}], "props": [{"shape": "mesh", "file": "../chair.glb", "size": [1, 1, 1]}]}"#,
            "props[0].file",
        ),
        (
            r#"{"characters": [{}], "props": [{"shape": "mesh", "file": " ", "size": [1, 1, 1]}]}"#,
            "props[0].file",
        ),
        (
            r#"{"characters": [{}], "props": [{"shape": "mesh", "file": "a.glb", "size": [1, 1]}]}"#,
            "props[0].size",
        ),
        (
            r#"{"characters": [{}], "props": [{"shape": "mesh", "file": "a.glb", "size": [1, 0, 1]}]}"#,
            "props[0].mesh",
        ),
    ];
    for (text, field) in cases {
        let error = Scene::from_json(text).expect_err(text).to_string();
        assert!(error.contains(field), "{text}: {error}");
    }
}

#[test]
fn a_mesh_prop_takes_link_format_11_and_others_keep_the_older_formats() {
    use base64::Engine as _;
    use base64::engine::general_purpose::URL_SAFE_NO_PAD;
    use stance_document::link;
    let first_byte = |fragment: &str| URL_SAFE_NO_PAD.decode(fragment).unwrap()[0];
    // Without a mesh, the format older readers read.
    assert_eq!(
        first_byte(&link::encode_scene(&two_characters())),
        link::SCENE_FORMAT
    );
    let scene = with_a_chair();
    let fragment = link::encode_scene(&scene);
    assert_eq!(first_byte(&fragment), link::MESH_FORMAT);
    assert_eq!(link::MESH_FORMAT, 11);
    let back = link::decode_scene(&fragment).expect("opens");
    let chair = &back.props[4];
    assert_eq!(chair.shape.file(), Some("chair.glb"));
    for (x, y) in chair.shape.dimensions().iter().zip([0.45, 0.9, 0.5]) {
        assert!((x - y).abs() <= link::POSITION_STEP_M / 2.0, "{x} {y}");
    }
    assert_eq!(link::encode_scene(&back), fragment);
    // The same payload framed as format 10 is refused: shape 4 is no shape there.
    let mut frame = URL_SAFE_NO_PAD.decode(&fragment).unwrap();
    frame[0] = link::BETWEEN_FORMAT;
    let n = frame.len() - 4;
    let crc = crc32fast::hash(&frame[..n]);
    frame[n..].copy_from_slice(&crc.to_le_bytes());
    let error = link::decode_scene(&URL_SAFE_NO_PAD.encode(&frame))
        .expect_err("no meshes before format 11")
        .to_string();
    assert!(error.contains("prop 4's shape is unknown"), "{error}");
}
