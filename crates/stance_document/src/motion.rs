//! Time in a document: the active interval of a task ([`TaskInterval`]) and the `motion`
//! section ([`MotionSection`]: the editor's timeline length and its keyframes). Both are
//! optional; a document without them is a single posture, as before.

use serde::ser::SerializeMap;
use serde::{Serialize, Serializer};
use serde_json::Value;

use crate::DocumentError;
use crate::document::PostureValues;
use crate::json::{arr, field, number, obj};

/// Seconds per frame of a timeline without a clip (30 fps).
pub const DEFAULT_FRAME_TIME: f64 = 1.0 / 30.0;
/// Frames of a timeline without a clip (2 s at 30 fps).
pub const DEFAULT_FRAME_COUNT: usize = 60;
/// Most frames a timeline may have, and the frames a key may be at (a document or a link
/// with more is refused: the editor walks every frame of its timeline).
pub const MAX_FRAME_COUNT: usize = 10_000_000;

/// `3x² − 2x³` of `x` clamped to `[0, 1]`: zero slope at both ends.
pub fn smoothstep(x: f64) -> f64 {
    let x = x.clamp(0.0, 1.0);
    x * x * (3.0 - 2.0 * x)
}

/// When a task acts on a timeline (seconds): fully between `start` and `end`, easing in over
/// `ease_in` before `start` and out over `ease_out` after `end` (smoothstep), not at all
/// outside. A task without an interval always acts.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TaskInterval {
    /// First second of full effect.
    pub start: f64,
    /// Last second of full effect (>= `start`).
    pub end: f64,
    /// Seconds of ramp before `start` (>= 0).
    pub ease_in: f64,
    /// Seconds of ramp after `end` (>= 0).
    pub ease_out: f64,
}

impl TaskInterval {
    /// Full effect from `start` to `end`, no ramps.
    pub fn new(start: f64, end: f64) -> Self {
        Self {
            start,
            end,
            ease_in: 0.0,
            ease_out: 0.0,
        }
    }

    /// The task's weight at `time` seconds: 0 outside, 1 inside, smoothstep on the ramps.
    pub fn weight(&self, time: f64) -> f64 {
        if time < self.start {
            if self.ease_in > 0.0 {
                smoothstep((time - (self.start - self.ease_in)) / self.ease_in)
            } else {
                0.0
            }
        } else if time > self.end {
            if self.ease_out > 0.0 {
                smoothstep(1.0 - (time - self.end) / self.ease_out)
            } else {
                0.0
            }
        } else {
            1.0
        }
    }

    /// Checks the numbers (paths relative: `interval.end`).
    pub fn validate(&self) -> Result<(), DocumentError> {
        for (name, value) in [
            ("start", self.start),
            ("end", self.end),
            ("ease_in", self.ease_in),
            ("ease_out", self.ease_out),
        ] {
            if !value.is_finite() {
                return Err(DocumentError::field(
                    format!("interval.{name}"),
                    "not a finite number",
                ));
            }
        }
        if self.end < self.start {
            return Err(DocumentError::field(
                "interval.end",
                "must not come before `start`",
            ));
        }
        if self.ease_in < 0.0 || self.ease_out < 0.0 {
            return Err(DocumentError::field("interval", "ease times must be >= 0"));
        }
        Ok(())
    }

    /// Parses `{"start": s, "end": s, "ease_in": s, "ease_out": s}` (eases default to 0);
    /// `at` is its path.
    pub fn from_json_value(v: &Value, at: &str) -> Result<Self, DocumentError> {
        let o = obj(v, at)?;
        let here = |name: &str| format!("{at}.{name}");
        let optional = |name: &str| -> Result<f64, DocumentError> {
            match o.get(name).filter(|v| !v.is_null()) {
                None => Ok(0.0),
                Some(v) => number(v, &here(name)),
            }
        };
        let interval = Self {
            start: number(field(o, "start", at)?, &here("start"))?,
            end: number(field(o, "end", at)?, &here("end"))?,
            ease_in: optional("ease_in")?,
            ease_out: optional("ease_out")?,
        };
        let prefix = at.strip_suffix("interval").unwrap_or(at);
        interval.validate().map_err(|error| {
            if prefix.is_empty() {
                error
            } else {
                error.within(prefix.trim_end_matches('.'))
            }
        })?;
        Ok(interval)
    }
}

impl Serialize for TaskInterval {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let mut m = s.serialize_map(Some(4))?;
        m.serialize_entry("start", &self.start)?;
        m.serialize_entry("end", &self.end)?;
        m.serialize_entry("ease_in", &self.ease_in)?;
        m.serialize_entry("ease_out", &self.ease_out)?;
        m.end()
    }
}

/// One keyframe: the whole posture at a frame of the timeline.
#[derive(Debug, Clone, PartialEq)]
pub struct MotionKey {
    /// The frame (0-based).
    pub frame: usize,
    /// The posture at that frame (joint DOF values, as the document's `posture`).
    pub posture: PostureValues,
}

/// The editor's timeline: its frame rate and length, and the keyframes. With a clip open the
/// keys are an additive layer over the clip (each key is the clip's posture at its frame
/// changed by the key's rotations); without one, plain keyframe poses over the rest posture.
#[derive(Debug, Clone, PartialEq)]
pub struct MotionSection {
    /// Seconds per frame (> 0).
    pub frame_time: f64,
    /// Frames of the timeline (>= 1).
    pub frame_count: usize,
    /// The keys, in frame order, at most one per frame.
    pub keys: Vec<MotionKey>,
}

impl Default for MotionSection {
    fn default() -> Self {
        Self {
            frame_time: DEFAULT_FRAME_TIME,
            frame_count: DEFAULT_FRAME_COUNT,
            keys: Vec::new(),
        }
    }
}

impl MotionSection {
    /// Checks the numbers and the key order (paths from `motion`). Keys may lie beyond the
    /// last frame (a timeline made shorter keeps them), not beyond [`MAX_FRAME_COUNT`].
    pub fn validate(&self) -> Result<(), DocumentError> {
        if !(self.frame_time.is_finite() && self.frame_time > 0.0) {
            return Err(DocumentError::field(
                "motion.frame_time",
                "must be a finite number > 0",
            ));
        }
        if self.frame_count == 0 {
            return Err(DocumentError::field("motion.frame_count", "must be >= 1"));
        }
        if self.frame_count > MAX_FRAME_COUNT {
            return Err(DocumentError::field(
                "motion.frame_count",
                format!("must be at most {MAX_FRAME_COUNT}"),
            ));
        }
        for (i, key) in self.keys.iter().enumerate() {
            if key.frame >= MAX_FRAME_COUNT {
                return Err(DocumentError::field(
                    format!("motion.keys[{i}].frame"),
                    format!("must be below {MAX_FRAME_COUNT}"),
                ));
            }
            if i > 0 && self.keys[i - 1].frame >= key.frame {
                return Err(DocumentError::field(
                    format!("motion.keys[{i}].frame"),
                    "keys must be in frame order, one per frame",
                ));
            }
            key.posture
                .validate_at(&format!("motion.keys[{i}].posture"))?;
        }
        Ok(())
    }

    /// Parses the `motion` object (`frame_time` and `frame_count` default to 30 fps and 60
    /// frames, `keys` to none).
    pub fn from_json_value(v: &Value) -> Result<Self, DocumentError> {
        let at = "motion";
        let o = obj(v, at)?;
        let opt = |name: &str| o.get(name).filter(|v| !v.is_null());
        let frame_time = match opt("frame_time") {
            None => DEFAULT_FRAME_TIME,
            Some(t) => number(t, "motion.frame_time")?,
        };
        let frame_count = match opt("frame_count") {
            None => DEFAULT_FRAME_COUNT,
            Some(n) => count(n, "motion.frame_count")?,
        };
        let keys = match opt("keys") {
            None => Vec::new(),
            Some(list) => arr(list, "motion.keys")?
                .iter()
                .enumerate()
                .map(|(i, key)| {
                    let here = format!("motion.keys[{i}]");
                    let k = obj(key, &here)?;
                    Ok(MotionKey {
                        frame: count(field(k, "frame", &here)?, &format!("{here}.frame"))?,
                        posture: PostureValues::from_json_value(
                            field(k, "posture", &here)?,
                            &format!("{here}.posture"),
                        )?,
                    })
                })
                .collect::<Result<_, DocumentError>>()?,
        };
        let section = Self {
            frame_time,
            frame_count,
            keys,
        };
        section.validate()?;
        Ok(section)
    }
}

/// A non-negative integer.
fn count(v: &Value, at: &str) -> Result<usize, DocumentError> {
    let n = number(v, at)?;
    if n < 0.0 || n.fract() != 0.0 || n > 1e9 {
        return Err(DocumentError::field(at, "expected an integer >= 0"));
    }
    Ok(n as usize)
}

impl Serialize for MotionKey {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let mut m = s.serialize_map(Some(2))?;
        m.serialize_entry("frame", &self.frame)?;
        m.serialize_entry("posture", &self.posture)?;
        m.end()
    }
}

impl Serialize for MotionSection {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let mut m = s.serialize_map(Some(3))?;
        m.serialize_entry("frame_time", &self.frame_time)?;
        m.serialize_entry("frame_count", &self.frame_count)?;
        m.serialize_entry("keys", &self.keys)?;
        m.end()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_interval_eases_in_and_out_by_smoothstep() {
        let interval = TaskInterval {
            start: 1.0,
            end: 2.0,
            ease_in: 0.5,
            ease_out: 0.5,
        };
        assert_eq!(interval.weight(0.4), 0.0);
        assert!((interval.weight(0.75) - 0.5).abs() < 1e-12);
        assert_eq!(interval.weight(1.5), 1.0);
        assert!((interval.weight(2.25) - 0.5).abs() < 1e-12);
        assert_eq!(interval.weight(2.6), 0.0);
        assert_eq!(TaskInterval::new(1.0, 2.0).weight(0.99), 0.0);
    }
}
