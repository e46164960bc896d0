//! BVH (Biovision Hierarchy) in and out.
//!
//! [`read_bvh`] parses the dialects of real files (see `docs/motion-formats.md`), builds
//! the clip in file units, maps its joints onto H-Anim ([`Mapping::auto`]), finds the
//! body's axes and the unit from the skeleton ([`stance_hanim::frame`]) and brings
//! everything into the H-Anim frame in metres: offsets and translations become `s R t`,
//! rotations `R q R⁻¹` (`R` the file-to-H-Anim rotation, `s` metres per file unit). The
//! origin is kept. What it noticed and did is in [`Clip::notes`].
//!
//! `End Site` blocks are kept as leaf joints without channels, named `<parent>_End`
//! (needed to export the same skeleton again); they are never mapped.
//!
//! [`write_bvh`] writes a clip back (H-Anim names, a chosen Euler order and unit).

mod euler;
mod parse;
mod write;

use glam::{DQuat, DVec3};
use stance_hanim::Mapping;
use stance_hanim::frame::{MOTION_UNITS, body_frame, unit_name, unit_scale};

pub use euler::EulerOrder;
pub use write::{BvhWriteOptions, write_bvh};

use crate::clip::{Clip, ClipFrame, ClipJoint};
use euler::axis_rotation;
use parse::Channel;

/// Sizes a file may have; each is checked before anything is allocated for it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct BvhLimits {
    /// Bytes of the file.
    pub max_bytes: usize,
    /// Joints, End Sites included.
    pub max_joints: usize,
    /// Channels of all joints together.
    pub max_channels: usize,
    /// Frames (declared or read).
    pub max_frames: usize,
    /// Motion values (frames times channels).
    pub max_values: usize,
}

impl Default for BvhLimits {
    fn default() -> Self {
        Self {
            max_bytes: 256 << 20,
            max_joints: 1024,
            max_channels: 6 * 1024,
            max_frames: 2_000_000,
            max_values: 400_000_000,
        }
    }
}

/// Why a BVH file could not be read. Every error names the 1-based line and the field
/// (`CHANNELS`, `OFFSET`, `Frames:`, `motion value 17 of frame 3 (channel Xrotation of
/// LeftArm)`...).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum BvhError {
    /// The text is not valid BVH.
    #[error("line {line}, {field}: {message}")]
    Syntax {
        /// 1-based line.
        line: usize,
        /// The keyword or value concerned.
        field: String,
        /// What is wrong.
        message: String,
    },
    /// A size is over [`BvhLimits`].
    #[error("line {line}, {field}: {message}")]
    Limit {
        /// 1-based line.
        line: usize,
        /// The keyword or value concerned.
        field: String,
        /// Which limit.
        message: String,
    },
}

impl BvhError {
    /// The 1-based line.
    pub fn line(&self) -> usize {
        match self {
            Self::Syntax { line, .. } | Self::Limit { line, .. } => *line,
        }
    }

    /// The field.
    pub fn field(&self) -> &str {
        match self {
            Self::Syntax { field, .. } | Self::Limit { field, .. } => field,
        }
    }
}

/// Reads a BVH file into a clip in the H-Anim frame (metres, +Y up, +Z front, +X left).
/// `name`: the clip's name (the file's stem).
pub fn read_bvh(bytes: &[u8], name: &str, limits: &BvhLimits) -> Result<Clip, BvhError> {
    let raw = parse::parse(bytes, limits)?;
    let mut notes = Vec::new();
    if raw.rows != raw.declared_frames {
        notes.push(format!(
            "frame count: 'Frames: {}' (line {}) but {} rows; the rows are used",
            raw.declared_frames, raw.frames_line, raw.rows
        ));
    }
    let joints: Vec<ClipJoint> = raw
        .joints
        .iter()
        .map(|j| ClipJoint {
            name: j.name.clone(),
            parent: j.parent,
            offset: j.offset,
        })
        .collect();

    // Position channels: absolute (MotionBuilder) when frame 0 equals the OFFSET within 1 %,
    // else added to the OFFSET (three.js, Blender).
    let mut starts = Vec::with_capacity(raw.joints.len());
    let mut at = 0usize;
    for j in &raw.joints {
        starts.push(at);
        at += j.channels.len();
    }
    let mut absolute = vec![false; raw.joints.len()];
    for (i, j) in raw.joints.iter().enumerate() {
        let mut p = DVec3::ZERO;
        let mut any = false;
        for (k, c) in j.channels.iter().enumerate() {
            if let Channel::Position(a) = c
                && let Some(v) = raw.values.get(starts[i] + k)
            {
                p[*a] = *v;
                any = true;
            }
        }
        if any && raw.rows > 0 {
            let len = j.offset.length();
            absolute[i] = len > 0.0 && (p - j.offset).length() <= 0.01 * len;
            if absolute[i] {
                notes.push(format!(
                    "position channels of '{}' read as absolute local translations \
                     (frame 1 equals its OFFSET, as MotionBuilder writes them)",
                    j.name
                ));
            } else if j.parent.is_some() {
                notes.push(format!(
                    "position channels of '{}' added to its OFFSET",
                    j.name
                ));
            }
        }
    }

    if raw.rows.saturating_mul(raw.joints.len().max(1)) > limits.max_values {
        return Err(BvhError::Limit {
            line: raw.frames_line,
            field: "Frames:".into(),
            message: format!(
                "{} frames of {} joints, over the limit of {} values",
                raw.rows,
                raw.joints.len(),
                limits.max_values
            ),
        });
    }
    let mut frames = Vec::with_capacity(raw.rows);
    for row in raw
        .values
        .chunks_exact(raw.channel_count.max(1))
        .take(raw.rows)
    {
        let mut translations = Vec::with_capacity(raw.joints.len());
        let mut rotations = Vec::with_capacity(raw.joints.len());
        for (i, j) in raw.joints.iter().enumerate() {
            let mut t = j.offset;
            let mut q = DQuat::IDENTITY;
            for (k, c) in j.channels.iter().enumerate() {
                let v = row.get(starts[i] + k).copied().unwrap_or(0.0);
                match *c {
                    Channel::Position(a) if absolute[i] => t[a] = v,
                    Channel::Position(a) => t[a] += v,
                    Channel::Rotation(a) => q *= axis_rotation(a, v.to_radians()),
                }
            }
            translations.push(t);
            rotations.push(q.normalize());
        }
        frames.push(ClipFrame {
            translations,
            rotations,
        });
    }
    if raw.channel_count == 0 {
        // A skeleton without channels: its frames are the rest pose.
        let rest = ClipFrame {
            translations: joints.iter().map(|j| j.offset).collect(),
            rotations: vec![DQuat::IDENTITY; joints.len()],
        };
        frames = vec![rest; raw.rows];
    }

    let mut clip = Clip {
        name: name.to_owned(),
        frame_time: raw.frame_time,
        joints,
        frames,
        mapping: Mapping::empty(0),
        notes: Vec::new(),
    };
    clip.mapping = Mapping::auto(&clip.source_joints(), &[], false);
    // A rest pose that is no pose (the legs laid the way the spine goes, as in a Rokoko
    // export whose bones all lie along their own X axes): the first frame is the rest.
    let rest = clip.rest_positions();
    let at = |h: &str| clip.joint_of(h).and_then(|i| rest.get(i).copied());
    if let (Some(lh), Some(rh), Some(la), Some(ra), Some(head)) = (
        at("l_hip"),
        at("r_hip"),
        at("l_talocrural"),
        at("r_talocrural"),
        at("skullbase"),
    ) {
        let hips = (lh + rh) * 0.5;
        if (head - hips).dot((la + ra) * 0.5 - hips) > 0.0 && !clip.frames.is_empty() {
            clip.rest_on_frame(0);
            clip.mapping = Mapping::auto(&clip.source_joints(), &[], false);
            notes.push(
                "the file's rest pose lays the legs the way the spine goes (bones along their \
                 own axes): the first frame is taken as the rest"
                    .to_owned(),
            );
        }
    }

    // The body's axes and unit.
    let rest = clip.rest_positions();
    let body = body_frame(|h| clip.joint_of(h).and_then(|i| rest.get(i).copied()));
    let (scale, warning) = unit_scale(body.height_file, &MOTION_UNITS);
    let mut head = Vec::new();
    if body.height_file > 1e-9 {
        let unit = match unit_name(scale, &MOTION_UNITS) {
            Some("m") => "metres".to_owned(),
            Some("cm") => "centimetres".to_owned(),
            Some("mm") => "millimetres".to_owned(),
            Some("dm") => "decimetres".to_owned(),
            Some("inch") => "inches".to_owned(),
            Some(other) => other.replace("unit ", "units "),
            None => format!("{scale:.6} m per unit (guessed)"),
        };
        head.push(format!(
            "units: {unit} (skull base {:.1} units above the ankles)",
            body.height_file
        ));
    } else {
        head.push("units: unknown (no head or ankles mapped); read as metres".to_owned());
    }
    if let Some(w) = warning {
        head.push(w);
    }
    let r = body.hanim_from_file;
    if !r.abs_diff_eq(glam::DMat3::IDENTITY, 1e-12) {
        let file_of = |v: DVec3| axis_name(r.transpose() * v);
        head.push(format!(
            "axes: the body's up is file {}, its front {}, its left {}; rotated to H-Anim \
             (+Y up, +Z front, +X left)",
            file_of(DVec3::Y),
            file_of(DVec3::Z),
            file_of(DVec3::X),
        ));
    }
    let rq = DQuat::from_mat3(&r).normalize();
    let rq_inv = rq.inverse();
    for j in &mut clip.joints {
        j.offset = scale * (rq * j.offset);
    }
    for f in &mut clip.frames {
        for t in &mut f.translations {
            *t = scale * (rq * *t);
        }
        for q in &mut f.rotations {
            *q = (rq * *q * rq_inv).normalize();
        }
    }
    // Map again in the H-Anim frame (the geometry fallback expects it).
    clip.mapping = Mapping::auto(&clip.source_joints(), &[], false);
    let unmapped: Vec<&str> = raw
        .joints
        .iter()
        .enumerate()
        .filter(|(i, j)| !j.end_site && clip.mapping.hanim_of(*i).is_none())
        .map(|(_, j)| j.name.as_str())
        .collect();
    if !unmapped.is_empty() {
        head.push(format!(
            "joints left unmapped: {} (End Sites aside)",
            unmapped.join(", ")
        ));
    }
    head.append(&mut notes);
    clip.notes = head;
    Ok(clip)
}

/// `+Z`, `-X`... for a signed axis, else the vector.
fn axis_name(v: DVec3) -> String {
    for (k, n) in ["X", "Y", "Z"].iter().enumerate() {
        if (v[k].abs() - 1.0).abs() < 1e-9 {
            return format!("{}{n}", if v[k] > 0.0 { "+" } else { "-" });
        }
    }
    format!("({:.3}, {:.3}, {:.3})", v.x, v.y, v.z)
}
