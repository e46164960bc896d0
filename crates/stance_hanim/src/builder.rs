//! Builds a [`stance_ik::Skeleton`] at a chosen level of articulation from a mapped avatar
//! (levels of mobility: the same avatar can be solved at LOA1 or LOA2), or from the H-Anim
//! default joint centres.
//!
//! **One meaning for posture values.** A built skeleton's rest is the H-Anim standard pose
//! (standing, arms at the sides: the default mannequin's), whatever the avatar's own rest: the
//! avatar's limbs are matched onto it once, bone by bone, with the bone-direction rest match of
//! [`crate::rest_match`] (the rest match of retargeting; the trunk, neck and head keep their
//! rest, their curve being the body's shape), and each joint keeps its segment lengths. [`BuiltJoint::rest_match`] is that world rotation: a posture's world rotation
//! `G` of a joint poses the avatar's node as `G · rest_match · (the node's rest)`. So the same
//! posture shows the same pose on the mannequin and on a T-pose, A-pose or any other avatar.
//!
//! Joint frames are parallel to the body frame at rest (the `stance_ik` convention), so the
//! anatomical ranges of [`crate::anatomy`] are re-expressed for the skeleton's rest: the
//! rotation that takes each H-Anim default segment direction (towards the segment's first
//! distal joint) onto the skeleton's shifts the ranges of that joint, and the frame of the
//! segment above it permutes the DOF axes of the joints below. In the standard pose these
//! rotations are small (the rest match turns each bone towards the mean of its children, and a
//! body's proportions differ from the default's), so the default axes are kept; where a frame
//! is within 45 degrees of axis-aligned, the nearest world axes are used (with a note); beyond,
//! the joint gets all three rotational DOF with the envelope of its ranges.

use glam::{DMat3, DQuat, DVec3};
use stance_ik::{Dof, Frames, IkError, JointDef, Posture, Skeleton};

use crate::anatomy::{self, JointClass};
use crate::mapping::{Mapping, MatchMethod};
use crate::names::Side;
use crate::{LevelOfArticulation, humanoid_joints};

/// Options of [`build_skeleton`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SkeletonOptions {
    /// Level of articulation (default LOA2).
    pub loa: LevelOfArticulation,
    /// Whole-body mass for the segment masses (kg, default 70).
    pub body_mass_kg: f64,
}

impl Default for SkeletonOptions {
    fn default() -> Self {
        Self {
            loa: LevelOfArticulation::Loa2,
            body_mass_kg: 70.0,
        }
    }
}

/// Which anatomical axis a built rotation DOF stands for: the anatomical ranges, strengths
/// and sign conventions of [`crate::anatomy`] are given about the H-Anim rest frame's axes; an
/// avatar's joint frame may have its axes permuted or reversed relative to it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AnatomicalAxis {
    /// The built DOF.
    pub dof: Dof,
    /// The anatomical DOF it carries (in the conventions of [`crate::anatomy`]).
    pub anatomical: Dof,
    /// +1 when a positive built value is a positive anatomical value, else -1.
    pub sign: f64,
}

/// One joint of a built skeleton (same index as in [`HumanoidSkeleton::skeleton`]).
#[derive(Debug, Clone, PartialEq)]
pub struct BuiltJoint {
    /// H-Anim 2.0 name (also the `stance_ik` joint name).
    pub hanim: &'static str,
    /// Source joint (avatar node) index; `None` for the default body.
    pub source: Option<usize>,
    /// False for implied joints (no DOF of their own).
    pub has_dofs: bool,
    /// The anatomical axis of each rotation DOF (empty: unknown, e.g. a joint far from any
    /// axis-aligned frame given envelope ranges).
    pub axes: Vec<AnatomicalAxis>,
    /// The world rotation (H-Anim frame) that turns the source joint's bone at the avatar's
    /// own rest onto the standard pose, the skeleton's rest: the avatar's node is posed as
    /// `world_from_joint · rest_match · (its rest world rotation)`. Only the limbs are matched
    /// (the joints on the body's sides: arms, hands, legs, feet); the trunk, neck and head
    /// keep their rest (identity), as on the default body and on avatars whose rest is the
    /// standard pose. A limb joint without a bone of its own (nothing mapped below it: a hand
    /// at LOA1) turns with its parent.
    pub rest_match: DQuat,
    /// The joint's position at the avatar's own rest (H-Anim frame, metres): its source
    /// joint's; the skeleton's rest position on the default body.
    pub own_rest: DVec3,
}

/// A built skeleton and how its joints relate to the avatar.
#[derive(Debug, Clone, PartialEq)]
pub struct HumanoidSkeleton {
    /// The solver's skeleton (H-Anim joint names).
    pub skeleton: Skeleton,
    /// Per skeleton joint, in skeleton order.
    pub joints: Vec<BuiltJoint>,
    /// The level it was built at.
    pub loa: LevelOfArticulation,
    /// Remarks (joints given envelope ranges...).
    pub notes: Vec<String>,
}

/// Errors of the builder.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum BuildError {
    /// The avatar lacks joints every humanoid has.
    #[error("not a humanoid: no joint found for {}", .missing.join(", "))]
    NotHumanoid {
        /// The missing H-Anim LOA1 joints.
        missing: Vec<String>,
    },
    /// A source joint position is missing or not finite.
    #[error("rest position of source joint {0} is missing or not finite")]
    BadPosition(usize),
    /// The solver rejected the skeleton.
    #[error("skeleton: {0}")]
    Ik(#[from] IkError),
}

struct Input {
    hanim: &'static str,
    class: JointClass,
    position: DVec3,
    default: DVec3,
    source: Option<usize>,
    implied: bool,
    parent: Option<usize>,
}

/// Builds the skeleton of a mapped avatar in the H-Anim standard pose (see the module
/// documentation). `rest_positions[i]`: world rest position of source joint `i` at the
/// avatar's own rest, in the H-Anim frame (+Y up, +Z front, +X left, metres).
pub fn build_skeleton(
    mapping: &Mapping,
    rest_positions: &[DVec3],
    options: &SkeletonOptions,
) -> Result<HumanoidSkeleton, BuildError> {
    let missing: Vec<String> = mapping
        .missing(LevelOfArticulation::Loa1)
        .into_iter()
        .map(str::to_owned)
        .collect();
    if !missing.is_empty() {
        return Err(BuildError::NotHumanoid { missing });
    }
    let mut lookup = Vec::new();
    for m in mapping.matches() {
        let p = rest_positions
            .get(m.source)
            .copied()
            .filter(|p| p.is_finite())
            .ok_or(BuildError::BadPosition(m.source))?;
        lookup.push((m.hanim, p, m.source, m.method == MatchMethod::Implied));
    }
    let own_rest = build(options, |name| {
        lookup
            .iter()
            .find(|(h, ..)| *h == name)
            .map(|&(_, p, s, implied)| (p, Some(s), implied))
    })?;
    let (standard, rest_match) = standard_pose(&own_rest, options.loa);
    let mut body = build(options, |name| {
        let k = own_rest.skeleton.joint_index(name)?;
        let implied = lookup
            .iter()
            .find(|(h, ..)| *h == name)
            .is_some_and(|l| l.3);
        Some((*standard.get(k)?, own_rest.joints.get(k)?.source, implied))
    })?;
    let own_positions =
        Frames::new(&own_rest.skeleton, &Posture::rest(&own_rest.skeleton)).joint_position;
    for joint in &mut body.joints {
        if let Some(k) = own_rest.skeleton.joint_index(joint.hanim)
            && let (Some(m), Some(p)) = (rest_match.get(k), own_positions.get(k))
        {
            joint.rest_match = *m;
            joint.own_rest = *p;
        }
    }
    Ok(body)
}

/// The joint positions of `own_rest` (a skeleton built at an avatar's own rest) in the
/// H-Anim standard pose, and per joint the world rotation that takes its bone there (see
/// [`BuiltJoint::rest_match`]). The segments keep their lengths; the ankles keep their mean
/// height (the feet stay on the floor).
fn standard_pose(
    own_rest: &HumanoidSkeleton,
    loa: LevelOfArticulation,
) -> (Vec<DVec3>, Vec<DQuat>) {
    let skeleton = &own_rest.skeleton;
    let rest = Frames::new(skeleton, &Posture::rest(skeleton)).joint_position;
    let table = humanoid_joints(loa);
    let standard: Vec<Option<DVec3>> = own_rest
        .joints
        .iter()
        .map(|j| {
            table
                .iter()
                .find(|t| t.definition.name == j.hanim)
                .map(|t| t.rest_centre)
        })
        .collect();
    let bones = crate::rest_match::bone_directions(own_rest, &rest, &standard);
    let joints = skeleton.joints();
    let has_children: Vec<bool> = (0..joints.len())
        .map(|k| joints.iter().any(|j| j.parent == Some(k)))
        .collect();
    let mut matched: Vec<DQuat> = Vec::with_capacity(joints.len());
    let mut positions: Vec<DVec3> = Vec::with_capacity(joints.len());
    for (k, joint) in joints.iter().enumerate() {
        let parent = joint
            .parent
            .and_then(|p| matched.get(p).copied().zip(positions.get(p)));
        let limb = own_rest
            .joints
            .get(k)
            .is_some_and(|j| Side::of(j.hanim) != Side::Centre);
        let m = match (bones.get(k).copied().flatten(), parent) {
            // The trunk, neck and head keep their rest: a spine's curve is the body's shape,
            // not a pose (a T-pose and an A-pose differ in the limbs), and the root's short
            // offset to the spine is no limb direction.
            _ if !limb => DQuat::IDENTITY,
            (_, None) => DQuat::IDENTITY,
            (Some(m), _) => m,
            (None, Some((m, _))) if !has_children[k] => m,
            _ => DQuat::IDENTITY,
        };
        let own = rest.get(k).copied().unwrap_or_default();
        let position = match (joint.parent, parent) {
            (Some(p), Some((parent_match, parent_position))) => {
                *parent_position + parent_match * (own - rest.get(p).copied().unwrap_or_default())
            }
            _ => own,
        };
        matched.push(m);
        positions.push(position);
    }
    let ankles = |p: &[DVec3]| {
        let ys: Vec<f64> = ["l_talocrural", "r_talocrural"]
            .iter()
            .filter_map(|n| skeleton.joint_index(n).and_then(|k| p.get(k)))
            .map(|v| v.y)
            .collect();
        (!ys.is_empty()).then(|| ys.iter().sum::<f64>() / ys.len() as f64)
    };
    if let (Some(own), Some(now)) = (ankles(&rest), ankles(&positions)) {
        let lift = DVec3::new(0.0, own - now, 0.0);
        for p in &mut positions {
            *p += lift;
        }
    }
    (positions, matched)
}

/// The skeleton of the H-Anim default body (default joint centres) at `options.loa`.
pub fn default_skeleton(options: &SkeletonOptions) -> Result<HumanoidSkeleton, BuildError> {
    let joints = humanoid_joints(options.loa);
    build(options, |name| {
        joints
            .iter()
            .find(|j| j.definition.name == name)
            .map(|j| (j.rest_centre, None, false))
    })
}

fn build(
    options: &SkeletonOptions,
    lookup: impl Fn(&str) -> Option<(DVec3, Option<usize>, bool)>,
) -> Result<HumanoidSkeleton, BuildError> {
    let table = humanoid_joints(options.loa);
    // Included joints and the nearest included ancestor of each.
    let mut included: Vec<Option<usize>> = vec![None; table.len()];
    let mut inputs: Vec<Input> = Vec::new();
    for (k, j) in table.iter().enumerate() {
        let Some((position, source, implied)) = lookup(j.definition.name) else {
            continue;
        };
        let mut parent = j.parent;
        while let Some(p) = parent {
            if included[p].is_some() {
                break;
            }
            parent = table[p].parent;
        }
        included[k] = Some(inputs.len());
        inputs.push(Input {
            hanim: j.definition.name,
            class: JointClass::of(j.definition.name),
            position,
            default: j.rest_centre,
            source,
            implied,
            parent: parent.and_then(|p| included[p]),
        });
    }
    if inputs.first().map(|i| i.class) != Some(JointClass::Root) {
        return Err(BuildError::NotHumanoid {
            missing: vec!["humanoid_root".into()],
        });
    }
    let children = |i: usize| -> Vec<usize> {
        (0..inputs.len())
            .filter(|&c| inputs[c].parent == Some(i))
            .collect()
    };
    // Distal joint of each (for segment direction and centre of mass).
    let distal: Vec<Option<usize>> = (0..inputs.len())
        .map(|i| {
            let kids = children(i);
            match inputs[i].class {
                JointClass::Wrist => kids
                    .iter()
                    .copied()
                    .find(|&c| inputs[c].hanim.ends_with("_3"))
                    .or_else(|| kids.first().copied()),
                JointClass::Root | JointClass::Pelvis => None,
                _ => kids.first().copied(),
            }
        })
        .collect();
    let aligned = |c: JointClass| {
        matches!(
            c,
            JointClass::Clavicle
                | JointClass::Acromion
                | JointClass::Shoulder
                | JointClass::Elbow
                | JointClass::Wrist
                | JointClass::Hip
                | JointClass::Knee
                | JointClass::ThumbBase
                | JointClass::Metacarpal
                | JointClass::Knuckle
                | JointClass::FingerHinge
        )
    };
    // Rotation from the H-Anim default direction of each segment to the avatar's. Joints
    // with no distal joint (a hand at LOA1) follow the segment above them.
    let mut alignment: Vec<DQuat> = Vec::with_capacity(inputs.len());
    for i in 0..inputs.len() {
        let inherited = inputs[i]
            .parent
            .filter(|&p| aligned(inputs[p].class))
            .map_or(DQuat::IDENTITY, |p| alignment[p]);
        let own = distal[i]
            .filter(|_| aligned(inputs[i].class))
            .and_then(|d| {
                let d0 = inputs[d].default - inputs[i].default;
                let d1 = inputs[d].position - inputs[i].position;
                (d0.length() > 1e-6 && d1.length() > 1e-9)
                    .then(|| DQuat::from_rotation_arc(d0.normalize(), d1.normalize()))
            });
        let a = match own {
            Some(a) => a,
            None if aligned(inputs[i].class) => inherited,
            None => DQuat::IDENTITY,
        };
        alignment.push(a);
    }
    let count = |pred: &dyn Fn(&Input) -> bool| inputs.iter().filter(|i| pred(i)).count();
    let spine_share = count(&|i| i.class == JointClass::Spine && !i.implied);
    let neck_share = count(&|i| i.class == JointClass::Neck && !i.implied);
    let lumbar = count(&|i| i.hanim.starts_with("vl"));
    let thoracic = count(&|i| i.hanim.starts_with("vt"));
    let default_height = 1.6209 - 0.824;
    let scale = {
        let root = inputs[0].position;
        inputs
            .iter()
            .find(|i| i.hanim == "skullbase")
            .map_or(1.0, |s| {
                ((s.position - root).length() / default_height).max(1e-3)
            })
    };
    let mass = options.body_mass_kg.max(0.0);
    let fraction = |name: &str| {
        anatomy::SEGMENTS
            .iter()
            .find(|s| s.name == name)
            .map_or(0.0, |s| s.mass_fraction)
    };
    let mut notes = Vec::new();
    let mut defs = Vec::with_capacity(inputs.len());
    let mut axes_by_joint = Vec::with_capacity(inputs.len());
    for (i, input) in inputs.iter().enumerate() {
        let parent_pos = input.parent.map(|p| inputs[p].position);
        let offset = input.position - parent_pos.unwrap_or(DVec3::ZERO);
        let parent_name = input.parent.map(|p| inputs[p].hanim);
        // DOF and limits.
        let (dofs, limits, anatomical_axes) = if input.class == JointClass::Root {
            (anatomy::dofs(JointClass::Root), Vec::new(), Vec::new())
        } else if input.implied {
            (Vec::new(), Vec::new(), Vec::new())
        } else {
            let share = match input.class {
                JointClass::Spine => spine_share,
                JointClass::Neck => neck_share,
                _ => 1,
            };
            let anatomical = anatomy::limits(input.hanim, share);
            let frame_alignment = input
                .parent
                .filter(|&p| aligned(inputs[p].class))
                .map_or(DQuat::IDENTITY, |p| alignment[p]);
            let frame_matrix = DMat3::from_quat(frame_alignment);
            let snapped = snap_to_axes(frame_matrix, 25.0).or_else(|| {
                let loose = snap_to_axes(frame_matrix, 45.0);
                if loose.is_some() {
                    notes.push(format!(
                        "{}: segment above far from the default direction, nearest axes used",
                        input.hanim
                    ));
                }
                loose
            });
            match snapped {
                Some(frame) => {
                    let relative = (DQuat::from_mat3(&frame).inverse() * alignment[i]).normalize();
                    // The shortest rotation (w >= 0), so the shift stays within +-pi.
                    let relative = if relative.w < 0.0 {
                        -relative
                    } else {
                        relative
                    };
                    let shift = relative.to_scaled_axis();
                    let mut dofs = Vec::new();
                    let mut limits = Vec::new();
                    let mut axes = Vec::new();
                    for (dof, lo, hi) in anatomical {
                        let k = dof.axis_index();
                        let (lo, hi) = ((lo - shift[k]).min(0.0), (hi - shift[k]).max(0.0));
                        let v = frame.col(k);
                        let m = v.abs().max_position();
                        let (lo, hi) = if v[m] > 0.0 { (lo, hi) } else { (-hi, -lo) };
                        let world = [Dof::Rx, Dof::Ry, Dof::Rz][m];
                        dofs.push(world);
                        limits.push((world, lo, hi));
                        axes.push(AnatomicalAxis {
                            dof: world,
                            anatomical: dof,
                            sign: if v[m] > 0.0 { 1.0 } else { -1.0 },
                        });
                    }
                    (dofs, limits, axes)
                }
                None => {
                    notes.push(format!(
                        "{}: segment above far from any axis-aligned frame, 3 DOF with envelope ranges",
                        input.hanim
                    ));
                    let reach = anatomical
                        .iter()
                        .map(|&(_, lo, hi)| lo.abs().max(hi.abs()))
                        .fold(0.0, f64::max);
                    let dofs = vec![Dof::Rx, Dof::Ry, Dof::Rz];
                    let limits = dofs.iter().map(|&d| (d, -reach, reach)).collect();
                    (dofs, limits, Vec::new())
                }
            }
        };
        // Mass and centre of mass.
        let towards = |frac: f64| -> DVec3 {
            distal[i].map_or(DVec3::ZERO, |d| {
                (inputs[d].position - input.position) * frac
            })
        };
        let (m, com) = match input.class {
            JointClass::Pelvis => (fraction("lower trunk") * mass, DVec3::ZERO),
            JointClass::Spine => {
                let upper = fraction("upper trunk");
                let middle = fraction("middle trunk");
                let share = if input.hanim.starts_with("vl") {
                    if thoracic == 0 {
                        (upper + middle) / lumbar.max(1) as f64
                    } else {
                        middle / lumbar.max(1) as f64
                    }
                } else if lumbar == 0 {
                    (upper + middle) / thoracic.max(1) as f64
                } else {
                    upper / thoracic.max(1) as f64
                };
                (share * mass, towards(0.5))
            }
            JointClass::Neck if input.hanim == "skullbase" => (
                fraction("head") * mass,
                DVec3::new(0.0, 0.1 * scale, 0.02 * scale),
            ),
            JointClass::Ankle => {
                let seg = fraction("foot");
                let com = if distal[i].is_some() {
                    towards(0.5)
                } else {
                    DVec3::new(0.0, -0.03, 0.06) * scale
                };
                (seg * mass, com)
            }
            JointClass::Wrist => {
                let com = match distal[i] {
                    Some(_) => towards(0.77),
                    None => input.parent.map_or(DVec3::ZERO, |p| {
                        (input.position - inputs[p].position).normalize_or_zero() * 0.07 * scale
                    }),
                };
                (fraction("hand") * mass, com)
            }
            c => match anatomy::segment_of(c) {
                Some(seg) if c != JointClass::Neck => {
                    (seg.mass_fraction * mass, towards(seg.com_fraction))
                }
                _ => (0.0, DVec3::ZERO),
            },
        };
        let mut def = JointDef::new(input.hanim, parent_name, offset, &dofs).with_mass(m, com);
        def.limits = limits;
        let share = match input.class {
            JointClass::Spine => spine_share,
            JointClass::Neck => neck_share,
            _ => 1,
        };
        let stiffness = anatomy::stiffness(input.class, share);
        if stiffness > 0.0 && input.class != JointClass::Root {
            def.stiffness = dofs
                .iter()
                .filter(|d| d.is_rotation())
                .map(|&d| (d, stiffness))
                .collect();
        }
        defs.push(def);
        axes_by_joint.push(anatomical_axes);
    }
    let skeleton = Skeleton::new(defs)?;
    // Skeleton::new keeps the given parents-first order; map back by name to be safe.
    let joints = skeleton
        .joints()
        .iter()
        .map(|j| {
            let at = inputs.iter().position(|i| i.hanim == j.name);
            let input = at.map(|k| &inputs[k]);
            BuiltJoint {
                hanim: input.map_or("", |i| i.hanim),
                source: input.and_then(|i| i.source),
                has_dofs: !j.dofs.is_empty(),
                axes: at
                    .and_then(|k| axes_by_joint.get(k).cloned())
                    .unwrap_or_default(),
                rest_match: DQuat::IDENTITY,
                own_rest: at
                    .and_then(|k| inputs.get(k))
                    .map_or(DVec3::ZERO, |i| i.position),
            }
        })
        .collect();
    Ok(HumanoidSkeleton {
        skeleton,
        joints,
        loa: options.loa,
        notes,
    })
}

/// The signed permutation matrix (a rotation) nearest to the rotation `m`, when `m` is within
/// `max_degrees` of it.
pub(crate) fn snap_to_axes(m: DMat3, max_degrees: f64) -> Option<DMat3> {
    let mut cols = [DVec3::ZERO; 3];
    let mut used = [false; 3];
    for (k, col) in cols.iter_mut().enumerate() {
        let v = m.col(k);
        let a = v.abs().max_position();
        if used[a] {
            return None;
        }
        used[a] = true;
        let mut e = DVec3::ZERO;
        e[a] = v[a].signum();
        *col = e;
    }
    let p = DMat3::from_cols(cols[0], cols[1], cols[2]);
    if p.determinant() < 0.0 || m.determinant() < 0.0 {
        return None;
    }
    let angle = DQuat::from_mat3(&p).angle_between(DQuat::from_mat3(&m));
    (angle < max_degrees.to_radians()).then_some(p)
}

#[cfg(test)]
mod tests {
    #[cfg(target_arch = "wasm32")]
    use wasm_bindgen_test::wasm_bindgen_test as test;

    use super::*;
    use crate::mapping::SourceJoint;

    #[test]
    fn default_body_at_each_level() {
        for (loa, joints) in [
            (LevelOfArticulation::Loa1, 18),
            (LevelOfArticulation::Loa2, 71),
        ] {
            let body = default_skeleton(&SkeletonOptions {
                loa,
                ..Default::default()
            })
            .unwrap();
            assert_eq!(body.skeleton.joint_count(), joints);
            assert!(
                (body.skeleton.total_mass() - 70.0).abs() < 1.5,
                "{}",
                body.skeleton.total_mass()
            );
            let elbow = body.skeleton.joint_index("l_elbow").unwrap();
            assert_eq!(body.skeleton.joints()[elbow].dofs, vec![Dof::Rx, Dof::Ry]);
        }
    }

    /// A T-pose body is built in the standard pose: its arms hang along the default body's
    /// (the default joint centres), each segment keeps its T-pose length, the left shoulder's
    /// rest match is the quarter turn that lowers the arm, and the joints get the default
    /// body's DOF and ranges.
    #[test]
    fn a_t_pose_is_built_in_the_standard_pose() {
        let loa1 = humanoid_joints(LevelOfArticulation::Loa1);
        let mut joints = Vec::new();
        for j in &loa1 {
            let mut p = j.rest_centre;
            let name = j.definition.name;
            let sh = |s: &str| {
                loa1.iter()
                    .find(|x| x.definition.name == s)
                    .map(|x| x.rest_centre)
                    .unwrap()
            };
            for side in ["l_", "r_"] {
                let shoulder = sh(&format!("{side}shoulder"));
                if name == format!("{side}elbow") || name == format!("{side}radiocarpal") {
                    let d = (shoulder - p).length();
                    let sign = if side == "l_" { 1.0 } else { -1.0 };
                    p = shoulder + DVec3::new(sign * d, 0.0, 0.0);
                }
            }
            joints.push(SourceJoint {
                name: name.into(),
                parent: j.parent,
                position: p,
            });
        }
        let mapping = Mapping::auto(&joints, &[], false);
        let positions: Vec<DVec3> = joints.iter().map(|j| j.position).collect();
        let body = build_skeleton(
            &mapping,
            &positions,
            &SkeletonOptions {
                loa: LevelOfArticulation::Loa1,
                ..Default::default()
            },
        )
        .unwrap();
        let s = &body.skeleton;
        let rest = Frames::new(s, &Posture::rest(s)).joint_position;
        let default = default_skeleton(&SkeletonOptions {
            loa: LevelOfArticulation::Loa1,
            ..Default::default()
        })
        .unwrap();
        let at = |name: &str| s.joint_index(name).unwrap();
        let centre = |name: &str| {
            loa1.iter()
                .find(|x| x.definition.name == name)
                .unwrap()
                .rest_centre
        };
        for side in ["l_", "r_"] {
            let [shoulder, elbow, wrist] =
                ["shoulder", "elbow", "radiocarpal"].map(|j| format!("{side}{j}"));
            for (a, b) in [(&shoulder, &elbow), (&elbow, &wrist)] {
                let built = rest[at(b)] - rest[at(a)];
                let standard = centre(b) - centre(a);
                let t_pose = positions[joints.iter().position(|j| j.name == *b).unwrap()]
                    - positions[joints.iter().position(|j| j.name == *a).unwrap()];
                assert!(
                    built.angle_between(standard).to_degrees() < 0.01,
                    "{a} -> {b}: {built} against {standard}"
                );
                assert!((built.length() - t_pose.length()).abs() < 1e-9);
            }
        }
        // The left arm points along +x in the T-pose; its rest match lowers it.
        let lowered = body.joints[at("l_shoulder")].rest_match * DVec3::X;
        let down = (centre("l_elbow") - centre("l_shoulder")).normalize();
        assert!(lowered.angle_between(down).to_degrees() < 0.01, "{lowered}");
        for name in ["l_elbow", "r_elbow", "l_shoulder", "l_knee"] {
            let (k, d) = (at(name), default.skeleton.joint_index(name).unwrap());
            assert_eq!(
                s.joints()[k].dofs,
                default.skeleton.joints()[d].dofs,
                "{name}"
            );
            let (start, dstart) = (
                s.joints()[k].dof_start,
                default.skeleton.joints()[d].dof_start,
            );
            for i in 0..s.joints()[k].dofs.len() {
                assert!(
                    (s.upper_limits()[start + i] - default.skeleton.upper_limits()[dstart + i])
                        .abs()
                        < 0.05,
                    "{name}"
                );
            }
        }
    }

    #[test]
    fn non_humanoid_is_refused() {
        let joints = vec![SourceJoint {
            name: "Bone".into(),
            parent: None,
            position: DVec3::ZERO,
        }];
        let mapping = Mapping::auto(&joints, &[], false);
        let err =
            build_skeleton(&mapping, &[DVec3::ZERO], &SkeletonOptions::default()).unwrap_err();
        assert!(matches!(err, BuildError::NotHumanoid { .. }));
        assert!(err.to_string().contains("l_hip"));
    }
}
