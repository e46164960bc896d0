//! Motion: clips of a humanoid over time and their re-use on other bodies (Boulic &
//! Baerlocher, section 2.2: the motion adapted to other characters and other levels of
//! articulation through constraints active over time windows, with priorities among them).
//!
//! - [`Clip`]: frames of local joint transforms on the clip's own skeleton, in the H-Anim
//!   frame (metres, +Y up, +Z front, +X the body's left), with the skeleton's mapping onto
//!   H-Anim 2.0 names.
//! - [`bvh`]: BVH in ([`read_bvh`]: the dialect quirks of real files, units and axes found
//!   from the skeleton, names mapped onto H-Anim, errors naming the line and field, sizes
//!   bounded by [`BvhLimits`]) and out ([`write_bvh`]: H-Anim names, any [`EulerOrder`],
//!   any unit). See `docs/motion-formats.md`.
//!
//! Like `stance_ik`, joint frames are parallel to the world at rest (BVH's convention too):
//! `world_from_joint = world_from_parent * T(translation) * R(rotation)`, the rest pose
//! having every translation equal to the joint's offset and every rotation the identity.

#![warn(missing_docs)]

pub mod bvh;
pub mod clip;

pub use bvh::{BvhError, BvhLimits, BvhWriteOptions, EulerOrder, read_bvh, write_bvh};
pub use clip::{Clip, ClipError, ClipFrame, ClipJoint};
pub mod contacts;
pub mod retarget;

pub use contacts::{Contact, ContactPart, ContactSettings};
pub use retarget::{MotionError, RestMatch, RetargetOptions, Retargeted, Retargeting, retarget};
