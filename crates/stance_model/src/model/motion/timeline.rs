//! The timeline's state read by the views (clip, playhead, contacts, trajectory): its
//! accessors, apart from the commands that change it (`motion.rs`).

use glam::DVec3;
use stance_document::ClipReference;
use stance_ik::Posture;
use stance_motion::{Clip, Contact, RetargetOptions};

use super::{Timeline, contact_words};

impl Default for Timeline {
    fn default() -> Self {
        Self {
            clip: None,
            retargeted: None,
            playing: false,
            looping: true,
            speed: 1.0,
            position: 0.0,
            frame: 0,
            last_now: 0.0,
            shown: None,
            pending_key: false,
            trajectory_joint: None,
            trajectory: Vec::new(),
            trajectory_for: None,
            base_revision: 0,
            options: RetargetOptions::default(),
            recording: None,
            source: None,
            wanted: None,
            opening: None,
            next_request: 0,
            file: None,
        }
    }
}

impl Timeline {
    /// The clip's name, when one is open.
    pub fn clip_name(&self) -> Option<&str> {
        self.clip.as_ref().map(|clip| clip.name.as_str())
    }

    /// The clip the document keeps: the open clip's file (embedded), else the clip a document
    /// or link named whose file is not loaded yet (a reference).
    pub fn document_clip(&self) -> Option<&ClipReference> {
        self.source.as_ref().or(self.wanted.as_ref())
    }

    /// The clip a document or link named whose file is not loaded yet.
    pub fn wanted_clip(&self) -> Option<&ClipReference> {
        self.wanted.as_ref()
    }

    /// The clip file being opened off the editor's thread, if any: its name and how far it
    /// has got (0 to 1).
    pub fn opening(&self) -> Option<(&str, f64)> {
        self.opening
            .as_ref()
            .map(|opening| (opening.name.as_str(), opening.progress))
    }

    /// How clips are put on the body (rest match, contact thresholds).
    pub fn retarget_options(&self) -> &RetargetOptions {
        &self.options
    }

    /// Whether the body is being recorded.
    pub fn is_recording(&self) -> bool {
        self.recording.is_some()
    }

    /// The open clip, as read (its mapping as corrected).
    pub fn clip(&self) -> Option<&Clip> {
        self.clip.as_deref()
    }

    /// Whether a clip is open.
    pub fn has_clip(&self) -> bool {
        self.retargeted.is_some()
    }

    /// Whether the playhead moves.
    pub fn is_playing(&self) -> bool {
        self.playing
    }

    /// Whether playback loops at the end.
    pub fn is_looping(&self) -> bool {
        self.looping
    }

    /// Playback speed (1 = real time).
    pub fn speed(&self) -> f64 {
        self.speed
    }

    /// The playhead's frame.
    pub fn frame(&self) -> usize {
        self.frame
    }

    /// The playhead's time (s).
    pub fn time_secs(&self) -> f64 {
        self.position
    }

    /// The open clip's contacts in words (see `contact_words`).
    pub(in crate::model) fn contact_words(&self) -> Option<String> {
        self.retargeted.as_ref().map(contact_words)
    }

    /// The clip's foot contacts on this body (frames, inclusive).
    pub fn contacts(&self) -> &[Contact] {
        self.retargeted
            .as_ref()
            .map_or(&[], |retargeted| retargeted.contacts.as_slice())
    }

    /// World positions of the trajectory joint at every frame (empty without a timeline or
    /// a joint).
    pub fn trajectory(&self) -> &[DVec3] {
        &self.trajectory
    }

    /// The retargeted clip's postures.
    pub(super) fn base_postures(&self) -> Option<&[Posture]> {
        self.retargeted
            .as_ref()
            .map(|retargeted| retargeted.postures.as_slice())
    }
}
