#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

#[cfg(target_arch = "wasm32")]
use wasm_bindgen_test::wasm_bindgen_test as test;

use super::*;
use crate::{LevelOfArticulation, SkeletonOptions, default_skeleton};

fn body(loa: LevelOfArticulation) -> HumanoidSkeleton {
    default_skeleton(&SkeletonOptions {
        loa,
        ..SkeletonOptions::default()
    })
    .unwrap()
}

fn dof(body: &HumanoidSkeleton, joint: &str, kind: Dof) -> usize {
    let s = &body.skeleton;
    let j = s.joint_index(joint).unwrap();
    s.joints()[j]
        .dof_range()
        .find(|&d| s.dof_kinds()[d] == kind)
        .unwrap()
}

#[test]
fn anderson_peaks_match_the_published_coefficients() {
    // A 69 kg, 1.732 m man (RBDL's reference subject): the hip extensors peak at C3 = 0.932 rad
    // of flexion with C1 m g h = 0.161 * 69 * 9.81 * 1.732 = 188.8 N m; the knee extensors at
    // 1.133 rad with 0.163 * 69 * 9.81 * 1.732 = 191.1 N m (hand computations).
    let profile = StrengthProfile {
        sex: Sex::Male,
        mass_kg: 69.0,
        stature_m: 1.732,
    };
    let hip = anderson(HIP_EXTENSION, -1.0, &profile);
    // Hip flexion is -rx: the peak is at rx = -0.932.
    let (peak, slope) = hip.at(-0.932);
    assert!((peak - 188.76).abs() < 0.05, "{peak}");
    assert!(slope.abs() < 1e-9);
    assert!(hip.at(-0.5).0 < peak && hip.at(-1.3).0 < peak);
    let knee = anderson(KNEE_EXTENSION, 1.0, &profile);
    assert!((knee.at(1.133).0 - 191.10).abs() < 0.05);
    // Far outside the tested range the curve keeps a tenth of its peak.
    assert!((knee.at(-2.0).0 - 0.1 * knee.peak).abs() < 1e-9);
}

#[test]
fn every_sourced_dof_has_a_strength_and_the_right_side_mirrors_the_left() {
    let b = body(LevelOfArticulation::Loa2);
    let strengths = dof_strengths(&b.skeleton, &built_axes(&b), &StrengthProfile::default());
    let at = |joint: &str, kind: Dof| strengths[dof(&b, joint, kind)];
    for joint in [
        "l_hip",
        "r_knee",
        "l_talocrural",
        "r_shoulder",
        "l_elbow",
        "r_radiocarpal",
    ] {
        assert!(at(joint, Rx).is_some(), "{joint}");
    }
    assert!(at("l_shoulder", Rz).is_some() && at("l_shoulder", Ry).is_some());
    assert!(at("l_hip", Rz).is_none(), "no source for hip abduction");
    // Shoulder: +rz abducts the left arm (abductors hold it: the +axis strength), adducts the
    // right one: the two sides' curves swap.
    let (left, right) = (at("l_shoulder", Rz).unwrap(), at("r_shoulder", Rz).unwrap());
    assert_eq!(left.positive.peak, right.negative.peak);
    assert_eq!(left.negative.peak, right.positive.peak);
    assert!(
        left.positive.peak < left.negative.peak,
        "abduction is the weaker"
    );
    // Flexion-extension (rx) is not mirrored.
    assert_eq!(at("l_elbow", Rx), at("r_elbow", Rx));
    // Only the lowest lumbar and cervical joints carry the regions' strengths.
    let s = &b.skeleton;
    let spine_with_strength = s
        .joints()
        .iter()
        .filter(|j| JointClass::of(&j.name) == JointClass::Spine)
        .filter(|j| j.dof_range().any(|d| strengths[d].is_some()))
        .count();
    assert_eq!(spine_with_strength, 1);
}

#[test]
fn strengths_scale_with_the_body() {
    let b = body(LevelOfArticulation::Loa1);
    let light = dof_strengths(
        &b.skeleton,
        &built_axes(&b),
        &StrengthProfile {
            mass_kg: 35.0,
            ..StrengthProfile::default()
        },
    );
    let normal = dof_strengths(&b.skeleton, &built_axes(&b), &StrengthProfile::default());
    // The default body's frames are the H-Anim frame: its built axes are the aligned ones.
    assert_eq!(
        dof_strengths(
            &b.skeleton,
            &aligned_axes(&b.skeleton),
            &StrengthProfile::default()
        ),
        normal
    );
    let d = dof(&b, "l_elbow", Rx);
    let ratio = light[d].unwrap().negative.peak / normal[d].unwrap().negative.peak;
    assert!((ratio - 0.5).abs() < 1e-12);
    // Elbow flexion of a 70 kg body: 0.78 N m per kg.
    assert!((normal[d].unwrap().negative.peak - 54.6).abs() < 1e-9);
}
