//! A clip file to open on another thread (the page's loading worker): [`ClipJob`] carries the
//! file, the body and the retargeting settings there; [`ClipJob::run`] reads the clip and
//! retargets it in steps (reporting its progress between them); [`ClipTransfer`] carries the
//! clip and its retargeting back, split in parts of frames so that the receiving thread can
//! take them in separate tasks. Like [`crate::AvatarTransfer`], the layout is postcard's with
//! the frames' numbers as byte runs in the machine's byte order (a copy to encode and to
//! decode); both ends are the same build on the same machine, the bytes are not a file format.
//!
//! Decoding checks what it reads (lengths, names, finite numbers, a skeleton that
//! [`stance_ik::Skeleton::new`] accepts, frames that fit the clip's joints and postures the
//! body's DOF) and returns an [`AssetError::Transfer`] naming the problem; it never panics.

use std::sync::Arc;

use glam::{DQuat, DVec3};
use serde::{Deserialize, Serialize};
use stance_hanim::{AnatomicalAxis, BuiltJoint, HumanoidSkeleton, LevelOfArticulation, Mapping};
use stance_ik::{Dof, JointDef, Posture, Skeleton};
use stance_motion::contacts::{Contact, Thresholds};
use stance_motion::retarget::Placement;
use stance_motion::{
    Clip, ClipFrame, ClipJoint, ContactSettings, RestMatch, RetargetOptions, Retargeted,
    Retargeting,
};

use crate::transfer::pod_vec;
use crate::{AssetError, LoadOptions, read_clip};

/// Frames the worker retargets between two progress reports.
pub const FRAMES_PER_STEP: usize = 50;
/// Frames per part of a [`ClipTransfer`].
pub const FRAMES_PER_PART: usize = 1000;

/// A clip file to read and retarget onto a body.
#[derive(Debug, Clone, PartialEq)]
pub struct ClipJob {
    /// The file's name (its extension says how to read it).
    pub name: String,
    /// The file's contents (BVH, or a glTF file's first animation), shared with the editor's
    /// copy (a long clip is megabytes: the main thread copies it once, into the trip).
    pub bytes: Arc<[u8]>,
    /// The body to put it on.
    pub body: HumanoidSkeleton,
    /// How.
    pub options: RetargetOptions,
    /// The clip's mapping onto H-Anim as the user corrected it (`None`: the one found when
    /// the file is read).
    pub mapping: Option<Mapping>,
}

/// A clip read and retargeted.
#[derive(Debug, Clone, PartialEq)]
pub struct OpenedClip {
    /// The clip as read.
    pub clip: Clip,
    /// Its retargeting onto the job's body. The plain copy (`copy`) is left out where it
    /// crossed threads: the editor does not show it.
    pub retargeted: Retargeted,
}

impl ClipJob {
    /// Reads the clip and retargets it, calling `progress` with the fraction done after each
    /// step of [`FRAMES_PER_STEP`] frames. `Err`: what is wrong (the file, or the clip on this
    /// body), in words.
    pub fn run(self, progress: &mut dyn FnMut(f64)) -> Result<OpenedClip, String> {
        let name = self.name;
        let mut clip = read_clip(&name, &self.bytes, &LoadOptions::default(), &mut |_| None)
            .map_err(|error| format!("{name} could not be opened as a clip: {error}."))?;
        if let Some(mapping) = self.mapping {
            if mapping.source_count() != clip.joints.len() {
                return Err(format!(
                    "{name}: the corrected mapping is for a clip of {} joints, the file has {}.",
                    mapping.source_count(),
                    clip.joints.len()
                ));
            }
            clip.mapping = mapping;
        }
        let clip_name = clip.name.clone();
        let cannot = |error: stance_motion::MotionError| {
            format!("The clip {clip_name} could not be put on this body: {error}.")
        };
        let mut job = Retargeting::new(clip, self.body, self.options).map_err(&cannot)?;
        while !job.step(FRAMES_PER_STEP).map_err(&cannot)? {
            progress(job.progress());
        }
        progress(1.0);
        let (clip, retargeted) = job.finish().map_err(cannot)?;
        Ok(OpenedClip { clip, retargeted })
    }

    /// The job as bytes for the trip: the head (name, body, settings, mapping and the file's
    /// length) in postcard's layout, then the file's bytes as they are (one copy).
    pub fn to_bytes(&self) -> Result<Vec<u8>, AssetError> {
        let head = JobHead {
            name: self.name.clone(),
            file_bytes: self.bytes.len() as u64,
            body: BodyWire::of(&self.body),
            options: OptionsWire::of(&self.options),
            mapping: self.mapping.clone(),
        };
        let mut out = postcard::to_allocvec(&head)
            .map_err(|error| AssetError::Transfer(error.to_string()))?;
        out.reserve_exact(self.bytes.len());
        out.extend_from_slice(&self.bytes);
        Ok(out)
    }

    /// The job again.
    pub fn from_bytes(bytes: &[u8]) -> Result<Self, AssetError> {
        let (head, file) = postcard::take_from_bytes::<JobHead>(bytes)
            .map_err(|error| AssetError::Transfer(format!("the job: {error}")))?;
        if file.len() as u64 != head.file_bytes {
            return Err(AssetError::Transfer(format!(
                "the job's file has {} bytes, its head says {}",
                file.len(),
                head.file_bytes
            )));
        }
        Ok(Self {
            name: head.name,
            bytes: file.into(),
            body: head.body.into_body()?,
            options: head.options.into_options()?,
            mapping: head.mapping,
        })
    }
}

/// An opened clip split for the trip: a head (the clip's skeleton and mapping, the contacts
/// and notes) and parts of [`FRAMES_PER_PART`] frames (the clip's and the postures).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ClipTransfer {
    /// Everything but the frames.
    pub head: Vec<u8>,
    /// The frames, in order.
    pub parts: Vec<Vec<u8>>,
}

/// One part of a [`ClipTransfer`] decoded.
#[derive(Debug, Clone, PartialEq)]
pub struct FramesPart {
    frames: Vec<ClipFrame>,
    postures: Vec<Posture>,
    /// Per frame, one residual per level (cut by the head's levels).
    residuals: Vec<f64>,
}

impl ClipTransfer {
    /// `opened` split for the trip.
    pub fn new(opened: &OpenedClip) -> Result<Self, AssetError> {
        let (clip, r) = (&opened.clip, &opened.retargeted);
        let head = HeadWire {
            name: clip.name.clone(),
            frame_time: clip.frame_time,
            joints: clip
                .joints
                .iter()
                .map(|j| (j.name.clone(), j.parent, j.offset))
                .collect(),
            mapping: clip.mapping.clone(),
            clip_notes: clip.notes.clone(),
            frame_count: clip.frames.len(),
            contacts: r.contacts.clone(),
            reference_frames: r.reference_frames,
            thresholds: r.thresholds,
            levels: r.levels.clone(),
            iterations: r.iterations,
            retargeted_frame_time: r.frame_time,
            placement: r.placement,
            notes: r.notes.clone(),
        };
        let encode = |e: postcard::Error| AssetError::Transfer(e.to_string());
        let head = postcard::to_allocvec(&head).map_err(encode)?;
        let mut parts = Vec::new();
        let frames = clip.frames.len().max(r.postures.len());
        for start in (0..frames).step_by(FRAMES_PER_PART) {
            let end = (start + FRAMES_PER_PART).min(frames);
            let frames = clip.frames.get(start..end).unwrap_or_default();
            let postures = r.postures.get(start..end).unwrap_or_default();
            let residuals = r.residuals.get(start..end).unwrap_or_default();
            let part = PartWire {
                frames: frames.len(),
                translations: frames
                    .iter()
                    .flat_map(|f| f.translations.iter().map(|t| t.to_array()))
                    .collect(),
                rotations: frames
                    .iter()
                    .flat_map(|f| f.rotations.iter().map(|q| q.to_array()))
                    .collect(),
                postures: postures.len(),
                values: postures.iter().flat_map(|p| p.values().to_vec()).collect(),
                residuals: residuals.iter().flatten().copied().collect(),
            };
            parts.push(postcard::to_allocvec(&part).map_err(encode)?);
        }
        Ok(Self { head, parts })
    }

    /// One part decoded (its frames cut by the clip's joints and the postures by the body's
    /// DOF, which the head and the body check when they are put together).
    pub fn decode_part(bytes: &[u8], joints: usize, dofs: usize) -> Result<FramesPart, AssetError> {
        let wire: PartWire = whole(bytes, "frames")?;
        let bad = |what: &str| AssetError::Transfer(format!("a part's {what} do not add up"));
        let frame_values = wire.frames.checked_mul(joints);
        if joints == 0
            || frame_values != Some(wire.translations.len())
            || frame_values != Some(wire.rotations.len())
        {
            return Err(bad("frames"));
        }
        if dofs == 0 || wire.postures.checked_mul(dofs) != Some(wire.values.len()) {
            return Err(bad("postures"));
        }
        let frames = wire
            .translations
            .chunks(joints)
            .zip(wire.rotations.chunks(joints))
            .map(|(t, q)| {
                let translations: Vec<DVec3> = t.iter().map(|&a| DVec3::from_array(a)).collect();
                let rotations: Vec<DQuat> = q.iter().map(|&a| DQuat::from_array(a)).collect();
                let finite = translations.iter().all(|t| t.is_finite())
                    && rotations.iter().all(|q| q.is_finite());
                finite
                    .then_some(ClipFrame {
                        translations,
                        rotations,
                    })
                    .ok_or_else(|| AssetError::Transfer("a frame is not finite".into()))
            })
            .collect::<Result<Vec<_>, _>>()?;
        let postures = wire
            .values
            .chunks(dofs)
            .map(|values| Posture::from_finite_values(values.to_vec()))
            .collect::<Result<Vec<_>, _>>()
            .map_err(|e| AssetError::Transfer(format!("a posture: {e}")))?;
        Ok(FramesPart {
            frames,
            postures,
            residuals: wire.residuals,
        })
    }

    /// The clip's joint count as the head gives it, to decode the parts with.
    pub fn head_joints(head: &[u8]) -> Result<usize, AssetError> {
        let wire: HeadWire = whole(head, "head")?;
        Ok(wire.joints.len())
    }

    /// The opened clip from its head and decoded parts, for a body of `dofs` DOF.
    pub fn assemble(
        head: &[u8],
        parts: Vec<FramesPart>,
        dofs: usize,
    ) -> Result<OpenedClip, AssetError> {
        let head: HeadWire = whole(head, "head")?;
        let bad = |what: String| AssetError::Transfer(what);
        let mut frames = Vec::with_capacity(head.frame_count);
        let mut postures = Vec::with_capacity(head.frame_count);
        let mut residual_values = Vec::new();
        for part in parts {
            frames.extend(part.frames);
            postures.extend(part.postures);
            residual_values.extend(part.residuals);
        }
        if frames.len() != head.frame_count || postures.len() != head.frame_count {
            return Err(bad(format!(
                "{} frames and {} postures for a clip of {}",
                frames.len(),
                postures.len(),
                head.frame_count
            )));
        }
        if postures.iter().any(|p| p.values().len() != dofs) {
            return Err(bad(format!("postures are not of {dofs} DOF")));
        }
        let levels = head.levels.len().max(1);
        if head.frame_count.checked_mul(head.levels.len()) != Some(residual_values.len()) {
            return Err(bad("the residuals do not add up".into()));
        }
        let residuals = residual_values
            .chunks(levels)
            .map(<[f64]>::to_vec)
            .collect();
        let joints: Vec<ClipJoint> = head
            .joints
            .into_iter()
            .map(|(name, parent, offset)| ClipJoint {
                name,
                parent,
                offset,
            })
            .collect();
        let clip = Clip {
            name: head.name,
            frame_time: head.frame_time,
            joints,
            frames,
            mapping: head.mapping,
            notes: head.clip_notes,
        };
        clip.validate()
            .map_err(|error| bad(format!("the clip is inconsistent: {error}")))?;
        if clip.mapping.source_count() != clip.joints.len() {
            return Err(bad("the clip's mapping is for other joints".into()));
        }
        let retargeted = Retargeted {
            postures,
            copy: Vec::new(),
            contacts: head.contacts,
            reference_frames: head.reference_frames,
            thresholds: head.thresholds,
            levels: head.levels,
            residuals,
            iterations: head.iterations,
            frame_time: head.retargeted_frame_time,
            placement: head.placement,
            notes: head.notes,
        };
        Ok(OpenedClip { clip, retargeted })
    }

    /// The opened clip again, on a body of `dofs` DOF.
    pub fn into_opened(self, dofs: usize) -> Result<OpenedClip, AssetError> {
        let joints = Self::head_joints(&self.head)?;
        let parts = self
            .parts
            .iter()
            .map(|part| Self::decode_part(part, joints, dofs))
            .collect::<Result<Vec<_>, _>>()?;
        Self::assemble(&self.head, parts, dofs)
    }
}

/// `T` decoded from all of `bytes`.
fn whole<T: for<'de> Deserialize<'de>>(bytes: &[u8], what: &str) -> Result<T, AssetError> {
    match postcard::take_from_bytes::<T>(bytes) {
        Ok((value, [])) => Ok(value),
        Ok((_, rest)) => Err(AssetError::Transfer(format!(
            "{} bytes after the {what}",
            rest.len()
        ))),
        Err(error) => Err(AssetError::Transfer(format!("the {what}: {error}"))),
    }
}

/// A [`ClipJob`] but its file, which follows it on the trip.
#[derive(Serialize, Deserialize)]
struct JobHead {
    name: String,
    /// The file's length (what follows the head).
    file_bytes: u64,
    body: BodyWire,
    options: OptionsWire,
    mapping: Option<Mapping>,
}

#[derive(Serialize, Deserialize)]
struct JointWire {
    name: String,
    parent: Option<String>,
    offset: DVec3,
    dofs: Vec<Dof>,
    limits: Vec<(Dof, f64, f64)>,
    mass: f64,
    com: DVec3,
    stiffness: Vec<(Dof, f64)>,
    // The built joint's.
    source: Option<usize>,
    has_dofs: bool,
    axes: Vec<(Dof, Dof, f64)>,
    rest_match: DQuat,
    own_rest: DVec3,
}

#[derive(Serialize, Deserialize)]
struct BodyWire {
    joints: Vec<JointWire>,
    loa: u8,
    notes: Vec<String>,
}

impl BodyWire {
    fn of(body: &HumanoidSkeleton) -> Self {
        let joints = body
            .skeleton
            .joint_defs()
            .into_iter()
            .zip(&body.joints)
            .map(|(def, built)| JointWire {
                name: def.name,
                parent: def.parent,
                offset: def.offset,
                dofs: def.dofs,
                limits: def.limits,
                mass: def.mass,
                com: def.com,
                stiffness: def.stiffness,
                source: built.source,
                has_dofs: built.has_dofs,
                axes: built
                    .axes
                    .iter()
                    .map(|a| (a.dof, a.anatomical, a.sign))
                    .collect(),
                rest_match: built.rest_match,
                own_rest: built.own_rest,
            })
            .collect();
        Self {
            joints,
            loa: body.loa.number(),
            notes: body.notes.clone(),
        }
    }

    fn into_body(self) -> Result<HumanoidSkeleton, AssetError> {
        let bad = |what: String| AssetError::Transfer(format!("the body: {what}"));
        let loa = LevelOfArticulation::from_number(self.loa)
            .ok_or_else(|| bad(format!("no level of articulation {}", self.loa)))?;
        let mut defs = Vec::with_capacity(self.joints.len());
        let mut built = Vec::with_capacity(self.joints.len());
        for joint in self.joints {
            let hanim = stance_hanim::joint_by_name(&joint.name)
                .map(|(_, definition)| definition.name)
                .ok_or_else(|| bad(format!("{} is not an H-Anim joint", joint.name)))?;
            built.push(BuiltJoint {
                hanim,
                source: joint.source,
                has_dofs: joint.has_dofs,
                axes: joint
                    .axes
                    .into_iter()
                    .map(|(dof, anatomical, sign)| AnatomicalAxis {
                        dof,
                        anatomical,
                        sign,
                    })
                    .collect(),
                rest_match: joint.rest_match,
                own_rest: joint.own_rest,
            });
            defs.push(JointDef {
                name: joint.name,
                parent: joint.parent,
                offset: joint.offset,
                dofs: joint.dofs,
                limits: joint.limits,
                mass: joint.mass,
                com: joint.com,
                stiffness: joint.stiffness,
            });
        }
        let skeleton = Skeleton::new(defs).map_err(|error| bad(error.to_string()))?;
        // The skeleton keeps the joints in the order given (parents first, as written).
        let same_order = skeleton
            .joints()
            .iter()
            .zip(&built)
            .all(|(j, b)| j.name == b.hanim);
        if !same_order || skeleton.joint_count() != built.len() {
            return Err(bad("its joints are out of order".into()));
        }
        Ok(HumanoidSkeleton {
            skeleton,
            joints: built,
            loa,
            notes: self.notes,
        })
    }
}

#[derive(Serialize, Deserialize)]
struct OptionsWire {
    rest_match: RestMatch,
    adjustments: Vec<(String, DQuat)>,
    contacts: Option<ContactSettings>,
    root_scale: Option<f64>,
    max_iterations: usize,
}

impl OptionsWire {
    fn of(options: &RetargetOptions) -> Self {
        Self {
            rest_match: options.rest_match,
            adjustments: options.adjustments.clone(),
            contacts: options.contacts,
            root_scale: options.root_scale,
            max_iterations: options.max_iterations,
        }
    }

    fn into_options(self) -> Result<RetargetOptions, AssetError> {
        // A bounded solve: the settings' own limit is the editor's (a few dozen).
        if self.max_iterations > 10_000 {
            return Err(AssetError::Transfer(format!(
                "{} iterations per frame",
                self.max_iterations
            )));
        }
        Ok(RetargetOptions {
            rest_match: self.rest_match,
            adjustments: self.adjustments,
            contacts: self.contacts,
            root_scale: self.root_scale,
            max_iterations: self.max_iterations,
        })
    }
}

#[derive(Serialize, Deserialize)]
struct HeadWire {
    name: String,
    frame_time: f64,
    joints: Vec<(String, Option<usize>, DVec3)>,
    mapping: Mapping,
    clip_notes: Vec<String>,
    frame_count: usize,
    contacts: Vec<Contact>,
    reference_frames: usize,
    thresholds: Thresholds,
    levels: Vec<u32>,
    iterations: usize,
    retargeted_frame_time: f64,
    placement: Placement,
    notes: Vec<String>,
}

#[derive(Serialize, Deserialize)]
struct PartWire {
    frames: usize,
    #[serde(with = "pod_vec")]
    translations: Vec<[f64; 3]>,
    #[serde(with = "pod_vec")]
    rotations: Vec<[f64; 4]>,
    postures: usize,
    #[serde(with = "pod_vec")]
    values: Vec<f64>,
    #[serde(with = "pod_vec")]
    residuals: Vec<f64>,
}
