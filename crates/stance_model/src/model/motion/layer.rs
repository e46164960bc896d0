//! The keys as an additive layer over a base motion (the retargeted clip, or the rest
//! posture without one): per joint a key is the local-rotation delta `q_key · q_base⁻¹` at
//! its frame (and the root translation's delta); between two keys the deltas are slerped
//! with ease (smoothstep of the normalised time), held before the first and after the last.

use glam::{DQuat, DVec3};
use stance_document::{MotionKey, PostureValues, motion::smoothstep};
use stance_hanim::resolve_joint;
use stance_ik::{Posture, Skeleton};

/// One key as deltas from the base at its frame.
#[derive(Debug, Clone)]
pub(crate) struct KeyDelta {
    /// The key's frame.
    pub frame: usize,
    /// Per joint, `q_key · q_base⁻¹`.
    pub rotations: Vec<DQuat>,
    /// The root translation's delta (m).
    pub translation: DVec3,
}

/// The posture of `values` on `skeleton`, leniently: joints or DOF the skeleton lacks are
/// skipped (keys made at another level of articulation still apply where they can).
pub(crate) fn lenient_posture(skeleton: &Skeleton, values: &PostureValues) -> Posture {
    let mut posture = Posture::rest(skeleton);
    for (name, dofs) in &values.joints {
        let Some(joint) = resolve_joint(skeleton, name).and_then(|j| skeleton.joints().get(j))
        else {
            continue;
        };
        for (dof, value) in dofs.iter() {
            if let Some(k) = joint.dofs.iter().position(|&d| d == dof)
                && let Some(slot) = posture.values_mut().get_mut(joint.dof_start + k)
                && value.is_finite()
            {
                *slot = value;
            }
        }
    }
    posture
}

/// The delta of `key` (a whole posture) over `base` (the base posture at its frame).
pub(crate) fn key_delta(
    skeleton: &Skeleton,
    frame: usize,
    key: &Posture,
    base: &Posture,
) -> KeyDelta {
    KeyDelta {
        frame,
        rotations: (0..skeleton.joint_count())
            .map(|j| {
                (key.local_rotation(skeleton, j) * base.local_rotation(skeleton, j).inverse())
                    .normalize()
            })
            .collect(),
        translation: key.translation(skeleton, 0) - base.translation(skeleton, 0),
    }
}

/// `delta` applied on `base`.
pub(crate) fn apply_delta(
    skeleton: &Skeleton,
    base: &Posture,
    rotations: &[DQuat],
    translation: DVec3,
) -> Posture {
    let local: Vec<DQuat> = (0..skeleton.joint_count())
        .map(|j| {
            let delta = rotations.get(j).copied().unwrap_or(DQuat::IDENTITY);
            (delta * base.local_rotation(skeleton, j)).normalize()
        })
        .collect();
    let root = base.translation(skeleton, 0) + translation;
    Posture::from_rotations(skeleton, root, &local).unwrap_or_else(|_| base.clone())
}

/// The deltas at `frame` from the keys (in frame order): eased slerp between the two keys
/// around it, the nearest key's outside them; `None` without keys.
pub(crate) fn delta_at(deltas: &[KeyDelta], frame: usize) -> Option<(Vec<DQuat>, DVec3)> {
    let first = deltas.first()?;
    let last = deltas.last()?;
    if frame <= first.frame {
        return Some((first.rotations.clone(), first.translation));
    }
    if frame >= last.frame {
        return Some((last.rotations.clone(), last.translation));
    }
    let next = deltas.iter().position(|d| d.frame > frame)?;
    let (a, b) = (&deltas[next - 1], &deltas[next]);
    let s = smoothstep((frame - a.frame) as f64 / (b.frame - a.frame) as f64);
    let rotations = a
        .rotations
        .iter()
        .zip(&b.rotations)
        .map(|(qa, qb)| qa.slerp(*qb, s).normalize())
        .collect();
    Some((rotations, a.translation.lerp(b.translation, s)))
}

/// The keys' deltas over the base (`base(frame)`).
pub(crate) fn key_deltas(
    skeleton: &Skeleton,
    keys: &[MotionKey],
    base: impl Fn(usize) -> Posture,
) -> Vec<KeyDelta> {
    keys.iter()
        .map(|key| {
            let posture = lenient_posture(skeleton, &key.posture);
            key_delta(skeleton, key.frame, &posture, &base(key.frame))
        })
        .collect()
}
