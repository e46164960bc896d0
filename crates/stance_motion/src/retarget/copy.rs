//! The plain rotation copy through H-Anim: rest match, world rotations, root motion.

use glam::{DQuat, DVec3};
use serde::{Deserialize, Serialize};
use stance_hanim::HumanoidSkeleton;
use stance_ik::{Frames, Posture, nearest_rotation_vector};

use super::{CONTACT_JOINTS, MotionError, RetargetOptions};
use crate::clip::Clip;

/// How the clip's rest pose is matched with the target's.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum RestMatch {
    /// Each target bone at rest is turned onto the clip's bone at rest (bone directions:
    /// towards the mean of the nearest mapped joints below it on the same side). A T-pose
    /// clip on an A-pose avatar, or the reverse.
    #[default]
    Directions,
    /// Both rest poses are taken to be the same pose.
    Same,
    /// The clip's first frame is the target's rest pose.
    FirstFrame,
}

/// The copy of a clip's frames onto a target skeleton, prepared once.
#[derive(Debug, Clone)]
pub struct RotationCopy {
    /// Per target joint: the clip joint of the same H-Anim name.
    source: Vec<Option<usize>>,
    /// Per target joint: the constant rotation `C·A` (identity where unmapped).
    matched: Vec<DQuat>,
    /// Clip joints of the hips (left, right): the root's path follows their midpoint.
    hips: Option<[usize; 2]>,
    /// Target joints of the hips.
    target_hips: Option<[usize; 2]>,
    /// Where clip positions land in the target's space.
    pub placement: Placement,
    /// What was noticed.
    pub notes: Vec<String>,
}

/// Where clip positions land in the target's space: scaled about the vertical through the
/// origin by hip height, the clip's ankle floor at the target's ankle height.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Placement {
    /// Root motion scale (target hip height over the clip's).
    pub root_scale: f64,
    /// Horizontal root motion scale: the root scale, or the one under which the feet in
    /// contact slide least (see [`crate::retarget()`]).
    pub stride_scale: f64,
    /// The clip's ankle floor: the 5th percentile of its ankles' heights over the motion
    /// (clip metres).
    pub lowest_ankle: f64,
    /// The target's ankle height standing at rest (m): the floor contact height.
    pub ankle_height: f64,
}

impl Placement {
    /// A clip position in the target's space.
    pub fn place(&self, p: DVec3) -> DVec3 {
        DVec3::new(
            self.stride_scale * p.x,
            self.ankle_height + self.root_scale * (p.y - self.lowest_ankle),
            self.stride_scale * p.z,
        )
    }
}

/// Mean rest height of the mapped ankles, from positions by H-Anim name.
fn ankle_height(position: impl Fn(&str) -> Option<DVec3>) -> Option<f64> {
    let ys: Vec<f64> = CONTACT_JOINTS
        .iter()
        .filter_map(|n| position(n))
        .map(|p| p.y)
        .collect();
    (!ys.is_empty()).then(|| ys.iter().sum::<f64>() / ys.len() as f64)
}

impl RotationCopy {
    /// Prepares the copy of `clip` onto `target`.
    pub fn new(
        clip: &Clip,
        target: &HumanoidSkeleton,
        options: &RetargetOptions,
    ) -> Result<Self, MotionError> {
        let skeleton = &target.skeleton;
        let source: Vec<Option<usize>> = target
            .joints
            .iter()
            .map(|j| clip.joint_of(j.hanim))
            .collect();
        if source.iter().all(Option::is_none) {
            return Err(MotionError::NoCommonJoints);
        }
        let target_rest = Frames::new(skeleton, &Posture::rest(skeleton)).joint_position;
        let source_rest = clip.rest_positions();
        let first = clip
            .frames
            .first()
            .map(|f| clip.world(f))
            .unwrap_or_default();
        let source_by_target: Vec<Option<DVec3>> = source
            .iter()
            .map(|s| s.and_then(|s| source_rest.get(s).copied()))
            .collect();
        let bones =
            stance_hanim::rest_match::bone_directions(target, &target_rest, &source_by_target);
        let mut notes = Vec::new();
        let adjust = |k: usize| {
            options
                .adjustments
                .iter()
                .find(|(n, _)| target.joints.get(k).is_some_and(|j| j.hanim == n.as_str()))
                .map_or(DQuat::IDENTITY, |(_, q)| q.normalize())
        };
        let matched: Vec<DQuat> = (0..source.len())
            .map(|k| {
                let c = match (options.rest_match, source[k]) {
                    (_, None) => DQuat::IDENTITY,
                    (RestMatch::Same, Some(_)) => DQuat::IDENTITY,
                    (RestMatch::FirstFrame, Some(s)) => {
                        first.get(s).map_or(DQuat::IDENTITY, |w| w.0.inverse())
                    }
                    (RestMatch::Directions, Some(_)) => {
                        bones.get(k).copied().flatten().unwrap_or(DQuat::IDENTITY)
                    }
                };
                c * adjust(k)
            })
            .collect();
        let unmapped: Vec<&str> = target
            .joints
            .iter()
            .zip(&source)
            .filter(|(j, s)| s.is_none() && j.has_dofs)
            .map(|(j, _)| j.hanim)
            .collect();
        if !unmapped.is_empty() {
            let shown = unmapped.len().min(8);
            notes.push(format!(
                "{} target joint(s) not in the clip move with their parent: {}{}",
                unmapped.len(),
                unmapped[..shown].join(", "),
                if unmapped.len() > shown { ", ..." } else { "" }
            ));
        }
        let by_name = |pos: &[DVec3], idx: &dyn Fn(&str) -> Option<usize>, n: &str| {
            idx(n).and_then(|i| pos.get(i).copied())
        };
        let target_index = |n: &str| skeleton.joint_index(n);
        let clip_index = |n: &str| clip.joint_of(n);
        let ankle_t =
            ankle_height(|n| by_name(&target_rest, &target_index, n)).unwrap_or_else(|| {
                target_rest
                    .iter()
                    .map(|p| p.y)
                    .fold(f64::INFINITY, f64::min)
            });
        let pair = |idx: &dyn Fn(&str) -> Option<usize>| Some([idx("l_hip")?, idx("r_hip")?]);
        let hips = pair(&clip_index);
        let target_hips = pair(&target_index);
        let hip_height =
            |pos: &[DVec3], h: [usize; 2], ankle: f64| (pos[h[0]].y + pos[h[1]].y) * 0.5 - ankle;
        let ankle_s = ankle_height(|n| by_name(&source_rest, &clip_index, n));
        let auto_scale = match (hips, target_hips, ankle_s) {
            (Some(hs), Some(ht), Some(a_s)) => {
                let (s, t) = (
                    hip_height(&source_rest, hs, a_s),
                    hip_height(&target_rest, ht, ankle_t),
                );
                (s > 1e-3 && t > 1e-3).then(|| t / s)
            }
            _ => None,
        };
        let root_scale = options.root_scale.or(auto_scale).unwrap_or_else(|| {
            notes.push("no hips and ankles to measure: root motion copied unscaled".into());
            1.0
        });
        let lowest_ankle = lowest_ankle(clip).unwrap_or(0.0);
        Ok(Self {
            source,
            matched,
            hips,
            target_hips,
            placement: Placement {
                root_scale,
                stride_scale: root_scale,
                lowest_ankle,
                ankle_height: ankle_t,
            },
            notes,
        })
    }

    /// The copy of frame `f` as a posture of the target.
    pub fn frame(
        &self,
        clip: &Clip,
        target: &HumanoidSkeleton,
        f: usize,
    ) -> Result<Posture, MotionError> {
        let skeleton = &target.skeleton;
        let world = clip
            .frames
            .get(f)
            .map(|fr| clip.world(fr))
            .unwrap_or_default();
        let joints = skeleton.joints();
        let mut rotation = vec![DQuat::IDENTITY; joints.len()];
        let mut posture = Posture::rest(skeleton);
        let (lo, hi) = (skeleton.lower_limits(), skeleton.upper_limits());
        let unlimited = DVec3::splat(f64::INFINITY);
        for (k, joint) in joints.iter().enumerate() {
            let parent = joint.parent.map_or(DQuat::IDENTITY, |p| rotation[p]);
            rotation[k] = match self.source[k].and_then(|s| world.get(s)) {
                Some(w) => (w.0 * self.matched[k]).normalize(),
                None => parent,
            };
            let local = parent.inverse() * rotation[k];
            // The rotation's projection onto the joint's DOF (the twist about a hinge's
            // axis), then each DOF clamped into its range as the solver clamps.
            let dofs = joint.rotation_dof.map(|d| d.is_some());
            let r = nearest_rotation_vector(local, dofs, unlimited, unlimited);
            for axis in 0..3 {
                if let Some(d) = joint.rotation_dof[axis] {
                    posture.values_mut()[d] = r[axis].clamp(lo[d], hi[d]);
                }
            }
        }
        self.place_root(&world, target, &mut posture);
        Ok(posture)
    }

    /// Moves the root so that the target's hip midpoint follows the clip's, placed.
    fn place_root(&self, world: &[(DQuat, DVec3)], target: &HumanoidSkeleton, p: &mut Posture) {
        let skeleton = &target.skeleton;
        let goal = match self.hips {
            Some([l, r]) => match (world.get(l), world.get(r)) {
                (Some(a), Some(b)) => self.placement.place((a.1 + b.1) * 0.5),
                _ => return,
            },
            None => match self
                .source
                .first()
                .copied()
                .flatten()
                .and_then(|s| world.get(s))
            {
                Some(w) => self.placement.place(w.1),
                None => return,
            },
        };
        let frames = Frames::new(skeleton, p);
        let now = match self.target_hips {
            Some([l, r]) => (frames.joint_position[l] + frames.joint_position[r]) * 0.5,
            None => frames.joint_position.first().copied().unwrap_or_default(),
        };
        let shift = goal - now;
        if let Some(root) = skeleton.joints().first() {
            for axis in 0..3 {
                if let Some(d) = root.translation_dof[axis] {
                    p.values_mut()[d] += shift[axis];
                }
            }
        }
    }
}

/// The floor of the clip's mapped ankles: the 5th percentile of their heights over the
/// motion (the reference frames at the start left out), so that a T-pose frame at another
/// height or a stray frame does not set it.
fn lowest_ankle(clip: &Clip) -> Option<f64> {
    let ankles: Vec<usize> = CONTACT_JOINTS
        .iter()
        .filter_map(|n| clip.joint_of(n))
        .collect();
    if ankles.is_empty() {
        return None;
    }
    let start = crate::contacts::reference_frames(clip);
    let mut heights: Vec<f64> = clip
        .frames
        .iter()
        .skip(start)
        .flat_map(|f| {
            let w = clip.world(f);
            ankles
                .iter()
                .filter_map(move |&a| w.get(a).map(|x| x.1.y))
                .collect::<Vec<_>>()
        })
        .filter(|y| y.is_finite())
        .collect();
    if heights.is_empty() {
        return None;
    }
    let k = heights.len() / 20;
    Some(*heights.select_nth_unstable_by(k, f64::total_cmp).1)
}
