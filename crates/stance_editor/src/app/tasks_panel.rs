//! The tasks panel: tasks by priority level, with their status and the reason a task gave
//! way; editing every field, adding (from where the body stands), removing, and reordering
//! tasks and whole levels by dragging.

use crate::model::Outbox;
use crate::model::TaskCommand;
use egui::{Color32, RichText};
use glam::DQuat;
use stance_document::{LimbName, TaskKindSpec, TaskSpec};
use stance_hanim::readable_name;
use stance_ik::Axes;

use super::ButtonRects;
use crate::history::EditKind;
use crate::model::{Command, EditorModel, NewTask};
use crate::posing::{MET_TOLERANCE, TaskStatus};

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

/// What the user did in the panel this frame (at most one change of the task list).
#[derive(Debug, Clone, PartialEq)]
enum Action {
    /// A field changed (the list already holds it).
    Edit(EditKind),
    Remove(usize),
    /// A task dropped onto a level.
    MoveTask(usize, u32),
    SwapLevels(u32, u32),
    /// A level dropped onto another level's place (`None`: made the lowest).
    MoveLevel(u32, Option<u32>),
}

/// The tasks panel over the model.
pub(super) struct TasksPanel<'a> {
    pub model: &'a EditorModel,
    pub outbox: &'a mut Outbox,
    pub buttons: &'a mut ButtonRects,
}

impl TasksPanel<'_> {
    /// The panel: the add menu and Table 1, then each level with its tasks.
    pub(super) fn show(&mut self, ui: &mut egui::Ui) {
        ui.heading("Tasks");
        ui.label(
            RichText::new("Level 1 is obeyed first; a lower level only uses what is left.").small(),
        );
        ui.horizontal(|ui| {
            let mut added = None;
            ui.menu_button("Add task", |ui| added = add_task_menu(ui, self.model));
            if let Some(what) = added {
                self.outbox.send(Command::Task(TaskCommand::Add(what)));
            }
            let table1 = ui
                .button("Table 1 example")
                .on_hover_text("the paper's example: foot, gaze and hand at level 1, balance at 2, other hand at 3");
            self.buttons.push(("table1", table1.rect));
            if table1.clicked() {
                self.outbox.send(Command::Task(TaskCommand::LoadTable1Example));
            }
        });
        let mut collision = self.model.session().collision_on();
        let toggle = ui
            .checkbox(&mut collision, "Collision (body and floor)")
            .on_hover_text(
                "the body's capsules kept apart from each other and above the floor, just below the pins",
            );
        self.buttons.push(("collision", toggle.rect));
        if toggle.changed() {
            self.outbox
                .send(Command::Task(TaskCommand::SetCollision(collision)));
        }
        ui.separator();
        let session = self.model.session();
        let mut tasks = session.tasks().to_vec();
        let statuses = session.statuses().to_vec();
        let joint_names: Vec<String> = session
            .skeleton()
            .joints()
            .iter()
            .map(|joint| joint.name.clone())
            .collect();
        let mut levels: Vec<u32> = tasks.iter().map(|task| task.level).collect();
        levels.sort_unstable();
        levels.dedup();
        let mut action = None;
        for position in 0..levels.len() {
            let zone = LevelZone {
                levels: &levels,
                position,
                statuses: &statuses,
                joint_names: &joint_names,
            };
            if let Some(done) = zone.show(ui, &mut tasks) {
                action = Some(done);
            }
        }
        if let Some(done) = lowest_level_zone(ui, &levels) {
            action = Some(done);
        }
        if let Some(action) = action {
            self.send(action, tasks);
        }
    }

    /// Sends the panel's action: a field edit as the edited list `tasks`, the rest as the
    /// task-list edit it is (the model computes the list).
    fn send(&mut self, action: Action, tasks: Vec<TaskSpec>) {
        let command = match action {
            Action::Edit(kind) => TaskCommand::Set { kind, tasks },
            Action::Remove(index) => TaskCommand::Remove(index),
            Action::MoveTask(task, level) => TaskCommand::MoveToLevel { task, level },
            Action::MoveLevel(from, onto) => TaskCommand::MoveLevel { from, onto },
            Action::SwapLevels(a, b) => TaskCommand::SwapLevels(a, b),
        };
        self.outbox.send(Command::Task(command));
    }
}

/// One level's drop zone: its header (drag, up, down) and its tasks.
struct LevelZone<'a> {
    levels: &'a [u32],
    position: usize,
    statuses: &'a [TaskStatus],
    joint_names: &'a [String],
}

impl LevelZone<'_> {
    fn show(&self, ui: &mut egui::Ui, tasks: &mut [TaskSpec]) -> Option<Action> {
        let level = self.levels[self.position];
        let members: Vec<usize> = (0..tasks.len())
            .filter(|&index| tasks[index].level == level)
            .collect();
        let level_met = members.iter().all(|&index| {
            !tasks[index].active
                || tasks[index].kind.is_soft()
                || self
                    .statuses
                    .get(index)
                    .is_some_and(|status| status.gave_way.is_none() && status.problem.is_none())
        });
        let mut action = None;
        let frame = egui::Frame::new().inner_margin(4.0).corner_radius(4.0);
        let (_, dropped) = ui.dnd_drop_zone::<Dragged, ()>(frame, |ui| {
            if let Some(done) = self.header(ui, level_met) {
                action = Some(done);
            }
            for &index in &members {
                if let Some(done) = self.task_row(ui, index, &mut tasks[index]) {
                    action = Some(done);
                }
            }
        });
        match dropped.as_deref() {
            Some(Dragged::Task(index)) => Some(Action::MoveTask(*index, level)),
            Some(Dragged::Level(from)) if *from != level => {
                Some(Action::MoveLevel(*from, Some(level)))
            }
            _ => action,
        }
    }

    /// "Level n", whether all of it is met, and the up/down buttons.
    fn header(&self, ui: &mut egui::Ui, level_met: bool) -> Option<Action> {
        let (levels, position) = (self.levels, self.position);
        let level = levels[position];
        let mut action = None;
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
                    .on_hover_text("raise this level's priority (swap with the level above)")
                    .clicked()
            {
                action = Some(Action::SwapLevels(level, levels[position - 1]));
            }
            if position + 1 < levels.len()
                && ui
                    .small_button("down")
                    .on_hover_text("lower this level's priority (swap with the level below)")
                    .clicked()
            {
                action = Some(Action::SwapLevels(level, levels[position + 1]));
            }
        });
        action
    }

    /// One task: its drag handle and its editor.
    fn task_row(&self, ui: &mut egui::Ui, index: usize, task: &mut TaskSpec) -> Option<Action> {
        let status = self.statuses.get(index).cloned();
        let id = egui::Id::NULL.with(("stance_task_drag", index));
        let mut action = None;
        // Only the handle drags the task: a drag source senses the press at once, which would
        // take the clicks of the header and the fields under it.
        ui.horizontal_top(|ui| {
            ui.dnd_drag_source(id, Dragged::Task(index), |ui| {
                ui.label(RichText::new("::").strong());
            })
            .response
            .on_hover_text("drag onto another level");
            ui.vertical(|ui| {
                let mut remove = None;
                if let Some(kind) = task_editor(
                    ui,
                    index,
                    task,
                    status.as_ref(),
                    self.joint_names,
                    &mut remove,
                ) {
                    action = Some(Action::Edit(kind));
                }
                if let Some(index) = remove {
                    action = Some(Action::Remove(index));
                }
            });
        });
        action
    }
}

/// The zone below the last level: a task dropped there makes a new lowest level, a level
/// dropped there becomes the lowest.
fn lowest_level_zone(ui: &mut egui::Ui, levels: &[u32]) -> Option<Action> {
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
        Some(Dragged::Task(index)) => Some(Action::MoveTask(*index, lowest)),
        Some(Dragged::Level(from)) => Some(Action::MoveLevel(*from, None)),
        None => None,
    }
}

/// Makes a new task on a joint.
type TaskOnJoint = fn(usize) -> NewTask;

/// The *Add task* menu: what to add, made from where the body stands.
fn add_task_menu(ui: &mut egui::Ui, model: &EditorModel) -> Option<NewTask> {
    let selected = model.selected_joint();
    let selected_name = selected
        .and_then(|joint| model.session().skeleton().joints().get(joint))
        .map(|joint| readable_name(&joint.name));
    let label = |what: &str| match &selected_name {
        Some(name) => format!("{what} of the {name}"),
        None => format!("{what} (select a body part first)"),
    };
    let on_selected: [(&str, &str, TaskOnJoint); 3] = [
        ("Position", "holds the part where it is", NewTask::Position),
        (
            "Orientation",
            "holds the part's orientation",
            NewTask::Orientation,
        ),
        (
            "Direction (keep an axis upright)",
            "keeps the segment's up axis along its present direction, the turn about it free; edit the axis and direction in the task list (e.g. a palm facing down)",
            NewTask::Direction,
        ),
    ];
    let mut chosen = None;
    for (what, hover, make) in on_selected {
        if ui
            .add_enabled(selected.is_some(), egui::Button::new(label(what)))
            .on_hover_text(hover)
            .clicked()
            && let Some(joint) = selected
        {
            chosen = Some(make(joint));
        }
    }
    let whole_body = [
        (
            "Gaze (head looks at a point)",
            "the head looks 1.5 m ahead; drag the goal",
            NewTask::Gaze,
        ),
        (
            "Balance (centre of mass over the pinned feet)",
            "keeps the centre of mass inside the support polygon of the parts pinned on the floor, 2 cm from its edges; no constraint while it is inside",
            NewTask::Balance,
        ),
        (
            "Centre of mass (a point over the floor)",
            "holds the centre of mass over the floor point under it now",
            NewTask::CentreOfMass,
        ),
        (
            "Comfort (effort, joint ranges, RULA)",
            "lowers the joint loads against gravity, the joints near the ends of their ranges and the RULA score, at the lowest level, with whatever freedom the other tasks leave",
            NewTask::Comfort,
        ),
        (
            "Posture attraction (rest)",
            "draws the joints toward the rest posture at the lowest level",
            NewTask::RestPosture,
        ),
    ];
    for (what, hover, task) in whole_body {
        if ui.button(what).on_hover_text(hover).clicked() {
            chosen = Some(task);
        }
    }
    ui.separator();
    ui.label("Limb (closed form, with swivel)");
    for limb in LimbName::ALL {
        if ui.button(limb.name().replace('_', " ")).clicked() {
            chosen = Some(NewTask::Limb(limb));
        }
    }
    if chosen.is_some() {
        ui.close();
    }
    chosen
}

/// One task's row: a collapsing header with its status, and its fields. Returns the kind of
/// edit when a field changed; sets `remove` when the task is to go.
fn task_editor(
    ui: &mut egui::Ui,
    index: usize,
    task: &mut TaskSpec,
    status: Option<&TaskStatus>,
    joint_names: &[String],
    remove: &mut Option<usize>,
) -> Option<EditKind> {
    let mut edit = None;
    let residual = status.and_then(|status| status.residual);
    let is_soft = task.kind.is_soft();
    let (mark, color) = match status {
        _ if !task.active => ("off", INACTIVE_COLOR),
        Some(status) if status.problem.is_some() => ("error", PROBLEM_COLOR),
        Some(status) if status.gave_way.is_some() => ("not all met", GAVE_WAY_COLOR),
        _ => ("", MET_COLOR),
    };
    let residual_text = match residual {
        Some(_) if is_soft => String::new(),
        Some(value) if value < MET_TOLERANCE => "met".to_owned(),
        Some(value) if task_is_angular(task) => format!("{:.1}° off", value.to_degrees()),
        Some(value) => format!("{:.1} mm off", value * 1000.0),
        None => String::new(),
    };
    let header =
        RichText::new(format!("{}  {residual_text} {mark}", task.description()).trim_end())
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
                    if let Some(kind) = common_fields(ui, index, task) {
                        edit = Some(kind);
                    }
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

/// Active, level and weight.
fn common_fields(ui: &mut egui::Ui, index: usize, task: &mut TaskSpec) -> Option<EditKind> {
    let mut rows = FieldRows {
        ui,
        index,
        joint_names: &[],
        edit: None,
    };
    rows.row("active", "", "active", |ui, label| {
        ui.checkbox(&mut task.active, "")
            .labelled_by(label)
            .changed()
    });
    rows.row("level", "1 is obeyed first", "level", |ui, label| {
        ui.add(
            egui::DragValue::new(&mut task.level)
                .range(1..=99)
                .speed(0.05),
        )
        .labelled_by(label)
        .changed()
    });
    rows.row("weight", "within its level", "weight", |ui, label| {
        ui.add(
            egui::DragValue::new(&mut task.weight)
                .range(0.0..=100.0)
                .speed(0.01)
                .max_decimals(3),
        )
        .labelled_by(label)
        .changed()
    });
    rows.edit
}

fn task_is_angular(task: &TaskSpec) -> bool {
    matches!(
        task.kind,
        TaskKindSpec::Orientation { .. }
            | TaskKindSpec::Gaze { .. }
            | TaskKindSpec::Direction { .. }
    )
}

/// Rows of a task's fields in its grid; remembers which field changed.
struct FieldRows<'a> {
    ui: &'a mut egui::Ui,
    index: usize,
    joint_names: &'a [String],
    edit: Option<EditKind>,
}

impl FieldRows<'_> {
    /// One row: a label (with a hover explanation when given) and its editor, which says
    /// whether `field` changed.
    fn row(
        &mut self,
        label: &str,
        hover: &str,
        field: &'static str,
        editor: impl FnOnce(&mut egui::Ui, egui::Id) -> bool,
    ) {
        let mut response = self.ui.label(label);
        if !hover.is_empty() {
            response = response.on_hover_text(hover);
        }
        if editor(self.ui, response.id) {
            self.edit = Some(EditKind::TaskField(self.index, field));
        }
        self.ui.end_row();
    }

    fn joint(&mut self, joint: &mut String) {
        if joint_row(self.ui, self.index, joint, self.joint_names) {
            self.edit = Some(EditKind::TaskField(self.index, "joint"));
        }
    }

    /// The head (or segment) that aims, its axis, its eye and the point it looks at.
    fn gaze(
        &mut self,
        joint: &mut String,
        axis: &mut [f64; 3],
        point: &mut [f64; 3],
        target: &mut [f64; 3],
    ) {
        self.joint(joint);
        self.row(
            "axis",
            "the direction that aims, in the joint's frame",
            "axis",
            |ui, _| axis_editor(ui, axis),
        );
        self.row(
            "eye",
            "the point the aiming axis starts from, in the joint's frame (m)",
            "point",
            |ui, _| vector_editor(ui, point, Axes::XYZ),
        );
        self.row("look at", "", "target", |ui, _| {
            vector_editor(ui, target, Axes::XYZ)
        });
    }

    /// The segment, its axis and the world direction the axis turns to.
    fn direction(&mut self, joint: &mut String, axis: &mut [f64; 3], target: &mut [f64; 3]) {
        self.joint(joint);
        self.row(
            "axis",
            "the segment's axis that is turned, in the joint's frame",
            "axis",
            |ui, _| axis_editor(ui, axis),
        );
        self.row(
            "along",
            "the world direction the axis turns to (y up, z the body's front); the turn about it stays free",
            "target",
            |ui, _| axis_editor(ui, target),
        );
    }

    /// The limb, its goal and its swivel.
    fn limb(
        &mut self,
        limb: &mut Option<LimbName>,
        joints: &mut Option<[String; 3]>,
        target: &mut [f64; 3],
        swivel: &mut Option<f64>,
    ) {
        let index = self.index;
        self.row("limb", "", "limb", |ui, _| {
            limb_picker(ui, index, limb, joints)
        });
        self.row("goal", "", "target", |ui, _| {
            vector_editor(ui, target, Axes::XYZ)
        });
        self.row(
            "swivel",
            "the elbow or knee around the shoulder-wrist (hip-ankle) axis; keep: as it is",
            "swivel",
            |ui, _| swivel_editor(ui, swivel),
        );
    }

    /// The support (named joints, or the pinned parts) and the margin.
    fn balance(&mut self, support: Option<&[String]>, margin: &mut f64) {
        let support_text = match support {
            None => "the parts pinned on the floor".to_owned(),
            Some(joints) => joints
                .iter()
                .map(|joint| readable_name(joint))
                .collect::<Vec<_>>()
                .join(", "),
        };
        self.row("support", "", "support", |ui, _| {
            ui.label(support_text);
            false
        });
        self.row(
            "margin",
            "how far inside the support polygon's edges the centre of mass stays",
            "margin",
            |ui, _| margin_editor(ui, margin),
        );
    }

    fn comfort(&mut self, effort: &mut f64, range: &mut f64, rula: &mut f64) {
        self.row(
            "effort",
            "weight of the joint loads against gravity, as shares of each joint's strength",
            "effort",
            |ui, _| comfort_weight_editor(ui, effort),
        );
        self.row(
            "joint ranges",
            "weight of the discomfort of joints near the ends of their ranges",
            "range",
            |ui, _| comfort_weight_editor(ui, range),
        );
        self.row(
            "RULA",
            "weight of a smooth stand-in for the RULA score (upper arm, lower arm, wrist, neck, trunk)",
            "rula",
            |ui, _| comfort_weight_editor(ui, rula),
        );
    }

    fn axes_and_goal(&mut self, axes: &mut Axes, target: &mut [f64; 3]) {
        if let Some(changed) = axes_and_goal_rows(self.ui, self.index, axes, target) {
            self.edit = Some(changed);
        }
    }
}

/// The fields of the task's kind.
fn kind_fields(
    ui: &mut egui::Ui,
    index: usize,
    kind: &mut TaskKindSpec,
    joint_names: &[String],
) -> Option<EditKind> {
    let mut rows = FieldRows {
        ui,
        index,
        joint_names,
        edit: None,
    };
    match kind {
        TaskKindSpec::Position {
            joint,
            point,
            axes,
            target,
        } => {
            rows.joint(joint);
            rows.row(
                "point",
                "the point of the segment that is placed, in the joint's frame (m)",
                "point",
                |ui, _| vector_editor(ui, point, Axes::XYZ),
            );
            rows.axes_and_goal(axes, target);
        }
        TaskKindSpec::Com { axes, target } => rows.axes_and_goal(axes, target),
        TaskKindSpec::Gaze {
            joint,
            axis,
            point,
            target,
        } => rows.gaze(joint, axis, point, target),
        TaskKindSpec::Limb {
            limb,
            joints,
            target,
            swivel,
            ..
        } => rows.limb(limb, joints, target, swivel),
        TaskKindSpec::Orientation { joint, target } => {
            rows.joint(joint);
            rows.row(
                "goal",
                "the segment's orientation in the world: turns about x, then y, then z (degrees)",
                "target",
                |ui, _| orientation_editor(ui, target),
            );
        }
        TaskKindSpec::Direction {
            joint,
            axis,
            target,
        } => rows.direction(joint, axis, target),
        TaskKindSpec::Balance { support, margin } => rows.balance(support.as_deref(), margin),
        // No fields of their own in the panel yet (made by `stance lift`, or problem files).
        TaskKindSpec::Posture { .. }
        | TaskKindSpec::Line { .. }
        | TaskKindSpec::Plane { .. }
        | TaskKindSpec::Collision { .. } => {}
        TaskKindSpec::Comfort {
            effort,
            range,
            rula,
        } => rows.comfort(effort, range, rula),
    }
    rows.edit
}

/// A comfort term's weight (0 turns it off).
fn comfort_weight_editor(ui: &mut egui::Ui, weight: &mut f64) -> bool {
    ui.add(
        egui::DragValue::new(weight)
            .range(0.0..=10.0)
            .speed(0.01)
            .max_decimals(3),
    )
    .changed()
}

/// A limb's swivel angle: kept as it is, or set (degrees).
fn swivel_editor(ui: &mut egui::Ui, swivel: &mut Option<f64>) -> bool {
    let mut changed = false;
    let mut keep = swivel.is_none();
    ui.horizontal(|ui| {
        if ui.checkbox(&mut keep, "keep").changed() {
            *swivel = if keep { None } else { Some(0.0) };
            changed = true;
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
                changed = true;
            }
        }
    });
    changed
}

/// A balance margin (m), edited in centimetres.
fn margin_editor(ui: &mut egui::Ui, margin: &mut f64) -> bool {
    let mut centimetres = *margin * 100.0;
    let changed = ui
        .add(
            egui::DragValue::new(&mut centimetres)
                .range(0.0..=20.0)
                .speed(0.1)
                .suffix(" cm"),
        )
        .changed();
    if changed {
        *margin = centimetres / 100.0;
    }
    changed
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
