//! The side panel (body, selection, joint angles, swivel, pose library) and the tasks panel
//! (tasks by priority level: status, reasons, editing, reordering).

use egui::{Color32, RichText};
use glam::{DQuat, DVec3};
use stance_document::{DEFAULT_BALANCE_MARGIN, LimbName, TaskKindSpec, TaskSpec};
use stance_ik::Axes;

use super::StanceApp;
use crate::history::EditKind;
use crate::model::Command;
use crate::posing::{MET_TOLERANCE, comfort_task, describe_task, joint_rotation};
use stance_hanim::readable_name;

/// Colours of task states.
const MET_COLOR: Color32 = Color32::from_rgb(90, 200, 120);
const GAVE_WAY_COLOR: Color32 = Color32::from_rgb(235, 150, 60);
const PROBLEM_COLOR: Color32 = Color32::from_rgb(240, 90, 90);
const INACTIVE_COLOR: Color32 = Color32::GRAY;

/// What is being dragged in the tasks panel: a task (onto another level) or a whole level
/// (onto another level's place).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Dragged {
    Task(usize),
    Level(u32),
}

impl StanceApp {
    pub(super) fn side_panel(&mut self, ui: &mut egui::Ui) {
        ui.heading("Humanoid");
        match &self.model.avatar {
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
        let current = self.model.session.level_of_articulation();
        let mut chosen = current;
        egui::ComboBox::from_label("Articulation")
            .selected_text(format!("LOA {}", current.number()))
            .show_ui(ui, |ui| {
                for loa in stance_hanim::LevelOfArticulation::ALL {
                    ui.selectable_value(&mut chosen, loa, format!("LOA {}", loa.number()));
                }
            });
        if chosen != current {
            self.model.apply(Command::SetLevelOfArticulation(chosen));
        }
        ui.label(format!(
            "{} joints, {} DOF",
            self.model.session.skeleton().joint_count(),
            self.model.session.skeleton().dof_count()
        ));
        ui.horizontal(|ui| {
            if ui
                .add_enabled(self.model.history.can_undo(), egui::Button::new("Undo"))
                .on_hover_text("Ctrl+Z")
                .clicked()
            {
                self.model.apply(Command::Undo);
            }
            if ui
                .add_enabled(self.model.history.can_redo(), egui::Button::new("Redo"))
                .on_hover_text("Ctrl+Shift+Z or Ctrl+Y")
                .clicked()
            {
                self.model.apply(Command::Redo);
            }
        });
        ui.horizontal(|ui| {
            if ui.button("Mirror").on_hover_text("M").clicked() {
                self.model.apply(Command::Mirror);
            }
            if ui.button("Rest pose").on_hover_text("R").clicked() {
                self.model.apply(Command::ResetToRest);
            }
        });
        let copy = ui.button("Copy posture link").on_hover_text("L");
        self.button_rects.push(("copy_link", copy.rect));
        if copy.clicked() {
            self.copy_link(ui.ctx());
        }
        let pin_tool = ui
            .toggle_value(&mut self.pin_tool, "Pin tool")
            .on_hover_text("While on, a click on the body pins that part (also Alt + click)");
        self.button_rects.push(("pin_tool", pin_tool.rect));
        let sensors = ui
            .button("Motion-capture sensors…")
            .on_hover_text("S: connect serial or HID sensors, calibrate, record, replay");
        self.button_rects.push(("sensors_open", sensors.rect));
        if sensors.clicked() {
            self.show_sensors = !self.show_sensors;
        }
        ui.separator();
        self.selection_section(ui);
        ui.separator();
        self.library_section(ui);
    }

    fn selection_section(&mut self, ui: &mut egui::Ui) {
        ui.heading("Selection");
        let Some(joint_index) = self.model.selected_joint else {
            ui.label("Click a body part to select it; drag it to pull it.");
            return;
        };
        let skeleton = self.model.session.skeleton();
        let Some(joint) = skeleton.joints().get(joint_index).cloned() else {
            self.model.apply(Command::Select(None));
            return;
        };
        let lower = skeleton.lower_limits().to_vec();
        let upper = skeleton.upper_limits().to_vec();
        ui.label(RichText::new(readable_name(&joint.name)).strong());
        ui.label(RichText::new(&joint.name).small().weak());
        ui.horizontal(|ui| {
            if ui.button("Pin").on_hover_text("P").clicked() {
                self.model.apply(Command::Pin(joint_index));
            }
            if ui
                .button("Hold orientation")
                .on_hover_text("add an orientation task with the current orientation")
                .clicked()
            {
                self.add_orientation_task(joint_index);
            }
        });
        // Joint mode: each DOF within its anatomical limits.
        let values = self.model.session.posture().values().to_vec();
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
        if let Some((dof, value)) = edit {
            self.model.apply(Command::SetDof { dof, value });
        }
        if let Some(limb) = LimbName::of_joint(&joint.name) {
            self.swivel_section(ui, limb);
        }
    }

    fn swivel_section(&mut self, ui: &mut egui::Ui, limb: LimbName) {
        let Some((swivel, intervals)) = self.model.session.limb_swivel(limb) else {
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
            self.model.apply(Command::SetSwivel {
                limb,
                swivel_angle: degrees.to_radians(),
            });
        }
    }

    fn library_section(&mut self, ui: &mut egui::Ui) {
        ui.heading("Pose library");
        ui.horizontal(|ui| {
            let label = ui.label("Name");
            ui.add(
                egui::TextEdit::singleline(&mut self.library_name)
                    .hint_text("pose name")
                    .desired_width(120.0),
            )
            .labelled_by(label.id);
            if ui.button("Save").clicked() {
                let name = self.library_name.clone();
                self.model.apply(Command::SaveToLibrary(name));
            }
        });
        let mut load = None;
        let mut delete = None;
        for (index, entry) in self.model.library.entries().iter().enumerate() {
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
            self.model.apply(Command::LoadFromLibrary(index));
        }
        if let Some(index) = delete {
            self.model.apply(Command::DeleteFromLibrary(index));
        }
        ui.horizontal(|ui| {
            if ui.button("Import…").clicked() {
                self.import_file();
            }
            if ui.button("Export…").clicked() {
                self.export_library();
            }
        });
    }

    // -----------------------------------------------------------------------------------------
    // Tasks

    pub(super) fn tasks_panel(&mut self, ui: &mut egui::Ui) {
        ui.heading("Tasks");
        ui.label(
            RichText::new("Level 1 is obeyed first; a lower level only uses what is left.").small(),
        );
        ui.horizontal(|ui| {
            ui.menu_button("Add task", |ui| self.add_task_menu(ui));
            let table1 = ui
                .button("Table 1 example")
                .on_hover_text("the paper's example: foot, gaze and hand at level 1, balance at 2, other hand at 3");
            self.button_rects.push(("table1", table1.rect));
            if table1.clicked() {
                self.load_table1_example();
            }
        });
        ui.separator();

        let mut tasks = self.model.session.tasks().to_vec();
        let statuses = self.model.session.statuses().to_vec();
        let joint_names: Vec<String> = self
            .model
            .session
            .skeleton()
            .joints()
            .iter()
            .map(|joint| joint.name.clone())
            .collect();
        let mut levels: Vec<u32> = tasks.iter().map(|task| task.level).collect();
        levels.sort_unstable();
        levels.dedup();
        let mut edit: Option<EditKind> = None;
        let mut remove: Option<usize> = None;
        let mut move_to_level: Option<(usize, u32)> = None;
        let mut swap_levels: Option<(u32, u32)> = None;
        // A level dropped onto another level's place (`None`: made the lowest).
        let mut move_level: Option<(u32, Option<u32>)> = None;

        for (position, &level) in levels.iter().enumerate() {
            let members: Vec<usize> = (0..tasks.len())
                .filter(|&index| tasks[index].level == level)
                .collect();
            let level_met = members.iter().all(|&index| {
                !tasks[index].active
                    || matches!(tasks[index].kind, TaskKindSpec::Posture { .. })
                    || statuses
                        .get(index)
                        .is_some_and(|status| status.gave_way.is_none() && status.problem.is_none())
            });
            let frame = egui::Frame::new().inner_margin(4.0).corner_radius(4.0);
            let (_, dropped) = ui.dnd_drop_zone::<Dragged, ()>(frame, |ui| {
                ui.horizontal(|ui| {
                    let (mark, color) = if level_met {
                        ("all met", MET_COLOR)
                    } else {
                        ("not all met", GAVE_WAY_COLOR)
                    };
                    // The level's title drags the whole level onto another level's place.
                    ui.dnd_drag_source(
                        egui::Id::NULL.with(("stance_level_drag", level)),
                        Dragged::Level(level),
                        |ui| ui.label(RichText::new(format!("Level {level}")).strong()),
                    )
                    .response
                    .on_hover_text("drag onto another level to take its place");
                    ui.colored_label(color, mark).on_hover_text(if level_met {
                        "every task of this level is met"
                    } else {
                        "a task of this level is not met"
                    });
                    if position > 0
                        && ui
                            .small_button("up")
                            .on_hover_text(
                                "raise this level's priority (swap with the level above)",
                            )
                            .clicked()
                    {
                        swap_levels = Some((level, levels[position - 1]));
                    }
                    if position + 1 < levels.len()
                        && ui
                            .small_button("down")
                            .on_hover_text(
                                "lower this level's priority (swap with the level below)",
                            )
                            .clicked()
                    {
                        swap_levels = Some((level, levels[position + 1]));
                    }
                });
                for &index in &members {
                    let status = statuses.get(index).cloned();
                    let id = egui::Id::NULL.with(("stance_task_drag", index));
                    // Only the handle drags the task: a drag source senses the press at once,
                    // which would take the clicks of the header and the fields under it.
                    ui.horizontal_top(|ui| {
                        ui.dnd_drag_source(id, Dragged::Task(index), |ui| {
                            ui.label(RichText::new("::").strong());
                        })
                        .response
                        .on_hover_text("drag onto another level");
                        ui.vertical(|ui| {
                            if let Some(kind) = task_editor(
                                ui,
                                index,
                                &mut tasks[index],
                                status.as_ref(),
                                &joint_names,
                                &mut remove,
                            ) {
                                edit = Some(kind);
                            }
                        });
                    });
                }
            });
            match dropped.as_deref() {
                Some(Dragged::Task(index)) => move_to_level = Some((*index, level)),
                Some(Dragged::Level(from)) if *from != level => {
                    move_level = Some((*from, Some(level)));
                }
                _ => {}
            }
        }
        // Dropping below the last level makes a new lowest level.
        let lowest = levels.last().copied().unwrap_or(0) + 1;
        let (_, dropped) =
            ui.dnd_drop_zone::<Dragged, ()>(egui::Frame::new().inner_margin(4.0), |ui| {
                ui.label(
                    RichText::new(
                        "drop a task here for a new lowest level, or a level to make it the lowest",
                    )
                    .small()
                    .weak(),
                );
            });
        match dropped.as_deref() {
            Some(Dragged::Task(index)) => move_to_level = Some((*index, lowest)),
            Some(Dragged::Level(from)) => move_level = Some((*from, None)),
            None => {}
        }

        if let Some(index) = remove
            && index < tasks.len()
        {
            tasks.remove(index);
            self.model.apply(Command::SetTasks {
                kind: EditKind::Command,
                tasks,
            });
        } else if let Some((index, level)) = move_to_level {
            if let Some(task) = tasks.get_mut(index) {
                task.level = level;
            }
            self.model.apply(Command::SetTasks {
                kind: EditKind::Command,
                tasks,
            });
        } else if let Some((from, onto)) = move_level {
            reorder_levels(&mut tasks, &levels, from, onto);
            self.model.apply(Command::SetTasks {
                kind: EditKind::Command,
                tasks,
            });
        } else if let Some((a, b)) = swap_levels {
            for task in &mut tasks {
                if task.level == a {
                    task.level = b;
                } else if task.level == b {
                    task.level = a;
                }
            }
            self.model.apply(Command::SetTasks {
                kind: EditKind::Command,
                tasks,
            });
        } else if let Some(kind) = edit {
            self.model.apply(Command::SetTasks { kind, tasks });
        }
    }

    fn add_task_menu(&mut self, ui: &mut egui::Ui) {
        let selected = self.model.selected_joint;
        let selected_name = selected
            .and_then(|joint| self.model.session.skeleton().joints().get(joint))
            .map(|joint| readable_name(&joint.name));
        let label = |what: &str| match &selected_name {
            Some(name) => format!("{what} of the {name}"),
            None => format!("{what} (select a body part first)"),
        };
        if ui
            .add_enabled(selected.is_some(), egui::Button::new(label("Position")))
            .clicked()
            && let Some(joint) = selected
        {
            self.add_position_task(joint);
            ui.close();
        }
        if ui
            .add_enabled(selected.is_some(), egui::Button::new(label("Orientation")))
            .clicked()
            && let Some(joint) = selected
        {
            self.add_orientation_task(joint);
            ui.close();
        }
        if ui
            .add_enabled(
                selected.is_some(),
                egui::Button::new(label("Direction (keep an axis upright)")),
            )
            .on_hover_text(
                "keeps the segment's up axis along its present direction, the turn about it free; edit the axis and direction in the task list (e.g. a palm facing down)",
            )
            .clicked()
            && let Some(joint) = selected
        {
            self.add_direction_task(joint);
            ui.close();
        }
        if ui.button("Gaze (head looks at a point)").clicked() {
            self.add_gaze_task();
            ui.close();
        }
        if ui
            .button("Balance (centre of mass over the pinned feet)")
            .on_hover_text(
                "keeps the centre of mass inside the support polygon of the parts pinned on the floor, 2 cm from its edges; no constraint while it is inside",
            )
            .clicked()
        {
            let mut task = TaskSpec::new(TaskKindSpec::Balance {
                support: None,
                margin: DEFAULT_BALANCE_MARGIN,
            });
            task.level = 2;
            self.push_task(task);
            ui.close();
        }
        if ui
            .button("Centre of mass (a point over the floor)")
            .clicked()
        {
            let com = self.model.session.frames().center_of_mass();
            let mut task = TaskSpec::new(TaskKindSpec::Com {
                axes: Axes::XZ,
                target: [com.x, 0.0, com.z],
            });
            task.level = 2;
            self.push_task(task);
            ui.close();
        }
        if ui.button("Posture attraction (comfort)").clicked() {
            self.push_task(comfort_task());
            ui.close();
        }
        ui.separator();
        ui.label("Limb (closed form, with swivel)");
        for limb in [
            LimbName::LeftArm,
            LimbName::RightArm,
            LimbName::LeftLeg,
            LimbName::RightLeg,
        ] {
            if ui.button(limb.name().replace('_', " ")).clicked() {
                self.add_limb_task(limb);
                ui.close();
            }
        }
    }

    /// The level for a new task: below every task but the posture attraction.
    fn next_level(&self) -> u32 {
        self.model
            .session
            .tasks()
            .iter()
            .filter(|task| !matches!(task.kind, TaskKindSpec::Posture { .. }))
            .map(|task| task.level)
            .max()
            .unwrap_or(0)
            + 1
    }

    fn push_task(&mut self, task: TaskSpec) {
        let mut tasks = self.model.session.tasks().to_vec();
        tasks.push(task);
        self.model.apply(Command::SetTasks {
            kind: EditKind::Command,
            tasks,
        });
    }

    fn joint_name(&self, joint: usize) -> Option<String> {
        self.model
            .session
            .skeleton()
            .joints()
            .get(joint)
            .map(|joint| joint.name.clone())
    }

    pub(super) fn add_position_task(&mut self, joint: usize) {
        let (Some(name), Some(position)) = (
            self.joint_name(joint),
            self.model
                .session
                .frames()
                .joint_position
                .get(joint)
                .copied(),
        ) else {
            return;
        };
        let mut task = TaskSpec::new(TaskKindSpec::Position {
            joint: name,
            point: [0.0; 3],
            axes: Axes::XYZ,
            target: position.to_array(),
        });
        task.level = self.next_level();
        self.push_task(task);
    }

    pub(super) fn add_orientation_task(&mut self, joint: usize) {
        let Some(name) = self.joint_name(joint) else {
            return;
        };
        let rotation = joint_rotation(self.model.session.frames(), joint);
        let mut task = TaskSpec::new(TaskKindSpec::Orientation {
            joint: name,
            target: rotation.to_array(),
        });
        task.level = self.next_level();
        self.push_task(task);
    }

    pub(super) fn add_direction_task(&mut self, joint: usize) {
        let Some(name) = self.joint_name(joint) else {
            return;
        };
        let up = joint_rotation(self.model.session.frames(), joint) * DVec3::Y;
        let mut task = TaskSpec::new(TaskKindSpec::Direction {
            joint: name,
            axis: [0.0, 1.0, 0.0],
            target: up.to_array(),
        });
        task.level = self.next_level();
        self.push_task(task);
    }

    fn add_gaze_task(&mut self) {
        let Some(head) = self.model.session.skeleton().joint_index("skullbase") else {
            self.model
                .warn("This body has no head joint (skullbase) to aim.");
            return;
        };
        let frames = self.model.session.frames();
        let position = frames.joint_position.get(head).copied().unwrap_or_default();
        let forward = joint_rotation(frames, head) * DVec3::Z;
        let mut task = TaskSpec::new(TaskKindSpec::Gaze {
            joint: "skullbase".to_owned(),
            axis: [0.0, 0.0, 1.0],
            point: [0.0; 3],
            target: (position + forward * 1.5).to_array(),
        });
        task.level = self.next_level();
        self.push_task(task);
    }

    pub(super) fn add_limb_task(&mut self, limb: LimbName) {
        let end = limb.joints()[2];
        let Some(position) = self.model.session.joint_position(end) else {
            self.model.warn(format!("This body has no {end} joint."));
            return;
        };
        let swivel = self
            .model
            .session
            .limb_swivel(limb)
            .map(|(swivel, _)| swivel);
        let mut task = TaskSpec::new(TaskKindSpec::Limb {
            limb: Some(limb),
            joints: None,
            target: position.to_array(),
            swivel,
            orientation: None,
        });
        task.level = self.next_level();
        self.push_task(task);
    }

    /// The paper's Table 1 ([`PosingSession::table1_example`]).
    pub fn load_table1_example(&mut self) {
        let tasks = self.model.session.table1_example();
        self.model.apply(Command::SetTasks {
            kind: EditKind::Command,
            tasks,
        });
        self.model.inform("Table 1 of the paper: level 1 holds the left foot, the gaze and the right hand; balance is level 2; the left hand on the bar level 3.");
    }
}

/// One task's row: a collapsing header with its status, and its fields. Returns the kind of
/// edit when a field changed; sets `remove` when the task is to go.
fn task_editor(
    ui: &mut egui::Ui,
    index: usize,
    task: &mut TaskSpec,
    status: Option<&crate::posing::TaskStatus>,
    joint_names: &[String],
    remove: &mut Option<usize>,
) -> Option<EditKind> {
    let mut edit = None;
    let residual = status.and_then(|status| status.residual);
    let is_posture = matches!(task.kind, TaskKindSpec::Posture { .. });
    let (mark, color) = match status {
        _ if !task.active => ("off", INACTIVE_COLOR),
        Some(status) if status.problem.is_some() => ("error", PROBLEM_COLOR),
        Some(status) if status.gave_way.is_some() => ("not all met", GAVE_WAY_COLOR),
        _ => ("", MET_COLOR),
    };
    let residual_text = match residual {
        Some(_) if is_posture => String::new(),
        Some(value) if value < MET_TOLERANCE => "met".to_owned(),
        Some(value) if task_is_angular(task) => format!("{:.1}° off", value.to_degrees()),
        Some(value) => format!("{:.1} mm off", value * 1000.0),
        None => String::new(),
    };
    let header =
        RichText::new(format!("{}  {residual_text} {mark}", describe_task(task)).trim_end())
            .color(color);
    egui::CollapsingHeader::new(header)
        .id_salt(("task", index))
        .show(ui, |ui| {
            if let Some(status) = status {
                if let Some(problem) = &status.problem {
                    ui.colored_label(PROBLEM_COLOR, problem);
                }
                if let Some(reason) = &status.gave_way {
                    ui.colored_label(GAVE_WAY_COLOR, format!("gave way: {reason}"));
                }
            }
            egui::Grid::new(("task_fields", index))
                .num_columns(2)
                .show(ui, |ui| {
                    let label = ui.label("active");
                    if ui
                        .checkbox(&mut task.active, "")
                        .labelled_by(label.id)
                        .changed()
                    {
                        edit = Some(EditKind::TaskField(index, "active"));
                    }
                    ui.end_row();
                    let label = ui.label("level");
                    if ui
                        .add(
                            egui::DragValue::new(&mut task.level)
                                .range(1..=99)
                                .speed(0.05),
                        )
                        .labelled_by(label.id)
                        .changed()
                    {
                        edit = Some(EditKind::TaskField(index, "level"));
                    }
                    ui.end_row();
                    let label = ui.label("weight");
                    if ui
                        .add(
                            egui::DragValue::new(&mut task.weight)
                                .range(0.0..=100.0)
                                .speed(0.01)
                                .max_decimals(3),
                        )
                        .labelled_by(label.id)
                        .changed()
                    {
                        edit = Some(EditKind::TaskField(index, "weight"));
                    }
                    ui.end_row();
                    if let Some(kind) = kind_fields(ui, index, &mut task.kind, joint_names) {
                        edit = Some(kind);
                    }
                });
            if ui.button("Remove").clicked() {
                *remove = Some(index);
            }
        });
    edit
}

fn task_is_angular(task: &TaskSpec) -> bool {
    matches!(
        task.kind,
        TaskKindSpec::Orientation { .. }
            | TaskKindSpec::Gaze { .. }
            | TaskKindSpec::Direction { .. }
    )
}

fn kind_fields(
    ui: &mut egui::Ui,
    index: usize,
    kind: &mut TaskKindSpec,
    joint_names: &[String],
) -> Option<EditKind> {
    let mut edit = None;
    match kind {
        TaskKindSpec::Position {
            joint,
            point,
            axes,
            target,
        } => {
            if joint_row(ui, index, joint, joint_names) {
                edit = Some(EditKind::TaskField(index, "joint"));
            }
            ui.label("point")
                .on_hover_text("the point of the segment that is placed, in the joint's frame (m)");
            if vector_editor(ui, point, Axes::XYZ) {
                edit = Some(EditKind::TaskField(index, "point"));
            }
            ui.end_row();
            if let Some(changed) = axes_and_goal_rows(ui, index, axes, target) {
                edit = Some(changed);
            }
        }
        TaskKindSpec::Com { axes, target } => {
            if let Some(changed) = axes_and_goal_rows(ui, index, axes, target) {
                edit = Some(changed);
            }
        }
        TaskKindSpec::Gaze {
            joint,
            axis,
            point,
            target,
        } => {
            if joint_row(ui, index, joint, joint_names) {
                edit = Some(EditKind::TaskField(index, "joint"));
            }
            ui.label("axis")
                .on_hover_text("the direction that aims, in the joint's frame");
            if axis_editor(ui, axis) {
                edit = Some(EditKind::TaskField(index, "axis"));
            }
            ui.end_row();
            ui.label("eye")
                .on_hover_text("the point the aiming axis starts from, in the joint's frame (m)");
            if vector_editor(ui, point, Axes::XYZ) {
                edit = Some(EditKind::TaskField(index, "point"));
            }
            ui.end_row();
            ui.label("look at");
            if vector_editor(ui, target, Axes::XYZ) {
                edit = Some(EditKind::TaskField(index, "target"));
            }
            ui.end_row();
        }
        TaskKindSpec::Limb {
            limb,
            joints,
            target,
            swivel,
            ..
        } => {
            ui.label("limb");
            if limb_picker(ui, index, limb, joints) {
                edit = Some(EditKind::TaskField(index, "limb"));
            }
            ui.end_row();
            ui.label("goal");
            if vector_editor(ui, target, Axes::XYZ) {
                edit = Some(EditKind::TaskField(index, "target"));
            }
            ui.end_row();
            ui.label("swivel");
            let mut keep = swivel.is_none();
            ui.horizontal(|ui| {
                if ui.checkbox(&mut keep, "keep").changed() {
                    *swivel = if keep { None } else { Some(0.0) };
                    edit = Some(EditKind::TaskField(index, "swivel"));
                }
                if let Some(angle) = swivel {
                    let mut degrees = angle.to_degrees();
                    if ui
                        .add(
                            egui::DragValue::new(&mut degrees)
                                .range(-180.0..=180.0)
                                .suffix("°"),
                        )
                        .changed()
                    {
                        *angle = degrees.to_radians();
                        edit = Some(EditKind::TaskField(index, "swivel"));
                    }
                }
            });
            ui.end_row();
        }
        TaskKindSpec::Orientation { joint, target } => {
            if joint_row(ui, index, joint, joint_names) {
                edit = Some(EditKind::TaskField(index, "joint"));
            }
            ui.label("goal").on_hover_text(
                "the segment's orientation in the world: turns about x, then y, then z (degrees)",
            );
            if orientation_editor(ui, target) {
                edit = Some(EditKind::TaskField(index, "target"));
            }
            ui.end_row();
        }
        TaskKindSpec::Direction {
            joint,
            axis,
            target,
        } => {
            if joint_row(ui, index, joint, joint_names) {
                edit = Some(EditKind::TaskField(index, "joint"));
            }
            ui.label("axis")
                .on_hover_text("the segment's axis that is turned, in the joint's frame");
            if axis_editor(ui, axis) {
                edit = Some(EditKind::TaskField(index, "axis"));
            }
            ui.end_row();
            ui.label("along").on_hover_text(
                "the world direction the axis turns to (y up, z the body's front); the turn about it stays free",
            );
            if axis_editor(ui, target) {
                edit = Some(EditKind::TaskField(index, "target"));
            }
            ui.end_row();
        }
        TaskKindSpec::Balance { support, margin } => {
            ui.label("support");
            ui.label(match support {
                None => "the parts pinned on the floor".to_owned(),
                Some(joints) => joints
                    .iter()
                    .map(|joint| readable_name(joint))
                    .collect::<Vec<_>>()
                    .join(", "),
            });
            ui.end_row();
            ui.label("margin").on_hover_text(
                "how far inside the support polygon's edges the centre of mass stays",
            );
            let mut centimetres = *margin * 100.0;
            if ui
                .add(
                    egui::DragValue::new(&mut centimetres)
                        .range(0.0..=20.0)
                        .speed(0.1)
                        .suffix(" cm"),
                )
                .changed()
            {
                *margin = centimetres / 100.0;
                edit = Some(EditKind::TaskField(index, "margin"));
            }
            ui.end_row();
        }
        TaskKindSpec::Posture { .. } => {}
    }
    edit
}

/// The "joint" row: which joint's segment the task moves, by its readable name.
fn joint_row(ui: &mut egui::Ui, index: usize, joint: &mut String, joint_names: &[String]) -> bool {
    let label = ui.label("joint");
    let mut changed = false;
    let response = egui::ComboBox::from_id_salt(("task_joint", index))
        .selected_text(readable_name(joint))
        .height(320.0)
        .show_ui(ui, |ui| {
            for name in joint_names {
                let selected = name == joint;
                if ui
                    .selectable_label(selected, readable_name(name))
                    .on_hover_text(name)
                    .clicked()
                    && !selected
                {
                    joint.clone_from(name);
                    changed = true;
                }
            }
        });
    response.response.labelled_by(label.id);
    ui.end_row();
    changed
}

/// The limb of a limb task (left/right arm/leg).
fn limb_picker(
    ui: &mut egui::Ui,
    index: usize,
    limb: &mut Option<LimbName>,
    joints: &mut Option<[String; 3]>,
) -> bool {
    let current = match (limb.as_ref(), joints.as_ref()) {
        (Some(limb), _) => limb.name().replace('_', " "),
        (None, Some(joints)) => readable_name(&joints[2]),
        (None, None) => "limb".to_owned(),
    };
    let mut changed = false;
    egui::ComboBox::from_id_salt(("task_limb", index))
        .selected_text(current)
        .show_ui(ui, |ui| {
            for choice in [
                LimbName::LeftArm,
                LimbName::RightArm,
                LimbName::LeftLeg,
                LimbName::RightLeg,
            ] {
                let selected = *limb == Some(choice);
                if ui
                    .selectable_label(selected, choice.name().replace('_', " "))
                    .clicked()
                    && !selected
                {
                    *limb = Some(choice);
                    *joints = None;
                    changed = true;
                }
            }
        });
    changed
}

/// An aiming axis (unitless; any non-zero direction, normalised when used).
fn axis_editor(ui: &mut egui::Ui, axis: &mut [f64; 3]) -> bool {
    let mut edited = *axis;
    let mut changed = false;
    ui.horizontal(|ui| {
        for (value, name) in edited.iter_mut().zip(["x ", "y ", "z "]) {
            changed |= ui
                .add(
                    egui::DragValue::new(value)
                        .range(-1.0..=1.0)
                        .speed(0.01)
                        .max_decimals(3)
                        .prefix(name),
                )
                .changed();
        }
    });
    // A zero axis aims nowhere: that edit is refused.
    if changed && edited.iter().any(|value| value.abs() > 1e-6) {
        *axis = edited;
        return true;
    }
    false
}

/// A world orientation as three angles in degrees (turns about x, then y, then z, each about
/// the turned frame's axis), stored as the quaternion `[qx, qy, qz, qw]`.
fn orientation_editor(ui: &mut egui::Ui, quaternion: &mut [f64; 4]) -> bool {
    let rotation = DQuat::from_array(*quaternion).normalize();
    let (x, y, z) = rotation.to_euler(glam::EulerRot::XYZ);
    let mut degrees = [x.to_degrees(), y.to_degrees(), z.to_degrees()];
    let mut changed = false;
    ui.horizontal(|ui| {
        for (value, name) in degrees.iter_mut().zip(["x ", "y ", "z "]) {
            changed |= ui
                .add(
                    egui::DragValue::new(value)
                        .range(-180.0..=180.0)
                        .speed(0.5)
                        .max_decimals(1)
                        .prefix(name)
                        .suffix("°"),
                )
                .changed();
        }
    });
    if changed {
        let edited = DQuat::from_euler(
            glam::EulerRot::XYZ,
            degrees[0].to_radians(),
            degrees[1].to_radians(),
            degrees[2].to_radians(),
        );
        if edited.is_finite() {
            *quaternion = edited.to_array();
            return true;
        }
    }
    false
}

/// Moves the group of tasks at level `from` to the place of level `onto` (the last place when
/// `None`); the groups in between shift by one. The set of level numbers stays the same, so
/// the default gaps (1, 2, 10...) are kept.
fn reorder_levels(tasks: &mut [TaskSpec], levels: &[u32], from: u32, onto: Option<u32>) {
    let mut order: Vec<u32> = levels.to_vec();
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

/// The "axes" and "goal" rows of a position or centre-of-mass task.
fn axes_and_goal_rows(
    ui: &mut egui::Ui,
    index: usize,
    axes: &mut Axes,
    target: &mut [f64; 3],
) -> Option<EditKind> {
    let mut edit = None;
    ui.label("axes");
    if axes_editor(ui, axes) {
        edit = Some(EditKind::TaskField(index, "axes"));
    }
    ui.end_row();
    ui.label("goal");
    if vector_editor(ui, target, *axes) {
        edit = Some(EditKind::TaskField(index, "target"));
    }
    ui.end_row();
    edit
}

fn axes_editor(ui: &mut egui::Ui, axes: &mut Axes) -> bool {
    let mut flags = [axes.has(0), axes.has(1), axes.has(2)];
    let mut changed = false;
    ui.horizontal(|ui| {
        for (flag, name) in flags.iter_mut().zip(["x", "y", "z"]) {
            changed |= ui.toggle_value(flag, name).changed();
        }
    });
    if changed && flags.iter().any(|flag| *flag) {
        *axes = Axes::new(flags[0], flags[1], flags[2]);
        return true;
    }
    false
}

fn vector_editor(ui: &mut egui::Ui, vector: &mut [f64; 3], axes: Axes) -> bool {
    let mut changed = false;
    ui.horizontal(|ui| {
        for (component, value) in vector.iter_mut().enumerate() {
            ui.add_enabled_ui(axes.has(component), |ui| {
                changed |= ui
                    .add(
                        egui::DragValue::new(value)
                            .speed(0.005)
                            .max_decimals(3)
                            .prefix(["x ", "y ", "z "][component])
                            .suffix(" m"),
                    )
                    .changed();
            });
        }
    });
    changed
}
