//! Handles in the viewport: the goals of tasks, dragged in the plane facing the camera, the
//! ring gizmo of the selected joint, one ring per rotational DOF, dragged around it, and the
//! swivel handle of the selected arm or leg, at the elbow or knee, dragged around the
//! shoulder-wrist (hip-ankle) axis.

use egui::{Color32, Pos2, Stroke};
use glam::DVec3;
use stance_document::{LimbName, TaskKindSpec};
use stance_ik::SwivelInterval;

use super::lens::{Lens, screen_angle};
use crate::model::EditorModel;
use crate::model::Gesture;

/// How close (points) the pointer must be to a handle to take it.
const HANDLE_REACH_PT: f32 = 9.0;
/// Radius of the rings of the joint gizmo (m).
const RING_RADIUS_M: f64 = 0.11;
/// Points per drawn ring.
const RING_SEGMENTS: usize = 48;
/// Ring colours by DOF axis (x, y, z).
const RING_COLORS: [Color32; 3] = [
    Color32::from_rgb(235, 80, 80),
    Color32::from_rgb(90, 200, 90),
    Color32::from_rgb(80, 130, 240),
];

/// Colour of the swivel handle and its circle.
const SWIVEL_COLOR: Color32 = Color32::from_rgb(240, 200, 60);
/// Colour of the swivel angles that keep the limb within its limits.
const SWIVEL_FEASIBLE_COLOR: Color32 = Color32::from_rgb(90, 200, 120);
/// Radius of the swivel handle's disc (points).
const SWIVEL_HANDLE_PT: f32 = 6.0;
/// Below this distance from the shoulder-wrist axis (m) the limb is straight: turning it
/// around the axis moves nothing, and there is no handle.
const SWIVEL_MIN_RADIUS_M: f64 = 0.01;

/// The swivel handle of the selected arm or leg.
#[derive(Debug, Clone)]
pub(super) struct SwivelHandle {
    pub limb: LimbName,
    /// The elbow or knee, where the handle is.
    pub middle_world: DVec3,
    /// The centre of the circle the middle joint turns on (on the shoulder-wrist axis).
    pub centre_world: DVec3,
    /// Unit shoulder-to-wrist (hip-to-ankle) direction.
    pub axis_world: DVec3,
    /// Distance of the middle joint from the axis (m).
    pub radius: f64,
    /// The swivel angle now (rad).
    pub swivel: f64,
    /// Swivel angles that keep the limb within its limits.
    pub intervals: Vec<SwivelInterval>,
}

impl SwivelHandle {
    /// The point of the circle at swivel angle `angle` (the handle at the current angle;
    /// the swivel turns right-handed about the axis).
    pub fn point_at(&self, angle: f64) -> DVec3 {
        let u = (self.middle_world - self.centre_world) / self.radius;
        let v = self.axis_world.cross(u);
        let turn = angle - self.swivel;
        self.centre_world + (u * turn.cos() + v * turn.sin()) * self.radius
    }
}

/// One ring of the gizmo.
#[derive(Debug, Clone, Copy)]
pub(super) struct Ring {
    pub dof: usize,
    pub axis_index: usize,
    pub centre_world: DVec3,
    pub axis_world: DVec3,
}

/// The handles of the model's tasks and selection, seen through the viewport's lens.
#[derive(Debug, Clone, Copy)]
pub(super) struct Handles<'a> {
    pub model: &'a EditorModel,
    pub lens: Lens<'a>,
}

impl Handles<'_> {
    /// Tasks whose goal can be dragged, with the goal's world position.
    pub(super) fn goal_handles(&self) -> Vec<(usize, DVec3)> {
        self.model
            .session()
            .tasks()
            .iter()
            .enumerate()
            .filter_map(|(index, task)| match &task.kind {
                TaskKindSpec::Position { target, .. }
                | TaskKindSpec::Gaze { target, .. }
                | TaskKindSpec::Limb { target, .. } => Some((index, DVec3::from_array(*target))),
                TaskKindSpec::Com { target, .. } => {
                    Some((index, DVec3::new(target[0], 0.0, target[2])))
                }
                _ => None,
            })
            .collect()
    }

    /// The rings of the selected joint's rotational DOF.
    pub(super) fn rings(&self) -> Vec<Ring> {
        let Some(joint_index) = self.model.selected_joint() else {
            return Vec::new();
        };
        let skeleton = self.model.session().skeleton();
        let frames = self.model.session().frames();
        let Some(joint) = skeleton.joints().get(joint_index) else {
            return Vec::new();
        };
        let Some(centre_world) = frames.joint_position.get(joint_index).copied() else {
            return Vec::new();
        };
        joint
            .dofs
            .iter()
            .enumerate()
            .filter(|(_, dof)| dof.is_rotation())
            .filter_map(|(offset, dof)| {
                let index = joint.dof_start + offset;
                let axis_world = frames.dof_axis.get(index)?.normalize_or_zero();
                (axis_world != DVec3::ZERO).then_some(Ring {
                    dof: index,
                    axis_index: dof.axis_index(),
                    centre_world,
                    axis_world,
                })
            })
            .collect()
    }

    /// The swivel handle of the selected joint's arm or leg (none for a straight limb).
    pub(super) fn swivel_handle(&self) -> Option<SwivelHandle> {
        let joint = self
            .model
            .session()
            .skeleton()
            .joints()
            .get(self.model.selected_joint()?)?;
        let limb = LimbName::of_joint(&joint.name)?;
        let [upper, middle, end] = limb
            .joints()
            .map(|name| self.model.session().joint_position(name));
        let (upper, middle_world, end) = (upper?, middle?, end?);
        let axis_world = (end - upper).normalize_or_zero();
        if axis_world == DVec3::ZERO {
            return None;
        }
        let centre_world = upper + axis_world * (middle_world - upper).dot(axis_world);
        let radius = (middle_world - centre_world).length();
        // A straight limb (or NaN) has no circle to turn on.
        if radius.is_nan() || radius < SWIVEL_MIN_RADIUS_M {
            return None;
        }
        let (swivel, intervals) = self.model.session().limb_swivel(limb)?;
        Some(SwivelHandle {
            limb,
            middle_world,
            centre_world,
            axis_world,
            radius,
            swivel,
            intervals,
        })
    }

    /// The swivel handle for the page's state: the limb, its swivel angle (rad), the handle
    /// and the circle's centre on screen, the circle from the handle once around, and the
    /// feasible swivel intervals; `null` when no arm or leg is selected.
    pub(super) fn swivel_state(&self) -> serde_json::Value {
        let Some(handle) = self.swivel_handle() else {
            return serde_json::Value::Null;
        };
        let screen = |point| self.lens.screen_point(point).map(|p| [p.x, p.y]);
        let circle: Vec<[f32; 2]> = self
            .swivel_points(&handle)
            .iter()
            .map(|p| [p.x, p.y])
            .collect();
        let feasible: Vec<[f64; 2]> = handle
            .intervals
            .iter()
            .map(|interval| [interval.start, interval.end])
            .collect();
        serde_json::json!({
            "limb": handle.limb.name(),
            "angle": handle.swivel,
            "screen": screen(handle.middle_world),
            "centre": screen(handle.centre_world),
            "circle": circle,
            "feasible": feasible,
        })
    }

    /// The swivel circle on screen from the handle, once around.
    pub(super) fn swivel_points(&self, handle: &SwivelHandle) -> Vec<Pos2> {
        (0..=RING_SEGMENTS)
            .filter_map(|segment| {
                let turn = segment as f64 / RING_SEGMENTS as f64 * std::f64::consts::TAU;
                self.lens
                    .screen_point(handle.point_at(handle.swivel + turn))
            })
            .collect()
    }

    pub(super) fn ring_points(&self, ring: &Ring) -> Vec<Pos2> {
        let helper = if ring.axis_world.x.abs() < 0.9 {
            DVec3::X
        } else {
            DVec3::Y
        };
        let u = ring.axis_world.cross(helper).normalize_or_zero();
        let v = ring.axis_world.cross(u);
        (0..=RING_SEGMENTS)
            .filter_map(|segment| {
                let angle = segment as f64 / RING_SEGMENTS as f64 * std::f64::consts::TAU;
                let point = ring.centre_world + (u * angle.cos() + v * angle.sin()) * RING_RADIUS_M;
                self.lens.screen_point(point)
            })
            .collect()
    }

    /// The handle under `pointer`, if any: goals first, then rings.
    pub(super) fn pick_handle(&self, pointer: Pos2) -> Option<Gesture> {
        let nearest_goal = self
            .goal_handles()
            .into_iter()
            .filter_map(|(task, goal)| {
                let distance = self.lens.screen_point(goal)?.distance(pointer);
                (distance <= HANDLE_REACH_PT).then_some((distance, task, goal))
            })
            .min_by(|a, b| a.0.total_cmp(&b.0));
        if let Some((_, _, goal)) = nearest_goal {
            let tasks = self
                .goal_handles()
                .into_iter()
                .filter(|(_, other)| (*other - goal).length() < 1e-3)
                .map(|(task, _)| task)
                .collect();
            return Some(Gesture::Goal {
                tasks,
                plane_point_world: goal,
            });
        }
        if let Some(handle) = self.swivel_handle()
            && self
                .lens
                .screen_point(handle.middle_world)
                .is_some_and(|at| at.distance(pointer) <= HANDLE_REACH_PT)
        {
            return Some(Gesture::Swivel {
                limb: handle.limb,
                start_swivel: handle.swivel,
                start_direction: (handle.middle_world - handle.centre_world) / handle.radius,
                centre_world: handle.centre_world,
                axis_world: handle.axis_world,
            });
        }
        let eye = self.lens.eye();
        for ring in self.rings() {
            let near = self.ring_points(&ring).windows(2).any(|pair| {
                distance_to_segment(pointer, pair[0], pair[1]) <= HANDLE_REACH_PT * 0.7
            });
            if !near {
                continue;
            }
            let centre_px = self.lens.screen_point(ring.centre_world)?;
            let start_value = self
                .model
                .session()
                .posture()
                .values()
                .get(ring.dof)
                .copied()?;
            let sign = if ring.axis_world.dot(eye - ring.centre_world) >= 0.0 {
                1.0
            } else {
                -1.0
            };
            return Some(Gesture::Ring {
                dof: ring.dof,
                centre_px: [centre_px.x, centre_px.y],
                last_angle: screen_angle(centre_px, pointer),
                accumulated: 0.0,
                start_value,
                sign,
            });
        }
        None
    }

    /// Draws the rings of the selected joint (the dragged one thicker).
    pub(super) fn draw_rings(&self, painter: &egui::Painter) {
        let active_dof = match self.model.gesture() {
            Some(Gesture::Ring { dof, .. }) => Some(*dof),
            _ => None,
        };
        for ring in self.rings() {
            let color = RING_COLORS
                .get(ring.axis_index)
                .copied()
                .unwrap_or(Color32::WHITE);
            let width = if active_dof == Some(ring.dof) {
                3.5
            } else {
                2.0
            };
            painter.add(egui::Shape::line(
                self.ring_points(&ring),
                Stroke::new(width, color.gamma_multiply(0.9)),
            ));
        }
        self.draw_swivel(painter);
    }

    /// Draws the swivel handle of the selected limb: the circle the elbow or knee turns on,
    /// its feasible arcs (within the joint limits) and the handle.
    fn draw_swivel(&self, painter: &egui::Painter) {
        let Some(handle) = self.swivel_handle() else {
            return;
        };
        let dragging = matches!(self.model.gesture(), Some(Gesture::Swivel { .. }));
        painter.add(egui::Shape::dashed_line(
            &self.swivel_points(&handle),
            Stroke::new(1.5, SWIVEL_COLOR.gamma_multiply(0.8)),
            6.0,
            4.0,
        ));
        for interval in &handle.intervals {
            let steps = ((interval.length() / std::f64::consts::TAU * RING_SEGMENTS as f64).ceil()
                as usize)
                .max(2);
            let arc: Vec<Pos2> = (0..=steps)
                .filter_map(|step| {
                    let angle = interval.start
                        + (interval.end - interval.start) * step as f64 / steps as f64;
                    self.lens.screen_point(handle.point_at(angle))
                })
                .collect();
            painter.add(egui::Shape::line(
                arc,
                Stroke::new(3.0, SWIVEL_FEASIBLE_COLOR.gamma_multiply(0.8)),
            ));
        }
        if let Some(at) = self.lens.screen_point(handle.middle_world) {
            let radius = if dragging {
                SWIVEL_HANDLE_PT + 2.0
            } else {
                SWIVEL_HANDLE_PT
            };
            painter.circle(
                at,
                radius,
                SWIVEL_COLOR,
                Stroke::new(1.5, Color32::from_black_alpha(200)),
            );
        }
    }
}

fn distance_to_segment(point: Pos2, a: Pos2, b: Pos2) -> f32 {
    let ab = b - a;
    let length_squared = ab.length_sq();
    if length_squared <= f32::EPSILON {
        return point.distance(a);
    }
    let t = ((point - a).dot(ab) / length_squared).clamp(0.0, 1.0);
    point.distance(a + ab * t)
}
