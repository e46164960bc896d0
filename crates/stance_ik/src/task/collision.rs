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

mod broad_phase;

use std::sync::Arc;

use glam::DVec3;

use super::obstacle::Obstacle;
use crate::{Frames, Posture, Skeleton};
use broad_phase::{Aabb, BroadPhase};

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

    /// Whether `other` is this task: the same capsules and pairs (shared, as clones share
    /// them), margin and rows: a [`NearList`] made for one serves the other, whose pairs it
    /// lists (the floor and the solids, which a frame's tasks may build afresh, are searched
    /// apart).
    fn same_data(&self, other: &Collision) -> bool {
        Arc::ptr_eq(&self.capsules, &other.capsules)
            && Arc::ptr_eq(&self.pairs, &other.pairs)
            && self.margin == other.margin
            && self.rows == other.rows
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
    /// `rows`. The search keeps only the nearest `rows` found so far and, once it has them,
    /// looks no further than the last of them ([`Nearest`]): far pairs are skipped by their
    /// groups' boxes, their own boxes and bounding spheres.
    pub(super) fn constraints_within(&self, frames: &Frames, reach: f64) -> Vec<Constraint> {
        let placed = self.placed(frames);
        let mut nearest = Nearest::new(self.rows, reach);
        self.broad_pairs(&placed, &mut nearest);
        self.search_floor(&placed, &mut nearest);
        self.search_obstacles(&placed, &mut nearest);
        nearest.found
    }

    /// [`Collision::constraints_within`] by way of `list`: the pairs it holds where it
    /// still serves this task, `reach` and the posture (see [`NearList`]), else made
    /// afresh at `frames`. The same constraints, the pairs further off not looked at.
    pub(super) fn constraints_listed(
        &self,
        frames: &Frames,
        reach: f64,
        list: &mut NearList,
    ) -> Vec<Constraint> {
        let placed = self.placed(frames);
        if !list.serves(self, reach, &placed) {
            list.make(self, reach, &placed);
        }
        let mut nearest = Nearest::new(self.rows, reach);
        let most = list.most_moved();
        for &(i, j, was) in &list.pairs {
            // The surfaces have come closer by at most their capsules' moves; the pairs are
            // in the order of their distances then.
            if was - most >= nearest.reach() {
                break;
            }
            let (Some(&mi), Some(&mj)) = (list.moved.get(i), list.moved.get(j)) else {
                continue;
            };
            if was - mi - mj < nearest.reach() {
                self.offer_pair(&placed, i, j, &mut nearest);
            }
        }
        self.search_floor(&placed, &mut nearest);
        self.search_obstacles(&placed, &mut nearest);
        nearest.found
    }

    /// Each capsule where `frames` puts it.
    fn placed(&self, frames: &Frames) -> Vec<Placed> {
        self.capsules
            .iter()
            .map(|c| Placed::new(c, frames))
            .collect()
    }

    /// Each pair whose groups' boxes come within `sink`'s reach to `sink`: the broad phase.
    fn broad_pairs(&self, placed: &[Placed], sink: &mut impl PairSink) {
        let broad = &self.broad;
        let mut group_boxes = vec![Aabb::EMPTY; broad.groups];
        for (&g, p) in broad.group.iter().zip(placed) {
            if let Some(gb) = group_boxes.get_mut(g) {
                *gb = gb.union(p.aabb);
            }
        }
        for (ga, gb, range) in &broad.runs {
            let (Some(box_a), Some(box_b)) = (group_boxes.get(*ga), group_boxes.get(*gb)) else {
                continue;
            };
            if !box_a.near(box_b, sink.reach()) {
                continue;
            }
            for &(i, j) in broad.pairs.get(range.clone()).unwrap_or(&[]) {
                sink.pair(self, placed, i, j);
            }
        }
    }

    /// The constraints of the pair `(i, j)` into `nearest` where its boxes and bounding
    /// spheres come within its reach.
    fn offer_pair(&self, placed: &[Placed], i: usize, j: usize, nearest: &mut Nearest) {
        if let Some([(a, pa), (b, pb)]) = self.near_pair(placed, i, j, nearest.reach()) {
            pair_constraints(a, pa.ends, b, pb.ends, nearest);
        }
    }

    /// The capsules `i` and `j` with their placements, where their boxes and bounding
    /// spheres come within `reach` of each other.
    fn near_pair<'a>(
        &'a self,
        placed: &'a [Placed],
        i: usize,
        j: usize,
        reach: f64,
    ) -> Option<[(&'a Capsule, &'a Placed); 2]> {
        let (a, b) = (self.capsules.get(i)?, self.capsules.get(j)?);
        let (pa, pb) = (placed.get(i)?, placed.get(j)?);
        pa.near(pb, reach).then_some([(a, pa), (b, pb)])
    }

    /// The floor's constraints into `nearest`: each floor capsule's lower end against
    /// `y = 0`.
    fn search_floor(&self, placed: &[Placed], nearest: &mut Nearest) {
        for &i in self.floor.iter().filter(|&&i| self.holds(None, i)) {
            let (Some(c), Some(p)) = (self.capsules.get(i), placed.get(i)) else {
                continue;
            };
            let (p0, p1) = p.ends;
            let low = if p0.y <= p1.y { p0 } else { p1 };
            nearest.offer(Constraint {
                distance: low.y - c.radius,
                a: (c.joint, low),
                b: None,
                normal: DVec3::Y,
                surface: (low - DVec3::Y * c.radius, DVec3::new(low.x, 0.0, low.z)),
            });
        }
    }

    /// The obstacles' constraints into `nearest`: each capsule held off an obstacle whose
    /// bounding ball comes within reach of its own, at the nearest point of its axis.
    fn search_obstacles(&self, placed: &[Placed], nearest: &mut Nearest) {
        for (k, obstacle) in self.obstacles.iter().enumerate() {
            let (centre, bound) = (obstacle.position, obstacle.bounding_radius());
            for &i in self.against.iter().filter(|&&i| self.holds(Some(k), i)) {
                let (Some(c), Some(p)) = (self.capsules.get(i), placed.get(i)) else {
                    continue;
                };
                // Bounding balls apart: nothing to compute.
                if (p.centre - centre).length() > p.radius + bound + nearest.reach() {
                    continue;
                }
                let (p0, p1) = p.ends;
                let (point, signed, gradient) = obstacle.nearest_on_segment(p0, p1);
                let outward = gradient.normalize_or(DVec3::Y);
                nearest.offer(Constraint {
                    distance: signed - c.radius,
                    a: (c.joint, point),
                    b: None,
                    normal: gradient,
                    surface: (point - outward * c.radius, point - outward * signed),
                });
            }
        }
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

/// A capsule where the posture puts it: its axis's ends in the world, its box and its
/// bounding sphere (tighter than the box for a capsule across the axes).
#[derive(Debug, Clone, Copy)]
struct Placed {
    ends: (DVec3, DVec3),
    aabb: Aabb,
    centre: DVec3,
    radius: f64,
}

impl Placed {
    fn new(c: &Capsule, frames: &Frames) -> Self {
        let (a, b) = c.world(frames);
        Self {
            ends: (a, b),
            aabb: Aabb::capsule(a, b, c.radius),
            centre: (a + b) * 0.5,
            radius: (b - a).length() * 0.5 + c.radius,
        }
    }

    /// Whether the boxes and bounding spheres of two capsules come within `reach`.
    fn near(&self, other: &Placed, reach: f64) -> bool {
        let apart = self.radius + other.radius + reach;
        self.aabb.near(&other.aabb, reach)
            && (self.centre - other.centre).length_squared() <= apart * apart
    }
}

/// How much further than asked a [`NearList`] looks (m): the list serves while no two
/// capsules have moved more than this together since it was made.
const LIST_SKIN: f64 = 0.03;

/// The pairs of a collision task near enough to matter at a posture, kept for the searches
/// that follow while the body moves little (a solver's iterations): the pairs whose surfaces
/// were within `reach` and [`LIST_SKIN`], with their distances then, nearest first, and the
/// capsules' ends then. While no two capsules have moved more than the skin together since
/// (a capsule's move: the longer of its ends'), no pair left out can have come within
/// `reach` (two surfaces come closer by at most their capsules' moves), so a search of the
/// listed pairs finds what a search of all would; it stops at the first pair whose distance
/// then, less the two largest moves, is past what it keeps.
#[derive(Debug, Clone, Default)]
pub(crate) struct NearList {
    /// The task it was made for (its shared data compared, see [`Collision::same_data`]).
    task: Option<Collision>,
    reach: f64,
    ends: Vec<(DVec3, DVec3)>,
    /// Two capsules and the distance of their surfaces when the list was made.
    pairs: Vec<(usize, usize, f64)>,
    /// How far each capsule's ends have moved since, the furthest of the two (m).
    moved: Vec<f64>,
}

impl NearList {
    /// Whether the list serves `task`'s search to `reach` with its capsules at `placed`;
    /// notes how far each has moved.
    fn serves(&mut self, task: &Collision, reach: f64, placed: &[Placed]) -> bool {
        if !(self.task.as_ref().is_some_and(|t| t.same_data(task))
            && self.reach == reach
            && self.ends.len() == placed.len())
        {
            return false;
        }
        self.moved.clear();
        self.moved.extend(
            self.ends
                .iter()
                .zip(placed)
                .map(|(&(a, b), p)| a.distance(p.ends.0).max(b.distance(p.ends.1))),
        );
        self.most_moved() <= LIST_SKIN
    }

    /// The most two capsules have moved together since the list was made: the two largest
    /// moves (m).
    fn most_moved(&self) -> f64 {
        let (mut first, mut second) = (0.0f64, 0.0f64);
        for &m in &self.moved {
            if m > first {
                (first, second) = (m, first);
            } else if m > second {
                second = m;
            }
        }
        first + second
    }

    /// Makes the list afresh for `task`'s search to `reach` with its capsules at `placed`.
    fn make(&mut self, task: &Collision, reach: f64, placed: &[Placed]) {
        self.task = Some(task.clone());
        self.reach = reach;
        self.ends.clear();
        self.ends.extend(placed.iter().map(|p| p.ends));
        self.moved.clear();
        self.moved.resize(placed.len(), 0.0);
        self.pairs.clear();
        let mut sink = ListSink {
            reach: reach + LIST_SKIN,
            pairs: std::mem::take(&mut self.pairs),
        };
        task.broad_pairs(placed, &mut sink);
        self.pairs = sink.pairs;
        self.pairs.sort_unstable_by(|x, y| x.2.total_cmp(&y.2));
    }
}

/// What the broad phase hands its pairs to: how far it looks, and each pair within it.
trait PairSink {
    fn reach(&self) -> f64;
    fn pair(&mut self, task: &Collision, placed: &[Placed], i: usize, j: usize);
}

impl PairSink for Nearest {
    fn reach(&self) -> f64 {
        Nearest::reach(self)
    }

    fn pair(&mut self, task: &Collision, placed: &[Placed], i: usize, j: usize) {
        task.offer_pair(placed, i, j, self);
    }
}

/// The pairs whose surfaces are within `reach`, with their distances (a [`NearList`] in the
/// making).
struct ListSink {
    reach: f64,
    pairs: Vec<(usize, usize, f64)>,
}

impl PairSink for ListSink {
    fn reach(&self) -> f64 {
        self.reach
    }

    fn pair(&mut self, task: &Collision, placed: &[Placed], i: usize, j: usize) {
        if let Some([(a, pa), (b, pb)]) = task.near_pair(placed, i, j, self.reach) {
            let distance = surface_distance(a, pa.ends, b, pb.ends).0;
            if distance < self.reach {
                self.pairs.push((i, j, distance));
            }
        }
    }
}

/// The nearest constraints a search has found so far, nearest first (in the order found
/// among equal distances), at most `rows`, each under `reach`.
struct Nearest {
    found: Vec<Constraint>,
    rows: usize,
    reach: f64,
}

impl Nearest {
    fn new(rows: usize, reach: f64) -> Self {
        Self {
            found: Vec::with_capacity(rows + 1),
            rows,
            reach,
        }
    }

    /// How far a constraint may be and still be kept: `reach`, or once `rows` are found,
    /// the distance of the furthest of them.
    fn reach(&self) -> f64 {
        match self.found.last() {
            Some(last) if self.found.len() >= self.rows => last.distance.min(self.reach),
            _ => self.reach,
        }
    }

    /// Keeps `c` where it is nearer than [`Nearest::reach`], after those found before it at
    /// its distance.
    fn offer(&mut self, c: Constraint) {
        if c.distance < self.reach() {
            let at = self.found.partition_point(|f| f.distance <= c.distance);
            self.found.insert(at, c);
            self.found.truncate(self.rows);
        }
    }
}

/// The constraints of the capsules `a` and `b` whose axes' ends are given (in the world)
/// into `nearest`: along their axes' closest points; for nearly parallel axes (an arm
/// hanging by the thigh), whose closest points jump from one end to the other as the axes
/// tilt, each end of either axis against the other too ([`PARALLEL_ENDS`]).
fn pair_constraints(
    a: &Capsule,
    (a0, a1): (DVec3, DVec3),
    b: &Capsule,
    (b0, b1): (DVec3, DVec3),
    nearest: &mut Nearest,
) {
    let mut offer = |distance: f64, pa: DVec3, pb: DVec3| {
        let gap = pa - pb;
        if distance < nearest.reach() && gap.length() > 1e-9 {
            let normal = gap.normalize();
            nearest.offer(Constraint {
                distance,
                a: (a.joint, pa),
                b: Some((b.joint, pb)),
                normal,
                surface: (pa - normal * a.radius, pb + normal * b.radius),
            });
        }
    };
    let (distance, pa, pb) = surface_distance(a, (a0, a1), b, (b0, b1));
    offer(distance, pa, pb);
    let (u, v) = ((a1 - a0).normalize_or_zero(), (b1 - b0).normalize_or_zero());
    if u.dot(v).abs() > PARALLEL_ENDS {
        let radii = a.radius + b.radius;
        for end in [a0, a1] {
            let (_, q) = closest_points(end, end, b0, b1);
            if (end - pa).length() > ENDS_APART {
                offer((end - q).length() - radii, end, q);
            }
        }
        for end in [b0, b1] {
            let (q, _) = closest_points(a0, a1, end, end);
            if (end - pb).length() > ENDS_APART {
                offer((q - end).length() - radii, q, end);
            }
        }
    }
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
mod tests;
