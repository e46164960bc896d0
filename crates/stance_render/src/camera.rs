//! An orbit camera: it turns around a target point, pans in the view plane and zooms; in
//! perspective or orthographic projection, with the standard views (front, back, sides, top,
//! three-quarter) and framing of a region.

use glam::{Mat4, Vec2, Vec3};

/// The standard views, as posing tools and Blender's numpad give them. The body faces +Z and
/// its left is +X (H-Anim), so *Left* looks at the body's left side from +X.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ViewPreset {
    /// From the front (+Z), level.
    Front,
    /// From behind (-Z), level.
    Back,
    /// At the body's left side (from +X), level.
    Left,
    /// At the body's right side (from -X), level.
    Right,
    /// From above, looking down, the front at the bottom of the screen.
    Top,
    /// From the front-left, a little above.
    ThreeQuarter,
}

impl ViewPreset {
    /// Every view, in menu order.
    pub const ALL: [Self; 6] = [
        Self::Front,
        Self::Back,
        Self::Left,
        Self::Right,
        Self::Top,
        Self::ThreeQuarter,
    ];

    /// `(yaw, pitch)` of the view.
    pub fn angles(self) -> (f32, f32) {
        use std::f32::consts::{FRAC_PI_2, FRAC_PI_4, PI};
        match self {
            Self::Front => (0.0, 0.0),
            Self::Back => (PI, 0.0),
            Self::Left => (FRAC_PI_2, 0.0),
            Self::Right => (3.0 * FRAC_PI_2, 0.0),
            Self::Top => (0.0, OrbitCamera::MAX_PITCH),
            Self::ThreeQuarter => (FRAC_PI_4, 0.2),
        }
    }

    /// Its name in menus.
    pub fn label(self) -> &'static str {
        match self {
            Self::Front => "Front",
            Self::Back => "Back",
            Self::Left => "Left side",
            Self::Right => "Right side",
            Self::Top => "Top",
            Self::ThreeQuarter => "Three-quarter",
        }
    }
}

/// A camera orbiting `target_world` at `distance_m`, perspective or orthographic.
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
    /// Vertical field of view, radians. An orthographic view shows the height the
    /// perspective one shows at the target's distance, so switching keeps the body's size.
    pub vertical_fov: f32,
    /// Orthographic (parallel) projection instead of perspective.
    pub orthographic: bool,
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
            orthographic: false,
        }
    }
}

impl OrbitCamera {
    /// A saved view (a document's `camera`: target, yaw, pitch, distance, projection) with
    /// the default field of view.
    pub fn saved(
        target_world: [f64; 3],
        yaw: f64,
        pitch: f64,
        distance_m: f64,
        orthographic: bool,
    ) -> Self {
        Self {
            target_world: Vec3::new(
                target_world[0] as f32,
                target_world[1] as f32,
                target_world[2] as f32,
            ),
            yaw: yaw as f32,
            pitch: pitch as f32,
            distance_m: distance_m as f32,
            orthographic,
            ..Self::default()
        }
    }

    /// Radians of rotation per pixel of drag.
    pub const ORBIT_SPEED: f32 = 0.008;
    const MIN_DISTANCE_M: f32 = 0.2;
    const MAX_DISTANCE_M: f32 = 60.0;
    const NEAR_M: f32 = 0.02;
    const FAR_M: f32 = 200.0;
    /// Steepest look down or up (a little short of vertical, where the view's up is lost).
    pub const MAX_PITCH: f32 = 1.5;

    /// Half the height the view shows at the target's distance (m).
    fn half_height_at_target(&self) -> f32 {
        self.distance_m * (self.vertical_fov * 0.5).tan()
    }

    /// Turns to a standard view (the target, distance and projection stay).
    pub fn set_view(&mut self, preset: ViewPreset) {
        (self.yaw, self.pitch) = preset.angles();
    }

    /// Aims at `centre` from a distance that shows a sphere of `radius_m` with a margin.
    pub fn frame(&mut self, centre: Vec3, radius_m: f32) {
        if !(centre.is_finite() && radius_m.is_finite()) {
            return;
        }
        self.target_world = centre;
        let fit = radius_m.max(0.05) * 1.2 / (self.vertical_fov * 0.5).sin();
        self.distance_m = fit.clamp(Self::MIN_DISTANCE_M, Self::MAX_DISTANCE_M);
    }

    /// Aims at the middle of `points_world` (their bounding box) from a distance that shows
    /// them all, with a margin, in a view of `aspect` (width / height): a narrow view steps
    /// back so that the width fits too. Nothing changes without a finite point.
    pub fn frame_points(&mut self, points_world: &[Vec3], aspect: f32) {
        let mut finite = points_world.iter().filter(|point| point.is_finite());
        let Some(first) = finite.next() else {
            return;
        };
        let (lo, hi) = finite.fold((*first, *first), |(lo, hi), p| (lo.min(*p), hi.max(*p)));
        let radius_m = (hi - lo).length() * 0.5;
        let narrow = if aspect.is_finite() && aspect > 0.0 {
            aspect.min(1.0)
        } else {
            1.0
        };
        self.frame((lo + hi) * 0.5, radius_m / narrow);
    }

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

    /// The projection for a viewport of `aspect` (width / height), wgpu clip space (depth
    /// 0..1).
    pub fn clip_from_view(&self, aspect: f32) -> Mat4 {
        let aspect = aspect.max(1e-3);
        if self.orthographic {
            let h = self.half_height_at_target();
            let w = h * aspect;
            return glam::camera::rh::proj::directx::orthographic(
                -w,
                w,
                -h,
                h,
                Self::NEAR_M,
                Self::FAR_M,
            );
        }
        // wgpu clip space: depth 0..1, y up (the "directx" convention).
        glam::camera::rh::proj::directx::perspective(
            self.vertical_fov,
            aspect,
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
        self.pitch =
            (self.pitch + delta_px.y * Self::ORBIT_SPEED).clamp(-Self::MAX_PITCH, Self::MAX_PITCH);
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

    /// The ray through pixel `point_px` (origin top left) of a viewport of `size_px`: its
    /// origin (on the near plane) and unit direction in world space. In perspective the rays
    /// leave the eye; in orthographic projection they are parallel.
    pub fn ray_through(&self, point_px: Vec2, size_px: Vec2) -> (Vec3, Vec3) {
        let size_px = size_px.max(Vec2::ONE);
        let ndc = Vec2::new(
            point_px.x / size_px.x * 2.0 - 1.0,
            1.0 - point_px.y / size_px.y * 2.0,
        );
        let world_from_clip = self.clip_from_world(size_px.x / size_px.y).inverse();
        let near = world_from_clip.project_point3(ndc.extend(0.0));
        let far = world_from_clip.project_point3(ndc.extend(1.0));
        let direction = (far - near).normalize_or(-Vec3::Z);
        (near, direction)
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
        // Orthographic: the same scale at every depth, the target's.
        let depth_m = if self.orthographic {
            self.distance_m
        } else {
            (depth_point_world - self.eye_world())
                .dot(forward)
                .max(0.01)
        };
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
    fn orthographic_rays_are_parallel_and_depth_does_not_move_a_point_on_screen() {
        let camera = OrbitCamera {
            orthographic: true,
            ..Default::default()
        };
        let size = Vec2::new(800.0, 600.0);
        let (o1, d1) = camera.ray_through(Vec2::new(100.0, 80.0), size);
        let (o2, d2) = camera.ray_through(Vec2::new(700.0, 500.0), size);
        assert!(d1.angle_between(d2) < 1e-5 && (o1 - o2).length() > 0.5);
        // Points along the view direction land on the same pixel.
        let forward = (camera.target_world - camera.eye_world()).normalize();
        let p = Vec3::new(0.2, 1.1, 0.1);
        let a = camera.project(p, size).unwrap();
        let b = camera.project(p + forward * 0.7, size).unwrap();
        assert!((a - b).length() < 1e-3, "{a} {b}");
        // A ray through a projected point passes through it, and drags match the cursor.
        let (origin, direction) = camera.ray_through(a, size);
        let miss = (origin + direction * (p - origin).dot(direction) - p).length();
        assert!(miss < 1e-4, "{miss}");
        let moved = p + camera.view_plane_displacement(Vec2::new(30.0, -20.0), p, 600.0);
        let delta = camera.project(moved, size).unwrap() - a;
        assert!((delta - Vec2::new(30.0, -20.0)).length() < 0.5, "{delta}");
    }

    #[test]
    fn switching_projection_keeps_the_size_at_the_target() {
        let mut camera = OrbitCamera::default();
        let size = Vec2::new(800.0, 600.0);
        let p = camera.target_world + Vec3::new(0.3, 0.4, 0.0);
        let perspective = camera.project(p, size).unwrap();
        camera.orthographic = true;
        let orthographic = camera.project(p, size).unwrap();
        // The same point in the target's plane (to first order): within a few pixels.
        assert!(
            (perspective - orthographic).length() < 6.0,
            "{perspective} {orthographic}"
        );
    }

    #[test]
    fn the_standard_views_look_from_where_their_names_say() {
        let mut camera = OrbitCamera::default();
        let eye = |c: &OrbitCamera| (c.eye_world() - c.target_world).normalize();
        for (view, from) in [
            (ViewPreset::Front, Vec3::Z),
            (ViewPreset::Back, -Vec3::Z),
            (ViewPreset::Left, Vec3::X),
            (ViewPreset::Right, -Vec3::X),
        ] {
            camera.set_view(view);
            assert!(
                (eye(&camera) - from).length() < 1e-5,
                "{view:?}: {}",
                eye(&camera)
            );
        }
        camera.set_view(ViewPreset::Top);
        assert!(eye(&camera).y > 0.99);
        // Seen from the top, the body's front (+Z) is at the bottom of the screen.
        let size = Vec2::new(800.0, 600.0);
        let front = camera
            .project(camera.target_world + Vec3::Z * 0.3, size)
            .unwrap();
        assert!(front.y > size.y * 0.5);
        camera.set_view(ViewPreset::ThreeQuarter);
        let e = eye(&camera);
        assert!(e.x > 0.5 && e.z > 0.5 && e.y > 0.0, "{e}");
    }

    #[test]
    fn framing_a_region_puts_it_in_the_middle_and_fits_it() {
        let mut camera = OrbitCamera::default();
        let size = Vec2::new(800.0, 600.0);
        let centre = Vec3::new(0.3, 1.4, 0.1);
        camera.frame(centre, 0.15);
        let middle = camera.project(centre, size).unwrap();
        assert!((middle - size * 0.5).length() < 1e-2);
        // A point on the sphere's edge, across the view, is inside the viewport.
        let right = camera.view_from_world().inverse().x_axis.truncate();
        let edge = camera.project(centre + right * 0.15, size).unwrap();
        assert!(edge.x < size.x && edge.x > size.x * 0.5 + 50.0, "{edge}");
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
