//! The bone-direction rest match: per joint of a built skeleton, the world rotation that turns
//! its bone at rest onto the bone of another body's joint of the same H-Anim name at that
//! body's rest. Retargeting matches a clip's rest onto a body with it
//! (`stance_motion::RestMatch::Directions`), and the builder matches every avatar's rest onto
//! the H-Anim standard pose with it ([`crate::builder`]: a T-pose avatar's arms are lowered to
//! the sides of the default mannequin), so that a posture means the same pose on every body.
//!
//! A bone goes from the joint to the mean of the nearest joints below it that both bodies
//! have, on its own side (a centre joint looks only at centre joints), each at least 1 mm away
//! in both. The rotation is the shortest arc between the two directions: no twist about the
//! bone is added. A foot's bones (the ankle and below) are matched by their heading alone:
//! both rests stand on flat soles.

use glam::{DQuat, DVec3};

use crate::builder::HumanoidSkeleton;
use crate::names::Side;

/// Per joint of `target`, its children.
fn children(target: &HumanoidSkeleton) -> Vec<Vec<usize>> {
    let joints = target.skeleton.joints();
    let mut out = vec![Vec::new(); joints.len()];
    for (k, j) in joints.iter().enumerate() {
        if let Some(p) = j.parent
            && let Some(siblings) = out.get_mut(p)
        {
            siblings.push(k);
        }
    }
    out
}

/// Per joint `k` of `target`: the shortest rotation taking the target's bone at rest onto the
/// other body's bone (`rotation · target_bone ∥ other_bone`), `None` where the joint has no
/// bone both bodies share (nothing below it, or the other body lacks the joint).
///
/// `target_rest[k]`: the world rest position of target joint `k`; `other_rest[k]`: the rest
/// position of the other body's joint standing for target joint `k` (`None`: it has none).
pub fn bone_directions(
    target: &HumanoidSkeleton,
    target_rest: &[DVec3],
    other_rest: &[Option<DVec3>],
) -> Vec<Option<DQuat>> {
    let kids = children(target);
    let skeleton = &target.skeleton;
    let ankles: Vec<usize> = ["l_talocrural", "r_talocrural"]
        .iter()
        .filter_map(|n| skeleton.joint_index(n))
        .collect();
    let in_foot = |k: usize| ankles.iter().any(|&a| skeleton.is_ancestor_or_self(a, k));
    (0..target.joints.len())
        .map(|k| {
            rest_bone(k, target, &kids, target_rest, other_rest).map(|(t, s)| {
                // Both rests stand on flat soles: a foot's bone is matched by its heading
                // alone (an ankle-to-toe bone slopes down by the foot's own shape, which
                // differs between skeletons).
                let flat = |v: DVec3| DVec3::new(v.x, 0.0, v.z);
                let (t, s) = if in_foot(k) && flat(t).length() > 1e-3 && flat(s).length() > 1e-3 {
                    (flat(t), flat(s))
                } else {
                    (t, s)
                };
                DQuat::from_rotation_arc(t.normalize(), s.normalize())
            })
        })
        .collect()
}

/// The bone of target joint `k` at rest in both bodies (target, other), see the module
/// documentation.
fn rest_bone(
    k: usize,
    target: &HumanoidSkeleton,
    children: &[Vec<usize>],
    target_rest: &[DVec3],
    other_rest: &[Option<DVec3>],
) -> Option<(DVec3, DVec3)> {
    let own_other = (*other_rest.get(k)?)?;
    let own_target = *target_rest.get(k)?;
    let side = Side::of(target.joints.get(k)?.hanim);
    let same_side = |c: &usize| {
        target
            .joints
            .get(*c)
            .is_some_and(|j| Side::of(j.hanim) == side)
    };
    let mut level: Vec<usize> = children.get(k)?.iter().copied().filter(same_side).collect();
    for _ in 0..64 {
        if level.is_empty() {
            break;
        }
        let ends: Vec<(DVec3, DVec3)> = level
            .iter()
            .filter_map(|&c| {
                let d = (*other_rest.get(c)?)? - own_other;
                let t = *target_rest.get(c)? - own_target;
                (t.length() > 1e-3 && d.length() > 1e-3).then_some((t, d))
            })
            .collect();
        if !ends.is_empty() {
            let n = ends.len() as f64;
            let t: DVec3 = ends.iter().map(|e| e.0).sum::<DVec3>() / n;
            let s: DVec3 = ends.iter().map(|e| e.1).sum::<DVec3>() / n;
            return Some((t, s));
        }
        level = level
            .iter()
            .flat_map(|&c| children.get(c).into_iter().flatten().copied())
            .filter(same_side)
            .collect();
    }
    None
}
