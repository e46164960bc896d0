//! What a retargeting run is judged by: contact drift and sinking, smoothness at constraint
//! boundaries.

use glam::{DQuat, DVec3};
use serde::{Deserialize, Serialize};
use stance_ik::{Posture, Skeleton};

use crate::contacts::Contact;

/// How firmly contacts held.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct ContactMetrics {
    /// Largest horizontal distance of a held point from where its contact began (m).
    pub max_drift: f64,
    /// Mean of that distance over the contact frames (m).
    pub mean_drift: f64,
    /// Deepest a held or sliding point went below the height it is held at (m, 0 if never).
    pub max_sink: f64,
    /// Highest a sliding point rose above the floor it is kept on (m, 0 if never).
    pub max_lift: f64,
    /// Contact frames measured (a held point's).
    pub frames: usize,
}

/// Contact metrics of point tracks: `track(contact, frame)` gives the world position of the
/// contact's point at that frame; it sinks where it is below the contact's held height, a
/// sliding point lifts where it is above it (a sliding point's drift is the clip's own).
pub fn contact_metrics(
    contacts: &[Contact],
    track: impl Fn(&Contact, usize) -> Option<DVec3>,
) -> ContactMetrics {
    let mut m = ContactMetrics::default();
    let mut sum = 0.0;
    for c in contacts {
        let Some(first) = track(c, c.start) else {
            continue;
        };
        for f in c.start..=c.end {
            let Some(p) = track(c, f) else {
                continue;
            };
            m.max_sink = m.max_sink.max(c.position.y - p.y);
            if c.slides {
                m.max_lift = m.max_lift.max(p.y - c.position.y);
                continue;
            }
            let d = DVec3::new(p.x - first.x, 0.0, p.z - first.z).length();
            m.max_drift = m.max_drift.max(d);
            sum += d;
            m.frames += 1;
        }
    }
    m.mean_drift = if m.frames > 0 {
        sum / m.frames as f64
    } else {
        0.0
    };
    m
}

/// Frame-to-frame joint motion.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct Smoothness {
    /// Largest change of any joint's local rotation between two frames next to a
    /// constraint boundary (rad).
    pub worst_boundary_jump: f64,
    /// Largest change of any joint's local rotation between two frames of the reference
    /// (the clip's own motion, rad).
    pub clip_max_jump: f64,
    /// Largest amount by which a joint's change between two frames next to a boundary
    /// exceeds the reference's own change of that joint there (rad; 0: the constraints
    /// added no jump).
    pub worst_boundary_excess: f64,
}

/// Per joint, the change of local rotation from `a` to `b` (rad).
fn jumps(skeleton: &Skeleton, a: &Posture, b: &Posture) -> Vec<f64> {
    (0..skeleton.joint_count())
        .map(|j| {
            let qa: DQuat = a.local_rotation(skeleton, j);
            let qb: DQuat = b.local_rotation(skeleton, j);
            qa.angle_between(qb)
        })
        .collect()
}

/// Smoothness of `postures` at the contacts' boundaries (within `ease` frames of a start or
/// an end) against the frame-to-frame motion of `reference`.
pub fn smoothness(
    skeleton: &Skeleton,
    postures: &[Posture],
    reference: &[Posture],
    contacts: &[Contact],
    ease: usize,
) -> Smoothness {
    let near = |f: usize| {
        contacts.iter().any(|c| {
            [c.start, c.end]
                .iter()
                .any(|&b| f + ease + 1 >= b && f <= b + ease + 1)
        })
    };
    let mut s = Smoothness::default();
    for f in 1..postures.len().min(reference.len()) {
        let own = jumps(skeleton, &reference[f - 1], &reference[f]);
        s.clip_max_jump = own.iter().copied().fold(s.clip_max_jump, f64::max);
        if near(f) {
            let out = jumps(skeleton, &postures[f - 1], &postures[f]);
            for (o, r) in out.iter().zip(&own) {
                s.worst_boundary_jump = s.worst_boundary_jump.max(*o);
                s.worst_boundary_excess = s.worst_boundary_excess.max(o - r);
            }
        }
    }
    s
}

/// Everything a retargeting run is judged by, side by side: the contacts as the clip itself
/// moves its feet (placed on the target), as the plain rotation copy does, and as the
/// retargeted result does; smoothness at the contacts' boundaries.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct Metrics {
    /// The clip's own feet, placed on the target.
    pub source: ContactMetrics,
    /// The plain rotation copy.
    pub copy: ContactMetrics,
    /// The retargeted result.
    pub output: ContactMetrics,
    /// Smoothness of the result against the copy's own frame-to-frame motion.
    pub smoothness: Smoothness,
    /// How far the tasks moved the joints from the plain copy (m): what the constraints
    /// changed in the motion.
    pub deviation: Deviation,
}

/// Distances of the joints of a result from those of a reference, over all frames.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct Deviation {
    /// Largest distance of any joint (m).
    pub max: f64,
    /// Mean over joints and frames (m).
    pub mean: f64,
}

/// How far `postures` put the joints of `skeleton` from where `reference` puts them.
pub fn deviation(skeleton: &Skeleton, postures: &[Posture], reference: &[Posture]) -> Deviation {
    let mut d = Deviation::default();
    let mut n = 0usize;
    for (a, b) in postures.iter().zip(reference) {
        let (fa, fb) = (
            stance_ik::Frames::new(skeleton, a),
            stance_ik::Frames::new(skeleton, b),
        );
        for (pa, pb) in fa.joint_position.iter().zip(&fb.joint_position) {
            let x = (*pa - *pb).length();
            d.max = d.max.max(x);
            d.mean += x;
            n += 1;
        }
    }
    if n > 0 {
        d.mean /= n as f64;
    }
    d
}

/// The metrics of `result`, retargeted from `clip` onto `target`; `ease`: the ease frames.
pub fn metrics(
    clip: &crate::Clip,
    target: &stance_hanim::HumanoidSkeleton,
    result: &super::Retargeted,
    ease: usize,
) -> Metrics {
    let skeleton = &target.skeleton;
    let on_target = |postures: &[Posture]| {
        let frames: Vec<stance_ik::Frames> = postures
            .iter()
            .map(|p| stance_ik::Frames::new(skeleton, p))
            .collect();
        contact_metrics(&result.contacts, |c, f| {
            let j = skeleton.joint_index(&c.joint)?;
            Some(frames.get(f)?.point(j, c.point))
        })
    };
    // The clip's own joint carrying the target's point (scaled back to the clip's size),
    // placed on the target.
    let scale = result.placement.root_scale.max(1e-9);
    let source = contact_metrics(&result.contacts, |c, f| {
        let j = clip.joint_of(&c.joint)?;
        let w = clip.world(clip.frames.get(f)?);
        w.get(j)
            .map(|x| result.placement.place(x.1 + x.0 * (c.point / scale)))
    });
    Metrics {
        source,
        copy: on_target(&result.copy),
        output: on_target(&result.postures),
        smoothness: smoothness(
            skeleton,
            &result.postures,
            &result.copy,
            &result.contacts,
            ease,
        ),
        deviation: deviation(skeleton, &result.postures, &result.copy),
    }
}
