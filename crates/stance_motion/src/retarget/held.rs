//! Contacts found on a clip and held on a body: the leg length and pace that scale the
//! thresholds, the heel, ball and other parts' points on the clip and on the body, the goals
//! each contact holds, and the stride scale that keeps them within the body's reach.

use glam::DVec3;
use stance_hanim::HumanoidSkeleton;
use stance_ik::{Frames, Posture};

use super::{CONTACT_JOINTS, KNEES, Placement, WRISTS};
use crate::clip::Clip;
use crate::contacts::{
    ClipScale, Contact, ContactPart, ContactSettings, PointTrack, Thresholds, detect_contacts,
    quantile,
};

/// The contacts found on a clip and held on a body.
#[derive(Debug)]
pub(super) struct Found {
    pub(super) contacts: Vec<Contact>,
    pub(super) thresholds: Thresholds,
    pub(super) notes: Vec<String>,
}

/// Leg length (hip to knee to ankle, both sides' mean) from rest positions by H-Anim name.
pub(super) fn leg_length(at: impl Fn(&str) -> Option<DVec3>) -> Option<f64> {
    let legs: Vec<f64> = ["l", "r"]
        .iter()
        .filter_map(|s| {
            let (h, k, a) = (
                at(&format!("{s}_hip"))?,
                at(&format!("{s}_knee"))?,
                at(&format!("{s}_talocrural"))?,
            );
            Some((k - h).length() + (a - k).length())
        })
        .filter(|l| *l > 1e-3)
        .collect();
    (!legs.is_empty()).then(|| legs.iter().sum::<f64>() / legs.len() as f64)
}

/// The heel and ball of the foot whose ankle is `ankle` (offsets in its rest frame) from the
/// rest positions of a skeleton given as (name, parent, position) rows.
pub(super) fn foot_points(
    ankle: usize,
    parents: &[Option<usize>],
    rest: &[DVec3],
    toe: Option<usize>,
    leg: f64,
) -> [DVec3; 2] {
    let below = |j: usize| is_below(j, ankle, parents);
    let foot: Vec<DVec3> = (0..rest.len())
        .filter(|&j| below(j))
        .map(|j| rest[j] - rest[ankle])
        .collect();
    let toes: Vec<DVec3> = toe
        .filter(|&t| below(t))
        .map(|t| rest[t] - rest[ankle])
        .into_iter()
        .collect();
    stance_hanim::anatomy::heel_and_ball(&toes, &foot, leg)
}

/// The joint below `ankle` that reaches furthest forward at rest (the tip of the toes),
/// when it is at least 2 cm ahead of the ball (`ball`, in the ankle's rest frame).
fn toe_tip(ankle: usize, parents: &[Option<usize>], rest: &[DVec3], ball: DVec3) -> Option<usize> {
    let below = |j: usize| is_below(j, ankle, parents);
    (0..rest.len())
        .filter(|&j| below(j))
        .map(|j| (j, rest[j].z - rest[ankle].z))
        .filter(|&(_, z)| z > ball.z + 0.02)
        .max_by(|a, b| a.1.total_cmp(&b.1))
        .map(|(j, _)| j)
}

/// Where a part's point is on each skeleton: the joint carrying it on the target with the
/// point's offset there, and how to find it on the clip (a clip joint and offset in its
/// frame, or the midpoint of the hips for the pelvis).
pub(super) struct PartPoint {
    pub(super) part: ContactPart,
    pub(super) target_joint: usize,
    pub(super) target_point: DVec3,
    pub(super) clip: ClipPoint,
    /// For the ball: the clip's joint at the tip of the toes (the one below the ankle that
    /// reaches furthest forward at rest, an End Site where the file has one), when it is
    /// ahead of the ball.
    pub(super) tip: Option<usize>,
}

pub(super) enum ClipPoint {
    Joint(usize, DVec3),
    Between(usize, usize),
}

/// The points that can rest on the ground, on both skeletons (parts the clip or the target
/// lacks are left out).
pub(super) fn part_points(
    clip: &Clip,
    target: &HumanoidSkeleton,
    settings: &ContactSettings,
) -> Vec<PartPoint> {
    let skeleton = &target.skeleton;
    let target_rest = Frames::new(skeleton, &Posture::rest(skeleton)).joint_position;
    let target_parents: Vec<Option<usize>> = skeleton.joints().iter().map(|j| j.parent).collect();
    let clip_rest = clip.rest_positions();
    let clip_parents: Vec<Option<usize>> = clip.joints.iter().map(|j| j.parent).collect();
    let target_at = |n: &str| skeleton.joint_index(n).map(|j| target_rest[j]);
    let clip_at = |n: &str| clip.joint_of(n).and_then(|j| clip_rest.get(j).copied());
    let target_leg = leg_length(target_at).unwrap_or(0.9);
    let clip_leg = leg_length(clip_at).unwrap_or(0.9);
    let mut points = Vec::new();
    for (side, ankle) in ["l", "r"].iter().zip(CONTACT_JOINTS) {
        let (Some(t), Some(c)) = (skeleton.joint_index(ankle), clip.joint_of(ankle)) else {
            continue;
        };
        let toe = format!("{side}_metatarsophalangeal_2");
        let on_target = foot_points(
            t,
            &target_parents,
            &target_rest,
            skeleton.joint_index(&toe),
            target_leg,
        );
        let on_clip = foot_points(c, &clip_parents, &clip_rest, clip.joint_of(&toe), clip_leg);
        let tip = toe_tip(c, &clip_parents, &clip_rest, on_clip[1]);
        for (k, part) in [ContactPart::Heel, ContactPart::Ball]
            .into_iter()
            .enumerate()
        {
            points.push(PartPoint {
                part,
                target_joint: t,
                target_point: on_target[k],
                clip: ClipPoint::Joint(c, on_clip[k]),
                tip: tip.filter(|_| part == ContactPart::Ball),
            });
        }
    }
    if !settings.body_parts {
        return points;
    }
    for (part, names) in [(ContactPart::Hand, WRISTS), (ContactPart::Knee, KNEES)] {
        for name in names {
            if let (Some(t), Some(c)) = (skeleton.joint_index(name), clip.joint_of(name)) {
                points.push(PartPoint {
                    part,
                    target_joint: t,
                    target_point: DVec3::ZERO,
                    clip: ClipPoint::Joint(c, DVec3::ZERO),
                    tip: None,
                });
            }
        }
    }
    let hips = |idx: &dyn Fn(&str) -> Option<usize>| Some((idx("l_hip")?, idx("r_hip")?));
    if let (Some((tl, tr)), Some((cl, cr))) = (
        hips(&|n| skeleton.joint_index(n)),
        hips(&|n| clip.joint_of(n)),
    ) && let Some(pelvis) = target_parents[tl]
    {
        points.push(PartPoint {
            part: ContactPart::Pelvis,
            target_joint: pelvis,
            target_point: (target_rest[tl] + target_rest[tr]) * 0.5 - target_rest[pelvis],
            clip: ClipPoint::Between(cl, cr),
            tip: None,
        });
    }
    points
}

/// The contacts of the clip (detected on the clip, so that every target gets the same ones),
/// each held on the target where the copy puts its point (its mean over the contact, or, for
/// a heel or ball that lands while the other point of that foot is held, at the copy's
/// distance from it), at the target's own standing height for that point over the contact's
/// floor.
pub(super) fn held_contacts(
    clip: &Clip,
    target: &HumanoidSkeleton,
    copy: &[Posture],
    placement: &Placement,
    reference: usize,
    settings: &ContactSettings,
) -> Found {
    let skeleton = &target.skeleton;
    let points = part_points(clip, target, settings);
    // Every point's track on the clip, and the root's (hips' midpoint) for the pace.
    let worlds: Vec<Vec<(glam::DQuat, DVec3)>> =
        clip.frames.iter().map(|f| clip.world(f)).collect();
    let clip_point = |w: &[(glam::DQuat, DVec3)], p: &ClipPoint| match *p {
        ClipPoint::Joint(j, offset) => w.get(j).map_or(DVec3::ZERO, |x| x.1 + x.0 * offset),
        ClipPoint::Between(a, b) => match (w.get(a), w.get(b)) {
            (Some(a), Some(b)) => (a.1 + b.1) * 0.5,
            _ => DVec3::ZERO,
        },
    };
    let tracks: Vec<PointTrack> = points
        .iter()
        .map(|p| PointTrack {
            joint: skeleton.joints()[p.target_joint].name.clone(),
            part: p.part,
            point: p.target_point,
            positions: worlds.iter().map(|w| clip_point(w, &p.clip)).collect(),
            tip: p.tip.map(|t| {
                worlds
                    .iter()
                    .map(|w| clip_point(w, &ClipPoint::Joint(t, DVec3::ZERO)))
                    .collect()
            }),
        })
        .collect();
    let clip_rest = clip.rest_positions();
    let clip_leg =
        leg_length(|n| clip.joint_of(n).and_then(|j| clip_rest.get(j).copied())).unwrap_or(0.9);
    let root: Vec<DVec3> = match (clip.joint_of("l_hip"), clip.joint_of("r_hip")) {
        (Some(a), Some(b)) => worlds
            .iter()
            .map(|w| clip_point(w, &ClipPoint::Between(a, b)))
            .collect(),
        _ => worlds
            .iter()
            .map(|w| w.first().map_or(DVec3::ZERO, |x| x.1))
            .collect(),
    };
    let pace = pace(&root, reference, clip.frame_time);
    let scale = ClipScale {
        leg: clip_leg,
        pace,
        start: reference,
    };
    let thresholds = settings.thresholds(&scale);
    let mut contacts = detect_contacts(&tracks, clip.frame_time, &scale, settings);
    contacts.sort_by_key(|c| c.start);
    // Each point's own floor over the clip (the 10th percentile of its height less its
    // clearance, the reference frames left out), against which a contact's floor is
    // measured: the height of the step it stands on.
    let own_floor = |c: &Contact| -> f64 {
        let Some(track) = tracks
            .iter()
            .find(|t| t.joint == c.joint && t.part == c.part)
        else {
            return c.floor;
        };
        let mut heights: Vec<f64> = track
            .positions
            .iter()
            .skip(reference)
            .map(|p| p.y - c.clearance)
            .collect();
        quantile(&mut heights, 0.1).unwrap_or(c.floor)
    };
    // On the target: the copy's points over each contact, the standing height of each point.
    let target_rest = Frames::new(skeleton, &Posture::rest(skeleton));
    let target_leg = leg_length(|n| {
        skeleton
            .joint_index(n)
            .map(|j| target_rest.joint_position[j])
    })
    .unwrap_or(0.9);
    let target_floor = {
        let soles: Vec<f64> = points
            .iter()
            .filter(|p| p.part.is_foot())
            .map(|p| target_rest.point(p.target_joint, p.target_point).y)
            .collect();
        if soles.is_empty() {
            placement.ankle_height
        } else {
            soles.iter().sum::<f64>() / soles.len() as f64
        }
    };
    let copy_frames: Vec<Frames> = copy.iter().map(|p| Frames::new(skeleton, p)).collect();
    let on_copy = |c: &Contact, f: usize| {
        let j = skeleton.joint_index(&c.joint).unwrap_or(0);
        copy_frames
            .get(f)
            .map_or(DVec3::ZERO, |fr| fr.point(j, c.point))
    };
    let all = contacts.clone();
    // The copy puts the clip's ankle floor (its lower ankle's) at the target's mean ankle
    // height: its ground is that much above the target's rest ground.
    let lift = CONTACT_JOINTS
        .iter()
        .filter_map(|n| skeleton.joint_index(n))
        .map(|j| target_rest.joint_position[j].y)
        .reduce(f64::min)
        .map_or(0.0, |low| placement.ankle_height - low);
    let mut held: Vec<Contact> = Vec::with_capacity(contacts.len());
    for mut c in contacts {
        let standing = lift
            + if c.part.is_foot() {
                let j = skeleton.joint_index(&c.joint).unwrap_or(0);
                target_rest.point(j, c.point).y
            } else {
                // The clip's clearance as a share of its leg, on the target's leg.
                target_floor + c.clearance / clip_leg * target_leg
            };
        // The other point of the same foot, held when this one lands: this one is held where
        // the copy's foot puts it from there, so that the two goals fit the foot.
        let partner = held.iter().rev().find(|h| {
            h.joint == c.joint
                && h.part != c.part
                && h.part.is_foot()
                && c.part.is_foot()
                && !h.slides
                && !c.slides
                && h.start <= c.start
                && h.end >= c.start
        });
        // The floor under the contact on the target: the point's standing height, raised by
        // the step it stands on (the floor under the contact over the point's own lowest).
        let step = c.floor - own_floor(&c);
        let floor = standing + placement.root_scale * step.max(0.0);
        c.position = match partner {
            // A sliding point: kept at that height where the copy takes it.
            None if c.slides => {
                let at = on_copy(&c, c.start);
                DVec3::new(at.x, floor, at.z)
            }
            Some(h) => h.position + (on_copy(&c, c.start) - on_copy(h, c.start)),
            None => {
                // The first point of a stance: where the copy lands it, moved by the copy's
                // mean slide over the whole stance (this contact and those of the foot's
                // other point that follow on from it), so that the held foot is as far from
                // the copy's at its landing as at its lift-off.
                let mut end = c.end;
                for o in contacts_after(&all, &c) {
                    end = end.max(o.end);
                }
                let end = end.min(copy.len().saturating_sub(1)).max(c.start);
                let j = skeleton.joint_index(&c.joint).unwrap_or(0);
                let origin = |f: usize| {
                    copy_frames
                        .get(f)
                        .map_or(DVec3::ZERO, |fr| fr.joint_position[j])
                };
                let slide = (c.start..=end)
                    .map(|f| origin(f) - origin(c.start))
                    .sum::<DVec3>()
                    / (end + 1 - c.start) as f64;
                let at = on_copy(&c, c.start) + slide;
                DVec3::new(at.x, floor, at.z)
            }
        };
        held.push(c);
    }
    // A sliding point next to a hold of its own (easing out of it or into it) is kept from
    // sinking under where that hold puts it, when lower (the foot's roll can hold a ball
    // under its standing height): the two never pull against each other.
    let ease = settings.ease_frames(clip.frame_time);
    for k in 0..held.len() {
        if !held[k].slides {
            continue;
        }
        let c = &held[k];
        let next_to = held
            .iter()
            .filter(|h| {
                !h.slides
                    && h.joint == c.joint
                    && h.part == c.part
                    && h.start <= c.end + ease
                    && h.end + ease >= c.start
            })
            .map(|h| h.position.y)
            .fold(c.position.y, f64::min);
        held[k].position.y = next_to;
    }
    let mut notes = Vec::new();
    let travel = root
        .iter()
        .skip(reference)
        .zip(root.iter().skip(reference + 1))
        .map(|(a, b)| DVec3::new(b.x - a.x, 0.0, b.z - a.z).length())
        .sum::<f64>();
    if travel > clip_leg {
        for (side, ankle) in ["left", "right"].iter().zip(CONTACT_JOINTS) {
            if clip.joint_of(ankle).is_some() && !held.iter().any(|c| c.joint == ankle && !c.slides)
            {
                let sliding = held.iter().filter(|c| c.joint == ankle).count();
                let how = if sliding > 0 {
                    format!(
                        "no contact that holds it still ({sliding} sliding, kept on the floor \
                         only)"
                    )
                } else {
                    "no contact".to_owned()
                };
                notes.push(format!(
                    "the clip moves ({travel:.1} m) but the {side} foot got {how}: raise the \
                     contact height ({:.3} m, {:.3} m on this clip's legs) or speed ({:.2} m/s, \
                     {:.2} m/s on this clip's legs and pace)",
                    settings.height, thresholds.height, settings.speed, thresholds.speed
                ));
            }
        }
    }
    Found {
        contacts: held,
        thresholds,
        notes,
    }
}

/// The horizontal root scale under which the copy's points in contact slide least: the
/// copy moves a point over a contact by the root's displacement `R` (the clip's, times the
/// scale) plus what the legs' rotations do `L` (the same under any scale), so the least
/// squares scale is `-Σ L·R / Σ R·R`. `None` when the contacts hardly move the root (under a
/// leg's length over all of them) or the fit is over half again or under half the root
/// scale.
pub(super) fn stride_scale(
    clip: &Clip,
    target: &HumanoidSkeleton,
    copy: &[Posture],
    placement: &Placement,
    contacts: &[Contact],
) -> Option<f64> {
    let skeleton = &target.skeleton;
    let hips = (clip.joint_of("l_hip")?, clip.joint_of("r_hip")?);
    let root = |f: usize| {
        let w = clip.world(clip.frames.get(f)?);
        let p = (w.get(hips.0)?.1 + w.get(hips.1)?.1) * 0.5;
        Some(DVec3::new(p.x, 0.0, p.z))
    };
    let point = |c: &Contact, f: usize| {
        let j = skeleton.joint_index(&c.joint)?;
        let p = Frames::new(skeleton, copy.get(f)?).point(j, c.point);
        Some(DVec3::new(p.x, 0.0, p.z))
    };
    let s0 = placement.stride_scale;
    let (mut lr, mut rr) = (0.0, 0.0);
    for c in contacts.iter().filter(|c| c.part.is_foot() && !c.slides) {
        let r = root(c.end)? - root(c.start)?;
        let d = point(c, c.end)? - point(c, c.start)?;
        let l = d - r * s0;
        lr += l.dot(r);
        rr += r.dot(r);
    }
    let leg = leg_length(|n| {
        let rest = clip.rest_positions();
        clip.joint_of(n).and_then(|j| rest.get(j).copied())
    })?;
    if rr < leg * leg {
        return None;
    }
    let s = -lr / rr;
    (s.is_finite() && s > 0.5 * s0 && s < 1.5 * s0).then_some(s)
}

/// The contacts of the other point of `c`'s foot that follow on from it: each starts within
/// the previous one (a ball contact starting within the heel's, a heel contact within that
/// ball's...), in start order.
pub(super) fn contacts_after<'a>(all: &'a [Contact], c: &Contact) -> Vec<&'a Contact> {
    let mut chain: Vec<&Contact> = Vec::new();
    let mut end = c.end;
    let mut from = c.start;
    for o in all {
        if o.joint == c.joint
            && o.part.is_foot()
            && c.part.is_foot()
            && !o.slides
            && !c.slides
            && o.start > from
            && o.start <= end
        {
            chain.push(o);
            end = end.max(o.end);
            from = o.start;
        }
    }
    chain
}

/// Median horizontal speed of the root over the motion (from `start`), measured over a
/// quarter of a second (m/s).
pub(super) fn pace(root: &[DVec3], start: usize, frame_time: f64) -> f64 {
    let span = ((0.25 / frame_time).round() as usize).max(1);
    let mut speeds: Vec<f64> = (start..root.len().saturating_sub(span))
        .map(|f| {
            let d = root[f + span] - root[f];
            DVec3::new(d.x, 0.0, d.z).length() / (span as f64 * frame_time)
        })
        .collect();
    if speeds.is_empty() {
        return 0.0;
    }
    let k = speeds.len() / 2;
    *speeds.select_nth_unstable_by(k, f64::total_cmp).1
}

/// Whether joint `j` hangs below `ankle` (a descendant of it) in the tree of `parents`.
fn is_below(mut j: usize, ankle: usize, parents: &[Option<usize>]) -> bool {
    while let Some(p) = parents[j] {
        if p == ankle {
            return true;
        }
        j = p;
    }
    false
}
