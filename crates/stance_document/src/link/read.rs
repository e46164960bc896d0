//! The payload decoder: a [`Document`] read back field by field, every count, index and
//! string length checked against the format's limits.

use glam::{DQuat, DVec3};
use stance_ik::{Axes, Dof};

use super::models::{
    ABOVE, ACTIVE, AVATAR_URL, AXES_XYZ, AXIS_Y, AXIS_Z, COLLISION_FLOOR, COLLISION_SELF,
    HANIM_JOINT, HAS_CLIP, HAS_INTERVAL, HAS_JOINTS, HAS_LIMB, HAS_MOTION, HAS_ORIENTATION,
    HAS_REFERENCE, HAS_SWIVEL, JOINT_MASK_DEFAULT, KINDS, MASKS_DEFAULT, MAX_QUANTISED, Models,
    POINT_ZERO, STANDARD_REST, WEIGHT_DECIMAL, WEIGHT_ONE, default_mask, dequantise, from_decimal,
    in_loa_base,
};
use super::{
    DIRECTION_STEP, MAX_COUNT, MAX_OVERRUN, MAX_STRING_BYTES, POSITION_STEP_M, ROTATION_STEP_RAD,
};
use crate::clip::ClipReference;
use crate::document::{
    AvatarReference, Document, DofValues, LimbName, PostureRest, PostureValues, TaskKindSpec,
    TaskSpec, dof_slot,
};
use crate::motion::{MAX_FRAME_COUNT, MotionKey, MotionSection, TaskInterval};
use crate::range_coder::{Decoder, UintModel};
use crate::stiffness::StiffnessValues;

struct Reader<'a> {
    d: Decoder<'a>,
    m: Models,
    format: u8,
}

type R<T> = Result<T, String>;

impl Reader<'_> {
    fn check(&self) -> R<()> {
        if self.d.overrun() > MAX_OVERRUN {
            Err("the data ends too early".to_owned())
        } else {
            Ok(())
        }
    }

    fn flag(&mut self, which: usize) -> bool {
        self.d.bit(&mut self.m.flags[which])
    }

    fn count(&mut self, what: &str) -> R<usize> {
        let n = self
            .m
            .count
            .decode(&mut self.d)
            .ok_or_else(|| format!("bad {what} count"))?;
        if n > MAX_COUNT {
            return Err(format!("too many {what} ({n})"));
        }
        Ok(n as usize)
    }

    fn string(&mut self) -> R<String> {
        let n = self
            .m
            .string_len
            .decode(&mut self.d)
            .ok_or("bad text length")?;
        if n > MAX_STRING_BYTES {
            return Err(format!("text of {n} bytes"));
        }
        let mut bytes = Vec::with_capacity(n as usize);
        for _ in 0..n {
            bytes.push(self.m.byte.decode(&mut self.d) as u8);
        }
        self.check()?;
        String::from_utf8(bytes).map_err(|_| "text is not UTF-8".to_owned())
    }

    fn signed(model: &mut UintModel, d: &mut Decoder, step: f64) -> R<f64> {
        let q = model
            .decode_signed(d)
            .ok_or_else(|| "bad number".to_owned())?;
        if q.unsigned_abs() > MAX_QUANTISED.unsigned_abs() {
            return Err(format!("a number out of range ({q} steps)"));
        }
        Ok(dequantise(q, step))
    }

    fn position(&mut self) -> R<[f64; 3]> {
        let mut v = [0.0; 3];
        for x in &mut v {
            *x = Self::signed(&mut self.m.position, &mut self.d, POSITION_STEP_M)?;
        }
        Ok(v)
    }

    /// An optional list of joints (`HAS_JOINTS`, then a count and the joints).
    fn joint_list(&mut self, what: &str) -> R<Option<Vec<String>>> {
        if !self.flag(HAS_JOINTS) {
            return Ok(None);
        }
        let n = self.count(what)?;
        let mut list = Vec::with_capacity(n);
        for _ in 0..n {
            list.push(self.joint()?);
            self.check()?;
        }
        Ok(Some(list))
    }

    fn direction(&mut self) -> R<[f64; 3]> {
        let mut v = [0.0; 3];
        for x in &mut v {
            *x = Self::signed(&mut self.m.direction, &mut self.d, DIRECTION_STEP)?;
        }
        Ok(v)
    }

    fn angle(&mut self) -> R<f64> {
        Self::signed(&mut self.m.angle, &mut self.d, ROTATION_STEP_RAD)
    }

    fn quaternion(&mut self) -> R<[f64; 4]> {
        let r = DVec3::new(self.angle()?, self.angle()?, self.angle()?);
        Ok(DQuat::from_scaled_axis(r).to_array())
    }

    fn joint(&mut self) -> R<String> {
        if self.flag(HANIM_JOINT) {
            let i = self.m.joint.decode(&mut self.d);
            stance_hanim::all_joints()
                .get(i)
                .map(|d| d.name.to_owned())
                .ok_or_else(|| format!("joint index {i} is not in the H-Anim table"))
        } else {
            self.string()
        }
    }

    fn axes(&mut self) -> R<Axes> {
        if self.flag(AXES_XYZ) {
            return Ok(Axes::XYZ);
        }
        let m = self.d.direct(3);
        if m == 0 {
            return Err("no axes selected".to_owned());
        }
        Ok(Axes::new(m & 1 != 0, m & 2 != 0, m & 4 != 0))
    }

    fn point(&mut self) -> R<[f64; 3]> {
        if self.flag(POINT_ZERO) {
            Ok([0.0; 3])
        } else {
            self.position()
        }
    }

    fn dofs(&mut self, mask: usize) -> R<DofValues> {
        let mut v = DofValues::default();
        for d in Dof::ALL {
            if mask & (1 << dof_slot(d)) == 0 {
                continue;
            }
            let x = if d.is_rotation() {
                Self::signed(&mut self.m.rotation, &mut self.d, ROTATION_STEP_RAD)?
            } else {
                Self::signed(&mut self.m.translation, &mut self.d, POSITION_STEP_M)?
            };
            v.set(d, x);
        }
        Ok(v)
    }

    fn posture(&mut self) -> R<PostureValues> {
        let table = stance_hanim::all_joints();
        let loa = self.m.loa.decode(&mut self.d);
        if loa > 4 {
            return Err(format!("level of articulation {loa}"));
        }
        let mut present: Vec<bool> = (0..table.len()).map(|i| in_loa_base(i, loa)).collect();
        let toggles = self.count("joint exceptions")?;
        let mut next = 0usize;
        for _ in 0..toggles {
            let gap = self.m.gap.decode(&mut self.d).ok_or("bad joint gap")?;
            let i = usize::try_from(gap)
                .ok()
                .and_then(|g| g.checked_add(next))
                .filter(|&i| i < table.len())
                .ok_or("joint index beyond the H-Anim table")?;
            present[i] = !present[i];
            next = i + 1;
        }
        let indices: Vec<usize> = (0..table.len()).filter(|&i| present[i]).collect();
        let mut masks: Vec<usize> = indices.iter().map(|&i| default_mask(i)).collect();
        if !self.flag(MASKS_DEFAULT) {
            for mask in &mut masks {
                if !self.flag(JOINT_MASK_DEFAULT) {
                    *mask = self.m.mask.decode(&mut self.d);
                }
            }
        }
        let mut p = PostureValues::default();
        for (&i, &mask) in indices.iter().zip(&masks) {
            let v = self.dofs(mask)?;
            p.joints.insert(table[i].name.to_owned(), v);
        }
        self.check()?;
        let extras = self.count("named joints")?;
        for _ in 0..extras {
            let name = self.string()?;
            let mask = self.m.mask.decode(&mut self.d);
            let v = self.dofs(mask)?;
            self.check()?;
            if p.joints.insert(name.clone(), v).is_some() {
                return Err(format!("joint `{name}` appears twice"));
            }
        }
        Ok(p)
    }

    /// A weight (see the writer).
    fn weight(&mut self) -> R<f64> {
        Ok(if self.flag(WEIGHT_ONE) {
            1.0
        } else if self.flag(WEIGHT_DECIMAL) {
            let m = self.m.weight.decode(&mut self.d).ok_or("bad weight")?;
            let k = self.d.direct(4) as i32;
            from_decimal(m, k)
        } else {
            f64::from_bits(self.d.direct(64))
        })
    }

    fn task(&mut self) -> R<TaskSpec> {
        let kind = if self.format >= 3 {
            self.m.kind16.decode(&mut self.d)
        } else {
            self.m.kind.decode(&mut self.d)
        };
        let level = self.m.level.decode(&mut self.d).ok_or("bad level")?;
        let level = level
            .checked_add(1)
            .and_then(|l| u32::try_from(l).ok())
            .ok_or("level out of range")?;
        let active = self.flag(ACTIVE);
        let weight = self.weight()?;
        // The point-on-a-line and point-on-a-plane kinds came with format 7, the collision
        // kind with 8.
        let known = match self.format {
            0..=6 => 9,
            7 => 11,
            _ => KINDS.len(),
        };
        let kind = match KINDS[..known].get(kind).copied() {
            Some("position") => TaskKindSpec::Position {
                joint: self.joint()?,
                point: self.point()?,
                axes: self.axes()?,
                target: self.position()?,
            },
            Some("orientation") => TaskKindSpec::Orientation {
                joint: self.joint()?,
                target: self.quaternion()?,
            },
            Some("gaze") => {
                let joint = self.joint()?;
                let axis = if self.flag(AXIS_Z) {
                    [0.0, 0.0, 1.0]
                } else {
                    self.direction()?
                };
                TaskKindSpec::Gaze {
                    joint,
                    axis,
                    point: self.point()?,
                    target: self.position()?,
                }
            }
            Some("direction") => {
                let joint = self.joint()?;
                let axis = if self.flag(AXIS_Y) {
                    [0.0, 1.0, 0.0]
                } else {
                    self.direction()?
                };
                TaskKindSpec::Direction {
                    joint,
                    axis,
                    target: self.direction()?,
                }
            }
            Some("balance") => {
                let support = self.joint_list("support joints")?;
                let margin = Self::signed(&mut self.m.position, &mut self.d, POSITION_STEP_M)?;
                TaskKindSpec::Balance { support, margin }
            }
            Some("com") => TaskKindSpec::Com {
                axes: self.axes()?,
                target: self.position()?,
            },
            Some("comfort") => TaskKindSpec::Comfort {
                effort: self.weight()?,
                range: self.weight()?,
                rula: self.weight()?,
            },
            Some("collision") if self.format >= 8 => {
                let margin = Self::signed(&mut self.m.position, &mut self.d, POSITION_STEP_M)?;
                TaskKindSpec::Collision {
                    margin,
                    self_collision: self.flag(COLLISION_SELF),
                    floor: self.flag(COLLISION_FLOOR),
                }
            }
            Some("posture") => {
                let joints = self.joint_list("posture joints")?;
                let reference = if self.flag(HAS_REFERENCE) {
                    Some(self.posture()?)
                } else {
                    None
                };
                TaskKindSpec::Posture { joints, reference }
            }
            Some("limb") => {
                let limb = if self.flag(HAS_LIMB) {
                    Some(LimbName::ALL[self.m.limb.decode(&mut self.d) & 3])
                } else {
                    None
                };
                let joints = if self.flag(HAS_JOINTS) {
                    Some([self.joint()?, self.joint()?, self.joint()?])
                } else {
                    None
                };
                let target = self.position()?;
                let swivel = if self.flag(HAS_SWIVEL) {
                    Some(self.angle()?)
                } else {
                    None
                };
                let orientation = if self.flag(HAS_ORIENTATION) {
                    Some(self.quaternion()?)
                } else {
                    None
                };
                TaskKindSpec::Limb {
                    limb,
                    joints,
                    target,
                    swivel,
                    orientation,
                }
            }
            Some("line") => TaskKindSpec::Line {
                joint: self.joint()?,
                point: self.point()?,
                origin: self.position()?,
                direction: self.direction()?,
            },
            Some("plane") => {
                let joint = self.joint()?;
                let point = self.point()?;
                let origin = self.position()?;
                let normal = if self.flag(AXIS_Y) {
                    [0.0, 1.0, 0.0]
                } else {
                    self.direction()?
                };
                TaskKindSpec::Plane {
                    joint,
                    point,
                    origin,
                    normal,
                    above: self.flag(ABOVE),
                }
            }
            _ => return Err(format!("unknown task kind {kind}")),
        };
        self.check()?;
        Ok(TaskSpec {
            level,
            weight,
            active,
            kind,
            interval: None,
            on: None,
        })
    }
}

/// Format 2's part after the tasks: each task's active interval, then the timeline.
fn motion(r: &mut Reader, tasks: &mut [TaskSpec]) -> R<Option<MotionSection>> {
    for task in tasks.iter_mut() {
        if r.flag(HAS_INTERVAL) {
            let mut v = [0.0; 4];
            for x in &mut v {
                *x = f64::from_bits(r.d.direct(64));
            }
            task.interval = Some(TaskInterval {
                start: v[0],
                end: v[1],
                ease_in: v[2],
                ease_out: v[3],
            });
        }
    }
    if !r.flag(HAS_MOTION) {
        return Ok(None);
    }
    let frame_time = f64::from_bits(r.d.direct(64));
    let frame_count = r.d.direct(32);
    if frame_count > MAX_FRAME_COUNT as u64 {
        return Err(format!("a timeline of {frame_count} frames"));
    }
    let n = r.count("keys")?;
    let mut keys = Vec::with_capacity(n);
    for _ in 0..n {
        // A key may lie beyond the timeline's last frame (as in a document).
        let frame = r.d.direct(32);
        if frame >= MAX_FRAME_COUNT as u64 {
            return Err(format!("a key at frame {frame}"));
        }
        let posture = r.posture()?;
        keys.push(MotionKey {
            frame: frame as usize,
            posture,
        });
        r.check()?;
    }
    Ok(Some(MotionSection {
        frame_time,
        frame_count: frame_count as usize,
        keys,
    }))
}

/// The document in a payload of `format`.
pub(super) fn decode_payload(bytes: &[u8], format: u8) -> R<Document> {
    let mut r = Reader {
        d: Decoder::new(bytes),
        m: Models::default(),
        format,
    };
    let avatar = if r.flag(AVATAR_URL) {
        AvatarReference::Url(r.string()?)
    } else {
        AvatarReference::Default
    };
    let posture = r.posture()?;
    let n = r.count("tasks")?;
    let mut tasks = Vec::with_capacity(n);
    for _ in 0..n {
        tasks.push(r.task()?);
    }
    let motion = if format >= 2 {
        motion(&mut r, &mut tasks)?
    } else {
        None
    };
    let stiffness = if format >= 4 {
        // Below 1 once quantised (1 is not a multiple of the step); a crafted value at or
        // above it fails the document's validation.
        r.posture()?
    } else {
        StiffnessValues::default()
    };
    // Before format 5 a link did not say: its values were relative to its body's own rest
    // (the standard pose on the mannequin).
    let rest = if format >= 5 {
        if r.flag(STANDARD_REST) {
            PostureRest::Standard
        } else {
            PostureRest::Avatar
        }
    } else if avatar == AvatarReference::Default {
        PostureRest::Standard
    } else {
        PostureRest::Avatar
    };
    let clip = if format >= 6 && r.flag(HAS_CLIP) {
        let name = r.string()?;
        let size = r.d.direct(32);
        let hash = r.d.direct(32);
        Some(ClipReference {
            name,
            size,
            hash,
            embedded: None,
        })
    } else {
        None
    };
    r.check()?;
    Ok(Document {
        avatar,
        posture,
        tasks,
        motion,
        camera: None,
        stiffness,
        rest,
        clip,
    })
}
