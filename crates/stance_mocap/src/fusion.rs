//! Orientation from a gyroscope and an accelerometer: Madgwick's gradient-descent filter
//! (IMU variant, no magnetometer).
//!
//! Written here rather than taken from the `ahrs` crate: that crate brings nalgebra and its
//! own quaternion type, while this filter is forty lines on glam, has no allocation and is
//! trivially wasm-clean. Heading (yaw about the earth's up axis) is not observable without a
//! magnetometer and drifts slowly; the calibration's heading reset corrects it.
//!
//! Frames: the orientation maps sensor vectors into an earth frame whose +Z points up
//! (an accelerometer at rest reads +9.81 along the sensor axis that points up).

use glam::{DQuat, DVec3};
use serde::{Deserialize, Serialize};

/// Filter settings.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct MadgwickSettings {
    /// Gradient step gain (rad/s). Larger trusts the accelerometer more: faster tilt
    /// correction, more noise. Madgwick suggests sqrt(3/4) * gyro noise; 0.05..0.1 suits
    /// consumer IMUs.
    pub beta: f64,
    /// Accelerometer readings whose magnitude differs from gravity by more than this fraction
    /// are ignored (the sensor is being shaken).
    pub accel_rejection: f64,
}

impl Default for MadgwickSettings {
    fn default() -> Self {
        MadgwickSettings {
            beta: 0.08,
            accel_rejection: 0.3,
        }
    }
}

/// Standard gravity, m/s².
pub const STANDARD_GRAVITY: f64 = 9.80665;

/// Madgwick IMU filter state.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Madgwick {
    settings: MadgwickSettings,
    earth_from_sensor: Option<DQuat>,
}

impl Madgwick {
    /// A filter with these settings and no estimate yet.
    pub fn new(settings: MadgwickSettings) -> Self {
        Madgwick {
            settings,
            earth_from_sensor: None,
        }
    }

    /// Current estimate (None before the first update).
    pub fn orientation(&self) -> Option<DQuat> {
        self.earth_from_sensor
    }

    /// Forgets the estimate: the next update aligns with gravity again.
    pub fn reset(&mut self) {
        self.earth_from_sensor = None;
    }

    /// Advances the filter by `dt_secs` with the angular velocity (sensor frame, rad/s) and the
    /// accelerometer reading (sensor frame, m/s²). The first call aligns the estimate with
    /// gravity at once, so there is no slow start.
    pub fn update(&mut self, gyro_radps: DVec3, accel: DVec3, dt_secs: f64) -> DQuat {
        let accel_ok = accel.is_finite() && accel.length_squared() > 1e-12;
        let gyro = if gyro_radps.is_finite() {
            gyro_radps
        } else {
            DVec3::ZERO
        };
        let dt = if dt_secs.is_finite() {
            dt_secs.clamp(0.0, 0.5)
        } else {
            0.0
        };
        let q = match self.earth_from_sensor {
            Some(q) => q,
            None => {
                let initial = if accel_ok {
                    DQuat::from_rotation_arc(accel.normalize(), DVec3::Z)
                } else {
                    DQuat::IDENTITY
                };
                self.earth_from_sensor = Some(initial);
                return initial;
            }
        };
        let (q0, q1, q2, q3) = (q.w, q.x, q.y, q.z);
        // Rate of change from the gyroscope: q_dot = 0.5 * q * (0, gyro).
        let mut rate = q * DQuat::from_xyzw(gyro.x, gyro.y, gyro.z, 0.0) * 0.5;
        let magnitude_ok = accel_ok && {
            (accel.length() / STANDARD_GRAVITY - 1.0).abs() <= self.settings.accel_rejection
        };
        if magnitude_ok {
            let a = accel.normalize();
            // Objective: the earth's up axis seen in the sensor frame minus the measurement.
            let f1 = 2.0 * (q1 * q3 - q0 * q2) - a.x;
            let f2 = 2.0 * (q0 * q1 + q2 * q3) - a.y;
            let f3 = 2.0 * (0.5 - q1 * q1 - q2 * q2) - a.z;
            // Gradient J^T f.
            let s0 = -2.0 * q2 * f1 + 2.0 * q1 * f2;
            let s1 = 2.0 * q3 * f1 + 2.0 * q0 * f2 - 4.0 * q1 * f3;
            let s2 = -2.0 * q0 * f1 + 2.0 * q3 * f2 - 4.0 * q2 * f3;
            let s3 = 2.0 * q1 * f1 + 2.0 * q2 * f2;
            let step = DQuat::from_xyzw(s1, s2, s3, s0);
            let norm = step.length();
            if norm > 1e-12 && norm.is_finite() {
                rate -= step * (self.settings.beta / norm);
            }
        }
        let next = q + rate * dt;
        let next = if next.is_finite() && next.length() > 1e-9 {
            next.normalize()
        } else {
            q
        };
        self.earth_from_sensor = Some(next);
        next
    }
}
