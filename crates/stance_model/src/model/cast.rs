//! The scene's characters. Each [`Character`] has its own body (avatar or mannequin, level of
//! articulation), posing session (posture, tasks, stiffness, hands), timeline and placement
//! on the floor. The selected one is the one every tool works on: the model holds it apart
//! from the others (so that a tool borrows it beside the history, the notice and the sensors);
//! the others wait as they were left, drawn and picked. Adding, duplicating, removing,
//! renaming, moving and selecting characters are [`SceneCommand`]s, undone like any edit
//! (the history keeps the cast as it was; a removed character is kept while a step names it).

use stance_asset::{SceneContent, SceneNode, export_scene_glb};
use stance_document::{
    BetweenTask, Placement, Prop, PropShape, Scene, SceneCharacter, clean_name,
    default_character_name,
};
use stance_render::MannequinBone;

use super::mapping::MappingCorrections;
use super::motion::Timeline;
use super::{EditorModel, bones, document_of};
use crate::avatar::LoadedAvatar;
use crate::history::{CastEntry, CastSnapshot};
use crate::posing::PosingSession;

/// Where a new character stands: this far (m) along +X from the rightmost one.
pub const CHARACTER_SPACING_M: f64 = 0.8;
/// The most characters a scene holds.
pub use stance_document::scene::MAX_CHARACTERS;

/// One character of the scene.
pub struct Character {
    /// Stable while the editor runs (the history names characters by it).
    pub(super) id: u64,
    pub(super) name: String,
    pub(super) placement: Placement,
    pub(super) session: PosingSession,
    pub(super) avatar: Option<LoadedAvatar>,
    /// The URL the avatar came from (links and autosave name it); `None` for local files.
    pub(super) avatar_url: Option<String>,
    /// The avatar its document names while it waits on the mannequin (opened with a scene,
    /// not the selected character): saved and shared as its avatar, and given to it once the
    /// editor has loaded that avatar.
    pub(super) wanted_avatar_url: Option<String>,
    pub(super) mapping_corrections: MappingCorrections,
    /// The clip, the playhead and the trajectory (the keys are in the document).
    pub(super) timeline: Timeline,
    /// The posed mannequin's bones after the last step (in the character's frame).
    pub(super) bones: Vec<MannequinBone>,
    /// The session revision the bones were built for.
    pub(super) bones_revision: Option<u64>,
}

impl std::fmt::Debug for Character {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Character")
            .field("id", &self.id)
            .field("name", &self.name)
            .field("placement", &self.placement)
            .finish_non_exhaustive()
    }
}

impl Character {
    pub(super) fn new(id: u64, name: String, session: PosingSession) -> Self {
        let mut character = Self {
            id,
            name,
            placement: Placement::default(),
            session,
            avatar: None,
            avatar_url: None,
            wanted_avatar_url: None,
            mapping_corrections: MappingCorrections::default(),
            timeline: Timeline::default(),
            bones: Vec::new(),
            bones_revision: None,
        };
        character.set_id(id);
        character.refresh_bones();
        character
    }

    /// Gives it the id `id`; its clip requests to the host are numbered from `id << 32` (the
    /// host answers by number: each character's run apart).
    fn set_id(&mut self, id: u64) {
        self.id = id;
        self.timeline.next_request = id << 32;
    }

    /// Its id (stable while the editor runs).
    pub fn id(&self) -> u64 {
        self.id
    }

    /// Its name.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// Where it stands in the scene.
    pub fn placement(&self) -> Placement {
        self.placement
    }

    /// Its posing session: body, posture, tasks, solver.
    pub fn session(&self) -> &PosingSession {
        &self.session
    }

    /// Its avatar, if it is not the mannequin.
    pub fn avatar(&self) -> Option<&LoadedAvatar> {
        self.avatar.as_ref()
    }

    /// Its posed bones (in its own frame; [`Placement::scene_from_character`] puts them in
    /// the scene).
    pub fn bones(&self) -> &[MannequinBone] {
        &self.bones
    }

    /// The bones follow the posture: rebuilt when the session's revision moved (or the
    /// session was replaced), not every frame.
    pub(super) fn refresh_bones(&mut self) {
        let revision = Some(self.session.revision());
        if revision != self.bones_revision {
            self.bones = bones::posed_bones(&self.session);
            self.bones_revision = revision;
        }
    }

    /// Its entry in the scene document; `for_autosave`: its clip file kept only when small
    /// (`Timeline::autosaved_clip`), else named.
    fn scene_character(&self, for_autosave: bool) -> SceneCharacter {
        let url = self.avatar_url.as_ref().or(self.wanted_avatar_url.as_ref());
        let mut document = document_of(&self.session, url.map(String::as_str));
        document.clip = if for_autosave {
            self.timeline.autosaved_clip()
        } else {
            self.timeline.document_clip().cloned()
        };
        SceneCharacter {
            name: self.name.clone(),
            placement: self.placement,
            document,
        }
    }

    fn cast_entry(&self) -> CastEntry {
        CastEntry {
            id: self.id,
            name: self.name.clone(),
            placement: self.placement,
        }
    }
}

/// The characters that are not selected, and the removed ones undo may bring back.
#[derive(Debug, Default)]
pub struct Cast {
    /// In the scene's order, the selected character left out.
    others: Vec<Character>,
    /// The selected character's place in the scene's order.
    selected_at: usize,
    /// The id of the next character.
    next_id: u64,
    /// Removed characters that a step of the history names.
    removed: Vec<Character>,
    /// The scene's props, in the outliner's order.
    pub(super) props: Vec<Prop>,
    /// The tasks between characters (by their places in the scene's order): saved, shared
    /// and undone with the cast; a removed character's go with it.
    between: Vec<BetweenTask>,
    /// The solver of frames where characters are joined (made when first needed).
    joined_solver: Option<stance_ik::Solver>,
}

/// A command for the scene's characters.
#[derive(Debug, Clone, PartialEq)]
pub enum SceneCommand {
    /// A new character on the mannequin, at the selected one's level of articulation, at
    /// rest, standing beside the others; it becomes the selected one.
    Add,
    /// A copy of the selected character (body, posture, tasks, timeline keys) beside the
    /// others; it becomes the selected one.
    Duplicate,
    /// Removes the character (not the last one).
    Remove(u64),
    /// Renames the character (trimmed; an empty name is refused).
    Rename(u64, String),
    /// Selects the character: the tools work on it.
    Select(u64),
    /// Moves or turns the character on the floor.
    Place(u64, Placement),
    /// A new prop of this shape in front of the selected character.
    AddProp(PropShape),
    /// A static glTF/GLB file (its name, its bytes) imported as a prop: kept by its name among
    /// the prop files; a new mesh prop on the floor in front of the selected character, sized
    /// from its bounds; or, when props of the scene name that file and wait for it, those
    /// drawn with it (no new prop).
    AddMeshProp {
        /// The file's name (`chair.glb`).
        file: String,
        /// Its contents.
        bytes: Vec<u8>,
    },
    /// Removes the prop at this index.
    RemoveProp(usize),
    /// Sets the prop at this index (its name, size, place, turn), as one edit over frames.
    EditProp(usize, Prop),
    /// A task between the selected character and another (a hand in another's hand): their
    /// parts meet, one level below the hard tasks of both; the two are then posed together.
    AddBetween(super::joined::NewBetween),
    /// Removes the task between characters at this index.
    RemoveBetween(usize),
}

impl EditorModel {
    /// The selected character (the one the tools work on).
    pub fn character(&self) -> &Character {
        &self.character
    }

    /// Every character in the scene's order, with whether it is the selected one.
    pub fn characters(&self) -> impl Iterator<Item = (&Character, bool)> + '_ {
        let (before, after) = self
            .cast
            .others
            .split_at(self.cast.selected_at.min(self.cast.others.len()));
        before
            .iter()
            .map(|c| (c, false))
            .chain(std::iter::once((&self.character, true)))
            .chain(after.iter().map(|c| (c, false)))
    }

    /// The characters that are not selected, in the scene's order.
    pub fn other_characters(&self) -> &[Character] {
        &self.cast.others
    }

    /// How many characters the scene holds.
    pub fn character_count(&self) -> usize {
        self.cast.others.len() + 1
    }

    /// The whole scene as a document: every character's document (its clip embedded), name and
    /// placement, the props and their files.
    pub fn scene(&self) -> Scene {
        self.scene_of(false)
    }

    /// The scene; `for_autosave`: each character's clip file kept only when small, the prop
    /// files up to the autosave's total.
    pub(super) fn scene_of(&self, for_autosave: bool) -> Scene {
        let characters = self
            .characters()
            .map(|(c, _)| {
                let mut character = c.scene_character(for_autosave);
                // A task attached to a prop since removed (undo may bring it back) is saved
                // where it stands, attached to nothing.
                for task in &mut character.document.tasks {
                    if task
                        .on
                        .as_ref()
                        .is_some_and(|on| !self.cast.props.iter().any(|p| &p.name == on))
                    {
                        task.on = None;
                    }
                }
                character
            })
            .collect();
        Scene {
            characters,
            props: self.cast.props.clone(),
            selected: self.cast.selected_at,
            between: self.cast.between.clone(),
            files: self.carried_prop_files(for_autosave),
        }
    }

    pub(super) fn apply_scene(&mut self, command: SceneCommand) -> super::Change {
        match command {
            SceneCommand::Add => self.add_character(false),
            SceneCommand::Duplicate => self.add_character(true),
            SceneCommand::Remove(id) => self.remove_character(id),
            SceneCommand::Rename(id, name) => self.rename_character(id, &name),
            SceneCommand::Select(id) => self.select_character(id),
            SceneCommand::Place(id, placement) => self.place_character(id, placement),
            SceneCommand::AddProp(shape) => self.add_prop(shape),
            SceneCommand::AddMeshProp { file, bytes } => self.add_mesh_prop(&file, bytes),
            SceneCommand::RemoveProp(index) => self.remove_prop(index),
            SceneCommand::EditProp(index, prop) => self.edit_prop(index, prop),
            SceneCommand::AddBetween(new) => self.add_between(new),
            SceneCommand::RemoveBetween(index) => self.remove_between(index),
        }
    }

    /// Whether the scene is one character at the origin, without props: its export is the
    /// posed avatar file alone (a VRM stays a VRM), as before scenes.
    pub fn is_single_character(&self) -> bool {
        self.cast.others.is_empty()
            && self.cast.props.is_empty()
            && self.character.placement.is_identity()
    }

    /// The whole scene as one GLB: every character posed at its placement (its avatar, or the
    /// mannequin's figure), each prop as a mesh, one node each named as in the outliner.
    pub fn scene_glb(&self) -> Result<Vec<u8>, String> {
        let bodies = self
            .characters()
            .map(|(character, _)| {
                let session = &character.session;
                let posed = match &character.avatar {
                    Some(loaded) => {
                        let mut avatar = loaded.avatar.clone();
                        avatar
                            .apply_posture(session.humanoid(), session.posture())
                            .map(|()| avatar)
                    }
                    None => stance_asset::posed_default_avatar(
                        session.skeleton(),
                        session.posture(),
                        session.level_of_articulation(),
                    ),
                };
                posed.map_err(|error| format!("{}: {error}", character.name))
            })
            .collect::<Result<Vec<_>, _>>()?;
        let meshes: Vec<_> = self
            .cast
            .props
            .iter()
            .map(|prop| self.prop_static_meshes(prop))
            .collect();
        let characters = self
            .characters()
            .zip(&bodies)
            .map(|((character, _), avatar)| SceneNode {
                name: character.name.clone(),
                scene_from_node: character.placement.scene_from_character(),
                content: SceneContent::Avatar(avatar),
            });
        let props = self
            .cast
            .props
            .iter()
            .zip(&meshes)
            .map(|(prop, mesh)| SceneNode {
                name: prop.name.clone(),
                scene_from_node: prop.scene_from_prop(),
                content: SceneContent::Mesh(mesh.as_slice()),
            });
        let nodes: Vec<SceneNode<'_>> = characters.chain(props).collect();
        export_scene_glb(&nodes).map_err(|error| error.to_string())
    }

    fn select_character(&mut self, id: u64) -> super::Change {
        if id == self.character.id || !self.switch_to_character(id) {
            return super::Change::Nothing;
        }
        let name = self.character.name.clone();
        self.inform(format!("Selected {name}: the tools work on it."));
        super::Change::View
    }

    fn place_character(&mut self, id: u64, placement: Placement) -> super::Change {
        if placement.validate_at("placement").is_err() {
            return super::Change::Nothing;
        }
        let Some(before) = self.character_mut(id).map(|c| c.placement) else {
            return super::Change::Nothing;
        };
        let change = self.edit_character(id, |character| {
            let changed = character.placement != placement;
            character.placement = placement;
            changed
        });
        self.follow_placement(id, before);
        change
    }

    /// A change of the character `id`'s entry in the cast (its name, its place) that `edit`
    /// makes, saying whether it changed anything: one undo step over a drag or typing.
    fn edit_character(
        &mut self,
        id: u64,
        edit: impl FnOnce(&mut Character) -> bool,
    ) -> super::Change {
        let before = self.cast_snapshot();
        let Some(character) = self.character_mut(id) else {
            return super::Change::Nothing;
        };
        if !edit(character) {
            return super::Change::Nothing;
        }
        self.wake_joined();
        self.history.record_cast(before, true, self.now_secs);
        super::Change::Document
    }

    /// The tasks between characters.
    pub(super) fn cast_between(&self) -> &[BetweenTask] {
        &self.cast.between
    }

    /// The selected character's place in the scene's order.
    pub fn selected_index(&self) -> usize {
        self.cast.selected_at
    }

    /// The other characters (in the scene's order, the selected one left out) and the
    /// selected one, both to change.
    pub(super) fn cast_and_selected_mut(&mut self) -> (&mut [Character], &mut Character) {
        (&mut self.cast.others, &mut self.character)
    }

    /// The solver of joined frames.
    pub(super) fn cast_solver(&mut self) -> &mut stance_ik::Solver {
        self.cast
            .joined_solver
            .get_or_insert_with(super::joined::joined_solver)
    }

    /// An edit of the tasks between characters: one undo step; every joined character's
    /// solver wakes (before and after the edit).
    pub(super) fn edit_between(&mut self, edit: impl FnOnce(&mut Vec<BetweenTask>)) {
        let before = self.cast_snapshot();
        self.wake_joined();
        edit(&mut self.cast.between);
        self.wake_joined();
        self.history.record_cast(before, false, self.now_secs);
    }

    /// Wakes the solver of every character a task between characters joins to another.
    pub(super) fn wake_joined(&mut self) {
        let joined: Vec<usize> = self
            .cast
            .between
            .iter()
            .filter(|t| t.active)
            .flat_map(|t| t.characters())
            .collect();
        for member in self.members_mut(&joined) {
            member.session.wake_for_tasks();
        }
    }

    pub(super) fn character_mut(&mut self, id: u64) -> Option<&mut Character> {
        if self.character.id == id {
            return Some(&mut self.character);
        }
        self.cast.others.iter_mut().find(|c| c.id == id)
    }

    /// The first "Character N" no character is named.
    fn free_name(&self) -> String {
        (1..)
            .map(default_character_name)
            .find(|name| self.characters().all(|(c, _)| c.name != *name))
            .unwrap_or_default()
    }

    /// A name for a copy of `name`: "name 2", "name 3"... the first free one.
    fn copy_name(&self, name: &str) -> String {
        (2..)
            .map(|n| format!("{name} {n}"))
            .find(|candidate| self.characters().all(|(c, _)| c.name != *candidate))
            .unwrap_or_default()
    }

    /// Where a new character stands: beside the rightmost one, on the floor.
    fn free_placement(&self) -> Placement {
        let right = self
            .characters()
            .map(|(c, _)| c.placement.position[0])
            .fold(f64::NEG_INFINITY, f64::max);
        Placement::at([right + CHARACTER_SPACING_M, 0.0, 0.0])
    }

    fn next_character_id(&mut self) -> u64 {
        self.cast.next_id += 1;
        self.cast.next_id
    }

    fn add_character(&mut self, duplicate: bool) -> super::Change {
        if self.character_count() >= MAX_CHARACTERS {
            self.warn(format!(
                "A scene holds at most {MAX_CHARACTERS} characters."
            ));
            return super::Change::Nothing;
        }
        let made = if duplicate {
            self.duplicate_selected()
        } else {
            PosingSession::new(self.character.session.level_of_articulation())
                .map(|session| Character::new(0, self.free_name(), session))
                .map_err(|error| error.to_string())
        };
        let mut character = match made {
            Ok(character) => character,
            Err(error) => {
                self.warn(format!("Could not add a character: {error}"));
                return super::Change::Nothing;
            }
        };
        let before = self.cast_snapshot();
        let id = self.next_character_id();
        character.set_id(id);
        character.placement = self.free_placement();
        let name = character.name.clone();
        self.history.record_cast(before, false, self.now_secs);
        self.cast.others.push(character);
        self.switch_to_character(id);
        self.inform(format!(
            "{} {name}: the tools work on it (Scene panel to select another).",
            if duplicate { "Duplicated as" } else { "Added" }
        ));
        super::Change::Document
    }

    /// A copy of the selected character (its body and document, not its saved view) under a
    /// name of its own; its id is given by the caller.
    fn duplicate_selected(&self) -> Result<Character, String> {
        let source = &self.character;
        let humanoid = source.session.humanoid().clone();
        let mut session = PosingSession::with_humanoid(humanoid).map_err(|e| e.to_string())?;
        let mut document = source.session.document();
        document.camera = None;
        session
            .restore_document(&document)
            .map_err(|e| e.to_string())?;
        let mut copy = Character::new(0, self.copy_name(&source.name), session);
        copy.avatar = source.avatar.as_ref().map(LoadedAvatar::duplicate);
        copy.avatar_url.clone_from(&source.avatar_url);
        Ok(copy)
    }

    fn remove_character(&mut self, id: u64) -> super::Change {
        if self.character_count() == 1 {
            self.warn("The scene's last character cannot be removed.");
            return super::Change::Nothing;
        }
        let before = self.cast_snapshot();
        let index = self.characters().position(|(c, _)| c.id == id);
        if let Some(index) = index {
            let between = std::mem::take(&mut self.cast.between);
            self.cast.between = between
                .iter()
                .filter_map(|task| task.without_character(index))
                .collect();
        }
        if self.character.id == id {
            // Select the next one in the scene's order (else the one before).
            let next = self
                .cast
                .others
                .get(self.cast.selected_at)
                .or_else(|| self.cast.others.last())
                .map(|c| c.id);
            let Some(next) = next else {
                return super::Change::Nothing;
            };
            self.switch_to_character(next);
        }
        let Some(at) = self.cast.others.iter().position(|c| c.id == id) else {
            return super::Change::Nothing;
        };
        let removed = self.cast.others.remove(at);
        if at < self.cast.selected_at {
            self.cast.selected_at -= 1;
        }
        let name = removed.name.clone();
        self.cast.removed.push(removed);
        self.history.record_cast(before, false, self.now_secs);
        self.inform(format!("Removed {name} (undo brings it back)."));
        super::Change::Document
    }

    fn rename_character(&mut self, id: u64, name: &str) -> super::Change {
        let Some(name) = clean_name(name) else {
            self.warn("A character's name cannot be empty.");
            return super::Change::Nothing;
        };
        self.edit_character(id, |character| {
            let changed = character.name != name;
            character.name = name;
            changed
        })
    }

    /// Makes the character `id` the selected one; the gesture, the joint selection, the
    /// trace and the sensors' hold end (they belonged to the other body), and a clip on its
    /// way to the character left is cancelled. Returns whether `id` is in the scene.
    pub(super) fn switch_to_character(&mut self, id: u64) -> bool {
        if self.character.id == id {
            return true;
        }
        let Some(index) = self.cast.others.iter().position(|c| c.id == id) else {
            return false;
        };
        self.character_switched_out();
        let selected_at = self.cast.selected_at;
        // The incoming character's place in the scene's order.
        let incoming_at = if index < selected_at {
            index
        } else {
            index + 1
        };
        let incoming = self.cast.others.remove(index);
        let outgoing = std::mem::replace(&mut self.character, incoming);
        self.cast.others.insert(
            selected_at - usize::from(incoming_at < selected_at),
            outgoing,
        );
        self.cast.selected_at = incoming_at;
        self.character_switched_in();
        true
    }

    /// What belonged to the character left ends: the gesture, the joint selection and hover,
    /// the trace, the sensors' hold, and a clip on its way to it (cancelled).
    fn character_switched_out(&mut self) {
        self.end_gesture();
        self.cancel_opening();
        self.sensors.release();
        self.selected_joint = None;
        self.hovered_joint = None;
        self.trace.clear();
    }

    /// The incoming character's bones are rebuilt, its avatar's GPU model made again if the
    /// renderer took it when it was selected before (the viewport uploads it again), and the
    /// views' per-session state starts again.
    fn character_switched_in(&mut self) {
        if let Some(avatar) = self.character.avatar.take() {
            self.character.avatar = Some(avatar.shown_again());
        }
        self.session_generation += 1;
        self.character.bones_revision = None;
        self.refresh_bones();
    }

    /// The cast as the history keeps it.
    pub(super) fn cast_snapshot(&self) -> CastSnapshot {
        CastSnapshot {
            order: self.characters().map(|(c, _)| c.cast_entry()).collect(),
            selected: self.character.id,
            props: self.cast.props.clone(),
            between: self.cast.between.clone(),
        }
    }

    /// Undo or redo of a change of the cast: the characters, their order, names and
    /// placements, and the selection as `snapshot` has them; characters it leaves out are
    /// kept as removed (a later step may bring them back).
    pub(super) fn restore_cast(&mut self, snapshot: &CastSnapshot) {
        let placements_before: Vec<(u64, Placement)> = self
            .characters()
            .map(|(c, _)| (c.id, c.placement))
            .collect();
        // A selection that comes back from the removed characters joins the others first (the
        // order is made again below).
        if let Some(at) = self
            .cast
            .removed
            .iter()
            .position(|c| c.id == snapshot.selected)
        {
            let back = self.cast.removed.remove(at);
            self.cast.others.push(back);
        }
        self.switch_to_character(snapshot.selected);
        let mut pool: Vec<Character> = self.cast.others.drain(..).collect();
        pool.append(&mut self.cast.removed);
        let mut others = Vec::with_capacity(snapshot.order.len());
        let mut selected_at = 0;
        for entry in &snapshot.order {
            if entry.id == self.character.id {
                selected_at = others.len();
                self.character.name.clone_from(&entry.name);
                self.character.placement = entry.placement;
            } else if let Some(at) = pool.iter().position(|c| c.id == entry.id) {
                let mut character = pool.remove(at);
                character.name.clone_from(&entry.name);
                character.placement = entry.placement;
                others.push(character);
            }
        }
        self.cast.others = others;
        self.cast.selected_at = selected_at;
        self.cast.removed = pool;
        // The attached tasks keep their place in the scene while their characters move back,
        // then follow their props back.
        for (id, before) in placements_before {
            self.follow_placement(id, before);
        }
        let props_before = std::mem::replace(&mut self.cast.props, snapshot.props.clone());
        if props_before.len() == snapshot.props.len() {
            let moves: Vec<(Prop, Prop)> = props_before
                .into_iter()
                .zip(snapshot.props.iter().cloned())
                .collect();
            self.follow_props(&moves);
        }
        self.cast.between.clone_from(&snapshot.between);
        self.wake_joined();
    }

    /// Opens `scene` in place of the scene's characters, as one undoable change of the cast
    /// (undo brings the characters back as they were). Every character is built before
    /// anything changes: one that does not fit leaves the scene as it was and names it.
    /// Characters are posed on the mannequin at the current level of articulation, or on the
    /// selected character's avatar when their document names it; the selected one's avatar
    /// named by URL is fetched (its document waits for it); the prop files it carries are
    /// taken as *Import prop* takes a file. Returns what to tell the user after "Opened NAME"
    /// (avatars left on the mannequin, prop files missing or not meshes).
    pub(super) fn open_scene(&mut self, scene: &Scene) -> Result<String, String> {
        let loa = self.character.session.level_of_articulation();
        let current_url = self.character.avatar_url.clone();
        let mut built = Vec::with_capacity(scene.characters.len());
        let mut on_mannequin = Vec::new();
        for (i, entry) in scene.characters.iter().enumerate() {
            let (character, wanted_url) = self.built_character(entry, loa, current_url.as_ref())?;
            if let Some(url) = &wanted_url
                && i != scene.selected
            {
                on_mannequin.push(format!("{} ({url})", entry.name));
            }
            built.push((character, wanted_url));
        }
        let before = self.cast_snapshot();
        let old: Vec<u64> = self.characters().map(|(c, _)| c.id).collect();
        let mut selected_id = None;
        let mut fetch = None;
        for (i, (mut character, wanted_url)) in built.into_iter().enumerate() {
            character.set_id(self.next_character_id());
            if i == scene.selected {
                selected_id = Some(character.id);
                fetch = wanted_url.map(|url| (url, scene.characters[i].document.clone()));
            }
            self.cast.others.push(character);
        }
        if let Some(id) = selected_id {
            self.switch_to_character(id);
        }
        let (kept, gone): (Vec<Character>, Vec<Character>) = self
            .cast
            .others
            .drain(..)
            .partition(|c| !old.contains(&c.id));
        self.cast.others = kept;
        self.cast.removed.extend(gone);
        self.cast.selected_at = scene.selected.min(self.cast.others.len());
        self.cast.props.clone_from(&scene.props);
        self.cast.between.clone_from(&scene.between);
        self.history.record_cast(before, false, self.now_secs);
        if let Some((url, document)) = fetch {
            self.pending_document = Some(document);
            self.fetch_avatar(&url);
        }
        self.view_requests += u64::from(self.character.session.camera().is_some());
        // The files are not part of the history: undo leaves them held, as after an import.
        let mut words = self.take_prop_files(&scene.files);
        words.push_str(&self.missing_prop_files_words());
        if !on_mannequin.is_empty() {
            words.push_str(&format!(
                " Posed on the mannequin until their avatar is loaded: {}.",
                on_mannequin.join(", ")
            ));
        }
        Ok(words)
    }

    /// A character made from a scene's `entry` at `loa` (its id not given yet): on the
    /// selected character's avatar when its document names that avatar's URL (`current_url`),
    /// else on the mannequin; with the URL of an avatar it names that is not loaded.
    fn built_character(
        &self,
        entry: &SceneCharacter,
        loa: stance_hanim::LevelOfArticulation,
        current_url: Option<&String>,
    ) -> Result<(Character, Option<String>), String> {
        let document = &entry.document;
        let named_url = match &document.avatar {
            stance_document::AvatarReference::Url(url) => Some(url.clone()),
            stance_document::AvatarReference::Default => None,
        };
        let avatar = self
            .character
            .avatar
            .as_ref()
            .filter(|_| named_url.is_some() && named_url.as_ref() == current_url)
            .map(LoadedAvatar::duplicate);
        let session = match &avatar {
            Some(avatar) => avatar
                .skeleton(loa)
                .and_then(|h| PosingSession::with_humanoid(h).map_err(|e| e.to_string())),
            None => PosingSession::new(loa).map_err(|e| e.to_string()),
        };
        let mut session = session.map_err(|e| format!("{}: {e}", entry.name))?;
        // Written before postures meant the same pose on every body, a document made on this
        // avatar has values relative to its own rest: converted as the selected character's is.
        let mut fitted = match &avatar {
            Some(_) => document.in_standard_rest(session.humanoid()),
            None => document.clone(),
        };
        fitted.posture = fitted.posture.fitted(session.skeleton());
        let restored = if fitted.posture.joints.is_empty() {
            session.load_document(&fitted)
        } else {
            session.restore_document(&fitted)
        };
        restored.map_err(|e| format!("{} does not fit its body: {e}", entry.name))?;
        let on_avatar = avatar.is_some();
        let mut character = Character::new(0, entry.name.clone(), session);
        character.placement = entry.placement;
        character.avatar = avatar;
        // The URL goes with the avatar when it is the one loaded, else it is still wanted.
        let (had, wanted) = if on_avatar {
            (named_url, None)
        } else {
            (None, named_url)
        };
        character.avatar_url = had;
        character.wanted_avatar_url.clone_from(&wanted);
        Ok((character, wanted))
    }

    /// Gives the selected character's avatar, just loaded, to every other character waiting
    /// for the same one on the mannequin: each rebuilt on it from its own document (posture,
    /// tasks, placement and timeline kept). Returns what to tell the user (empty: none).
    pub(super) fn give_avatar_to_waiting(&mut self) -> String {
        let Some(url) = self.character.avatar_url.clone() else {
            return String::new();
        };
        let loa = self.character.session.level_of_articulation();
        let mut given = 0;
        for i in 0..self.cast.others.len() {
            if self.cast.others[i].wanted_avatar_url.as_ref() != Some(&url) {
                continue;
            }
            let entry = self.cast.others[i].scene_character(false);
            match self.built_character(&entry, loa, Some(&url)) {
                Ok((mut built, _)) => {
                    let old = &mut self.cast.others[i];
                    built.set_id(old.id);
                    built.timeline = std::mem::take(&mut old.timeline);
                    *old = built;
                    given += 1;
                }
                Err(error) => self.warn(format!(
                    "{} stays on the mannequin: {error}",
                    self.cast.others[i].name
                )),
            }
        }
        if given == 0 {
            return String::new();
        }
        self.wake_joined();
        format!(" Also given to {given} more character(s) of the scene waiting for it.")
    }

    /// Forgets the removed characters no step of the history names.
    pub(super) fn forget_unreferenced_characters(&mut self) {
        let named: Vec<u64> = self.history.characters().collect();
        self.cast.removed.retain(|c| named.contains(&c.id));
    }
}
