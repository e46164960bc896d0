//! One person's keypoints lifted onto the body: the camera (given, or fitted to the
//! keypoints), the tasks (each keypoint on its camera ray, the feet on the floor, balance,
//! comfort), the start posture (the rest body turned and placed to match the keypoints) and
//! the solve.

use glam::{DQuat, DVec2, DVec3};
use stance_document::{Document, PostureValues, TaskKindSpec, TaskSpec};
use stance_hanim::keypoints::{
    HAND_KEYPOINTS, KeypointFinder, KeypointSource, NECK, PoseKeypoints,
};
use stance_ik::{Dof, Effector, Frames, Posture, Skeleton, SolveReport};
use stance_render::{OpenPosePerson, OrbitCamera};

use crate::LiftError;
use crate::place::{LIMBS, LimbKeypoints, PlacedLimb, Ray};
use crate::stages::descends_from;

mod tasks;
mod view;

use tasks::{floor_tasks, image_plane_tasks, standing_feet};
pub use view::camera_spec;
use view::{Scale, View, fit_camera};

/// COCO-18 indices.
const NOSE: usize = 0;
const R_SHOULDER: usize = 2;
const L_SHOULDER: usize = 5;
const R_HIP: usize = 8;
const R_ANKLE: usize = 10;
const L_HIP: usize = 11;
const L_ANKLE: usize = 13;
const R_EAR: usize = 16;
const L_EAR: usize = 17;

/// The bones between body keypoints whose rest length gives the body's scale in the image
/// (arms, legs, shoulders, hips, the torso's sides).
const SCALE_BONES: [(usize, usize); 12] = [
    (2, 3),
    (3, 4),
    (5, 6),
    (6, 7),
    (8, 9),
    (9, 10),
    (11, 12),
    (12, 13),
    (2, 5),
    (8, 11),
    (2, 8),
    (5, 11),
];

/// An ankle whose keypoint lies within this many metres (at the body's scale in the image)
/// of the lowest ankle's is taken to stand on the floor; a higher one only stays above it.
const STANDING_SLACK_M: f64 = 0.25;

/// The levels of the lifted document's tasks.
const IMAGE_LEVEL: u32 = 1;
const FLOOR_LEVEL: u32 = 2;
const BALANCE_LEVEL: u32 = 3;

/// What a lift made.
#[derive(Debug, Clone)]
pub struct Lifted {
    /// The document: the solved posture, its tasks (each keypoint on its ray at level 1, the
    /// feet at 2, balance at 3, comfort at 10) and the camera as its saved view.
    pub document: Document,
    /// The solved posture on the body's skeleton.
    pub posture: Posture,
    /// The camera the keypoints were seen with (given, or fitted).
    pub camera: OrbitCamera,
    /// Whether the camera was fitted to the keypoints.
    pub camera_fitted: bool,
    /// How many keypoints became tasks.
    pub keypoints_used: usize,
    /// The feet taken to stand on the floor (ankle joint names).
    pub standing: Vec<String>,
    /// The joints whose depth the lift flipped to meet the image level (see
    /// [`crate::flip_depth`]), in order.
    pub flips: Vec<String>,
    /// The solve's report.
    pub report: SolveReport,
}

/// Lifts `person`'s keypoints, seen in an image of `size_px` through `camera` (or, without
/// one, a camera fitted to them: see `fit_camera`), onto `skeleton`.
pub fn lift(
    skeleton: &Skeleton,
    person: &OpenPosePerson,
    size_px: [u32; 2],
    camera: Option<OrbitCamera>,
) -> Result<Lifted, LiftError> {
    let seen = person
        .body
        .iter()
        .chain(&person.left_hand)
        .chain(&person.right_hand)
        .flatten()
        .count();
    if seen == 0 {
        return Err(LiftError::NoKeypoints);
    }
    let finder = KeypointFinder::new(skeleton);
    let rest = Frames::new(skeleton, &Posture::rest(skeleton));
    let rest_points = finder.find(skeleton, &rest);
    let scale = Scale::new(person, &rest_points)?;
    let (camera, camera_fitted) = match camera {
        Some(camera) => {
            crate::read::check_camera(&camera)?;
            (camera, false)
        }
        None => (fit_camera(person, size_px, &rest_points, &scale), true),
    };
    let view = View { camera, size_px };
    let (mut tasks, keypoints_used) = image_plane_tasks(skeleton, &finder, person, &view);
    let standing = standing_feet(person, &scale);
    tasks.extend(floor_tasks(skeleton, &rest, &standing));
    tasks.push(TaskSpec::comfort());
    let start = start_posture(skeleton, person, &view, &rest_points, &scale, false);
    let about_face = start_posture(skeleton, person, &view, &rest_points, &scale, true);
    let mut document = Document {
        posture: PostureValues::from_posture(skeleton, &start),
        tasks,
        camera: Some(camera_spec(&camera)),
        ..Document::default()
    };
    // The feet on the floor where their rays meet it: only through the camera the keypoints were
    // seen with (a fitted one sees the floor at another pitch).
    let on_floor = if camera_fitted {
        &[][..]
    } else {
        &standing[..]
    };
    let search = Search {
        skeleton,
        document: &document,
        finder: &finder,
        view: &view,
        person,
        camera_fitted,
    };
    let (found, flips) = search.run([&start, &about_face], on_floor)?;
    // Comfort last, once, from the posture the image, the floor and balance chose.
    let (posture, report) = settle_comfort(skeleton, &document, &found.posture, found.report)?;
    document.posture = PostureValues::from_posture(skeleton, &posture);
    Ok(Lifted {
        document,
        posture,
        camera,
        camera_fitted,
        keypoints_used,
        standing,
        flips,
        report,
    })
}

/// A posture the lift's search found: its solve's report and how far its worst keypoint lands
/// from its pixel (px).
struct Found {
    posture: Posture,
    report: SolveReport,
    worst: f64,
}

impl Found {
    /// `other` in place of this one where its worst keypoint is nearer its pixel; whether it is.
    fn keep_better(&mut self, other: Found) -> bool {
        let better = other.worst < self.worst;
        if better {
            *self = other;
        }
        better
    }
}

/// What the lift's search solves: the document's tasks on the body, the keypoints seen through
/// the view.
struct Search<'a> {
    skeleton: &'a Skeleton,
    document: &'a Document,
    finder: &'a KeypointFinder,
    view: &'a View,
    person: &'a OpenPosePerson,
    camera_fitted: bool,
}

impl Search<'_> {
    /// The largest distance of a keypoint from its pixel in `posture` (px; see
    /// [`worst_pixel`]): all, or with `below` those of that joint's limb.
    fn off(&self, posture: &Posture, below: Option<usize>) -> f64 {
        let Search {
            skeleton,
            finder,
            view,
            person,
            ..
        } = *self;
        worst_pixel(skeleton, finder, posture, view, person, below)
    }

    /// A solve's posture with how far it lands from the keypoints.
    fn found(&self, (posture, report): (Posture, SolveReport)) -> Found {
        let worst = self.off(&posture, None);
        Found {
            posture,
            report,
            worst,
        }
    }

    /// A keypoint this close to its pixel counts as on it (px): through a fitted camera no
    /// posture lands every keypoint on its pixel, so more is tried only for what a wrong
    /// depth leaves (a limb's keypoints many pixels off).
    fn on_pixel(&self) -> f64 {
        if self.camera_fitted {
            FITTED_OFF_PX
        } else {
            ON_PIXEL_PX
        }
    }

    /// The search from `starts` (the plain start, and turned about), the feet of `on_floor`
    /// standing where their rays meet the floor: the placed start solved; from the plain start
    /// too when that led astray; the limbs left off solved alone; the flips in depth that
    /// bring limbs onto their keypoints; and the whole problem with the solver's restarts as
    /// the last resort. Returns the posture found and the joints flipped.
    fn run(
        &self,
        starts: [&Posture; 2],
        on_floor: &[String],
    ) -> Result<(Found, Vec<String>), LiftError> {
        let (skeleton, document) = (self.skeleton, self.document);
        let placed = placed_start(skeleton, document, starts, self.person, self.view, on_floor)?;
        let mut found = self.found(solve_pose(skeleton, document, &placed, POSE_ITERATIONS)?);
        let lost = found.worst > LOST_PX;
        if lost {
            // The placed start led astray (the torso's solve can run off along the rays from a
            // start turned the wrong way): the plain start solved in stages (tens of
            // milliseconds), where it does better; the whole problem with restarts (up to
            // seconds) only when neither this nor the depth flips below find the keypoints.
            found.keep_better(self.found(solve_pose(
                skeleton,
                document,
                starts[0],
                POSE_ITERATIONS,
            )?));
        }
        if found.worst > self.on_pixel() {
            found.keep_better(self.limbs_alone(&found)?);
        }
        let flips = self.flip_limbs(&mut found)?;
        // Still far off (more than a fitted camera's misfit) after a start that led astray.
        if lost && found.worst > FITTED_OFF_PX {
            let whole = self.found(crate::stages::solve_whole(
                skeleton,
                document,
                starts[0],
                POSE_ITERATIONS,
                LIFT_TOLERANCE_M,
            )?);
            if found.keep_better(whole) {
                return Ok((found, Vec::new()));
            }
        }
        Ok((found, flips))
    }

    /// What the stages leave off: each arm or leg whose keypoints are off solved alone (a hand
    /// whose elbow must move: the hand's stage holds the hinge; a nearly straight knee, where
    /// the body stage stalls). (The whole problem's iterations here before took 3 to 8 times
    /// as long for no better keypoints on the random family of `examples/lift_bench`.)
    fn limbs_alone(&self, found: &Found) -> Result<Found, LiftError> {
        let off_limbs: Vec<&LimbKeypoints> = LIMBS
            .iter()
            .filter(|limb| {
                self.skeleton
                    .joint_index(limb.joints[1])
                    .is_some_and(|middle| self.off(&found.posture, Some(middle)) > self.on_pixel())
            })
            .collect();
        Ok(self.found(crate::stages::solve_limbs(
            self.skeleton,
            self.document,
            &found.posture,
            &off_limbs,
            LIMB_ITERATIONS,
            LIFT_TOLERANCE_M,
        )?))
    }

    /// Up to [`MAX_FLIPS`] limbs flipped in depth ([`Search::best_flip`]) while a keypoint is
    /// off its pixel; returns the joints flipped, in order.
    fn flip_limbs(&self, found: &mut Found) -> Result<Vec<String>, LiftError> {
        let mut flips = Vec::new();
        for _ in 0..MAX_FLIPS {
            if found.worst <= self.on_pixel() {
                break;
            }
            let Some((joints, flipped)) = self.best_flip(found)? else {
                break;
            };
            flips.extend(joints);
            *found = flipped;
        }
        Ok(flips)
    }
}

/// A lift from the placed start leaving a keypoint this far off its pixel (px) is solved again
/// from the plain start (the rest body turned and placed): in stages first, and as the whole
/// problem with the solver's restarts if a keypoint is still over [`FITTED_OFF_PX`] off after
/// the whole problem's iterations and the flips.
const LOST_PX: f64 = 20.0;

/// Iterations of each limb's solve (an arm with its hand, a leg) after the stages when a
/// keypoint of it is left off its pixel.
const LIMB_ITERATIONS: usize = 30;

/// At most this many limbs are flipped in depth to meet the image level.
const MAX_FLIPS: usize = 3;

/// The floor level's residual in a solve (m).
fn floor_residual(report: &SolveReport) -> f64 {
    report
        .levels
        .iter()
        .find(|l| l.level == FLOOR_LEVEL)
        .map_or(0.0, |l| l.residual_after)
}

/// Through a fitted camera, a keypoint this close to its pixel is taken as the camera's misfit
/// (its pitch and distance are the default's), not a wrong depth: no flip is tried (px). A
/// limb at the wrong depth leaves its keypoints 5 to 40 px off at 768 px.
const FITTED_OFF_PX: f64 = 8.0;

/// A keypoint this close to its pixel counts as on it: no flip is tried (px). A wrong depth
/// puts a limb's keypoints pixels off its rays; a right one that the pose stage left short of
/// its tolerance stays within a pixel or so.
const ON_PIXEL_PX: f64 = 1.5;

/// The largest distance in the image between a seen keypoint and where `posture` puts it
/// (pixels; the renderer's projection of the body's keypoints, as `stance render` draws them).
/// With `below`, only the keypoints on that joint's segment or below it (a limb whose depth a
/// flip would change).
fn worst_pixel(
    skeleton: &Skeleton,
    finder: &KeypointFinder,
    posture: &Posture,
    view: &View,
    person: &OpenPosePerson,
    below: Option<usize>,
) -> f64 {
    let points = finder.find(skeleton, &Frames::new(skeleton, posture));
    let sources = finder.sources(skeleton);
    let on_limb = |joints: [Option<usize>; 2]| {
        below.is_none_or(|limb| {
            joints
                .into_iter()
                .flatten()
                .any(|joint| descends_from(skeleton, joint, limb))
        })
    };
    let body_joints = sources.body.map(|source| match source {
        Some(KeypointSource::On(e)) => [Some(e.joint), None],
        Some(KeypointSource::Between(a, b)) => [Some(a.joint), Some(b.joint)],
        None => [None, None],
    });
    let hand_joints =
        |hand: [Option<Effector>; HAND_KEYPOINTS]| hand.map(|e| [e.map(|e| e.joint), None]);
    let project = |p: Option<DVec3>| {
        let p = p?;
        view.camera
            .project(p.as_vec3(), view.size())
            .map(|px| px.as_dvec2())
    };
    let pairs = person
        .body
        .iter()
        .zip(points.body.map(project))
        .zip(body_joints)
        .chain(
            person
                .left_hand
                .iter()
                .zip(points.left_hand.map(project))
                .zip(hand_joints(sources.left_hand)),
        )
        .chain(
            person
                .right_hand
                .iter()
                .zip(points.right_hand.map(project))
                .zip(hand_joints(sources.right_hand)),
        );
    pairs
        .filter(|(_, joints)| on_limb(*joints))
        .filter_map(|((seen, got), _)| Some((*seen)?.distance(got.unwrap_or(DVec2::splat(1e9)))))
        .fold(0.0, f64::max)
}

/// The keypoint rays of a limb's middle and end joints, when both are seen.
fn limb_rays(person: &OpenPosePerson, view: &View, limb: &LimbKeypoints) -> Option<[Ray; 2]> {
    let [middle, end] = limb.keypoints;
    Some([view.ray(person.body[middle]?), view.ray(person.body[end]?)])
}

/// How far a limb's middle and end joints lie from their rays (m, summed).
fn off_rays(frames: &Frames, placed: &PlacedLimb, rays: [Ray; 2]) -> f64 {
    let [_, middle, end] = placed.positions(frames);
    let off = |p: DVec3, (origin, direction): Ray| {
        let v = p - origin;
        (v - direction * v.dot(direction)).length()
    };
    off(middle, rays[0]) + off(end, rays[1])
}

/// How far a limb is turned from rest: the sum of its joints' rotation angles (rad).
fn turned(skeleton: &Skeleton, posture: &Posture, placed: &PlacedLimb) -> f64 {
    placed
        .joints()
        .iter()
        .map(|&j| posture.rotation_vector(skeleton, j).length())
        .sum()
}

/// A limb to place on its keypoints' rays: its closed form, the rays of its middle and end
/// joints, and the floor's height when its end joint stands on it.
struct LimbOnRays {
    placed: PlacedLimb,
    rays: [Ray; 2],
    floor: Option<f64>,
}

impl LimbOnRays {
    /// The limb placed at each of its four depth choices from `posture` ([`PlacedLimb`]): the
    /// postures, with how far its joints land from their rays (m) and how far it turns from
    /// rest.
    fn choices(&self, skeleton: &Skeleton, posture: &Posture) -> Vec<(usize, Posture, f64, f64)> {
        let frames = Frames::new(skeleton, posture);
        self.placed
            .candidates(&frames, self.rays, self.floor)
            .into_iter()
            .enumerate()
            .map(|(choice, goal)| {
                let mut trial = posture.clone();
                self.placed.place(skeleton, &mut trial, goal);
                let off = off_rays(&Frames::new(skeleton, &trial), &self.placed, self.rays);
                let turn = turned(skeleton, &trial, &self.placed);
                (choice, trial, off, turn)
            })
            .collect()
    }
}

/// Off the rays by no more than this more than the best choice (m), a limb's depth choices
/// count as fitting as well: the one turned least from rest is taken.
const CHOICE_SLACK_M: f64 = 0.005;
/// Iterations of the torso's solve before the limbs are placed.
const TORSO_ITERATIONS: usize = 30;

/// The start of the solve: `start` with its torso solved onto the torso's keypoints (the limbs
/// held), then each arm and leg placed on its keypoints' rays in closed form, at the depth
/// choice that lands on them best and, among those that land as well, turns it least from
/// rest.
fn placed_start(
    skeleton: &Skeleton,
    document: &Document,
    starts: [&Posture; 2],
    person: &OpenPosePerson,
    view: &View,
    standing: &[String],
) -> Result<Posture, LiftError> {
    let Some(mut posture) =
        best_torso(skeleton, &torso_document(skeleton, document), starts, view)?
    else {
        return Ok(starts[0].clone());
    };
    for limb in limbs_on_rays(skeleton, person, view, standing) {
        let best = limb
            .choices(skeleton, &posture)
            .into_iter()
            .map(|(_, p, off, turn)| (p, off, turn))
            .reduce(|a, b| {
                let better =
                    b.1 < a.1 - CHOICE_SLACK_M || (b.1 <= a.1 + CHOICE_SLACK_M && b.2 < a.2);
                if better { b } else { a }
            });
        if let Some((p, _, _)) = best {
            posture = p;
        }
    }
    Ok(posture)
}

/// The arms and legs whose middle and end keypoints are seen, with their rays; a leg's foot
/// on the floor where its ankle is of `standing`.
fn limbs_on_rays(
    skeleton: &Skeleton,
    person: &OpenPosePerson,
    view: &View,
    standing: &[String],
) -> Vec<LimbOnRays> {
    let rest = Frames::new(skeleton, &Posture::rest(skeleton));
    let floor = |limb: &LimbKeypoints| {
        let ankle = limb.joints[2];
        standing
            .iter()
            .any(|s| s == ankle)
            .then(|| skeleton.joint_index(ankle))
            .flatten()
            .map(|j| rest.joint_position[j].y)
    };
    LIMBS
        .iter()
        .filter_map(|limb| {
            Some(LimbOnRays {
                placed: PlacedLimb::new(skeleton, limb.joints)?,
                rays: limb_rays(person, view, limb)?,
                floor: floor(limb),
            })
        })
        .collect()
}

/// `document` with only the torso's keypoints (those on no limb's middle joint or below it).
fn torso_document(skeleton: &Skeleton, document: &Document) -> Document {
    let middles: Vec<usize> = LIMBS
        .iter()
        .filter_map(|limb| skeleton.joint_index(limb.joints[1]))
        .collect();
    let on_torso = |task: &TaskSpec| match &task.kind {
        TaskKindSpec::Line { joint, .. } => skeleton
            .joint_index(joint)
            .is_some_and(|j| !middles.iter().any(|&m| descends_from(skeleton, j, m))),
        _ => false,
    };
    Document {
        tasks: document
            .tasks
            .iter()
            .filter(|t| on_torso(t))
            .cloned()
            .collect(),
        ..document.clone()
    }
}

/// `torso`'s keypoints solved from each of `starts` (facing as the keypoints say, and turned
/// about: the torso's solve keeps to the side it starts on, and the image's left and right
/// can mislead, a twisted trunk, a head turned over a shoulder): the posture that meets them
/// best before the camera.
fn best_torso(
    skeleton: &Skeleton,
    torso: &Document,
    starts: [&Posture; 2],
    view: &View,
) -> Result<Option<Posture>, LiftError> {
    let mut torsos = Vec::with_capacity(2);
    for start in starts {
        let (posture, report) = crate::stages::solve_staged(
            skeleton,
            torso,
            start,
            TORSO_ITERATIONS,
            LIFT_TOLERANCE_M,
            false,
        )?;
        // A torso behind the eye meets the rays too (the lines go on through it), and can
        // meet them better than the one before the camera: never taken.
        let root = Frames::new(skeleton, &posture)
            .joint_position
            .first()
            .copied();
        let residual = report
            .levels
            .iter()
            .find(|l| l.level == IMAGE_LEVEL)
            .filter(|_| root.is_some_and(|p| view.in_front(p)))
            .map_or(f64::INFINITY, |l| l.residual_after);
        torsos.push((posture, residual));
    }
    Ok(torsos
        .into_iter()
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .map(|(posture, _)| posture))
}

impl Search<'_> {
    /// The first limb whose keypoints are off their rays that a flip in depth
    /// ([`crate::flip_depth`]) brings nearer: flipped at its middle joint, its end joint, and
    /// both, each candidate solved again on the limb alone (its keypoints on its DOF: a leg's
    /// flip solves no hand, an arm's no torso; a third of the whole pose's cost); the one that
    /// brings the limb's keypoints nearest their pixels solved as the whole pose too (the torso
    /// may have to move with the limb), the better of the two kept if it halves the distance
    /// of the worst keypoint, or of the limb's (the others no further), and keeps the feet
    /// where they stood; with the joints flipped.
    fn best_flip(&self, found: &Found) -> Result<Option<(Vec<String>, Found)>, LiftError> {
        for limb in &LIMBS {
            let Some(limb_top) = self.skeleton.joint_index(limb.joints[1]) else {
                continue;
            };
            let limb_off = self.off(&found.posture, Some(limb_top));
            if limb_off <= ON_PIXEL_PX {
                continue;
            }
            let floor_kept = |solved: &Found| {
                floor_residual(&solved.report) <= floor_residual(&found.report) + FLOOR_KEPT_M
            };
            let mut best: Option<(Vec<&str>, Posture, f64, Found)> = None;
            for (joints, trial) in self.flip_candidates(&found.posture, limb) {
                let solved = self.found(crate::stages::solve_limbs(
                    self.skeleton,
                    self.document,
                    &trial,
                    &[limb],
                    CANDIDATE_ITERATIONS,
                    LIFT_TOLERANCE_M,
                )?);
                let solved_off = self.off(&solved.posture, Some(limb_top));
                if floor_kept(&solved) && best.as_ref().is_none_or(|b| solved_off < b.2) {
                    best = Some((joints, trial, solved_off, solved));
                }
            }
            let Some((joints, trial, _, mut solved)) = best else {
                continue;
            };
            // The torso may have to move with the limb: the whole pose from the flip too.
            let whole = self.found(solve_pose(
                self.skeleton,
                self.document,
                &trial,
                CANDIDATE_ITERATIONS,
            )?);
            if floor_kept(&whole) {
                solved.keep_better(whole);
            }
            let limb_halved = self.off(&solved.posture, Some(limb_top)) < 0.5 * limb_off;
            if solved.worst < 0.5 * found.worst || (limb_halved && solved.worst < found.worst) {
                let joints = joints.into_iter().map(str::to_owned).collect();
                return Ok(Some((joints, solved)));
            }
        }
        Ok(None)
    }

    /// `posture` with `limb` flipped in depth at its end joint, at both joints and at its
    /// middle joint, with the joints flipped; a flip that does not fit within the joints'
    /// ranges is no candidate.
    fn flip_candidates(
        &self,
        posture: &Posture,
        limb: &LimbKeypoints,
    ) -> Vec<(Vec<&'static str>, Posture)> {
        let [_, middle, end] = limb.joints;
        let flip = |p: &Posture, joint: &str| {
            crate::flip_depth(self.skeleton, p, &self.view.camera, joint).ok()
        };
        let flipped_middle = flip(posture, middle);
        [
            (vec![end], flip(posture, end)),
            (
                vec![middle, end],
                flipped_middle.as_ref().and_then(|p| flip(p, end)),
            ),
            (vec![middle], flipped_middle),
        ]
        .into_iter()
        .filter_map(|(joints, trial)| Some((joints, trial?)))
        .collect()
    }
}

/// A flip that takes the feet further than this from the floor than before (m) is refused.
const FLOOR_KEPT_M: f64 = 0.005;

/// Solves `document`'s tasks on `skeleton` from `start` (a lift's, or one flipped by
/// [`crate::flip_depth`]): the image, the floor and balance first ([`solve_pose`]), then a few
/// iterations of comfort among the postures they leave ([`settle_comfort`]).
pub fn solve(
    skeleton: &Skeleton,
    document: &Document,
    start: &Posture,
) -> Result<(Posture, SolveReport), LiftError> {
    let (posture, report) = solve_pose(skeleton, document, start, POSE_ITERATIONS)?;
    settle_comfort(skeleton, document, &posture, report)
}

/// Iterations of each stage when a flip candidate is solved: from a flip's exact start a
/// candidate that fits meets its levels within a few; the best one is kept as solved.
const CANDIDATE_ITERATIONS: usize = 20;
/// A level is met within this (m): a keypoint 0.1 mm off its ray is a hundredth of a pixel
/// at the distances images are taken from.
const LIFT_TOLERANCE_M: f64 = 1e-4;
/// Iterations of the pose stage: the image, the floor and balance are met well within them
/// when they can be; a stage that stalls stops sooner.
const POSE_ITERATIONS: usize = 200;
/// Iterations of comfort after the pose stage: the comfort level is never "met" (it moves
/// while its cost falls), so its share of the lift is bounded here.
const COMFORT_ITERATIONS: usize = 12;

/// `document`'s tasks without comfort, solved from `start`: what the flip search compares,
/// stopping once every level is met.
fn solve_pose(
    skeleton: &Skeleton,
    document: &Document,
    start: &Posture,
    iterations: usize,
) -> Result<(Posture, SolveReport), LiftError> {
    crate::stages::solve_staged(
        skeleton,
        document,
        start,
        iterations,
        LIFT_TOLERANCE_M,
        false,
    )
}

/// Comfort among the postures that keep the image, the floor and balance: a few iterations
/// from `posture`; the pose stage's result (`report`) stands when the document has no comfort
/// task or the comfort stage loses a higher level. The first [`COMFORT_PROBE_ITERATIONS`] tell
/// whether comfort has anything to change: where they lose a level, or move no DOF by more
/// than [`COMFORT_STILL`], the rest are not taken.
fn settle_comfort(
    skeleton: &Skeleton,
    document: &Document,
    posture: &Posture,
    report: SolveReport,
) -> Result<(Posture, SolveReport), LiftError> {
    if !document
        .tasks
        .iter()
        .any(|t| matches!(t.kind, TaskKindSpec::Comfort { .. }))
    {
        return Ok((posture.clone(), report));
    }
    let comfort = |from: &Posture, iterations: usize| {
        crate::stages::solve_staged(skeleton, document, from, iterations, LIFT_TOLERANCE_M, true)
    };
    let (probed, probe_report) = comfort(posture, COMFORT_PROBE_ITERATIONS)?;
    let moved = posture
        .values()
        .iter()
        .zip(probed.values())
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    if loses_a_level(&report, &probe_report) {
        return Ok((posture.clone(), report));
    }
    if moved <= COMFORT_STILL {
        return Ok((probed, probe_report));
    }
    let (settled, mut settled_report) =
        comfort(&probed, COMFORT_ITERATIONS - COMFORT_PROBE_ITERATIONS)?;
    if loses_a_level(&report, &settled_report) {
        Ok((posture.clone(), report))
    } else {
        settled_report.iterations += probe_report.iterations;
        Ok((settled, settled_report))
    }
}

/// Iterations of comfort that tell whether it has anything to change ([`settle_comfort`]).
const COMFORT_PROBE_ITERATIONS: usize = 3;
/// Comfort that moves no DOF by more than this in its first iterations (rad, or m for the
/// root's place) has nothing to change: on lift_bench's random family half the comfort stages
/// moved the posture by less than 0.01 rad in all their iterations.
const COMFORT_STILL: f64 = 0.01;

/// Whether the comfort stage's result (`after`) loses a level of the pose stage's (`before`):
/// strict priority keeps the higher levels, but a level that was met and no longer is (the
/// iteration budget cut a correction short), or one above comfort taken further from its goal
/// (a stage whose start was far off can run away in a few iterations), is lost.
fn loses_a_level(before: &SolveReport, after: &SolveReport) -> bool {
    before.levels.iter().any(|before| {
        after.levels.iter().any(|after| {
            after.level == before.level
                && ((before.met && !after.met)
                    || after.residual_after > before.residual_after + LIFT_TOLERANCE_M)
        })
    })
}

/// The rest body turned about the vertical to face as the keypoints say (its left and right
/// shoulders or hips apart in the image: how much it faces the camera; the nose before the
/// ears or neck: to which side it turns) and moved so that its keypoints' centroid lies on the
/// centroid's ray at the depth of the body's scale.
fn start_posture(
    skeleton: &Skeleton,
    person: &OpenPosePerson,
    view: &View,
    rest: &PoseKeypoints,
    scale: &Scale,
    about_face: bool,
) -> Posture {
    let body = &person.body;
    let across = |r: usize, l: usize| {
        let image = body[l]?.x - body[r]?.x;
        let width = (rest.body[l]? - rest.body[r]?).length();
        Some(image / (width * scale.px_per_m).max(1e-9))
    };
    let facing = across(R_SHOULDER, L_SHOULDER)
        .or_else(|| across(R_HIP, L_HIP))
        .unwrap_or(1.0)
        .clamp(-1.0, 1.0);
    let head = match (body[R_EAR], body[L_EAR]) {
        (Some(r), Some(l)) => Some((r + l) * 0.5),
        (Some(e), None) | (None, Some(e)) => Some(e),
        (None, None) => body[NECK],
    };
    let side = match (body[NOSE], head) {
        (Some(nose), Some(head)) => ((nose.x - head.x) / (0.09 * scale.px_per_m)).clamp(-1.0, 1.0),
        _ => 0.0,
    };
    // The image's x axis is the camera's right; turned by `camera.yaw` from the world's +X.
    let turn = f64::from(view.camera.yaw)
        + side.atan2(facing)
        + if about_face {
            std::f64::consts::PI
        } else {
            0.0
        };
    let rotation = DQuat::from_rotation_y(turn);
    let root = rest_root(skeleton);
    let visible: Vec<DVec3> = body
        .iter()
        .zip(rest.body)
        .filter_map(|(seen, at)| seen.and(at))
        .collect();
    let rest_centroid = visible.iter().sum::<DVec3>() / visible.len().max(1) as f64;
    let depth = if view.camera.orthographic {
        f64::from(view.camera.distance_m)
    } else {
        view.focal_px() / scale.px_per_m
    };
    let centre = view.at_depth(scale.centroid_px, depth);
    let shift = centre - root - rotation * (rest_centroid - root);
    let mut values = PostureValues::new();
    let name = skeleton
        .joints()
        .first()
        .map_or("humanoid_root", |j| j.name.as_str());
    let r = rotation.to_scaled_axis();
    for (dof, v) in [
        (Dof::Tx, shift.x),
        (Dof::Ty, shift.y),
        (Dof::Tz, shift.z),
        (Dof::Rx, r.x),
        (Dof::Ry, r.y),
        (Dof::Rz, r.z),
    ] {
        values.set(name, dof, v);
    }
    values
        .to_posture_at(skeleton, "posture")
        .unwrap_or_else(|_| Posture::rest(skeleton))
}

/// The root joint's rest position.
fn rest_root(skeleton: &Skeleton) -> DVec3 {
    Frames::new(skeleton, &Posture::rest(skeleton))
        .joint_position
        .first()
        .copied()
        .unwrap_or_default()
}

/// Lifts every person of `observed` onto `skeleton`, in the file's order, through one camera:
/// `camera`, else the one the file carries, else the one fitted to the first person (so that
/// where the people stand relative to each other comes from one view). A person whose
/// keypoints cannot be lifted fails the whole, naming them (1-based).
pub fn lift_people(
    skeleton: &Skeleton,
    observed: &crate::ObservedPose,
    camera: Option<OrbitCamera>,
) -> Result<Vec<Lifted>, LiftError> {
    let mut camera = camera.or(observed.camera);
    let mut lifted = Vec::with_capacity(observed.people.len());
    for (index, person) in observed.people.iter().enumerate() {
        let one = lift(skeleton, person, observed.size_px, camera)
            .map_err(|e| LiftError::Person(index + 1, Box::new(e)))?;
        camera = Some(one.camera);
        lifted.push(one);
    }
    if lifted.is_empty() {
        return Err(LiftError::NoPeople);
    }
    Ok(lifted)
}

/// The lifted people as one scene: a character each ("Person 1", "Person 2"...), where the lift
/// put them (their placements at the origin: each body's root holds its place in the camera's
/// world), the first one selected.
pub fn lifted_scene(people: &[Lifted]) -> stance_document::Scene {
    stance_document::Scene {
        characters: people
            .iter()
            .enumerate()
            .map(|(index, person)| stance_document::SceneCharacter {
                name: format!("Person {}", index + 1),
                placement: stance_document::Placement::default(),
                document: person.document.clone(),
            })
            .collect(),
        props: Vec::new(),
        selected: 0,
        between: Vec::new(),
        files: Vec::new(),
    }
}
