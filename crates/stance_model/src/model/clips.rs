//! Clips in and out of the editor: a BVH file or a glTF animation (another file's, or the
//! loaded avatar's own) onto the timeline, the live session recorded into a clip (sensors
//! driving it, a replay, or hand posing), the retargeting settings (rest match, contact
//! thresholds), the timeline baked out as a glTF animation on the avatar or as BVH, and the
//! clip kept with the document (embedded in a saved file, named by content hash in a link).

use std::sync::Arc;

use stance_asset::{
    ANIMATION_SAMPLE_FPS, ClipJob, OpenedClip, clip_from_animation, export_glb_animation,
    is_bvh_file,
};
use stance_document::{ClipReference, Document};
use stance_hanim::Mapping;
use stance_ik::{CONSTANT_DAMPING, Posture, Solver, SolverSettings};
use stance_motion::{BvhWriteOptions, Clip, RetargetOptions, write_bvh};

use super::EditorModel;
use super::motion::MotionCommand;
use crate::jobs::{HostJob, JobOutput, JobRequest};

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

/// A clip file the host is reading and retargeting off the editor's thread
/// ([`HostHooks::run_job`](crate::HostHooks::run_job)).
#[derive(Debug)]
pub(super) struct Opening {
    /// The host's request.
    pub(super) id: u64,
    /// The file's name.
    pub(super) name: String,
    /// How far it has got (0 to 1).
    pub(super) progress: f64,
    /// The file, asked for again when the body or the settings change meanwhile (shared
    /// with the job and the document's reference: a long clip is megabytes).
    bytes: Arc<[u8]>,
    /// The file as the document keeps it; `None`: the clip written as BVH (not a BVH file:
    /// the whole glTF file would be kept).
    source: Option<ClipReference>,
    /// A document's clip: the document's own tasks stay (none set aside), and it stays
    /// named when the clip cannot be opened.
    from_document: bool,
    /// The open clip put on the body again (after a change of body or settings) with its
    /// mapping as corrected: the playhead, keys and tasks stay as they are.
    again: Option<Mapping>,
}

/// What the next picked file is for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PickPurpose {
    /// A sensor recording to replay.
    Recording,
    /// A motion clip (BVH, or a glTF file's animation).
    Clip,
    /// OpenPose keypoints to lift (*File > Open keypoints*).
    Keypoints,
    /// A static glTF/GLB mesh to import as a prop (*File > Import prop...*).
    Prop,
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
    /// timeline stays as it was. Read and retargeted by the host where it can (off the
    /// editor's thread, the timeline shows the progress and *Cancel*), else here.
    pub(super) fn open_clip_file(&mut self, name: &str, bytes: Vec<u8>) {
        let bytes: Arc<[u8]> = bytes.into();
        let source = is_bvh_file(name).then(|| ClipReference::embed_shared(name, bytes.clone()));
        // (An open clip hidden while it was asked for again waits for this one: asked for
        // again if this one fails or is cancelled.)
        if let Some(result) = self.start_opening(name, bytes, source, false, None) {
            self.report_opening(false, false, result);
        }
    }

    /// Asks the host to read and retarget the clip file `name` (a request before it is
    /// cancelled); where it cannot, does it here. `again`: the open clip put on the body
    /// again, with this mapping. `None`: under way (the result arrives as
    /// [`MotionCommand::ClipOpened`]); else what to say after "Opened " (or, `again`, the
    /// whole notice), or why not.
    pub(super) fn start_opening(
        &mut self,
        name: &str,
        bytes: Arc<[u8]>,
        source: Option<ClipReference>,
        from_document: bool,
        again: Option<Mapping>,
    ) -> Option<Result<String, String>> {
        if let Some(previous) = self.character.timeline.opening.take() {
            self.hooks.cancel_job(previous.id);
        }
        let id = self.character.timeline.next_request;
        self.character.timeline.next_request += 1;
        let job = Box::new(ClipJob {
            name: name.to_owned(),
            bytes: bytes.clone(),
            body: self.character.session.humanoid().clone(),
            options: self.character.timeline.options.clone(),
            mapping: again.clone(),
        });
        let opening = Opening {
            id,
            name: name.to_owned(),
            progress: 0.0,
            bytes,
            source,
            from_document,
            again,
        };
        let job = HostJob::Clip(job);
        match self.hooks.run_job(JobRequest { id, job }) {
            Ok(()) => {
                self.character.timeline.opening = Some(opening);
                None
            }
            Err(request) => {
                let result = request
                    .job
                    .run(&mut |_| {})
                    .and_then(|output| match output {
                        JobOutput::Clip(opened) => Ok(*opened),
                        JobOutput::Lift(_) => Err("a clip job lifted keypoints".to_owned()),
                    });
                Some(self.finish_opening(opening, result))
            }
        }
    }

    /// The clip read and retargeted (`result`) goes on the timeline; returns what to say
    /// after "Opened ", or why it could not (the timeline then stays as it was, and a
    /// document's clip stays named).
    fn finish_opening(
        &mut self,
        opening: Opening,
        result: Result<OpenedClip, String>,
    ) -> Result<String, String> {
        let OpenedClip { clip, retargeted } = result?;
        // Made for this body (a change of body meanwhile asks again): a result that does
        // not fit it is refused rather than shown.
        let dofs = self.character.session.skeleton().dof_count();
        if retargeted.postures.len() != clip.frames.len()
            || retargeted.postures.iter().any(|p| p.values().len() != dofs)
        {
            return Err(format!(
                "The clip {} came back for another body: open it again.",
                clip.name
            ));
        }
        let source = opening.source.unwrap_or_else(|| written_source(&clip));
        let file = Some((opening.name, opening.bytes));
        if opening.again.is_some() {
            let name = clip.name.clone();
            self.set_clip(Box::new(clip), retargeted, source, file);
            self.show_playhead();
            let words = self.character.timeline.contact_words().unwrap_or_default();
            return Ok(format!("The clip {name} is on the body again: {words}."));
        }
        if opening.from_document {
            self.character.timeline.wanted = None;
        }
        let set_aside = !opening.from_document;
        Ok(self.put_clip(Box::new(clip), retargeted, source, file, set_aside))
    }

    /// The open clip could not be put on the body again (`why`): it is closed, the document
    /// still names it (its keys stay; the file opens again with Motion > Open clip).
    fn clip_lost(&mut self, why: String) {
        self.close_clip(true);
        self.warn(format!(
            "{}: the clip is closed; the document still names it (open the file again with Motion > Open clip).",
            why.trim_end_matches('.')
        ));
    }

    /// The host's progress with the clip request `id`.
    pub(super) fn clip_progress(&mut self, id: u64, fraction: f64) {
        if let Some(opening) = self.character.timeline.opening.as_mut()
            && opening.id == id
            && fraction.is_finite()
        {
            opening.progress = fraction.clamp(opening.progress, 1.0);
        }
    }

    /// The host's result for the clip request `id`: put on the timeline if it is the one
    /// awaited (dropped if it was cancelled or another clip opened since).
    pub(super) fn clip_opened(&mut self, id: u64, result: Result<Box<OpenedClip>, String>) {
        if self
            .character
            .timeline
            .opening
            .as_ref()
            .is_none_or(|o| o.id != id)
        {
            return;
        }
        let Some(opening) = self.character.timeline.opening.take() else {
            return;
        };
        let (again, from_document) = (opening.again.is_some(), opening.from_document);
        let result = self.finish_opening(opening, result.map(|opened| *opened));
        self.report_opening(again, from_document, result);
    }

    /// Says how an opening ended (`again`: the open clip put on the body again;
    /// `from_document`: a document's clip). A failure closes the open clip put on the body
    /// again and keeps it named, or else brings back the open clip hidden meanwhile.
    pub(super) fn report_opening(
        &mut self,
        again: bool,
        from_document: bool,
        result: Result<String, String>,
    ) {
        match result {
            Ok(text) if again => self.inform(text),
            Err(error) if again => self.clip_lost(error),
            Ok(text) if from_document => {
                self.inform(format!("The document's clip is on the timeline: {text}"));
            }
            Ok(text) => self.inform(format!("Opened {text}")),
            Err(error) => {
                self.warn(error);
                self.bring_back_hidden_clip();
            }
        }
    }

    /// *Cancel*: the clip being opened is dropped; the document and the timeline stay as
    /// they were (a document's clip stays named, to be opened again).
    pub(super) fn cancel_opening(&mut self) {
        let Some(opening) = self.character.timeline.opening.take() else {
            return;
        };
        self.hooks.cancel_job(opening.id);
        if opening.again.is_some() {
            self.clip_lost(format!(
                "Putting the clip {} on the body again was cancelled",
                opening.name
            ));
            return;
        }
        let text = if opening.from_document {
            format!(
                "Opening the clip {} was cancelled: the document's keys stay without it (open the file with Motion > Open clip).",
                opening.name
            )
        } else {
            format!(
                "Opening {} was cancelled: the document and the timeline are as they were.",
                opening.name
            )
        };
        self.inform(text);
        self.bring_back_hidden_clip();
    }

    /// After a change of body, retargeting settings or clip mapping, every clip is asked for
    /// again as things are now: a clip on its way (the open clip's own request with its
    /// mapping as it is now; the open clip hidden meanwhile when another is on its way to
    /// replace it, asked for again if that one fails or is cancelled), else the open clip
    /// ([`Self::retarget_clip`]).
    pub(super) fn put_clips_on_body_again(&mut self) {
        let Some(opening) = self.character.timeline.opening.take() else {
            self.retarget_clip();
            return;
        };
        self.hooks.cancel_job(opening.id);
        let again = opening.again.map(|old| {
            self.character
                .timeline
                .clip
                .as_ref()
                .map_or(old, |clip| clip.mapping.clone())
        });
        let is_again = again.is_some();
        if !is_again {
            self.hide_clip();
        }
        let from_document = opening.from_document;
        let progress = self.start_opening(
            &opening.name,
            opening.bytes,
            opening.source,
            from_document,
            again,
        );
        if let Some(result) = progress {
            self.report_opening(is_again, from_document, result);
        }
    }

    /// The open clip was hidden while another was on its way, which failed or was cancelled:
    /// it is asked for again on the body as it is.
    fn bring_back_hidden_clip(&mut self) {
        if self.character.timeline.opening.is_none() && self.clip_hidden() {
            self.retarget_clip();
        }
    }

    /// The open clip's own request (put on the body again) is cancelled, if one is on its way.
    pub(super) fn cancel_reopening(&mut self) {
        if self
            .character
            .timeline
            .opening
            .as_ref()
            .is_some_and(|opening| opening.again.is_some())
            && let Some(opening) = self.character.timeline.opening.take()
        {
            self.hooks.cancel_job(opening.id);
        }
    }

    /// Whether `reference` is the open clip's file.
    fn is_open_clip(&self, reference: &ClipReference) -> bool {
        self.character
            .timeline
            .source
            .as_ref()
            .is_some_and(|open| open.hash == reference.hash && open.size == reference.size)
    }

    /// After a document opened: the clip it carries is opened (by the host where it can:
    /// it follows), or, named without its file, is asked for. Returns what to add to the
    /// notice, and whether it is a warning.
    pub(super) fn follow_document_clip(&mut self, document: &Document) -> (String, bool) {
        let Some(reference) = &document.clip else {
            return (String::new(), false);
        };
        if self.is_open_clip(reference) {
            self.character.timeline.wanted = None;
            return (
                format!(" Its clip {} is the one open.", reference.name),
                false,
            );
        }
        // Saved again before the clip is open (or when it cannot be), the document still
        // names its clip.
        self.character.timeline.wanted = Some(reference.without_file());
        if let Some(embedded) = &reference.embedded {
            let name = reference.name.clone();
            let bytes = embedded.shared_bytes();
            return match self.start_opening(&name, bytes, Some(reference.clone()), true, None) {
                None => (
                    format!(" Its clip {name} is being read and put on the body…"),
                    false,
                ),
                Some(Ok(text)) => (format!(" With its clip: {text}"), false),
                Some(Err(error)) => (format!(" {error}"), true),
            };
        }
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
        let clip = match self.character.avatar.as_ref() {
            Some(loaded) if index < loaded.avatar.animations.len() => {
                clip_from_animation(&loaded.avatar, index, ANIMATION_SAMPLE_FPS)
                    .map_err(|e| e.to_string())
            }
            Some(_) => Err(format!("the avatar has no animation {index}")),
            None => Err("no avatar is loaded".into()),
        };
        match clip {
            Ok(clip) => {
                self.apply_motion(MotionCommand::OpenClip(Box::new(clip)));
            }
            Err(error) => self.warn(format!("The animation could not be opened: {error}.")),
        }
    }

    /// Starts recording the session frame by frame, or stops and puts the recording on the
    /// timeline as a clip (resampled at [`CLIP_FPS`]).
    pub(super) fn record_motion(&mut self, on: bool) {
        if on {
            self.character.timeline.recording = Some(Vec::new());
            self.inform("Recording: the body is captured every frame until you stop.");
            return;
        }
        let Some(samples) = self.character.timeline.recording.take() else {
            return;
        };
        if samples.len() < 2 {
            self.warn("The recording is empty: nothing moved while it ran.");
            return;
        }
        let clip = Clip::from_samples(
            "recording",
            self.character.session.humanoid(),
            &samples,
            1.0 / CLIP_FPS,
        );
        match clip {
            Ok(clip) => {
                self.apply_motion(MotionCommand::OpenClip(Box::new(clip)));
            }
            Err(error) => self.warn(format!("The recording could not become a clip: {error}.")),
        }
    }

    /// While recording, the posture of this frame (after the solve).
    pub(super) fn capture_frame(&mut self, now: f64) {
        if let Some(samples) = self.character.timeline.recording.as_mut() {
            let newer = samples.last().is_none_or(|(t, _)| now > *t);
            if newer {
                samples.push((now, self.character.session.posture().clone()));
            }
        }
    }

    /// New retargeting settings: the clip is put on the body again with them.
    pub(super) fn set_retarget_options(&mut self, options: RetargetOptions) {
        self.character.timeline.options = options;
        self.put_clips_on_body_again();
        self.show_playhead();
        if let Some(words) = self.character.timeline.contact_words() {
            self.inform(format!("The clip is put on the body again: {words}."));
        }
    }

    /// The clip's mapping corrected: the clip is put on the body again with it.
    pub(super) fn set_clip_mapping(&mut self, mapping: stance_hanim::Mapping) {
        let Some(clip) = self.character.timeline.clip.as_mut() else {
            self.warn("No clip is open: nothing to map.");
            return;
        };
        if mapping.source_count() != clip.joints.len() {
            self.warn("That mapping is for another clip.");
            return;
        }
        clip.mapping = mapping;
        let name = clip.name.clone();
        self.put_clips_on_body_again();
        self.show_playhead();
        if self.character.timeline.has_clip() {
            self.inform(format!(
                "The clip {name} is retargeted with the corrected mapping."
            ));
        }
    }

    /// Every frame of the timeline as shown: the clip and keys, then the tasks with their
    /// interval weights at that frame's time.
    pub fn baked_postures(&self) -> Vec<Posture> {
        let humanoid = self.character.session.humanoid();
        // One solve per frame, as the editor shows it: the frame-by-frame damping.
        let mut solver = Solver::new(SolverSettings {
            damping: CONSTANT_DAMPING,
            ..SolverSettings::default()
        })
        .unwrap_or_default();
        (0..self.frame_count())
            .map(|frame| {
                let mut posture = self.frame_posture(frame);
                let time = frame as f64 * self.frame_time();
                let specs = crate::posing::timed_tasks_at(
                    self.character.session.tasks(),
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
            .character
            .timeline
            .clip_name()
            .unwrap_or("stance-motion")
            .to_owned();
        let postures = self.baked_postures();
        let frame_time = self.frame_time();
        let humanoid = self.character.session.humanoid();
        let (file_name, result) = match format {
            AnimationFormat::Glb => {
                let file_name = format!("{name}.glb");
                let Some(loaded) = self.character.avatar.as_ref() else {
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
