//! The camera of a lift: the view the keypoints were drawn through (rays through pixels,
//! points at a depth), the body's scale in the image, and a camera fitted to the keypoints
//! when the file has none.

use glam::{DVec2, DVec3, Vec2};
use stance_document::CameraSpec;
use stance_render::OrbitCamera;

use super::{L_ANKLE, LiftError, OpenPosePerson, PoseKeypoints, R_ANKLE, SCALE_BONES};

/// The document's saved view of `camera` (its field of view is the default one's).
pub fn camera_spec(camera: &OrbitCamera) -> CameraSpec {
    let t = camera.target_world;
    CameraSpec {
        target: [f64::from(t.x), f64::from(t.y), f64::from(t.z)],
        yaw: f64::from(camera.yaw),
        pitch: f64::from(camera.pitch),
        distance: f64::from(camera.distance_m),
        orthographic: camera.orthographic,
    }
}

/// A camera and the image it sees.
#[derive(Debug, Clone, Copy)]
pub(super) struct View {
    pub(super) camera: OrbitCamera,
    pub(super) size_px: [u32; 2],
}

impl View {
    pub(super) fn size(&self) -> Vec2 {
        Vec2::new(self.size_px[0] as f32, self.size_px[1] as f32)
    }

    /// The ray through `pixel`: origin and unit direction.
    pub(super) fn ray(&self, pixel: DVec2) -> (DVec3, DVec3) {
        let (origin, direction) = self.camera.ray_through(pixel.as_vec2(), self.size());
        (origin.as_dvec3(), direction.as_dvec3())
    }

    /// The point seen at `pixel` at `depth` metres from the eye along the view axis.
    pub(super) fn at_depth(&self, pixel: DVec2, depth: f64) -> DVec3 {
        let eye = self.camera.eye_world().as_dvec3();
        let forward = (self.camera.target_world.as_dvec3() - eye).normalize_or(DVec3::NEG_Z);
        let (origin, direction) = self.ray(pixel);
        let along = direction.dot(forward).max(1e-6);
        origin + direction * ((depth - (origin - eye).dot(forward)) / along)
    }

    /// Whether `p` lies before the eye (any point does in orthographic projection).
    pub(super) fn in_front(&self, p: DVec3) -> bool {
        let eye = self.camera.eye_world().as_dvec3();
        let forward = (self.camera.target_world.as_dvec3() - eye).normalize_or(DVec3::NEG_Z);
        self.camera.orthographic || (p - eye).dot(forward) > 0.0
    }

    /// Pixels per metre at `depth` from the eye (for orthographic projection, at any depth).
    pub(super) fn focal_px(&self) -> f64 {
        f64::from(self.size_px[1]) * 0.5 / f64::from(self.camera.vertical_fov * 0.5).tan()
    }
}

/// The body's scale in the image: pixels per metre at its depth, the largest ratio of a
/// visible bone's length in the image to its rest length (a bone seen side-on is not
/// shortened; any other is), and the keypoints' centroid in the image.
pub(super) struct Scale {
    pub(super) px_per_m: f64,
    pub(super) centroid_px: DVec2,
}

impl Scale {
    pub(super) fn new(person: &OpenPosePerson, rest: &PoseKeypoints) -> Result<Scale, LiftError> {
        let visible: Vec<DVec2> = person.body.iter().flatten().copied().collect();
        let px_per_m = SCALE_BONES
            .iter()
            .filter_map(|&(a, b)| {
                let image = (person.body[a]? - person.body[b]?).length();
                let length = (rest.body[a]? - rest.body[b]?).length();
                (length > 1e-3).then_some(image / length)
            })
            .fold(0.0, f64::max);
        if visible.len() < 2 || px_per_m <= 0.0 {
            return Err(LiftError::TooFewKeypoints(visible.len()));
        }
        let centroid_px = visible.iter().sum::<DVec2>() / visible.len() as f64;
        Ok(Scale {
            px_per_m,
            centroid_px,
        })
    }
}

/// A perspective camera of the default field of view, level with the editor's default pitch
/// and looking at the body's front (yaw 0: the body turns instead), placed so that the rest
/// body's bones match the keypoints in scale ([`Scale`]: the distance at which a metre spans
/// that many pixels) and position: the keypoints' centroid seen over the world origin, and
/// the lowest ankle's keypoint at the rest ankle's height (without an ankle, the centroid at
/// the rest keypoints' centroid height).
pub(super) fn fit_camera(
    person: &OpenPosePerson,
    size_px: [u32; 2],
    rest: &PoseKeypoints,
    scale: &Scale,
) -> OrbitCamera {
    let provisional = OrbitCamera {
        target_world: glam::Vec3::ZERO,
        yaw: 0.0,
        ..OrbitCamera::default()
    };
    let view = View {
        camera: provisional,
        size_px,
    };
    let depth = view.focal_px() / scale.px_per_m;
    let distance = depth as f32;
    let view = View {
        camera: OrbitCamera {
            distance_m: distance,
            ..provisional
        },
        size_px,
    };
    let centre = view.at_depth(scale.centroid_px, depth);
    let lowest_ankle = [R_ANKLE, L_ANKLE]
        .into_iter()
        .filter_map(|k| Some((k, person.body[k]?)))
        .max_by(|a, b| a.1.y.total_cmp(&b.1.y));
    let lift_y = match lowest_ankle {
        Some((k, pixel)) => {
            let height = rest.body[k].map_or(0.08, |p| p.y);
            height - view.at_depth(pixel, depth).y
        }
        None => {
            let visible: Vec<DVec3> = person
                .body
                .iter()
                .zip(rest.body)
                .filter_map(|(seen, at)| seen.and(at))
                .collect();
            let height = visible.iter().map(|p| p.y).sum::<f64>() / visible.len().max(1) as f64;
            height - centre.y
        }
    };
    let shift = DVec3::new(-centre.x, lift_y, -centre.z);
    OrbitCamera {
        target_world: shift.as_vec3(),
        distance_m: distance,
        ..provisional
    }
}
