//! Every command in one place: [`EditorModel::apply`] hands each feature's command to that
//! feature's `apply` in one exhaustive match (a new command does not compile until it is
//! carried out), and each says what it changed ([`Change`]): a posture edit becomes a key of a
//! paused timeline.

use stance_document::TaskSpec;

use super::command::{
    AvatarCommand, Change, Command, FileCommand, Gesture, GestureCommand, HistoryCommand,
    LibraryCommand, NoticeCommand, PostureCommand, TaskCommand, ViewCommand, goals_moved,
};
use super::{EditorModel, PickPurpose, make_task, table1_example};
use crate::history::EditKind;
use crate::sensors::{SensorCommand, SensorOutcome};

/// The commands the views sent during a frame, in the order sent: the views read the model
/// and never change it; the app carries the commands out ([`EditorModel::apply_outbox`])
/// between the views it shows.
#[derive(Debug, Default)]
pub struct Outbox {
    commands: Vec<Command>,
}

impl Outbox {
    /// Sends `command` to the model (carried out when the app empties the outbox).
    pub fn send(&mut self, command: Command) {
        self.commands.push(command);
    }

    /// Whether no command waits.
    pub fn is_empty(&self) -> bool {
        self.commands.is_empty()
    }
}

/// A posture link of the document, as the host shares it ([`EditorModel::share_link`]).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SharedLink {
    /// The address to copy (the page's URL with the fragment, or the fragment alone).
    pub url: String,
    /// The fragment's length, in characters.
    pub characters: usize,
    /// The length the timeline's keys would have made it, when they were left out.
    pub keys_left_out: Option<usize>,
}

impl EditorModel {
    /// Carries out the commands waiting in `outbox`, in order; says the most any of them
    /// changed.
    pub fn apply_outbox(&mut self, outbox: &mut Outbox) -> Change {
        let commands = std::mem::take(&mut outbox.commands);
        commands
            .into_iter()
            .map(|command| self.apply(command))
            .max()
            .unwrap_or_default()
    }

    /// The document's posture link, as the host shares it; send
    /// [`FileCommand::LinkShared`] once it is copied.
    pub fn share_link(&self) -> SharedLink {
        let scene = self.scene();
        let shared = if scene.is_plain_document() {
            stance_document::link::encode_for_sharing(&self.document())
        } else {
            stance_document::link::encode_scene_for_sharing(&scene)
        };
        SharedLink {
            url: self.hooks.share_link(&shared.fragment),
            characters: shared.fragment.len(),
            keys_left_out: shared.keys_left_out,
        }
    }

    /// Carries out one command of the UI (undo and redo included) and says what it changed;
    /// an edit of the posture, paused on a timeline, becomes a key.
    pub fn apply(&mut self, command: Command) -> Change {
        let change = match command {
            Command::View(command) => self.apply_view(command),
            Command::Gesture(command) => self.apply_gesture(command),
            Command::Posture(command) => self.apply_posture(command),
            Command::Task(command) => self.apply_task(command),
            Command::History(command) => self.apply_history(command),
            Command::Hands(command) => self.apply_hands(command),
            Command::Avatar(command) => self.apply_avatar(command),
            Command::File(command) => self.apply_file(command),
            Command::Library(command) => self.apply_library(command),
            Command::Sensors(command) => self.apply_sensors(command),
            Command::Motion(command) => self.apply_motion(command),
            Command::Comfort(command) => self.comfort.apply(command),
            Command::Notice(command) => self.apply_notice(command),
            Command::Scene(command) => self.apply_scene(command),
            Command::Keypoints(command) => self.apply_keypoints(command),
        };
        if change == Change::Posture {
            self.motion_posture_edited();
        }
        change
    }

    /// Selection and hover.
    fn apply_view(&mut self, command: ViewCommand) -> Change {
        match command {
            ViewCommand::Select(joint) => self.selected_joint = joint,
            ViewCommand::Hover(joint) => self.hovered_joint = joint,
            ViewCommand::ShowCapsules(shown) => self.show_capsules = shown,
        }
        Change::View
    }

    /// The gesture in progress: each move sets the posture or the tasks directly (the undo
    /// step was recorded when it began).
    fn apply_gesture(&mut self, command: GestureCommand) -> Change {
        match command {
            GestureCommand::BeginPull { joint, point_world } => self.begin_pull(joint, point_world),
            GestureCommand::BeginHandle(gesture) => self.begin_handle(gesture),
            GestureCommand::MoveGrab { target_world } => {
                if self.is_pulling() {
                    self.character.session.move_grab(target_world);
                }
            }
            GestureCommand::MoveGoal {
                goal_world,
                floor_world,
            } => {
                if let Some(Gesture::Goal { tasks: moved, .. }) = &self.gesture {
                    let tasks = goals_moved(
                        self.character.session.tasks(),
                        moved,
                        goal_world,
                        floor_world,
                    );
                    self.character.session.set_tasks(tasks);
                }
            }
            GestureCommand::TurnRing { screen_angle } => {
                if let Some((dof, value)) = self
                    .gesture
                    .as_mut()
                    .and_then(|gesture| gesture.turn_ring(screen_angle))
                {
                    self.character.session.set_dof(dof, value);
                }
            }
            GestureCommand::TurnSwivel { point_world } => {
                if let Some((limb, angle)) = self
                    .gesture
                    .as_ref()
                    .and_then(|gesture| gesture.swivel_at(point_world))
                {
                    self.character.session.set_limb_swivel(limb, angle);
                }
            }
            GestureCommand::EndGesture => self.end_gesture(),
            GestureCommand::CancelGesture => self.cancel_gesture(),
        }
        Change::Document
    }

    /// The edits of the posture, each one undoable.
    fn apply_posture(&mut self, command: PostureCommand) -> Change {
        match command {
            PostureCommand::Pin(joint) => self.pin(joint),
            PostureCommand::PinSelected => match self.selected_joint {
                Some(joint) => self.pin(joint),
                None => {
                    self.inform("Select a body part first (click it), then pin it.");
                    return Change::View;
                }
            },
            PostureCommand::SetDof { dof, value } => {
                self.record(EditKind::Joint(dof));
                self.character.session.set_dof(dof, value);
                return Change::Posture;
            }
            PostureCommand::SetStiffness { dof, value } => self.set_stiffness(dof, value),
            PostureCommand::SetSwivel { limb, swivel_angle } => {
                self.record(EditKind::Swivel(limb as usize));
                self.character.session.set_limb_swivel(limb, swivel_angle);
                return Change::Posture;
            }
            PostureCommand::ResetToRest => {
                self.record(EditKind::Command);
                self.character.session.reset_to_rest();
                self.trace.clear();
                return Change::Posture;
            }
            PostureCommand::Mirror => {
                self.record(EditKind::Command);
                self.character.session.mirror();
                return Change::Posture;
            }
            PostureCommand::SaveCamera(camera) => {
                self.record(EditKind::Command);
                self.character.session.set_camera(camera);
                self.inform(match camera {
                    Some(_) => "The view is saved with the document: opening it shows this view.",
                    None => "The document no longer has a view of its own.",
                });
            }
        }
        Change::Document
    }

    /// The edits of the task list, each one undoable.
    fn apply_task(&mut self, command: TaskCommand) -> Change {
        let mut tasks = self.character.session.tasks().to_vec();
        let kind = match command {
            TaskCommand::Set { kind, tasks: new } => {
                tasks = new;
                kind
            }
            TaskCommand::AddOnProp { joint, prop } => {
                let Some(task) = self.task_made(self.task_on_prop(joint, prop)) else {
                    return Change::View;
                };
                tasks.push(task);
                EditKind::Command
            }
            TaskCommand::Add(what) => {
                let Some(task) = self.task_made(make_task(&self.character.session, what)) else {
                    return Change::View;
                };
                tasks.push(task);
                EditKind::Command
            }
            TaskCommand::LoadTable1Example => {
                self.place_table1_props();
                tasks = table1_example(&self.character.session);
                self.inform("Table 1 of the paper: level 1 holds the left foot, the gaze and the right hand on the sphere; balance is level 2; the left hand on the bar level 3.");
                EditKind::Command
            }
            TaskCommand::SetCollision(on) => {
                crate::posing::collision_switched(&mut tasks, on);
                EditKind::Command
            }
            TaskCommand::Remove(index) => {
                if index < tasks.len() {
                    tasks.remove(index);
                }
                EditKind::Command
            }
            TaskCommand::MoveToLevel { task, level } => {
                if let Some(task) = tasks.get_mut(task) {
                    task.level = level;
                }
                EditKind::Command
            }
            TaskCommand::SwapLevels(a, b) => {
                swap_levels(&mut tasks, a, b);
                EditKind::Command
            }
            TaskCommand::MoveLevel { from, onto } => {
                move_level(&mut tasks, from, onto);
                EditKind::Command
            }
        };
        self.commit_tasks(kind, tasks)
    }

    /// A new task, or, where it could not be made, `None` and a warning saying why.
    fn task_made(&mut self, made: Result<TaskSpec, String>) -> Option<TaskSpec> {
        made.map_err(|error| self.warn(format!("The task could not be added: {error}.")))
            .ok()
    }

    /// Replaces the task list as one edit of `kind`, when it changed.
    pub(super) fn commit_tasks(&mut self, kind: EditKind, tasks: Vec<TaskSpec>) -> Change {
        if tasks.as_slice() == self.character.session.tasks() {
            return Change::Nothing;
        }
        self.record(kind);
        self.character.session.set_tasks(tasks);
        Change::Document
    }

    /// Undo and redo.
    fn apply_history(&mut self, command: HistoryCommand) -> Change {
        match command {
            HistoryCommand::Undo => self.undo(),
            HistoryCommand::Redo => self.redo(),
        }
        Change::Document
    }

    /// The body: avatar, mannequin, level of articulation, mapping.
    fn apply_avatar(&mut self, command: AvatarCommand) -> Change {
        match command {
            AvatarCommand::SetLevelOfArticulation(loa) => self.set_level_of_articulation(loa),
            AvatarCommand::LoadAvatar { name, bytes } => self.load_avatar(name, bytes, Vec::new()),
            AvatarCommand::FetchAvatar(url) => self.fetch_avatar(&url),
            AvatarCommand::UseMannequin => self.use_mannequin(),
            AvatarCommand::ApplyMapping {
                mapping,
                corrections,
            } => self.apply_mapping(*mapping, corrections),
            AvatarCommand::RevertMappingCorrection => self.revert_mapping_correction(),
            AvatarCommand::DecodedImages { file, images } => {
                self.decoded_images = Some((file, images));
                return Change::Nothing;
            }
            AvatarCommand::AvatarImported { name, result } => self.avatar_imported(&name, result),
            AvatarCommand::ExportPosedAvatar => {
                self.export_posed_avatar();
                return Change::View;
            }
            AvatarCommand::MeshTaken => {
                if let Some(avatar) = self.character.avatar.as_mut() {
                    avatar.take_mesh();
                }
                return Change::Nothing;
            }
        }
        Change::Document
    }

    /// Files and links: opening them, asking the host for one, offering downloads.
    fn apply_file(&mut self, command: FileCommand) -> Change {
        match command {
            FileCommand::OpenLink(text) => {
                self.open_link(&text);
                return Change::Document;
            }
            FileCommand::OpenFile { name, bytes } => {
                self.open_file(&name, bytes);
                return Change::Document;
            }
            FileCommand::OpenFiles(files) => {
                self.open_files(files);
                return Change::Document;
            }
            FileCommand::PickFile => {
                let result = self.hooks.pick_file();
                self.host_result(result, "Could not open a file");
            }
            FileCommand::PickRecording => self.pick(PickPurpose::Recording, "Sensors"),
            FileCommand::PickClip => self.pick(PickPurpose::Clip, "Motion"),
            FileCommand::PickProp => self.pick(PickPurpose::Prop, "Import prop"),
            FileCommand::ExportDocument => self.export_document(),
            FileCommand::ExportAnimation(format) => self.export_animation(format),
            FileCommand::SaveImage { png, width, height } => self.save_image(&png, width, height),
            FileCommand::SaveOpenPose {
                png,
                json,
                width,
                height,
            } => self.save_openpose(&png, &json, width, height),
            FileCommand::SaveControlMap {
                map,
                png,
                width,
                height,
            } => self.save_control_map(map, &png, width, height),
            FileCommand::JobFailed { id, reason } => {
                // The reply names its request: a lift's, else a clip's.
                if self.is_lift(id) {
                    return self.lift_done(id, Err(reason));
                }
                self.clip_opened(id, Err(reason));
            }
            FileCommand::HostFailed(reason) => {
                self.pending_pick = None;
                self.warn(reason);
            }
            FileCommand::LinkShared {
                characters,
                keys_left_out,
            } => self.link_shared(characters, keys_left_out),
        }
        Change::View
    }

    /// Asks the host for a file to open for `purpose`; `what` names the feature when it
    /// cannot.
    pub(super) fn pick(&mut self, purpose: PickPurpose, what: &str) {
        match self.hooks.pick_file() {
            Ok(()) => self.pending_pick = Some(purpose),
            Err(error) => self.warn(format!("{what}: {error}")),
        }
    }

    /// The pose library.
    fn apply_library(&mut self, command: LibraryCommand) -> Change {
        match command {
            LibraryCommand::Save(name) => self.save_to_library(&name),
            LibraryCommand::Load(index) => {
                self.load_from_library(index);
                return Change::Document;
            }
            LibraryCommand::Delete(index) => self.delete_from_library(index),
            LibraryCommand::Export => self.export_library(),
        }
        Change::View
    }

    /// The sensors: what they say becomes the notice.
    fn apply_sensors(&mut self, command: SensorCommand) -> Change {
        let outcome = self.sensors.apply(
            command,
            &mut self.character.session,
            self.hooks.as_ref(),
            self.now_secs,
        );
        match outcome {
            SensorOutcome::Quiet => {}
            SensorOutcome::Inform(text) => self.inform(text),
            SensorOutcome::Warn(text) => self.warn(text),
        }
        Change::View
    }

    /// The message above the viewport.
    fn apply_notice(&mut self, command: NoticeCommand) -> Change {
        match command {
            NoticeCommand::Inform(text) => self.inform(text),
            NoticeCommand::Warn(text) => self.warn(text),
            NoticeCommand::Dismiss => self.notice = None,
        }
        Change::View
    }
}

/// Levels `a` and `b` swap their tasks.
fn swap_levels(tasks: &mut [TaskSpec], a: u32, b: u32) {
    for task in tasks {
        if task.level == a {
            task.level = b;
        } else if task.level == b {
            task.level = a;
        }
    }
}

/// Moves the group of tasks at level `from` to the place of level `onto` (the last place when
/// `None`); the groups in between shift by one. The set of level numbers stays the same, so
/// the default gaps (1, 2, 10...) are kept.
fn move_level(tasks: &mut [TaskSpec], from: u32, onto: Option<u32>) {
    let mut levels: Vec<u32> = tasks.iter().map(|task| task.level).collect();
    levels.sort_unstable();
    levels.dedup();
    let mut order = levels.clone();
    let Some(source) = order.iter().position(|&level| level == from) else {
        return;
    };
    order.remove(source);
    let target = onto
        .and_then(|onto| levels.iter().position(|&level| level == onto))
        .unwrap_or(order.len())
        .min(order.len());
    order.insert(target, from);
    for task in tasks.iter_mut() {
        if let Some(rank) = order.iter().position(|&level| level == task.level)
            && let Some(&number) = levels.get(rank)
        {
            task.level = number;
        }
    }
}
