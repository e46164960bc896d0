//! Joint stiffness in a session: the body's anatomical defaults (kept from when it was built)
//! and the document's overrides, applied to the skeleton the solver works on.

use super::Wake;
use stance_document::{StiffnessValues, apply_stiffness};

use super::{PosingError, PosingSession};

impl PosingSession {
    /// The stiffness overrides of the document (empty: the body's anatomical defaults).
    pub fn stiffness_overrides(&self) -> &StiffnessValues {
        &self.stiffness
    }

    /// The anatomical default stiffness of DOF `dof` (0 for translations).
    pub fn default_stiffness(&self, dof: usize) -> f64 {
        self.anatomical_stiffness.get(dof).copied().unwrap_or(0.0)
    }

    /// Sets rotation DOF `dof`'s stiffness in [0, 1), or back to its anatomical default
    /// (`None`), and wakes the solver. On error the session stays as it was.
    pub fn set_stiffness(&mut self, dof: usize, value: Option<f64>) -> Result<(), PosingError> {
        let skeleton = self.skeleton();
        let Some(&kind) = skeleton.dof_kinds().get(dof) else {
            return Ok(());
        };
        let Some(joint) = skeleton.joints().get(skeleton.dof_joint(dof)) else {
            return Ok(());
        };
        let name = joint.name.clone();
        let mut overrides = self.stiffness.clone();
        match value {
            Some(v) => overrides.set(&name, kind, v),
            None => {
                if let Some(dofs) = overrides.joints.get_mut(&name) {
                    dofs.remove(kind);
                    if dofs.is_empty() {
                        overrides.joints.remove(&name);
                    }
                }
            }
        }
        self.apply_stiffness_overrides(&overrides)?;
        self.wake(Wake::Tasks);
        Ok(())
    }

    /// Replaces the overrides: the skeleton's stiffness becomes the anatomical defaults with
    /// `overrides` set. On error (a joint or DOF the body lacks, a value out of [0, 1)) the
    /// session stays as it was.
    pub(super) fn apply_stiffness_overrides(
        &mut self,
        overrides: &StiffnessValues,
    ) -> Result<(), PosingError> {
        let mut defaults = self.humanoid.skeleton.clone();
        for (d, &s) in self.anatomical_stiffness.iter().enumerate() {
            if defaults.dof_kinds()[d].is_rotation() {
                defaults.set_stiffness(d, s)?;
            }
        }
        self.humanoid.skeleton = apply_stiffness(overrides, &defaults)?;
        self.stiffness = overrides.clone();
        Ok(())
    }
}
