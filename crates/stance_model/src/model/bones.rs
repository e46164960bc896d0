//! The posed mannequin's bones: one capsule per bone with the joint that carries it, as the
//! viewport draws and picks them.

use stance_render::{MannequinBone, posed_mannequin_bones};

use crate::posing::PosingSession;

/// The bones of `session`'s body in its current posture.
pub fn posed_bones(session: &PosingSession) -> Vec<MannequinBone> {
    posed_mannequin_bones(session.skeleton(), session.frames())
}
