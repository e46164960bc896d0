//! Landmarks on the head: where the nose, eyes and ears are on a skeleton that has joints but
//! no face.
//!
//! H-Anim names surface landmarks *feature points*, placed by `Site` objects (ISO/IEC
//! 19774-1:2019 Annex B, after CAESAR and ISO 7250); its LOA 0 table gives their default
//! translations on the default body (H-Anim 1.1 Annex A, "Default Site Translations"), in the
//! same frame and proportions as the default joint centres ([`crate::default_centre`]). The
//! head's sites are held here relative to `skullbase` (the default `skullbase` centre
//! subtracted, left and right averaged into a symmetric head), in the H-Anim frame (+Y up, +Z
//! the front, +X the body's left), metres:
//!
//! | site | default translation (m) | relative to `skullbase` |
//! |---|---|---|
//! | `sellion` (the nasal bridge) | 0.0058 1.6316 0.0852 | (0, 0.0107, 0.0616) |
//! | `l_infraorbitale` (the orbit's lower rim) | 0.0341 1.6171 0.0752 | (±0.0289, -0.0038, 0.0516) |
//! | `r_infraorbitale` | -0.0237 1.6171 0.0752 | |
//! | `l_tragion` (the ear's tragus) | 0.0739 1.6348 0.0282 | (±0.0693, 0.0139, 0.0056) |
//! | `r_tragion` | -0.0646 1.6347 0.0302 | |
//!
//! H-Anim has no site for the pupils or the tip of the nose, which pose keypoints use; they are
//! placed from the sites above by proportions of the face:
//!
//! - a **pupil** is above its `infraorbitale`, at the height of the `sellion` (the line of
//!   the pupils crosses the nasal bridge, about 1.5 cm above the orbit's lower rim);
//! - the **pronasale** (the tip of the nose, a CAESAR landmark) is on the midline 1.5 cm below
//!   the infraorbitale and 2 cm in front of the `sellion` (the nose's projection on an adult
//!   face).
//!
//! H-Anim's default `skullbase` sits almost at the height of the eyes (the `sellion` 1 cm above
//! it). The head Stance draws sits higher on the neck: the default figure's head has its
//! centre 8.5 cm above `skullbase` and 2.5 cm in front of it (`stance_asset`'s generated
//! avatar; the mannequin's head is higher still), as avatars whose head bone is at the top of
//! the neck do. The sites keep H-Anim's layout relative to one another and are moved as one
//! onto that head, [`HEAD_SHIFT_M`] (6 cm up, 4.5 cm forward: the middle of H-Anim's sites,
//! between `skull_tip` and `supramenton`, `sellion` and `nuchale`, onto the figure's head's
//! centre), so that the face's points land on the face drawn.
//!
//! A body of another size scales them by the length from `humanoid_root` to `skullbase` at
//! rest over the default body's. The sites turn and move with `skullbase`: at rest every joint
//! frame is parallel to the world's (a posture of zeros), so an offset in the H-Anim frame is
//! an offset in `skullbase`'s frame.

use glam::DVec3;
use stance_ik::{Effector, Frames, Skeleton};

use crate::names::resolve_joint;

/// A landmark on the head.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum HeadSite {
    /// The tip of the nose.
    Pronasale,
    /// The centre of the left eye's pupil.
    LeftPupil,
    /// The centre of the right eye's pupil.
    RightPupil,
    /// The left ear (H-Anim `l_tragion`).
    LeftTragion,
    /// The right ear (H-Anim `r_tragion`).
    RightTragion,
    /// The nasal bridge (H-Anim `sellion`).
    Sellion,
}

/// `sellion` relative to `skullbase` on the default body (m).
const SELLION_M: DVec3 = DVec3::new(0.0, 0.0107, 0.0616);
/// `l_infraorbitale` relative to `skullbase` (m); the right one is its mirror image.
const INFRAORBITALE_M: DVec3 = DVec3::new(0.0289, -0.0038, 0.0516);
/// `l_tragion` relative to `skullbase` (m); the right one is its mirror image.
const TRAGION_M: DVec3 = DVec3::new(0.0693, 0.0139, 0.0056);
/// How far the head's sites are moved from H-Anim's default head onto the head Stance draws
/// (m, H-Anim frame).
pub const HEAD_SHIFT_M: DVec3 = DVec3::new(0.0, 0.06, 0.045);
/// The tip of the nose below the infraorbitale and in front of the sellion (m).
const NOSE_DROP_M: f64 = 0.015;
const NOSE_PROJECTION_M: f64 = 0.02;

impl HeadSite {
    /// Every site.
    pub const ALL: [HeadSite; 6] = [
        HeadSite::Pronasale,
        HeadSite::LeftPupil,
        HeadSite::RightPupil,
        HeadSite::LeftTragion,
        HeadSite::RightTragion,
        HeadSite::Sellion,
    ];

    /// The name: H-Anim's where it has one (`l_tragion`), else the anthropometric one
    /// (`pronasale`, `l_pupil`).
    pub fn name(self) -> &'static str {
        match self {
            HeadSite::Pronasale => "pronasale",
            HeadSite::LeftPupil => "l_pupil",
            HeadSite::RightPupil => "r_pupil",
            HeadSite::LeftTragion => "l_tragion",
            HeadSite::RightTragion => "r_tragion",
            HeadSite::Sellion => "sellion",
        }
    }

    /// Where the site is relative to `skullbase` on the default body, H-Anim frame (m):
    /// H-Anim's layout moved by [`HEAD_SHIFT_M`].
    pub fn default_offset(self) -> DVec3 {
        self.hanim_offset() + HEAD_SHIFT_M
    }

    /// The way the head's surface faces at the site, H-Anim frame (unit): the ears sideways,
    /// the eyes forward and a little outward (each eye sees its own side), the nose forward.
    pub fn facing(self) -> DVec3 {
        match self {
            HeadSite::Pronasale | HeadSite::Sellion => DVec3::Z,
            HeadSite::LeftPupil => DVec3::new(0.45, 0.0, 0.9).normalize(),
            HeadSite::RightPupil => DVec3::new(-0.45, 0.0, 0.9).normalize(),
            HeadSite::LeftTragion => DVec3::X,
            HeadSite::RightTragion => -DVec3::X,
        }
    }

    /// The site relative to `skullbase` on H-Anim's default head (m).
    fn hanim_offset(self) -> DVec3 {
        let mirror = |v: DVec3| DVec3::new(-v.x, v.y, v.z);
        let pupil = DVec3::new(INFRAORBITALE_M.x, SELLION_M.y, INFRAORBITALE_M.z);
        match self {
            HeadSite::Pronasale => DVec3::new(
                0.0,
                INFRAORBITALE_M.y - NOSE_DROP_M,
                SELLION_M.z + NOSE_PROJECTION_M,
            ),
            HeadSite::LeftPupil => pupil,
            HeadSite::RightPupil => mirror(pupil),
            HeadSite::LeftTragion => TRAGION_M,
            HeadSite::RightTragion => mirror(TRAGION_M),
            HeadSite::Sellion => SELLION_M,
        }
    }
}

/// The head's sites of one skeleton: its `skullbase` and its size against the default body.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HeadSites {
    skullbase: usize,
    scale: f64,
}

impl HeadSites {
    /// The sites of `skeleton`'s head; `None` without a `skullbase` joint.
    pub fn new(skeleton: &Skeleton) -> Option<HeadSites> {
        let skullbase = resolve_joint(skeleton, "skullbase")?;
        Some(HeadSites {
            skullbase,
            scale: body_scale(skeleton, skullbase),
        })
    }

    /// How much larger this body is than the default one (1 for the default skeleton).
    pub fn scale(&self) -> f64 {
        self.scale
    }

    /// The world position of `site` in the posture of `frames` (forward kinematics of the
    /// same skeleton).
    pub fn position(&self, frames: &Frames, site: HeadSite) -> Option<DVec3> {
        let at = self.effector(site);
        (at.joint < frames.joint_position.len()
            && at.joint < frames.world_from_joint_rotation.len())
        .then(|| frames.point(at.joint, at.point))
    }

    /// `site` as a point of the head's segment (`skullbase`'s frame): what
    /// [`HeadSites::position`] places in a posture; a solver task can hold it.
    pub fn effector(&self, site: HeadSite) -> Effector {
        Effector {
            joint: self.skullbase,
            point: site.default_offset() * self.scale,
        }
    }

    /// The world direction the head's surface faces at `site` in the posture of `frames`.
    pub fn facing(&self, frames: &Frames, site: HeadSite) -> Option<DVec3> {
        let rotation = frames.world_from_joint_rotation.get(self.skullbase)?;
        Some(*rotation * site.facing())
    }
}

/// The rest length from `humanoid_root` to `skullbase` over the default body's (1 when it
/// cannot be told).
fn body_scale(skeleton: &Skeleton, skullbase: usize) -> f64 {
    let default_length = || {
        let centre = |name| crate::joint_by_name(name).map(|(_, d)| crate::default_centre(d));
        Some((centre("skullbase")? - centre("humanoid_root")?).length())
    };
    let rest_length = || {
        let root = resolve_joint(skeleton, "humanoid_root")?;
        let rest = Frames::new(skeleton, &stance_ik::Posture::rest(skeleton));
        Some((*rest.joint_position.get(skullbase)? - *rest.joint_position.get(root)?).length())
    };
    match (rest_length(), default_length()) {
        (Some(length), Some(default)) if length > 1e-6 && default > 1e-6 => length / default,
        _ => 1.0,
    }
}

#[cfg(test)]
mod tests {
    #[cfg(target_arch = "wasm32")]
    use wasm_bindgen_test::wasm_bindgen_test as test;

    use super::*;
    use crate::{LevelOfArticulation, SkeletonOptions, default_skeleton};

    #[test]
    fn the_default_body_puts_the_sites_at_h_anims_default_translations_moved_onto_its_head() {
        // Catches a wrong sign or frame: H-Anim 1.1's `l_tragion` is at 0.0739 1.6348 0.0282,
        // `sellion` at 0.0058 1.6316 0.0852 (the default body stands a few mm off x = 0),
        // each moved by HEAD_SHIFT_M.
        let skeleton = default_skeleton(&SkeletonOptions {
            loa: LevelOfArticulation::Loa1,
            ..SkeletonOptions::default()
        })
        .unwrap()
        .skeleton;
        let sites = HeadSites::new(&skeleton).unwrap();
        assert!((sites.scale() - 1.0).abs() < 1e-9, "{}", sites.scale());
        let rest = Frames::new(&skeleton, &stance_ik::Posture::rest(&skeleton));
        let at = |site| sites.position(&rest, site).unwrap() - HEAD_SHIFT_M;
        let near = |a: DVec3, b: [f64; 3]| (a - DVec3::from_array(b)).length() < 0.004;
        assert!(near(at(HeadSite::LeftTragion), [0.0739, 1.6348, 0.0282]));
        assert!(near(at(HeadSite::RightTragion), [-0.0646, 1.6347, 0.0302]));
        assert!(near(at(HeadSite::Sellion), [0.0058, 1.6316, 0.0852]));
        // The nose in front of the eyes, the eyes in front of the ears, left at +X.
        let nose = at(HeadSite::Pronasale);
        let (left, right) = (at(HeadSite::LeftPupil), at(HeadSite::RightPupil));
        assert!(nose.z > left.z && left.z > at(HeadSite::LeftTragion).z);
        assert!(left.x > right.x && nose.y < left.y);
    }
}
