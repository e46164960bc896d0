//! Clips in and out of the editor: a BVH file or a glTF animation (another file's, or the
//! loaded avatar's own) onto the timeline, the live session recorded into a clip (sensors
//! driving it, a replay, or hand posing), the retargeting settings (rest match, contact
//! thresholds), the timeline baked out as a glTF animation on the avatar or as BVH, and the
//! clip kept with the document (embedded in a saved file, named by content hash in a link).

use stance_asset::{
    ANIMATION_SAMPLE_FPS, LoadOptions, clip_from_animation, export_glb_animation, is_bvh_file,
    read_clip,
};
use stance_document::{ClipReference, Document};
use stance_ik::{Posture, Solver, SolverSettings};
use stance_motion::{BvhWriteOptions, Clip, RetargetOptions, write_bvh};

use super::EditorModel;
use super::motion::MotionCommand;

/// Frames per second of a recorded clip.
pub const CLIP_FPS: f64 = 30.0;
/// Largest clip file the autosave embeds (bytes; compressed, about 1 MiB of characters: the
/// browser's storage holds a few megabytes): a larger clip is autosaved as a reference, and
/// the restored work asks for its file.
pub const AUTOSAVE_CLIP_BYTES: u64 = 2 << 20;

/// The clip's file as a document keeps it when it was not read from a BVH file (a glTF
/// animation, a recording): the clip written as BVH (`<name>.bvh`), which reads back as the
/// same clip.
pub(super) fn written_source(clip: &Clip) -> ClipReference {
    let text = write_bvh(clip, &BvhWriteOptions::default());
    ClipReference::embed(&format!("{}.bvh", clip.name), text.as_bytes())
}

/// The clip read from the file `name`, as a document keeps it: a BVH file as it is, other
/// files (a glTF file's animation: the whole file would be kept) as [`written_source`].
fn file_source(name: &str, bytes: &[u8], clip: &Clip) -> ClipReference {
    if is_bvh_file(name) {
        ClipReference::embed(name, bytes)
    } else {
        written_source(clip)
    }
}

/// A clip a document carries, read before the document is opened (a clip that cannot be
/// read leaves everything as it was).
pub(super) struct DocumentClip {
    clip: Box<Clip>,
    source: ClipReference,
}

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
            Ok(clip) => {
                let source = file_source(name, bytes, &clip);
                match self.open_clip(Box::new(clip), source, true) {
                    Ok(text) => self.inform(format!("Opened {text}")),
                    Err(error) => self.warn(error),
                }
            }
            Err(error) => self.warn(format!("{name} could not be opened as a clip: {error}.")),
        }
    }

    /// The clip `document` carries, read; `None` when it carries none, only names one, or
    /// names the clip already open. `Err`: the embedded file is not a clip (what to say).
    pub(super) fn read_document_clip(
        &self,
        document: &Document,
    ) -> Result<Option<DocumentClip>, String> {
        let Some(reference) = &document.clip else {
            return Ok(None);
        };
        let Some(embedded) = &reference.embedded else {
            return Ok(None);
        };
        if self.is_open_clip(reference) {
            return Ok(None);
        }
        let name = &reference.name;
        let clip = read_clip(name, embedded.bytes(), &LoadOptions::default(), &mut |_| {
            None
        })
        .map_err(|error| format!("its clip {name} could not be read: {error}"))?;
        Ok(Some(DocumentClip {
            clip: Box::new(clip),
            source: reference.clone(),
        }))
    }

    /// Whether `reference` is the open clip's file.
    fn is_open_clip(&self, reference: &ClipReference) -> bool {
        self.timeline
            .source
            .as_ref()
            .is_some_and(|open| open.hash == reference.hash && open.size == reference.size)
    }

    /// After a document opened: its clip goes on the timeline (`read`, from
    /// [`Self::read_document_clip`]), or, named without its file, is asked for. Returns what
    /// to add to the notice, and whether it is a warning.
    pub(super) fn follow_document_clip(
        &mut self,
        document: &Document,
        read: Option<DocumentClip>,
    ) -> (String, bool) {
        if let Some(DocumentClip { clip, source }) = read {
            let reference = source.without_file();
            self.timeline.wanted = None;
            return match self.open_clip(clip, source, false) {
                Ok(text) => (format!(" With its clip: {text}"), false),
                Err(error) => {
                    // Saved again, the document still names its clip.
                    self.timeline.wanted = Some(reference);
                    (format!(" {error}"), true)
                }
            };
        }
        let Some(reference) = &document.clip else {
            return (String::new(), false);
        };
        if self.is_open_clip(reference) {
            self.timeline.wanted = None;
            return (
                format!(" Its clip {} is the one open.", reference.name),
                false,
            );
        }
        self.timeline.wanted = Some(reference.without_file());
        (
            format!(
                " Its keys were made over the clip {} ({} bytes), which is not loaded: open that file (Motion > Open clip) to see them over it.",
                reference.name, reference.size
            ),
            true,
        )
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

impl super::Timeline {
    /// The clip the document keeps, for the autosave: embedded while it is small enough for
    /// the browser's storage, else named only.
    pub(super) fn autosaved_clip(&self) -> Option<ClipReference> {
        self.document_clip().map(|clip| {
            if clip.embedded.is_some() && clip.size <= AUTOSAVE_CLIP_BYTES {
                clip.clone()
            } else {
                clip.without_file()
            }
        })
    }
}
