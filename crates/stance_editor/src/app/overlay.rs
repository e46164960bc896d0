//! What the viewport draws over the 3D picture: task goals (met, gave way, inactive), the
//! pulled point and the cursor's goal, the centre of mass over its support polygon, the
//! collision task's contacts, and the trace of the pulled effector (the paper's figure 9).

use egui::{Color32, Pos2, Stroke};
use glam::DVec3;
use stance_document::TaskKindSpec;

use super::lens::Lens;
use crate::model::EditorModel;

const GOAL_MET: Color32 = Color32::from_rgb(90, 210, 120);
const GOAL_UNMET: Color32 = Color32::from_rgb(240, 150, 50);
const GOAL_INACTIVE: Color32 = Color32::from_gray(140);
const PULL_COLOR: Color32 = Color32::from_rgb(250, 230, 80);
const COM_COLOR: Color32 = Color32::from_rgb(120, 200, 255);
const TRACE_COLOR: Color32 = Color32::from_rgba_premultiplied(200, 120, 250, 200);
const TRAJECTORY_COLOR: Color32 = Color32::from_rgb(90, 220, 230);
const CONTACT_COLOR: Color32 = Color32::from_rgb(255, 70, 70);

/// What is drawn over the 3D picture, from the model, through the viewport's lens.
#[derive(Debug, Clone, Copy)]
pub(super) struct Overlay<'a> {
    pub model: &'a EditorModel,
    pub lens: Lens<'a>,
    /// Whether the pulled effector's trace shows.
    pub show_trace: bool,
}

impl Overlay<'_> {
    pub(super) fn draw(&self, painter: &egui::Painter) {
        let painter = painter.with_clip_rect(self.lens.rect);
        if self.show_trace {
            self.draw_trace(&painter);
        }
        self.draw_trajectory(&painter);
        if let Some(polygon) = self.draw_goals(&painter) {
            self.draw_balance(&painter, &polygon);
        }
        self.draw_pull(&painter);
        self.draw_contacts(&painter);
    }

    /// The collision task's contacts: the two closest points of each pair of surfaces held
    /// apart (or of a surface and the floor), joined.
    fn draw_contacts(&self, painter: &egui::Painter) {
        for contact in self.model.session().contacts() {
            let (a, b) = contact.points;
            if let (Some(a), Some(b)) = (self.lens.screen_point(a), self.lens.screen_point(b)) {
                painter.line_segment([a, b], Stroke::new(2.0, CONTACT_COLOR));
                painter.circle_filled(a, 3.0, CONTACT_COLOR);
                painter.circle_filled(b, 3.0, CONTACT_COLOR);
            }
        }
    }

    /// The trace of the pulled point (the paper's figure 9).
    fn draw_trace(&self, painter: &egui::Painter) {
        if self.model.trace().len() > 1 {
            let points: Vec<Pos2> = self
                .model
                .trace()
                .iter()
                .filter_map(|point| self.lens.screen_point(*point))
                .collect();
            painter.add(egui::Shape::line(points, Stroke::new(2.0, TRACE_COLOR)));
        }
    }

    /// The timeline's trajectory joint over every frame, with a dot at the playhead.
    fn draw_trajectory(&self, painter: &egui::Painter) {
        let timeline = self.model.timeline();
        let trajectory = timeline.trajectory();
        if trajectory.len() > 1 {
            let points: Vec<Pos2> = trajectory
                .iter()
                .filter_map(|point| self.lens.screen_point(*point))
                .collect();
            painter.add(egui::Shape::line(
                points,
                Stroke::new(1.5, TRAJECTORY_COLOR),
            ));
        }
        if let Some(here) = trajectory
            .get(timeline.frame())
            .and_then(|point| self.lens.screen_point(*point))
        {
            painter.circle_filled(here, 4.0, TRAJECTORY_COLOR);
        }
    }

    /// Each task's goal, coloured by its status. Returns the balance's support polygon when a
    /// balance or centre-of-mass task is active (empty for a centre-of-mass task).
    fn draw_goals(&self, painter: &egui::Painter) -> Option<Vec<DVec3>> {
        let skeleton = self.model.session().skeleton();
        let frames = self.model.session().frames();
        let mut has_balance = false;
        let mut polygon = Vec::new();
        for (task, status) in self
            .model
            .session()
            .tasks()
            .iter()
            .zip(self.model.session().statuses())
        {
            let color = if !task.active {
                GOAL_INACTIVE
            } else if status.gave_way.is_some() || status.problem.is_some() {
                GOAL_UNMET
            } else {
                GOAL_MET
            };
            match &task.kind {
                TaskKindSpec::Position {
                    joint,
                    point,
                    target,
                    ..
                } => {
                    let Some(index) = skeleton.joint_index(joint) else {
                        continue;
                    };
                    let effector = frames.point(index, DVec3::from_array(*point));
                    let goal = DVec3::from_array(*target);
                    self.goal_marker(painter, effector, goal, color, task.level == 1);
                }
                TaskKindSpec::Limb { target, limb, .. } => {
                    let end = limb.map(|limb| limb.joints()[2]);
                    if let Some(effector) =
                        end.and_then(|end| self.model.session().joint_position(end))
                    {
                        self.goal_marker(
                            painter,
                            effector,
                            DVec3::from_array(*target),
                            color,
                            false,
                        );
                    }
                }
                TaskKindSpec::Gaze { target, .. } => {
                    if let Some(goal) = self.lens.screen_point(DVec3::from_array(*target)) {
                        painter.circle_stroke(goal, 7.0, Stroke::new(2.0, color));
                        painter.circle_filled(goal, 2.5, color);
                    }
                }
                TaskKindSpec::Com { .. } => has_balance |= task.active,
                TaskKindSpec::Balance { .. } if task.active => {
                    has_balance = true;
                    if let Ok(solver_task) = task.to_task(skeleton, self.model.session().tasks()) {
                        polygon = solver_task.support_polygon(frames);
                    }
                }
                _ => {}
            }
        }

        has_balance.then_some(polygon)
    }

    /// The pulled point and where the cursor wants it.
    fn draw_pull(&self, painter: &egui::Painter) {
        if let (Some(grab), Some(point)) = (
            self.model.session().grab(),
            self.model.session().grabbed_point_world(),
        ) && let (Some(from), Some(to)) = (
            self.lens.screen_point(point),
            self.lens.screen_point(grab.target_world),
        ) {
            painter.line_segment([from, to], Stroke::new(1.5, PULL_COLOR));
            painter.circle_filled(from, 4.0, PULL_COLOR);
            painter.circle_stroke(to, 6.0, Stroke::new(2.0, PULL_COLOR));
        }
    }

    fn goal_marker(
        &self,
        painter: &egui::Painter,
        effector: DVec3,
        goal: DVec3,
        color: Color32,
        pinned: bool,
    ) {
        let Some(goal_px) = self.lens.screen_point(goal) else {
            return;
        };
        if (effector - goal).length() > 1e-3
            && let Some(effector_px) = self.lens.screen_point(effector)
        {
            painter.line_segment([effector_px, goal_px], Stroke::new(1.5, color));
        }
        if pinned {
            let half = egui::vec2(4.5, 4.5);
            painter.rect_filled(
                egui::Rect::from_min_max(goal_px - half, goal_px + half),
                1.0,
                color,
            );
        } else {
            painter.circle_stroke(goal_px, 5.0, Stroke::new(2.0, color));
        }
    }

    /// The centre of mass, its projection on the floor, and the support polygon of the balance
    /// task (as the solver sees it), if there is one.
    fn draw_balance(&self, painter: &egui::Painter, polygon: &[DVec3]) {
        let com = self.model.session().frames().center_of_mass();
        let floor_com = DVec3::new(com.x, 0.0, com.z);
        if polygon.len() >= 2 {
            let mut points: Vec<Pos2> = polygon
                .iter()
                .filter_map(|corner| self.lens.screen_point(*corner))
                .collect();
            if let Some(first) = points.first().copied() {
                points.push(first);
            }
            painter.add(egui::Shape::line(points, Stroke::new(1.5, COM_COLOR)));
        }
        if let (Some(com_px), Some(floor_px)) = (
            self.lens.screen_point(com),
            self.lens.screen_point(floor_com),
        ) {
            painter.line_segment(
                [com_px, floor_px],
                Stroke::new(1.0, COM_COLOR.gamma_multiply(0.6)),
            );
            painter.circle_stroke(com_px, 6.0, Stroke::new(2.0, COM_COLOR));
            painter.line_segment(
                [com_px - egui::vec2(6.0, 0.0), com_px + egui::vec2(6.0, 0.0)],
                Stroke::new(1.5, COM_COLOR),
            );
            painter.line_segment(
                [com_px - egui::vec2(0.0, 6.0), com_px + egui::vec2(0.0, 6.0)],
                Stroke::new(1.5, COM_COLOR),
            );
            painter.circle_filled(floor_px, 3.5, COM_COLOR);
        }
    }

    /// The skeleton over the avatar: a line per bone, a dot per joint.
    pub(super) fn draw_skeleton(&self, painter: &egui::Painter) {
        let skeleton = self.model.session().skeleton();
        let frames = self.model.session().frames();
        let stroke = Stroke::new(1.5, Color32::from_rgba_unmultiplied(255, 255, 255, 170));
        for (index, joint) in skeleton.joints().iter().enumerate() {
            let Some(position) = frames.joint_position.get(index).copied() else {
                continue;
            };
            let Some(here) = self.lens.screen_point(position) else {
                continue;
            };
            if let Some(parent) = joint.parent
                && let Some(parent_position) = frames.joint_position.get(parent).copied()
                && let Some(there) = self.lens.screen_point(parent_position)
            {
                painter.line_segment([there, here], stroke);
            }
            let color = if Some(index) == self.model.selected_joint() {
                Color32::from_rgb(80, 160, 255)
            } else {
                Color32::WHITE
            };
            painter.circle_filled(here, 2.5, color);
        }
    }
}
