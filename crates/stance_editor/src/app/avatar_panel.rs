//! The avatar's side of the editor: the mapping window, where the user checks and corrects
//! which H-Anim joint each joint of the file drives (the skeleton and the posing session are
//! rebuilt from the corrected mapping), and the export of the posed avatar as GLB.

use egui::{Color32, RichText};
use stance_hanim::{LevelOfArticulation, Mapping, MatchMethod, all_joints, joint_by_name};

use super::StanceApp;
use crate::model::{Command, Correction};
use stance_hanim::{mirror_name, readable_name};

/// Matches less sure than this are guesses the user should check (name patterns, geometry).
const LOW_CONFIDENCE: f32 = 0.8;
/// Colour of guessed matches.
const GUESS_COLOR: Color32 = Color32::from_rgb(235, 150, 60);
/// Colour of the joints every humanoid needs and the draft lacks.
const MISSING_COLOR: Color32 = Color32::from_rgb(240, 90, 90);
/// What an unmapped row shows.
const UNMAPPED: &str = "none";

/// The mapping window's state (the corrections kept for the session are the model's).
#[derive(Debug, Default)]
pub(super) struct MappingEditor {
    pub(super) open: bool,
    /// The mapping being edited; `None` until the window shows an avatar.
    draft: Option<Mapping>,
    /// The corrections made in the draft and not applied yet.
    staged: Vec<Correction>,
    filter: String,
    only_guesses: bool,
}

impl MappingEditor {
    /// Another avatar arrived: the draft starts again.
    pub(super) fn restart(&mut self) {
        self.draft = None;
        self.staged.clear();
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
        let Some(avatar) = &self.model.avatar else {
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
                self.model.avatar.is_some(),
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
        let Some(avatar) = self.model.avatar.as_mut() else {
            self.model
                .warn("Load an avatar first (Avatar menu): the mannequin cannot be exported.");
            return;
        };
        let file_name = posed_file_name(&avatar.name);
        let bytes =
            match avatar.posed_glb(self.model.session.humanoid(), self.model.session.posture()) {
                Ok(bytes) => bytes,
                Err(error) => {
                    self.model
                        .warn(format!("The posed avatar could not be exported: {error}"));
                    return;
                }
            };
        match self.model.hooks.download_bytes(&file_name, &bytes) {
            Ok(()) => self.model.inform(format!(
                "Exported {file_name} ({} KB): the avatar in this posture, for any glTF viewer or engine.",
                bytes.len().div_ceil(1024)
            )),
            Err(error) => self.model.warn(format!("{file_name} could not be downloaded: {error}")),
        }
    }

    /// The mapping window (when open and an avatar is loaded).
    pub(super) fn mapping_window(&mut self, ctx: &egui::Context) {
        if !self.mapping_editor.open {
            return;
        }
        let Some(avatar) = self.model.avatar.as_ref() else {
            self.mapping_editor.open = false;
            self.mapping_editor.draft = None;
            self.mapping_editor.staged.clear();
            return;
        };
        let loa = self.model.session.level_of_articulation();
        let can_revert = self
            .model
            .mapping_corrections
            .before_last(&avatar.name)
            .is_some();
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
                self.model.inform("The mapping changes were discarded.");
            }
            Some(MappingAction::Revert) => {
                self.mapping_editor.restart();
                self.model.apply(Command::RevertMappingCorrection);
            }
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
            Err(error) => self
                .model
                .warn(format!("That correction is not possible: {error}")),
        }
    }

    /// Rebuilds the skeleton and the session from the draft, as one correction to revert.
    fn apply_mapping_corrections(&mut self) {
        let draft = self.mapping_editor.draft.take();
        let corrections = std::mem::take(&mut self.mapping_editor.staged);
        match draft {
            Some(mapping) if !corrections.is_empty() => self.model.apply(Command::ApplyMapping {
                mapping: Box::new(mapping),
                corrections,
            }),
            _ => self.model.apply(Command::Inform(
                "Nothing to apply: pick another H-Anim joint in a row first.".to_owned(),
            )),
        }
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
}
