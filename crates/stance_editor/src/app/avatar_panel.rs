//! The avatar's side of the editor: the mapping window, where the user checks and corrects
//! which H-Anim joint each joint of the file drives (the skeleton and the posing session are
//! rebuilt from the corrected mapping), and the export of the posed avatar as GLB.

use std::collections::BTreeMap;

use egui::{Color32, RichText};
use glam::{DQuat, DVec3};
use stance_document::TaskSpec;
use stance_hanim::{
    HumanoidSkeleton, LevelOfArticulation, Mapping, MappingError, MatchMethod, all_joints,
    joint_by_name,
};
use stance_ik::{Posture, Skeleton};

use super::StanceApp;
use crate::avatar::LoadedAvatar;
use crate::posing::{PosingSession, describe_task};
use stance_hanim::{mirror_name, readable_name};

/// Matches less sure than this are guesses the user should check (name patterns, geometry).
const LOW_CONFIDENCE: f32 = 0.8;
/// Colour of guessed matches.
const GUESS_COLOR: Color32 = Color32::from_rgb(235, 150, 60);
/// Colour of the joints every humanoid needs and the draft lacks.
const MISSING_COLOR: Color32 = Color32::from_rgb(240, 90, 90);
/// What an unmapped row shows.
const UNMAPPED: &str = "none";

/// One correction: source joint (node index) `source` drives `hanim`, or nothing.
#[derive(Debug, Clone, PartialEq)]
struct Correction {
    source: usize,
    hanim: Option<&'static str>,
}

impl Correction {
    fn apply(&self, mapping: &mut Mapping) -> Result<(), MappingError> {
        match self.hanim {
            Some(hanim) => mapping.set(hanim, self.source),
            None => {
                if let Some(hanim) = mapping.hanim_of(self.source) {
                    mapping.remove(hanim);
                }
                Ok(())
            }
        }
    }
}

/// The corrections applied to one avatar (by name) during the session.
#[derive(Debug)]
struct AvatarCorrections {
    /// The mapping the file got on import.
    automatic: Mapping,
    /// Each applied batch, oldest first.
    applied: Vec<Vec<Correction>>,
}

impl AvatarCorrections {
    /// The automatic mapping with the first `batches` batches applied.
    fn mapping(&self, batches: usize) -> Result<Mapping, MappingError> {
        let mut mapping = self.automatic.clone();
        for correction in self.applied.iter().take(batches).flatten() {
            correction.apply(&mut mapping)?;
        }
        Ok(mapping)
    }
}

/// The mapping window's state and the corrections kept for the session.
#[derive(Debug, Default)]
pub(super) struct MappingEditor {
    pub(super) open: bool,
    /// The mapping being edited; `None` until the window shows an avatar.
    draft: Option<Mapping>,
    /// The corrections made in the draft and not applied yet.
    staged: Vec<Correction>,
    filter: String,
    only_guesses: bool,
    /// Per avatar name.
    by_avatar: BTreeMap<String, AvatarCorrections>,
}

impl MappingEditor {
    /// An avatar file was imported: the draft starts again and, when the user corrected an
    /// avatar of that name earlier in the session (the same file: same automatic mapping),
    /// those corrections are made again and `humanoid` rebuilt. Returns a line for the load
    /// message.
    pub(super) fn reapply(
        &mut self,
        avatar: &mut LoadedAvatar,
        loa: LevelOfArticulation,
        humanoid: &mut HumanoidSkeleton,
    ) -> Option<String> {
        self.draft = None;
        self.staged.clear();
        let entry = self.by_avatar.get(&avatar.name)?;
        if entry.automatic != avatar.avatar.mapping {
            // Another file under the same name: its joints are not the same.
            self.by_avatar.remove(&avatar.name);
            return None;
        }
        if entry.applied.is_empty() {
            return None;
        }
        let count: usize = entry.applied.iter().map(Vec::len).sum();
        let rebuilt = entry
            .mapping(entry.applied.len())
            .map_err(|error| error.to_string())
            .and_then(|mapping| {
                let built = avatar.skeleton_with_mapping(&mapping, loa)?;
                Ok((mapping, built))
            });
        match rebuilt {
            Ok((mapping, built)) => {
                avatar.avatar.mapping = mapping;
                *humanoid = built;
                Some(format!(
                    "Your {count} mapping correction(s) of this session were made again."
                ))
            }
            Err(error) => {
                self.by_avatar.remove(&avatar.name);
                Some(format!(
                    "Your mapping corrections could not be made again ({error}); the automatic mapping is used."
                ))
            }
        }
    }
}

/// What the user asked for in the mapping window.
enum MappingAction {
    Pick(usize, Option<&'static str>),
    Apply,
    Discard,
    Revert,
}

/// One row of the mapping window.
struct MappingRow {
    source: usize,
    name: String,
    hanim: Option<&'static str>,
    method: Option<MatchMethod>,
    confidence: Option<f32>,
    changed: bool,
}

impl StanceApp {
    /// The side panel's line about guessed joints and the button that opens the window.
    pub(super) fn avatar_mapping_button(&mut self, ui: &mut egui::Ui) {
        let Some(avatar) = &self.avatar else {
            return;
        };
        let guesses = avatar
            .avatar
            .mapping
            .matches()
            .iter()
            .filter(|found| found.method != MatchMethod::Implied)
            .filter(|found| found.confidence < LOW_CONFIDENCE)
            .count();
        if guesses > 0 {
            ui.colored_label(
                GUESS_COLOR,
                format!("{guesses} of them guessed: check them in the mapping"),
            );
        }
        let button = ui
            .button("Avatar mapping…")
            .on_hover_text("check and correct which H-Anim joint each joint of the file drives");
        self.button_rects.push(("mapping_open", button.rect));
        if button.clicked() {
            self.mapping_editor.open = !self.mapping_editor.open;
        }
    }

    /// The File menu's entry for the posed GLB.
    pub(super) fn export_posed_menu_item(&mut self, ui: &mut egui::Ui) {
        let button = ui
            .add_enabled(
                self.avatar.is_some(),
                egui::Button::new("Export posed avatar (GLB)…"),
            )
            .on_disabled_hover_text("load an avatar first (Avatar menu)");
        self.button_rects.push(("export_posed", button.rect));
        if button.clicked() {
            self.export_posed_avatar();
            ui.close();
        }
    }

    /// Offers the avatar in the current posture as a GLB download (what `stance
    /// export-posed` writes); says why when it cannot.
    pub fn export_posed_avatar(&mut self) {
        let Some(avatar) = self.avatar.as_mut() else {
            self.warn("Load an avatar first (Avatar menu): the mannequin cannot be exported.");
            return;
        };
        let file_name = posed_file_name(&avatar.name);
        let bytes = match avatar.posed_glb(self.session.humanoid(), self.session.posture()) {
            Ok(bytes) => bytes,
            Err(error) => {
                self.warn(format!("The posed avatar could not be exported: {error}"));
                return;
            }
        };
        match self.hooks.download_bytes(&file_name, &bytes) {
            Ok(()) => self.inform(format!(
                "Exported {file_name} ({} KB): the avatar in this posture, for any glTF viewer or engine.",
                bytes.len().div_ceil(1024)
            )),
            Err(error) => self.warn(format!("{file_name} could not be downloaded: {error}")),
        }
    }

    /// The mapping window (when open and an avatar is loaded).
    pub(super) fn mapping_window(&mut self, ctx: &egui::Context) {
        if !self.mapping_editor.open {
            return;
        }
        let Some(avatar) = self.avatar.as_ref() else {
            self.mapping_editor.open = false;
            self.mapping_editor.draft = None;
            self.mapping_editor.staged.clear();
            return;
        };
        let loa = self.session.level_of_articulation();
        let can_revert = self
            .mapping_editor
            .by_avatar
            .get(&avatar.name)
            .is_some_and(|entry| !entry.applied.is_empty());
        let MappingEditor {
            draft,
            staged,
            filter,
            only_guesses,
            ..
        } = &mut self.mapping_editor;
        let draft: &Mapping = draft.get_or_insert_with(|| avatar.avatar.mapping.clone());
        let node_name = |source: usize| {
            avatar
                .avatar
                .nodes
                .get(source)
                .map_or_else(|| format!("node {source}"), |node| node.name.clone())
        };
        let rows: Vec<MappingRow> = avatar
            .joint_nodes()
            .into_iter()
            .map(|source| {
                let hanim = draft.hanim_of(source);
                let found = hanim.and_then(|hanim| draft.get(hanim));
                MappingRow {
                    source,
                    name: node_name(source),
                    hanim,
                    method: found.map(|found| found.method),
                    confidence: found.map(|found| found.confidence),
                    changed: hanim != avatar.avatar.mapping.hanim_of(source),
                }
            })
            .collect();
        let needed = draft.missing(LevelOfArticulation::Loa1);
        let missing = draft.missing(loa);
        let left_out = missing.len().saturating_sub(needed.len());
        let needle = filter.trim().to_lowercase();
        let staged_count = staged.len();
        let rects = &mut self.button_rects;
        let mut action = None;
        let mut open = true;
        egui::Window::new("Avatar mapping")
            .open(&mut open)
            .default_width(560.0)
            .resizable(true)
            .show(ctx, |ui| {
                ui.label(format!(
                    "Which H-Anim joint each joint of {} drives. Orange rows are guesses (confidence below {:.0} %): check them, pick another H-Anim joint or none, then Apply.",
                    avatar.name,
                    LOW_CONFIDENCE * 100.0
                ));
                ui.horizontal(|ui| {
                    let label = ui.label("Filter joints");
                    ui.add(
                        egui::TextEdit::singleline(filter)
                            .hint_text("name")
                            .desired_width(140.0),
                    )
                    .labelled_by(label.id);
                    ui.checkbox(only_guesses, "only guesses and unmapped");
                });
                egui::ScrollArea::vertical()
                    .max_height(340.0)
                    .auto_shrink([false, true])
                    .show(ui, |ui| {
                        egui::Grid::new("mapping_rows")
                            .striped(true)
                            .num_columns(4)
                            .show(ui, |ui| {
                                ui.label(RichText::new("Joint in the file").strong());
                                ui.label(RichText::new("H-Anim joint").strong());
                                ui.label(RichText::new("Found by").strong());
                                ui.label(RichText::new("Confidence").strong());
                                ui.end_row();
                                for row in &rows {
                                    let guess = row.confidence.is_some_and(|c| c < LOW_CONFIDENCE);
                                    if *only_guesses && !guess && row.hanim.is_some() {
                                        continue;
                                    }
                                    if !needle.is_empty()
                                        && !row.name.to_lowercase().contains(&needle)
                                        && !row.hanim.is_some_and(|hanim| hanim.contains(&needle))
                                    {
                                        continue;
                                    }
                                    let suggested = suggestions(row.hanim, &needed, &missing);
                                    if let Some(pick) =
                                        mapping_row(ui, row, draft, &suggested, &node_name)
                                    {
                                        action = Some(pick);
                                    }
                                }
                            });
                    });
                if !needed.is_empty() {
                    ui.colored_label(
                        MISSING_COLOR,
                        format!(
                            "Every humanoid needs these joints: {}. Pick a joint of the file for each before applying.",
                            needed.join(", ")
                        ),
                    );
                } else if left_out > 0 {
                    ui.label(
                        RichText::new(format!(
                            "{left_out} joints of LOA {} are not mapped: the skeleton goes without them.",
                            loa.number()
                        ))
                        .small(),
                    );
                }
                if staged_count > 0 {
                    ui.label(format!("{staged_count} change(s) not applied yet."));
                }
                ui.horizontal(|ui| {
                    let apply = ui.add_enabled(
                        staged_count > 0 && needed.is_empty(),
                        egui::Button::new("Apply"),
                    );
                    rects.push(("mapping_apply", apply.rect));
                    if apply.clicked() {
                        action = Some(MappingAction::Apply);
                    }
                    let discard =
                        ui.add_enabled(staged_count > 0, egui::Button::new("Discard changes"));
                    rects.push(("mapping_discard", discard.rect));
                    if discard.clicked() {
                        action = Some(MappingAction::Discard);
                    }
                    let revert =
                        ui.add_enabled(can_revert, egui::Button::new("Revert last correction"));
                    rects.push(("mapping_revert", revert.rect));
                    if revert.clicked() {
                        action = Some(MappingAction::Revert);
                    }
                });
                ui.label(
                    RichText::new(
                        "Applying rebuilds the skeleton; the posture and the tasks that still fit carry over. Ctrl+Z does not undo a mapping change: Revert last correction does.",
                    )
                    .small(),
                );
            });
        if !open {
            self.mapping_editor.open = false;
        }
        match action {
            Some(MappingAction::Pick(source, hanim)) => self.stage_correction(source, hanim),
            Some(MappingAction::Apply) => self.apply_mapping_corrections(),
            Some(MappingAction::Discard) => {
                self.mapping_editor.draft = None;
                self.mapping_editor.staged.clear();
                self.inform("The mapping changes were discarded.");
            }
            Some(MappingAction::Revert) => self.revert_mapping_correction(),
            None => {}
        }
    }

    fn stage_correction(&mut self, source: usize, hanim: Option<&'static str>) {
        let Some(draft) = self.mapping_editor.draft.as_mut() else {
            return;
        };
        let correction = Correction { source, hanim };
        match correction.apply(draft) {
            Ok(()) => self.mapping_editor.staged.push(correction),
            Err(error) => self.warn(format!("That correction is not possible: {error}")),
        }
    }

    /// Rebuilds the skeleton and the session from the draft, as one correction to revert.
    fn apply_mapping_corrections(&mut self) {
        let Some(avatar) = &self.avatar else {
            return;
        };
        let Some(draft) = self
            .mapping_editor
            .draft
            .clone()
            .filter(|_| !self.mapping_editor.staged.is_empty())
        else {
            self.inform("Nothing to apply: pick another H-Anim joint in a row first.");
            return;
        };
        let name = avatar.name.clone();
        let before = avatar.avatar.mapping.clone();
        let changes: Vec<String> = avatar
            .joint_nodes()
            .into_iter()
            .filter(|&source| before.hanim_of(source) != draft.hanim_of(source))
            .map(|source| {
                let node = avatar
                    .avatar
                    .nodes
                    .get(source)
                    .map_or("?", |node| node.name.as_str());
                match draft.hanim_of(source) {
                    Some(hanim) => format!("{node} drives {hanim}"),
                    None => format!("{node} drives no joint"),
                }
            })
            .collect();
        match self.remap_avatar(draft) {
            Ok(dropped) => {
                let staged = std::mem::take(&mut self.mapping_editor.staged);
                self.mapping_editor
                    .by_avatar
                    .entry(name)
                    .or_insert_with(|| AvatarCorrections {
                        automatic: before,
                        applied: Vec::new(),
                    })
                    .applied
                    .push(staged);
                self.mapping_editor.draft = None;
                self.inform(format!(
                    "Mapping corrected ({}): {} Ctrl+Z does not undo this; Revert last correction in the mapping window does.",
                    summarize(&changes),
                    self.rebuilt_summary(&dropped)
                ));
            }
            Err(error) => self.warn(format!(
                "The corrected mapping could not be applied: {error}. The skeleton stays as it was."
            )),
        }
    }

    /// Goes back to the mapping before the last applied correction.
    fn revert_mapping_correction(&mut self) {
        let Some(avatar) = &self.avatar else {
            return;
        };
        let name = avatar.name.clone();
        let previous = match self.mapping_editor.by_avatar.get(&name) {
            Some(entry) if !entry.applied.is_empty() => entry.mapping(entry.applied.len() - 1),
            _ => {
                self.inform("There is no mapping correction to revert.");
                return;
            }
        };
        match previous
            .map_err(|error| error.to_string())
            .and_then(|mapping| self.remap_avatar(mapping))
        {
            Ok(dropped) => {
                if let Some(entry) = self.mapping_editor.by_avatar.get_mut(&name) {
                    entry.applied.pop();
                }
                self.mapping_editor.draft = None;
                self.mapping_editor.staged.clear();
                self.inform(format!(
                    "Reverted the last mapping correction: {}",
                    self.rebuilt_summary(&dropped)
                ));
            }
            Err(error) => self.warn(format!("The correction could not be reverted: {error}")),
        }
    }

    fn rebuilt_summary(&self, dropped: &[String]) -> String {
        let skeleton = self.session.skeleton();
        let mut text = format!(
            "the skeleton was rebuilt ({} joints, {} DOF); the posture and {} task(s) carried over.",
            skeleton.joint_count(),
            skeleton.dof_count(),
            self.session.tasks().len()
        );
        if !dropped.is_empty() {
            text.push_str(&format!(
                " Dropped, their joints are gone: {}.",
                dropped.join(", ")
            ));
        }
        text
    }

    /// Rebuilds the avatar's skeleton and the posing session from `mapping` at the current
    /// LOA: the posture carries over by joint name, the tasks that still fit stay. On error
    /// nothing changes. Returns the dropped tasks, described.
    fn remap_avatar(&mut self, mapping: Mapping) -> Result<Vec<String>, String> {
        let loa = self.session.level_of_articulation();
        let Some(avatar) = self.avatar.as_mut() else {
            return Err("no avatar is loaded".to_owned());
        };
        let humanoid = avatar.skeleton_with_mapping(&mapping, loa)?;
        let mut session =
            PosingSession::with_humanoid(humanoid).map_err(|error| error.to_string())?;
        let (kept, dropped): (Vec<TaskSpec>, Vec<TaskSpec>) = self
            .session
            .tasks()
            .iter()
            .cloned()
            .partition(|task| task.to_solver_tasks(session.skeleton(), &[]).is_ok());
        if let Some(posture) = carry_posture(&self.session, session.skeleton()) {
            session.set_posture(posture);
        }
        session.set_tasks(kept);
        avatar.avatar.mapping = mapping;
        self.session = session;
        self.sensors.release();
        self.selected_joint = None;
        self.hovered_joint = None;
        self.pull = None;
        self.handle_drag = None;
        self.trace.clear();
        Ok(dropped.iter().map(describe_task).collect())
    }
}

/// One row: the file's joint (orange when guessed, bold when changed), the H-Anim joint to
/// pick, how it was found and how sure. Returns the pick.
fn mapping_row(
    ui: &mut egui::Ui,
    row: &MappingRow,
    draft: &Mapping,
    suggested: &[&'static str],
    node_name: &dyn Fn(usize) -> String,
) -> Option<MappingAction> {
    let guess = row.confidence.is_some_and(|c| c < LOW_CONFIDENCE);
    let mut name = RichText::new(&row.name);
    if guess {
        name = name.color(GUESS_COLOR);
    } else if row.hanim.is_none() {
        name = name.weak();
    }
    if row.changed {
        name = name.strong();
    }
    let label = ui.label(name);
    let mut pick = None;
    let combo = egui::ComboBox::from_id_salt(("mapping_row", row.source))
        .selected_text(row.hanim.unwrap_or(UNMAPPED))
        .height(320.0)
        .show_ui(ui, |ui| {
            if ui
                .selectable_label(row.hanim.is_none(), "none (not an H-Anim joint)")
                .clicked()
            {
                pick = Some(MappingAction::Pick(row.source, None));
            }
            let mut entry = |ui: &mut egui::Ui, hanim: &'static str| {
                let item = ui.selectable_label(row.hanim == Some(hanim), joint_item_text(hanim));
                let item = match draft.source_of(hanim) {
                    Some(other) if other != row.source => item.on_hover_text(format!(
                        "now on {}; picking it here unmaps it there",
                        node_name(other)
                    )),
                    _ => item,
                };
                if item.clicked() {
                    pick = Some(MappingAction::Pick(row.source, Some(hanim)));
                }
            };
            if !suggested.is_empty() {
                ui.label(RichText::new("suggested").small().weak());
                for &hanim in suggested {
                    entry(ui, hanim);
                }
                ui.separator();
                ui.label(RichText::new("all H-Anim joints").small().weak());
            }
            for joint in all_joints() {
                entry(ui, joint.name);
            }
        });
    combo.response.labelled_by(label.id);
    ui.label(match (row.method, row.changed) {
        (_, true) => "your change (not applied)",
        (Some(method), false) => method_text(method),
        (None, false) => "",
    });
    match row.confidence {
        Some(confidence) => {
            let text = RichText::new(format!("{:.0} %", confidence * 100.0));
            ui.label(if guess { text.color(GUESS_COLOR) } else { text })
        }
        None => ui.label(""),
    };
    ui.end_row();
    pick
}

/// The joints a row's list offers first: those every humanoid needs and the draft lacks, the
/// other side's joint of the row's own, then other unmapped joints of the current LOA.
fn suggestions(
    current: Option<&'static str>,
    needed: &[&'static str],
    missing: &[&'static str],
) -> Vec<&'static str> {
    const MOST: usize = 8;
    let mirrored = current
        .and_then(|hanim| joint_by_name(&mirror_name(hanim)))
        .map(|(_, joint)| joint.name);
    let mut out: Vec<&'static str> = Vec::new();
    for hanim in needed
        .iter()
        .copied()
        .chain(mirrored)
        .chain(missing.iter().copied())
    {
        if Some(hanim) != current && !out.contains(&hanim) && out.len() < MOST {
            out.push(hanim);
        }
    }
    out
}

/// A combo box entry: the H-Anim name and the joint in words (`l_elbow · left elbow`).
fn joint_item_text(name: &str) -> String {
    format!("{name} · {}", readable_name(name))
}

fn method_text(method: MatchMethod) -> &'static str {
    match method {
        MatchMethod::Vrm => "VRM humanoid",
        MatchMethod::HAnimName => "H-Anim name",
        MatchMethod::KnownName => "known rig name",
        MatchMethod::NamePattern => "name pattern",
        MatchMethod::Geometry => "position (guess)",
        MatchMethod::Implied => "implied",
        MatchMethod::User => "yours",
    }
}

/// The first changes in a line.
fn summarize(changes: &[String]) -> String {
    const SHOWN: usize = 4;
    let mut text = changes
        .iter()
        .take(SHOWN)
        .cloned()
        .collect::<Vec<_>>()
        .join(", ");
    if changes.len() > SHOWN {
        text.push_str(&format!(" and {} more", changes.len() - SHOWN));
    }
    if text.is_empty() {
        text.push_str("no joint changed");
    }
    text
}

/// The posture of `old` on `skeleton`, by joint name: each joint keeps its world rotation (a
/// joint new to the skeleton turns with its parent), projected onto its DOF; the root keeps
/// its translation.
fn carry_posture(old: &PosingSession, skeleton: &Skeleton) -> Option<Posture> {
    let old_skeleton = old.skeleton();
    let frames = old.frames();
    let mut world: Vec<DQuat> = Vec::with_capacity(skeleton.joint_count());
    for joint in skeleton.joints() {
        let own = old_skeleton
            .joint_index(&joint.name)
            .filter(|&index| index < frames.world_from_joint_rotation.len())
            .map(|index| frames.rotation(index).normalize());
        let inherited = joint.parent.and_then(|parent| world.get(parent).copied());
        world.push(own.or(inherited).unwrap_or(DQuat::IDENTITY));
    }
    let locals: Vec<DQuat> = skeleton
        .joints()
        .iter()
        .zip(&world)
        .map(
            |(joint, rotation)| match joint.parent.and_then(|parent| world.get(parent)) {
                Some(parent) => (parent.inverse() * *rotation).normalize(),
                None => *rotation,
            },
        )
        .collect();
    let values = old.posture().values();
    let mut translation = DVec3::ZERO;
    if let Some(root) = old_skeleton.joints().first() {
        for axis in 0..3 {
            if let Some(value) = root.translation_dof[axis].and_then(|dof| values.get(dof)) {
                translation[axis] = *value;
            }
        }
    }
    Posture::from_rotations(skeleton, translation, &locals).ok()
}

/// `Avatars/Jane.vrm?x=1` -> `Jane-posed.glb`.
fn posed_file_name(name: &str) -> String {
    let path = name.split(['?', '#']).next().unwrap_or(name);
    let base = path.rsplit(['/', '\\']).next().unwrap_or(path);
    let stem = base.rsplit_once('.').map_or(base, |(stem, _)| stem).trim();
    let stem = if stem.is_empty() { "avatar" } else { stem };
    format!("{stem}-posed.glb")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_posed_file_is_named_after_the_avatar() {
        assert_eq!(posed_file_name("Jane.vrm"), "Jane-posed.glb");
        assert_eq!(
            posed_file_name("https://example.org/a/Bob.glb?v=2#top"),
            "Bob-posed.glb"
        );
        assert_eq!(posed_file_name("C:\\models\\x.gltf"), "x-posed.glb");
        assert_eq!(posed_file_name(""), "avatar-posed.glb");
    }

    #[test]
    fn a_posture_carries_over_by_joint_name() {
        let mut old = PosingSession::new(LevelOfArticulation::Loa2).unwrap();
        let elbow = old.skeleton().joint_index("l_elbow").unwrap();
        let dof = old.skeleton().joints()[elbow].dof_start;
        old.set_dof(dof, 0.7);
        let target = PosingSession::new(LevelOfArticulation::Loa1).unwrap();
        let carried = carry_posture(&old, target.skeleton()).unwrap();
        let frames = stance_ik::Frames::new(target.skeleton(), &carried);
        let new_elbow = target.skeleton().joint_index("l_elbow").unwrap();
        let angle = frames
            .rotation(new_elbow)
            .angle_between(old.frames().rotation(elbow));
        assert!(angle < 1e-6, "the elbow turned {angle} rad away");
    }
}
