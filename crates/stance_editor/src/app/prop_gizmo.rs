//! Props in the viewport: a click on a prop selects it; a drag on it moves it over the floor
//! (at its height); the selected prop shows a gizmo: a ring around it on its horizontal plane
//! (dragged round, the prop turns about the vertical) and a square on the ring along the
//! prop's own X axis (dragged out or in, the prop grows or shrinks). Every change is a
//! [`SceneCommand::EditProp`], which the model coalesces into one undo step per drag.

use egui::{Color32, Pos2, Stroke};
use glam::{DQuat, DVec3};
use stance_document::{Prop, PropShape};

use super::lens::Lens;
use crate::model::{Command, EditorModel, Outbox, SceneCommand};

/// Pixels within which a pointer is on the ring or the square.
const GRAB_PX: f32 = 8.0;
/// Segments the ring is drawn and picked with.
const RING_SEGMENTS: usize = 48;
/// The smallest and largest scale one drag can give (of the size when it started).
const SCALE_RANGE: (f64, f64) = (0.05, 20.0);
const RING_COLOR: Color32 = Color32::from_rgb(240, 190, 60);

/// What a drag on a prop does.
#[derive(Debug, Clone, Copy, PartialEq)]
enum DragKind {
    /// Over the horizontal plane through the grabbed point; `offset`: the prop's centre from
    /// that point.
    Move { height: f64, offset: DVec3 },
    /// Round the ring: the pointer's angle about the vertical when the drag started.
    Turn { start_angle: f64 },
    /// The square: the pointer's distance from the centre when the drag started.
    Scale { start_distance: f64 },
}

#[derive(Debug, Clone, PartialEq)]
struct PropDrag {
    index: usize,
    start: Prop,
    kind: DragKind,
}

/// The viewport's props: the selected one and the drag under way.
#[derive(Debug, Default)]
pub(super) struct PropGizmo {
    selected: Option<usize>,
    drag: Option<PropDrag>,
}

/// Where the ray `origin + t direction` (scene) first meets `prop`'s box (its full extents,
/// turned with it), as the distance `t`.
pub(super) fn ray_hits_prop(prop: &Prop, origin: DVec3, direction: DVec3) -> Option<f64> {
    let prop_from_scene = prop.scene_from_prop().inverse();
    let o = prop_from_scene.transform_point3(origin);
    let d = prop_from_scene.transform_vector3(direction);
    let half = DVec3::from_array(prop.shape.extents()) / 2.0;
    let (mut near, mut far) = (f64::NEG_INFINITY, f64::INFINITY);
    for axis in 0..3 {
        if d[axis].abs() < 1e-12 {
            if o[axis].abs() > half[axis] {
                return None;
            }
            continue;
        }
        let a = (-half[axis] - o[axis]) / d[axis];
        let b = (half[axis] - o[axis]) / d[axis];
        near = near.max(a.min(b));
        far = far.min(a.max(b));
    }
    (near <= far && far >= 0.0).then_some(near.max(0.0))
}

/// The prop the scene ray meets first, and the distance along it.
pub(super) fn pick_prop(
    model: &EditorModel,
    origin: DVec3,
    direction: DVec3,
) -> Option<(usize, f64)> {
    model
        .props()
        .iter()
        .enumerate()
        .filter_map(|(i, prop)| Some((i, ray_hits_prop(prop, origin, direction)?)))
        .min_by(|a, b| a.1.total_cmp(&b.1))
}

/// The gizmo's ring around `prop` (scene): its centre and radius.
fn ring(prop: &Prop) -> (DVec3, f64) {
    let [x, _, z] = prop.shape.extents();
    let centre = DVec3::from_array(prop.position);
    (centre, 0.5 * x.max(z) + 0.12)
}

/// The prop's own X axis, flattened onto the floor (unit; +X when it points straight up).
fn flat_x_axis(prop: &Prop) -> DVec3 {
    let x = DQuat::from_array(prop.rotation).normalize() * DVec3::X;
    DVec3::new(x.x, 0.0, x.z)
        .try_normalize()
        .unwrap_or(DVec3::X)
}

/// The pointer on the horizontal plane at `height` (scene).
fn on_level(lens: &Lens<'_>, pointer: Pos2, height: f64) -> Option<DVec3> {
    let (origin, direction) = lens.pointer_scene_ray(pointer);
    if direction.y.abs() < 1e-9 {
        return None;
    }
    let t = (height - origin.y) / direction.y;
    (t > 0.0).then(|| origin + direction * t)
}

/// The angle about the vertical of `v` (scene), growing as a turn about +Y does.
fn yaw_of(v: DVec3) -> f64 {
    (-v.z).atan2(v.x)
}

impl PropGizmo {
    /// The selected prop, if it is still in the scene.
    pub(super) fn selected(&self, model: &EditorModel) -> Option<usize> {
        self.selected.filter(|&i| i < model.props().len())
    }

    /// Whether a drag on a prop is under way.
    pub(super) fn dragging(&self) -> bool {
        self.drag.is_some()
    }

    /// Selects the prop (or none).
    pub(super) fn select(&mut self, index: Option<usize>) {
        self.selected = index;
    }

    /// The selected prop's ring and square on screen: a point of the ring (its +X side, in
    /// the prop's turn) and the square.
    pub(super) fn handles_on_screen(
        &self,
        model: &EditorModel,
        lens: &Lens<'_>,
    ) -> Option<(Vec<Pos2>, Pos2)> {
        let prop = model.props().get(self.selected(model)?)?;
        let (centre, radius) = ring(prop);
        let points = (0..=RING_SEGMENTS)
            .filter_map(|k| {
                let a = std::f64::consts::TAU * k as f64 / RING_SEGMENTS as f64;
                lens.scene_screen_point(centre + DVec3::new(a.cos(), 0.0, -a.sin()) * radius)
            })
            .collect();
        let square = lens.scene_screen_point(centre + flat_x_axis(prop) * radius)?;
        Some((points, square))
    }

    /// A drag that starts at `pointer`: on the selected prop's square or ring, or on a prop
    /// nearer than `body_distance` (the body's hit along the same ray, if any). Returns
    /// whether one started.
    pub(super) fn begin(
        &mut self,
        model: &EditorModel,
        lens: &Lens<'_>,
        pointer: Pos2,
        body_distance: Option<f64>,
    ) -> bool {
        if let Some(index) = self.selected(model)
            && let Some((ring_points, square)) = self.handles_on_screen(model, lens)
            && let Some(prop) = model.props().get(index)
        {
            let (centre, _) = ring(prop);
            let at = on_level(lens, pointer, centre.y);
            let kind = if square.distance(pointer) <= GRAB_PX {
                at.map(|p| DragKind::Scale {
                    start_distance: (p - centre).length().max(1e-3),
                })
            } else if near_polyline(&ring_points, pointer) {
                at.map(|p| DragKind::Turn {
                    start_angle: yaw_of(p - centre),
                })
            } else {
                None
            };
            if let Some(kind) = kind {
                self.drag = Some(PropDrag {
                    index,
                    start: prop.clone(),
                    kind,
                });
                return true;
            }
        }
        let (origin, direction) = lens.pointer_scene_ray(pointer);
        let direction = direction.normalize_or(DVec3::NEG_Z);
        let Some((index, distance)) = pick_prop(model, origin, direction) else {
            return false;
        };
        if body_distance.is_some_and(|body| body < distance) {
            return false;
        }
        let Some(prop) = model.props().get(index) else {
            return false;
        };
        let grabbed = origin + direction * distance;
        self.selected = Some(index);
        self.drag = Some(PropDrag {
            index,
            start: prop.clone(),
            kind: DragKind::Move {
                height: grabbed.y,
                offset: DVec3::from_array(prop.position) - grabbed,
            },
        });
        true
    }

    /// The drag follows `pointer` (`None`: the button was released: the drag ends).
    pub(super) fn follow(&mut self, lens: &Lens<'_>, pointer: Option<Pos2>, outbox: &mut Outbox) {
        let Some(drag) = &self.drag else {
            return;
        };
        let Some(pointer) = pointer else {
            self.drag = None;
            return;
        };
        let mut prop = drag.start.clone();
        let (centre, _) = ring(&drag.start);
        match drag.kind {
            DragKind::Move { height, offset } => {
                let Some(at) = on_level(lens, pointer, height) else {
                    return;
                };
                let moved = at + offset;
                prop.position = [moved.x, prop.position[1], moved.z];
            }
            DragKind::Turn { start_angle } => {
                let Some(at) = on_level(lens, pointer, centre.y) else {
                    return;
                };
                let turn = DQuat::from_rotation_y(yaw_of(at - centre) - start_angle);
                prop.rotation = (turn * DQuat::from_array(drag.start.rotation).normalize())
                    .normalize()
                    .to_array();
            }
            DragKind::Scale { start_distance } => {
                let Some(at) = on_level(lens, pointer, centre.y) else {
                    return;
                };
                let factor =
                    ((at - centre).length() / start_distance).clamp(SCALE_RANGE.0, SCALE_RANGE.1);
                prop.shape = scaled(&drag.start.shape, factor);
            }
        }
        outbox.send(Command::Scene(SceneCommand::EditProp(drag.index, prop)));
    }

    /// The selected prop's ring and square.
    pub(super) fn draw(&self, painter: &egui::Painter, model: &EditorModel, lens: &Lens<'_>) {
        let Some((points, square)) = self.handles_on_screen(model, lens) else {
            return;
        };
        painter.add(egui::Shape::line(points, Stroke::new(2.0, RING_COLOR)));
        painter.rect_filled(
            egui::Rect::from_center_size(square, egui::vec2(10.0, 10.0)),
            1.0,
            RING_COLOR,
        );
    }
}

/// `shape` grown by `factor` in every dimension, each kept within the sizes a prop may have (a
/// mesh keeps its file).
fn scaled(shape: &PropShape, factor: f64) -> PropShape {
    let dimensions: Vec<f64> = shape
        .dimensions()
        .iter()
        .map(|d| (d * factor).clamp(0.005, stance_document::scene::MAX_PROP_SIZE_M))
        .collect();
    shape
        .with_dimensions(&dimensions)
        .unwrap_or_else(|| shape.clone())
}

/// Whether `pointer` is within [`GRAB_PX`] of the polyline through `points`.
fn near_polyline(points: &[Pos2], pointer: Pos2) -> bool {
    points.windows(2).any(|pair| {
        let (a, b) = (pair[0], pair[1]);
        let ab = b - a;
        let t = if ab.length_sq() > 0.0 {
            ((pointer - a).dot(ab) / ab.length_sq()).clamp(0.0, 1.0)
        } else {
            0.0
        };
        (a + ab * t).distance(pointer) <= GRAB_PX
    })
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;

    /// A ray against a turned box, by hand: a 1 m cube turned 45 degrees about +Y at x = 2,
    /// met by a ray along +X at its centre's height: its nearest corner, at 2 - 0.5 sqrt 2.
    #[test]
    fn a_ray_meets_a_turned_box_at_its_nearest_corner() {
        let mut prop = Prop::new(
            "Box".into(),
            PropShape::Box {
                size: [1.0, 1.0, 1.0],
            },
            [2.0, 0.5, 0.0],
        );
        prop.rotation = DQuat::from_rotation_y(std::f64::consts::FRAC_PI_4).to_array();
        let t = ray_hits_prop(&prop, DVec3::new(0.0, 0.5, 0.0), DVec3::X).unwrap();
        assert!((t - (2.0 - 0.5 * 2f64.sqrt())).abs() < 1e-9, "{t}");
        // Above it, or pointing away: no hit.
        assert!(ray_hits_prop(&prop, DVec3::new(0.0, 1.5, 0.0), DVec3::X).is_none());
        assert!(ray_hits_prop(&prop, DVec3::new(0.0, 0.5, 0.0), -DVec3::X).is_none());
    }

    #[test]
    fn a_scaled_prop_keeps_its_shape_and_stays_within_the_sizes_allowed() {
        let bar = PropShape::Cylinder {
            radius: 0.02,
            height: 2.0,
        };
        assert_eq!(
            scaled(&bar, 1.5),
            PropShape::Cylinder {
                radius: 0.03,
                height: 3.0
            }
        );
        let PropShape::Cylinder { radius, .. } = scaled(&bar, 0.01) else {
            panic!("a cylinder")
        };
        assert!((radius - 0.005).abs() < 1e-12);
        // A mesh keeps its file; its box grows.
        let chair = PropShape::Mesh {
            file: "chair.glb".into(),
            size: [0.4, 0.8, 0.5],
        };
        assert_eq!(
            scaled(&chair, 2.0),
            PropShape::Mesh {
                file: "chair.glb".into(),
                size: [0.8, 1.6, 1.0]
            }
        );
    }
}
