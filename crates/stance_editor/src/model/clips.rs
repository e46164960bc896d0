//! Clips in and out of the editor: a BVH file or a glTF animation (another file's, or the
//! loaded avatar's own) onto the timeline, the live session recorded into a clip (sensors
//! driving it, a replay, or hand posing), the retargeting settings (rest match, contact
//! thresholds), and the timeline baked out as a glTF animation on the avatar or as BVH.

use stance_asset::{
    ANIMATION_SAMPLE_FPS, LoadOptions, clip_from_animation, export_glb_animation, read_clip,
};
use stance_ik::{Posture, Solver, SolverSettings};
use stance_motion::{BvhWriteOptions, Clip, RetargetOptions, write_bvh};

use super::EditorModel;
use super::motion::MotionCommand;

/// Frames per second of a recorded clip.
pub const CLIP_FPS: f64 = 30.0;

/// What the next picked file is for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PickPurpose {
    /// A sensor recording to replay.
    Recording,
    /// A motion clip (BVH, or a glTF file's animation).
    Clip,
}

/// How a baked animation is written.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum AnimationFormat {
    /// The avatar with a glTF animation (GLB).
    Glb,
    /// BVH with H-Anim joint names.
    Bvh,
}

impl EditorModel {
    /// Opens a picked or dropped clip file; a file that cannot be read says why and the
    /// timeline stays as it was.
    pub(super) fn open_clip_file(&mut self, name: &str, bytes: &[u8]) {
        match read_clip(name, bytes, &LoadOptions::default(), &mut |_| None) {
            Ok(clip) => self.apply_motion(MotionCommand::OpenClip(Box::new(clip))),
            Err(error) => self.warn(format!("{name} could not be opened as a clip: {error}.")),
        }
    }

    /// Puts the loaded avatar's animation `index` on the timeline.
    pub(super) fn open_avatar_animation(&mut self, index: usize) {
        let clip = match self.avatar.as_ref() {
            Some(loaded) if index < loaded.avatar.animations.len() => {
                clip_from_animation(&loaded.avatar, index, ANIMATION_SAMPLE_FPS)
                    .map_err(|e| e.to_string())
            }
            Some(_) => Err(format!("the avatar has no animation {index}")),
            None => Err("no avatar is loaded".into()),
        };
        match clip {
            Ok(clip) => self.apply_motion(MotionCommand::OpenClip(Box::new(clip))),
            Err(error) => self.warn(format!("The animation could not be opened: {error}.")),
        }
    }

    /// Starts recording the session frame by frame, or stops and puts the recording on the
    /// timeline as a clip (resampled at [`CLIP_FPS`]).
    pub(super) fn record_motion(&mut self, on: bool) {
        if on {
            self.timeline.recording = Some(Vec::new());
            self.inform("Recording: the body is captured every frame until you stop.");
            return;
        }
        let Some(samples) = self.timeline.recording.take() else {
            return;
        };
        if samples.len() < 2 {
            self.warn("The recording is empty: nothing moved while it ran.");
            return;
        }
        let clip = Clip::from_samples(
            "recording",
            self.session.humanoid(),
            &samples,
            1.0 / CLIP_FPS,
        );
        match clip {
            Ok(clip) => self.apply_motion(MotionCommand::OpenClip(Box::new(clip))),
            Err(error) => self.warn(format!("The recording could not become a clip: {error}.")),
        }
    }

    /// While recording, the posture of this frame (after the solve).
    pub(super) fn capture_frame(&mut self, now: f64) {
        if let Some(samples) = self.timeline.recording.as_mut() {
            let newer = samples.last().is_none_or(|(t, _)| now > *t);
            if newer {
                samples.push((now, self.session.posture().clone()));
            }
        }
    }

    /// New retargeting settings: the clip is put on the body again with them.
    pub(super) fn set_retarget_options(&mut self, options: RetargetOptions) {
        self.timeline.options = options;
        self.retarget_clip();
        self.show_playhead();
        if let Some(words) = self.timeline.contact_words() {
            self.inform(format!("The clip is put on the body again: {words}."));
        }
    }

    /// The clip's mapping corrected: the clip is put on the body again with it.
    pub(super) fn set_clip_mapping(&mut self, mapping: stance_hanim::Mapping) {
        let Some(clip) = self.timeline.clip.as_mut() else {
            self.warn("No clip is open: nothing to map.");
            return;
        };
        if mapping.source_count() != clip.joints.len() {
            self.warn("That mapping is for another clip.");
            return;
        }
        clip.mapping = mapping;
        let name = clip.name.clone();
        self.retarget_clip();
        self.show_playhead();
        if self.timeline.has_clip() {
            self.inform(format!(
                "The clip {name} is retargeted with the corrected mapping."
            ));
        }
    }

    /// Every frame of the timeline as shown: the clip and keys, then the tasks with their
    /// interval weights at that frame's time.
    pub fn baked_postures(&self) -> Vec<Posture> {
        let humanoid = self.session.humanoid();
        let mut solver = Solver::new(SolverSettings::default()).unwrap_or_default();
        (0..self.frame_count())
            .map(|frame| {
                let mut posture = self.frame_posture(frame);
                let time = frame as f64 * self.frame_time();
                let specs = crate::posing::timed_tasks_at(
                    self.session.tasks(),
                    &humanoid.skeleton,
                    &posture,
                    time,
                );
                let tasks: Vec<_> = specs
                    .iter()
                    .filter_map(|spec| spec.to_solver_tasks_on(humanoid, &specs).ok())
                    .flatten()
                    .collect();
                if !tasks.is_empty() {
                    // A frame the solver refuses keeps the clip's posture.
                    let _ = solver.solve(&humanoid.skeleton, &tasks, &mut posture);
                }
                posture
            })
            .collect()
    }

    /// Offers the timeline as a download: a GLB of the avatar with the animation, or BVH.
    pub(super) fn export_animation(&mut self, format: AnimationFormat) {
        if !self.has_timeline() {
            self.warn("Nothing to export: open a clip or set keys first (Motion menu).");
            return;
        }
        let name = self
            .timeline
            .clip_name()
            .unwrap_or("stance-motion")
            .to_owned();
        let postures = self.baked_postures();
        let frame_time = self.frame_time();
        let humanoid = self.session.humanoid();
        let (file_name, result) = match format {
            AnimationFormat::Glb => {
                let file_name = format!("{name}.glb");
                let Some(loaded) = self.avatar.as_ref() else {
                    self.warn("Load an avatar first (Avatar menu) to export a GLB, or export BVH.");
                    return;
                };
                let bytes =
                    export_glb_animation(&loaded.avatar, humanoid, &postures, frame_time, &name)
                        .map_err(|e| e.to_string());
                let sent =
                    bytes.and_then(|b| self.hooks.download_bytes(&file_name, &b).map(|()| b.len()));
                (file_name, sent)
            }
            AnimationFormat::Bvh => {
                let file_name = format!("{name}.bvh");
                let clip = Clip::from_postures(&name, humanoid, &postures, frame_time);
                let text = write_bvh(&clip, &BvhWriteOptions::default());
                let sent = self.hooks.download(&file_name, &text).map(|()| text.len());
                (file_name, sent)
            }
        };
        match result {
            Ok(size) => self.inform(format!(
                "Exported {file_name} ({} KB): {} frames at {:.3} fps.",
                size.div_ceil(1024),
                postures.len(),
                1.0 / frame_time
            )),
            Err(error) => self.warn(format!("{file_name} could not be exported: {error}")),
        }
    }
}
