//! The collision task's broad phase: the capsules grouped by branch of the skeleton and the
//! pairs sorted by the groups they join, with the groups' boxes (see [`super::Collision`]).

use glam::DVec3;

use super::Capsule;
use crate::Skeleton;

/// Joints of a branch in one group of the broad phase.
const BRANCH_PIECE: usize = 2;

/// The capsules' groups and the pairs sorted by the groups they join (see [`Collision`]).
#[derive(Debug, Clone, PartialEq, Default)]
pub(super) struct BroadPhase {
    /// Each capsule's group.
    pub(super) group: Vec<usize>,
    pub(super) groups: usize,
    /// The pairs in the order of `runs`.
    pub(super) pairs: Vec<(usize, usize)>,
    /// Two groups and the range of `pairs` that joins them.
    pub(super) runs: Vec<(usize, usize, std::ops::Range<usize>)>,
}

impl BroadPhase {
    /// Groups: each capsule goes with the highest joint of its branch, the lowest ancestor
    /// (or itself) of its joint whose parent has other children or none (a leg from its
    /// hip, an arm from its collarbone, each finger), in pieces of [`BRANCH_PIECE`] joints
    /// down the branch (the thigh and the shank, the upper arm, the forearm and the palm).
    pub(super) fn new(skeleton: &Skeleton, capsules: &[Capsule], pairs: &[(usize, usize)]) -> Self {
        let joints = skeleton.joints();
        let mut children = vec![0usize; joints.len()];
        for joint in joints {
            if let Some(p) = joint.parent.and_then(|p| children.get_mut(p)) {
                *p += 1;
            }
        }
        // The branch's highest joint and how far down it `j` is, in pieces of
        // `BRANCH_PIECE` joints (a long branch's box would hold most of the body).
        let branch = |mut j: usize| {
            let mut depth = 0;
            while let Some(p) = joints.get(j).and_then(|joint| joint.parent) {
                if children.get(p).copied().unwrap_or(0) != 1 {
                    break;
                }
                j = p;
                depth += 1;
            }
            (j, depth / BRANCH_PIECE)
        };
        let mut roots: Vec<(usize, usize)> = Vec::new();
        let group: Vec<usize> = capsules
            .iter()
            .map(|c| {
                let root = branch(c.joint);
                roots.iter().position(|&r| r == root).unwrap_or_else(|| {
                    roots.push(root);
                    roots.len() - 1
                })
            })
            .collect();
        let key = |&(i, j): &(usize, usize)| {
            let (a, b) = (
                group.get(i).copied().unwrap_or(0),
                group.get(j).copied().unwrap_or(0),
            );
            (a.min(b), a.max(b))
        };
        let mut sorted = pairs.to_vec();
        sorted.sort_by_key(key);
        let mut runs: Vec<(usize, usize, std::ops::Range<usize>)> = Vec::new();
        for (k, pair) in sorted.iter().enumerate() {
            let (a, b) = key(pair);
            match runs.last_mut() {
                Some((ra, rb, range)) if (*ra, *rb) == (a, b) => range.end = k + 1,
                _ => runs.push((a, b, k..k + 1)),
            }
        }
        Self {
            group,
            groups: roots.len(),
            pairs: sorted,
            runs,
        }
    }
}

/// An axis-aligned box.
#[derive(Debug, Clone, Copy)]
pub(super) struct Aabb {
    pub(super) min: DVec3,
    pub(super) max: DVec3,
}

impl Aabb {
    pub(super) const EMPTY: Aabb = Aabb {
        min: DVec3::INFINITY,
        max: DVec3::NEG_INFINITY,
    };

    /// The box of a capsule whose axis runs from `a` to `b`.
    pub(super) fn capsule(a: DVec3, b: DVec3, radius: f64) -> Self {
        Self {
            min: a.min(b) - radius,
            max: a.max(b) + radius,
        }
    }

    pub(super) fn union(self, other: Aabb) -> Self {
        Self {
            min: self.min.min(other.min),
            max: self.max.max(other.max),
        }
    }

    /// Whether the boxes come within `reach` of each other along every axis.
    pub(super) fn near(&self, other: &Aabb, reach: f64) -> bool {
        self.min.cmple(other.max + reach).all() && other.min.cmple(self.max + reach).all()
    }
}
