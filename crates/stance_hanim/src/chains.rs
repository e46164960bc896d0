//! Chains of H-Anim joints that act together, such as the spine joints an upper-back sensor
//! drives.

use stance_ik::Skeleton;

/// The spine joints an upper-back sensor drives, root to tip, with their weights: the
/// contiguous lumbar (`vl*`) and thoracic (`vt*`) joints ending at the highest thoracic joint
/// present; lumbar joints share half of the rotation and thoracic joints the other half
/// (evenly within each group; one group takes all when the other is absent).
pub fn spine_chain(skeleton: &Skeleton) -> Vec<(String, f64)> {
    let joints = skeleton.joints();
    let is_spine = |name: &str| name.starts_with("vl") || name.starts_with("vt");
    // The tip: the spine joint none of whose children is a spine joint, nearest the neck.
    let tip = joints.iter().enumerate().rev().find(|(index, joint)| {
        is_spine(&joint.name)
            && joint.has_rotation()
            && !joints
                .iter()
                .any(|child| child.parent == Some(*index) && is_spine(&child.name))
    });
    let Some((mut index, _)) = tip else {
        return Vec::new();
    };
    let mut chain = Vec::new();
    while let Some(joint) = joints.get(index) {
        if !is_spine(&joint.name) {
            break;
        }
        if joint.has_rotation() {
            chain.push(joint.name.clone());
        }
        match joint.parent {
            Some(parent) => index = parent,
            None => break,
        }
    }
    chain.reverse();
    let lumbar = chain.iter().filter(|name| name.starts_with("vl")).count();
    let thoracic = chain.len() - lumbar;
    let (lumbar_share, thoracic_share) = match (lumbar, thoracic) {
        (0, _) => (0.0, 1.0),
        (_, 0) => (1.0, 0.0),
        _ => (0.5, 0.5),
    };
    chain
        .into_iter()
        .map(|name| {
            let weight = if name.starts_with("vl") {
                lumbar_share / lumbar.max(1) as f64
            } else {
                thoracic_share / thoracic.max(1) as f64
            };
            (name, weight)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::expect_used)]

    use super::*;
    use crate::{LevelOfArticulation, SkeletonOptions, default_skeleton};

    #[test]
    fn the_spine_chain_is_contiguous_and_its_weights_sum_to_one() {
        for loa in LevelOfArticulation::ALL {
            let humanoid = default_skeleton(&SkeletonOptions {
                loa,
                ..SkeletonOptions::default()
            })
            .unwrap();
            let skeleton = &humanoid.skeleton;
            let chain = spine_chain(skeleton);
            if loa == LevelOfArticulation::Loa1 && chain.is_empty() {
                continue;
            }
            assert!(!chain.is_empty(), "{loa:?}");
            let sum: f64 = chain.iter().map(|(_, w)| w).sum();
            assert!((sum - 1.0).abs() < 1e-12, "{loa:?}: {chain:?}");
            for pair in chain.windows(2) {
                let child = skeleton.joint_index(&pair[1].0).unwrap();
                let parent = skeleton.joints()[child].parent.unwrap();
                assert_eq!(
                    skeleton.joints()[parent].name,
                    pair[0].0,
                    "{loa:?}: contiguous"
                );
            }
            let lumbar: f64 = chain
                .iter()
                .filter(|(name, _)| name.starts_with("vl"))
                .map(|(_, w)| w)
                .sum();
            assert!(
                lumbar == 0.0 || lumbar == 1.0 || (lumbar - 0.5).abs() < 1e-12,
                "{loa:?}: lumbar share {lumbar}"
            );
        }
    }
}
