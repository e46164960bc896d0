//! The mapping window, where the user checks and corrects which H-Anim joint each joint of
//! the avatar's file drives (the model rebuilds the skeleton and the posing session from the
//! corrected mapping), or each joint of the open motion clip (the model retargets the clip
//! with the corrected mapping).

use crate::model::Outbox;
use crate::model::{AvatarCommand, NoticeCommand};
use egui::{Color32, RichText};
use stance_hanim::{
    LevelOfArticulation, Mapping, MatchMethod, all_joints, joint_by_name, mirror_name,
    readable_name,
};

use super::ButtonRects;
use crate::model::{Command, Correction, EditorModel, MotionCommand};

/// Matches less sure than this are guesses the user should check (name patterns, geometry).
pub(super) const LOW_CONFIDENCE: f32 = 0.8;
/// Colour of guessed matches.
pub(super) const GUESS_COLOR: Color32 = Color32::from_rgb(235, 150, 60);
/// Colour of the joints every humanoid needs and the draft lacks.
const MISSING_COLOR: Color32 = Color32::from_rgb(240, 90, 90);
/// What an unmapped row shows.
const UNMAPPED: &str = "none";

/// Whose mapping the window edits.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub(crate) enum SubjectKind {
    /// The loaded avatar's.
    #[default]
    Avatar,
    /// The open motion clip's.
    Clip,
}

/// What the window shows of its subject: its name, the joints listed, every joint's name (by
/// source index) and the mapping as it is now.
struct Subject {
    kind: SubjectKind,
    title: String,
    joints: Vec<usize>,
    names: Vec<String>,
    original: Mapping,
    can_revert: bool,
}

impl Subject {
    fn of(model: &EditorModel, kind: SubjectKind) -> Option<Self> {
        match kind {
            SubjectKind::Avatar => {
                let avatar = model.avatar()?;
                Some(Self {
                    kind,
                    title: avatar.name.clone(),
                    joints: avatar.joint_nodes(),
                    names: avatar.avatar.nodes.iter().map(|n| n.name.clone()).collect(),
                    original: avatar.avatar.mapping.clone(),
                    can_revert: model.can_revert_mapping(&avatar.name),
                })
            }
            SubjectKind::Clip => {
                let clip = model.timeline().clip()?;
                Some(Self {
                    kind,
                    title: format!("the clip {}", clip.name),
                    joints: (0..clip.joints.len())
                        .filter(|&j| !clip.joints[j].name.ends_with("_End"))
                        .collect(),
                    names: clip.joints.iter().map(|j| j.name.clone()).collect(),
                    original: clip.mapping.clone(),
                    can_revert: false,
                })
            }
        }
    }

    /// The name of joint `source`.
    fn name(&self, source: usize) -> String {
        self.names
            .get(source)
            .cloned()
            .unwrap_or_else(|| format!("joint {source}"))
    }
}

/// The mapping window's state (the corrections kept for the session are the model's).
#[derive(Debug, Default)]
pub(super) struct MappingEditor {
    /// Whose mapping is edited.
    kind: SubjectKind,
    /// The mapping being edited; `None` until the window shows its subject.
    draft: Option<Mapping>,
    /// The corrections made in the draft and not applied yet.
    staged: Vec<Correction>,
    filter: String,
    only_guesses: bool,
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

impl MappingEditor {
    /// Another avatar arrived: the draft starts again.
    pub(super) fn restart(&mut self) {
        self.draft = None;
        self.staged.clear();
    }

    /// The window (while `open` and an avatar is loaded); what the user picks goes to `model`.
    pub(super) fn show(
        &mut self,
        ctx: &egui::Context,
        model: &EditorModel,
        outbox: &mut Outbox,
        (open, kind): (&mut bool, SubjectKind),
        buttons: &mut ButtonRects,
    ) {
        if !*open {
            return;
        }
        if kind != self.kind {
            self.kind = kind;
            self.restart();
        }
        let Some(subject) = Subject::of(model, self.kind) else {
            *open = false;
            self.restart();
            return;
        };
        let MappingEditor {
            kind: _,
            draft,
            staged,
            filter,
            only_guesses,
        } = self;
        let draft: &Mapping = draft.get_or_insert_with(|| subject.original.clone());
        let table = MappingTable::new(&subject, draft, model.level_of_articulation());
        let staged_count = staged.len();
        let mut action = None;
        let title = match subject.kind {
            SubjectKind::Avatar => "Avatar mapping",
            SubjectKind::Clip => "Clip mapping",
        };
        egui::Window::new(title)
            .open(open)
            .default_width(560.0)
            .resizable(true)
            .show(ctx, |ui| {
                ui.label(format!(
                    "Which H-Anim joint each joint of {} drives. Orange rows are guesses (confidence below {:.0} %): check them, pick another H-Anim joint or none, then Apply.",
                    subject.title,
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
                if let Some(pick) = table.show(ui, filter, *only_guesses) {
                    action = Some(pick);
                }
                table.notes(ui, staged_count);
                let ready = staged_count > 0 && table.needed.is_empty();
                let footer = Footer {
                    ready,
                    changed: staged_count > 0,
                    can_revert: subject.can_revert,
                    kind: subject.kind,
                };
                if let Some(pressed) = footer.show(ui, buttons) {
                    action = Some(pressed);
                }
            });
        if let Some(action) = action {
            self.act(action, outbox);
        }
    }

    /// Carries out what the user asked for.
    fn act(&mut self, action: MappingAction, outbox: &mut Outbox) {
        match action {
            MappingAction::Pick(source, hanim) => {
                let Some(draft) = self.draft.as_mut() else {
                    return;
                };
                let correction = Correction { source, hanim };
                match correction.apply(draft) {
                    Ok(()) => self.staged.push(correction),
                    Err(error) => {
                        outbox.send(Command::Notice(NoticeCommand::Warn(format!(
                            "That correction is not possible: {error}"
                        ))));
                    }
                }
            }
            MappingAction::Apply => {
                let draft = self.draft.take();
                let corrections = std::mem::take(&mut self.staged);
                match (draft, self.kind) {
                    (Some(mapping), SubjectKind::Avatar) => {
                        outbox.send(Command::Avatar(AvatarCommand::ApplyMapping {
                            mapping: Box::new(mapping),
                            corrections,
                        }));
                    }
                    (Some(mapping), SubjectKind::Clip) => outbox.send(Command::Motion(
                        MotionCommand::SetClipMapping(Box::new(mapping)),
                    )),
                    (None, _) => {}
                }
            }
            MappingAction::Discard => {
                self.restart();
                outbox.send(Command::Notice(NoticeCommand::Inform(
                    "The mapping changes were discarded.".to_owned(),
                )));
            }
            MappingAction::Revert => {
                self.restart();
                outbox.send(Command::Avatar(AvatarCommand::RevertMappingCorrection));
            }
        }
    }
}

/// The rows of the mapping window for one subject and draft.
struct MappingTable<'a> {
    subject: &'a Subject,
    draft: &'a Mapping,
    loa: LevelOfArticulation,
    rows: Vec<MappingRow>,
    /// Joints every humanoid needs that the draft lacks.
    needed: Vec<&'static str>,
    /// Joints of the current LOA that the draft lacks.
    missing: Vec<&'static str>,
}

impl<'a> MappingTable<'a> {
    fn new(subject: &'a Subject, draft: &'a Mapping, loa: LevelOfArticulation) -> Self {
        let rows = subject
            .joints
            .iter()
            .map(|&source| {
                let hanim = draft.hanim_of(source);
                let found = hanim.and_then(|hanim| draft.get(hanim));
                MappingRow {
                    source,
                    name: subject.name(source),
                    hanim,
                    method: found.map(|found| found.method),
                    confidence: found.map(|found| found.confidence),
                    changed: hanim != subject.original.hanim_of(source),
                }
            })
            .collect();
        Self {
            subject,
            draft,
            loa,
            rows,
            needed: draft.missing(LevelOfArticulation::Loa1),
            missing: draft.missing(loa),
        }
    }

    /// The grid of rows that pass the filter; returns a pick.
    fn show(&self, ui: &mut egui::Ui, filter: &str, only_guesses: bool) -> Option<MappingAction> {
        let needle = filter.trim().to_lowercase();
        let mut action = None;
        egui::ScrollArea::vertical()
            .max_height(340.0)
            .auto_shrink([false, true])
            .show(ui, |ui| {
                egui::Grid::new("mapping_rows")
                    .striped(true)
                    .num_columns(4)
                    .show(ui, |ui| {
                        for title in [
                            "Joint in the file",
                            "H-Anim joint",
                            "Found by",
                            "Confidence",
                        ] {
                            ui.label(RichText::new(title).strong());
                        }
                        ui.end_row();
                        for row in &self.rows {
                            let guess = row.confidence.is_some_and(|c| c < LOW_CONFIDENCE);
                            let filtered_out = (only_guesses && !guess && row.hanim.is_some())
                                || (!needle.is_empty()
                                    && !row.name.to_lowercase().contains(&needle)
                                    && !row.hanim.is_some_and(|hanim| hanim.contains(&needle)));
                            if filtered_out {
                                continue;
                            }
                            let suggested = suggestions(row.hanim, &self.needed, &self.missing);
                            let node_name = |source| self.subject.name(source);
                            if let Some(pick) =
                                mapping_row(ui, row, self.draft, &suggested, &node_name)
                            {
                                action = Some(pick);
                            }
                        }
                    });
            });
        action
    }

    /// What the draft still lacks, and how many changes wait.
    fn notes(&self, ui: &mut egui::Ui, staged_count: usize) {
        let left_out = self.missing.len().saturating_sub(self.needed.len());
        if !self.needed.is_empty() {
            ui.colored_label(
                MISSING_COLOR,
                format!(
                    "Every humanoid needs these joints: {}. Pick a joint of the file for each before applying.",
                    self.needed.join(", ")
                ),
            );
        } else if left_out > 0 {
            ui.label(
                RichText::new(format!(
                    "{left_out} joints of LOA {} are not mapped: the skeleton goes without them.",
                    self.loa.number()
                ))
                .small(),
            );
        }
        if staged_count > 0 {
            ui.label(format!("{staged_count} change(s) not applied yet."));
        }
    }
}

/// The window's buttons.
struct Footer {
    ready: bool,
    changed: bool,
    can_revert: bool,
    kind: SubjectKind,
}

impl Footer {
    /// Apply, discard and revert; returns the button pressed.
    fn show(&self, ui: &mut egui::Ui, buttons: &mut ButtonRects) -> Option<MappingAction> {
        let mut action = None;
        ui.horizontal(|ui| {
            let apply = ui.add_enabled(self.ready, egui::Button::new("Apply"));
            buttons.push(("mapping_apply", apply.rect));
            if apply.clicked() {
                action = Some(MappingAction::Apply);
            }
            let discard = ui.add_enabled(self.changed, egui::Button::new("Discard changes"));
            buttons.push(("mapping_discard", discard.rect));
            if discard.clicked() {
                action = Some(MappingAction::Discard);
            }
            if self.kind == SubjectKind::Avatar {
                let revert =
                    ui.add_enabled(self.can_revert, egui::Button::new("Revert last correction"));
                buttons.push(("mapping_revert", revert.rect));
                if revert.clicked() {
                    action = Some(MappingAction::Revert);
                }
            }
        });
        let text = match self.kind {
            SubjectKind::Avatar => {
                "Applying rebuilds the skeleton; the posture and the tasks that still fit carry over. Ctrl+Z does not undo a mapping change: Revert last correction does."
            }
            SubjectKind::Clip => {
                "Applying retargets the clip with this mapping (the keys stay); reopening the file starts from the guessed mapping again."
            }
        };
        ui.label(RichText::new(text).small());
        action
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
