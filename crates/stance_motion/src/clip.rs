//! A motion clip on its own skeleton.

use glam::{DQuat, DVec3};
use stance_hanim::{HumanoidSkeleton, Mapping, SourceJoint};
use stance_ik::Posture;

/// One joint of a clip's skeleton.
#[derive(Debug, Clone, PartialEq)]
pub struct ClipJoint {
    /// The name in the source file.
    pub name: String,
    /// Index of the parent (always smaller than this joint's); `None` for the root.
    pub parent: Option<usize>,
    /// Rest offset from the parent joint (metres, H-Anim frame; for the root its rest
    /// position in the world).
    pub offset: DVec3,
}

/// One frame: a local transform per joint, in joint order.
#[derive(Debug, Clone, PartialEq)]
pub struct ClipFrame {
    /// Local translation of each joint from its parent (metres; equal to the joint's
    /// offset unless the joint has position channels; for the root, its world position).
    pub translations: Vec<DVec3>,
    /// Local rotation of each joint (`parent_from_joint`, relative to the rest frame, which
    /// is parallel to the world).
    pub rotations: Vec<DQuat>,
}

/// A motion clip: frames at a fixed rate on the clip's skeleton, mapped onto H-Anim.
#[derive(Debug, Clone, PartialEq)]
pub struct Clip {
    /// A name (the file's stem).
    pub name: String,
    /// Seconds per frame (BVH `Frame Time`), > 0.
    pub frame_time: f64,
    /// The skeleton, parents before children.
    pub joints: Vec<ClipJoint>,
    /// The frames.
    pub frames: Vec<ClipFrame>,
    /// Which joint is which H-Anim joint (source joint index = clip joint index).
    pub mapping: Mapping,
    /// What the reader noticed and did (units detected, frame count corrected...).
    pub notes: Vec<String>,
}

/// Errors of clip operations.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ClipError {
    /// A frame's joint count differs from the skeleton's.
    #[error("frame {frame} has {got} joints, the skeleton {expected}")]
    FrameSize {
        /// Frame index.
        frame: usize,
        /// Joints in the skeleton.
        expected: usize,
        /// Joints in the frame.
        got: usize,
    },
    /// A parent index is not before its child.
    #[error("joint {0} ('{1}') has a parent that does not come before it")]
    Parent(usize, String),
    /// A number is not finite.
    #[error("{0} is not finite")]
    NotFinite(String),
    /// The frame time is not positive.
    #[error("the frame time must be positive and finite, got {0}")]
    FrameTime(f64),
}

impl Clip {
    /// A clip of postures of a solver skeleton (a sensor recording, keyframes baked, a
    /// retargeted clip): joints with their H-Anim names, frames from the postures.
    pub fn from_postures(
        name: &str,
        skeleton: &HumanoidSkeleton,
        postures: &[Posture],
        frame_time: f64,
    ) -> Self {
        let s = &skeleton.skeleton;
        let joints: Vec<ClipJoint> = s
            .joints()
            .iter()
            .map(|j| ClipJoint {
                name: j.name.clone(),
                parent: j.parent,
                offset: j.offset,
            })
            .collect();
        let frames = postures
            .iter()
            .map(|p| ClipFrame {
                translations: (0..joints.len())
                    .map(|k| joints[k].offset + p.translation(s, k))
                    .collect(),
                rotations: (0..joints.len()).map(|k| p.local_rotation(s, k)).collect(),
            })
            .collect();
        let mut clip = Self {
            name: name.to_owned(),
            frame_time,
            joints,
            frames,
            mapping: Mapping::empty(0),
            notes: Vec::new(),
        };
        clip.mapping = Mapping::auto(&clip.source_joints(), &[], false);
        clip
    }

    /// A clip at a fixed rate from postures sampled at irregular times (a sensor recording,
    /// a live session captured frame by frame): `samples` as `(seconds, posture)` in time
    /// order, resampled every `frame_time` from the first sample to the last, each joint's
    /// rotation interpolated by slerp and the root's translation linearly.
    pub fn from_samples(
        name: &str,
        skeleton: &HumanoidSkeleton,
        samples: &[(f64, Posture)],
        frame_time: f64,
    ) -> Result<Self, ClipError> {
        if !(frame_time.is_finite() && frame_time > 0.0) {
            return Err(ClipError::FrameTime(frame_time));
        }
        let (Some(first), Some(last)) = (samples.first(), samples.last()) else {
            return Ok(Self::from_postures(name, skeleton, &[], frame_time));
        };
        let span = last.0 - first.0;
        if !span.is_finite() || span < 0.0 {
            return Err(ClipError::NotFinite("the sample times".into()));
        }
        let count = (span / frame_time + 1e-9).floor() as usize + 1;
        let s = &skeleton.skeleton;
        let mut postures = Vec::with_capacity(count);
        let mut k = 0;
        for f in 0..count {
            let t = first.0 + f as f64 * frame_time;
            while k + 2 < samples.len() + 1 && k + 1 < samples.len() && samples[k + 1].0 < t {
                k += 1;
            }
            let a = &samples[k];
            let b = samples.get(k + 1).unwrap_or(a);
            let u = if b.0 > a.0 {
                ((t - a.0) / (b.0 - a.0)).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let rotations: Vec<_> = (0..s.joint_count())
                .map(|j| a.1.local_rotation(s, j).slerp(b.1.local_rotation(s, j), u))
                .collect();
            let root = a.1.translation(s, 0).lerp(b.1.translation(s, 0), u);
            let posture = Posture::from_rotations(s, root, &rotations)
                .map_err(|e| ClipError::NotFinite(format!("frame {f}: {e}")))?;
            postures.push(posture);
        }
        Ok(Self::from_postures(name, skeleton, &postures, frame_time))
    }

    /// Number of frames.
    pub fn frame_count(&self) -> usize {
        self.frames.len()
    }

    /// Frames per second.
    pub fn fps(&self) -> f64 {
        1.0 / self.frame_time
    }

    /// Duration in seconds (`frame_count * frame_time`, BVH's convention).
    pub fn duration(&self) -> f64 {
        self.frames.len() as f64 * self.frame_time
    }

    /// Checks the structure: parents first, frame sizes, finite numbers, frame time.
    pub fn validate(&self) -> Result<(), ClipError> {
        if !(self.frame_time.is_finite() && self.frame_time > 0.0) {
            return Err(ClipError::FrameTime(self.frame_time));
        }
        for (i, j) in self.joints.iter().enumerate() {
            if j.parent.is_some_and(|p| p >= i) || (i > 0 && j.parent.is_none()) {
                return Err(ClipError::Parent(i, j.name.clone()));
            }
            if !j.offset.is_finite() {
                return Err(ClipError::NotFinite(format!("the offset of '{}'", j.name)));
            }
        }
        let n = self.joints.len();
        for (f, frame) in self.frames.iter().enumerate() {
            for got in [frame.translations.len(), frame.rotations.len()] {
                if got != n {
                    return Err(ClipError::FrameSize {
                        frame: f,
                        expected: n,
                        got,
                    });
                }
            }
            if !frame.translations.iter().all(|t| t.is_finite())
                || !frame.rotations.iter().all(|q| q.is_finite())
            {
                return Err(ClipError::NotFinite(format!("frame {f}")));
            }
        }
        Ok(())
    }

    /// The rest frame: offsets and identity rotations.
    pub fn rest_frame(&self) -> ClipFrame {
        ClipFrame {
            translations: self.joints.iter().map(|j| j.offset).collect(),
            rotations: vec![DQuat::IDENTITY; self.joints.len()],
        }
    }

    /// World rotation and position of every joint in `frame` (forward kinematics).
    pub fn world(&self, frame: &ClipFrame) -> Vec<(DQuat, DVec3)> {
        let mut out: Vec<(DQuat, DVec3)> = Vec::with_capacity(self.joints.len());
        for (i, j) in self.joints.iter().enumerate() {
            let t = frame.translations.get(i).copied().unwrap_or(j.offset);
            let r = frame.rotations.get(i).copied().unwrap_or(DQuat::IDENTITY);
            let w = match j.parent.and_then(|p| out.get(p)) {
                Some(&(pr, pp)) => ((pr * r).normalize(), pp + pr * t),
                None => (r.normalize(), t),
            };
            out.push(w);
        }
        out
    }

    /// The same motion on a skeleton whose rest pose is frame `f`'s pose, with joint frames
    /// parallel to the world there: for files whose rest pose is no pose (a Rokoko export's
    /// bones all laid along their own X axes), `f`'s offsets become `G_parent(f) o`, each
    /// world rotation `G(t)` becomes `G(t) G(f)⁻¹`, so that every frame's joint positions stay
    /// where they were. Nothing changes when `f` is not a frame.
    pub fn rest_on_frame(&mut self, f: usize) {
        let Some(at) = self.frames.get(f).map(|fr| self.world(fr)) else {
            return;
        };
        let posed = |k: usize| at.get(k).map_or(DQuat::IDENTITY, |w| w.0);
        let parent_rotation = |k: usize| {
            self.joints
                .get(k)
                .and_then(|j| j.parent)
                .map_or(DQuat::IDENTITY, posed)
        };
        let turns: Vec<DQuat> = (0..self.joints.len()).map(parent_rotation).collect();
        for frame in &mut self.frames {
            let world = {
                let mut out: Vec<DQuat> = Vec::with_capacity(self.joints.len());
                for (k, j) in self.joints.iter().enumerate() {
                    let r = frame.rotations.get(k).copied().unwrap_or(DQuat::IDENTITY);
                    let w = j
                        .parent
                        .and_then(|p| out.get(p).copied())
                        .map_or(r, |p| p * r);
                    out.push(w.normalize());
                }
                out
            };
            let new_world: Vec<DQuat> = world
                .iter()
                .enumerate()
                .map(|(k, w)| (*w * posed(k).inverse()).normalize())
                .collect();
            for (k, j) in self.joints.iter().enumerate() {
                let parent = j.parent.and_then(|p| new_world.get(p).copied());
                if let Some(q) = frame.rotations.get_mut(k) {
                    *q = parent.map_or(new_world[k], |p| (p.inverse() * new_world[k]).normalize());
                }
                if j.parent.is_some()
                    && let Some(t) = frame.translations.get_mut(k)
                {
                    *t = turns[k] * *t;
                }
            }
        }
        for (k, j) in self.joints.iter_mut().enumerate() {
            if j.parent.is_some() {
                j.offset = turns[k] * j.offset;
            }
        }
    }

    /// World positions of every joint at rest.
    pub fn rest_positions(&self) -> Vec<DVec3> {
        self.world(&self.rest_frame())
            .into_iter()
            .map(|(_, p)| p)
            .collect()
    }

    /// The joints as the H-Anim mapper sees them (rest positions).
    pub fn source_joints(&self) -> Vec<SourceJoint> {
        self.joints
            .iter()
            .zip(self.rest_positions())
            .map(|(j, position)| SourceJoint {
                name: j.name.clone(),
                parent: j.parent,
                position,
            })
            .collect()
    }

    /// Index of the clip joint mapped to an H-Anim joint.
    pub fn joint_of(&self, hanim: &str) -> Option<usize> {
        self.mapping
            .source_of(hanim)
            .filter(|&i| i < self.joints.len())
    }
}
