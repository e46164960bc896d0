//! Foot contacts: when a foot rests on the floor (low and slow), and how firmly each frame
//! holds it (ease-in and ease-out weights, so a constraint never pops on or off).

use glam::DVec3;
use serde::{Deserialize, Serialize};

/// Thresholds of the contact detection (all editable; defaults suit walks and runs).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct ContactSettings {
    /// A foot joint at most this high above its height standing at rest is low enough (m,
    /// default 0.05).
    pub height: f64,
    /// ... and moving horizontally at most this fast is still enough (m/s, default 0.35).
    pub speed: f64,
    /// Shortest contact kept (s, default 0.05).
    pub min_duration: f64,
    /// Ease-in and ease-out time around a contact (s, default 0.1).
    pub ease: f64,
}

impl Default for ContactSettings {
    fn default() -> Self {
        Self {
            height: 0.05,
            speed: 0.35,
            min_duration: 0.05,
            ease: 0.1,
        }
    }
}

impl ContactSettings {
    /// The ease time in frames at `frame_time` seconds per frame.
    pub fn ease_frames(&self, frame_time: f64) -> usize {
        let frames = self.ease / frame_time;
        if frames.is_finite() && frames > 0.0 {
            frames.round().min(1e6) as usize
        } else {
            0
        }
    }
}

/// One contact of a joint with the floor over a window of frames.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Contact {
    /// The H-Anim joint held (e.g. `l_talocrural`).
    pub joint: String,
    /// First frame of the contact.
    pub start: usize,
    /// Last frame of the contact (inclusive).
    pub end: usize,
    /// Where the joint is held (m, H-Anim frame).
    pub position: DVec3,
}

/// Contacts of one joint from its trajectory (`positions[f]`, m), its height standing at
/// rest (`rest_height`, m) and the frame time (s). Frames that are low and slow form runs;
/// runs shorter than `min_duration` are dropped; the joint is held at the mean horizontal
/// position of its run, at the run's mean height but never below `rest_height`.
pub fn detect_contacts(
    joint: &str,
    positions: &[DVec3],
    rest_height: f64,
    frame_time: f64,
    settings: &ContactSettings,
) -> Vec<Contact> {
    let n = positions.len();
    let speed = |f: usize| -> f64 {
        let (a, b) = match (f.checked_sub(1), f + 1 < n) {
            (Some(p), true) => (p, f + 1),
            (Some(p), false) => (p, f),
            (None, true) => (f, f + 1),
            (None, false) => return 0.0,
        };
        let d = positions[b] - positions[a];
        DVec3::new(d.x, 0.0, d.z).length() / (frame_time * (b - a) as f64)
    };
    let low =
        |f: usize| positions[f].y - rest_height <= settings.height && speed(f) <= settings.speed;
    let min_frames = (settings.min_duration / frame_time).round().max(1.0) as usize;
    let mut contacts = Vec::new();
    let mut f = 0;
    while f < n {
        if !low(f) {
            f += 1;
            continue;
        }
        let start = f;
        while f < n && low(f) {
            f += 1;
        }
        let end = f - 1;
        if end + 1 - start >= min_frames {
            let run = &positions[start..=end];
            let mean = run.iter().copied().sum::<DVec3>() / run.len() as f64;
            contacts.push(Contact {
                joint: joint.to_owned(),
                start,
                end,
                position: DVec3::new(mean.x, mean.y.max(rest_height), mean.z),
            });
        }
    }
    contacts
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
mod tests {
    use super::*;

    #[test]
    fn a_foot_that_stops_on_the_floor_is_one_contact_held_where_it_rested() {
        // 1 m/s swing, rest 10 frames at x = 0.5 on the floor, swing again.
        let dt = 0.01;
        let mut p = Vec::new();
        for f in 0..10 {
            p.push(DVec3::new(f as f64 * 0.05, 0.2, 0.0));
        }
        for _ in 0..10 {
            p.push(DVec3::new(0.5, 0.08, 0.0));
        }
        for f in 0..10 {
            p.push(DVec3::new(0.5 + f as f64 * 0.05, 0.2, 0.0));
        }
        let c = detect_contacts("l_talocrural", &p, 0.08, dt, &ContactSettings::default());
        assert_eq!(c.len(), 1);
        // Frame 10 moves 2.5 m/s by the central difference: not in contact. Frame 19 is
        // still (frame 20 lifts off straight up) and low: in contact.
        assert_eq!((c[0].start, c[0].end), (11, 19));
        assert!((c[0].position - DVec3::new(0.5, 0.08, 0.0)).length() < 1e-12);
        assert_eq!(contact_weight(&c[0], 15, 5), 1.0);
        assert_eq!(contact_weight(&c[0], 5, 5), 0.0);
        let w: Vec<f64> = (5..=11).map(|f| contact_weight(&c[0], f, 5)).collect();
        assert!(w.windows(2).all(|p| p[0] < p[1]), "{w:?}");
    }

    #[test]
    fn a_low_but_sliding_foot_and_a_short_touch_are_no_contacts() {
        let dt = 1.0 / 30.0;
        let slide: Vec<DVec3> = (0..20)
            .map(|f| DVec3::new(f as f64 * 0.05, 0.08, 0.0))
            .collect();
        assert!(detect_contacts("l", &slide, 0.08, dt, &ContactSettings::default()).is_empty());
        let mut touch = vec![DVec3::new(0.0, 0.3, 0.0); 10];
        touch[5] = DVec3::new(0.0, 0.08, 0.0);
        let s = ContactSettings {
            speed: 100.0,
            min_duration: 0.1,
            ..Default::default()
        };
        assert!(detect_contacts("l", &touch, 0.08, dt, &s).is_empty());
    }
}
