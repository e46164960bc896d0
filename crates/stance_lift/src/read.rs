//! OpenPose keypoints JSON read back: what `stance render --map openpose --keypoints-out`
//! writes ([`stance_render::OpenPose::to_json`]) and OpenPose itself writes (its `people`,
//! each with flat `x, y, confidence` lists), in pixels or in fractions of the canvas, with
//! Stance's optional `stance_camera`. A JSON that is not such a file is refused, naming what
//! it looks like.

use glam::{DVec2, Vec3};
use serde_json::{Map, Value};
use stance_hanim::keypoints::{BODY_KEYPOINTS, HAND_KEYPOINTS};
use stance_render::{KeypointUnits, OpenPosePerson, OrbitCamera};

use crate::LiftError;

/// The keypoints of one image, as read.
#[derive(Debug, Clone, PartialEq)]
pub struct ObservedPose {
    /// Width and height of the image, pixels.
    pub size_px: [u32; 2],
    /// Each person's keypoints in pixels (origin top left, y down); `None` for a missing one
    /// (`0, 0, 0`, or a confidence of 0).
    pub people: Vec<OpenPosePerson>,
    /// The camera Stance saw them with (`stance_camera`), when the file carries it.
    pub camera: Option<OrbitCamera>,
    /// Whether the file gave pixels or fractions of the canvas.
    pub units: KeypointUnits,
}

/// The fields of a Stance document, a problem file and a glTF file, to say what a JSON that is
/// not OpenPose keypoints is.
fn looks_like(o: &Map<String, Value>) -> String {
    let has = |k: &str| o.contains_key(k);
    if has("skeleton") && has("tasks") {
        return "a Stance problem file (it has `skeleton` and `tasks`)".to_owned();
    }
    if ["posture", "tasks", "version", "avatar", "motion"]
        .iter()
        .any(|k| has(k))
    {
        return "a Stance document (it has `posture`, `tasks` or `version`)".to_owned();
    }
    if has("asset") && (has("nodes") || has("meshes")) {
        return "a glTF file".to_owned();
    }
    let mut keys: Vec<&str> = o.keys().map(String::as_str).take(6).collect();
    keys.sort_unstable();
    if keys.is_empty() {
        "an empty JSON object".to_owned()
    } else {
        format!("a JSON object with {}", keys.join(", "))
    }
}

fn kind_of(v: &Value) -> &'static str {
    match v {
        Value::Null => "null",
        Value::Bool(_) => "a boolean",
        Value::Number(_) => "a number",
        Value::String(_) => "a string",
        Value::Array(_) => "an array",
        Value::Object(_) => "an object",
    }
}

/// One flat `x, y, c` list of `count` points; `None` when absent or empty.
fn points(
    v: Option<&Value>,
    count: usize,
    at: &str,
) -> Result<Option<Vec<Option<DVec2>>>, LiftError> {
    let Some(v) = v.filter(|v| !v.is_null()) else {
        return Ok(None);
    };
    let list = v.as_array().ok_or_else(|| {
        LiftError::NotOpenPose(format!("{at} is {}, not a list of numbers", kind_of(v)))
    })?;
    if list.is_empty() {
        return Ok(None);
    }
    if list.len() != count * 3 {
        let what = if at.ends_with("pose_keypoints_2d") && list.len() == 25 * 3 {
            " (OpenPose's BODY_25 model: Stance reads COCO-18, `--model_pose COCO`)".to_owned()
        } else {
            String::new()
        };
        return Err(LiftError::NotOpenPose(format!(
            "{at} has {} numbers, expected {} ({count} points of x, y, confidence){what}",
            list.len(),
            count * 3
        )));
    }
    let mut out = Vec::with_capacity(count);
    for (k, triple) in list.chunks(3).enumerate() {
        let number = |i: usize| {
            triple[i].as_f64().filter(|x| x.is_finite()).ok_or_else(|| {
                LiftError::NotOpenPose(format!("{at}[{}] is not a finite number", k * 3 + i))
            })
        };
        let (x, y, c) = (number(0)?, number(1)?, number(2)?);
        out.push((c > 0.0 && !(x == 0.0 && y == 0.0)).then_some(DVec2::new(x, y)));
    }
    Ok(Some(out))
}

fn canvas(o: &Map<String, Value>, name: &str) -> Result<Option<u32>, LiftError> {
    match o.get(name) {
        None | Some(Value::Null) => Ok(None),
        Some(v) => v
            .as_u64()
            .filter(|&n| (1..=1 << 16).contains(&n))
            .map(|n| Some(n as u32))
            .ok_or_else(|| {
                LiftError::NotOpenPose(format!(
                    "{name} is {v}, not a whole number of pixels from 1 to 65536"
                ))
            }),
    }
}

fn camera(v: &Value) -> Result<OrbitCamera, LiftError> {
    let bad = |what: &str| LiftError::BadCamera(format!("stance_camera.{what}"));
    let o = v.as_object().ok_or_else(|| bad("(not an object)"))?;
    let number = |k: &str| {
        o.get(k)
            .and_then(Value::as_f64)
            .filter(|x| x.is_finite())
            .ok_or_else(|| bad(&format!("{k}: expected a finite number")))
    };
    let target = o
        .get("target")
        .and_then(Value::as_array)
        .filter(|a| a.len() == 3)
        .and_then(|a| {
            let c: Option<Vec<f64>> = a.iter().map(Value::as_f64).collect();
            c
        })
        .filter(|c| c.iter().all(|x| x.is_finite()))
        .ok_or_else(|| bad("target: expected 3 finite numbers"))?;
    let camera = OrbitCamera {
        target_world: Vec3::new(target[0] as f32, target[1] as f32, target[2] as f32),
        yaw: number("yaw")? as f32,
        pitch: number("pitch")? as f32,
        distance_m: number("distance")? as f32,
        vertical_fov: match o.get("vertical_fov") {
            None => OrbitCamera::default().vertical_fov,
            Some(_) => number("vertical_fov")? as f32,
        },
        orthographic: o
            .get("orthographic")
            .and_then(Value::as_bool)
            .unwrap_or(false),
    };
    check_camera(&camera)?;
    Ok(camera)
}

/// A camera whose numbers make a view: a positive distance, a pitch short of vertical, a
/// field of view between 1 and 170 degrees.
pub(crate) fn check_camera(camera: &OrbitCamera) -> Result<(), LiftError> {
    let bad = |what: &str| Err(LiftError::BadCamera(what.to_owned()));
    if !(camera.distance_m.is_finite() && camera.distance_m > 0.0) {
        return bad("distance: must be above 0 m");
    }
    if !(camera.pitch.is_finite() && camera.pitch.abs() <= OrbitCamera::MAX_PITCH) {
        return bad("pitch: must be within -1.5 to 1.5 rad");
    }
    let fov = camera.vertical_fov.to_degrees();
    if !(fov.is_finite() && (1.0..=170.0).contains(&fov)) {
        return bad("vertical_fov: must be within 1 and 170 degrees");
    }
    if !(camera.yaw.is_finite() && camera.target_world.is_finite()) {
        return bad("yaw and target: must be finite");
    }
    Ok(())
}

impl ObservedPose {
    /// The first person (several people come with the scene: only the first is lifted).
    pub fn first_person(&self) -> Result<&OpenPosePerson, LiftError> {
        self.people.first().ok_or(LiftError::NoPeople)
    }

    /// Reads an OpenPose keypoints JSON. `size_px` is the image's size when the file has no
    /// `canvas_width` and `canvas_height` (OpenPose's own output has none). Positions are
    /// pixels, or fractions of the canvas when every coordinate lies within 0 to 1.
    pub fn from_json(text: &str, size_px: Option<[u32; 2]>) -> Result<ObservedPose, LiftError> {
        let v: Value = serde_json::from_str(text)
            .map_err(|e| LiftError::NotOpenPose(format!("not JSON ({e})")))?;
        let o = v.as_object().ok_or_else(|| {
            LiftError::NotOpenPose(format!("{}, not an object with `people`", kind_of(&v)))
        })?;
        let Some(people) = o.get("people") else {
            return Err(LiftError::NotOpenPose(format!(
                "{}: OpenPose keypoints have a `people` list",
                looks_like(o)
            )));
        };
        let people = people.as_array().ok_or_else(|| {
            LiftError::NotOpenPose(format!("`people` is {}, not a list", kind_of(people)))
        })?;
        let width = canvas(o, "canvas_width")?;
        let height = canvas(o, "canvas_height")?;
        let size_px = match (width, height, size_px) {
            (Some(w), Some(h), _) => [w, h],
            (_, _, Some(size)) => size,
            _ => return Err(LiftError::NoImageSize),
        };
        let mut read = people
            .iter()
            .enumerate()
            .map(|(i, person)| read_person(i, person))
            .collect::<Result<Vec<_>, _>>()?;
        let units = to_pixels(&mut read, size_px);
        let camera = match o.get("stance_camera") {
            None | Some(Value::Null) => None,
            Some(c) => Some(camera(c)?),
        };
        Ok(ObservedPose {
            size_px,
            people: read,
            camera,
            units,
        })
    }
}

/// Person `i` of the file's `people` list (`person`), its keypoints as the file gives them.
fn read_person(i: usize, person: &Value) -> Result<OpenPosePerson, LiftError> {
    let at = format!("people[{i}]");
    let p = person.as_object().ok_or_else(|| {
        LiftError::NotOpenPose(format!("{at} is {}, not an object", kind_of(person)))
    })?;
    let list = |name: &str, count: usize| points(p.get(name), count, &format!("{at}.{name}"));
    let mut out = OpenPosePerson::EMPTY;
    if let Some(body) = list("pose_keypoints_2d", BODY_KEYPOINTS)? {
        out.body.copy_from_slice(&body);
    }
    if let Some(hand) = list("hand_left_keypoints_2d", HAND_KEYPOINTS)? {
        out.left_hand.copy_from_slice(&hand);
    }
    if let Some(hand) = list("hand_right_keypoints_2d", HAND_KEYPOINTS)? {
        out.right_hand.copy_from_slice(&hand);
    }
    Ok(out)
}

/// The keypoints of `read` in pixels of an image of `size_px`: normalised ones (every
/// keypoint within 0 to 1) scaled to it. Returns the units the file gave.
fn to_pixels(read: &mut [OpenPosePerson], size_px: [u32; 2]) -> KeypointUnits {
    let every = |read: &[OpenPosePerson]| -> Vec<DVec2> {
        read.iter()
            .flat_map(|p| p.body.iter().chain(&p.left_hand).chain(&p.right_hand))
            .flatten()
            .copied()
            .collect()
    };
    let seen = every(read);
    let fractions = !seen.is_empty()
        && seen
            .iter()
            .all(|p| (0.0..=1.0).contains(&p.x) && (0.0..=1.0).contains(&p.y));
    if !fractions {
        return KeypointUnits::Pixels;
    }
    let scale = DVec2::new(f64::from(size_px[0]), f64::from(size_px[1]));
    for person in read {
        for p in person
            .body
            .iter_mut()
            .chain(&mut person.left_hand)
            .chain(&mut person.right_hand)
            .flatten()
        {
            *p *= scale;
        }
    }
    KeypointUnits::Normalized
}
