//! One meaning for posture values: the same document posed on the generated mannequin and on
//! avatars whose rests differ (T-pose with the bones carrying the turn, A-pose with legs
//! apart, bones carrying roll, a Mixamo-named Z-up rig in centimetres, VRM 0.x and 1.0, the
//! vendored real avatar) gives the same world directions of the upper arms, forearms, thighs
//! and shins. The directions are read back from the exported GLB by the `gltf` crate with this
//! file's own matrix product, not by the importer; each file's frame is turned into the H-Anim
//! frame by the rotation this file built it with.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

#[cfg(target_arch = "wasm32")]
use wasm_bindgen_test::wasm_bindgen_test as test;

use std::collections::HashMap;

use glam::{DMat4, DQuat, DVec3, Mat4};
use serde_json::{Value, json};
use stance_asset::{LoadOptions, export_glb, load_avatar};
use stance_document::Document;
use stance_hanim::{LevelOfArticulation, SkeletonOptions};

use crate::common;

/// The bones measured: (from, to) H-Anim joints.
const BONES: [(&str, &str); 8] = [
    ("l_shoulder", "l_elbow"),
    ("l_elbow", "l_radiocarpal"),
    ("r_shoulder", "r_elbow"),
    ("r_elbow", "r_radiocarpal"),
    ("l_hip", "l_knee"),
    ("l_knee", "l_talocrural"),
    ("r_hip", "r_knee"),
    ("r_knee", "r_talocrural"),
];

/// A document as a user makes it: a turned and bent body, a right-arm reach, the left arm
/// lifted, the head turned.
const DOCUMENT: &str = r#"{
  "version": 1,
  "posture": {
    "humanoid_root": {"tx": 0.05, "ty": -0.1, "tz": 0, "rx": 0.1, "ry": 0.4, "rz": 0},
    "vl5": {"rx": 0.25, "rz": 0.1},
    "l_hip": {"rx": -0.7, "ry": 0.1, "rz": 0.15},
    "l_knee": {"rx": 1.1},
    "r_hip": {"rx": 0.3, "rz": -0.1},
    "r_knee": {"rx": 0.4},
    "r_shoulder": {"rx": -1.3, "ry": 0.2, "rz": -0.4},
    "r_elbow": {"rx": -0.9},
    "l_shoulder": {"rx": -0.3, "rz": 0.8},
    "l_elbow": {"rx": -0.5},
    "skullbase": {"ry": 0.3}
  }
}"#;

/// The default GLB as JSON and BIN, its node indices by name, without the rest Stance wrote
/// (so that each node's transform is its rest).
fn base() -> (Value, Vec<u8>, HashMap<String, usize>) {
    let (mut j, bin) = common::split(&common::default_glb());
    let mut index = HashMap::new();
    for (i, node) in j["nodes"].as_array_mut().unwrap().iter_mut().enumerate() {
        if let Some(object) = node.as_object_mut() {
            object.remove("extras");
        }
        index.insert(node["name"].as_str().unwrap().to_owned(), i);
    }
    (j, bin, index)
}

fn quat(q: DQuat) -> Value {
    json!([q.x, q.y, q.z, q.w])
}

fn rotation_of(node: &Value) -> DQuat {
    node.get("rotation").map_or(DQuat::IDENTITY, |r| {
        DQuat::from_xyzw(
            r[0].as_f64().unwrap(),
            r[1].as_f64().unwrap(),
            r[2].as_f64().unwrap(),
            r[3].as_f64().unwrap(),
        )
    })
}

/// Turns node `n`'s own rotation by `q` (in its parent's frame): the bone and everything
/// below turn, and the node carries the turn.
fn carry_turn(j: &mut Value, n: usize, q: DQuat) {
    let now = rotation_of(&j["nodes"][n]);
    j["nodes"][n]["rotation"] = quat((q * now).normalize());
}

/// Turns everything below node `n` about it by `q` without rotating any node: each
/// descendant's translation turns (the default file's nodes have no rotation).
fn turn_below(j: &mut Value, n: usize, q: DQuat) {
    let children: Vec<usize> = j["nodes"][n]["children"]
        .as_array()
        .map(|c| c.iter().map(|v| v.as_u64().unwrap() as usize).collect())
        .unwrap_or_default();
    for c in children {
        let t = &j["nodes"][c]["translation"];
        let t = DVec3::new(
            t[0].as_f64().unwrap(),
            t[1].as_f64().unwrap(),
            t[2].as_f64().unwrap(),
        );
        let t = q * t;
        j["nodes"][c]["translation"] = json!([t.x, t.y, t.z]);
        turn_below(j, c, q);
    }
}

/// One test body: its GLB, the H-Anim joint -> node index of the measured joints, and the
/// rotation from its file's world frame to the H-Anim frame.
struct Body {
    name: &'static str,
    glb: Vec<u8>,
    nodes: HashMap<&'static str, usize>,
    hanim_from_file: DQuat,
}

fn measured_nodes(index: &HashMap<String, usize>) -> HashMap<&'static str, usize> {
    BONES
        .iter()
        .flat_map(|(a, b)| [*a, *b])
        .map(|name| (name, index[name]))
        .collect()
}

fn plain(name: &'static str, edit: impl Fn(&mut Value, &HashMap<String, usize>)) -> Body {
    let (mut j, bin, index) = base();
    edit(&mut j, &index);
    Body {
        name,
        glb: common::join(&j, &bin),
        nodes: measured_nodes(&index),
        hanim_from_file: DQuat::IDENTITY,
    }
}

fn degrees_z(d: f64) -> DQuat {
    DQuat::from_rotation_z(d.to_radians())
}

/// Arms horizontal, the shoulder nodes carrying the quarter turn.
fn t_pose(j: &mut Value, index: &HashMap<String, usize>) {
    carry_turn(j, index["l_shoulder"], degrees_z(90.0));
    carry_turn(j, index["r_shoulder"], degrees_z(-90.0));
}

/// Arms 45 degrees below horizontal and legs 8 degrees apart, no node rotated.
fn a_pose(j: &mut Value, index: &HashMap<String, usize>) {
    turn_below(j, index["l_shoulder"], degrees_z(45.0));
    turn_below(j, index["r_shoulder"], degrees_z(-45.0));
    turn_below(j, index["l_hip"], degrees_z(8.0));
    turn_below(j, index["r_hip"], degrees_z(-8.0));
}

/// A T-pose whose bones carry roll about themselves: the shoulders rolled 40 degrees about
/// the horizontal arm, the elbows 35 degrees about the forearm, the thighs and shins turned
/// about their own (vertical) axes.
fn rolled(j: &mut Value, index: &HashMap<String, usize>) {
    let roll = |d: f64| DQuat::from_rotation_x(d.to_radians());
    carry_turn(j, index["l_shoulder"], roll(40.0) * degrees_z(90.0));
    carry_turn(j, index["r_shoulder"], roll(-40.0) * degrees_z(-90.0));
    for (joint, angle) in [
        ("l_elbow", 35.0),
        ("r_elbow", -35.0),
        ("l_hip", 25.0),
        ("r_hip", -25.0),
        ("l_knee", -30.0),
        ("r_knee", 30.0),
    ] {
        carry_turn(
            j,
            index[joint],
            DQuat::from_rotation_y(f64::to_radians(angle)),
        );
    }
}

/// Mixamo's names for the joints it has.
const MIXAMO: [(&str, &str); 17] = [
    ("humanoid_root", "mixamorig:Hips"),
    ("vl5", "mixamorig:Spine"),
    ("skullbase", "mixamorig:Head"),
    ("l_sternoclavicular", "mixamorig:LeftShoulder"),
    ("l_shoulder", "mixamorig:LeftArm"),
    ("l_elbow", "mixamorig:LeftForeArm"),
    ("l_radiocarpal", "mixamorig:LeftHand"),
    ("r_sternoclavicular", "mixamorig:RightShoulder"),
    ("r_shoulder", "mixamorig:RightArm"),
    ("r_elbow", "mixamorig:RightForeArm"),
    ("r_radiocarpal", "mixamorig:RightHand"),
    ("l_hip", "mixamorig:LeftUpLeg"),
    ("l_knee", "mixamorig:LeftLeg"),
    ("l_talocrural", "mixamorig:LeftFoot"),
    ("r_hip", "mixamorig:RightUpLeg"),
    ("r_knee", "mixamorig:RightLeg"),
    ("r_talocrural", "mixamorig:RightFoot"),
];

fn bodies() -> Vec<Body> {
    let mut out = vec![
        plain("mannequin", |_, _| {}),
        plain("T-pose", t_pose),
        plain("A-pose", a_pose),
        plain("rolled bones", rolled),
    ];
    // Mixamo names, T-pose, Z up in centimetres facing -X (common's armature).
    let (mut j, bin, index) = base();
    t_pose(&mut j, &index);
    for (hanim, mixamo) in MIXAMO {
        j["nodes"][index[hanim]]["name"] = json!(mixamo);
    }
    let glb = common::z_up_centimetres_facing_minus_x(&common::join(&j, &bin));
    let armature = DQuat::from_rotation_z(-std::f64::consts::FRAC_PI_2)
        * DQuat::from_rotation_x(std::f64::consts::FRAC_PI_2);
    out.push(Body {
        name: "Mixamo rig (Z up, cm)",
        glb,
        nodes: measured_nodes(&index),
        hanim_from_file: armature.inverse(),
    });
    // VRM 0.x in a T-pose (facing -Z: its root turned half about y), VRM 1.0 in an A-pose.
    for (version, name, edit) in [
        (
            0u8,
            "VRM 0.x T-pose",
            t_pose as fn(&mut Value, &HashMap<String, usize>),
        ),
        (1, "VRM 1.0 A-pose", a_pose),
    ] {
        let (mut j, bin, index) = base();
        edit(&mut j, &index);
        let glb = common::vrm_from(&common::join(&j, &bin), version);
        out.push(Body {
            name,
            glb,
            nodes: measured_nodes(&index),
            hanim_from_file: if version == 0 {
                DQuat::from_rotation_y(std::f64::consts::PI).inverse()
            } else {
                DQuat::IDENTITY
            },
        });
    }
    // The vendored real avatar (tests/fixtures/avatars, MIT): Mixamo names without the
    // prefix, Y up and facing +Z as glTF has it, its own rest; its nodes found by name here.
    let glb = include_bytes!("../../../tests/fixtures/avatars/Black_F_2_Casual.glb").to_vec();
    let json = common::split(&glb).0;
    let index = |name: &str| {
        json["nodes"]
            .as_array()
            .unwrap()
            .iter()
            .position(|n| n["name"] == name)
            .unwrap()
    };
    let names = [
        ("l_shoulder", "LeftArm"),
        ("l_elbow", "LeftForeArm"),
        ("l_radiocarpal", "LeftHand"),
        ("r_shoulder", "RightArm"),
        ("r_elbow", "RightForeArm"),
        ("r_radiocarpal", "RightHand"),
        ("l_hip", "LeftUpLeg"),
        ("l_knee", "LeftLeg"),
        ("l_talocrural", "LeftFoot"),
        ("r_hip", "RightUpLeg"),
        ("r_knee", "RightLeg"),
        ("r_talocrural", "RightFoot"),
    ];
    out.push(Body {
        name: "vendored avatar",
        nodes: names.iter().map(|(h, n)| (*h, index(n))).collect(),
        glb,
        hanim_from_file: DQuat::IDENTITY,
    });
    out
}

/// World transforms of every node of a GLB, by the `gltf` crate's reading of the node
/// transforms and this file's own products down the scene's hierarchy.
fn node_worlds(glb: &[u8]) -> Vec<DMat4> {
    // (The vendored file requires extensions the `gltf` crate does not know; node
    // transforms need none.)
    let gltf = gltf::Gltf::from_slice_without_validation(glb).unwrap();
    let document = &gltf.document;
    let mut world = vec![DMat4::IDENTITY; document.nodes().count()];
    fn walk(node: gltf::Node, parent: DMat4, world: &mut [DMat4]) {
        let local = Mat4::from_cols_array_2d(&node.transform().matrix()).as_dmat4();
        let w = parent * local;
        world[node.index()] = w;
        for child in node.children() {
            walk(child, w, world);
        }
    }
    let scene = document.scenes().next().unwrap();
    for root in scene.nodes() {
        walk(root, DMat4::IDENTITY, &mut world);
    }
    world
}

/// The bones' world directions (H-Anim frame) in `glb`, an export of `body`.
fn directions(body: &Body, glb: &[u8]) -> Vec<DVec3> {
    let world = node_worlds(glb);
    let at = |name: &str| world[body.nodes[name]].w_axis.truncate();
    BONES
        .iter()
        .map(|(a, b)| (body.hanim_from_file * (at(b) - at(a))).normalize())
        .collect()
}

/// `document` posed on `body` at LOA 2 and exported.
fn posed(body: &Body, document: &Document) -> Vec<u8> {
    let mut avatar = load_avatar(
        &body.glb,
        &LoadOptions {
            decode_textures: false,
            ..Default::default()
        },
    )
    .unwrap_or_else(|e| panic!("{}: {e}", body.name));
    let skeleton = avatar
        .skeleton(&SkeletonOptions {
            loa: LevelOfArticulation::Loa2,
            ..Default::default()
        })
        .unwrap();
    let posture = document.posture.to_posture(&skeleton.skeleton).unwrap();
    avatar.apply_posture(&skeleton, &posture).unwrap();
    export_glb(&avatar).unwrap()
}

/// The largest angle (degrees) between the bones of `glb` and the mannequin's.
fn worst(body: &Body, glb: &[u8], mannequin: &[DVec3]) -> (f64, &'static str) {
    directions(body, glb)
        .iter()
        .zip(mannequin)
        .zip(BONES)
        .map(|((a, b), (_, to))| (a.angle_between(*b).to_degrees(), to))
        .fold((0.0, ""), |w, x| if x.0 > w.0 { x } else { w })
}

#[test]
fn a_document_poses_every_rest_alike() {
    let document = Document::from_json(DOCUMENT).unwrap();
    let bodies = bodies();
    let mannequin = directions(&bodies[0], &posed(&bodies[0], &document));
    // The posture moved the bones: the reach is far from the rest.
    let rest = directions(&bodies[0], &bodies[0].glb);
    assert!(rest[2].angle_between(mannequin[2]).to_degrees() > 45.0);
    for body in &bodies[1..] {
        // The rests differ from the mannequin's (the test bodies are what they say).
        let (at_rest, _) = worst(body, &body.glb, &rest);
        let (angle, bone) = worst(body, &posed(body, &document), &mannequin);
        eprintln!(
            "{}: rest {at_rest:.1} deg from the mannequin's; posed, worst bone {bone} at {angle:.3} deg",
            body.name
        );
        assert!(at_rest > 7.0, "{}: {at_rest}", body.name);
        assert!(angle < 2.0, "{}: {bone} is {angle} degrees off", body.name);
    }
}

/// A posture link made on one avatar (the document's values as they are after the link's
/// quantisation) opens on another in the same pose, and on the mannequin.
#[test]
fn a_posture_link_from_one_avatar_opens_on_another_in_the_same_pose() {
    let bodies = bodies();
    let t_pose = &bodies[1];
    let a_pose = &bodies[2];
    let mut document = Document::from_json(DOCUMENT).unwrap();
    document.avatar = stance_document::AvatarReference::Url("https://example.org/t.glb".into());
    // Made on the T-pose avatar: its posture read back from the posed avatar.
    let avatar = load_avatar(&posed(t_pose, &document), &LoadOptions::default()).unwrap();
    let skeleton = avatar.skeleton(&SkeletonOptions::default()).unwrap();
    let made = avatar.current_posture(&skeleton).unwrap();
    document.posture = stance_document::PostureValues::from_posture(&skeleton.skeleton, &made);
    let link = stance_document::link::encode(&document);
    let opened = stance_document::link::decode(&link).unwrap();
    let on_a = directions(a_pose, &posed(a_pose, &opened));
    let on_t = directions(t_pose, &posed(t_pose, &opened));
    let mannequin = directions(&bodies[0], &posed(&bodies[0], &opened));
    for (k, (a, t)) in on_a.iter().zip(&on_t).enumerate() {
        let angle = a.angle_between(*t).to_degrees();
        assert!(angle < 2.0, "{}: {angle} degrees", BONES[k].1);
        assert!(a.angle_between(mannequin[k]).to_degrees() < 2.0);
    }
}
