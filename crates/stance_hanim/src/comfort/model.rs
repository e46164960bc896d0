//! The comfort of an H-Anim body's posture, measured and as a cost: joint loads due to gravity
//! against each DOF's strength ([`crate::strength`]), joint-range discomfort, and RULA
//! ([`super::rula`]); the [`ComfortModel`] of the comfort task and the [`ComfortReport`] that
//! the editor's comfort panel, `stance comfort` and `stance solve` show.

use stance_ik::comfort::{ComfortModel, ComfortTerms, dof_torques};
use stance_ik::{Frames, Posture, Skeleton};

use super::rula::{RulaReport, RulaSettings, rula, rula_bands};
use crate::AnatomicalAxis;
use crate::strength::{FLAGGED_SHARE, StrengthProfile, dof_strengths};

/// What the comfort cost weighs, and the inputs RULA cannot read from a posture.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ComfortSettings {
    /// Weight of the effort: the sum of squared load shares (default 1).
    pub effort: f64,
    /// Weight of the joint-range discomfort (default 0.1).
    pub range: f64,
    /// Weight of the smooth stand-in for RULA (default 0.5).
    pub rula: f64,
    /// RULA's inputs that are not in the posture (load, muscle use, variant...).
    pub rula_settings: RulaSettings,
    /// The body the strengths are scaled to.
    pub profile: StrengthProfile,
}

impl Default for ComfortSettings {
    fn default() -> Self {
        Self {
            effort: 1.0,
            range: 0.1,
            rula: 0.5,
            rula_settings: RulaSettings::default(),
            profile: StrengthProfile::default(),
        }
    }
}

/// The cost of the comfort task for `skeleton` (H-Anim names; `axes` per joint: see
/// [`crate::strength::built_axes`] and [`crate::strength::aligned_axes`]).
pub fn comfort_model(
    skeleton: &Skeleton,
    axes: &[Vec<AnatomicalAxis>],
    settings: &ComfortSettings,
) -> ComfortModel {
    let profile = StrengthProfile {
        mass_kg: if skeleton.total_mass() > 0.0 {
            skeleton.total_mass()
        } else {
            settings.profile.mass_kg
        },
        ..settings.profile
    };
    ComfortModel {
        effort_weight: settings.effort,
        strength: dof_strengths(skeleton, axes, &profile),
        range_weight: settings.range,
        band_weight: settings.rula,
        bands: rula_bands(skeleton, settings.rula_settings.variant),
    }
}

/// The static load of one joint.
#[derive(Debug, Clone, PartialEq)]
pub struct JointLoad {
    /// H-Anim joint name.
    pub joint: String,
    /// The gravity torque about the joint's DOF axes (N m, the norm over its rotation DOF).
    pub torque_nm: f64,
    /// The largest share of a DOF's maximal voluntary torque (`None`: no strength known).
    pub share: Option<f64>,
    /// `share` above [`FLAGGED_SHARE`] (15 %).
    pub flagged: bool,
}

/// The comfort of a posture.
#[derive(Debug, Clone, PartialEq)]
pub struct ComfortReport {
    /// RULA (`None`: the body lacks a joint it measures).
    pub rula: Option<RulaReport>,
    /// Every joint with rotation DOF, highest share first (then highest torque).
    pub loads: Vec<JointLoad>,
    /// The cost's terms (effort = sum of squared shares).
    pub terms: ComfortTerms,
}

impl ComfortReport {
    /// The `count` joints with the highest loads.
    pub fn highest(&self, count: usize) -> &[JointLoad] {
        &self.loads[..count.min(self.loads.len())]
    }
}

/// Measures `posture`.
pub fn comfort_report(
    skeleton: &Skeleton,
    axes: &[Vec<AnatomicalAxis>],
    posture: &Posture,
    settings: &ComfortSettings,
) -> ComfortReport {
    let frames = Frames::new(skeleton, posture);
    let model = comfort_model(skeleton, axes, settings);
    let torques = dof_torques(skeleton, &frames);
    let mut loads: Vec<JointLoad> = skeleton
        .joints()
        .iter()
        .filter(|j| j.has_rotation())
        .map(|joint| {
            let mut sum_sq = 0.0;
            let mut share: Option<f64> = None;
            for d in joint.dof_range() {
                if !skeleton.dof_kinds()[d].is_rotation() {
                    continue;
                }
                let t = torques[d];
                sum_sq += t * t;
                if let Some(Some(strength)) = model.strength.get(d) {
                    let (s, _) = strength.holding(t).at(posture.values()[d]);
                    let this = t.abs() / s;
                    share = Some(share.map_or(this, |v| v.max(this)));
                }
            }
            JointLoad {
                joint: joint.name.clone(),
                torque_nm: sum_sq.sqrt(),
                share,
                flagged: share.is_some_and(|s| s > FLAGGED_SHARE),
            }
        })
        .collect();
    loads.sort_by(|a, b| {
        b.share
            .unwrap_or(-1.0)
            .total_cmp(&a.share.unwrap_or(-1.0))
            .then(b.torque_nm.total_cmp(&a.torque_nm))
    });
    ComfortReport {
        rula: rula(skeleton, &frames, &settings.rula_settings),
        loads,
        terms: model.terms(skeleton, &frames, posture.values()),
    }
}

#[cfg(test)]
mod tests;
