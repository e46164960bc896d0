//! The document and scene readers (`Document::from_json`, `Scene::from_json`) on arbitrary text. Must never panic; every
//! error must say something. A document that loads survives its JSON and its link, and is
//! set on the default H-Anim body (LOA2) as the editor does: its posture, its tasks as a
//! problem, their mirror images, and a few solver iterations with the solution's report.
//!
//! Seeds: `fuzz/seeds/document/` (written by `cargo test -p stance_document --test all
//! fuzz_seeds:: -- --ignored`).
#![no_main]

use std::sync::OnceLock;

#[path = "../common/solve_briefly.rs"]
mod solve_briefly;

use libfuzzer_sys::fuzz_target;
use stance_document::{Document, Problem, Scene, link};
use stance_hanim::{HumanoidSkeleton, SkeletonOptions, default_skeleton};

fn body() -> Option<&'static HumanoidSkeleton> {
    static BODY: OnceLock<Option<HumanoidSkeleton>> = OnceLock::new();
    BODY.get_or_init(|| default_skeleton(&SkeletonOptions::default()).ok())
        .as_ref()
}

fuzz_target!(|data: &[u8]| {
    let text = String::from_utf8_lossy(data);
    match Scene::from_json(&text) {
        Ok(scene) => {
            let again = Scene::from_json(&scene.to_json(true));
            assert_eq!(again.as_ref(), Ok(&scene), "the scene's JSON round trip");
        }
        Err(e) => assert!(!e.to_string().trim().is_empty(), "empty error: {e:?}"),
    }
    let document = match Document::from_json(&text) {
        Ok(document) => document,
        Err(e) => {
            assert!(!e.to_string().trim().is_empty(), "empty error: {e:?}");
            return;
        }
    };
    let json = Document::from_json(&document.to_json(true));
    assert_eq!(json.as_ref(), Ok(&document), "the JSON round trip");
    if let Err(e) = link::decode(&link::encode(&document)) {
        panic!("a valid document's link does not open: {e}\n{document:?}");
    }
    for task in &document.tasks {
        let _ = task.description();
        let _ = task.mirrored().validate();
    }
    let _ = document.posture.mirrored();
    let Some(body) = body() else {
        return;
    };
    if let Err(e) = document.to_posture(&body.skeleton) {
        assert!(!e.to_string().trim().is_empty(), "empty error: {e:?}");
    }
    let problem = match Problem::from_document(&document, body.skeleton.clone()) {
        Ok(problem) => problem,
        Err(e) => {
            assert!(!e.to_string().trim().is_empty(), "empty error: {e:?}");
            return;
        }
    };
    solve_briefly::solve_briefly(&problem);
});
