//! Errors of the kinematics and solver API.

use thiserror::Error;

/// Everything that can be wrong with a skeleton, a posture or a task.
///
/// Not converging is *not* an error: the solver reports it in [`crate::SolveReport`].
#[derive(Debug, Clone, PartialEq, Error)]
pub enum IkError {
    /// Two joints share a name.
    #[error("duplicate joint name `{0}`")]
    DuplicateJoint(String),
    /// A joint names a parent that does not exist.
    #[error("joint `{joint}` has unknown parent `{parent}`")]
    UnknownParent {
        /// The joint whose parent is missing.
        joint: String,
        /// The missing parent name.
        parent: String,
    },
    /// The parent relation contains a cycle (so some joints never reach a root).
    #[error("the parent relation has a cycle through joint `{0}`")]
    Cycle(String),
    /// The skeleton has no root, or more than one.
    #[error("a skeleton needs exactly one root joint (parent null), found {0}")]
    RootCount(usize),
    /// The skeleton has no joints.
    #[error("the skeleton has no joints")]
    Empty,
    /// A joint lists the same degree of freedom twice.
    #[error("joint `{joint}` lists DOF `{dof}` twice")]
    DuplicateDof {
        /// The joint.
        joint: String,
        /// The repeated DOF.
        dof: String,
    },
    /// A limit is given for a DOF the joint does not have.
    #[error("joint `{joint}` has a limit for DOF `{dof}` that it does not have")]
    LimitWithoutDof {
        /// The joint.
        joint: String,
        /// The DOF.
        dof: String,
    },
    /// A limit interval is empty or not finite.
    #[error("joint `{joint}`: limit of `{dof}` must be finite with lower <= upper")]
    BadLimit {
        /// The joint.
        joint: String,
        /// The DOF.
        dof: String,
    },
    /// A stiffness is outside [0, 1), or names a DOF the joint lacks (or a translation).
    #[error("joint `{joint}`: stiffness of `{dof}` must be a rotation DOF's, in [0, 1)")]
    BadStiffness {
        /// The joint.
        joint: String,
        /// The DOF.
        dof: String,
    },
    /// A number that must be finite is NaN or infinite.
    #[error("{what} is not finite")]
    NotFinite {
        /// Which value (for example `task 3 target`).
        what: String,
    },
    /// A mass is negative.
    #[error("joint `{0}` has a negative mass")]
    NegativeMass(String),
    /// A name that does not exist in the skeleton.
    #[error("unknown joint `{0}`")]
    UnknownJoint(String),
    /// A posture does not fit the skeleton.
    #[error("posture has {got} values but the skeleton has {expected} DOF")]
    PostureSize {
        /// DOF of the skeleton.
        expected: usize,
        /// Values in the posture.
        got: usize,
    },
    /// A task is malformed (zero axes, zero-length direction, bad weight...).
    #[error("task {index}: {reason}")]
    BadTask {
        /// Index of the task in the list given to the solver.
        index: usize,
        /// What is wrong.
        reason: String,
    },
    /// Three joints that do not form a limb the closed form can solve.
    #[error("not a solvable limb: {0}")]
    BadLimb(String),
    /// A body that [`crate::Bodies`] cannot join or place.
    #[error("body {body}: {reason}")]
    BadBody {
        /// The body's index.
        body: usize,
        /// What is wrong.
        reason: String,
    },
    /// A setting is out of range.
    #[error("setting `{0}` is out of range")]
    BadSetting(&'static str),
}
