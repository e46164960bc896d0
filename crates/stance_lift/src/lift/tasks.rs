//! The lift's tasks: each keypoint on its camera ray (level 1), the standing feet on the
//! floor (level 2) and balance over them (level 3).

use glam::DVec2;
use stance_document::{TaskKindSpec, TaskSpec};
use stance_hanim::keypoints::{HAND_KEYPOINTS, KeypointFinder, KeypointSource, NECK};
use stance_ik::{Effector, Frames, Skeleton};
use stance_render::OpenPosePerson;

use super::{
    BALANCE_LEVEL, FLOOR_LEVEL, IMAGE_LEVEL, L_ANKLE, L_SHOULDER, R_ANKLE, R_SHOULDER,
    STANDING_SLACK_M, Scale, View,
};

/// The joint name of an effector.
fn joint_name(skeleton: &Skeleton, effector: &Effector) -> Option<String> {
    Some(skeleton.joints().get(effector.joint)?.name.clone())
}

/// The level-1 tasks: every visible keypoint's body point on the camera ray through its
/// pixel. The neck is the shoulders' midpoint, not a point of one segment: with both shoulders
/// seen it adds no task (their rays place it); with one shoulder missing, that shoulder is
/// taken at the neck's mirror of the other's pixel (exact in orthographic projection, within
/// about a pixel at the usual distances). Returns the tasks and how many keypoints they hold.
pub(super) fn image_plane_tasks(
    skeleton: &Skeleton,
    finder: &KeypointFinder,
    person: &OpenPosePerson,
    view: &View,
) -> (Vec<TaskSpec>, usize) {
    let sources = finder.sources(skeleton);
    let mut body = person.body;
    if let Some(neck) = body[NECK] {
        match (body[R_SHOULDER], body[L_SHOULDER]) {
            (Some(r), None) => body[L_SHOULDER] = Some(neck * 2.0 - r),
            (None, Some(l)) => body[R_SHOULDER] = Some(neck * 2.0 - l),
            _ => {}
        }
    }
    let mut tasks = Vec::new();
    let mut used = 0;
    let mut on_ray = |effector: &Effector, pixel: DVec2| {
        let Some(joint) = joint_name(skeleton, effector) else {
            return false;
        };
        let (origin, direction) = view.ray(pixel);
        let mut task = TaskSpec::new(TaskKindSpec::Line {
            joint,
            point: effector.point.to_array(),
            origin: origin.to_array(),
            direction: direction.to_array(),
        });
        task.level = IMAGE_LEVEL;
        tasks.push(task);
        true
    };
    for (k, (pixel, source)) in body.iter().zip(sources.body).enumerate() {
        if let (Some(pixel), Some(KeypointSource::On(effector))) = (pixel, source)
            && on_ray(&effector, *pixel)
            && person.body[k].is_some()
        {
            used += 1;
        }
    }
    used += usize::from(person.body[NECK].is_some());
    for (hand, effectors) in [
        (&person.left_hand, sources.left_hand),
        (&person.right_hand, sources.right_hand),
    ] {
        for (pixel, effector) in hand.iter().zip(effectors).take(HAND_KEYPOINTS) {
            if let (Some(pixel), Some(effector)) = (pixel, effector)
                && on_ray(&effector, *pixel)
            {
                used += 1;
            }
        }
    }
    (tasks, used)
}

/// The ankles (COCO indices) taken to stand on the floor: those seen within
/// [`STANDING_SLACK_M`] of the lowest ankle in the image.
pub(super) fn standing_ankles(person: &OpenPosePerson, scale: &Scale) -> Vec<usize> {
    let ankles: Vec<(usize, f64)> = [R_ANKLE, L_ANKLE]
        .into_iter()
        .filter_map(|k| Some((k, person.body[k]?.y)))
        .collect();
    let lowest = ankles.iter().map(|a| a.1).fold(f64::NEG_INFINITY, f64::max);
    ankles
        .into_iter()
        .filter(|&(_, y)| y >= lowest - STANDING_SLACK_M * scale.px_per_m)
        .map(|(k, _)| k)
        .collect()
}

const ANKLE_JOINTS: [(usize, &str); 2] = [(R_ANKLE, "r_talocrural"), (L_ANKLE, "l_talocrural")];

pub(super) fn standing_feet(person: &OpenPosePerson, scale: &Scale) -> Vec<String> {
    let standing = standing_ankles(person, scale);
    ANKLE_JOINTS
        .iter()
        .filter(|(k, _)| standing.contains(k))
        .map(|(_, name)| (*name).to_owned())
        .collect()
}

/// Level 2: each ankle at its rest height over the floor when it stands, else on or above
/// that height; level 3: balance over the standing feet.
pub(super) fn floor_tasks(
    skeleton: &Skeleton,
    rest: &Frames,
    standing: &[String],
) -> Vec<TaskSpec> {
    let mut tasks = Vec::new();
    for (_, name) in ANKLE_JOINTS {
        let Some(j) = skeleton.joint_index(name) else {
            continue;
        };
        let height = rest.joint_position.get(j).map_or(0.0, |p| p.y);
        let mut task = TaskSpec::new(TaskKindSpec::Plane {
            joint: name.to_owned(),
            point: [0.0; 3],
            origin: [0.0, height, 0.0],
            normal: [0.0, 1.0, 0.0],
            above: !standing.iter().any(|s| s == name),
        });
        task.level = FLOOR_LEVEL;
        tasks.push(task);
    }
    if !standing.is_empty() {
        let mut balance = TaskSpec::balance();
        balance.kind = TaskKindSpec::Balance {
            support: Some(standing.to_vec()),
            margin: stance_document::DEFAULT_BALANCE_MARGIN,
        };
        balance.level = BALANCE_LEVEL;
        tasks.push(balance);
    }
    tasks
}
