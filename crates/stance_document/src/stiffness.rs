//! A document's joint stiffness: per joint and rotation DOF, a value in [0, 1) (H-Anim's
//! `stiffness`) that replaces the body's anatomical default. The solver weighs a DOF by
//! `1 - stiffness` in its weighted pseudo-inverse: a stiff DOF moves less for the same task.

use stance_ik::Skeleton;

use crate::DocumentError;
use crate::document::PostureValues;

/// Stiffness overrides, in the shape of a posture: `{"joint": {"rx": 0.6, ...}}`.
pub type StiffnessValues = PostureValues;

/// Checks every value: a rotation DOF (`rx ry rz`), finite, in [0, 1). `at` is the path in
/// errors (`stiffness`).
pub fn validate_stiffness(values: &StiffnessValues, at: &str) -> Result<(), DocumentError> {
    for (joint, dofs) in &values.joints {
        for (dof, v) in dofs.iter() {
            let here = format!("{at}.{joint}.{}", dof.name());
            if !dof.is_rotation() {
                return Err(DocumentError::field(
                    here,
                    "stiffness applies to rotation DOF (rx, ry, rz) only",
                ));
            }
            if !(v.is_finite() && (0.0..1.0).contains(&v)) {
                return Err(DocumentError::field(here, "expected a number in [0, 1)"));
            }
        }
    }
    Ok(())
}

/// `skeleton` with the overrides set (every other DOF keeps its stiffness). Errors name the
/// field (`stiffness.vl5.rx: joint `vl5` has no DOF `rx``); the skeleton is left unchanged.
pub fn apply_stiffness(
    values: &StiffnessValues,
    skeleton: &Skeleton,
) -> Result<Skeleton, DocumentError> {
    validate_stiffness(values, "stiffness")?;
    let mut out = skeleton.clone();
    values.for_each_dof(skeleton, "stiffness", |dof, value, there| {
        out.set_stiffness(dof, value)
            .map_err(|e| DocumentError::field(there, e.to_string()))
    })?;
    Ok(out)
}
