//! Collision avoidance as an inequality: capsules fixed in the joints' frames keep at least
//! `margin` between their surfaces, above the floor (`y = 0`) and off fixed solids (a scene's
//! props: [`Obstacle`]). Each row is one
//! constraint along its line of closest approach: the distance between the surfaces, with an
//! error where it is under the margin. The constraints within [`COLLISION_LOOKAHEAD`] over
//! the margin are the solver's candidates: a step that would bring one inside the margin is
//! taken again with its row at the margin (the surfaces may slide along each other or part,
//! not come closer; the solver's active set). The nearest constraints fill the task's rows,
//! nearest first, up to their number; the level has rows only for the constraints under the
//! margin (none while the body is clear: the level then costs its search alone), each on the
//! DOF that move one point against the other.

use std::sync::Arc;

use glam::DVec3;

use super::obstacle::Obstacle;
use crate::{Frames, Posture, Skeleton};

/// How far past the margin a constraint still counts as a contact (drawn in the editor;
/// the pairs touching at rest closer than the margin and this are left out) (m).
pub const COLLISION_BAND: f64 = 0.002;

/// How far past the margin a row of the solver's level aims (m): a row pushing its surfaces
/// apart, or stopping them, aims there, so that a step's second-order motion does not leave
/// them just inside the margin (half [`COLLISION_BAND`]).
pub const COLLISION_AIM: f64 = 0.5 * COLLISION_BAND;

/// How far past the margin the solver looks for constraints a step may bring inside it (its
/// active set's candidates, see the module's note) (m).
pub const COLLISION_LOOKAHEAD: f64 = 0.05;

/// A collision task's data: the surfaces of the `pairs` of `capsules` (and of the `floor`
/// capsules and the floor `y = 0`) keep at least `margin` apart, `rows` constraints at most.
/// One row per constraint along its line of closest approach, the nearest first: an error
/// where two surfaces are closer than the margin; those within [`COLLISION_LOOKAHEAD`]
/// beyond it join the level only where a step would bring them inside it (they may slide
/// along each other or part, not come closer); the level has no row for the rest.
///
/// The search for the constraints (once per linearisation) is a broad phase on boxes: the
/// capsules are grouped by branch of the skeleton (a leg, an arm, a finger, the spine...;
/// [`Collision::new`]) and the pairs by the two groups they join, so that two groups whose
/// boxes are further apart than the margin and the band skip every pair between them; then
/// each pair's boxes, then its closest points.
#[derive(Debug, Clone, PartialEq)]
pub struct Collision {
    capsules: Arc<[Capsule]>,
    pairs: Arc<[(usize, usize)]>,
    floor: Arc<[usize]>,
    margin: f64,
    rows: usize,
    broad: Arc<BroadPhase>,
    /// Fixed solids the capsules of `against` keep the margin from.
    obstacles: Arc<[Obstacle]>,
    /// The capsules held off the obstacles: those clear of the floor at rest (the feet, which
    /// stand on things, are left to the tasks that place them).
    against: Arc<[usize]>,
    /// Capsules left off one solid: a hand or foot placed on it (see
    /// [`Collision::with_contacts`]): the obstacle's index (`None`: the floor), the capsule's.
    exempt: Arc<[(Option<usize>, usize)]>,
}

/// How near (m) a placing task's point of a surface must be to a solid's surface (or the
/// floor) for the solid to be the one the part is placed on.
pub const CONTACT_REACH: f64 = 1e-3;

/// Above this cosine between two capsules' axes each end of either axis against the other
/// is a constraint of its own (see [`Collision::constraints_within`]).
const PARALLEL_ENDS: f64 = 0.9;
/// An end's constraint only where the end is this far from the closest point (m).
const ENDS_APART: f64 = 0.01;

/// Joints of a branch in one group of the broad phase.
const BRANCH_PIECE: usize = 2;

/// The capsules' groups and the pairs sorted by the groups they join (see [`Collision`]).
#[derive(Debug, Clone, PartialEq, Default)]
struct BroadPhase {
    /// Each capsule's group.
    group: Vec<usize>,
    groups: usize,
    /// The pairs in the order of `runs`.
    pairs: Vec<(usize, usize)>,
    /// Two groups and the range of `pairs` that joins them.
    runs: Vec<(usize, usize, std::ops::Range<usize>)>,
}

impl BroadPhase {
    /// Groups: each capsule goes with the highest joint of its branch, the lowest ancestor
    /// (or itself) of its joint whose parent has other children or none (a leg from its
    /// hip, an arm from its collarbone, each finger), in pieces of [`BRANCH_PIECE`] joints
    /// down the branch (the thigh and the shank, the upper arm, the forearm and the palm).
    fn new(skeleton: &Skeleton, capsules: &[Capsule], pairs: &[(usize, usize)]) -> Self {
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
struct Aabb {
    min: DVec3,
    max: DVec3,
}

impl Aabb {
    const EMPTY: Aabb = Aabb {
        min: DVec3::INFINITY,
        max: DVec3::NEG_INFINITY,
    };

    /// The box of a capsule whose axis runs from `a` to `b`.
    fn capsule(a: DVec3, b: DVec3, radius: f64) -> Self {
        Self {
            min: a.min(b) - radius,
            max: a.max(b) + radius,
        }
    }

    fn union(self, other: Aabb) -> Self {
        Self {
            min: self.min.min(other.min),
            max: self.max.max(other.max),
        }
    }

    /// Whether the boxes come within `reach` of each other along every axis.
    fn near(&self, other: &Aabb, reach: f64) -> bool {
        self.min.cmple(other.max + reach).all() && other.min.cmple(self.max + reach).all()
    }
}

impl Collision {
    /// The task's data: the `pairs` of `capsules` kept apart ([`collision_pairs`]), the
    /// `floor` capsules kept above the floor ([`floor_capsules`]), `margin` between surfaces,
    /// at most `rows` constraints at once; the capsules grouped by the branches of
    /// `skeleton` for the search (see [`Collision`]). [`Collision::validate`] checks it.
    pub fn new(
        skeleton: &Skeleton,
        capsules: Vec<Capsule>,
        pairs: Vec<(usize, usize)>,
        floor: Vec<usize>,
        margin: f64,
        rows: usize,
    ) -> Self {
        let broad = BroadPhase::new(skeleton, &capsules, &pairs);
        let rest = Frames::new(skeleton, &Posture::rest(skeleton));
        let against = floor_capsules(&capsules, &rest);
        Self {
            capsules: Arc::from(capsules),
            pairs: Arc::from(pairs),
            floor: Arc::from(floor),
            margin,
            rows,
            broad: Arc::new(broad),
            obstacles: Arc::from(Vec::new()),
            against: Arc::from(against),
            exempt: Arc::from(Vec::new()),
        }
    }

    /// The same task with the parts placed on a surface left off that surface's solid: for
    /// each `(joint, point, inside)` of `contacts` (a hand or foot put on a prop or the floor
    /// by a point-on-plane task, its point of the plane; `inside`: a point that may be inside
    /// the solid, a bar's axis), the capsules of the joint, of the joints below it and the bone
    /// that ends at it (the forearm of a hand, the shank of a foot) are not held off the
    /// obstacles whose surface passes within [`CONTACT_REACH`] of the point (or, `inside`, that
    /// hold it), nor off the floor where the point is on it: the placing
    /// task puts the joint's centre on the surface, which the capsules round it would
    /// otherwise hold off by their radius and the margin. The rest of the body keeps off.
    pub fn with_contacts(mut self, skeleton: &Skeleton, contacts: &[(usize, DVec3, bool)]) -> Self {
        let joints = skeleton.joints();
        let mut exempt = Vec::new();
        for &(joint, at, inside) in contacts {
            // The joint, the joints below it (parents come first) and its parent, whose
            // capsule is the bone ending at it.
            let mut placed = vec![false; joints.len()];
            for (j, def) in joints.iter().enumerate() {
                let below = def.parent.and_then(|p| placed.get(p).copied());
                if let Some(slot) = placed.get_mut(j) {
                    *slot = j == joint || below == Some(true);
                }
            }
            let parent = joints.get(joint).and_then(|def| def.parent);
            let carried = |c: &Capsule| {
                placed.get(c.joint).copied().unwrap_or(false)
                    || (Some(c.joint) == parent
                        && joints.get(joint).is_some_and(|def| {
                            (c.end - def.offset).length() < 1e-6
                                || (c.start - def.offset).length() < 1e-6
                        }))
            };
            let mut solids: Vec<Option<usize>> = self
                .obstacles
                .iter()
                .enumerate()
                .filter(|(_, o)| {
                    let d = o.signed_distance(at).0;
                    d < CONTACT_REACH && (inside || d > -CONTACT_REACH)
                })
                .map(|(k, _)| Some(k))
                .collect();
            if at.y.abs() < CONTACT_REACH {
                solids.push(None);
            }
            for (i, c) in self.capsules.iter().enumerate() {
                if carried(c) {
                    exempt.extend(solids.iter().map(|&solid| (solid, i)));
                }
            }
        }
        self.exempt = Arc::from(exempt);
        self
    }

    /// Whether capsule `i` is held off `solid` (an obstacle's index; `None`: the floor).
    fn holds(&self, solid: Option<usize>, i: usize) -> bool {
        !self.exempt.contains(&(solid, i))
    }

    /// The same task with the body's capsules (those clear of the floor at rest: not the
    /// feet) also held `margin` off these fixed solids (a scene's props).
    pub fn with_obstacles(mut self, obstacles: Vec<Obstacle>) -> Self {
        self.obstacles = Arc::from(obstacles);
        self
    }

    /// The fixed solids the capsules keep off.
    pub fn obstacles(&self) -> &[Obstacle] {
        &self.obstacles
    }

    /// The body's capsules.
    pub fn capsules(&self) -> &[Capsule] {
        &self.capsules
    }

    /// Indices into [`Collision::capsules`] of the pairs tested.
    pub fn pairs(&self) -> &[(usize, usize)] {
        &self.pairs
    }

    /// Indices into [`Collision::capsules`] of those kept above the floor.
    pub fn floor(&self) -> &[usize] {
        &self.floor
    }

    /// Distance kept between surfaces (m).
    pub fn margin(&self) -> f64 {
        self.margin
    }

    /// Constraints held at once, at most.
    pub fn rows(&self) -> usize {
        self.rows
    }

    /// Checks the data against a skeleton; the reason names the offending part.
    pub fn validate(&self, skeleton: &Skeleton) -> Result<(), String> {
        for (i, c) in self.capsules.iter().enumerate() {
            if c.joint >= skeleton.joint_count() {
                return Err(format!("capsule {i}: joint index {} out of range", c.joint));
            }
            if !(c.start.is_finite() && c.end.is_finite()) {
                return Err(format!("capsule {i}: its ends are not finite"));
            }
            if !(c.radius.is_finite() && c.radius > 0.0) {
                return Err(format!("capsule {i}: radius must be finite and > 0"));
            }
        }
        let n = self.capsules.len();
        if let Some(&(a, b)) = self
            .pairs
            .iter()
            .find(|&&(a, b)| a == b || a >= n || b >= n)
        {
            return Err(format!("pair ({a}, {b}) is not two of the capsules"));
        }
        if let Some(i) = self.floor.iter().find(|&&i| i >= n) {
            return Err(format!("floor capsule {i} is not one of the capsules"));
        }
        if let Some(i) = self.against.iter().find(|&&i| i >= n) {
            return Err(format!(
                "capsule {i} held off the obstacles is not one of the capsules"
            ));
        }
        for (k, obstacle) in self.obstacles.iter().enumerate() {
            obstacle
                .validate()
                .map_err(|reason| format!("obstacle {k}: {reason}"))?;
        }
        if !(self.margin.is_finite() && self.margin >= 0.0) {
            return Err("margin must be finite and >= 0".into());
        }
        if self.rows == 0 {
            return Err("a collision task needs at least one row".into());
        }
        Ok(())
    }

    /// The DOF whose columns may be nonzero: those of the capsules' joints and their
    /// ancestors, sorted.
    pub(super) fn support(&self, skeleton: &Skeleton) -> Vec<usize> {
        let joints = skeleton.joints();
        let mut moved = vec![false; joints.len()];
        for c in self.capsules.iter() {
            let mut at = Some(c.joint);
            while let Some(j) = at {
                match moved.get_mut(j) {
                    Some(m) if !*m => *m = true,
                    _ => break,
                }
                at = joints.get(j).and_then(|joint| joint.parent);
            }
        }
        joints
            .iter()
            .zip(&moved)
            .filter(|(_, m)| **m)
            .flat_map(|(joint, _)| joint.dof_range())
            .collect::<std::collections::BTreeSet<usize>>()
            .into_iter()
            .collect()
    }

    /// The constraints at `frames`: every pair and every floor capsule within the margin plus
    /// the band, nearest first, at most `rows`.
    pub(super) fn constraints(&self, frames: &Frames) -> Vec<Constraint> {
        self.constraints_within(frames, self.margin + COLLISION_BAND)
    }

    /// The constraints at `frames` whose distance is under `reach`, nearest first, at most
    /// `rows`.
    pub(super) fn constraints_within(&self, frames: &Frames, reach: f64) -> Vec<Constraint> {
        let capsules = &self.capsules;
        let broad = &self.broad;
        // Each capsule's ends in the world and its box, once; each group's box.
        let ends: Vec<(DVec3, DVec3)> = capsules.iter().map(|c| c.world(frames)).collect();
        let boxes: Vec<Aabb> = capsules
            .iter()
            .zip(&ends)
            .map(|(c, &(a, b))| Aabb::capsule(a, b, c.radius))
            .collect();
        // Bounding spheres: tighter than the boxes for a capsule across the axes.
        let spheres: Vec<(DVec3, f64)> = capsules
            .iter()
            .zip(&ends)
            .map(|(c, &(a, b))| ((a + b) * 0.5, (b - a).length() * 0.5 + c.radius))
            .collect();
        let mut group_boxes = vec![Aabb::EMPTY; broad.groups];
        for (&g, b) in broad.group.iter().zip(&boxes) {
            if let Some(gb) = group_boxes.get_mut(g) {
                *gb = gb.union(*b);
            }
        }
        let mut found = Vec::new();
        for (ga, gb, range) in &broad.runs {
            let (Some(box_a), Some(box_b)) = (group_boxes.get(*ga), group_boxes.get(*gb)) else {
                continue;
            };
            if !box_a.near(box_b, reach) {
                continue;
            }
            for &(i, j) in broad.pairs.get(range.clone()).unwrap_or(&[]) {
                let (Some(a), Some(b), Some(ba), Some(bb)) =
                    (capsules.get(i), capsules.get(j), boxes.get(i), boxes.get(j))
                else {
                    continue;
                };
                let ((ca, ra), (cb, rb)) = (spheres[i], spheres[j]);
                let apart = ra + rb + reach;
                if !ba.near(bb, reach) || (ca - cb).length_squared() > apart * apart {
                    continue;
                }
                let (distance, pa, pb) = surface_distance(a, ends[i], b, ends[j]);
                let mut push = |distance: f64, pa: DVec3, pb: DVec3| {
                    let gap = pa - pb;
                    if distance < reach && gap.length() > 1e-9 {
                        let normal = gap.normalize();
                        found.push(Constraint {
                            distance,
                            a: (a.joint, pa),
                            b: Some((b.joint, pb)),
                            normal,
                            surface: (pa - normal * a.radius, pb + normal * b.radius),
                        });
                    }
                };
                push(distance, pa, pb);
                // Nearly parallel axes (an arm hanging by the thigh): the closest points
                // jump from one end to the other as the axes tilt, so each end of either
                // axis against the other is a constraint too (`PARALLEL_ENDS`).
                let ((a0, a1), (b0, b1)) = (ends[i], ends[j]);
                let (u, v) = ((a1 - a0).normalize_or_zero(), (b1 - b0).normalize_or_zero());
                if u.dot(v).abs() > PARALLEL_ENDS {
                    let radii = a.radius + b.radius;
                    for end in [a0, a1] {
                        let (_, q) = closest_points(end, end, b0, b1);
                        if (end - pa).length() > ENDS_APART {
                            push((end - q).length() - radii, end, q);
                        }
                    }
                    for end in [b0, b1] {
                        let (q, _) = closest_points(a0, a1, end, end);
                        if (end - pb).length() > ENDS_APART {
                            push((q - end).length() - radii, q, end);
                        }
                    }
                }
            }
        }
        for &i in self.floor.iter().filter(|&&i| self.holds(None, i)) {
            let (Some(c), Some(&(p0, p1))) = (capsules.get(i), ends.get(i)) else {
                continue;
            };
            let low = if p0.y <= p1.y { p0 } else { p1 };
            let distance = low.y - c.radius;
            if distance < reach {
                found.push(Constraint {
                    distance,
                    a: (c.joint, low),
                    b: None,
                    normal: DVec3::Y,
                    surface: (low - DVec3::Y * c.radius, DVec3::new(low.x, 0.0, low.z)),
                });
            }
        }
        for (k, obstacle) in self.obstacles.iter().enumerate() {
            let (centre, bound) = (obstacle.position, obstacle.bounding_radius());
            for &i in self.against.iter().filter(|&&i| self.holds(Some(k), i)) {
                let (Some(c), Some(&(p0, p1)), Some(&(sc, sr))) =
                    (capsules.get(i), ends.get(i), spheres.get(i))
                else {
                    continue;
                };
                // Bounding balls apart: nothing to compute.
                if (sc - centre).length() > sr + bound + reach {
                    continue;
                }
                let (point, signed, gradient) = obstacle.nearest_on_segment(p0, p1);
                let distance = signed - c.radius;
                if distance < reach {
                    let outward = gradient.normalize_or(DVec3::Y);
                    found.push(Constraint {
                        distance,
                        a: (c.joint, point),
                        b: None,
                        normal: gradient,
                        surface: (point - outward * c.radius, point - outward * signed),
                    });
                }
            }
        }
        found.sort_by(|x, y| x.distance.total_cmp(&y.distance));
        found.truncate(self.rows);
        found
    }

    /// The contacts at `frames`: the constraints the task holds there (every pair and floor
    /// capsule within the margin plus [`COLLISION_BAND`], nearest first, at most
    /// [`Collision::rows`]), as the editor draws them.
    pub fn contacts(&self, frames: &Frames) -> Vec<Contact> {
        self.constraints(frames)
            .into_iter()
            .map(|c| Contact {
                distance: c.distance,
                joints: (c.a.0, c.b.map(|(joint, _)| joint)),
                points: c.surface,
            })
            .collect()
    }
}

/// Two surfaces a collision task holds apart (or a surface and the floor), within its margin
/// and [`COLLISION_BAND`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Contact {
    /// Distance between the surfaces (m; negative where they overlap).
    pub distance: f64,
    /// The joints carrying the two capsules (`None` for the floor or an obstacle).
    pub joints: (usize, Option<usize>),
    /// The closest points of the two surfaces (world, m): on the first capsule, then on the
    /// second, the floor or the obstacle.
    pub points: (DVec3, DVec3),
}

/// A capsule of the body: a segment fixed in a joint's frame, swept by a sphere.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Capsule {
    /// The joint whose frame carries it.
    pub joint: usize,
    /// Centre of the start cap, joint frame (m).
    pub start: DVec3,
    /// Centre of the end cap, joint frame (m).
    pub end: DVec3,
    /// Radius of the swept sphere (m).
    pub radius: f64,
}

impl Capsule {
    /// Its two cap centres in the world, the body posed as `frames` say.
    pub fn world(&self, frames: &Frames) -> (DVec3, DVec3) {
        (
            frames.point(self.joint, self.start),
            frames.point(self.joint, self.end),
        )
    }
}

/// The closest points of the segments `p0 p1` and `q0 q1` (one on each; either may be a
/// point): the pair minimising the distance, the first segment's parameter clamped first
/// where the segments are parallel.
pub fn closest_points(p0: DVec3, p1: DVec3, q0: DVec3, q1: DVec3) -> (DVec3, DVec3) {
    let (u, v, w) = (p1 - p0, q1 - q0, p0 - q0);
    let (a, b, c) = (u.dot(u), u.dot(v), v.dot(v));
    let (d, e) = (u.dot(w), v.dot(w));
    const TINY: f64 = 1e-18;
    // t for a given s: the projection of the point at s onto the second segment.
    let t_of = |s: f64| {
        if c <= TINY {
            0.0
        } else {
            ((b * s + e) / c).clamp(0.0, 1.0)
        }
    };
    // s for a given t: the projection of the point at t onto the first segment.
    let s_of = |t: f64| {
        if a <= TINY {
            0.0
        } else {
            ((b * t - d) / a).clamp(0.0, 1.0)
        }
    };
    let denominator = a * c - b * b;
    let s = if a <= TINY {
        0.0
    } else if denominator <= TINY * a.max(1.0) * c.max(1.0) {
        // Parallel (or the second a point): any s; the start of the first.
        0.0
    } else {
        ((b * e - c * d) / denominator).clamp(0.0, 1.0)
    };
    let t = t_of(s);
    // Clamping t may move the best s: project back once.
    let s = s_of(t);
    let t = t_of(s);
    (p0 + u * s, q0 + v * t)
}

/// The pairs of `capsules` a collision task tests: capsules on joints at least three steps
/// apart in the tree (a bone and its neighbours, which share a joint, always touch), and more
/// than `clearance` apart at the rest posture `rest` (capsules that touch standing at rest,
/// such as the chest and the upper arms' roots, are one body; pass the task's margin and
/// [`COLLISION_BAND`], so that no pair starts held).
pub fn collision_pairs(
    skeleton: &Skeleton,
    capsules: &[Capsule],
    rest: &Frames,
    clearance: f64,
) -> Vec<(usize, usize)> {
    let parents: Vec<Option<usize>> = skeleton.joints().iter().map(|j| j.parent).collect();
    let depth = |mut j: usize| {
        let mut k = 0;
        while let Some(p) = parents.get(j).copied().flatten() {
            j = p;
            k += 1;
        }
        k
    };
    // Steps between two joints through their lowest common ancestor.
    let steps = |mut a: usize, mut b: usize| {
        let (mut da, mut db) = (depth(a), depth(b));
        let mut k = 0;
        while a != b {
            if da >= db {
                let Some(p) = parents[a] else { break };
                a = p;
                da -= 1;
            } else {
                let Some(p) = parents[b] else { break };
                b = p;
                db -= 1;
            }
            k += 1;
        }
        k
    };
    let mut pairs = Vec::new();
    for i in 0..capsules.len() {
        for j in i + 1..capsules.len() {
            let (a, b) = (&capsules[i], &capsules[j]);
            if a.joint >= parents.len() || b.joint >= parents.len() || steps(a.joint, b.joint) < 3 {
                continue;
            }
            if surface_distance(a, a.world(rest), b, b.world(rest)).0 > clearance {
                pairs.push((i, j));
            }
        }
    }
    pairs
}

/// The capsules a collision task keeps above the floor `y = 0`: those clear of it at the rest
/// posture (`rest`). The feet's capsules, which stand on it (their axes run through the bones,
/// so their bottoms dip under the sole), are left to the tasks that hold the feet.
pub fn floor_capsules(capsules: &[Capsule], rest: &Frames) -> Vec<usize> {
    capsules
        .iter()
        .enumerate()
        .filter(|(_, c)| {
            let (a, b) = c.world(rest);
            a.y.min(b.y) - c.radius > 0.0
        })
        .map(|(i, _)| i)
        .collect()
}

/// The distance between the surfaces of `a` and `b` whose axes' ends are given (in the
/// world; negative where they overlap) and the closest points of their axes, on each.
fn surface_distance(
    a: &Capsule,
    (a0, a1): (DVec3, DVec3),
    b: &Capsule,
    (b0, b1): (DVec3, DVec3),
) -> (f64, DVec3, DVec3) {
    let (pa, pb) = closest_points(a0, a1, b0, b1);
    ((pa - pb).length() - a.radius - b.radius, pa, pb)
}

/// One constraint: the distance between two surfaces (or a surface and the floor) and how it
/// changes.
#[derive(Debug, Clone, Copy)]
pub(super) struct Constraint {
    /// Distance between the surfaces (m).
    pub distance: f64,
    /// Closest point of the first capsule's axis, and its joint.
    a: (usize, DVec3),
    /// The second capsule's, or `None` for the floor or an obstacle.
    b: Option<(usize, DVec3)>,
    /// Unit direction from the second to the first (up for the floor, the obstacle's outward
    /// normal for an obstacle: the distance's gradient, of a length under 1 on a kink inside
    /// one).
    normal: DVec3,
    /// The closest points of the two surfaces (the second on the floor for the floor).
    surface: (DVec3, DVec3),
}

/// The task's errors at `found` (`margin` less each distance where it is under it, 0 for the
/// rows held in the band and the empty ones); returns their norm.
pub(super) fn errors(found: &[Constraint], margin: f64, err: &mut [f64]) -> f64 {
    err.fill(0.0);
    for (e, c) in err.iter_mut().zip(found) {
        *e = (margin - c.distance).max(0.0);
    }
    err.iter().map(|e| e * e).sum::<f64>().sqrt()
}

/// The task's rows at `found` into `jac_t` (`n x found.len()`, column-major, zero on entry):
/// each the distance's change for unit velocities of the DOF that move one point against the
/// other. A DOF of the two points' common ancestors (or of the lowest common joint itself)
/// carries both rigidly: it changes `pa - pb` by `axis x (pa - pb)` (or not at all), which
/// is normal to the line of closest approach, so its entry is zero and is not written; the
/// rows are sparse, on the chains from each point's joint up to their lowest common joint.
/// A floor row has the whole chain of its point.
pub(super) fn write_rows(
    skeleton: &Skeleton,
    frames: &Frames,
    found: &[Constraint],
    jac_t: &mut [f64],
    n: usize,
) {
    for (row, c) in found.iter().enumerate() {
        let Some(column) = jac_t.get_mut(row * n..(row + 1) * n) else {
            return;
        };
        let (ja, pa) = c.a;
        match c.b {
            None => add_chain(skeleton, frames, (ja, pa), None, c.normal, column),
            Some((jb, pb)) => {
                let common = lowest_common_joint(skeleton, ja, jb);
                add_chain(skeleton, frames, (ja, pa), common, c.normal, column);
                add_chain(skeleton, frames, (jb, pb), common, -c.normal, column);
            }
        }
    }
}

/// Adds to `column` `normal` dotted with the velocity of the world point `point` carried by
/// `joint` for each DOF of `joint` and its ancestors below `stop` (the whole chain for
/// `None`).
fn add_chain(
    skeleton: &Skeleton,
    frames: &Frames,
    (joint, point): (usize, DVec3),
    stop: Option<usize>,
    normal: DVec3,
    column: &mut [f64],
) {
    let joints = skeleton.joints();
    let kinds = skeleton.dof_kinds();
    let mut at = Some(joint);
    while let Some(j) = at.filter(|&j| Some(j) != stop) {
        let Some(def) = joints.get(j) else {
            return;
        };
        for d in def.dof_range() {
            let axis = frames.dof_axis[d];
            let velocity = if kinds[d].is_rotation() {
                axis.cross(point - frames.joint_position[j])
            } else {
                axis
            };
            if let Some(entry) = column.get_mut(d) {
                *entry += normal.dot(velocity);
            }
        }
        at = def.parent;
    }
}

/// The lowest joint that is an ancestor of (or is) both `a` and `b` (joints are ordered
/// parents first), `None` in a forest without one.
fn lowest_common_joint(skeleton: &Skeleton, mut a: usize, mut b: usize) -> Option<usize> {
    let joints = skeleton.joints();
    while a != b {
        let deeper = if a > b { &mut a } else { &mut b };
        *deeper = joints.get(*deeper)?.parent?;
    }
    Some(a)
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

    use rand::rngs::StdRng;
    use rand::{RngExt, SeedableRng};

    use super::*;

    /// The distance of two segments by another route: `f(s) = min_t |p(s) - q(t)|` is convex
    /// in `s` (the distance of a point on a line to a convex set, along a line), its inner
    /// minimum the clamped projection; a golden-section search over `s`.
    fn searched(p0: DVec3, p1: DVec3, q0: DVec3, q1: DVec3) -> f64 {
        let v = q1 - q0;
        let inner = |s: f64| {
            let p = p0 + (p1 - p0) * s;
            let t = if v.length_squared() > 0.0 {
                ((p - q0).dot(v) / v.length_squared()).clamp(0.0, 1.0)
            } else {
                0.0
            };
            (p - (q0 + v * t)).length()
        };
        let (mut lo, mut hi) = (0.0f64, 1.0f64);
        let g = (5f64.sqrt() - 1.0) / 2.0;
        for _ in 0..200 {
            let (m1, m2) = (hi - g * (hi - lo), lo + g * (hi - lo));
            if inner(m1) <= inner(m2) {
                hi = m2;
            } else {
                lo = m1;
            }
        }
        inner((lo + hi) / 2.0).min(inner(0.0)).min(inner(1.0))
    }

    /// Catches a closest-point routine that clamps wrongly (end against end, a point against
    /// a segment, parallel segments): on random segments, some degenerate, some parallel, the
    /// distance equals the searched one and both points lie on their segments.
    #[test]
    fn closest_points_match_a_search_along_the_segments() {
        let mut r = StdRng::seed_from_u64(3);
        let point = |r: &mut StdRng| {
            DVec3::new(
                r.random_range(-1.0..1.0),
                r.random_range(-1.0..1.0),
                r.random_range(-1.0..1.0),
            )
        };
        for case in 0..2000 {
            let p0 = point(&mut r);
            let mut p1 = point(&mut r);
            let q0 = point(&mut r);
            let mut q1 = point(&mut r);
            match case % 5 {
                0 => p1 = p0,
                1 => q1 = q0,
                2 => q1 = q0 + (p1 - p0) * 0.7,
                _ => {}
            }
            let (pa, pb) = closest_points(p0, p1, q0, q1);
            let on = |x: DVec3, a: DVec3, b: DVec3| {
                let ab = b - a;
                let t = if ab.length_squared() > 0.0 {
                    ((x - a).dot(ab) / ab.length_squared()).clamp(0.0, 1.0)
                } else {
                    0.0
                };
                (a + ab * t - x).length() < 1e-9
            };
            assert!(on(pa, p0, p1) && on(pb, q0, q1), "case {case}");
            let expected = searched(p0, p1, q0, q1);
            let got = (pa - pb).length();
            assert!(
                (got - expected).abs() < 1e-9,
                "case {case}: {got} vs {expected}"
            );
        }
    }
}
