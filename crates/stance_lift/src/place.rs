//! Arms and legs placed on their keypoints' rays in closed form.
//!
//! With its upper joint (a shoulder, a hip) where the body put it, a limb's middle joint (the
//! elbow, the knee) lies on its keypoint's camera ray at its bone's length from the upper
//! joint: where the ray meets that sphere, at two points, one nearer the camera and one
//! farther, mirror images in the plane through the upper joint perpendicular to the ray. The
//! end joint (the wrist, the ankle) likewise, from the middle joint. Each choice of the two
//! gives a limb that projects onto the same keypoints: this is the depth a single image leaves
//! open. The limb's closed form ([`stance_ik::Limb`]) then turns the three joints to put the
//! end joint there with the middle joint on its side (its swivel angle), within the joint
//! limits where it can.

use glam::DVec3;
use stance_ik::{Frames, Limb, LimbGoal, Posture, Skeleton};

/// A ray from the camera: origin and unit direction.
pub(crate) type Ray = (DVec3, DVec3);

/// The two points where `ray` meets the sphere about `centre` of `radius`: nearer the camera
/// first. Where the ray passes the sphere by, its point nearest the centre, twice.
pub(crate) fn ray_sphere(ray: Ray, centre: DVec3, radius: f64) -> [DVec3; 2] {
    let (origin, direction) = ray;
    let to_centre = centre - origin;
    let along = to_centre.dot(direction);
    let off_sq = (to_centre.length_squared() - along * along).max(0.0);
    let half = (radius * radius - off_sq).max(0.0).sqrt();
    [
        origin + direction * (along - half),
        origin + direction * (along + half),
    ]
}

/// The other of the two points of [`ray_sphere`]: `point` (on `ray`) mirrored in the plane
/// through `centre` perpendicular to the ray.
pub(crate) fn other_depth(ray: Ray, centre: DVec3, point: DVec3) -> DVec3 {
    let direction = ray.1;
    point - direction * (2.0 * (point - centre).dot(direction))
}

/// A limb of the body and its keypoints (COCO-18 indices of the middle and end joints).
#[derive(Debug, Clone, Copy)]
pub(crate) struct LimbKeypoints {
    /// Upper, middle and end joint names.
    pub joints: [&'static str; 3],
    /// The middle and end joints' keypoints.
    pub keypoints: [usize; 2],
}

/// The arms and legs, in COCO-18 order.
pub(crate) const LIMBS: [LimbKeypoints; 4] = [
    LimbKeypoints {
        joints: ["r_shoulder", "r_elbow", "r_radiocarpal"],
        keypoints: [3, 4],
    },
    LimbKeypoints {
        joints: ["l_shoulder", "l_elbow", "l_radiocarpal"],
        keypoints: [6, 7],
    },
    LimbKeypoints {
        joints: ["r_hip", "r_knee", "r_talocrural"],
        keypoints: [9, 10],
    },
    LimbKeypoints {
        joints: ["l_hip", "l_knee", "l_talocrural"],
        keypoints: [12, 13],
    },
];

/// A limb's closed form on a skeleton: the limb and its joints' bone lengths.
pub(crate) struct PlacedLimb {
    limb: Limb,
    joints: [usize; 3],
    lengths: [f64; 2],
}

impl PlacedLimb {
    /// The limb of `joints` on `skeleton`, if it has them.
    pub fn new(skeleton: &Skeleton, joints: [&str; 3]) -> Option<PlacedLimb> {
        let limb = Limb::from_names(skeleton, joints).ok()?;
        let [upper, middle, end] = limb.joints();
        let rest = Frames::new(skeleton, &Posture::rest(skeleton));
        let at = |j: usize| rest.joint_position[j];
        Some(PlacedLimb {
            limb,
            joints: [upper, middle, end],
            lengths: [
                (at(middle) - at(upper)).length(),
                (at(end) - at(middle)).length(),
            ],
        })
    }

    /// The bone lengths: upper to middle joint, middle to end joint (m).
    pub fn lengths(&self) -> [f64; 2] {
        self.lengths
    }

    /// The limb's joints (upper, middle, end).
    pub fn joints(&self) -> [usize; 3] {
        self.joints
    }

    /// The joints' world positions (upper, middle, end) in `frames`.
    pub fn positions(&self, frames: &Frames) -> [DVec3; 3] {
        self.joints.map(|j| frames.joint_position[j])
    }

    /// The middle and end joints' places on their rays in `frames`, for each of the four
    /// choices of depth (`[middle farther, end farther]` as bits: 0 both nearer... 3 both
    /// farther), each end point found from its middle point.
    /// With `floor` (a height), the end joint stands on it: where its ray meets that level,
    /// whatever the choice.
    pub fn candidates(
        &self,
        frames: &Frames,
        rays: [Ray; 2],
        floor: Option<f64>,
    ) -> [[DVec3; 2]; 4] {
        let upper = frames.joint_position[self.joints[0]];
        let middles = ray_sphere(rays[0], upper, self.lengths[0]);
        let (origin, direction) = rays[1];
        let on_floor = floor
            .filter(|_| direction.y.abs() > 1e-6)
            .map(|height| origin + direction * ((height - origin.y) / direction.y))
            .filter(|p| (*p - origin).dot(direction) > 0.0);
        std::array::from_fn(|choice| {
            let middle = middles[choice & 1];
            let end = on_floor
                .unwrap_or_else(|| ray_sphere(rays[1], middle, self.lengths[1])[(choice >> 1) & 1]);
            [middle, end]
        })
    }

    /// `posture` with the limb turned to put its end joint at `goal[1]` and its middle joint
    /// on the side of `goal[0]` (the swivel angle that does, moved within the joint limits
    /// when it is not). Returns whether the joints stay within their limits.
    pub fn place(&self, skeleton: &Skeleton, posture: &mut Posture, goal: [DVec3; 2]) -> bool {
        let frames = Frames::new(skeleton, posture);
        let base = self.limb.base(skeleton, &frames);
        let target = LimbGoal::position(goal[1]);
        // Where swivel 0 puts the middle joint; the wanted swivel turns it about the axis
        // from the upper joint to the end joint onto the wanted side.
        let zero = self.limb.solve(base, &target, 0.0);
        let mut trial = posture.clone();
        self.limb.apply(&zero, &mut trial);
        let at_zero = Frames::new(skeleton, &trial).joint_position[self.joints[1]];
        let axis = (zero.end_position - base.upper_position).normalize_or_zero();
        let across = |p: DVec3| {
            let v = p - base.upper_position;
            v - axis * v.dot(axis)
        };
        let (from, to) = (across(at_zero), across(goal[0]));
        let swivel = from.cross(to).dot(axis).atan2(from.dot(to));
        let solution = self
            .limb
            .solve_within_limits(base, &target, zero.swivel_angle + swivel);
        self.limb.apply(&solution, posture);
        solution.within_limits
    }
}
