//! The package's retargeting module, natively: a BVH clip onto the body a solver-module
//! skeleton's recipe describes, the same as retargeting onto that body directly.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use stance_js::Body;
use stance_js_motion::retarget_bvh;

const WALK: &str = include_str!("../../../tests/fixtures/motion/walk.bvh");

/// The clip comes back on the body of the recipe, frame for frame what `stance_motion`
/// gives on the solver module's own body (catches a recipe that builds another body: the
/// values would be for other DOF), with its foot contacts; the plain copy differs; bodies
/// without H-Anim names, malformed clips and recipes say why.
#[test]
fn a_bvh_clip_is_retargeted_onto_the_body_of_a_recipe() {
    let body = Body::hanim(2).unwrap();
    let r = retarget_bvh(&body.recipe_json(), WALK, true).unwrap();
    assert_eq!(r.frame_count, 260);
    assert!((r.frame_time - 0.0083333).abs() < 1e-12);
    assert_eq!(r.values.len(), 260 * body.skeleton.dof_count());
    let clip = stance_motion::bvh::read_bvh(
        WALK.as_bytes(),
        "clip",
        &stance_motion::bvh::BvhLimits::default(),
    )
    .unwrap();
    let options = stance_motion::RetargetOptions {
        contacts: Some(stance_motion::ContactSettings::default()),
        ..Default::default()
    };
    let direct = stance_motion::retarget(&clip, body.humanoid.as_ref().unwrap(), &options).unwrap();
    let direct: Vec<f64> = direct
        .postures
        .iter()
        .flat_map(|p| p.values().iter().copied())
        .collect();
    assert_eq!(r.values, direct);
    let contacts = r.report["contacts"].as_array().unwrap();
    for foot in ["l_talocrural", "r_talocrural"] {
        assert!(contacts.iter().any(|c| c["joint"] == foot), "{contacts:?}");
    }
    let copy = retarget_bvh(&body.recipe_json(), WALK, false).unwrap();
    assert_eq!(copy.values.len(), r.values.len());
    assert!(copy.report["contacts"].as_array().unwrap().is_empty());
    assert_ne!(copy.values, r.values);

    let joints =
        Body::from_joints(r#"{"joints":[{"name":"a","parent":null,"offset":[0,0,0]}]}"#).unwrap();
    let e = retarget_bvh(&joints.recipe_json(), WALK, true).unwrap_err();
    assert!(e.contains("H-Anim body"), "{e}");
    let e = retarget_bvh(&body.recipe_json(), "HIERARCHY\nROOT Hips\n{\n", true).unwrap_err();
    assert!(e.starts_with("bvh: line"), "{e}");
    let e = retarget_bvh(r#"{"hanim": 7}"#, WALK, true).unwrap_err();
    assert!(e.contains("loa"), "{e}");
}
