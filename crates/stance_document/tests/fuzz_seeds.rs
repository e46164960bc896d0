//! The seed corpora of the `link`, `document` and `problem` fuzz targets (`fuzz/seeds/<target>/`):
//! small valid links (as text and as framed payloads, every link format), documents and
//! problem files. `the_fuzz_seeds_are_valid` checks the committed seeds; `write_fuzz_seeds`
//! (ignored) writes them again: `cargo test -p stance_document --test all fuzz_seeds:: -- --ignored`.

#![cfg(not(target_arch = "wasm32"))]
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use std::path::{Path, PathBuf};

use base64::Engine as _;
use base64::engine::general_purpose::URL_SAFE_NO_PAD;
use stance_document::{ClipReference, Document, Problem, Scene, TaskKindSpec, TaskSpec, link};
use stance_hanim::{LevelOfArticulation, SkeletonOptions, default_skeleton};
use stance_ik::Skeleton;

fn seed_dir(target: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("fuzz/seeds")
        .join(target)
}

/// A scene of two characters, one named and moved.
const SCENE: &str = r#"{"characters": [
  {"name": "Ann", "posture": {"l_elbow": {"rx": -0.5}}, "tasks": [{"level": 1, "kind": "position", "joint": "l_talocrural", "target": [0.1, 0.07, 0.0]}]},
  {"name": "Bo", "placement": {"position": [0.8, 0, -0.2], "yaw": 90}}
], "selected": 1}"#;

/// [`SCENE`] with a task between its characters and one attached to a prop (format 10).
const SCENE_BETWEEN: &str = r#"{"characters": [
  {"name": "Ann", "tasks": [{"level": 1, "kind": "position", "joint": "l_talocrural", "target": [0.1, 0.07, 0.0]},
    {"level": 2, "kind": "line", "joint": "r_radiocarpal", "origin": [-0.4, 1, 0.3], "direction": [0, 1, 0], "on": "Bar"}]},
  {"name": "Bo", "placement": {"position": [0.8, 0, -0.2], "yaw": 90}}
], "props": [{"name": "Bar", "shape": "cylinder", "radius": 0.02, "height": 2.0, "position": [-0.4, 1, 0.3]}],
"between": [{"kind": "meet", "a": {"character": 0, "joint": "r_radiocarpal"},
  "b": {"character": 1, "joint": "l_radiocarpal", "point": [0, -0.05, 0]}, "axes": "xz", "level": 3}],
"selected": 0}"#;

/// [`SCENE_BETWEEN`] with a chair from a glTF file beside the bar (format 11).
const SCENE_MESH: &str = r#"{"characters": [
  {"name": "Ann", "tasks": [{"level": 2, "kind": "line", "joint": "r_radiocarpal", "origin": [-0.4, 1, 0.3], "direction": [0, 1, 0], "on": "Bar"}]},
  {"name": "Bo", "placement": {"position": [0.8, 0, -0.2], "yaw": 90}}
], "props": [{"name": "Bar", "shape": "cylinder", "radius": 0.02, "height": 2.0, "position": [-0.4, 1, 0.3]},
  {"name": "Chair", "shape": "mesh", "file": "chair.glb", "size": [0.45, 0.9, 0.5], "position": [0.2, 0.45, 0.7],
   "rotation": [0, 0.2955202, 0, 0.9553365]}],
"selected": 0}"#;

/// [`SCENE_MESH`] carrying its chair's file (a few bytes standing in for a GLB: the reader
/// checks the file's size and hash, not its content).
fn scene_files() -> Vec<u8> {
    let mut scene = Scene::from_json(SCENE_MESH).unwrap();
    scene.files = vec![stance_document::FileReference::embed(
        "chair.glb",
        b"glTF: a stand-in for chair.glb, chair.glb, chair.glb",
    )];
    scene.to_json(false).into_bytes()
}

/// A document with every kind of task, a timeline, a camera and joint stiffness.
const EVERYTHING: &str = r#"{
  "version": 1,
  "avatar": {"url": "https://example.org/avatars/jin.vrm"},
  "posture": {
    "humanoid_root": {"tx": 0.1, "ty": -0.02, "tz": 0, "rx": 0, "ry": 0.5, "rz": 0},
    "l_knee": {"rx": 0.3},
    "l_shoulder": {"rx": -0.4, "ry": 0.1, "rz": 1.2},
    "mixamorig:LeftHand": {"rz": 0.2}
  },
  "tasks": [
    {"level": 1, "kind": "position", "joint": "l_talocrural", "point": [0, 0, 0.01], "axes": "xz",
     "target": [0.1, 0.07, 0.0], "weight": 1, "active": true,
     "interval": {"start": 0.5, "end": 1.5, "ease_in": 0.25, "ease_out": 0}},
    {"level": 1, "kind": "orientation", "joint": "skullbase", "target": [0, 0, 0.1, 1], "active": false},
    {"level": 1, "kind": "gaze", "joint": "skullbase", "axis": [0, 0, 1], "point": [0, 0.08, 0.1], "target": [0, 1.6, 2]},
    {"level": 2, "kind": "direction", "joint": "r_radiocarpal", "axis": [1, 0, 0], "target": [0, -1, 0]},
    {"level": 2, "kind": "com", "axes": "xz", "target": [0.02, 0, 0.03], "weight": 0.5},
    {"level": 2, "kind": "balance", "support": ["l_talocrural", "r_talocrural"], "margin": 0.03},
    {"level": 3, "kind": "limb", "limb": "r_arm", "target": [-0.3, 1.2, 0.3], "swivel": 0.5,
     "orientation": [0, 0, 0, 1]},
    {"level": 3, "kind": "limb", "joints": ["l_hip", "l_knee", "l_ankle"], "target": [0.1, 0.1, 0.1]},
    {"level": 4, "kind": "posture", "weight": 0.1, "joints": ["l_hip", "vl5"],
     "reference": {"l_hip": {"rx": -0.2}}},
    {"level": 5, "kind": "comfort", "effort": 1, "range": 0.1, "rula": 0.5},
    {"level": 2, "kind": "collision", "margin": 0.015, "floor": false}
  ],
  "motion": {
    "frame_time": 0.0333333, "frame_count": 40,
    "keys": [
      {"frame": 0, "posture": {"l_shoulder": {"rx": 0, "ry": 0, "rz": 0}}},
      {"frame": 30, "posture": {"l_shoulder": {"rx": 0, "ry": 0, "rz": 1.5708}, "humanoid_root": {"ty": -0.1}}}
    ]
  },
  "camera": {"target": [0, 1, 0], "yaw": 0.3, "pitch": -0.2, "distance": 3, "orthographic": false},
  "stiffness": {"vl5": {"rx": 0.6, "rz": 0.3}, "l_elbow": {"rx": 0}}
}"#;

/// A two-frame clip of one joint, embedded in the `clip` document seed.
const TINY_BVH: &str = "HIERARCHY\nROOT Hips\n{\n\tOFFSET 0 0 0\n\tCHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation\n\tEnd Site\n\t{\n\t\tOFFSET 0 10 0\n\t}\n}\nMOTION\nFrames: 2\nFrame Time: 0.033333\n0 90 0 0 0 0\n1 90 0 0 5 0\n";

/// `EVERYTHING` cut down to what link format `format` holds (8: with a collision task; 6: with
/// a clip; 4: no clip; 3: no stiffness; 2: no comfort task either; 1: no timeline nor interval
/// either).
fn document(format: u8) -> Document {
    let mut d = Document::from_json(EVERYTHING).unwrap();
    // Made on an avatar: before format 5 relative to its own rest, from 5 to the standard
    // pose (which older formats cannot say).
    if format >= 5 {
        d.rest = stance_document::PostureRest::Standard;
    }
    // From format 6 the clip the keys were made over (a link names it, never carries it).
    if format >= 6 {
        d.clip = Some(ClipReference::embed("tiny.bvh", TINY_BVH.as_bytes()));
    }
    // From format 7 a point-on-a-line and a point-on-a-plane task.
    if format >= 7 {
        d.tasks.extend(on_line_and_plane());
    }
    if format < 8 {
        d.tasks
            .retain(|t| !matches!(t.kind, TaskKindSpec::Collision { .. }));
    }
    if format < 4 {
        d.stiffness = Default::default();
    }
    if format < 3 {
        d.tasks
            .retain(|t| !matches!(t.kind, TaskKindSpec::Comfort { .. }));
    }
    if format < 2 {
        d.motion = None;
        for t in &mut d.tasks {
            t.interval = None;
        }
    }
    d
}

/// A wrist on a bar and a foot on or above a tilted plane.
fn on_line_and_plane() -> Vec<TaskSpec> {
    vec![
        TaskSpec::new(TaskKindSpec::Line {
            joint: "l_radiocarpal".into(),
            point: [0.0; 3],
            origin: [0.3, 1.2, 0.35],
            direction: [1.0, 0.0, 0.0],
        }),
        TaskSpec::new(TaskKindSpec::Plane {
            joint: "r_talocrural".into(),
            point: [0.0, -0.07, 0.02],
            origin: [0.0, 0.1, 0.0],
            normal: [0.0, 1.0, 0.3],
            above: true,
        }),
    ]
}

/// The skeleton of `s` in a problem file's form.
fn skeleton_json(s: &Skeleton) -> serde_json::Value {
    let joints: Vec<serde_json::Value> = s
        .joints()
        .iter()
        .map(|j| {
            let mut limits = serde_json::Map::new();
            for (k, d) in j.dofs.iter().enumerate() {
                let i = j.dof_start + k;
                let (lo, hi) = (s.lower_limits()[i], s.upper_limits()[i]);
                if lo.is_finite() && hi.is_finite() {
                    limits.insert(d.name().to_owned(), serde_json::json!([lo, hi]));
                }
            }
            let dofs: Vec<&str> = j.dofs.iter().map(|d| d.name()).collect();
            let mut joint = serde_json::json!({
                "name": j.name,
                "parent": j.parent.map(|p| s.joints()[p].name.clone()),
                "offset": [j.offset.x, j.offset.y, j.offset.z],
                "dofs": dofs,
                "limits": limits,
                "mass": j.mass,
                "com": [j.com.x, j.com.y, j.com.z],
            });
            // A capsule radius set by hand (the collision task's).
            if j.name.ends_with("_elbow") {
                joint["radius"] = serde_json::json!(0.05);
            }
            joint
        })
        .collect();
    serde_json::json!({ "joints": joints })
}

/// A five-joint arm with every settings field.
const ARM: &str = r#"{
  "skeleton": {"joints": [
    {"name": "base", "parent": null, "offset": [0, 1, 0], "dofs": ["tx", "ty", "tz", "rx", "ry", "rz"]},
    {"name": "l_shoulder", "parent": "base", "offset": [0.2, 0.3, 0], "dofs": ["rx", "ry", "rz"],
     "limits": {"rx": [-3, 1], "rz": [-1, 3]}, "mass": 2, "com": [0, -0.15, 0], "stiffness": {"ry": 0.3}},
    {"name": "l_elbow", "parent": "l_shoulder", "offset": [0, -0.3, 0], "dofs": ["rx"],
     "limits": {"rx": [-2.6, 0]}, "mass": 1.5, "com": [0, -0.12, 0]},
    {"name": "l_radiocarpal", "parent": "l_elbow", "offset": [0, -0.25, 0], "dofs": ["rx", "rz"], "mass": 0.5},
    {"name": "tip", "parent": "l_radiocarpal", "offset": [0, -0.08, 0]}
  ]},
  "tasks": [
    {"level": 1, "kind": "limb", "limb": "l_arm", "target": [0.3, 1.0, 0.3], "swivel": 0.4},
    {"level": 1, "kind": "position", "joint": "tip", "point": [0.01, 0, 0], "axes": "xyz", "target": [0.3, 0.95, 0.4]},
    {"level": 2, "kind": "orientation", "joint": "l_radiocarpal", "target": [0, 0, 0.38268, 0.92388]},
    {"level": 2, "kind": "gaze", "joint": "base", "axis": [0, 0, 1], "target": [0.5, 1.2, 1]},
    {"level": 3, "kind": "direction", "joint": "l_elbow", "axis": [1, 0, 0], "target": [0, -1, 0], "weight": 0.5},
    {"level": 3, "kind": "com", "axes": "y", "target": [0, 1.2, 0]},
    {"level": 4, "kind": "posture", "weight": 0.1, "reference": {"l_elbow": {"rx": -0.5}}}
  ],
  "settings": {"max_iterations": 50, "tolerance": 1e-6, "stall_window": 5, "stall_step": 1e-9,
    "stall_improvement": 0.01, "rank_tolerance": 1e-9, "max_linear_step": 0.1,
    "max_angular_step": 0.3, "max_dof_step": 0.3, "trust_region": 0.5, "priority_budget": 1.0, "time_budget_ms": 50,
    "adaptive_damping": {"lambda_max": 0.1, "epsilon": 0.05},
    "levels": {"3": {"lambda": 0.05}}, "enforce_limits": true, "restarts": false,
    "iteration": "guarded", "hybrid": true},
  "posture": {"l_elbow": {"rx": -0.3}, "base": {"ty": 0.01}}
}"#;

/// The default H-Anim body at LOA1 with a balance, a comfort task, foot limbs, the comfort
/// settings and a collision task (the forearms' capsules thicker).
fn loa1_problem() -> String {
    let body = default_skeleton(&SkeletonOptions {
        loa: LevelOfArticulation::Loa1,
        ..SkeletonOptions::default()
    })
    .unwrap();
    let problem = serde_json::json!({
        "skeleton": skeleton_json(&body.skeleton),
        "tasks": [
            {"level": 1, "kind": "limb", "limb": "l_leg", "target": [0.1, 0.08, 0.0], "orientation": [0, 0, 0, 1]},
            {"level": 1, "kind": "position", "joint": "r_talocrural", "target": [-0.1, 0.08, 0.0]},
            {"level": 2, "kind": "balance"},
            {"level": 3, "kind": "limb", "joints": ["r_shoulder", "r_elbow", "r_wrist"], "target": [-0.3, 1.2, 0.3]},
            {"level": 3, "kind": "line", "joint": "l_wrist", "origin": [0.3, 1.2, 0.35], "direction": [1, 0, 0]},
            {"level": 3, "kind": "plane", "joint": "l_knee", "origin": [0, 0.3, 0], "normal": [0, 0, -1], "above": true},
            {"level": 4, "kind": "comfort", "effort": 1, "range": 0.2, "rula": 0.5},
            {"level": 2, "kind": "collision", "self": true, "floor": true}
        ],
        "settings": {"max_iterations": 20, "iteration": "textbook", "lambda": 0.01},
        "posture": {"l_knee": {"rx": 0.3}},
        "comfort": {"variant": "worksheet", "load": "intermittent_2_10", "muscle_use": true,
            "arm_supported": false, "legs_supported": true, "seated_supported": false,
            "sex": "female", "mass": 60, "stature": 1.65}
    });
    serde_json::to_string(&problem).unwrap()
}

/// Every seed: (target, file name, bytes).
fn seeds() -> Vec<(&'static str, String, Vec<u8>)> {
    let mut out = Vec::new();
    for format in 1..=link::LINK_FORMAT {
        let text = if format == link::SCENE_FORMAT {
            link::encode_scene(&Scene::from_json(SCENE).unwrap())
        } else if format == link::BETWEEN_FORMAT {
            link::encode_scene(&Scene::from_json(SCENE_BETWEEN).unwrap())
        } else if format == link::MESH_FORMAT {
            link::encode_scene(&Scene::from_json(SCENE_MESH).unwrap())
        } else {
            link::encode(&document(format))
        };
        let frame = URL_SAFE_NO_PAD.decode(&text).unwrap();
        assert_eq!(frame[0], format);
        // The frame without its format byte, length and CRC: the fuzz target frames it again.
        let header = 1 + frame[1..].iter().position(|b| b & 0x80 == 0).unwrap() + 1;
        let mut framed = vec![1 | (format << 1)];
        framed.extend_from_slice(&frame[header..frame.len() - 4]);
        out.push(("link", format!("format{format}.payload"), framed));
        let mut text_seed = vec![0];
        if format == 1 {
            text_seed.extend_from_slice(format!("https://stance.example/#{text}").as_bytes());
        } else {
            text_seed.extend_from_slice(text.as_bytes());
        }
        out.push(("link", format!("format{format}.txt"), text_seed));
    }
    out.push(("document", "everything.json".into(), EVERYTHING.into()));
    out.push((
        "document",
        "written.json".into(),
        document(1).to_json(false).into_bytes(),
    ));
    out.push(("document", "empty.json".into(), b"{}".to_vec()));
    out.push((
        "document",
        "clip.json".into(),
        document(link::SCENE_FORMAT - 1).to_json(false).into_bytes(),
    ));
    out.push(("document", "scene.json".into(), SCENE.into()));
    out.push((
        "document",
        "scene-between.json".into(),
        SCENE_BETWEEN.into(),
    ));
    out.push(("document", "scene-mesh.json".into(), SCENE_MESH.into()));
    out.push(("document", "scene-files.json".into(), scene_files()));
    out.push(("problem", "arm.json".into(), ARM.into()));
    out.push(("problem", "loa1.json".into(), loa1_problem().into_bytes()));
    out
}

#[test]
#[ignore = "writes the seed corpora: run with --ignored after changing the generators"]
fn write_fuzz_seeds() {
    for (target, name, bytes) in seeds() {
        let dir = seed_dir(target);
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(dir.join(name), bytes).unwrap();
    }
}

fn files(target: &str) -> Vec<(String, Vec<u8>)> {
    let mut files: Vec<(String, Vec<u8>)> = std::fs::read_dir(seed_dir(target))
        .unwrap()
        .map(|e| {
            let path = e.unwrap().path();
            let name = path.file_name().unwrap().to_string_lossy().into_owned();
            let bytes = std::fs::read(&path).unwrap();
            assert!(
                bytes.len() < 16 * 1024,
                "{target}/{name}: {} bytes",
                bytes.len()
            );
            (name, bytes)
        })
        .collect();
    files.sort();
    files
}

#[test]
fn the_fuzz_seeds_are_valid() {
    let expected = seeds();
    for target in ["link", "document", "problem"] {
        let mut names: Vec<String> = expected
            .iter()
            .filter(|(t, _, _)| *t == target)
            .map(|(_, n, _)| n.clone())
            .collect();
        names.sort();
        let found = files(target);
        assert_eq!(
            found.iter().map(|(n, _)| n.clone()).collect::<Vec<_>>(),
            names
        );
        for (name, bytes) in found {
            let result = match target {
                "link" => {
                    let text = if bytes[0] & 1 == 0 {
                        String::from_utf8(bytes[1..].to_vec()).unwrap()
                    } else {
                        let payload = &bytes[1..];
                        let mut frame = vec![bytes[0] >> 1];
                        let mut len = payload.len();
                        while len >= 0x80 {
                            frame.push((len & 0x7F) as u8 | 0x80);
                            len >>= 7;
                        }
                        frame.push(len as u8);
                        frame.extend_from_slice(payload);
                        let crc = crc32fast::hash(&frame);
                        frame.extend_from_slice(&crc.to_le_bytes());
                        URL_SAFE_NO_PAD.encode(frame)
                    };
                    link::decode_scene(&text)
                        .map(|_| ())
                        .map_err(|e| e.to_string())
                }
                // The document target reads scenes too (a document is a scene of one).
                "document" => Scene::from_json(std::str::from_utf8(&bytes).unwrap())
                    .map(|_| ())
                    .map_err(|e| e.to_string()),
                _ => Problem::from_json(std::str::from_utf8(&bytes).unwrap())
                    .map(|_| ())
                    .map_err(|e| e.to_string()),
            };
            if let Err(e) = result {
                panic!("{target}/{name}: {e}");
            }
        }
    }
}
