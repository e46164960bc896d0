//! The viewport's camera and rectangle as one lens: the selected character's world points to
//! screen points, and the pointer's ray back into that world (onto the plane facing the
//! camera, the floor, or the plane across an axis). The character's world is its own frame
//! (its session's: pins, goals, the pulled point), placed in the scene the camera looks at by
//! `scene_from_character`.

use crate::model::GestureCommand;
use egui::Pos2;
use glam::{DAffine3, DVec3, Vec2};
use stance_render::OrbitCamera;

use crate::model::{Command, Gesture};

/// The camera looking through the viewport's rectangle (screen points).
#[derive(Debug, Clone, Copy)]
pub(super) struct Lens<'a> {
    pub camera: &'a OrbitCamera,
    pub rect: egui::Rect,
    /// The selected character's placement in the scene.
    pub scene_from_character: DAffine3,
}

impl Lens<'_> {
    /// Where a world point of the selected character shows on screen; `None` behind the
    /// camera.
    pub fn screen_point(self, point_world: DVec3) -> Option<Pos2> {
        self.scene_screen_point(self.scene_from_character.transform_point3(point_world))
    }

    /// Where a point of the scene shows on screen; `None` behind the camera.
    pub fn scene_screen_point(self, point_scene: DVec3) -> Option<Pos2> {
        let rect = self.rect;
        let pixel = self.camera.project(
            point_scene.as_vec3(),
            Vec2::new(rect.width(), rect.height()),
        )?;
        let position = rect.min + egui::vec2(pixel.x, pixel.y);
        position.x.is_finite().then_some(position)
    }

    /// The camera ray under the pointer: origin and direction in the scene.
    pub fn pointer_scene_ray(&self, pointer: Pos2) -> (DVec3, DVec3) {
        let rect = self.rect;
        let local = pointer - rect.min;
        let (origin, direction) = self.camera.ray_through(
            Vec2::new(local.x, local.y),
            Vec2::new(rect.width(), rect.height()),
        );
        (origin.as_dvec3(), direction.as_dvec3())
    }

    /// The camera ray under the pointer: origin and direction in the selected character's
    /// world.
    pub fn pointer_ray(&self, pointer: Pos2) -> (DVec3, DVec3) {
        let (origin, direction) = self.pointer_scene_ray(pointer);
        let character_from_scene = self.scene_from_character.inverse();
        (
            character_from_scene.transform_point3(origin),
            character_from_scene.transform_vector3(direction),
        )
    }

    /// Where the pointer meets the plane facing the camera through `plane_point_world`.
    pub fn pointer_on_view_plane(&self, pointer: Pos2, plane_point_world: DVec3) -> Option<DVec3> {
        let (origin, direction) = self.pointer_ray(pointer);
        let forward_scene =
            self.camera.target_world.as_dvec3() - self.camera.eye_world().as_dvec3();
        let normal = self
            .scene_from_character
            .inverse()
            .transform_vector3(forward_scene)
            .normalize_or_zero();
        ray_meets_plane(origin, direction, plane_point_world, normal, 1e-6)
    }

    /// Where the pointer's ray meets the floor (the scene's y = 0).
    pub fn pointer_on_floor(&self, pointer: Pos2) -> Option<DVec3> {
        let (origin, direction) = self.pointer_ray(pointer);
        let floor = self
            .scene_from_character
            .inverse()
            .transform_point3(DVec3::ZERO);
        ray_meets_plane(origin, direction, floor, DVec3::Y, 1e-6)
    }

    /// The camera's eye in the selected character's world.
    pub fn eye(&self) -> DVec3 {
        self.scene_from_character
            .inverse()
            .transform_point3(self.camera.eye_world().as_dvec3())
    }

    /// Where the pointer's ray meets the plane through `centre` across `axis` (the swivel
    /// circle's plane); seen edge-on, the plane facing the camera is used instead.
    pub fn pointer_around_axis(&self, pointer: Pos2, centre: DVec3, axis: DVec3) -> Option<DVec3> {
        let (origin, direction) = self.pointer_ray(pointer);
        if direction.dot(axis).abs() < 0.1 {
            return self.pointer_on_view_plane(pointer, centre);
        }
        ray_meets_plane(origin, direction, centre, axis, 0.1)
    }
}

impl Lens<'_> {
    /// The command that makes `gesture` follow the pointer at `pointer`; `None` when the
    /// pointer's ray misses what the gesture moves on.
    pub fn follow(&self, gesture: &Gesture, pointer: Pos2) -> Option<Command> {
        match gesture {
            Gesture::Pull {
                plane_point_world, ..
            } => self
                .pointer_on_view_plane(pointer, *plane_point_world)
                .map(|target_world| Command::Gesture(GestureCommand::MoveGrab { target_world })),
            Gesture::Goal {
                plane_point_world, ..
            } => self
                .pointer_on_view_plane(pointer, *plane_point_world)
                .map(|goal_world| {
                    Command::Gesture(GestureCommand::MoveGoal {
                        goal_world,
                        floor_world: self.pointer_on_floor(pointer),
                    })
                }),
            Gesture::Ring { centre_px, .. } => Some(Command::Gesture(GestureCommand::TurnRing {
                screen_angle: screen_angle(egui::pos2(centre_px[0], centre_px[1]), pointer),
            })),
            Gesture::Swivel {
                centre_world,
                axis_world,
                ..
            } => self
                .pointer_around_axis(pointer, *centre_world, *axis_world)
                .map(|point_world| Command::Gesture(GestureCommand::TurnSwivel { point_world })),
        }
    }
}

/// The pointer's angle around `centre` on screen (radians; screen y points down).
pub(super) fn screen_angle(centre: Pos2, pointer: Pos2) -> f32 {
    (pointer.y - centre.y).atan2(pointer.x - centre.x)
}

/// Where the ray `origin + t direction` (t > 0) meets the plane through `plane_point` with
/// `normal`; `None` when the ray is within `min_cosine` of parallel to it or points away.
fn ray_meets_plane(
    origin: DVec3,
    direction: DVec3,
    plane_point: DVec3,
    normal: DVec3,
    min_cosine: f64,
) -> Option<DVec3> {
    let denominator = direction.dot(normal);
    if denominator.abs() < min_cosine {
        return None;
    }
    let distance = (plane_point - origin).dot(normal) / denominator;
    (distance > 0.0 && distance.is_finite()).then(|| origin + direction * distance)
}
