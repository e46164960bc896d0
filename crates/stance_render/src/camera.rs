//! An orbit camera: it turns around a target point, pans in the view plane and zooms.

use glam::{Mat4, Vec2, Vec3};

/// A perspective camera orbiting `target_world` at `distance_m`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OrbitCamera {
    /// The point the camera looks at and turns around, world frame, metres.
    pub target_world: Vec3,
    /// Rotation about the world +Y axis; 0 looks at the body's front (from +Z towards -Z).
    pub yaw: f32,
    /// Elevation above the horizontal plane; positive looks down.
    pub pitch: f32,
    /// Distance from the target to the eye, metres.
    pub distance_m: f32,
    /// Vertical field of view, radians.
    pub vertical_fov: f32,
}

impl Default for OrbitCamera {
    /// Frames a standing person of about 1.7 m, seen from the front and a little above.
    fn default() -> Self {
        Self {
            target_world: Vec3::new(0.0, 0.9, 0.0),
            yaw: 0.35,
            pitch: 0.12,
            distance_m: 3.4,
            vertical_fov: 40f32.to_radians(),
        }
    }
}

impl OrbitCamera {
    /// Radians of rotation per pixel of drag.
    pub const ORBIT_SPEED: f32 = 0.008;
    const MIN_DISTANCE_M: f32 = 0.2;
    const MAX_DISTANCE_M: f32 = 60.0;
    const NEAR_M: f32 = 0.02;
    const FAR_M: f32 = 200.0;

    /// Camera position in world space.
    pub fn eye_world(&self) -> Vec3 {
        let (sin_yaw, cos_yaw) = self.yaw.sin_cos();
        let (sin_pitch, cos_pitch) = self.pitch.sin_cos();
        let direction = Vec3::new(sin_yaw * cos_pitch, sin_pitch, cos_yaw * cos_pitch);
        self.target_world + direction * self.distance_m
    }

    /// The view matrix: world coordinates to camera coordinates (right-handed, looking down -Z).
    pub fn view_from_world(&self) -> Mat4 {
        glam::camera::rh::view::look_at_mat4(self.eye_world(), self.target_world, Vec3::Y)
    }

    /// The perspective projection for a viewport of `aspect` (width / height), wgpu clip space
    /// (depth 0..1).
    pub fn clip_from_view(&self, aspect: f32) -> Mat4 {
        // wgpu clip space: depth 0..1, y up (the "directx" convention).
        glam::camera::rh::proj::directx::perspective(
            self.vertical_fov,
            aspect.max(1e-3),
            Self::NEAR_M,
            Self::FAR_M,
        )
    }

    /// Projection times view: world coordinates to wgpu clip space.
    pub fn clip_from_world(&self, aspect: f32) -> Mat4 {
        self.clip_from_view(aspect) * self.view_from_world()
    }

    /// Turns the camera by a drag of `delta_px` pixels (right drag turns the view right).
    pub fn orbit(&mut self, delta_px: Vec2) {
        self.yaw -= delta_px.x * Self::ORBIT_SPEED;
        self.pitch = (self.pitch + delta_px.y * Self::ORBIT_SPEED).clamp(-1.5, 1.5);
        self.yaw = self.yaw.rem_euclid(std::f32::consts::TAU);
    }

    /// Moves the target so that the point under the cursor follows a drag of `delta_px`
    /// in a viewport `viewport_height_px` tall.
    pub fn pan(&mut self, delta_px: Vec2, viewport_height_px: f32) {
        let metres_per_px =
            2.0 * self.distance_m * (self.vertical_fov * 0.5).tan() / viewport_height_px.max(1.0);
        let world_from_view = self.view_from_world().inverse();
        let right = world_from_view.x_axis.truncate();
        let up = world_from_view.y_axis.truncate();
        self.target_world += (-right * delta_px.x + up * delta_px.y) * metres_per_px;
    }

    /// Zooms by `factor` (> 1 comes closer).
    pub fn zoom(&mut self, factor: f32) {
        if factor.is_finite() && factor > 0.0 {
            self.distance_m =
                (self.distance_m / factor).clamp(Self::MIN_DISTANCE_M, Self::MAX_DISTANCE_M);
        }
    }

    /// Pixel coordinates (origin top left) of a world point in a viewport of `size_px`,
    /// or `None` when the point is behind the camera.
    pub fn project(&self, point_world: Vec3, size_px: Vec2) -> Option<Vec2> {
        let clip = self.clip_from_world(size_px.x / size_px.y) * point_world.extend(1.0);
        if clip.w <= 1e-6 {
            return None;
        }
        let ndc = clip.truncate() / clip.w;
        Some(Vec2::new(
            (ndc.x * 0.5 + 0.5) * size_px.x,
            (0.5 - ndc.y * 0.5) * size_px.y,
        ))
    }

    /// The ray from the eye through pixel `point_px` (origin top left) of a viewport of
    /// `size_px`: its origin and unit direction in world space.
    pub fn ray_through(&self, point_px: Vec2, size_px: Vec2) -> (Vec3, Vec3) {
        let size_px = size_px.max(Vec2::ONE);
        let ndc = Vec2::new(
            point_px.x / size_px.x * 2.0 - 1.0,
            1.0 - point_px.y / size_px.y * 2.0,
        );
        let world_from_clip = self.clip_from_world(size_px.x / size_px.y).inverse();
        let far = world_from_clip.project_point3(ndc.extend(1.0));
        let eye = self.eye_world();
        let direction = (far - eye).normalize_or(-Vec3::Z);
        (eye, direction)
    }

    /// The world-space displacement, in the plane facing the camera at `depth_point_world`,
    /// of a cursor move of `delta_px` in a viewport `viewport_height_px` tall.
    pub fn view_plane_displacement(
        &self,
        delta_px: Vec2,
        depth_point_world: Vec3,
        viewport_height_px: f32,
    ) -> Vec3 {
        let world_from_view = self.view_from_world().inverse();
        let forward = -world_from_view.z_axis.truncate();
        let depth_m = (depth_point_world - self.eye_world())
            .dot(forward)
            .max(0.01);
        let metres_per_px =
            2.0 * depth_m * (self.vertical_fov * 0.5).tan() / viewport_height_px.max(1.0);
        let right = world_from_view.x_axis.truncate();
        let up = world_from_view.y_axis.truncate();
        (right * delta_px.x - up * delta_px.y) * metres_per_px
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_ray_through_a_projected_point_passes_through_the_point() {
        let camera = OrbitCamera::default();
        let size = Vec2::new(800.0, 600.0);
        for point in [Vec3::new(0.2, 1.5, 0.1), Vec3::new(-0.4, 0.1, 0.3)] {
            let pixel = camera.project(point, size).unwrap_or_default();
            let (origin, direction) = camera.ray_through(pixel, size);
            let along = (point - origin).dot(direction);
            let miss = (origin + direction * along - point).length();
            assert!(miss < 1e-4, "ray misses by {miss} m");
        }
    }

    #[test]
    fn a_cursor_move_moves_a_point_by_the_same_pixels_on_screen() {
        let camera = OrbitCamera::default();
        let size = Vec2::new(800.0, 600.0);
        let point = Vec3::new(0.1, 1.2, 0.0);
        let moved = point + camera.view_plane_displacement(Vec2::new(30.0, -20.0), point, 600.0);
        let before = camera.project(point, size).unwrap_or_default();
        let after = camera.project(moved, size).unwrap_or_default();
        let delta = after - before;
        assert!(
            (delta - Vec2::new(30.0, -20.0)).length() < 0.5,
            "moved {delta}"
        );
    }

    #[test]
    fn the_target_projects_to_the_centre_of_the_viewport() {
        let camera = OrbitCamera::default();
        let size = Vec2::new(800.0, 600.0);
        let centre = camera.project(camera.target_world, size).unwrap();
        assert!((centre - size * 0.5).length() < 1e-3, "{centre}");
    }

    #[test]
    fn orbiting_moves_the_eye_but_keeps_the_distance() {
        let mut camera = OrbitCamera::default();
        let before = camera.eye_world();
        camera.orbit(Vec2::new(120.0, -40.0));
        let after = camera.eye_world();
        assert!((before - after).length() > 0.5);
        assert!(((after - camera.target_world).length() - camera.distance_m).abs() < 1e-4);
    }

    #[test]
    fn panning_moves_the_target_along_the_drag() {
        let mut camera = OrbitCamera {
            yaw: 0.0,
            pitch: 0.0,
            ..Default::default()
        };
        let size = Vec2::new(800.0, 600.0);
        let point = Vec3::new(0.0, 1.0, 0.0);
        let before = camera.project(point, size).unwrap();
        camera.pan(Vec2::new(50.0, 20.0), size.y);
        let after = camera.project(point, size).unwrap();
        assert!(
            (after - before - Vec2::new(50.0, 20.0)).length() < 0.5,
            "{before} {after}"
        );
    }

    #[test]
    fn zoom_is_clamped_and_ignores_bad_factors() {
        let mut camera = OrbitCamera::default();
        camera.zoom(1e9);
        assert!(camera.distance_m >= 0.2);
        camera.zoom(f32::NAN);
        camera.zoom(-2.0);
        assert!(camera.distance_m.is_finite() && camera.distance_m >= 0.2);
    }
}
