//! *File > Open keypoints…*: an OpenPose keypoints file lifted into postures
//! (`stance_lift`), a character per person, through the file's camera (or one fitted to the
//! keypoints), which each character's document keeps as its saved view; and the one-click
//! depth flip of a lifted character's limb. Both take seconds, so they run as the host's jobs
//! (the page's loading worker, [`crate::HostHooks::run_job`]) the way clips are opened, with
//! a busy notice and *Cancel*; where the host cannot, here at once.
//!
//! The keypoints stay with each lifted character as its document's image-plane tasks (a
//! `line` task per keypoint: the camera ray through its pixel) and its saved view: a flip
//! flips the posture and solves those tasks again, so the document format needs nothing new
//! and a saved or shared lifted document can still be flipped.

use stance_document::{Scene, TaskKindSpec};

use super::EditorModel;
use crate::history::EditKind;
use crate::jobs::{HostJob, JobOutput, JobRequest, LiftJob};

/// Lift requests are numbered apart from the clip requests (each character's from its id
/// shifted by 32 bits), so that a reply's id names one request only. Below 2^53: the page
/// hands ids to its workers and back as JavaScript numbers, exact only up to there (at 2^63
/// the second lift's id came back as the first's, and the lift never ended).
const LIFT_REQUESTS: u64 = 1 << 52;

/// The limbs offered to flip: the words, and the joint that ends the flipped segment (the
/// segment and what hangs below it turn about its parent joint, [`stance_lift::flip_depth`]).
/// Whole arms and legs, about the shoulder and hip: a forearm or shin alone turns about a
/// hinge (the elbow, the knee), which cannot carry it across in depth.
pub const FLIPPABLE_LIMBS: [(&str, &str); 4] = [
    ("left arm", "l_elbow"),
    ("right arm", "r_elbow"),
    ("left leg", "l_knee"),
    ("right leg", "r_knee"),
];

/// Opening keypoints and flipping a lifted limb.
#[derive(Debug, Clone, PartialEq)]
pub enum KeypointsCommand {
    /// Ask the page for a keypoints file to open.
    Pick,
    /// Lift an OpenPose keypoints file: the scene is replaced by its people (one undoable
    /// step) once the lift is done; a file that cannot be lifted leaves everything as it was.
    Open {
        /// The file's name.
        name: String,
        /// The file's contents (OpenPose JSON).
        bytes: Vec<u8>,
    },
    /// Flip the depth of the selected lifted character's limb ending at `joint` (see
    /// [`FLIPPABLE_LIMBS`]), solving its keypoints again from there (one undoable step).
    Flip {
        /// The joint that ends the flipped segment (`r_elbow`: the right arm).
        joint: String,
    },
    /// Drop the lift under way: nothing changes.
    Cancel,
    /// The host's result for the lift request `id`.
    Lifted {
        /// The request.
        id: u64,
        /// The lifted scene, or why not.
        result: Result<Box<Scene>, String>,
    },
}

/// A lift the host is running.
#[derive(Debug, Clone, PartialEq)]
pub struct Lifting {
    /// The host's request.
    pub id: u64,
    /// What it is for.
    pub purpose: LiftPurpose,
}

/// What a lift is for.
#[derive(Debug, Clone, PartialEq)]
pub enum LiftPurpose {
    /// A keypoints file opened (its name).
    Open(String),
    /// A limb of the character `character` flipped (its words).
    Flip {
        /// The character's id.
        character: u64,
        /// The limb, in words.
        limb: String,
    },
}

impl Lifting {
    /// What it does, in words ("Lifting people.json…").
    pub fn words(&self) -> String {
        match &self.purpose {
            LiftPurpose::Open(name) => format!("Lifting the keypoints of {name}…"),
            LiftPurpose::Flip { limb, .. } => format!("Flipping the {limb} in depth…"),
        }
    }
}

impl EditorModel {
    pub(super) fn apply_keypoints(&mut self, command: KeypointsCommand) -> super::Change {
        match command {
            KeypointsCommand::Pick => {
                self.pick(super::PickPurpose::Keypoints, "Open keypoints");
            }
            KeypointsCommand::Open { name, bytes } => self.open_keypoints(&name, bytes),
            KeypointsCommand::Flip { joint } => self.flip_limb(&joint),
            KeypointsCommand::Cancel => self.cancel_lift(),
            KeypointsCommand::Lifted { id, result } => {
                return self.lift_done(id, result.map(|scene| *scene));
            }
        }
        super::Change::View
    }

    /// The lift under way, if any.
    pub fn lifting(&self) -> Option<&Lifting> {
        self.lifting.as_ref()
    }

    /// Whether the selected character was lifted from keypoints (its document has
    /// image-plane tasks and a saved view): the limbs it can flip.
    pub fn flippable_limbs(&self) -> Vec<(&'static str, &'static str)> {
        let session = &self.character.session;
        let lifted = session.camera().is_some()
            && session
                .tasks()
                .iter()
                .any(|t| matches!(t.kind, TaskKindSpec::Line { .. }));
        if !lifted || self.character.avatar.is_some() {
            return Vec::new();
        }
        let skeleton = session.skeleton();
        FLIPPABLE_LIMBS
            .into_iter()
            .filter(|(_, joint)| skeleton.joint_index(joint).is_some())
            .collect()
    }

    fn open_keypoints(&mut self, name: &str, bytes: Vec<u8>) {
        let Ok(keypoints) = String::from_utf8(bytes) else {
            self.warn(format!(
                "{name} is not OpenPose keypoints: not a text (JSON) file. Nothing was changed."
            ));
            return;
        };
        let loa = self.character.session.level_of_articulation().number();
        let job = LiftJob::Open {
            name: name.to_owned(),
            keypoints,
            loa,
        };
        self.start_lift(job, LiftPurpose::Open(name.to_owned()));
    }

    fn flip_limb(&mut self, joint: &str) {
        let Some((limb, _)) = self
            .flippable_limbs()
            .into_iter()
            .find(|(_, j)| *j == joint)
        else {
            self.warn(format!(
                "No depth flip of {joint} here: flips are for characters lifted from keypoints, on the mannequin (File > Open keypoints)."
            ));
            return;
        };
        let job = LiftJob::Flip {
            document: Box::new(self.character.session.document()),
            loa: self.character.session.level_of_articulation().number(),
            joint: joint.to_owned(),
        };
        let purpose = LiftPurpose::Flip {
            character: self.character.id,
            limb: limb.to_owned(),
        };
        self.start_lift(job, purpose);
    }

    /// Hands the lift to the host (a lift under way is dropped), or runs it here when the
    /// host cannot.
    fn start_lift(&mut self, job: LiftJob, purpose: LiftPurpose) {
        self.cancel_lift_quietly();
        let id = LIFT_REQUESTS | self.next_lift;
        self.next_lift += 1;
        let request = JobRequest {
            id,
            job: HostJob::Lift(Box::new(job)),
        };
        self.lifting = Some(Lifting { id, purpose });
        match self.hooks.run_job(request) {
            Ok(()) => {
                if let Some(lifting) = &self.lifting {
                    self.inform(lifting.words());
                }
            }
            Err(request) => {
                let result = request
                    .job
                    .run(&mut |_| {})
                    .and_then(|output| match output {
                        JobOutput::Lift(scene) => Ok(*scene),
                        JobOutput::Clip(_) => Err("a lift job opened a clip".to_owned()),
                    });
                self.lift_done(id, result);
            }
        }
    }

    fn cancel_lift_quietly(&mut self) -> Option<Lifting> {
        let lifting = self.lifting.take()?;
        self.hooks.cancel_job(lifting.id);
        Some(lifting)
    }

    fn cancel_lift(&mut self) {
        if let Some(lifting) = self.cancel_lift_quietly() {
            let what = match lifting.purpose {
                LiftPurpose::Open(name) => format!("Lifting {name}"),
                LiftPurpose::Flip { limb, .. } => format!("The flip of the {limb}"),
            };
            self.inform(format!("{what} was cancelled: nothing was changed."));
        }
    }

    /// Whether the job `id` is the lift under way (the host's failures are routed by it).
    pub(super) fn is_lift(&self, id: u64) -> bool {
        self.lifting.as_ref().is_some_and(|l| l.id == id)
    }

    /// The lift `id` is done: the scene replaced by its people, or the flipped character's
    /// posture set (each one undoable step); a failure says why and changes nothing. A reply
    /// to a request dropped since is ignored.
    pub(super) fn lift_done(&mut self, id: u64, result: Result<Scene, String>) -> super::Change {
        if !self.is_lift(id) {
            return super::Change::Nothing;
        }
        let Some(lifting) = self.lifting.take() else {
            return super::Change::Nothing;
        };
        match (lifting.purpose, result) {
            (LiftPurpose::Open(name), Err(error)) => {
                self.warn(format!(
                    "{name} could not be lifted: {error}. Nothing was changed."
                ));
                super::Change::View
            }
            (LiftPurpose::Open(name), Ok(scene)) => self.put_lifted_scene(&name, &scene),
            (LiftPurpose::Flip { limb, .. }, Err(error)) => {
                self.warn(format!(
                    "The {limb} could not be flipped: {error}. Nothing was changed."
                ));
                super::Change::View
            }
            (LiftPurpose::Flip { character, limb }, Ok(scene)) => {
                self.put_flipped(character, &limb, &scene)
            }
        }
    }

    fn put_lifted_scene(&mut self, name: &str, scene: &Scene) -> super::Change {
        match self.open_scene(scene) {
            Ok(words) => {
                let people = scene.characters.len();
                self.selected_joint = None;
                self.trace.clear();
                self.inform(format!(
                    "Lifted {name}: {people} {}, seen through the keypoints' camera (the saved view). Where a limb's depth is wrong, flip it (Scene panel).{words}",
                    if people == 1 { "person" } else { "people" }
                ));
                super::Change::Document
            }
            Err(error) => {
                self.warn(format!(
                    "{name} was lifted but could not be opened: {error}. Nothing was changed."
                ));
                super::Change::View
            }
        }
    }

    fn put_flipped(&mut self, character: u64, limb: &str, scene: &Scene) -> super::Change {
        if self.character.id != character && !self.switch_to_character(character) {
            self.warn(format!(
                "The {limb} was flipped, but its character is gone: nothing was changed."
            ));
            return super::Change::View;
        }
        let posture = scene.characters.first().map(|c| {
            c.document
                .posture
                .to_posture_at(self.character.session.skeleton(), "posture")
        });
        match posture {
            Some(Ok(posture)) => {
                self.record(EditKind::Command);
                self.character.session.set_posture(posture);
                self.refresh_bones();
                self.inform(format!(
                    "Flipped the {limb} in depth: the keypoints are solved again from there (undo brings it back)."
                ));
                super::Change::Posture
            }
            Some(Err(error)) => {
                self.warn(format!("The {limb} could not be flipped: {error}."));
                super::Change::View
            }
            None => {
                self.warn(format!(
                    "The {limb} could not be flipped: no posture came back."
                ));
                super::Change::View
            }
        }
    }
}
