//! Contacts with the ground: when a part of the body rests on it (low and still), and how
//! firmly each frame holds it (ease-in and ease-out weights, so a constraint never pops on or
//! off).
//!
//! Detection works on the clip's own motion (metres, H-Anim frame), one point track per part
//! that can touch the ground ([`ContactPart`]: the heel and the ball of each foot, the hands,
//! the knees, the pelvis):
//!
//! 1. **Reference frames** at the start (a T-pose or an A-pose followed by a cut or a blend
//!    into the motion, as the cgspeed releases of the CMU database have) are left out
//!    ([`reference_frames`]).
//! 2. **The ground** near each frame is a robust statistic, not the minimum: the 10th
//!    percentile, within half a second, of the lowest point of the body (each part's point
//!    less its clearance: how high it stands over the ground when it rests, found on the clip
//!    for the hands, knees and pelvis, [`clearances`]), so that a stray frame does not set it.
//!    Where a foot is the body's lowest still point above that ground for longer than a jump
//!    keeps still at its top (a step, a slope: the window still sees the floor below), the
//!    floor is raised there to that foot's level (`raised_floors`).
//! 3. A point is **low** within `height` of that ground (or of a floor raised there) and
//!    **still** while its horizontal speed, measured over `window` seconds (a central
//!    difference, so that 120-240 fps capture noise does not break a stance), is at most
//!    `speed`.
//! 4. **Thresholds scale** with the body and the clip: `height` and `speed` are given for a
//!    leg (hip to ankle) of [`REFERENCE_LEG`] and scale with the clip's leg; `speed` also
//!    scales with the clip's pace (its median root speed) over [`REFERENCE_PACE`] (runs). Runs of
//!    low and still frames shorter than `min_duration` are dropped, gaps shorter than the
//!    window are bridged. Each contact finds its own floor (its lower quartile) and spans the
//!    still frames at it on either side, whatever the ground there (a foot landed on a step
//!    while the other still stands on the floor below).
//! 5. **Sliding contacts**: a point of a foot that stays low for `min_duration` but moves
//!    faster than `speed` (at most [`SLIDE_SPEED_FACTOR`] times faster: a foot passing low
//!    in its swing moves faster still), at frames where no contact of that foot holds it
//!    still, slides on the ground: it is kept from sinking under the floor, not held in
//!    place ([`Contact::slides`]).

use glam::DVec3;
use serde::{Deserialize, Serialize};

use crate::clip::Clip;

/// The leg length (hip to ankle, m) for which [`ContactSettings::height`] and
/// [`ContactSettings::speed`] are given; a clip's thresholds scale with its own leg.
pub const REFERENCE_LEG: f64 = 0.9;
/// The pace (median horizontal root speed, m/s) up to which [`ContactSettings::speed`] holds
/// as given; a faster clip (a run) scales it up in proportion to its pace.
pub const REFERENCE_PACE: f64 = 1.2;
/// A point of a foot low on the ground and moving at most this many times `speed` slides on
/// it; faster, it is passing low in its swing.
pub const SLIDE_SPEED_FACTOR: f64 = 3.0;
/// Half the width of the window over which the ground is taken (s).
const GROUND_WINDOW: f64 = 0.5;
/// Gravity's acceleration (m/s²).
const GRAVITY: f64 = 9.81;

/// A part of the body that can rest on the ground.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ContactPart {
    /// The heel: the sole below the ankle, at its back.
    Heel,
    /// The ball of the foot (the metatarsophalangeal joints), on the sole.
    Ball,
    /// The hand (the wrist's centre).
    Hand,
    /// The knee.
    Knee,
    /// The pelvis (between the hip joints): sitting on the floor.
    Pelvis,
}

impl ContactPart {
    /// Every part, feet first.
    pub const ALL: [ContactPart; 5] = [
        ContactPart::Heel,
        ContactPart::Ball,
        ContactPart::Hand,
        ContactPart::Knee,
        ContactPart::Pelvis,
    ];

    /// Whether the part is a point of a foot's sole.
    pub fn is_foot(self) -> bool {
        matches!(self, ContactPart::Heel | ContactPart::Ball)
    }

    /// How high the part's point typically is above the ground it rests on, as a share of
    /// the leg (hip to ankle): 0 for the sole's points, the wrist's centre over the palm, the
    /// knee's centre over the kneecap, the hip joints over the seat. A clip that shows the
    /// part resting gives its own ([`clearances`]); this holds where it does not.
    pub fn clearance(self) -> f64 {
        match self {
            ContactPart::Heel | ContactPart::Ball => 0.0,
            ContactPart::Hand => 0.04,
            ContactPart::Knee => 0.07,
            ContactPart::Pelvis => 0.12,
        }
    }

    /// The most the part's point can stand above the ground it rests on, as a share of the
    /// leg (hip to ankle, about 0.49 of the stature): the wrist's centre a hand's length over
    /// the fingertips (0.11 of the stature), the knee's centre its depth over the shin it
    /// kneels on (0.06), the hip joints over the seat leaning back. A part found resting
    /// higher on a clip does not rest on it (standing, the corpus's knees rest no lower than
    /// 0.43 of the leg, its hands 0.74 and its pelvis 0.55).
    pub fn max_clearance(self) -> f64 {
        match self {
            ContactPart::Heel | ContactPart::Ball => 0.0,
            ContactPart::Hand => 0.22,
            ContactPart::Knee => 0.12,
            ContactPart::Pelvis => 0.2,
        }
    }

    /// The part in words.
    pub fn label(self) -> &'static str {
        match self {
            ContactPart::Heel => "heel",
            ContactPart::Ball => "ball of the foot",
            ContactPart::Hand => "hand",
            ContactPart::Knee => "knee",
            ContactPart::Pelvis => "pelvis",
        }
    }
}

/// Thresholds of the contact detection (all editable; defaults suit walks, runs and jumps).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct ContactSettings {
    /// A point at most this high above the ground is low enough (m for a leg of
    /// [`REFERENCE_LEG`], scaled with the clip's leg; default 0.05).
    pub height: f64,
    /// ... and moving horizontally at most this fast is still (m/s for a leg of
    /// [`REFERENCE_LEG`] at a pace up to [`REFERENCE_PACE`], scaled with the clip's leg and
    /// faster pace; default 0.35).
    pub speed: f64,
    /// Shortest contact kept (s, default 0.05).
    pub min_duration: f64,
    /// Ease-in and ease-out time around a contact (s, default 0.05).
    pub ease: f64,
    /// Time over which speeds are measured (s, default 0.08).
    pub window: f64,
    /// Whether hands, knees and the pelvis get contacts too (default true); feet always do.
    pub body_parts: bool,
}

impl Default for ContactSettings {
    fn default() -> Self {
        Self {
            height: 0.05,
            speed: 0.35,
            min_duration: 0.05,
            ease: 0.05,
            window: 0.08,
            body_parts: true,
        }
    }
}

impl ContactSettings {
    /// The ease time in frames at `frame_time` seconds per frame.
    pub fn ease_frames(&self, frame_time: f64) -> usize {
        frames_of(self.ease, frame_time)
    }

    /// The thresholds as they apply to a clip of this leg and pace.
    pub fn thresholds(&self, scale: &ClipScale) -> Thresholds {
        let s = if scale.leg.is_finite() && scale.leg > 0.0 {
            scale.leg / REFERENCE_LEG
        } else {
            1.0
        };
        let pace = if scale.pace.is_finite() {
            scale.pace
        } else {
            0.0
        };
        Thresholds {
            height: self.height * s,
            speed: self.speed * s * (pace / REFERENCE_PACE).max(1.0),
        }
    }
}

/// `seconds` in whole frames of `frame_time` (0 when not finite or not positive).
fn frames_of(seconds: f64, frame_time: f64) -> usize {
    let frames = seconds / frame_time;
    if frames.is_finite() && frames > 0.0 {
        frames.round().min(1e6) as usize
    } else {
        0
    }
}

/// The detection's thresholds as applied to one clip.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct Thresholds {
    /// Height above the ground (m).
    pub height: f64,
    /// Horizontal speed (m/s).
    pub speed: f64,
}

/// What the detection needs to know of the clip as a whole.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct ClipScale {
    /// Leg length, hip to knee to ankle at rest (m).
    pub leg: f64,
    /// Median horizontal speed of the root over the motion (m/s).
    pub pace: f64,
    /// First frame of the motion (the reference frames before it are left out).
    pub start: usize,
}

/// The track of one point that can rest on the ground.
#[derive(Debug, Clone, PartialEq)]
pub struct PointTrack {
    /// The H-Anim joint the point belongs to.
    pub joint: String,
    /// Which part.
    pub part: ContactPart,
    /// The point's offset in the joint's frame on the body being posed (what a contact
    /// holds).
    pub point: DVec3,
    /// World positions of the point on the clip, per frame (m).
    pub positions: Vec<DVec3>,
    /// For the ball of a foot: the tip of the toes on the clip, per frame (m), where the clip
    /// has toes. The ball is low also when the tip is (standing on tiptoe, the toes bent
    /// under a raised ball).
    pub tip: Option<Vec<DVec3>>,
}

/// One contact of a point with the ground over a window of frames.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Contact {
    /// The H-Anim joint held (e.g. `l_talocrural`).
    pub joint: String,
    /// Which part of the body.
    pub part: ContactPart,
    /// The point held, in the joint's frame (m).
    pub point: DVec3,
    /// First frame of the contact.
    pub start: usize,
    /// Last frame of the contact (inclusive).
    pub end: usize,
    /// Where the point is held (m; on the clip as detected, on the body once retargeted).
    pub position: DVec3,
    /// The ground under the contact: the median height of the point less its clearance over
    /// the contact (m, on the clip).
    pub floor: f64,
    /// How high the point stands over the ground it rests on, on the clip (m): the part's
    /// clearance found on the clip ([`clearances`]).
    #[serde(default)]
    pub clearance: f64,
    /// A sliding contact: a point of a foot low on the ground but moving (a shuffle, a toe
    /// that drags, a video capture's skating foot, a landing or toe-off under way), where no
    /// contact of that foot holds it still. It is kept from sinking under the floor (the
    /// height of `position`), not held in place: the clip moves it along. Its `floor` is the
    /// ground's there.
    #[serde(default)]
    pub slides: bool,
}

/// The value a share `q` (0 to 1) of the way up `values` (reordering them): the one at
/// index `len · q` once sorted. `None` when there are none.
pub(crate) fn quantile(values: &mut [f64], q: f64) -> Option<f64> {
    let last = values.len().checked_sub(1)?;
    let k = ((values.len() as f64 * q) as usize).min(last);
    Some(*values.select_nth_unstable_by(k, f64::total_cmp).1)
}

/// How high each track's point stands over the ground when it rests, on this clip (m): 0 for
/// the sole's points; for a hand, a knee or the pelvis, its resting height found on the clip,
/// the 10th percentile of its height over the frames it is still (`speeds` at most
/// `limits.speed`, both sides of the body together), over the feet's floor (the 10th
/// percentile of the lowest sole point's height). A joint's centre stands over what it rests
/// on by as much as the capture's skeleton puts it there (the crawl of the corpus rests its
/// wrists 14 % of its leg over its feet's floor, its knees 3.4 %), not by a share fixed for
/// every body.
/// A part found resting higher than [`ContactPart::max_clearance`] never rests on the clip
/// (a hand hanging at the side, a knee standing): it keeps [`ContactPart::clearance`].
pub fn clearances(
    tracks: &[PointTrack],
    speeds: &[Vec<f64>],
    limits: &Thresholds,
    scale: &ClipScale,
) -> Vec<f64> {
    let n = tracks.iter().map(|t| t.positions.len()).min().unwrap_or(0);
    let typical: Vec<f64> = tracks
        .iter()
        .map(|t| t.part.clearance() * scale.leg)
        .collect();
    let mut soles: Vec<f64> = (scale.start..n)
        .map(|f| {
            tracks
                .iter()
                .filter(|t| t.part.is_foot())
                .map(|t| low_height(t, 0.0, f))
                .fold(f64::INFINITY, f64::min)
        })
        .filter(|y| y.is_finite())
        .collect();
    let Some(floor) = quantile(&mut soles, 0.1) else {
        return typical;
    };
    let mut resting = Vec::new();
    for part in ContactPart::ALL.into_iter().filter(|p| !p.is_foot()) {
        let mut heights: Vec<f64> = tracks
            .iter()
            .zip(speeds)
            .filter(|(t, _)| t.part == part)
            .flat_map(|(t, speed)| {
                (scale.start..n)
                    .filter(|&f| speed.get(f).is_some_and(|&v| v <= limits.speed))
                    .map(move |f| t.positions[f].y - floor)
            })
            .filter(|h| h.is_finite())
            .collect();
        if let Some(h) = quantile(&mut heights, 0.1)
            && h <= part.max_clearance() * scale.leg
        {
            resting.push((part, h.max(0.0)));
        }
    }
    tracks
        .iter()
        .zip(typical)
        .map(|(t, typical)| {
            resting
                .iter()
                .find(|(p, _)| *p == t.part)
                .map_or(typical, |&(_, h)| h)
        })
        .collect()
}

/// The ground near each frame: the 10th percentile, within `GROUND_WINDOW` seconds and
/// from `start` on, of the lowest of the tracks' points less their `clearances` (m).
pub fn ground(
    tracks: &[PointTrack],
    clearances: &[f64],
    frame_time: f64,
    scale: &ClipScale,
) -> Vec<f64> {
    let n = tracks.iter().map(|t| t.positions.len()).min().unwrap_or(0);
    let lowest: Vec<f64> = (0..n)
        .map(|f| {
            tracks
                .iter()
                .zip(clearances)
                .map(|(t, c)| t.positions[f].y - c)
                .fold(f64::INFINITY, f64::min)
        })
        .collect();
    let half = frames_of(GROUND_WINDOW, frame_time).max(1);
    let start = scale.start.min(n.saturating_sub(1));
    let mut window = Vec::with_capacity(2 * half + 1);
    (0..n)
        .map(|f| {
            let a = f.saturating_sub(half).max(start);
            let b = (f + half).min(n - 1).max(a);
            window.clear();
            window.extend(lowest[a..=b].iter().copied().filter(|y| y.is_finite()));
            quantile(&mut window, 0.1).unwrap_or(0.0)
        })
        .collect()
}

/// The floors raised over the ground where a foot stands above it (a step, a slope climbed, a
/// stair walked down: the window's statistic still sees, for up to half a second, the floor
/// the other foot left), per frame: over every stretch of at least `hold` frames where the
/// lowest of the points still then (horizontally, `velocity`) is a point of a foot, still in
/// height too, at one level (each frame within a third of `height` of the one before), and
/// that level (the stretch's lower quartile) is over `ground` by more than `height` at one
/// frame of it at least. The body stands on its lowest still point; a foot still at the top
/// of a jump, the one other way to be lowest and still, stays within the still speed
/// vertically for `2 · speed / g` only, under `hold`. A hand or a knee still in the air while
/// the feet move raises nothing.
fn raised_floors(
    tracks: &[PointTrack],
    (clearances, velocity): (&[f64], &[Vec<DVec3>]),
    ground: &[f64],
    limits: &Thresholds,
    (start, hold): (usize, usize),
) -> Vec<Option<f64>> {
    let n = ground.len();
    // Per frame, the height of the foot that supports the body, where a foot does.
    let support = |f: usize| -> Option<f64> {
        let (k, y) = tracks
            .iter()
            .zip(clearances)
            .enumerate()
            .filter(|(k, _)| {
                velocity[*k]
                    .get(f)
                    .is_some_and(|v| horizontal(*v) <= limits.speed)
            })
            .map(|(k, (t, &c))| (k, low_height(t, c, f)))
            .min_by(|a, b| a.1.total_cmp(&b.1))?;
        let still = velocity[k]
            .get(f)
            .is_some_and(|v| v.y.abs() <= limits.speed);
        (tracks[k].part.is_foot() && still).then_some(y)
    };
    let levels: Vec<Option<f64>> = (0..n)
        .map(|f| if f >= start { support(f) } else { None })
        .collect();
    let mut raised = vec![None; n];
    let mut f = 0;
    while f < n {
        let Some(mut last) = levels[f] else {
            f += 1;
            continue;
        };
        let a = f;
        f += 1;
        while let Some(y) = levels.get(f).copied().flatten() {
            if (y - last).abs() > limits.height / 3.0 {
                break;
            }
            last = y;
            f += 1;
        }
        let mut stretch: Vec<f64> = levels[a..f].iter().flatten().copied().collect();
        let Some(level) = quantile(&mut stretch, 0.25) else {
            continue;
        };
        if f - a >= hold && ground[a..f].iter().any(|g| level - g > limits.height) {
            for r in &mut raised[a..f] {
                *r = Some(level);
            }
        }
    }
    raised
}

/// The horizontal length of `v`.
fn horizontal(v: DVec3) -> f64 {
    DVec3::new(v.x, 0.0, v.z).length()
}

/// Velocity of `positions` at each frame, over `half` frames on either side (within
/// `start..`), m/s.
fn velocities(positions: &[DVec3], start: usize, half: usize, frame_time: f64) -> Vec<DVec3> {
    let n = positions.len();
    (0..n)
        .map(|f| {
            let a = f.saturating_sub(half).max(start.min(f));
            let b = (f + half).min(n - 1);
            if b <= a {
                return DVec3::ZERO;
            }
            (positions[b] - positions[a]) / (frame_time * (b - a) as f64)
        })
        .collect()
}

/// The contacts of every track (see the module documentation); each holds its point at its
/// mean position over the contact (on the clip; the retargeting places it on the body).
pub fn detect_contacts(
    tracks: &[PointTrack],
    frame_time: f64,
    scale: &ClipScale,
    settings: &ContactSettings,
) -> Vec<Contact> {
    let limits = settings.thresholds(scale);
    let n = tracks.iter().map(|t| t.positions.len()).min().unwrap_or(0);
    let half = frames_of(settings.window * 0.5, frame_time).max(1);
    let min_frames = frames_of(settings.min_duration, frame_time).max(1);
    // Each track's positions up to the shortest track's length, its velocities and its
    // horizontal speeds.
    let positions: Vec<&[DVec3]> = tracks.iter().map(|t| &t.positions[..n]).collect();
    let velocity: Vec<Vec<DVec3>> = positions
        .iter()
        .map(|p| velocities(p, scale.start, half, frame_time))
        .collect();
    let speed: Vec<Vec<f64>> = velocity
        .iter()
        .map(|v| v.iter().copied().map(horizontal).collect())
        .collect();
    let clearances = clearances(tracks, &speed, &limits, scale);
    let ground = ground(tracks, &clearances, frame_time, scale);
    // Twice as long as a free fall stays within the still speed vertically.
    let hold = frames_of(4.0 * limits.speed / GRAVITY, frame_time).max(min_frames);
    let raised = raised_floors(
        tracks,
        (&clearances, &velocity),
        &ground,
        &limits,
        (scale.start, hold),
    );
    let mut contacts = Vec::new();
    for (((track, positions), speed), &clearance) in
        tracks.iter().zip(&positions).zip(&speed).zip(&clearances)
    {
        // Low: at most `height` over the ground, or within `height` of a floor raised there
        // (a point under it stands on the ground below).
        let rest = |f: usize| {
            let h = low_height(track, clearance, f);
            f >= scale.start
                && (h - ground[f] <= limits.height
                    || raised[f].is_some_and(|y| (h - y).abs() <= limits.height))
                && speed[f] <= limits.speed
        };
        let runs = runs_of(positions.len(), rest, |a, b| b - a <= half);
        // The first frame the next contact may take (after the last one pushed).
        let mut free = scale.start;
        for (k, &(start, end)) in runs.iter().enumerate() {
            // The run's own floor (its lower quartile); frames at either end that have
            // risen over a third of `height` above it are no longer resting (a heel lifting
            // while the ball holds, a ball lifting after the heel strike).
            let mut heights: Vec<f64> = positions[start..=end]
                .iter()
                .map(|p| p.y - clearance)
                .collect();
            let Some(floor) = quantile(&mut heights, 0.25) else {
                continue;
            };
            let up = |f: usize| positions[f].y - clearance - floor > limits.height / 3.0;
            let (mut start, mut end) = (start, end);
            while start < end && up(start) {
                start += 1;
            }
            while end > start && up(end) {
                end -= 1;
            }
            if end + 1 - start < min_frames {
                continue;
            }
            // Frames either side where the point is still at that floor rest on it too,
            // whatever the ground there: a foot landed on a step while the other still
            // stood on the floor below (the lowest still point, the ground then).
            let next = runs.get(k + 1).map_or(positions.len(), |r| r.0);
            let on_floor = |f: usize| speed[f] <= limits.speed && !up(f);
            while start > free && on_floor(start - 1) {
                start -= 1;
            }
            while end + 1 < next && on_floor(end + 1) {
                end += 1;
            }
            free = end + 1;
            contacts.push(contact_over(track, (start, end), (floor, clearance), false));
        }
    }
    let held = contacts.len();
    for ((track, positions), speed) in tracks.iter().zip(&positions).zip(&speed) {
        if !track.part.is_foot() {
            continue;
        }
        // Frames where a contact of this foot (either point) holds it still.
        let mut still = vec![false; positions.len()];
        for c in contacts[..held].iter().filter(|c| c.joint == track.joint) {
            for s in still.iter_mut().take(c.end + 1).skip(c.start) {
                *s = true;
            }
        }
        let low = |f: usize| {
            f >= scale.start
                && !still[f]
                && low_height(track, 0.0, f) - ground[f] <= limits.height
                && speed[f] <= SLIDE_SPEED_FACTOR * limits.speed
        };
        // A short rise bridged, not a frame held still.
        let bridged = |a: usize, b: usize| b - a <= half && !still[a..b].iter().any(|&s| s);
        for (start, end) in runs_of(positions.len(), low, bridged) {
            if end + 1 - start < min_frames {
                continue;
            }
            let mut under = ground[start..=end].to_vec();
            let Some(floor) = quantile(&mut under, 0.5) else {
                continue;
            };
            contacts.push(contact_over(track, (start, end), (floor, 0.0), true));
        }
    }
    contacts
}

/// The runs of frames `0..len` that are `in_run` (first and last, inclusive), a gap from the
/// last frame `a` of one to the first `b` of the next joined where `bridged(a, b)`.
fn runs_of(
    len: usize,
    in_run: impl Fn(usize) -> bool,
    bridged: impl Fn(usize, usize) -> bool,
) -> Vec<(usize, usize)> {
    let mut runs: Vec<(usize, usize)> = Vec::new();
    let mut f = 0;
    while f < len {
        if !in_run(f) {
            f += 1;
            continue;
        }
        let start = f;
        while f < len && in_run(f) {
            f += 1;
        }
        match runs.last_mut() {
            Some(last) if bridged(last.1, start) => last.1 = f - 1,
            _ => runs.push((start, f - 1)),
        }
    }
    runs
}

/// The height that makes a track's point low at frame `f`: its own less its `clearance`, or,
/// under a ball, the toes' tip's where lower.
fn low_height(track: &PointTrack, clearance: f64, f: usize) -> f64 {
    let own = track
        .positions
        .get(f)
        .map_or(f64::INFINITY, |p| p.y - clearance);
    track
        .tip
        .as_ref()
        .and_then(|t| t.get(f))
        .map_or(own, |t| own.min(t.y))
}

/// A contact of `track`'s point over the frames `start..=end`, held at its mean position,
/// over `floor` by `clearance`.
fn contact_over(
    track: &PointTrack,
    (start, end): (usize, usize),
    (floor, clearance): (f64, f64),
    slides: bool,
) -> Contact {
    let run = &track.positions[start..=end];
    let mean = run.iter().copied().sum::<DVec3>() / run.len().max(1) as f64;
    Contact {
        joint: track.joint.clone(),
        part: track.part,
        point: track.point,
        start,
        end,
        position: mean,
        floor,
        clearance,
        slides,
    }
}

/// The frames at the start of `clip` that are a reference rather than motion: a T-pose or an
/// A-pose (both upper arms at most 55 degrees below horizontal, both legs straight within 15
/// degrees) from the first frame on, when it ends in a cut or a blend into the motion (a
/// frame-to-frame change of the joints' rotations over three times the clip's median), then
/// the frames of that blend (at most a second). 0 when the clip starts in motion or lacks
/// the arms and legs to tell.
pub fn reference_frames(clip: &Clip) -> usize {
    let n = clip.frames.len();
    let names = [
        "l_shoulder",
        "l_elbow",
        "r_shoulder",
        "r_elbow",
        "l_hip",
        "l_knee",
        "l_talocrural",
        "r_hip",
        "r_knee",
        "r_talocrural",
    ];
    let Some(joints) = names
        .iter()
        .map(|name| clip.joint_of(name))
        .collect::<Option<Vec<usize>>>()
    else {
        return 0;
    };
    if n < 3 {
        return 0;
    }
    let reference_pose = |f: usize| {
        let w = clip.world(&clip.frames[f]);
        let at = |k: usize| w.get(joints[k]).map_or(DVec3::ZERO, |x| x.1);
        let arm_up = |s: usize, e: usize| {
            let d = (at(e) - at(s)).normalize_or_zero();
            (-d.y).asin().to_degrees() <= 55.0
        };
        let straight = |h: usize, k: usize, a: usize| {
            (at(k) - at(h)).angle_between(at(a) - at(k)).to_degrees() <= 15.0
        };
        arm_up(0, 1) && arm_up(2, 3) && straight(4, 5, 6) && straight(7, 8, 9)
    };
    let mapped: Vec<usize> = (0..clip.joints.len())
        .filter(|&j| clip.mapping.hanim_of(j).is_some())
        .collect();
    let change = |f: usize| -> f64 {
        let (a, b) = (&clip.frames[f - 1], &clip.frames[f]);
        mapped
            .iter()
            .map(|&j| match (a.rotations.get(j), b.rotations.get(j)) {
                (Some(p), Some(q)) => p.angle_between(*q),
                _ => 0.0,
            })
            .sum()
    };
    let changes: Vec<f64> = (1..n).map(change).collect();
    let mut sorted = changes.clone();
    sorted.sort_by(f64::total_cmp);
    let sharp = 3.0 * sorted[sorted.len() / 2];
    let limit = frames_of(2.0, clip.frame_time).clamp(1, n / 2);
    let mut start = 0;
    while start < limit && reference_pose(start) {
        start += 1;
    }
    if start == 0 || start >= limit || changes[start - 1] <= sharp {
        return 0;
    }
    let blend_end = (start + frames_of(1.0, clip.frame_time)).min(n / 2);
    while start < blend_end && changes[start - 1] > sharp {
        start += 1;
    }
    start
}

/// How much a contact holds at `frame`: 1 inside it, easing to 0 over `ease_frames` on both
/// sides (smoothstep: zero slope at both ends, so nothing pops).
pub fn contact_weight(contact: &Contact, frame: usize, ease_frames: usize) -> f64 {
    let distance = if frame < contact.start {
        contact.start - frame
    } else if frame > contact.end {
        frame - contact.end
    } else {
        return 1.0;
    };
    if distance > ease_frames || ease_frames == 0 {
        return 0.0;
    }
    let x = 1.0 - distance as f64 / (ease_frames as f64 + 1.0);
    x * x * (3.0 - 2.0 * x)
}

#[cfg(test)]
mod tests;
