//! *File > Open photo…*: a person's posture from a photo. The host (the page) decodes the
//! picture and runs a pose detector on it off the editor's thread (MediaPipe Pose in a Web
//! Worker, `web/photo.js`); its 33 landmarks come here ([`DetectedPhoto`]), become OpenPose's
//! COCO-18 keypoints in the photo's pixels ([`openpose_from_landmarks`]) and go through the
//! same lift as *File > Open keypoints* (a [`crate::jobs::LiftJob`], the camera fitted to the
//! keypoints in an image of the photo's size). Once lifted, the photo stays behind the
//! viewport as a reference ([`ReferencePhoto`], shown or hidden by
//! [`super::KeypointsCommand::ShowPhoto`]); a photo that cannot be read, or in which no
//! person is found, changes nothing.

use std::sync::Arc;

/// MediaPipe Pose's landmarks (BlazePose's 33 points) in its order.
pub const MEDIAPIPE_LANDMARKS: usize = 33;

/// A landmark less visible than this (MediaPipe's `visibility`, 0 to 1) is taken as missing,
/// as MediaPipe's own drawing utilities leave out points under 0.5.
pub const MIN_VISIBILITY: f32 = 0.5;

/// OpenPose's COCO-18 body keypoints from MediaPipe's landmarks: for each COCO-18 point (in
/// OpenPose's order, docs/control-maps.md), the MediaPipe landmark it is (the neck, 1, is
/// the midpoint of the shoulders, as OpenPose's COCO-18 made it; `None` here).
pub const COCO18_FROM_MEDIAPIPE: [Option<usize>; 18] = [
    Some(0),  // nose
    None,     // neck: the shoulders' midpoint
    Some(12), // right shoulder
    Some(14), // right elbow
    Some(16), // right wrist
    Some(11), // left shoulder
    Some(13), // left elbow
    Some(15), // left wrist
    Some(24), // right hip
    Some(26), // right knee
    Some(28), // right ankle
    Some(23), // left hip
    Some(25), // left knee
    Some(27), // left ankle
    Some(5),  // right eye
    Some(2),  // left eye
    Some(8),  // right ear
    Some(7),  // left ear
];

/// One MediaPipe landmark: `x`, `y` as fractions of the image's width and height (0 at the
/// top left), `z` (depth, in about the same scale as `x`), and `visibility`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Landmark {
    /// Fraction of the image's width.
    pub x: f32,
    /// Fraction of the image's height, down.
    pub y: f32,
    /// Depth relative to the hips (MediaPipe's scale); not used by the lift.
    pub z: f32,
    /// How likely the point is in view and not hidden (0 to 1).
    pub visibility: f32,
}

/// A picture and what the detector found in it, as the host hands it over.
#[derive(Clone, PartialEq)]
pub struct DetectedPhoto {
    /// The file's name.
    pub name: String,
    /// The photo's size in pixels, as decoded.
    pub size_px: [u32; 2],
    /// MediaPipe's 33 landmarks of the one person found.
    pub landmarks: Vec<Landmark>,
    /// The photo to show behind the viewport: RGBA8 pixels, `reference_size_px` (the photo
    /// scaled down to fit a texture, else the photo's own size).
    pub reference_rgba: Vec<u8>,
    /// The reference image's size in pixels.
    pub reference_size_px: [u32; 2],
    /// How long the detection took in the host (ms: the detector's start included the first
    /// time).
    pub detect_ms: f64,
}

impl std::fmt::Debug for DetectedPhoto {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("DetectedPhoto")
            .field("name", &self.name)
            .field("size_px", &self.size_px)
            .field("landmarks", &self.landmarks.len())
            .field("reference_size_px", &self.reference_size_px)
            .field("detect_ms", &self.detect_ms)
            .finish_non_exhaustive()
    }
}

/// The photo behind the viewport (not part of the document: it stays until another photo is
/// opened).
#[derive(Clone, PartialEq)]
pub struct ReferencePhoto {
    /// The file's name.
    pub name: String,
    /// Counts the photos opened (the viewport uploads a new one when it changes).
    pub id: u64,
    /// The photo's size in pixels: the keypoints' image, which the lifted camera sees whole
    /// (its height spans the camera's vertical field of view).
    pub size_px: [u32; 2],
    /// The image shown: RGBA8 pixels of `reference_size_px`.
    pub rgba: Arc<Vec<u8>>,
    /// Its size in pixels (the photo's aspect ratio).
    pub reference_size_px: [u32; 2],
    /// The COCO-18 keypoints the detector found (pixels of the photo; `None`: missing), in
    /// OpenPose's order.
    pub keypoints: [Option<[f64; 2]>; 18],
    /// The detection's time in the host (ms).
    pub detect_ms: f64,
    /// The lift's time, from the request to the lifted scene in the editor (ms).
    pub lift_ms: f64,
}

impl std::fmt::Debug for ReferencePhoto {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ReferencePhoto")
            .field("name", &self.name)
            .field("id", &self.id)
            .field("size_px", &self.size_px)
            .field("reference_size_px", &self.reference_size_px)
            .finish_non_exhaustive()
    }
}

/// The COCO-18 keypoints (photo pixels) of MediaPipe's landmarks in an image of `size_px`:
/// a landmark less visible than [`MIN_VISIBILITY`] or outside the image is missing; the neck
/// is the shoulders' midpoint when both are there. `Err`: what is wrong with the landmarks.
pub fn coco18_from_landmarks(
    landmarks: &[Landmark],
    size_px: [u32; 2],
) -> Result<[Option<[f64; 2]>; 18], String> {
    if landmarks.len() != MEDIAPIPE_LANDMARKS {
        return Err(format!(
            "the detector gave {} landmarks, not MediaPipe Pose's {MEDIAPIPE_LANDMARKS}",
            landmarks.len()
        ));
    }
    let [width, height] = size_px.map(f64::from);
    let point = |index: usize| {
        let l = landmarks.get(index)?;
        let inside = (0.0..=1.0).contains(&l.x) && (0.0..=1.0).contains(&l.y);
        let seen = l.visibility.is_finite() && l.visibility >= MIN_VISIBILITY;
        (inside && seen).then(|| [f64::from(l.x) * width, f64::from(l.y) * height])
    };
    let mut out = [None; 18];
    for (slot, source) in out.iter_mut().zip(COCO18_FROM_MEDIAPIPE) {
        *slot = source.and_then(point);
    }
    out[1] = match (out[2], out[5]) {
        (Some(r), Some(l)) => Some([(r[0] + l[0]) * 0.5, (r[1] + l[1]) * 0.5]),
        _ => None,
    };
    Ok(out)
}

/// An OpenPose keypoints JSON (one person, COCO-18 body points in pixels, no hands or face)
/// of `keypoints` in an image of `size_px`: what *File > Open keypoints* reads.
pub fn openpose_json(keypoints: &[Option<[f64; 2]>; 18], size_px: [u32; 2]) -> String {
    let body: Vec<f64> = keypoints
        .iter()
        .flat_map(|p| match p {
            Some([x, y]) => [*x, *y, 1.0],
            None => [0.0, 0.0, 0.0],
        })
        .collect();
    serde_json::json!({
        "people": [{
            "pose_keypoints_2d": body,
            "hand_left_keypoints_2d": [],
            "hand_right_keypoints_2d": [],
            "face_keypoints_2d": [],
        }],
        "canvas_width": size_px[0],
        "canvas_height": size_px[1],
    })
    .to_string()
}

/// [`coco18_from_landmarks`] as OpenPose JSON ([`openpose_json`]).
pub fn openpose_from_landmarks(
    landmarks: &[Landmark],
    size_px: [u32; 2],
) -> Result<String, String> {
    coco18_from_landmarks(landmarks, size_px).map(|k| openpose_json(&k, size_px))
}
