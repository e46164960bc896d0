//! The timeline, without egui: an optional motion clip retargeted onto the current body
//! (with its foot contacts), the playhead (play, pause, scrub, step, loop, speed), the
//! keyframes (an additive layer over the clip, kept in the document's `motion` section so
//! that undo, autosave and files carry them), the tasks' active intervals, and the
//! trajectory of one joint over every frame.
//!
//! Playback puts each new frame's posture into the session without an undo record; the
//! tasks then act on it with their interval weights (`posing::timed_tasks`). A gesture or a
//! posture edit made while paused on a timeline becomes a key at the current frame once the
//! body settles (covered by the edit's own undo record).

mod layer;
mod timeline;

use std::sync::Arc;

use glam::DVec3;
use stance_document::motion::{DEFAULT_FRAME_COUNT, DEFAULT_FRAME_TIME};
use stance_document::{ClipReference, MotionKey, MotionSection, PostureValues, TaskInterval};
use stance_hanim::resolve_joint;
use stance_ik::{Frames, Posture};
use stance_motion::{Clip, RetargetOptions, Retargeted, retarget};

use self::layer::{KeyDelta, apply_delta, delta_at, key_delta, key_deltas};
use super::{Change, EditorModel};
use crate::history::EditKind;

/// Frames of the trajectory computed per step (see `refresh_trajectory`).
pub const TRAJECTORY_FRAMES_PER_STEP: usize = 1000;

/// Slowest and fastest playback.
pub const SPEED_RANGE: (f64, f64) = (0.1, 4.0);

/// What the timeline is asked to do.
#[derive(Debug, Clone)]
pub enum MotionCommand {
    /// Retarget a clip onto the body (with its foot contacts) and put it on the timeline.
    OpenClip(Box<Clip>),
    /// Take the clip off the timeline (the keys stay).
    CloseClip,
    /// Start playing from the playhead.
    Play,
    /// Stop where the playhead is.
    Pause,
    /// Play or pause.
    TogglePlay,
    /// Move the playhead to a frame (scrub).
    Seek(usize),
    /// Move the playhead by a number of frames (±1: step).
    StepFrames(i64),
    /// Loop at the end, or stop there.
    SetLooping(bool),
    /// Playback speed (clamped to [`SPEED_RANGE`]).
    SetSpeed(f64),
    /// Frames of a timeline without a clip.
    SetFrameCount(usize),
    /// A key at the playhead from the current posture.
    SetKey,
    /// Delete the key at a frame.
    DeleteKey(usize),
    /// Move the key at `from` to `to` (its change over the clip moves with it).
    MoveKey {
        /// The key's frame.
        from: usize,
        /// Where it goes.
        to: usize,
    },
    /// Copy the key at `from` to `to`.
    CopyKey {
        /// The key's frame.
        from: usize,
        /// Where the copy goes.
        to: usize,
    },
    /// Set (or clear) a task's active interval.
    SetInterval {
        /// The task (index in the task list).
        task: usize,
        /// The interval; `None`: always active.
        interval: Option<TaskInterval>,
    },
    /// Drag one end of a task's interval to `secs`.
    DragInterval {
        /// The task (index in the task list).
        task: usize,
        /// Which end.
        edge: IntervalEdge,
        /// Where it goes (s).
        secs: f64,
    },
    /// The joint whose trajectory is drawn (H-Anim name); `None`: the selected joint.
    SetTrajectory(Option<String>),
    /// Put the loaded avatar's glTF animation `index` on the timeline.
    OpenAvatarAnimation(usize),
    /// Start (true) or stop (false) recording the body every frame; stopping puts the
    /// recording on the timeline as a clip.
    Record(bool),
    /// Retarget the clip again with these settings (rest match, contact thresholds).
    SetRetargetOptions(Box<RetargetOptions>),
    /// The clip's joints mapped onto H-Anim this way (the mapping window's corrections):
    /// the clip is retargeted with it.
    SetClipMapping(Box<stance_hanim::Mapping>),
    /// How far the host has got with the clip being opened (request `id`).
    ClipProgress {
        /// The host's request.
        id: u64,
        /// From 0 to 1.
        fraction: f64,
    },
    /// The clip being opened (request `id`), read and retargeted by the host, or why not.
    ClipOpened {
        /// The host's request.
        id: u64,
        /// The clip and its retargeting, or what is wrong (in words).
        result: Result<Box<stance_asset::OpenedClip>, String>,
    },
    /// Stop opening the clip: the document and the timeline stay as they were.
    CancelOpening,
}

impl MotionCommand {
    /// What carrying out the command changes: the playhead and playback are the view; the
    /// clip, keys and intervals are the document.
    pub fn change(&self) -> Change {
        match self {
            MotionCommand::Play
            | MotionCommand::Pause
            | MotionCommand::TogglePlay
            | MotionCommand::Seek(_)
            | MotionCommand::StepFrames(_)
            | MotionCommand::SetLooping(_)
            | MotionCommand::SetSpeed(_)
            | MotionCommand::SetTrajectory(_)
            | MotionCommand::ClipProgress { .. }
            | MotionCommand::Record(true) => Change::View,
            MotionCommand::OpenClip(_)
            | MotionCommand::CloseClip
            | MotionCommand::SetFrameCount(_)
            | MotionCommand::SetKey
            | MotionCommand::DeleteKey(_)
            | MotionCommand::MoveKey { .. }
            | MotionCommand::CopyKey { .. }
            | MotionCommand::SetInterval { .. }
            | MotionCommand::DragInterval { .. }
            | MotionCommand::OpenAvatarAnimation(_)
            | MotionCommand::Record(false)
            | MotionCommand::SetRetargetOptions(_)
            | MotionCommand::SetClipMapping(_)
            | MotionCommand::ClipOpened { .. }
            | MotionCommand::CancelOpening => Change::Document,
        }
    }
}

/// One end of an active interval.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum IntervalEdge {
    /// The start of full effect.
    Start,
    /// The end of full effect.
    End,
}

/// The timeline's state (the keys are in the session's document).
#[derive(Debug)]
pub struct Timeline {
    pub(super) clip: Option<Box<Clip>>,
    retargeted: Option<Retargeted>,
    playing: bool,
    looping: bool,
    speed: f64,
    /// The playhead (s).
    position: f64,
    frame: usize,
    last_now: f64,
    /// The frame whose posture the session shows.
    shown: Option<usize>,
    pending_key: bool,
    trajectory_joint: Option<String>,
    trajectory: Vec<DVec3>,
    /// What the trajectory was computed for: joint, clip revision, session generation,
    /// keys revision.
    trajectory_for: Option<(usize, u64, u64, u64)>,
    /// Changes when the clip or its retargeting changes.
    base_revision: u64,
    /// How clips are put on the body (rest match, contacts).
    pub(super) options: RetargetOptions,
    /// The body captured every frame while recording: `(seconds, posture)`.
    pub(super) recording: Option<Vec<(f64, Posture)>>,
    /// The open clip's file as the document keeps it (embedded): the file read, or the clip
    /// written as BVH when it came from elsewhere.
    pub(super) source: Option<ClipReference>,
    /// The clip a document or link was made over whose file is not loaded yet: the next
    /// clip opened is compared with it.
    pub(super) wanted: Option<ClipReference>,
    /// The clip file the host is reading and retargeting ([`HostHooks::retarget_clip`](crate::HostHooks::retarget_clip)).
    pub(super) opening: Option<super::clips::Opening>,
    /// The file the open clip was read from (name, contents): after a change of body or
    /// settings it goes back to the host to be put on the body again off the editor's
    /// thread. `None` for a recording or an avatar's animation (put on the body here).
    pub(super) file: Option<(String, Arc<[u8]>)>,
    /// The id of the next clip request to the host.
    pub(super) next_request: u64,
}

impl EditorModel {
    /// The timeline: clip, playhead, contacts, trajectory.
    pub fn timeline(&self) -> &Timeline {
        &self.character.timeline
    }

    /// Whether there is a timeline to show: a clip or keys.
    pub fn has_timeline(&self) -> bool {
        self.character.timeline.has_clip() || !self.key_frames().is_empty()
    }

    /// Frames of the timeline: the clip's (also while it is hidden, being put on the body
    /// again: the same count), else the document's (60 by default).
    pub fn frame_count(&self) -> usize {
        match (
            self.character.timeline.base_postures(),
            &self.character.timeline.clip,
            self.character.session.motion(),
        ) {
            (Some(postures), _, _) => postures.len().max(1),
            (None, Some(hidden), _) => hidden.frames.len().max(1),
            (None, None, Some(motion)) => motion.frame_count.max(1),
            (None, None, None) => DEFAULT_FRAME_COUNT,
        }
    }

    /// Seconds per frame: the clip's, else the document's (30 fps by default).
    pub fn frame_time(&self) -> f64 {
        match (
            &self.character.timeline.retargeted,
            &self.character.timeline.clip,
            self.character.session.motion(),
        ) {
            (Some(retargeted), _, _) => retargeted.frame_time,
            (None, Some(hidden), _) => hidden.frame_time,
            (None, None, Some(motion)) => motion.frame_time,
            (None, None, None) => DEFAULT_FRAME_TIME,
        }
    }

    /// The frames that have a key, in order.
    pub fn key_frames(&self) -> Vec<usize> {
        self.character
            .session
            .motion()
            .map(|motion| motion.keys.iter().map(|key| key.frame).collect())
            .unwrap_or_default()
    }

    /// The posture of `frame`: the clip's (or the rest posture) with the keys' layer.
    pub fn frame_posture(&self, frame: usize) -> Posture {
        let deltas = self.key_layer();
        self.layered_posture(&deltas, frame)
    }

    fn base_posture(&self, frame: usize) -> Posture {
        let skeleton = self.character.session.skeleton();
        match self.character.timeline.base_postures() {
            Some(postures) if !postures.is_empty() => {
                postures[frame.min(postures.len() - 1)].clone()
            }
            _ => Posture::rest(skeleton),
        }
    }

    fn key_layer(&self) -> Vec<KeyDelta> {
        let keys = self
            .character
            .session
            .motion()
            .map_or(&[][..], |m| m.keys.as_slice());
        key_deltas(self.character.session.skeleton(), keys, |frame| {
            self.base_posture(frame)
        })
    }

    fn layered_posture(&self, deltas: &[KeyDelta], frame: usize) -> Posture {
        let base = self.base_posture(frame);
        match delta_at(deltas, frame) {
            Some((rotations, translation)) => apply_delta(
                self.character.session.skeleton(),
                &base,
                &rotations,
                translation,
            ),
            None => base,
        }
    }

    /// Carries out a timeline command; says what it changed ([`MotionCommand::change`]).
    pub(crate) fn apply_motion(&mut self, command: MotionCommand) -> Change {
        let change = command.change();
        self.carry_out_motion(command);
        change
    }

    /// Carries out a timeline command.
    fn carry_out_motion(&mut self, command: MotionCommand) {
        match command {
            MotionCommand::OpenClip(clip) => {
                let source = super::clips::written_source(&clip);
                match self.open_clip(clip, source, true) {
                    Ok(text) => self.inform(format!("Opened {text}")),
                    Err(error) => self.warn(error),
                }
            }
            MotionCommand::CloseClip => self.close_clip(false),
            MotionCommand::Play => self.play(true),
            MotionCommand::Pause => self.play(false),
            MotionCommand::TogglePlay => self.play(!self.character.timeline.playing),
            MotionCommand::Seek(frame) => self.seek(frame),
            MotionCommand::StepFrames(by) => {
                self.character.timeline.playing = false;
                let frame = self.character.timeline.frame as i64 + by;
                self.seek(frame.max(0) as usize);
            }
            MotionCommand::SetLooping(looping) => self.character.timeline.looping = looping,
            MotionCommand::SetSpeed(speed) => {
                if speed.is_finite() {
                    self.character.timeline.speed = speed.clamp(SPEED_RANGE.0, SPEED_RANGE.1);
                }
            }
            MotionCommand::SetFrameCount(count) => self.set_frame_count(count),
            MotionCommand::SetKey
            | MotionCommand::DeleteKey(_)
            | MotionCommand::MoveKey { .. }
            | MotionCommand::CopyKey { .. }
                if self.clip_hidden() =>
            {
                self.inform(
                    "The clip is being put on the body: keys can be edited once it is back.",
                );
            }
            MotionCommand::SetKey => self.set_key_here(true),
            MotionCommand::DeleteKey(frame) => self.edit_keys(|keys, _| {
                keys.retain(|key| key.frame != frame);
            }),
            MotionCommand::MoveKey { from, to } => self.move_key(from, to, false),
            MotionCommand::CopyKey { from, to } => self.move_key(from, to, true),
            MotionCommand::SetInterval { task, interval } => self.set_interval(task, interval),
            MotionCommand::DragInterval { task, edge, secs } => {
                self.drag_interval(task, edge, secs);
            }
            MotionCommand::SetTrajectory(joint) => {
                self.character.timeline.trajectory_joint = joint;
                self.refresh_trajectory();
            }
            MotionCommand::OpenAvatarAnimation(index) => self.open_avatar_animation(index),
            MotionCommand::Record(on) => self.record_motion(on),
            MotionCommand::SetRetargetOptions(options) => self.set_retarget_options(*options),
            MotionCommand::SetClipMapping(mapping) => self.set_clip_mapping(*mapping),
            MotionCommand::ClipProgress { id, fraction } => self.clip_progress(id, fraction),
            MotionCommand::ClipOpened { id, result } => self.clip_opened(id, result),
            MotionCommand::CancelOpening => self.cancel_opening(),
        }
    }

    /// Retargets `clip` onto the body and puts it on the timeline, kept in the document as
    /// `source`; `set_aside`: the tasks without an interval are set aside (a clip opened by
    /// the user; not one a document brings back with its own tasks). Returns what to say
    /// after "Opened " (`the clip walk: 260 frames...`), or why it could not be put on the
    /// body (the timeline then stays as it was).
    pub(super) fn open_clip(
        &mut self,
        clip: Box<Clip>,
        source: ClipReference,
        set_aside: bool,
    ) -> Result<String, String> {
        let retargeted = retarget(
            &clip,
            self.character.session.humanoid(),
            &self.character.timeline.options,
        )
        .map_err(|error| {
            format!(
                "The clip {} could not be put on this body: {error}.",
                clip.name
            )
        })?;
        Ok(self.put_clip(clip, retargeted, source, None, set_aside))
    }

    /// Puts `clip`, retargeted onto the body, on the timeline (see [`Self::open_clip`]).
    pub(super) fn put_clip(
        &mut self,
        clip: Box<Clip>,
        retargeted: Retargeted,
        source: ClipReference,
        file: Option<(String, Arc<[u8]>)>,
        set_aside: bool,
    ) -> String {
        let (frames, fps) = (retargeted.postures.len(), 1.0 / retargeted.frame_time);
        let contacts = contact_words(&retargeted);
        let name = clip.name.clone();
        let mut text = format!("the clip {name}: {frames} frames at {fps:.3} fps, {contacts}.");
        if let Some(wanted) = self.character.timeline.wanted.take() {
            if wanted.hash == source.hash && wanted.size == source.size {
                text.push_str(&format!(
                    " It is the clip the document was made over ({}): its keys are over it again.",
                    wanted.name
                ));
            } else {
                text.push_str(&format!(
                    " The document was made over another clip, {} ({} bytes, {}): its keys may not fit this one.",
                    wanted.name,
                    wanted.size,
                    wanted.hash_text()
                ));
            }
        }
        self.set_clip(clip, retargeted, source, file);
        self.character.timeline.playing = false;
        let set_aside = if set_aside {
            self.set_aside_standing_tasks()
        } else {
            0
        };
        if set_aside > 0 {
            text.push_str(&format!(
                " {set_aside} task(s) without an active interval were set aside: they would hold the body as it stands against the clip (undo brings them back)."
            ));
        }
        self.seek(0);
        text
    }

    /// Removes the tasks without an interval (the standing pins, balance, comfort) as one
    /// undoable edit. Returns how many.
    fn set_aside_standing_tasks(&mut self) -> usize {
        let tasks: Vec<_> = self
            .character
            .session
            .tasks()
            .iter()
            .filter(|task| task.interval.is_some())
            .cloned()
            .collect();
        let removed = self.character.session.tasks().len() - tasks.len();
        self.commit_tasks(EditKind::Command, tasks);
        removed
    }

    fn play(&mut self, playing: bool) {
        self.flush_pending_key();
        if playing
            && self.character.timeline.frame + 1 >= self.frame_count()
            && !self.character.timeline.looping
        {
            self.character.timeline.frame = 0;
            self.character.timeline.position = 0.0;
        }
        self.character.timeline.playing = playing;
        self.character.timeline.last_now = self.now_secs;
    }

    fn seek(&mut self, frame: usize) {
        self.flush_pending_key();
        let frame = frame.min(self.frame_count() - 1);
        self.character.timeline.frame = frame;
        self.character.timeline.position = frame as f64 * self.frame_time();
        self.show_frame(frame);
    }

    /// Puts the posture of `frame` in the session (no undo record).
    fn show_frame(&mut self, frame: usize) {
        let posture = self.frame_posture(frame);
        let time = frame as f64 * self.frame_time();
        self.character.session.show_timed(Some((posture, time)));
        self.character.timeline.shown = Some(frame);
    }

    /// The playhead advances while playing (real time × speed), and a new frame is shown.
    pub(super) fn motion_before_solve(&mut self, now: f64) {
        let elapsed = (now - self.character.timeline.last_now).max(0.0);
        self.character.timeline.last_now = now;
        if !self.character.timeline.playing {
            return;
        }
        let (count, frame_time) = (self.frame_count(), self.frame_time());
        let duration = count as f64 * frame_time;
        let mut position =
            self.character.timeline.position + elapsed * self.character.timeline.speed;
        let mut frame = (position / frame_time + 1e-9).floor() as usize;
        if frame >= count {
            if self.character.timeline.looping && duration > 0.0 {
                position %= duration;
                frame = ((position / frame_time + 1e-9).floor() as usize).min(count - 1);
            } else {
                frame = count - 1;
                position = frame as f64 * frame_time;
                self.character.timeline.playing = false;
            }
        }
        self.character.timeline.position = position;
        self.character.timeline.frame = frame;
        if self.character.timeline.shown != Some(frame) {
            self.show_frame(frame);
        }
    }

    /// A pending key is set once the body settles; the trajectory follows the keys.
    pub(super) fn motion_after_solve(&mut self) {
        if self.character.timeline.pending_key
            && self.gesture.is_none()
            && self.character.session.is_settled()
        {
            self.flush_pending_key();
        }
        self.refresh_trajectory();
    }

    /// A gesture ended or a posture edit landed: paused on a timeline, it becomes a key.
    pub(super) fn motion_posture_edited(&mut self) {
        if self.has_timeline() && !self.character.timeline.playing {
            self.character.timeline.pending_key = true;
        }
    }

    /// Undo or redo put a document back: no key is pending any more.
    pub(super) fn motion_restored(&mut self) {
        self.character.timeline.pending_key = false;
    }

    /// The session was replaced (another body, LOA or mapping): the keys carry over by
    /// joint name, the clip is retargeted onto the new body and the frame shown again.
    pub(super) fn motion_session_replaced(&mut self, motion: Option<MotionSection>) {
        self.character.timeline.pending_key = false;
        self.character.timeline.shown = None;
        if self.character.session.motion().is_none() && motion.is_some() {
            self.character.session.set_motion(motion);
        }
        self.put_clips_on_body_again();
        self.character.timeline.playing = false;
        self.show_playhead();
    }

    /// Puts the open clip on the current body again (no clip on its way). A clip read from a
    /// file goes back to the host with the file and its mapping as corrected (off the editor's
    /// thread where the host can: hidden meanwhile, as it was made for the old body; the
    /// document still names it); a recording or an avatar's animation is put on the body here.
    /// A clip that does not fit is closed with a notice.
    pub(super) fn retarget_clip(&mut self) {
        let Some(clip) = &self.character.timeline.clip else {
            return;
        };
        if let Some((name, bytes)) = self.character.timeline.file.clone() {
            let mapping = clip.mapping.clone();
            let source = self.character.timeline.source.clone();
            self.hide_clip();
            if let Some(result) = self.start_opening(&name, bytes, source, false, Some(mapping)) {
                self.report_opening(true, false, result);
            }
            return;
        }
        match retarget(
            clip,
            self.character.session.humanoid(),
            &self.character.timeline.options,
        ) {
            Ok(retargeted) => self.character.timeline.retargeted = Some(retargeted),
            Err(error) => {
                self.close_clip(false);
                self.warn(format!("The clip does not fit the body: {error}."));
            }
        }
        self.character.timeline.base_revision += 1;
        self.character.timeline.shown = None;
    }

    /// The open clip hidden from the timeline (made for another body) while it is asked for
    /// again or another clip on its way replaces it; the document still names it.
    pub(super) fn hide_clip(&mut self) {
        if self.character.timeline.retargeted.take().is_some() {
            self.character.timeline.base_revision += 1;
            self.character.timeline.shown = None;
        }
    }

    /// Whether the open clip is hidden (see [`Self::hide_clip`]).
    pub(super) fn clip_hidden(&self) -> bool {
        self.character.timeline.clip.is_some() && self.character.timeline.retargeted.is_none()
    }

    /// `clip`, retargeted onto the body, on the timeline, kept in the document as `source`
    /// and read from `file` (see [`Timeline::file`]).
    pub(super) fn set_clip(
        &mut self,
        clip: Box<Clip>,
        retargeted: Retargeted,
        source: ClipReference,
        file: Option<(String, Arc<[u8]>)>,
    ) {
        self.character.timeline.clip = Some(clip);
        self.character.timeline.retargeted = Some(retargeted);
        self.character.timeline.source = Some(source);
        self.character.timeline.file = file;
        self.character.timeline.base_revision += 1;
        self.character.timeline.shown = None;
    }

    /// Closes the clip (a request putting it on the body again is cancelled); `keep_named`:
    /// the document still names it (its keys stay; its file opens again with Motion > Open
    /// clip).
    pub(super) fn close_clip(&mut self, keep_named: bool) {
        self.cancel_reopening();
        let source = self.character.timeline.source.take();
        self.character.timeline.wanted = if keep_named {
            source.or(self.character.timeline.wanted.take())
        } else {
            None
        };
        self.character.timeline.clip = None;
        self.character.timeline.retargeted = None;
        self.character.timeline.file = None;
        self.character.timeline.playing = false;
        self.character.timeline.base_revision += 1;
        self.character.timeline.shown = None;
        self.character.session.show_timed(None);
    }

    /// Shows the playhead's frame again (after the clip or the body changed).
    pub(super) fn show_playhead(&mut self) {
        if self.has_timeline() {
            let frame = self.character.timeline.frame.min(self.frame_count() - 1);
            self.seek(frame);
        }
    }

    fn flush_pending_key(&mut self) {
        // A key over a clip that is being put on the body would be taken over the rest posture.
        if std::mem::take(&mut self.character.timeline.pending_key) && !self.clip_hidden() {
            self.set_key_here(false);
        }
    }

    /// The document's motion section, made for this timeline when missing.
    fn motion_section(&self) -> MotionSection {
        let mut motion = self.character.session.motion().cloned().unwrap_or_default();
        if let Some(retargeted) = &self.character.timeline.retargeted {
            motion.frame_time = retargeted.frame_time;
            motion.frame_count = retargeted.postures.len().max(1);
        }
        motion
    }

    /// A key at the playhead from the current posture; `record`: as its own undo step
    /// (otherwise the gesture's or edit's record covers it).
    fn set_key_here(&mut self, record: bool) {
        let frame = self.character.timeline.frame;
        let posture = PostureValues::from_posture(
            self.character.session.skeleton(),
            self.character.session.posture(),
        );
        let mut motion = self.motion_section();
        motion.keys.retain(|key| key.frame != frame);
        let at = motion.keys.partition_point(|key| key.frame < frame);
        motion.keys.insert(at, MotionKey { frame, posture });
        if record {
            self.record(EditKind::Command);
        }
        self.character.session.set_motion(Some(motion));
        self.character.timeline.shown = Some(frame);
    }

    /// One undoable change of the keys; the playhead's frame is shown again.
    fn edit_keys(&mut self, change: impl FnOnce(&mut Vec<MotionKey>, &Self)) {
        let mut motion = self.motion_section();
        change(&mut motion.keys, self);
        if Some(&motion) == self.character.session.motion() {
            return;
        }
        self.record(EditKind::Command);
        self.character.session.set_motion(Some(motion));
        if self.has_timeline() {
            self.show_frame(self.character.timeline.frame);
        }
    }

    /// Moves (or copies) the key at `from` to `to`: its change over the clip goes along.
    fn move_key(&mut self, from: usize, to: usize, copy: bool) {
        let to = to.min(self.frame_count() - 1);
        if from == to {
            return;
        }
        self.edit_keys(|keys, model| {
            let Some(index) = keys.iter().position(|key| key.frame == from) else {
                return;
            };
            let skeleton = model.character.session.skeleton();
            let key = layer::lenient_posture(skeleton, &keys[index].posture);
            let delta = key_delta(skeleton, from, &key, &model.base_posture(from));
            let moved = apply_delta(
                skeleton,
                &model.base_posture(to),
                &delta.rotations,
                delta.translation,
            );
            if !copy {
                keys.remove(index);
            }
            keys.retain(|key| key.frame != to);
            let at = keys.partition_point(|key| key.frame < to);
            let posture = PostureValues::from_posture(skeleton, &moved);
            keys.insert(at, MotionKey { frame: to, posture });
        });
    }

    fn set_frame_count(&mut self, count: usize) {
        if self.character.timeline.has_clip() || count == 0 {
            return;
        }
        let mut motion = self.motion_section();
        if motion.frame_count == count {
            return;
        }
        motion.frame_count = count;
        self.record(EditKind::Command);
        self.character.session.set_motion(Some(motion));
        if self.character.timeline.frame >= count {
            self.seek(count - 1);
        }
    }

    fn set_interval(&mut self, task: usize, interval: Option<TaskInterval>) {
        if interval.is_some_and(|interval| interval.validate().is_err()) {
            self.warn("An interval needs finite times, its end after its start and eases >= 0.");
            return;
        }
        let mut tasks = self.character.session.tasks().to_vec();
        let Some(spec) = tasks.get_mut(task) else {
            return;
        };
        spec.interval = interval;
        self.commit_tasks(EditKind::TaskField(task, "interval"), tasks);
    }

    fn drag_interval(&mut self, task: usize, edge: IntervalEdge, secs: f64) {
        let Some(mut interval) = self
            .character
            .session
            .tasks()
            .get(task)
            .and_then(|spec| spec.interval)
        else {
            return;
        };
        if !secs.is_finite() {
            return;
        }
        match edge {
            IntervalEdge::Start => interval.start = secs.min(interval.end),
            IntervalEdge::End => interval.end = secs.max(interval.start),
        }
        self.set_interval(task, Some(interval));
    }

    /// The trajectory joint's world positions over every frame, when the keys, the clip,
    /// the body or the joint changed: [`TRAJECTORY_FRAMES_PER_STEP`] frames a step (a
    /// 10,000-frame clip's would hold up one frame of the page for about 100 ms).
    fn refresh_trajectory(&mut self) {
        let skeleton = self.character.session.skeleton();
        let joint = match &self.character.timeline.trajectory_joint {
            Some(name) => resolve_joint(skeleton, name),
            None => self.selected_joint,
        };
        let Some(joint) = joint.filter(|_| self.has_timeline()) else {
            self.character.timeline.trajectory.clear();
            self.character.timeline.trajectory_for = None;
            return;
        };
        let wanted = (
            joint,
            self.character.timeline.base_revision,
            self.session_generation,
            self.character.session.motion_revision(),
        );
        if self.character.timeline.trajectory_for != Some(wanted) {
            self.character.timeline.trajectory.clear();
            self.character.timeline.trajectory_for = Some(wanted);
        }
        let from = self.character.timeline.trajectory.len();
        let to = self
            .frame_count()
            .min(from.saturating_add(TRAJECTORY_FRAMES_PER_STEP));
        if from >= to {
            return;
        }
        let deltas = self.key_layer();
        let more: Vec<DVec3> = (from..to)
            .map(|frame| {
                let posture = self.layered_posture(&deltas, frame);
                Frames::new(skeleton, &posture)
                    .joint_position
                    .get(joint)
                    .copied()
                    .unwrap_or_default()
            })
            .collect();
        self.character.timeline.trajectory.extend(more);
    }

    /// Whether the trajectory has frames still to compute (the next steps add them).
    pub(super) fn trajectory_pending(&self) -> bool {
        self.character.timeline.trajectory_for.is_some()
            && self.character.timeline.trajectory.len() < self.frame_count()
    }

    /// The page shared a posture link of the document (`characters` long): says so, what of
    /// the timeline it carries (the keys and intervals fit in short links; `keys_left_out`:
    /// the length they would have made), and that a clip is only named in it.
    pub(super) fn link_shared(&mut self, characters: usize, keys_left_out: Option<usize>) {
        let mut text = format!(
            "Link copied to the clipboard ({characters} characters): opening it shows exactly this posture and these tasks"
        );
        let intervals = self
            .character
            .session
            .tasks()
            .iter()
            .any(|task| task.interval.is_some());
        let keys = self.key_frames().len();
        match keys_left_out {
            Some(would_be) => text.push_str(&format!(
                ". The {keys} keys are not in it: with them the link would be {would_be} characters, longer than a link should be (export the document as JSON to keep them)."
            )),
            None if keys > 0 || intervals => {
                text.push_str(", with the timeline's keys and the tasks' active intervals.");
            }
            None => text.push('.'),
        }
        if let Some(clip) = self.character.timeline.document_clip() {
            text.push_str(&format!(
                " The clip file {} is not in the link, only named by its content: whoever opens the link is asked to open that file (a saved document carries it).",
                clip.name
            ));
        }
        self.inform(text);
    }
}

/// The contacts of a retargeted clip in words: how many of each part are held, then what the
/// retargeting said of missing ones (a moving clip with a foot that got no contact, and the
/// thresholds to change) and of reference frames left out.
fn contact_words(retargeted: &Retargeted) -> String {
    use stance_motion::ContactPart;
    let count = |slides: bool| -> Vec<String> {
        ContactPart::ALL
            .iter()
            .filter_map(|part| {
                let n = retargeted
                    .contacts
                    .iter()
                    .filter(|c| c.part == *part && c.slides == slides)
                    .count();
                (n > 0).then(|| format!("{n} {}", part.label()))
            })
            .collect()
    };
    let (still, sliding) = (count(false), count(true));
    let mut text = if still.is_empty() {
        "no contact held".to_owned()
    } else {
        format!("contacts held: {}", still.join(", "))
    };
    if !sliding.is_empty() {
        text.push_str(&format!(
            "; kept on the floor while sliding: {}",
            sliding.join(", ")
        ));
    }
    for note in retargeted
        .notes
        .iter()
        .filter(|n| n.starts_with("the clip moves") || n.starts_with("the first "))
    {
        text.push_str("; ");
        text.push_str(note);
    }
    text
}
