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

/// `(joint, dof, curve: +1 the +axis strength / -1 the -axis one, profile, q in rad,
/// expected N m, what it is)`.
type Point = (
    &'static str,
    Dof,
    f64,
    StrengthProfile,
    f64,
    f64,
    &'static str,
);

const MEAN: StrengthProfile = StrengthProfile {
    sex: Sex::Unspecified,
    mass_kg: 70.0,
    stature_m: 1.75,
};
const MAN: StrengthProfile = StrengthProfile {
    sex: Sex::Male,
    mass_kg: 80.0,
    stature_m: 1.80,
};
const WOMAN: StrengthProfile = StrengthProfile {
    sex: Sex::Female,
    mass_kg: 60.0,
    stature_m: 1.62,
};

#[test]
fn every_anderson_curve_matches_its_formula_evaluated_by_hand() {
    // Catches a wrong or swapped coefficient (C1, C2, C3, a male row read as the female one,
    // the mean of the rows), a wrong sign of the anatomical angle (hip and ankle flexion are
    // -rx), a curve put on the wrong side of a DOF (flexion for extension), and a lost floor:
    // each of the six curves at two angles (the mean rows, 70 kg, 1.75 m) and with each
    // sex's row (at q = 0), through the DOF of the default body.
    //
    // Hand computation: strength = C1 m g h cos(C2 (sign q - C3)), g = 9.81, at least
    // 0.1 C1 m g h. Mean rows: m g h = 70 * 9.81 * 1.75 = 1201.725; man 80 * 9.81 * 1.80 =
    // 1412.64; woman 60 * 9.81 * 1.62 = 953.532.
    let points: [Point; 24] = [
        // Hip extension (+rx), sign -1: C = (0.171, 0.8275, 1.087) (mean of 0.161/0.181,
        // 0.958/0.697, 0.932/1.242); peak 0.171 * 1201.725 = 205.495.
        // q = 0: cos(0.8275 * (0 - 1.087)) = cos(-0.89949) = 0.62201 -> 127.819.
        (
            "l_hip",
            Rx,
            1.0,
            MEAN,
            0.0,
            127.819,
            "hip extension, mean, q 0",
        ),
        // q = -1 (1 rad of flexion): cos(0.8275 * (1 - 1.087)) = cos(-0.07199) = 0.99741
        // -> 204.963.
        (
            "r_hip",
            Rx,
            1.0,
            MEAN,
            -1.0,
            204.963,
            "hip extension, mean, q -1",
        ),
        // Man: 0.161 * 1412.64 = 227.435, cos(0.958 * -0.932) = cos(-0.89286) = 0.62719
        // -> 142.645.
        ("l_hip", Rx, 1.0, MAN, 0.0, 142.645, "hip extension, man"),
        // Woman: 0.181 * 953.532 = 172.589, cos(0.697 * -1.242) = cos(-0.86567) = 0.64813
        // -> 111.860.
        (
            "l_hip",
            Rx,
            1.0,
            WOMAN,
            0.0,
            111.860,
            "hip extension, woman",
        ),
        // Hip flexion (-rx), sign -1: C = (0.12, 0.694, -0.282); peak 0.12 * 1201.725 =
        // 144.207. q = 0: cos(0.694 * 0.282) = cos(0.19571) = 0.98091 -> 141.454.
        (
            "l_hip",
            Rx,
            -1.0,
            MEAN,
            0.0,
            141.454,
            "hip flexion, mean, q 0",
        ),
        // q = -1: cos(0.694 * (1 + 0.282)) = cos(0.88971) = 0.62964 -> 90.798.
        (
            "r_hip",
            Rx,
            -1.0,
            MEAN,
            -1.0,
            90.798,
            "hip flexion, mean, q -1",
        ),
        // Man: 0.113 * 1412.64 = 159.628, cos(0.738 * 0.214) = cos(0.15793) = 0.98755
        // -> 157.642.
        ("l_hip", Rx, -1.0, MAN, 0.0, 157.642, "hip flexion, man"),
        // Woman: 0.127 * 953.532 = 121.099, cos(0.650 * 0.350) = cos(0.2275) = 0.97423
        // -> 117.978.
        ("l_hip", Rx, -1.0, WOMAN, 0.0, 117.978, "hip flexion, woman"),
        // Knee extension (-rx), sign +1: C = (0.161, 1.2225, 1.2035); peak 0.161 * 1201.725
        // = 193.478. q = 0.5: cos(1.2225 * (0.5 - 1.2035)) = cos(-0.86003) = 0.65242
        // -> 126.228.
        (
            "l_knee",
            Rx,
            -1.0,
            MEAN,
            0.5,
            126.228,
            "knee extension, mean, q 0.5",
        ),
        // q = 1: cos(1.2225 * -0.2035) = cos(-0.24878) = 0.96921 -> 187.521.
        (
            "r_knee",
            Rx,
            -1.0,
            MEAN,
            1.0,
            187.521,
            "knee extension, mean, q 1",
        ),
        // Man: 0.163 * 1412.64 = 230.260, cos(1.258 * -1.133) = cos(-1.42531) = 0.14497
        // -> 33.381.
        ("l_knee", Rx, -1.0, MAN, 0.0, 33.381, "knee extension, man"),
        // Woman: 0.159 * 953.532 = 151.612, cos(1.187 * -1.274) = cos(-1.51224) = 0.05852,
        // below the floor: 0.1 * 151.612 = 15.161.
        (
            "l_knee",
            Rx,
            -1.0,
            WOMAN,
            0.0,
            15.161,
            "knee extension, woman (floor)",
        ),
        // Knee flexion (+rx), sign +1: C = (0.0835, 0.871, 0.5785); peak 0.0835 * 1201.725
        // = 100.344. q = 0: cos(0.871 * -0.5785) = cos(-0.50387) = 0.87573 -> 87.873.
        (
            "l_knee",
            Rx,
            1.0,
            MEAN,
            0.0,
            87.873,
            "knee flexion, mean, q 0",
        ),
        // q = 1: cos(0.871 * 0.4215) = cos(0.36713) = 0.93336 -> 93.657.
        (
            "r_knee",
            Rx,
            1.0,
            MEAN,
            1.0,
            93.657,
            "knee flexion, mean, q 1",
        ),
        // Man: 0.087 * 1412.64 = 122.900, cos(0.869 * -0.522) = cos(-0.45362) = 0.89886
        // -> 110.471.
        ("l_knee", Rx, 1.0, MAN, 0.0, 110.471, "knee flexion, man"),
        // Woman: 0.080 * 953.532 = 76.283, cos(0.873 * -0.635) = cos(-0.55436) = 0.85023
        // -> 64.858.
        ("l_knee", Rx, 1.0, WOMAN, 0.0, 64.858, "knee flexion, woman"),
        // Ankle plantar flexion (+rx), sign -1: C = (0.0995, 1.395, 0.416); peak 0.0995 *
        // 1201.725 = 119.572. q = 0: cos(1.395 * -0.416) = cos(-0.58032) = 0.83629 -> 99.996.
        (
            "l_talocrural",
            Rx,
            1.0,
            MEAN,
            0.0,
            99.996,
            "plantar flexion, mean, q 0",
        ),
        // q = -0.3 (0.3 rad of dorsiflexion): cos(1.395 * (0.3 - 0.416)) = cos(-0.16182) =
        // 0.98694 -> 118.010.
        (
            "r_talocrural",
            Rx,
            1.0,
            MEAN,
            -0.3,
            118.010,
            "plantar flexion, mean, q -0.3",
        ),
        // Man: 0.095 * 1412.64 = 134.201, cos(1.391 * -0.408) = cos(-0.56753) = 0.84323
        // -> 113.162.
        (
            "l_talocrural",
            Rx,
            1.0,
            MAN,
            0.0,
            113.162,
            "plantar flexion, man",
        ),
        // Woman: 0.104 * 953.532 = 99.167, cos(1.399 * -0.424) = cos(-0.59318) = 0.82917
        // -> 82.227.
        (
            "l_talocrural",
            Rx,
            1.0,
            WOMAN,
            0.0,
            82.227,
            "plantar flexion, woman",
        ),
        // Ankle dorsiflexion (-rx), sign -1: C = (0.03, 1.2945, -0.2445); peak 0.03 *
        // 1201.725 = 36.052. q = 0: cos(1.2945 * 0.2445) = cos(0.31651) = 0.95033 -> 34.261.
        (
            "l_talocrural",
            Rx,
            -1.0,
            MEAN,
            0.0,
            34.261,
            "dorsiflexion, mean, q 0",
        ),
        // q = -0.3: cos(1.2945 * (0.3 + 0.2445)) = cos(0.70486) = 0.76170 -> 27.461.
        (
            "r_talocrural",
            Rx,
            -1.0,
            MEAN,
            -0.3,
            27.461,
            "dorsiflexion, mean, q -0.3",
        ),
        // Man: 0.033 * 1412.64 = 46.617, cos(1.510 * 0.187) = cos(0.28237) = 0.96040
        // -> 44.771.
        (
            "l_talocrural",
            Rx,
            -1.0,
            MAN,
            0.0,
            44.771,
            "dorsiflexion, man",
        ),
        // Woman: 0.027 * 953.532 = 25.745, cos(1.079 * 0.302) = cos(0.32586) = 0.94738
        // -> 24.391.
        (
            "l_talocrural",
            Rx,
            -1.0,
            WOMAN,
            0.0,
            24.391,
            "dorsiflexion, woman",
        ),
    ];
    check_points(&points);
}

#[test]
fn every_constant_strength_matches_its_source() {
    // Catches a constant on the wrong side of its DOF (flexion for extension), a right side
    // not mirrored (or rx mirrored), a lost gymnast-to-population scaling, a strength on a
    // joint that is not the lowest of its region, and a mass scaling that is not linear.
    // Each constant at two DOF values (a constant must not vary), 70 kg unless said.
    //
    // Hand computation: the gymnast's shoulder values times 89.9 / 91.1388 = 0.986408:
    // extension 127.401 -> 125.669, abduction 94.6839 -> 93.397, adduction 128.496 ->
    // 126.749, external rotation 43.5837 -> 42.991, internal 50.522 -> 49.835. Elbow
    // 0.67 * 70 = 46.9 (extension), 0.78 * 70 = 54.6 (flexion). Lower back extension 288,
    // flexion 288 / 1.3 = 221.538. At 35 kg every constant halves.
    let half = StrengthProfile {
        mass_kg: 35.0,
        ..MEAN
    };
    let mut points: Vec<Point> = Vec::new();
    let constants: [(&str, Dof, f64, f64, &str); 22] = [
        // Shoulder: +rx extension, -rx flexion (89.9, the population value itself).
        (
            "l_shoulder",
            Rx,
            125.669,
            89.9,
            "shoulder extension / flexion",
        ),
        (
            "r_shoulder",
            Rx,
            125.669,
            89.9,
            "right shoulder, rx not mirrored",
        ),
        // +rz abducts the left arm; on the right +rz adducts: the two swap.
        (
            "l_shoulder",
            Rz,
            93.397,
            126.749,
            "shoulder abduction / adduction",
        ),
        (
            "r_shoulder",
            Rz,
            126.749,
            93.397,
            "right shoulder rz mirrored",
        ),
        // +ry external rotation on the left; mirrored on the right.
        ("l_shoulder", Ry, 42.991, 49.835, "shoulder rotation"),
        (
            "r_shoulder",
            Ry,
            49.835,
            42.991,
            "right shoulder ry mirrored",
        ),
        ("l_elbow", Rx, 46.9, 54.6, "elbow extension / flexion"),
        ("r_elbow", Rx, 46.9, 54.6, "right elbow"),
        ("l_elbow", Ry, 13.0, 13.0, "forearm pronation / supination"),
        ("r_elbow", Ry, 13.0, 13.0, "right forearm"),
        // Wrist: +rz extension 7.1, -rz flexion 12.2; +rx ulnar 9.5, -rx radial 11.0.
        ("l_radiocarpal", Rz, 7.1, 12.2, "wrist extension / flexion"),
        ("r_radiocarpal", Rz, 12.2, 7.1, "right wrist rz mirrored"),
        (
            "l_radiocarpal",
            Rx,
            9.5,
            11.0,
            "wrist ulnar / radial deviation",
        ),
        (
            "r_radiocarpal",
            Rx,
            9.5,
            11.0,
            "right wrist rx not mirrored",
        ),
        // The lowest lumbar joint (vl5 at LOA 1): +rx flexion held by the extensors.
        ("vl5", Rx, 221.538, 288.0, "lower back"),
        // The lowest cervical joint (the skull base at LOA 1).
        ("skullbase", Rx, 30.0, 51.0, "neck flexion / extension"),
        ("skullbase", Rz, 32.0, 32.0, "neck lateral bending"),
        ("skullbase", Ry, 13.0, 13.0, "neck axial rotation"),
        // Without a source: none (checked below). Scaled with the body mass:
        ("l_shoulder", Rx, 125.669, 89.9, "35 kg: halves"),
        ("l_elbow", Rx, 46.9, 54.6, "35 kg: halves"),
        ("l_radiocarpal", Rz, 7.1, 12.2, "35 kg: halves"),
        ("vl5", Rx, 221.538, 288.0, "35 kg: halves"),
    ];
    for (i, (joint, kind, positive, negative, what)) in constants.into_iter().enumerate() {
        let (profile, scale) = if i >= 18 { (half, 0.5) } else { (MEAN, 1.0) };
        for q in [0.0, 0.7] {
            points.push((joint, kind, 1.0, profile, q, positive * scale, what));
            points.push((joint, kind, -1.0, profile, q, negative * scale, what));
        }
    }
    check_points(&points);
    // No source, no strength: hip ab-/adduction and rotation.
    let b = body(LevelOfArticulation::Loa1);
    let strengths = dof_strengths(&b.skeleton, &built_axes(&b), &MEAN);
    for (joint, kind) in [("l_hip", Rz), ("l_hip", Ry), ("r_hip", Rz)] {
        assert!(
            strengths[dof(&b, joint, kind)].is_none(),
            "{joint} {kind:?}"
        );
    }
}

/// Evaluates every point on the LOA 1 default body (built axes) and reports all misses.
fn check_points(points: &[Point]) {
    let b = body(LevelOfArticulation::Loa1);
    let mut misses = Vec::new();
    for &(joint, kind, side, profile, q, expected, what) in points {
        let strengths = dof_strengths(&b.skeleton, &built_axes(&b), &profile);
        let Some(strength) = strengths[dof(&b, joint, kind)] else {
            misses.push(format!("{what}: {joint} {kind:?} has no strength"));
            continue;
        };
        let curve = if side > 0.0 {
            strength.positive
        } else {
            strength.negative
        };
        let (got, _) = curve.at(q);
        // The hand computations keep 5-6 significant digits.
        if (got - expected).abs() > 2e-3 {
            misses.push(format!(
                "{what}: {joint} {kind:?} {} at q {q}: {got:.4} N m, by hand {expected}",
                if side > 0.0 { "+axis" } else { "-axis" }
            ));
        }
    }
    assert!(misses.is_empty(), "{}", misses.join("\n"));
}
