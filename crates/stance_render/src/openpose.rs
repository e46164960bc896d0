//! OpenPose keypoints seen by a camera: a body's keypoints (`stance_hanim::keypoints`)
//! projected into an image of any size, the ones outside it or (on request) behind the body
//! left out, written as the JSON image-generation tools read, and drawn as the skeleton image
//! of the ControlNet OpenPose models ([`OpenPose::draw`]).
//!
//! Pixel coordinates have their origin at the image's top-left corner, x to the right, y
//! down; pixel `(i, j)` covers `[i, i + 1) x [j, j + 1)` (the preprocessors draw a point at
//! `int(x)`).

use glam::{DVec2, Vec2};
use stance_hanim::keypoints::{BODY_KEYPOINTS, HAND_KEYPOINTS, NECK, PoseKeypoints};

use crate::pick::ray_capsule_distance;
use crate::{Capsule, OrbitCamera};

/// What to do with a keypoint the body hides from the camera.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum HiddenKeypoints {
    /// Keep it (a whole skeleton, as a pose editor shows it).
    #[default]
    Keep,
    /// Leave it out, as missing (`0, 0, 0`), as a detector that cannot see it would.
    Missing,
}

/// How the JSON gives positions.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum KeypointUnits {
    /// Pixels of the canvas.
    #[default]
    Pixels,
    /// Fractions of the canvas's width and height (0 to 1).
    Normalized,
}

/// How deep under the body's surface along the line of sight a keypoint may lie and still
/// count as seen, beyond the radius of the thickest body part it is inside (m): a joint's
/// keypoint lies inside its limbs, about a radius under their surface.
const SEEN_DEPTH_M: f32 = 0.01;
/// How far past side-on a landmark's surface may turn from the camera and still be seen (the
/// cosine's magnitude: about 12 degrees, so that the nose in profile is seen).
const TURNED_AWAY: f32 = 0.2;

/// One person's keypoints in the image, pixels; `None` for a missing one.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OpenPosePerson {
    /// COCO-18, in OpenPose's order (`stance_hanim::keypoints::BODY_KEYPOINT_NAMES`).
    pub body: [Option<DVec2>; BODY_KEYPOINTS],
    /// The person's left hand (21 points).
    pub left_hand: [Option<DVec2>; HAND_KEYPOINTS],
    /// The person's right hand.
    pub right_hand: [Option<DVec2>; HAND_KEYPOINTS],
}

impl OpenPosePerson {
    /// No keypoint at all.
    pub const EMPTY: OpenPosePerson = OpenPosePerson {
        body: [None; BODY_KEYPOINTS],
        left_hand: [None; HAND_KEYPOINTS],
        right_hand: [None; HAND_KEYPOINTS],
    };

    /// `keypoints` seen by `camera` in an image of `size_px`: each projected, missing when
    /// it falls outside the image or behind the camera, and, with [`HiddenKeypoints::Missing`],
    /// when `body` (the body's capsules) hides it.
    pub fn seen(
        keypoints: &PoseKeypoints,
        camera: &OrbitCamera,
        size_px: [u32; 2],
        body: &[Capsule],
        hidden: HiddenKeypoints,
    ) -> OpenPosePerson {
        let view = View {
            camera,
            size_px: Vec2::new(size_px[0] as f32, size_px[1] as f32),
            body,
            hidden,
        };
        let mut body = [None; BODY_KEYPOINTS];
        // The neck is made from the shoulders, as OpenPose's training data made it whether or
        // not the body hid them: it is never hidden (else, missing, it would cut every limb
        // off in a side view, where the near shoulder covers it).
        let neck_view = View {
            hidden: HiddenKeypoints::Keep,
            ..view
        };
        for (index, ((seen, point), facing)) in body
            .iter_mut()
            .zip(keypoints.body)
            .zip(keypoints.body_facing)
            .enumerate()
        {
            let view = if index == NECK { &neck_view } else { &view };
            *seen = point.and_then(|point| view.see_on_surface(point, facing));
        }
        OpenPosePerson {
            body,
            left_hand: keypoints.left_hand.map(|point| view.see(point?)),
            right_hand: keypoints.right_hand.map(|point| view.see(point?)),
        }
    }
}

/// The keypoints of everyone in one image.
#[derive(Debug, Clone, PartialEq)]
pub struct OpenPose {
    /// Width and height of the image, pixels.
    pub size_px: [u32; 2],
    /// One per person.
    pub people: Vec<OpenPosePerson>,
}

#[derive(Clone, Copy)]
struct View<'a> {
    camera: &'a OrbitCamera,
    size_px: Vec2,
    body: &'a [Capsule],
    hidden: HiddenKeypoints,
}

impl View<'_> {
    fn see(&self, point_world: glam::DVec3) -> Option<DVec2> {
        self.see_on_surface(point_world, None)
    }

    /// A point, which lies on the body's surface facing `facing` where that is given (a
    /// landmark of the head), else inside the body (a joint).
    fn see_on_surface(
        &self,
        point_world: glam::DVec3,
        facing: Option<glam::DVec3>,
    ) -> Option<DVec2> {
        let point_world = point_world.as_vec3();
        let pixel = self.camera.project(point_world, self.size_px)?;
        let inside = pixel.is_finite()
            && (0.0..self.size_px.x).contains(&pixel.x)
            && (0.0..self.size_px.y).contains(&pixel.y);
        if !inside {
            return None;
        }
        if self.hidden == HiddenKeypoints::Missing
            && self.is_hidden(point_world, pixel, facing.map(|f| f.as_vec3()))
        {
            return None;
        }
        Some(pixel.as_dvec2())
    }

    /// Whether the body hides `point_world` (seen at `pixel`).
    ///
    /// A joint: when the line of sight enters the body more than [`SEEN_DEPTH_M`] plus the
    /// radius of the thickest capsule holding the point before it reaches the point. A point
    /// on the surface facing `facing`: when that surface turns away from the camera (more than
    /// [`TURNED_AWAY`] past side-on), or when a body part that does not hold it (a hand before
    /// the face) lies more than [`SEEN_DEPTH_M`] in front of it.
    fn is_hidden(&self, point_world: glam::Vec3, pixel: Vec2, facing: Option<glam::Vec3>) -> bool {
        let (origin, direction) = self.camera.ray_through(pixel, self.size_px);
        if facing.is_some_and(|facing| facing.dot(-direction) < -TURNED_AWAY) {
            return true;
        }
        let depth = (point_world - origin).dot(direction);
        let holds = |capsule: &&Capsule| distance_to_axis(capsule, point_world) <= capsule.radius_m;
        let (occluders, allowance): (Vec<&Capsule>, f32) = if facing.is_some() {
            let apart = self.body.iter().filter(|capsule| !holds(capsule)).collect();
            (apart, SEEN_DEPTH_M)
        } else {
            let thickest = self
                .body
                .iter()
                .filter(holds)
                .map(|capsule| capsule.radius_m)
                .fold(0.0, f32::max);
            (self.body.iter().collect(), thickest + SEEN_DEPTH_M)
        };
        occluders.into_iter().any(|capsule| {
            ray_capsule_distance(origin, direction, capsule)
                .is_some_and(|entry| entry < depth - allowance)
        })
    }
}

/// Distance from `point` to the capsule's segment (m).
fn distance_to_axis(capsule: &Capsule, point: glam::Vec3) -> f32 {
    let axis = capsule.end_world - capsule.start_world;
    let along = if axis.length_squared() > 1e-12 {
        ((point - capsule.start_world).dot(axis) / axis.length_squared()).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (capsule.start_world + axis * along - point).length()
}

impl OpenPose {
    /// The people of a scene seen by `camera` in an image of `size_px`: one per pose of
    /// `people` (each in the scene's frame), in their order, each hidden by `bodies` (every
    /// body's capsules, in the scene's frame) as `hidden` says; a person with no point in the
    /// picture is left out (nobody is there).
    pub fn of_scene<'a>(
        people: impl IntoIterator<Item = &'a PoseKeypoints>,
        camera: &OrbitCamera,
        size_px: [u32; 2],
        bodies: &[Capsule],
        hidden: HiddenKeypoints,
    ) -> Self {
        let people = people
            .into_iter()
            .map(|keypoints| OpenPosePerson::seen(keypoints, camera, size_px, bodies, hidden))
            .filter(|person| {
                person
                    .body
                    .iter()
                    .chain(&person.left_hand)
                    .chain(&person.right_hand)
                    .any(Option::is_some)
            })
            .collect();
        Self { size_px, people }
    }

    /// The JSON of OpenPose's output as image-generation tools read it (OpenPose's
    /// `people` with each person's `pose_keypoints_2d`, `hand_left_keypoints_2d`,
    /// `hand_right_keypoints_2d` and `face_keypoints_2d` as flat `x, y, confidence` lists, and
    /// the ControlNet editors' `canvas_width` and `canvas_height`): confidence 1 for a point
    /// seen, `0, 0, 0` for a missing one; no face points (an empty list).
    pub fn to_json(&self, units: KeypointUnits) -> String {
        self.json(units, None)
    }

    /// [`OpenPose::to_json`] with the camera that saw the keypoints as one more field,
    /// `"stance_camera"`: `{"target": [x, y, z], "yaw", "pitch", "distance", "orthographic",
    /// "vertical_fov"}` (the orbit camera's, m and rad), which other readers ignore and
    /// `stance lift` takes instead of fitting one.
    pub fn to_json_seen_by(&self, units: KeypointUnits, camera: &OrbitCamera) -> String {
        self.json(units, Some(camera))
    }

    fn json(&self, units: KeypointUnits, camera: Option<&OrbitCamera>) -> String {
        let [width, height] = self.size_px;
        let scale = match units {
            KeypointUnits::Pixels => DVec2::ONE,
            KeypointUnits::Normalized => DVec2::new(
                1.0 / f64::from(width.max(1)),
                1.0 / f64::from(height.max(1)),
            ),
        };
        let list = |points: &[Option<DVec2>]| {
            let items: Vec<String> = points
                .iter()
                .map(|point| match point {
                    Some(point) => {
                        let p = *point * scale;
                        match units {
                            KeypointUnits::Pixels => format!("{:.3},{:.3},1", p.x, p.y),
                            KeypointUnits::Normalized => format!("{:.6},{:.6},1", p.x, p.y),
                        }
                    }
                    None => "0,0,0".to_owned(),
                })
                .collect();
            format!("[{}]", items.join(","))
        };
        let people: Vec<String> = self
            .people
            .iter()
            .map(|person| {
                format!(
                    "{{\"pose_keypoints_2d\":{},\"hand_left_keypoints_2d\":{},\"hand_right_keypoints_2d\":{},\"face_keypoints_2d\":[]}}",
                    list(&person.body),
                    list(&person.left_hand),
                    list(&person.right_hand)
                )
            })
            .collect();
        let camera = camera.map_or(String::new(), |c| {
            let t = c.target_world;
            format!(
                ",\"stance_camera\":{{\"target\":[{},{},{}],\"yaw\":{},\"pitch\":{},\"distance\":{},\"orthographic\":{},\"vertical_fov\":{}}}",
                t.x, t.y, t.z, c.yaw, c.pitch, c.distance_m, c.orthographic, c.vertical_fov
            )
        });
        format!(
            "{{\"people\":[{}],\"canvas_width\":{width},\"canvas_height\":{height}{camera}}}\n",
            people.join(",")
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::{DVec3, Vec3};

    fn front_camera() -> OrbitCamera {
        OrbitCamera {
            target_world: Vec3::new(0.0, 1.0, 0.0),
            yaw: 0.0,
            pitch: 0.0,
            distance_m: 3.0,
            ..OrbitCamera::default()
        }
    }

    fn only_body_point(point: DVec3) -> PoseKeypoints {
        let mut body = [None; BODY_KEYPOINTS];
        body[0] = Some(point);
        PoseKeypoints {
            body,
            body_facing: [None; BODY_KEYPOINTS],
            left_hand: [None; HAND_KEYPOINTS],
            right_hand: [None; HAND_KEYPOINTS],
        }
    }

    #[test]
    fn a_point_straight_ahead_lands_at_the_centre_and_one_at_the_edge_of_the_view_at_the_edge() {
        // By hand: the camera at (0, 1, 3) looks at (0, 1, 0) with a 40 degree vertical field
        // of view. The target is the image's centre; a point at the target's distance
        // tan(20 deg) * 3 m above it is on the top edge, and at that height times the aspect to
        // the left (the body's right, -X, seen from the front) on the left edge.
        let camera = front_camera();
        let size = [800, 600];
        let see = |point| {
            OpenPosePerson::seen(
                &only_body_point(point),
                &camera,
                size,
                &[],
                HiddenKeypoints::Keep,
            )
            .body[0]
        };
        let centre = see(DVec3::new(0.0, 1.0, 0.0)).unwrap();
        assert!(
            (centre - DVec2::new(400.0, 300.0)).length() < 1e-3,
            "{centre}"
        );
        let half_height = 3.0 * 20f64.to_radians().tan();
        let near_top = see(DVec3::new(0.0, 1.0 + half_height * 0.99, 0.0)).unwrap();
        assert!(
            (near_top - DVec2::new(400.0, 3.0)).length() < 0.05,
            "{near_top}"
        );
        let near_left = see(DVec3::new(-half_height * 4.0 / 3.0 * 0.99, 1.0, 0.0)).unwrap();
        assert!(
            (near_left - DVec2::new(4.0, 300.0)).length() < 0.05,
            "{near_left}"
        );
        // Just outside the frame, or behind the camera: missing.
        assert_eq!(see(DVec3::new(0.0, 1.0 + half_height * 1.01, 0.0)), None);
        assert_eq!(see(DVec3::new(0.0, 1.0, 5.0)), None);
    }

    #[test]
    fn a_point_behind_the_body_is_missing_only_when_asked() {
        // A torso capsule between the camera and a point behind it; a point in front stays.
        let body = [Capsule {
            start_world: Vec3::new(0.0, 0.8, 0.0),
            end_world: Vec3::new(0.0, 1.4, 0.0),
            radius_m: 0.15,
            color_linear: [1.0; 4],
        }];
        let camera = front_camera();
        let see = |point, hidden| {
            OpenPosePerson::seen(&only_body_point(point), &camera, [512, 512], &body, hidden).body
                [0]
        };
        let behind = DVec3::new(0.05, 1.1, -0.3);
        assert!(see(behind, HiddenKeypoints::Keep).is_some());
        assert_eq!(see(behind, HiddenKeypoints::Missing), None);
        let in_front = DVec3::new(0.05, 1.1, 0.3);
        assert!(see(in_front, HiddenKeypoints::Missing).is_some());
        // A joint inside the capsule near its front surface is seen (the limb holds it).
        let inside = DVec3::new(0.0, 1.1, 0.05);
        assert!(see(inside, HiddenKeypoints::Missing).is_some());
    }

    #[test]
    fn a_landmark_turned_away_is_hidden_and_the_neck_never_is() {
        // Catches: the face's points seen through the back of the head; a neck left out in a
        // side view, which would cut every limb off.
        let camera = front_camera();
        let body = [Capsule {
            start_world: Vec3::new(-0.2, 1.1, 0.0),
            end_world: Vec3::new(0.2, 1.1, 0.0),
            radius_m: 0.1,
            color_linear: [1.0; 4],
        }];
        let mut keypoints = only_body_point(DVec3::new(0.0, 1.4, 0.3));
        keypoints.body[NECK] = Some(DVec3::new(0.0, 1.1, -0.3));
        let see = |keypoints: &PoseKeypoints, hidden| {
            OpenPosePerson::seen(keypoints, &camera, [512, 512], &body, hidden).body
        };
        keypoints.body_facing[0] = Some(DVec3::Z);
        let toward = see(&keypoints, HiddenKeypoints::Missing);
        assert!(toward[0].is_some() && toward[NECK].is_some());
        keypoints.body_facing[0] = Some(-DVec3::Z);
        let away = see(&keypoints, HiddenKeypoints::Missing);
        assert!(away[0].is_none() && away[NECK].is_some());
        assert!(see(&keypoints, HiddenKeypoints::Keep)[0].is_some());
    }

    #[test]
    fn the_json_lists_every_point_with_missing_ones_as_zeros() {
        let mut person = OpenPosePerson::EMPTY;
        person.body[1] = Some(DVec2::new(256.0, 128.5));
        let pose = OpenPose {
            size_px: [512, 256],
            people: vec![person],
        };
        let json = pose.to_json(KeypointUnits::Pixels);
        assert!(
            json.starts_with("{\"people\":[{\"pose_keypoints_2d\":[0,0,0,256.000,128.500,1,0,0,0"),
            "{json}"
        );
        assert!(json.contains("\"canvas_width\":512,\"canvas_height\":256"));
        let normalized = pose.to_json(KeypointUnits::Normalized);
        assert!(
            normalized.contains("[0,0,0,0.500000,0.501953,1,"),
            "{normalized}"
        );
        // 18 body points and 21 per hand, three numbers each.
        let count = |key: &str| {
            let start = json.find(key).unwrap() + key.len() + 2;
            let end = start + json[start..].find(']').unwrap();
            json[start..end].split(',').count()
        };
        assert_eq!(count("pose_keypoints_2d"), 54);
        assert_eq!(count("hand_left_keypoints_2d"), 63);
        assert_eq!(count("hand_right_keypoints_2d"), 63);
    }
}
