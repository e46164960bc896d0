//! The side panel: the scene's characters (`scene_panel`), the selected one's body (avatar or mannequin, its mapping, the level of articulation),
//! undo and the posing commands, the selection (joint angles, swivel), the hands and the pose
//! library.

use crate::model::Outbox;
use crate::model::{
    AvatarCommand, FileCommand, HistoryCommand, LibraryCommand, PostureCommand, TaskCommand,
    ViewCommand,
};
use egui::RichText;
use stance_document::LimbName;
use stance_hanim::{MatchMethod, readable_name};
use stance_ik::Joint;

use super::avatar_panel::{GUESS_COLOR, LOW_CONFIDENCE};
use super::{ButtonRects, Windows, copy_link};
use crate::model::{Command, EditorModel, NewTask};

/// The side panel over the model.
pub(super) struct SidePanel<'a> {
    pub model: &'a EditorModel,
    pub outbox: &'a mut Outbox,
    /// A click on the body pins it.
    pub pin_tool: &'a mut bool,
    pub windows: &'a mut Windows,
    /// The name typed for the next saved pose.
    pub library_name: &'a mut String,
    pub buttons: &'a mut ButtonRects,
}

impl SidePanel<'_> {
    /// The whole panel.
    pub(super) fn show(&mut self, ui: &mut egui::Ui) {
        super::scene_panel::show(ui, self.model, self.outbox, self.buttons);
        ui.separator();
        self.humanoid_section(ui);
        self.edit_buttons(ui);
        let copy = ui.button("Copy posture link").on_hover_text("L");
        self.buttons.push(("copy_link", copy.rect));
        if copy.clicked() {
            copy_link(ui.ctx(), self.model, self.outbox);
        }
        let pin_tool = ui
            .toggle_value(self.pin_tool, "Pin tool")
            .on_hover_text("While on, a click on the body pins that part (also Alt + click)");
        self.buttons.push(("pin_tool", pin_tool.rect));
        let sensors = ui
            .button("Motion-capture sensors…")
            .on_hover_text("S: connect serial or HID sensors, calibrate, record, replay");
        self.buttons.push(("sensors_open", sensors.rect));
        if sensors.clicked() {
            self.windows.sensors = !self.windows.sensors;
        }
        ui.separator();
        self.selection_and_hands(ui);
        ui.separator();
        self.library_section(ui);
        ui.separator();
        super::comfort_panel::show(ui, self.model, self.outbox);
    }

    /// The body: avatar or mannequin, its level of articulation, joints and DOF.
    fn humanoid_section(&mut self, ui: &mut egui::Ui) {
        ui.heading("Humanoid");
        match self.model.avatar() {
            Some(avatar) => {
                ui.label(RichText::new(&avatar.name).strong());
                ui.label(format!(
                    "{} vertices, {} joints mapped onto H-Anim",
                    avatar.vertex_count,
                    avatar.mapping_summary().0
                ));
                self.avatar_mapping_button(ui);
            }
            None => {
                ui.label("H-Anim 2.0 mannequin (Avatar menu or drop a file to pose yours)");
            }
        }
        let current = self.model.session().level_of_articulation();
        let mut chosen = current;
        egui::ComboBox::from_label("Articulation")
            .selected_text(format!("LOA {}", current.number()))
            .show_ui(ui, |ui| {
                for loa in stance_hanim::LevelOfArticulation::ALL {
                    ui.selectable_value(&mut chosen, loa, format!("LOA {}", loa.number()));
                }
            });
        if chosen != current {
            self.outbox
                .send(Command::Avatar(AvatarCommand::SetLevelOfArticulation(
                    chosen,
                )));
        }
        ui.label(format!(
            "{} joints, {} DOF",
            self.model.session().skeleton().joint_count(),
            self.model.session().skeleton().dof_count()
        ));
    }

    /// Undo and redo, mirror and rest.
    fn edit_buttons(&mut self, ui: &mut egui::Ui) {
        ui.horizontal(|ui| {
            if ui
                .add_enabled(self.model.history().can_undo(), egui::Button::new("Undo"))
                .on_hover_text("Ctrl+Z")
                .clicked()
            {
                self.outbox.send(Command::History(HistoryCommand::Undo));
            }
            if ui
                .add_enabled(self.model.history().can_redo(), egui::Button::new("Redo"))
                .on_hover_text("Ctrl+Shift+Z or Ctrl+Y")
                .clicked()
            {
                self.outbox.send(Command::History(HistoryCommand::Redo));
            }
        });
        ui.horizontal(|ui| {
            if ui.button("Mirror").on_hover_text("M").clicked() {
                self.outbox.send(Command::Posture(PostureCommand::Mirror));
            }
            if ui.button("Rest pose").on_hover_text("R").clicked() {
                self.outbox
                    .send(Command::Posture(PostureCommand::ResetToRest));
            }
        });
    }

    /// The selection and, on a body with fingers, the hands.
    fn selection_and_hands(&mut self, ui: &mut egui::Ui) {
        self.selection_section(ui);
        super::hands_panel::show(ui, self.model, self.outbox);
    }

    fn selection_section(&mut self, ui: &mut egui::Ui) {
        ui.heading("Selection");
        let Some(joint_index) = self.model.selected_joint() else {
            ui.label("Click a body part to select it; drag it to pull it.");
            return;
        };
        let skeleton = self.model.session().skeleton();
        let Some(joint) = skeleton.joints().get(joint_index).cloned() else {
            self.outbox.send(Command::View(ViewCommand::Select(None)));
            return;
        };
        ui.label(RichText::new(readable_name(&joint.name)).strong());
        ui.label(RichText::new(&joint.name).small().weak());
        ui.horizontal(|ui| {
            if ui.button("Pin").on_hover_text("P").clicked() {
                self.outbox
                    .send(Command::Posture(PostureCommand::Pin(joint_index)));
            }
            if ui
                .button("Hold orientation")
                .on_hover_text("add an orientation task with the current orientation")
                .clicked()
            {
                self.outbox
                    .send(Command::Task(TaskCommand::Add(NewTask::Orientation(
                        joint_index,
                    ))));
            }
        });
        if let Some((dof, value)) = dof_editors(ui, self.model, &joint) {
            self.outbox
                .send(Command::Posture(PostureCommand::SetDof { dof, value }));
        }
        self.stiffness_section(ui, &joint);
        if let Some(limb) = LimbName::of_joint(&joint.name) {
            self.swivel_section(ui, limb);
        }
    }

    /// Each rotation DOF's stiffness (H-Anim's `stiffness`): how much less it moves than a
    /// free DOF for the same task; its anatomical default until changed.
    fn stiffness_section(&mut self, ui: &mut egui::Ui, joint: &stance_ik::Joint) {
        let session = self.model.session();
        let stiffness = session.skeleton().stiffness().to_vec();
        let rotations: Vec<(usize, stance_ik::Dof)> = joint
            .dofs
            .iter()
            .enumerate()
            .filter(|(_, dof)| dof.is_rotation())
            .map(|(offset, &dof)| (joint.dof_start + offset, dof))
            .collect();
        if rotations.is_empty() {
            return;
        }
        let mut edit: Option<(usize, Option<f64>)> = None;
        ui.label(RichText::new("Stiffness").strong()).on_hover_text(
            "0: moves freely; near 1: moves little, the rest of the body takes over",
        );
        egui::Grid::new("joint_stiffness")
            .num_columns(3)
            .show(ui, |ui| {
                for (index, dof) in rotations {
                    let Some(&value) = stiffness.get(index) else {
                        continue;
                    };
                    let default = session.default_stiffness(index);
                    ui.label(dof.name());
                    let mut v = value;
                    if ui
                        .add(
                            egui::DragValue::new(&mut v)
                                .range(0.0..=0.95)
                                .speed(0.01)
                                .max_decimals(2),
                        )
                        .changed()
                    {
                        edit = Some((index, Some(v)));
                    }
                    let changed = (value - default).abs() > 1e-12;
                    if ui
                        .add_enabled(changed, egui::Button::new("default").small())
                        .on_hover_text(format!("the anatomical default, {default:.2}"))
                        .clicked()
                    {
                        edit = Some((index, None));
                    }
                    ui.end_row();
                }
            });
        if let Some((dof, value)) = edit {
            self.outbox
                .send(Command::Posture(PostureCommand::SetStiffness {
                    dof,
                    value,
                }));
        }
    }

    fn swivel_section(&mut self, ui: &mut egui::Ui, limb: LimbName) {
        let Some((swivel, intervals)) = self.model.session().limb_swivel(limb) else {
            return;
        };
        ui.separator();
        ui.label(RichText::new(format!("{} swivel", limb.name().replace('_', " "))).strong());
        let mut degrees = swivel.to_degrees();
        let response = ui
            .add(egui::Slider::new(&mut degrees, -180.0..=180.0).suffix("°"))
            .on_hover_text("turns the elbow or knee around the shoulder-wrist (hip-ankle) axis; the hand or foot stays");
        let feasible: Vec<String> = intervals
            .iter()
            .map(|interval| {
                format!(
                    "{:.0}° to {:.0}°",
                    interval.start.to_degrees(),
                    interval.end.to_degrees()
                )
            })
            .collect();
        ui.label(
            RichText::new(if feasible.is_empty() {
                "no swivel keeps every joint within its limits".to_owned()
            } else {
                format!("within limits: {}", feasible.join(", "))
            })
            .small(),
        );
        if response.changed() {
            self.outbox
                .send(Command::Posture(PostureCommand::SetSwivel {
                    limb,
                    swivel_angle: degrees.to_radians(),
                }));
        }
    }

    fn library_section(&mut self, ui: &mut egui::Ui) {
        ui.heading("Pose library");
        ui.horizontal(|ui| {
            let label = ui.label("Name");
            ui.add(
                egui::TextEdit::singleline(self.library_name)
                    .hint_text("pose name")
                    .desired_width(120.0),
            )
            .labelled_by(label.id);
            if ui.button("Save").clicked() {
                let name = self.library_name.clone();
                self.outbox
                    .send(Command::Library(LibraryCommand::Save(name)));
            }
        });
        let mut load = None;
        let mut delete = None;
        for (index, entry) in self.model.library().entries().iter().enumerate() {
            ui.horizontal(|ui| {
                if ui.button("Load").clicked() {
                    load = Some(index);
                }
                if ui.small_button("x").on_hover_text("delete").clicked() {
                    delete = Some(index);
                }
                ui.label(&entry.name);
            });
        }
        if let Some(index) = load {
            self.outbox
                .send(Command::Library(LibraryCommand::Load(index)));
        }
        if let Some(index) = delete {
            self.outbox
                .send(Command::Library(LibraryCommand::Delete(index)));
        }
        ui.horizontal(|ui| {
            if ui.button("Import…").clicked() {
                self.outbox.send(Command::File(FileCommand::PickFile));
            }
            if ui.button("Export…").clicked() {
                self.outbox.send(Command::Library(LibraryCommand::Export));
            }
        });
    }

    /// The side panel's line about guessed joints and the button that opens the window.
    fn avatar_mapping_button(&mut self, ui: &mut egui::Ui) {
        let Some(avatar) = self.model.avatar() else {
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
        self.buttons.push(("mapping_open", button.rect));
        if button.clicked() {
            self.windows.mapping = !self.windows.mapping;
            self.windows.mapping_subject = super::avatar_panel::SubjectKind::Avatar;
        }
    }
}

/// Joint mode: each DOF of `joint` within its anatomical limits; returns the DOF edited and
/// its new value.
fn dof_editors(ui: &mut egui::Ui, model: &EditorModel, joint: &Joint) -> Option<(usize, f64)> {
    let skeleton = model.session().skeleton();
    let (lower, upper) = (skeleton.lower_limits(), skeleton.upper_limits());
    let values = model.session().posture().values();
    let mut edit: Option<(usize, f64)> = None;
    egui::Grid::new("joint_dofs").num_columns(2).show(ui, |ui| {
        for (offset, dof) in joint.dofs.iter().enumerate() {
            let index = joint.dof_start + offset;
            let (Some(&value), Some(&low), Some(&high)) =
                (values.get(index), lower.get(index), upper.get(index))
            else {
                continue;
            };
            ui.label(dof.name());
            if dof.is_rotation() {
                let mut degrees = value.to_degrees();
                let range = low.to_degrees().max(-360.0)..=high.to_degrees().min(360.0);
                let response = ui.add(
                    egui::DragValue::new(&mut degrees)
                        .range(range)
                        .speed(0.5)
                        .suffix("°")
                        .max_decimals(1),
                );
                if response.changed() {
                    edit = Some((index, degrees.to_radians()));
                }
            } else {
                let mut metres = value;
                if ui
                    .add(
                        egui::DragValue::new(&mut metres)
                            .speed(0.005)
                            .suffix(" m")
                            .max_decimals(3),
                    )
                    .changed()
                {
                    edit = Some((index, metres));
                }
            }
            ui.end_row();
        }
    });
    edit
}
