//! A document's joint stiffness: read, checked, written, linked, and felt by the solver.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

#[cfg(target_arch = "wasm32")]
use wasm_bindgen_test::wasm_bindgen_test as test;

use stance_document::{Document, Problem, link};
use stance_hanim::{LevelOfArticulation, SkeletonOptions, default_skeleton};
use stance_ik::{Dof, Posture, Skeleton};

fn body() -> Skeleton {
    default_skeleton(&SkeletonOptions {
        loa: LevelOfArticulation::Loa2,
        ..Default::default()
    })
    .unwrap()
    .skeleton
}

/// Both feet where they stand, the right wrist 20 cm up and out of its rest position.
fn reach(stiffness: &str) -> Document {
    let s = body();
    let frames = stance_ik::Frames::new(&s, &Posture::rest(&s));
    let at = |name: &str| frames.joint_position[s.joint_index(name).unwrap()];
    let (l, r, w) = (at("l_talocrural"), at("r_talocrural"), at("r_radiocarpal"));
    Document::from_json(&format!(
        r#"{{"tasks":[
          {{"kind":"position","joint":"l_talocrural","target":[{},{},{}]}},
          {{"kind":"position","joint":"r_talocrural","target":[{},{},{}]}},
          {{"kind":"position","joint":"r_radiocarpal","target":[{},{},{}],"level":2}}],
          "stiffness":{stiffness}}}"#,
        l.x,
        l.y,
        l.z,
        r.x,
        r.y,
        r.z,
        w.x - 0.1,
        w.y + 0.2,
        w.z + 0.1
    ))
    .unwrap()
}

/// Rotation (rad) summed over the DOF of the joints whose name satisfies `which`.
fn turned(s: &Skeleton, p: &Posture, which: impl Fn(&str) -> bool) -> f64 {
    s.joints()
        .iter()
        .filter(|j| which(&j.name))
        .flat_map(|j| j.dof_range())
        .filter(|&d| s.dof_kinds()[d].is_rotation())
        .map(|d| p.values()[d].abs())
        .sum()
}

#[test]
fn a_stiff_shoulder_moves_less_and_the_rest_of_the_body_takes_over() {
    let solve = |doc: &Document| {
        let problem = Problem::from_document(doc, body()).unwrap();
        let (posture, report) = problem.solve().unwrap();
        assert!(report.levels.iter().all(|l| l.met), "{report:?}");
        (problem.skeleton, posture)
    };
    let (s, free) = solve(&reach("{}"));
    let (stiff_s, stiff) = solve(&reach(r#"{"r_shoulder":{"rx":0.95,"ry":0.95,"rz":0.95}}"#));
    let shoulder = s.joint_index("r_shoulder").unwrap();
    let d = s.joints()[shoulder].dof_start;
    assert_eq!(
        stiff_s.stiffness()[d],
        0.95,
        "the document's value reaches the solver"
    );
    let is_shoulder = |n: &str| n == "r_shoulder";
    let is_trunk = |n: &str| n.starts_with("vl") || n.starts_with("vt");
    let (a, b) = (
        turned(&s, &free, is_shoulder),
        turned(&s, &stiff, is_shoulder),
    );
    assert!(
        b < 0.7 * a,
        "shoulder {a} rad with its default stiffness, {b} rad stiff"
    );
    let (a, b) = (turned(&s, &free, is_trunk), turned(&s, &stiff, is_trunk));
    assert!(b > a, "trunk {a} rad, {b} rad with a stiff shoulder");
}

#[test]
fn stiffness_round_trips_through_json_and_a_link() {
    let doc = reach(r#"{"vl5":{"rx":0.8,"rz":0.25},"r_elbow":{"rx":0.1}}"#);
    assert_eq!(doc.stiffness.get("vl5", Dof::Rx), Some(0.8));
    let again = Document::from_json(&doc.to_json(false)).unwrap();
    assert_eq!(again, doc);
    let fragment = link::encode(&doc);
    let back = link::decode(&fragment).unwrap();
    for (joint, dof, want) in [
        ("vl5", Dof::Rx, 0.8),
        ("vl5", Dof::Rz, 0.25),
        ("r_elbow", Dof::Rx, 0.1),
    ] {
        let got = back.stiffness.get(joint, dof).unwrap();
        assert!(
            (got - want).abs() <= link::ROTATION_STEP_RAD,
            "{joint}.{dof:?}: {got}"
        );
    }
    assert_eq!(back.stiffness.joints.len(), 2);
    // A document without stiffness keeps the older format its readers know.
    let plain = Document {
        stiffness: Default::default(),
        ..doc.clone()
    };
    let bytes = |f: &str| f.len();
    assert!(bytes(&link::encode(&plain)) < bytes(&fragment));
}

#[test]
fn bad_stiffness_is_named() {
    for (stiffness, want) in [
        (r#"{"vl5":{"rx":1.0}}"#, "stiffness.vl5.rx"),
        (r#"{"vl5":{"rx":-0.1}}"#, "stiffness.vl5.rx"),
        (
            r#"{"humanoid_root":{"tx":0.5}}"#,
            "stiffness.humanoid_root.tx",
        ),
        (r#"{"vl5":{"rx":"stiff"}}"#, "stiffness.vl5.rx"),
    ] {
        let text = format!(r#"{{"stiffness":{stiffness}}}"#);
        let error = Document::from_json(&text).unwrap_err().to_string();
        assert!(error.contains(want), "{stiffness}: {error}");
    }
    // A joint the body lacks: named when the document meets the body, which stays as it was.
    let doc = Document::from_json(r#"{"stiffness":{"l_tail":{"rx":0.5}}}"#).unwrap();
    let s = body();
    let error = stance_document::apply_stiffness(&doc.stiffness, &s).unwrap_err();
    assert!(error.to_string().contains("stiffness.l_tail"), "{error}");
    let error = Problem::from_document(&doc, s).unwrap_err();
    assert!(error.to_string().contains("l_tail"), "{error}");
}
