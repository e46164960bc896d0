//! The payload encoder: a [`Document`] written field by field with the range coder.

use glam::{DQuat, DVec3};
use stance_ik::Axes;

use super::models::{
    ABOVE, ACTIVE, AVATAR_URL, AXES_XYZ, AXIS_Y, AXIS_Z, COLLISION_FLOOR, COLLISION_SELF,
    HANIM_JOINT, HAS_CLIP, HAS_INTERVAL, HAS_JOINTS, HAS_LIMB, HAS_MOTION, HAS_ORIENTATION,
    HAS_REFERENCE, HAS_SWIVEL, JOINT_MASK_DEFAULT, KINDS, MASKS_DEFAULT, Models, POINT_ZERO,
    STANDARD_REST, WEIGHT_DECIMAL, WEIGHT_ONE, default_mask, hanim_index, in_loa_base, mask_of,
    quantise, short_decimal, unit,
};
use super::{DIRECTION_STEP, POSITION_STEP_M, ROTATION_STEP_RAD};
use crate::document::{
    AvatarReference, Document, DofValues, LimbName, PostureRest, PostureValues, TaskKindSpec,
    TaskSpec,
};
use crate::range_coder::Encoder;

struct Writer {
    e: Encoder,
    m: Models,
    format: u8,
}

impl Writer {
    fn flag(&mut self, which: usize, value: bool) {
        self.e.bit(&mut self.m.flags[which], value);
    }

    fn count(&mut self, n: usize) {
        self.m.count.encode(&mut self.e, n as u64);
    }

    fn string(&mut self, s: &str) {
        self.m.string_len.encode(&mut self.e, s.len() as u64);
        for &b in s.as_bytes() {
            self.m.byte.encode(&mut self.e, usize::from(b));
        }
    }

    fn position(&mut self, v: [f64; 3]) {
        for x in v {
            self.m
                .position
                .encode_signed(&mut self.e, quantise(x, POSITION_STEP_M));
        }
    }

    fn angle(&mut self, x: f64) {
        self.m
            .angle
            .encode_signed(&mut self.e, quantise(x, ROTATION_STEP_RAD));
    }

    fn joint(&mut self, name: &str) {
        match hanim_index(name) {
            Some(i) => {
                self.flag(HANIM_JOINT, true);
                self.m.joint.encode(&mut self.e, i);
            }
            None => {
                self.flag(HANIM_JOINT, false);
                self.string(name);
            }
        }
    }

    fn axes(&mut self, axes: Axes) {
        let xyz = axes == Axes::XYZ;
        self.flag(AXES_XYZ, xyz);
        if !xyz {
            self.e.direct(
                u64::from(axes.has(0))
                    | (u64::from(axes.has(1)) << 1)
                    | (u64::from(axes.has(2)) << 2),
                3,
            );
        }
    }

    fn dofs(&mut self, v: &DofValues) {
        for (d, x) in v.iter() {
            if d.is_rotation() {
                self.m
                    .rotation
                    .encode_signed(&mut self.e, quantise(x, ROTATION_STEP_RAD));
            } else {
                self.m
                    .translation
                    .encode_signed(&mut self.e, quantise(x, POSITION_STEP_M));
            }
        }
    }

    fn posture(&mut self, p: &PostureValues) {
        let table_len = stance_hanim::all_joints().len();
        let mut hanim: Vec<(usize, &DofValues)> = Vec::new();
        let mut extras: Vec<(&str, &DofValues)> = Vec::new();
        for (name, v) in &p.joints {
            match hanim_index(name) {
                Some(i) => hanim.push((i, v)),
                None => extras.push((name, v)),
            }
        }
        hanim.sort_by_key(|(i, _)| *i);
        let mut present = vec![false; table_len];
        for (i, _) in &hanim {
            present[*i] = true;
        }
        let toggles_for = |loa: usize| -> Vec<usize> {
            (0..table_len)
                .filter(|&i| present[i] != in_loa_base(i, loa))
                .collect()
        };
        let (loa, toggles) = (0..=4)
            .map(|loa| (loa, toggles_for(loa)))
            .min_by_key(|(_, t)| t.len())
            .unwrap_or((0, Vec::new()));
        self.m.loa.encode(&mut self.e, loa);
        self.count(toggles.len());
        let mut next = 0usize;
        for t in toggles {
            self.m.gap.encode(&mut self.e, (t - next) as u64);
            next = t + 1;
        }
        let all_default = hanim.iter().all(|(i, v)| mask_of(v) == default_mask(*i));
        self.flag(MASKS_DEFAULT, all_default);
        if !all_default {
            for (i, v) in &hanim {
                let mask = mask_of(v);
                let is_default = mask == default_mask(*i);
                self.flag(JOINT_MASK_DEFAULT, is_default);
                if !is_default {
                    self.m.mask.encode(&mut self.e, mask);
                }
            }
        }
        for (_, v) in &hanim {
            self.dofs(v);
        }
        self.count(extras.len());
        for (name, v) in extras {
            self.string(name);
            self.m.mask.encode(&mut self.e, mask_of(v));
            self.dofs(v);
        }
    }

    /// A weight: 1 in one flag, a short decimal exactly, else its bits.
    fn weight(&mut self, weight: f64) {
        let one = weight == 1.0;
        self.flag(WEIGHT_ONE, one);
        if !one {
            match short_decimal(weight) {
                Some((m, k)) => {
                    self.flag(WEIGHT_DECIMAL, true);
                    self.m.weight.encode(&mut self.e, m);
                    self.e.direct(u64::from(k), 4);
                }
                None => {
                    self.flag(WEIGHT_DECIMAL, false);
                    self.e.direct(weight.to_bits(), 64);
                }
            }
        }
    }

    fn task(&mut self, t: &TaskSpec) {
        let kind = KINDS.iter().position(|k| *k == t.kind.name()).unwrap_or(0);
        if self.format >= 3 {
            self.m.kind16.encode(&mut self.e, kind);
        } else {
            self.m.kind.encode(&mut self.e, kind);
        }
        self.m
            .level
            .encode(&mut self.e, u64::from(t.level.saturating_sub(1)));
        self.flag(ACTIVE, t.active);
        self.weight(t.weight);
        match &t.kind {
            TaskKindSpec::Position {
                joint,
                point,
                axes,
                target,
            } => {
                self.joint(joint);
                self.point(*point);
                self.axes(*axes);
                self.position(*target);
            }
            TaskKindSpec::Orientation { joint, target } => {
                self.joint(joint);
                self.quaternion(*target);
            }
            TaskKindSpec::Gaze {
                joint,
                axis,
                point,
                target,
            } => {
                self.joint(joint);
                let axis = unit(*axis);
                let z = axis == [0.0, 0.0, 1.0];
                self.flag(AXIS_Z, z);
                if !z {
                    self.direction(axis);
                }
                self.point(*point);
                self.position(*target);
            }
            TaskKindSpec::Direction {
                joint,
                axis,
                target,
            } => {
                self.joint(joint);
                let axis = unit(*axis);
                let y = axis == [0.0, 1.0, 0.0];
                self.flag(AXIS_Y, y);
                if !y {
                    self.direction(axis);
                }
                self.direction(unit(*target));
            }
            TaskKindSpec::Balance { support, margin } => {
                self.joint_list(support.as_deref());
                self.m
                    .position
                    .encode_signed(&mut self.e, quantise(*margin, POSITION_STEP_M));
            }
            TaskKindSpec::Com { axes, target } => {
                self.axes(*axes);
                self.position(*target);
            }
            TaskKindSpec::Comfort {
                effort,
                range,
                rula,
            } => {
                for w in [effort, range, rula] {
                    self.weight(*w);
                }
            }
            TaskKindSpec::Collision {
                margin,
                self_collision,
                floor,
            } => {
                self.m
                    .position
                    .encode_signed(&mut self.e, quantise(*margin, POSITION_STEP_M));
                self.flag(COLLISION_SELF, *self_collision);
                self.flag(COLLISION_FLOOR, *floor);
            }
            TaskKindSpec::Posture { joints, reference } => {
                self.joint_list(joints.as_deref());
                self.flag(HAS_REFERENCE, reference.is_some());
                if let Some(r) = reference {
                    self.posture(r);
                }
            }
            TaskKindSpec::Limb {
                limb,
                joints,
                target,
                swivel,
                orientation,
            } => {
                self.flag(HAS_LIMB, limb.is_some());
                if let Some(l) = limb {
                    let i = LimbName::ALL.iter().position(|x| x == l).unwrap_or(0);
                    self.m.limb.encode(&mut self.e, i);
                }
                self.flag(HAS_JOINTS, joints.is_some());
                if let Some(js) = joints {
                    for j in js {
                        self.joint(j);
                    }
                }
                self.position(*target);
                self.flag(HAS_SWIVEL, swivel.is_some());
                if let Some(s) = swivel {
                    self.angle(*s);
                }
                self.flag(HAS_ORIENTATION, orientation.is_some());
                if let Some(q) = orientation {
                    self.quaternion(*q);
                }
            }
            TaskKindSpec::Line {
                joint,
                point,
                origin,
                direction,
            } => {
                self.joint(joint);
                self.point(*point);
                self.position(*origin);
                self.direction(unit(*direction));
            }
            TaskKindSpec::Plane {
                joint,
                point,
                origin,
                normal,
                above,
            } => {
                self.joint(joint);
                self.point(*point);
                self.position(*origin);
                let normal = unit(*normal);
                let y = normal == [0.0, 1.0, 0.0];
                self.flag(AXIS_Y, y);
                if !y {
                    self.direction(normal);
                }
                self.flag(ABOVE, *above);
            }
        }
    }

    /// As a rotation vector with `qw >= 0`, at the rotation step.
    fn quaternion(&mut self, q: [f64; 4]) {
        let mut q = DQuat::from_array(q).normalize();
        if q.w < 0.0 {
            q = -q;
        }
        let r = q.to_scaled_axis();
        let r = if r.is_finite() { r } else { DVec3::ZERO };
        for x in r.to_array() {
            self.angle(x);
        }
    }

    /// An optional list of joints (`HAS_JOINTS`, then a count and the joints).
    fn joint_list(&mut self, joints: Option<&[String]>) {
        self.flag(HAS_JOINTS, joints.is_some());
        if let Some(list) = joints {
            self.count(list.len());
            for j in list {
                self.joint(j);
            }
        }
    }

    /// A unit vector, at the direction step.
    fn direction(&mut self, v: [f64; 3]) {
        for x in v {
            self.m
                .direction
                .encode_signed(&mut self.e, quantise(x, DIRECTION_STEP));
        }
    }

    fn point(&mut self, p: [f64; 3]) {
        let zero = p == [0.0; 3];
        self.flag(POINT_ZERO, zero);
        if !zero {
            self.position(p);
        }
    }
}

/// Format 2's part after the tasks: each task's active interval, then the timeline.
fn motion(w: &mut Writer, d: &Document) {
    for t in &d.tasks {
        w.flag(HAS_INTERVAL, t.interval.is_some());
        if let Some(i) = &t.interval {
            for x in [i.start, i.end, i.ease_in, i.ease_out] {
                w.e.direct(x.to_bits(), 64);
            }
        }
    }
    w.flag(HAS_MOTION, d.motion.is_some());
    if let Some(m) = &d.motion {
        w.e.direct(m.frame_time.to_bits(), 64);
        w.e.direct(m.frame_count as u64, 32);
        w.count(m.keys.len());
        for key in &m.keys {
            w.e.direct(key.frame as u64, 32);
            w.posture(&key.posture);
        }
    }
}

/// The payload of `format` (1: posture and tasks; 2: also the intervals and the timeline; 3:
/// the task kinds in a 16-symbol model, comfort among them; 4: also the joint stiffness, in
/// the shape and quantisation of a posture; 5: the rest flag; 6: the clip's reference: file
/// name, size and content hash, never the file; 7: the line and plane task kinds, no new field).
pub(super) fn encode_payload(d: &Document, format: u8) -> Vec<u8> {
    let mut w = Writer {
        e: Encoder::new(),
        m: Models::default(),
        format,
    };
    match &d.avatar {
        AvatarReference::Default => w.flag(AVATAR_URL, false),
        AvatarReference::Url(u) => {
            w.flag(AVATAR_URL, true);
            w.string(u);
        }
    }
    w.posture(&d.posture);
    w.count(d.tasks.len());
    for t in &d.tasks {
        w.task(t);
    }
    if format >= 2 {
        motion(&mut w, d);
    }
    if format >= 4 {
        w.posture(&d.stiffness);
    }
    if format >= 5 {
        w.flag(STANDARD_REST, d.rest == PostureRest::Standard);
    }
    if format >= 6 {
        match &d.clip {
            Some(clip) => {
                w.flag(HAS_CLIP, true);
                w.string(&clip.name);
                // At most MAX_CLIP_BYTES in a valid document, below 2^32.
                w.e.direct(clip.size.min(u64::from(u32::MAX)), 32);
                w.e.direct(clip.hash, 32);
            }
            None => w.flag(HAS_CLIP, false),
        }
    }
    w.e.finish()
}
