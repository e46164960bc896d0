//! Calibration properties (Molet et al., magnetic sensors).

// Test helpers outside #[test] functions may unwrap too (clippy.toml only covers the tests).
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

#[cfg(target_arch = "wasm32")]
use wasm_bindgen_test::wasm_bindgen_test as test;

use std::collections::BTreeMap;

use glam::{DQuat, DVec3};
use rand::rngs::StdRng;
use rand::{RngExt, SeedableRng};
use stance_mocap::SensorId;
use stance_mocap::calibration::{
    Calibration, CalibrationError, CalibrationSetup, HANIM_SPINE_WEIGHTS, SensorTarget, heading_of,
    rotation_fraction,
};

type Joint = &'static str;

const PELVIS: SensorId = SensorId(1);
const UPPER_BACK: SensorId = SensorId(2);
const UPPER_ARM: SensorId = SensorId(3);
const HAND: SensorId = SensorId(4);

const JOINTS: [Joint; 9] = [
    "humanoid_root",
    "sacroiliac",
    "vl5",
    "vt10",
    "vt1",
    "skullbase",
    "r_shoulder",
    "r_elbow",
    "r_wrist",
];

fn parents() -> BTreeMap<Joint, Joint> {
    BTreeMap::from([
        ("sacroiliac", "humanoid_root"),
        ("vl5", "sacroiliac"),
        ("vt10", "vl5"),
        ("vt1", "vt10"),
        ("skullbase", "vt1"),
        ("r_shoulder", "vt1"),
        ("r_elbow", "r_shoulder"),
        ("r_wrist", "r_elbow"),
    ])
}

fn spine_chain() -> SensorTarget<Joint> {
    SensorTarget::Chain(HANIM_SPINE_WEIGHTS.to_vec())
}

/// Device frame Z up, world Y up.
fn world_from_device() -> DQuat {
    DQuat::from_rotation_x(-std::f64::consts::FRAC_PI_2)
}

fn setup() -> CalibrationSetup<Joint> {
    CalibrationSetup::new(world_from_device(), parents())
        .bind(PELVIS, SensorTarget::Joint("sacroiliac"))
        .bind(UPPER_BACK, spine_chain())
        .bind(UPPER_ARM, SensorTarget::Joint("r_shoulder"))
        .bind(HAND, SensorTarget::Joint("r_wrist"))
}

fn random_rotation(rng: &mut StdRng) -> DQuat {
    let axis = DVec3::new(
        rng.random_range(-1.0..1.0),
        rng.random_range(-1.0..1.0),
        rng.random_range(-1.0..1.0),
    );
    let axis = if axis.length() < 1e-3 {
        DVec3::X
    } else {
        axis.normalize()
    };
    DQuat::from_axis_angle(axis, rng.random_range(-3.0..3.0))
}

fn small_rotation(rng: &mut StdRng, max_angle: f64) -> DQuat {
    let axis = random_rotation(rng) * DVec3::X;
    DQuat::from_axis_angle(axis, rng.random_range(-max_angle..max_angle))
}

/// World rotations of a posture given by local rotations.
fn world_from_locals(locals: &BTreeMap<Joint, DQuat>) -> BTreeMap<Joint, DQuat> {
    let parents = parents();
    let mut world = BTreeMap::new();
    for joint in JOINTS {
        let parent = parents
            .get(joint)
            .map(|p| world[p])
            .unwrap_or(DQuat::IDENTITY);
        world.insert(joint, parent * locals[joint]);
    }
    world
}

fn random_posture(rng: &mut StdRng, max_angle: f64) -> BTreeMap<Joint, DQuat> {
    let locals = JOINTS
        .iter()
        .map(|j| (*j, small_rotation(rng, max_angle)))
        .collect();
    world_from_locals(&locals)
}

fn random_readings(rng: &mut StdRng) -> BTreeMap<SensorId, DQuat> {
    [PELVIS, UPPER_BACK, UPPER_ARM, HAND]
        .into_iter()
        .map(|s| (s, random_rotation(rng)))
        .collect()
}

fn local_in(world: &BTreeMap<Joint, DQuat>, joint: Joint) -> DQuat {
    let parent = parents()
        .get(joint)
        .map(|p| world[p])
        .unwrap_or(DQuat::IDENTITY);
    parent.inverse() * world[joint]
}

/// Same rotation within 1e-9 (component-wise, up to the sign of the quaternion; `acos`-based
/// angles are too coarse near zero for this tolerance).
fn assert_same_rotation(a: DQuat, b: DQuat, what: &str) {
    let difference = (a - b).length().min((a + b).length());
    assert!(difference < 1e-9, "{what}: {a:?} vs {b:?}");
}

#[test]
fn at_the_calibration_instant_joints_equal_the_calibration_posture() {
    let mut rng = StdRng::seed_from_u64(1);
    for _ in 0..200 {
        let posture = random_posture(&mut rng, 1.5);
        let readings = random_readings(&mut rng);
        let calibration = Calibration::calibrate(&setup(), &posture, &readings).unwrap();
        let world = calibration.world_rotations(&readings, &posture);
        for joint in JOINTS {
            assert_same_rotation(world[joint], posture[joint], joint);
        }
        let locals = calibration.local_rotations(&readings, &posture);
        for (joint, local) in &locals {
            assert_same_rotation(*local, local_in(&posture, joint), joint);
        }
        // Only driven joints come back.
        let driven: Vec<&Joint> = locals.keys().collect();
        assert_eq!(
            driven,
            [
                &"r_shoulder",
                &"r_wrist",
                &"sacroiliac",
                &"vl5",
                &"vt1",
                &"vt10"
            ]
        );
    }
}

#[test]
fn a_sensor_mounting_rotation_does_not_change_joint_rotations() {
    let mut rng = StdRng::seed_from_u64(2);
    for _ in 0..100 {
        let posture = random_posture(&mut rng, 1.0);
        let at_calibration = random_readings(&mut rng);
        let later = random_readings(&mut rng);
        let reference = Calibration::calibrate(&setup(), &posture, &at_calibration).unwrap();
        // Every sensor strapped on differently: S' = S * R_mount.
        let mounts: BTreeMap<SensorId, DQuat> = at_calibration
            .keys()
            .map(|s| (*s, random_rotation(&mut rng)))
            .collect();
        let remount = |readings: &BTreeMap<SensorId, DQuat>| -> BTreeMap<SensorId, DQuat> {
            readings.iter().map(|(s, q)| (*s, *q * mounts[s])).collect()
        };
        let remounted =
            Calibration::calibrate(&setup(), &posture, &remount(&at_calibration)).unwrap();
        let want = reference.local_rotations(&later, &posture);
        let got = remounted.local_rotations(&remount(&later), &posture);
        assert_eq!(want.len(), got.len());
        for (joint, q) in &want {
            assert_same_rotation(*q, got[joint], joint);
        }
    }
}

#[test]
fn the_spine_split_multiplies_back_to_the_measured_rotation() {
    let mut rng = StdRng::seed_from_u64(3);
    for _ in 0..200 {
        let posture = random_posture(&mut rng, 0.8);
        let at_calibration = random_readings(&mut rng);
        let calibration = Calibration::calibrate(&setup(), &posture, &at_calibration).unwrap();
        let later = random_readings(&mut rng);
        let world = calibration.world_rotations(&later, &posture);
        let locals = calibration.local_rotations(&later, &posture);
        // The measured world rotation of the upper back: A * S(t) * M.
        let sensor_to_joint = calibration.sensor_to_joint(UPPER_BACK).unwrap();
        let measured = world_from_device() * later[&UPPER_BACK] * sensor_to_joint;
        let product = world["sacroiliac"] * locals["vl5"] * locals["vt10"] * locals["vt1"];
        assert_same_rotation(product, measured, "spine product");
        assert_same_rotation(world["vt1"], measured, "spine tip");
    }
}

#[test]
fn from_a_straight_spine_each_joint_takes_its_weight() {
    let mut rng = StdRng::seed_from_u64(4);
    let straight: BTreeMap<Joint, DQuat> = JOINTS.iter().map(|j| (*j, DQuat::IDENTITY)).collect();
    for _ in 0..100 {
        let at_calibration = random_readings(&mut rng);
        let calibration = Calibration::calibrate(&setup(), &straight, &at_calibration).unwrap();
        let mut later = at_calibration.clone();
        // Bend the upper back by a known world rotation: A * S' = bend * A * S.
        let bend = small_rotation(&mut rng, 2.5);
        let bent = world_from_device().inverse()
            * bend
            * world_from_device()
            * at_calibration[&UPPER_BACK];
        later.insert(UPPER_BACK, bent);
        let locals = calibration.local_rotations(&later, &straight);
        for (joint, weight) in HANIM_SPINE_WEIGHTS {
            assert_same_rotation(locals[joint], rotation_fraction(bend, weight), joint);
        }
    }
}

#[test]
fn a_heading_reset_keeps_pitch_and_roll() {
    let mut rng = StdRng::seed_from_u64(5);
    let up = DVec3::Y;
    for _ in 0..200 {
        let posture = random_posture(&mut rng, 1.0);
        let at_calibration = random_readings(&mut rng);
        let mut calibration = Calibration::calibrate(&setup(), &posture, &at_calibration).unwrap();
        let later = random_readings(&mut rng);
        let before = calibration.world_rotations(&later, &posture);
        calibration.reset_heading(&random_readings(&mut rng));
        let after = calibration.world_rotations(&later, &posture);
        for joint in ["sacroiliac", "vt1", "r_shoulder", "r_wrist"] {
            // The up axis seen from the joint is the same: pitch and roll are kept...
            let tilt_before = before[joint].inverse() * up;
            let tilt_after = after[joint].inverse() * up;
            assert!(tilt_before.distance(tilt_after) < 1e-9, "{joint}");
            // ...and the change is a pure rotation about up.
            let change = after[joint] * before[joint].inverse();
            assert!(
                change.xyz().cross(up).length() < 1e-9,
                "{joint}: {change:?}"
            );
        }
    }
}

#[test]
fn a_heading_reset_removes_heading_drift() {
    let mut rng = StdRng::seed_from_u64(6);
    for _ in 0..100 {
        let posture = random_posture(&mut rng, 0.5);
        let at_calibration = random_readings(&mut rng);
        let mut calibration = Calibration::calibrate(&setup(), &posture, &at_calibration).unwrap();
        // Each IMU's heading drifted about the device's up axis (Z).
        let drifted: BTreeMap<SensorId, DQuat> = at_calibration
            .iter()
            .map(|(s, q)| (*s, DQuat::from_rotation_z(rng.random_range(-3.0..3.0)) * *q))
            .collect();
        calibration.reset_heading(&drifted);
        let world = calibration.world_rotations(&drifted, &posture);
        for joint in ["sacroiliac", "vt1", "r_shoulder", "r_wrist"] {
            assert_same_rotation(world[joint], posture[joint], joint);
        }
        calibration.clear_heading();
        let world = calibration.world_rotations(&at_calibration, &posture);
        assert_same_rotation(world["r_wrist"], posture["r_wrist"], "cleared");
    }
}

#[test]
fn joints_without_sensors_keep_their_local_rotation() {
    let mut rng = StdRng::seed_from_u64(7);
    for _ in 0..100 {
        let posture = random_posture(&mut rng, 1.0);
        let at_calibration = random_readings(&mut rng);
        let calibration = Calibration::calibrate(&setup(), &posture, &at_calibration).unwrap();
        // The editor's posture moved on (IK) since calibration.
        let current = random_posture(&mut rng, 1.0);
        let later = random_readings(&mut rng);
        let world = calibration.world_rotations(&later, &current);
        for joint in ["humanoid_root", "skullbase", "r_elbow"] {
            assert_same_rotation(local_in(&world, joint), local_in(&current, joint), joint);
        }
        // A sensor without a reading leaves its joint alone too.
        let mut partial = later.clone();
        partial.remove(&HAND);
        let locals = calibration.local_rotations(&partial, &current);
        assert!(!locals.contains_key("r_wrist"));
        let world = calibration.world_rotations(&partial, &current);
        assert_same_rotation(
            local_in(&world, "r_wrist"),
            local_in(&current, "r_wrist"),
            "wrist",
        );
    }
}

#[test]
fn heading_of_is_a_rotation_about_up() {
    let mut rng = StdRng::seed_from_u64(8);
    for _ in 0..100 {
        let q = random_rotation(&mut rng);
        let heading = heading_of(q, DVec3::Y);
        assert!(heading.xyz().cross(DVec3::Y).length() < 1e-12);
        // What is left (the swing) has no twist about up.
        let swing = heading.inverse() * q;
        assert!(swing.y.abs() < 1e-9, "{swing:?}");
    }
}

#[test]
fn bad_setups_are_errors() {
    let posture: BTreeMap<Joint, DQuat> = JOINTS.iter().map(|j| (*j, DQuat::IDENTITY)).collect();
    let readings: BTreeMap<SensorId, DQuat> = [PELVIS, UPPER_BACK, UPPER_ARM, HAND]
        .into_iter()
        .map(|s| (s, DQuat::IDENTITY))
        .collect();
    let base = || CalibrationSetup::new(DQuat::IDENTITY, parents());
    let err = |setup: CalibrationSetup<Joint>, readings: &BTreeMap<SensorId, DQuat>| {
        Calibration::calibrate(&setup, &posture, readings).unwrap_err()
    };
    assert_eq!(
        err(
            base().bind(SensorId(9), SensorTarget::Joint("vl5")),
            &readings
        ),
        CalibrationError::MissingSensorReading(SensorId(9))
    );
    let chain = |c: Vec<(Joint, f64)>| base().bind(PELVIS, SensorTarget::Chain(c));
    assert!(matches!(
        err(chain(vec![("vl5", 0.5), ("vt10", 0.2)]), &readings),
        CalibrationError::BadWeights { .. }
    ));
    assert!(matches!(
        err(chain(vec![("vl5", 0.5), ("vt1", 0.5)]), &readings),
        CalibrationError::NotAChain { .. }
    ));
    assert!(matches!(
        err(chain(vec![]), &readings),
        CalibrationError::EmptyChain(_)
    ));
    let twice = base()
        .bind(PELVIS, SensorTarget::Joint("vl5"))
        .bind(HAND, SensorTarget::even_chain(&["vl5", "vt10"]));
    assert!(matches!(
        err(twice, &readings),
        CalibrationError::JointDrivenTwice(_)
    ));
    let bound_twice = base()
        .bind(PELVIS, SensorTarget::Joint("vl5"))
        .bind(PELVIS, SensorTarget::Joint("vt1"));
    assert!(matches!(
        err(bound_twice, &readings),
        CalibrationError::SensorBoundTwice(_)
    ));
    assert!(matches!(
        err(base().bind(PELVIS, SensorTarget::Joint("nose")), &readings),
        CalibrationError::MissingJointRotation(_)
    ));
    let mut cyclic = parents();
    cyclic.insert("humanoid_root", "r_wrist");
    let cyclic_setup = CalibrationSetup::new(DQuat::IDENTITY, cyclic);
    assert!(matches!(
        Calibration::calibrate(&cyclic_setup, &posture, &readings),
        Err(CalibrationError::CyclicHierarchy(_))
    ));
    let mut bad_reading = readings.clone();
    bad_reading.insert(PELVIS, DQuat::from_xyzw(f64::NAN, 0.0, 0.0, 1.0));
    assert!(matches!(
        err(
            base().bind(PELVIS, SensorTarget::Joint("vl5")),
            &bad_reading
        ),
        CalibrationError::BadRotation(_)
    ));
}
