//! Measuring RULA's angles on a posture (see the parent module's documentation).

use super::*;

/// One arm's joints and its segment axes (each in its joint's frame).
#[derive(Debug, Clone, Copy)]
pub(super) struct Arm {
    /// +1 for the left arm (outward is +X), -1 for the right.
    pub(super) side: f64,
    pub(super) clavicle: Option<usize>,
    pub(super) shoulder: usize,
    pub(super) elbow: usize,
    pub(super) wrist: usize,
    pub(super) knuckle: Option<usize>,
    /// Upper-arm axis in the shoulder frame.
    pub(super) upper_axis: DVec3,
    /// Forearm axis in the elbow frame.
    pub(super) forearm_axis: DVec3,
    /// The hand's neutral direction in the elbow (forearm) frame, and in the wrist frame.
    pub(super) hand_neutral: DVec3,
    /// The wrist's flexion axis (the forearm's front axis) in the elbow frame.
    pub(super) flexion_axis: DVec3,
    /// The clavicle (sternoclavicular joint to shoulder) at rest, body frame.
    pub(super) clavicle_rest: Option<DVec3>,
    /// The pronation/supination DOF of the elbow, the sign that makes it + pronation, and its
    /// axis index.
    pub(super) twist_dof: Option<(usize, f64, usize)>,
}

/// The joints RULA reads, resolved on one skeleton.
#[derive(Debug, Clone, Copy)]
pub(super) struct Body {
    pub(super) pelvis: usize,
    pub(super) trunk: usize,
    pub(super) head: usize,
    pub(super) feet: [usize; 2],
    pub(super) left: Arm,
    pub(super) right: Arm,
}

/// Rest positions of all joints (body frame): frames are parallel to it at rest.
pub(super) fn rest_positions(skeleton: &Skeleton) -> Vec<DVec3> {
    let mut positions: Vec<DVec3> = Vec::with_capacity(skeleton.joint_count());
    for joint in skeleton.joints() {
        let parent = joint
            .parent
            .and_then(|p| positions.get(p).copied())
            .unwrap_or(DVec3::ZERO);
        positions.push(parent + joint.offset);
    }
    positions
}

/// The direction between two joints of the H-Anim default body.
pub(super) fn default_direction(from: &str, to: &str) -> Option<DVec3> {
    let (_, a) = joint_by_name(from)?;
    let (_, b) = joint_by_name(to)?;
    (default_centre(b) - default_centre(a)).try_normalize()
}

/// The rotation that takes the H-Anim default direction of the segment `from`-`to` onto the
/// skeleton's rest direction (the identity on the default body, or when either is unknown).
pub(super) fn alignment(rest: &[DVec3], from: (usize, &str), to: (usize, &str)) -> DQuat {
    let here = match (rest.get(from.0), rest.get(to.0)) {
        (Some(&a), Some(&b)) => (b - a).try_normalize(),
        _ => None,
    };
    match (default_direction(from.1, to.1), here) {
        (Some(d0), Some(d1)) => DQuat::from_rotation_arc(d0, d1),
        _ => DQuat::IDENTITY,
    }
}

impl Arm {
    pub(super) fn resolve(skeleton: &Skeleton, rest: &[DVec3], prefix: &str) -> Option<Arm> {
        let name = |joint: &str| format!("{prefix}{joint}");
        let find = |joint: &str| resolve_joint(skeleton, &name(joint));
        let clavicle = find("sternoclavicular");
        let shoulder = find("shoulder")?;
        let elbow = find("elbow")?;
        let wrist = find("radiocarpal")?;
        let knuckle = find("metacarpophalangeal_3");
        let down = DVec3::NEG_Y;
        let upper = alignment(rest, (shoulder, &name("shoulder")), (elbow, &name("elbow")));
        let forearm = alignment(rest, (elbow, &name("elbow")), (wrist, &name("radiocarpal")));
        let hand_default = knuckle
            .and_then(|_| default_direction(&name("radiocarpal"), &name("metacarpophalangeal_3")))
            .unwrap_or(down);
        let clavicle_rest = clavicle.and_then(|c| {
            let (a, b) = (rest.get(c)?, rest.get(shoulder)?);
            (*b - *a).try_normalize()
        });
        // Pronation/supination: the elbow's rotation DOF about the forearm's rest direction.
        let forearm_rest = match (rest.get(elbow), rest.get(wrist)) {
            (Some(&a), Some(&b)) => (b - a).try_normalize(),
            _ => None,
        };
        let twist_dof = forearm_rest.and_then(|f| {
            let axis = f.abs().max_position();
            let dof = skeleton.joints().get(elbow)?.rotation_dof[axis]?;
            Some((dof, f[axis].signum(), axis))
        });
        let side = if prefix.starts_with('r') { -1.0 } else { 1.0 };
        Some(Arm {
            side,
            clavicle,
            shoulder,
            elbow,
            wrist,
            knuckle,
            upper_axis: upper * down,
            forearm_axis: forearm * down,
            hand_neutral: (forearm * hand_default).normalize_or_zero(),
            flexion_axis: forearm * DVec3::Z,
            clavicle_rest,
            twist_dof,
        })
    }
}

impl Body {
    pub(super) fn resolve(skeleton: &Skeleton) -> Option<Body> {
        let rest = rest_positions(skeleton);
        let find = |name: &str| resolve_joint(skeleton, name);
        let left = Arm::resolve(skeleton, &rest, "l_")?;
        let right = Arm::resolve(skeleton, &rest, "r_")?;
        let pelvis = find("sacroiliac")?;
        let head = find("skullbase")?;
        let hips = [find("l_hip")?, find("r_hip")?];
        // The upper trunk: the spine joint the shoulders hang from.
        let joints = skeleton.joints();
        let first_parent = joints.get(left.shoulder)?.parent?;
        let mut trunk = first_parent;
        let mut at = Some(first_parent);
        while let Some(j) = at {
            let joint = joints.get(j)?;
            if JointClass::of(&joint.name) == JointClass::Spine {
                trunk = j;
                break;
            }
            at = joint.parent;
        }
        let foot = |prefix: &str, hip: usize| {
            find(&format!("{prefix}talocrural"))
                .or_else(|| find(&format!("{prefix}knee")))
                .unwrap_or(hip)
        };
        Some(Body {
            pelvis,
            trunk,
            head,
            feet: [foot("l_", hips[0]), foot("r_", hips[1])],
            left,
            right,
        })
    }
}

/// The signed angle from `from` to `to` about the unit `axis`, both projected on the plane
/// normal to it (radians).
pub(super) fn angle_about(axis: DVec3, from: DVec3, to: DVec3) -> f64 {
    let a = from - axis * from.dot(axis);
    let b = to - axis * to.dot(axis);
    a.cross(b).dot(axis).atan2(a.dot(b))
}

/// The angle between two vectors (radians, 0 to pi).
pub(super) fn angle_between(a: DVec3, b: DVec3) -> f64 {
    a.cross(b).length().atan2(a.dot(b))
}

/// The arcsine of a component, clamped (radians).
pub(super) fn elevation(component: f64) -> f64 {
    component.clamp(-1.0, 1.0).asin()
}

/// The angle of the rotation `relative` about its frame's y axis (swing-twist decomposition;
/// radians, -pi to pi).
pub(super) fn twist_about_y(relative: DMat3) -> f64 {
    let q = DQuat::from_mat3(&relative).normalize();
    let q = if q.w < 0.0 { -q } else { q };
    2.0 * q.y.atan2(q.w)
}

/// The horizontal part of `v`, normalised (`None` when `v` is vertical).
pub(super) fn horizontal(v: DVec3) -> Option<DVec3> {
    DVec3::new(v.x, 0.0, v.z).try_normalize()
}

pub(super) fn measure_arm(
    skeleton: &Skeleton,
    frames: &Frames,
    body: &Body,
    arm: &Arm,
) -> ArmAngles {
    let rotation = |j: usize| {
        frames
            .world_from_joint_rotation
            .get(j)
            .copied()
            .unwrap_or(DMat3::IDENTITY)
    };
    let position = |j: usize| frames.joint_position.get(j).copied().unwrap_or(DVec3::ZERO);
    let trunk = rotation(body.trunk);
    let to_trunk = trunk.transpose();
    let side = arm.side;
    // Upper arm in the trunk frame.
    let upper = rotation(arm.shoulder) * arm.upper_axis;
    let a = to_trunk * upper;
    let mut flexion = a.z.atan2(-a.y).to_degrees();
    if flexion < -90.0 {
        flexion += 360.0;
    }
    let abduction = elevation(side * a.x).to_degrees();
    let shoulder_elevation = arm.clavicle.zip(arm.clavicle_rest).and_then(|(c, rest)| {
        let now = (to_trunk * (position(arm.shoulder) - position(c))).try_normalize()?;
        Some((elevation(now.y) - elevation(rest.y)).to_degrees())
    });
    // Elbow.
    let elbow = rotation(arm.elbow);
    let forearm = elbow * arm.forearm_axis;
    let elbow_flexion = angle_between(upper, forearm).to_degrees();
    // Hand position against the midline.
    let middle = 0.5 * (position(body.left.shoulder) + position(body.right.shoulder));
    let lateral = |p: DVec3| side * (to_trunk * (p - middle)).x;
    let shoulder_out = lateral(position(arm.shoulder));
    let wrist_out = lateral(position(arm.wrist));
    let across_midline = wrist_out < 0.0;
    let out_to_side = shoulder_out > 0.0 && wrist_out >= OUT_TO_SIDE_RATIO * shoulder_out;
    // Wrist, in the forearm frame.
    let to_forearm = elbow.transpose();
    let by_frame = to_forearm * rotation(arm.wrist) * arm.hand_neutral;
    let hand = arm
        .knuckle
        .and_then(|k| (to_forearm * (position(k) - position(arm.wrist))).try_normalize())
        .unwrap_or(by_frame);
    let n = arm.hand_neutral;
    let z = arm.flexion_axis;
    // + about the front axis bends a left hand toward +X, away from its palm.
    let wrist_flexion = (-side * angle_about(z, n, hand)).to_degrees();
    let wrist_deviation = (elevation(hand.dot(z)) - elevation(n.dot(z))).to_degrees();
    // Forearm rotation from the elbow's local rotation.
    let (forearm_rotation, wrist_twist) = match arm.twist_dof {
        Some((dof, sign, axis)) => {
            let local = rotation(arm.shoulder).transpose() * elbow;
            let value = DQuat::from_mat3(&local).normalize().to_scaled_axis()[axis];
            let (lo, hi) = (
                skeleton
                    .lower_limits()
                    .get(dof)
                    .copied()
                    .unwrap_or(f64::NAN),
                skeleton
                    .upper_limits()
                    .get(dof)
                    .copied()
                    .unwrap_or(f64::NAN),
            );
            let quarter = 0.25 * (hi - lo);
            let near_end = quarter.is_finite()
                && quarter > 0.0
                && (value < lo + quarter || value > hi - quarter);
            (
                Some((side * sign * value).to_degrees()),
                if near_end { 2 } else { 1 },
            )
        }
        None => (None, 1),
    };
    ArmAngles {
        upper_arm_flexion: flexion,
        upper_arm_abduction: abduction,
        shoulder_elevation,
        elbow_flexion,
        across_midline,
        out_to_side,
        wrist_flexion,
        wrist_deviation,
        forearm_rotation,
        wrist_twist,
    }
}

/// Measures the angles RULA reads on a posture (see the module documentation). `None` when
/// the skeleton lacks a joint it needs: `l_`/`r_` `shoulder`, `elbow`, `radiocarpal`, `hip`,
/// and `sacroiliac`, `skullbase`; or when `frames` do not cover the skeleton.
pub fn measure(skeleton: &Skeleton, frames: &Frames) -> Option<RulaAngles> {
    if frames.world_from_joint_rotation.len() < skeleton.joint_count()
        || frames.joint_position.len() < skeleton.joint_count()
    {
        return None;
    }
    let body = Body::resolve(skeleton)?;
    let rotation = |j: usize| frames.world_from_joint_rotation[j];
    let trunk = rotation(body.trunk);
    let pelvis = rotation(body.pelvis);
    let head = rotation(body.head);
    // Neck: the head in the trunk frame.
    let neck = trunk.transpose() * head;
    let head_up = neck * DVec3::Y;
    let neck_flexion = head_up.z.atan2(head_up.y).to_degrees();
    let neck_side_bend = head_up.x.atan2(head_up.y.hypot(head_up.z)).to_degrees();
    let neck_twist = twist_about_y(neck).to_degrees();
    // Trunk against vertical, in its own sagittal plane.
    let up = trunk * DVec3::Y;
    let left = horizontal(trunk * DVec3::X)
        .or_else(|| horizontal(pelvis * DVec3::X))
        .unwrap_or(DVec3::X);
    let front = left.cross(DVec3::Y);
    let trunk_flexion = up.dot(front).atan2(up.y).to_degrees();
    let trunk_side_bend = up.dot(left).atan2(up.dot(front).hypot(up.y)).to_degrees();
    let trunk_twist = twist_about_y(pelvis.transpose() * trunk).to_degrees();
    // Legs: feet level, the centre of mass between them.
    let [l_foot, r_foot] = body.feet.map(|f| frames.joint_position[f]);
    let level = (l_foot.y - r_foot.y).abs() <= FEET_LEVEL_M;
    let span = DVec3::new(l_foot.x - r_foot.x, 0.0, l_foot.z - r_foot.z);
    let com = frames.center_of_mass() - r_foot;
    let share = DVec3::new(com.x, 0.0, com.z).dot(span) / span.length_squared();
    let balanced = span.length() > 0.01 && (BALANCED_SHARE..=1.0 - BALANCED_SHARE).contains(&share);
    Some(RulaAngles {
        left: measure_arm(skeleton, frames, &body, &body.left),
        right: measure_arm(skeleton, frames, &body, &body.right),
        neck_flexion,
        neck_twist,
        neck_side_bend,
        trunk_flexion,
        trunk_twist,
        trunk_side_bend,
        weight_balanced: level && balanced,
    })
}
