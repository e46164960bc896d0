//! Sensor-to-joint calibration after Molet, Boulic & Thalmann 1999 (magnetic sensors).
//!
//! In a calibration posture whose joint world rotations `J_cal` are known (the editor's current
//! posture: rest pose, T-pose...), each sensor's constant sensor-to-joint rotation is
//! `M_sj = (A * S_cal)^-1 * J_cal`, with `A` the rotation from the device frame to the world.
//! Afterwards `J(t) = H_s * A * S(t) * M_sj` (`H_s` a per-sensor heading correction, identity
//! until [`Calibration::reset_heading`]) and the joint's local rotation is
//! `J_parent(t)^-1 * J(t)`.
//!
//! One sensor may drive a chain of joints (the spine). Its measured rotation of the chain's tip
//! relative to the chain's parent, `C(t) = P(t)^-1 * J_tip(t)`, differs from the calibration
//! one by `D = C(t) * C_cal^-1`; joint `i` of the chain gets the fraction `c_i` (sum of the
//! weights up to it) of that difference: `J_i(t) = P(t) * D^c_i * P_cal^-1 * J_i,cal`, where
//! `D^c = slerp(identity, D, c)`. With an identity calibration posture this is the classic
//! `L_i = slerp(identity, D, w_i)`, and the product of the chain's local rotations always
//! gives back the measured tip rotation.
//!
//! Joints are keyed by any ordered key (H-Anim names, indices); this module knows nothing of
//! the IK crate. Joints without sensors keep their local rotation from the posture given to
//! [`Calibration::local_rotations`], so sensors and IK tasks combine.

use std::collections::{BTreeMap, BTreeSet};
use std::fmt::Debug;

use glam::{DQuat, DVec3};
use serde::{Deserialize, Serialize};
use thiserror::Error;

use crate::decoder::{Sample, SensorId};

/// What one sensor drives.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum SensorTarget<K> {
    /// The sensor sits on this joint's segment.
    Joint(K),
    /// The sensor sits on the segment of the last joint of a chain (ordered from the chain's
    /// root to its tip, each joint the parent of the next); the chain's rotation is shared out
    /// by the weights, which must be non-negative and sum to 1.
    Chain(Vec<(K, f64)>),
}

impl<K: Clone> SensorTarget<K> {
    /// A chain with equal weights.
    pub fn even_chain(joints: &[K]) -> Self {
        let weight = 1.0 / joints.len().max(1) as f64;
        SensorTarget::Chain(joints.iter().map(|j| (j.clone(), weight)).collect())
    }
}

/// Suggested weights for one sensor on the upper back driving an H-Anim LOA 1 spine
/// (`vl5` lumbar, `vt10` mid thoracic, `vt1` upper thoracic): most bending happens in the
/// lumbar spine, least in the upper thoracic (after Molet et al.).
pub const HANIM_SPINE_WEIGHTS: [(&str, f64); 3] = [("vl5", 0.5), ("vt10", 0.3), ("vt1", 0.2)];

/// One sensor and the joint or chain it drives.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SensorBinding<K> {
    /// The sensor, as its samples name it.
    pub sensor: SensorId,
    /// The joint (or joint chain) whose segment the sensor sits on.
    pub target: SensorTarget<K>,
}

/// Everything fixed before calibrating.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(bound(deserialize = "K: Ord + Deserialize<'de>", serialize = "K: Serialize"))]
pub struct CalibrationSetup<K> {
    /// `A`: rotation from the device reference frame (transmitter, source or earth frame) to
    /// the editor's world frame.
    pub world_from_device: DQuat,
    /// The world's up axis (heading is rotation about it).
    pub world_up: DVec3,
    /// Joint hierarchy: child -> parent. Roots are absent.
    pub parents: BTreeMap<K, K>,
    /// What each sensor drives: a sensor may be bound once, a joint driven by one sensor only.
    pub bindings: Vec<SensorBinding<K>>,
}

impl<K: Ord> CalibrationSetup<K> {
    /// A setup with no sensors bound yet and +Y as the world's up axis.
    pub fn new(world_from_device: DQuat, parents: BTreeMap<K, K>) -> Self {
        CalibrationSetup {
            world_from_device,
            world_up: DVec3::Y,
            parents,
            bindings: Vec::new(),
        }
    }

    /// Binds `sensor` to what it drives (checked by [`Calibration::calibrate`]).
    pub fn bind(mut self, sensor: SensorId, target: SensorTarget<K>) -> Self {
        self.bindings.push(SensorBinding { sensor, target });
        self
    }
}

/// Why [`Calibration::calibrate`] refused a setup, posture or set of sensor readings.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum CalibrationError {
    /// A bound sensor has no orientation at the calibration instant.
    #[error("sensor {0:?} has no reading at the calibration instant")]
    MissingSensorReading(SensorId),
    /// A driven joint (or a chain's parent) has no world rotation in the calibration posture.
    #[error("joint {0} has no world rotation in the calibration posture")]
    MissingJointRotation(String),
    /// The same sensor appears in two bindings.
    #[error("sensor {0:?} is bound more than once")]
    SensorBoundTwice(SensorId),
    /// A joint is driven by two bindings, or appears twice in one chain.
    #[error("joint {0} is driven by more than one sensor")]
    JointDrivenTwice(String),
    /// A sensor is bound to a chain without joints.
    #[error("sensor {0:?} drives an empty chain")]
    EmptyChain(SensorId),
    /// A chain's weights are negative, not finite or do not sum to 1.
    #[error(
        "chain weights of sensor {sensor:?} must be finite and non-negative and sum to 1, sum is {sum}"
    )]
    BadWeights {
        /// The sensor driving the chain.
        sensor: SensorId,
        /// The sum of the chain's weights.
        sum: f64,
    },
    /// A chain's joints are not each the parent of the next in the hierarchy.
    #[error("joint {child} of the chain of sensor {sensor:?} is not a child of {expected_parent}")]
    NotAChain {
        /// The sensor driving the chain.
        sensor: SensorId,
        /// The joint whose parent is not the previous joint of the chain.
        child: String,
        /// The previous joint of the chain, which should be its parent.
        expected_parent: String,
    },
    /// The child-to-parent map loops back on itself.
    #[error("the joint hierarchy has a cycle through {0}")]
    CyclicHierarchy(String),
    /// A rotation (`world_from_device`, a sensor reading or a joint's world rotation) is not a
    /// finite unit quaternion.
    #[error("rotation of {0} is not finite or not unit length")]
    BadRotation(String),
    /// `world_up` is zero or not finite.
    #[error("the world up axis must be a finite non-zero vector")]
    BadUpAxis,
}

#[derive(Clone, Debug, PartialEq)]
enum Driven<K> {
    Joint {
        joint: K,
        /// `M_sj`.
        sensor_to_joint: DQuat,
    },
    Chain {
        joints: Vec<K>,
        /// `c_i`: weights summed up to and including joint i (last is 1).
        cumulative_weights: Vec<f64>,
        /// `M_s,tip`.
        sensor_to_tip: DQuat,
        /// Parent of the chain's first joint.
        chain_parent: Option<K>,
        /// `P_cal^-1 * J_i,cal` for each joint of the chain.
        joint_in_parent_at_calibration: Vec<DQuat>,
    },
}

#[derive(Clone, Debug, PartialEq)]
struct CalibratedSensor<K> {
    sensor: SensorId,
    driven: Driven<K>,
    /// `J_cal` of the joint the sensor sits on (the tip for chains).
    joint_world_at_calibration: DQuat,
    /// `H_s`, a rotation about the world up axis.
    heading_correction: DQuat,
}

/// A calibrated set of sensors: turns sensor orientations into joint rotations.
#[derive(Clone, Debug, PartialEq)]
pub struct Calibration<K> {
    world_from_device: DQuat,
    world_up: DVec3,
    parents: BTreeMap<K, K>,
    /// Every joint known at calibration, parents before children.
    joint_order: Vec<K>,
    sensors: Vec<CalibratedSensor<K>>,
}

fn name<K: Debug>(key: &K) -> String {
    format!("{key:?}")
}

fn check_unit(q: DQuat, what: impl FnOnce() -> String) -> Result<DQuat, CalibrationError> {
    if q.is_finite() && (q.length() - 1.0).abs() < 1e-3 {
        Ok(q.normalize())
    } else {
        Err(CalibrationError::BadRotation(what()))
    }
}

/// `slerp(identity, q, fraction)`, taking the shorter way round.
pub fn rotation_fraction(q: DQuat, fraction: f64) -> DQuat {
    let q = if q.w < 0.0 { -q } else { q };
    let (axis, angle) = q.to_axis_angle();
    if angle.abs() < 1e-12 || !axis.is_finite() {
        return DQuat::IDENTITY;
    }
    DQuat::from_axis_angle(axis, angle * fraction)
}

/// The part of `q` that rotates about `up` (swing-twist decomposition); identity when `q`
/// turns `up` upside down and the twist is undefined.
pub fn heading_of(q: DQuat, up: DVec3) -> DQuat {
    let projected = up * q.xyz().dot(up);
    let twist = DQuat::from_xyzw(projected.x, projected.y, projected.z, q.w);
    let length = twist.length();
    if length < 1e-9 || !length.is_finite() {
        DQuat::IDENTITY
    } else {
        twist / length
    }
}

/// Orders joints so that every parent comes before its children.
fn parents_first<K: Ord + Clone + Debug>(
    parents: &BTreeMap<K, K>,
    extra: impl IntoIterator<Item = K>,
) -> Result<Vec<K>, CalibrationError> {
    let mut joints: BTreeSet<K> = parents.keys().cloned().collect();
    joints.extend(parents.values().cloned());
    joints.extend(extra);
    let limit = joints.len() + 1;
    let mut with_depth = Vec::with_capacity(joints.len());
    for joint in joints {
        let mut depth = 0usize;
        let mut current = &joint;
        while let Some(parent) = parents.get(current) {
            depth += 1;
            if depth > limit {
                return Err(CalibrationError::CyclicHierarchy(name(&joint)));
            }
            current = parent;
        }
        with_depth.push((depth, joint));
    }
    with_depth.sort();
    Ok(with_depth.into_iter().map(|(_, joint)| joint).collect())
}

impl<K: Ord + Clone + Debug> Calibration<K> {
    /// Calibrates: the posture's joint world rotations and each bound sensor's orientation at
    /// the same instant (`S_cal`, in the device frame).
    pub fn calibrate(
        setup: &CalibrationSetup<K>,
        posture_world: &BTreeMap<K, DQuat>,
        sensor_orientations: &BTreeMap<SensorId, DQuat>,
    ) -> Result<Self, CalibrationError> {
        let up = setup.world_up;
        if !up.is_finite() || up.length_squared() < 1e-12 {
            return Err(CalibrationError::BadUpAxis);
        }
        let world_from_device =
            check_unit(setup.world_from_device, || "world_from_device".to_owned())?;
        let joint_order = parents_first(&setup.parents, posture_world.keys().cloned())?;
        let world_of = |joint: &K| -> Result<DQuat, CalibrationError> {
            let q = posture_world
                .get(joint)
                .copied()
                .ok_or_else(|| CalibrationError::MissingJointRotation(name(joint)))?;
            check_unit(q, || name(joint))
        };
        let mut seen_sensors = BTreeSet::new();
        let mut driven_joints = BTreeSet::new();
        let mut sensors = Vec::with_capacity(setup.bindings.len());
        for binding in &setup.bindings {
            let sensor = binding.sensor;
            if !seen_sensors.insert(sensor) {
                return Err(CalibrationError::SensorBoundTwice(sensor));
            }
            let reading = sensor_orientations
                .get(&sensor)
                .copied()
                .ok_or(CalibrationError::MissingSensorReading(sensor))?;
            let reading = check_unit(reading, || format!("sensor {sensor:?}"))?;
            let world_from_sensor = world_from_device * reading;
            let (driven, joint_world_at_calibration) = match &binding.target {
                SensorTarget::Joint(joint) => {
                    if !driven_joints.insert(joint.clone()) {
                        return Err(CalibrationError::JointDrivenTwice(name(joint)));
                    }
                    let joint_world = world_of(joint)?;
                    let sensor_to_joint = world_from_sensor.inverse() * joint_world;
                    (
                        Driven::Joint {
                            joint: joint.clone(),
                            sensor_to_joint,
                        },
                        joint_world,
                    )
                }
                SensorTarget::Chain(chain) => {
                    let Some(((first, _), (tip, _))) = chain.first().zip(chain.last()) else {
                        return Err(CalibrationError::EmptyChain(sensor));
                    };
                    let sum: f64 = chain.iter().map(|(_, w)| w).sum();
                    let weights_ok = chain.iter().all(|(_, w)| w.is_finite() && *w >= 0.0);
                    if !weights_ok || (sum - 1.0).abs() > 1e-6 {
                        return Err(CalibrationError::BadWeights { sensor, sum });
                    }
                    for pair in chain.windows(2) {
                        if let [(parent, _), (child, _)] = pair
                            && setup.parents.get(child) != Some(parent)
                        {
                            return Err(CalibrationError::NotAChain {
                                sensor,
                                child: name(child),
                                expected_parent: name(parent),
                            });
                        }
                    }
                    for (joint, _) in chain {
                        if !driven_joints.insert(joint.clone()) {
                            return Err(CalibrationError::JointDrivenTwice(name(joint)));
                        }
                    }
                    let chain_parent = setup.parents.get(first).cloned();
                    let parent_world = match &chain_parent {
                        Some(parent) => world_of(parent)?,
                        None => DQuat::IDENTITY,
                    };
                    let tip_world = world_of(tip)?;
                    let mut cumulative = 0.0;
                    let mut cumulative_weights = Vec::with_capacity(chain.len());
                    let mut joint_in_parent_at_calibration = Vec::with_capacity(chain.len());
                    for (joint, weight) in chain {
                        cumulative += weight;
                        cumulative_weights.push(cumulative);
                        joint_in_parent_at_calibration
                            .push(parent_world.inverse() * world_of(joint)?);
                    }
                    if let Some(last) = cumulative_weights.last_mut() {
                        *last = 1.0;
                    }
                    let driven = Driven::Chain {
                        joints: chain.iter().map(|(joint, _)| joint.clone()).collect(),
                        cumulative_weights,
                        sensor_to_tip: world_from_sensor.inverse() * tip_world,
                        chain_parent,
                        joint_in_parent_at_calibration,
                    };
                    (driven, tip_world)
                }
            };
            sensors.push(CalibratedSensor {
                sensor,
                driven,
                joint_world_at_calibration,
                heading_correction: DQuat::IDENTITY,
            });
        }
        Ok(Calibration {
            world_from_device,
            world_up: up.normalize(),
            parents: setup.parents.clone(),
            joint_order,
            sensors,
        })
    }

    /// The sensors this calibration uses.
    pub fn sensors(&self) -> impl Iterator<Item = SensorId> + '_ {
        self.sensors.iter().map(|s| s.sensor)
    }

    /// `M_sj` of a sensor (to the tip joint for chains).
    pub fn sensor_to_joint(&self, sensor: SensorId) -> Option<DQuat> {
        self.sensors
            .iter()
            .find(|s| s.sensor == sensor)
            .map(|s| match &s.driven {
                Driven::Joint {
                    sensor_to_joint, ..
                } => *sensor_to_joint,
                Driven::Chain { sensor_to_tip, .. } => *sensor_to_tip,
            })
    }

    fn measured_world(&self, calibrated: &CalibratedSensor<K>, reading: DQuat) -> DQuat {
        let sensor_to_joint = match &calibrated.driven {
            Driven::Joint {
                sensor_to_joint, ..
            } => *sensor_to_joint,
            Driven::Chain { sensor_to_tip, .. } => *sensor_to_tip,
        };
        (calibrated.heading_correction * self.world_from_device * reading * sensor_to_joint)
            .normalize()
    }

    /// Heading (yaw) reset: with the performer back in the calibration posture, rotates each
    /// sensor's joint about the world up axis so that its heading matches the calibration
    /// posture again. Pitch and roll are untouched. Sensors without a reading keep their
    /// correction.
    pub fn reset_heading(&mut self, sensor_orientations: &BTreeMap<SensorId, DQuat>) {
        let up = self.world_up;
        let world_from_device = self.world_from_device;
        for calibrated in &mut self.sensors {
            let Some(reading) = sensor_orientations.get(&calibrated.sensor) else {
                continue;
            };
            if !reading.is_finite() || reading.length() < 1e-9 {
                continue;
            }
            let sensor_to_joint = match &calibrated.driven {
                Driven::Joint {
                    sensor_to_joint, ..
                } => *sensor_to_joint,
                Driven::Chain { sensor_to_tip, .. } => *sensor_to_tip,
            };
            let uncorrected = world_from_device * reading.normalize() * sensor_to_joint;
            let current = heading_of(uncorrected, up);
            let wanted = heading_of(calibrated.joint_world_at_calibration, up);
            calibrated.heading_correction = (wanted * current.inverse()).normalize();
        }
    }

    /// Forgets heading corrections.
    pub fn clear_heading(&mut self) {
        for calibrated in &mut self.sensors {
            calibrated.heading_correction = DQuat::IDENTITY;
        }
    }

    /// World rotations of every joint after applying the sensors: driven joints follow their
    /// sensors, other joints keep their local rotation from `posture_world` (the current
    /// posture's world rotations). Joints missing from `posture_world` get an identity local
    /// rotation.
    pub fn world_rotations(
        &self,
        sensor_orientations: &BTreeMap<SensorId, DQuat>,
        posture_world: &BTreeMap<K, DQuat>,
    ) -> BTreeMap<K, DQuat> {
        let posture_local = |joint: &K| -> DQuat {
            let Some(world) = posture_world.get(joint) else {
                return DQuat::IDENTITY;
            };
            let parent_world = self
                .parents
                .get(joint)
                .and_then(|parent| posture_world.get(parent))
                .copied()
                .unwrap_or(DQuat::IDENTITY);
            parent_world.inverse() * *world
        };
        // Which sensor (and chain position) drives each joint.
        let mut driver: BTreeMap<&K, (&CalibratedSensor<K>, usize)> = BTreeMap::new();
        let mut tip_world: BTreeMap<SensorId, DQuat> = BTreeMap::new();
        for calibrated in &self.sensors {
            let Some(reading) = sensor_orientations.get(&calibrated.sensor) else {
                continue;
            };
            if !reading.is_finite() || reading.length() < 1e-9 {
                continue;
            }
            tip_world.insert(
                calibrated.sensor,
                self.measured_world(calibrated, reading.normalize()),
            );
            match &calibrated.driven {
                Driven::Joint { joint, .. } => {
                    driver.insert(joint, (calibrated, 0));
                }
                Driven::Chain { joints, .. } => {
                    for (index, joint) in joints.iter().enumerate() {
                        driver.insert(joint, (calibrated, index));
                    }
                }
            }
        }
        let mut world: BTreeMap<K, DQuat> = BTreeMap::new();
        for joint in &self.joint_order {
            let parent_world = |world: &BTreeMap<K, DQuat>, joint: &K| {
                self.parents
                    .get(joint)
                    .and_then(|parent| world.get(parent))
                    .copied()
                    .unwrap_or(DQuat::IDENTITY)
            };
            let rotation = match driver.get(joint) {
                None => parent_world(&world, joint) * posture_local(joint),
                Some((calibrated, index)) => {
                    let measured = tip_world
                        .get(&calibrated.sensor)
                        .copied()
                        .unwrap_or_default();
                    match &calibrated.driven {
                        Driven::Joint { .. } => measured,
                        Driven::Chain {
                            cumulative_weights,
                            chain_parent,
                            joint_in_parent_at_calibration,
                            ..
                        } => {
                            let chain_parent_world = chain_parent
                                .as_ref()
                                .and_then(|parent| world.get(parent))
                                .copied()
                                .unwrap_or(DQuat::IDENTITY);
                            let tip_in_parent_at_calibration = joint_in_parent_at_calibration
                                .last()
                                .copied()
                                .unwrap_or_default();
                            let difference = chain_parent_world.inverse()
                                * measured
                                * tip_in_parent_at_calibration.inverse();
                            let fraction = cumulative_weights.get(*index).copied().unwrap_or(1.0);
                            let rest = joint_in_parent_at_calibration
                                .get(*index)
                                .copied()
                                .unwrap_or_default();
                            chain_parent_world * rotation_fraction(difference, fraction) * rest
                        }
                    }
                }
            };
            world.insert(joint.clone(), rotation.normalize());
        }
        world
    }

    /// Local rotations (`J_parent^-1 * J`) of the joints driven by sensors that have a reading;
    /// every other joint keeps its local rotation in the posture.
    pub fn local_rotations(
        &self,
        sensor_orientations: &BTreeMap<SensorId, DQuat>,
        posture_world: &BTreeMap<K, DQuat>,
    ) -> BTreeMap<K, DQuat> {
        let world = self.world_rotations(sensor_orientations, posture_world);
        let mut locals = BTreeMap::new();
        for calibrated in &self.sensors {
            if !sensor_orientations.contains_key(&calibrated.sensor) {
                continue;
            }
            let joints: Vec<&K> = match &calibrated.driven {
                Driven::Joint { joint, .. } => vec![joint],
                Driven::Chain { joints, .. } => joints.iter().collect(),
            };
            for joint in joints {
                let Some(joint_world) = world.get(joint) else {
                    continue;
                };
                let parent_world = self
                    .parents
                    .get(joint)
                    .and_then(|parent| world.get(parent))
                    .copied()
                    .unwrap_or(DQuat::IDENTITY);
                locals.insert(
                    joint.clone(),
                    (parent_world.inverse() * *joint_world).normalize(),
                );
            }
        }
        locals
    }
}

/// The latest orientation of each sensor in a batch of samples.
pub fn latest_orientations(samples: &[Sample]) -> BTreeMap<SensorId, DQuat> {
    let mut latest = BTreeMap::new();
    for sample in samples {
        if let Some(q) = sample.orientation {
            latest.insert(sample.sensor, q);
        }
    }
    latest
}
