//! The collision task's unit tests.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use rand::rngs::StdRng;
use rand::{RngExt, SeedableRng};

use super::*;

/// The distance of two segments by another route: `f(s) = min_t |p(s) - q(t)|` is convex
/// in `s` (the distance of a point on a line to a convex set, along a line), its inner
/// minimum the clamped projection; a golden-section search over `s`.
fn searched(p0: DVec3, p1: DVec3, q0: DVec3, q1: DVec3) -> f64 {
    let v = q1 - q0;
    let inner = |s: f64| {
        let p = p0 + (p1 - p0) * s;
        let t = if v.length_squared() > 0.0 {
            ((p - q0).dot(v) / v.length_squared()).clamp(0.0, 1.0)
        } else {
            0.0
        };
        (p - (q0 + v * t)).length()
    };
    let (mut lo, mut hi) = (0.0f64, 1.0f64);
    let g = (5f64.sqrt() - 1.0) / 2.0;
    for _ in 0..200 {
        let (m1, m2) = (hi - g * (hi - lo), lo + g * (hi - lo));
        if inner(m1) <= inner(m2) {
            hi = m2;
        } else {
            lo = m1;
        }
    }
    inner((lo + hi) / 2.0).min(inner(0.0)).min(inner(1.0))
}

/// Catches a closest-point routine that clamps wrongly (end against end, a point against
/// a segment, parallel segments): on random segments, some degenerate, some parallel, the
/// distance equals the searched one and both points lie on their segments.
#[test]
fn closest_points_match_a_search_along_the_segments() {
    let mut r = StdRng::seed_from_u64(3);
    let point = |r: &mut StdRng| {
        DVec3::new(
            r.random_range(-1.0..1.0),
            r.random_range(-1.0..1.0),
            r.random_range(-1.0..1.0),
        )
    };
    for case in 0..2000 {
        let p0 = point(&mut r);
        let mut p1 = point(&mut r);
        let q0 = point(&mut r);
        let mut q1 = point(&mut r);
        match case % 5 {
            0 => p1 = p0,
            1 => q1 = q0,
            2 => q1 = q0 + (p1 - p0) * 0.7,
            _ => {}
        }
        let (pa, pb) = closest_points(p0, p1, q0, q1);
        let on = |x: DVec3, a: DVec3, b: DVec3| {
            let ab = b - a;
            let t = if ab.length_squared() > 0.0 {
                ((x - a).dot(ab) / ab.length_squared()).clamp(0.0, 1.0)
            } else {
                0.0
            };
            (a + ab * t - x).length() < 1e-9
        };
        assert!(on(pa, p0, p1) && on(pb, q0, q1), "case {case}");
        let expected = searched(p0, p1, q0, q1);
        let got = (pa - pb).length();
        assert!(
            (got - expected).abs() < 1e-9,
            "case {case}: {got} vs {expected}"
        );
    }
}

/// A body of six legs of three joints round a turning root, each leg's bones a capsule.
fn spider() -> (Skeleton, Collision) {
    use crate::{Dof, JointDef};
    let mut defs = vec![JointDef::new(
        "root",
        None,
        DVec3::new(0.0, 0.5, 0.0),
        &[Dof::Rx, Dof::Ry, Dof::Rz],
    )];
    for leg in 0..6 {
        let turn = leg as f64 * std::f64::consts::TAU / 6.0;
        let out = DVec3::new(turn.cos(), -0.3, turn.sin()) * 0.15;
        let mut parent = "root".to_owned();
        for k in 0..3 {
            let name = format!("leg{leg}_{k}");
            let offset = if k == 0 { out * 0.5 } else { out };
            let dofs = [Dof::Rx, Dof::Rz];
            defs.push(JointDef::new(&name, Some(&parent), offset, &dofs));
            parent = name;
        }
    }
    let skeleton = Skeleton::new(defs).unwrap();
    let capsules: Vec<Capsule> = skeleton
        .joints()
        .iter()
        .enumerate()
        .skip(1)
        .map(|(j, joint)| Capsule {
            joint: j,
            start: DVec3::ZERO,
            end: joint.offset.normalize() * 0.15,
            radius: 0.03,
        })
        .collect();
    let rest = Frames::new(&skeleton, &Posture::rest(&skeleton));
    let pairs = collision_pairs(&skeleton, &capsules, &rest, f64::NEG_INFINITY);
    let floor = floor_capsules(&capsules, &rest);
    let task = Collision::new(&skeleton, capsules, pairs, floor, 0.01, 16);
    (skeleton, task)
}

/// Catches a list of near pairs kept past its use (a pair left out that has come within
/// reach, a stop at a pair too early): the legs of a body wander, by small steps and
/// large, and at each posture the search by the list kept from the last finds the
/// constraints a search of every pair finds.
#[test]
fn a_kept_list_finds_what_a_full_search_finds() {
    let (skeleton, task) = spider();
    let mut r = StdRng::seed_from_u64(7);
    let mut posture = Posture::rest(&skeleton);
    let mut list = NearList::default();
    let reach = task.margin() + COLLISION_LOOKAHEAD;
    let (mut kept, mut made, mut found) = (0, 0, 0);
    for step in 0..600 {
        let size = [0.005, 0.02, 0.3][step % 3];
        for v in posture.values_mut().iter_mut() {
            *v = (*v + r.random_range(-size..size)).clamp(-1.2, 1.2);
        }
        let frames = Frames::new(&skeleton, &posture);
        let ends = list.ends.clone();
        let listed = task.constraints_listed(&frames, reach, &mut list);
        let all = task.constraints_within(&frames, reach);
        if list.ends == ends {
            kept += 1;
        } else {
            made += 1;
        }
        found += all.len();
        let key = |c: &Constraint| (c.distance, c.a.0, c.b.map(|b| b.0));
        let (listed, all): (Vec<_>, Vec<_>) = (
            listed.iter().map(key).collect(),
            all.iter().map(key).collect(),
        );
        assert_eq!(listed, all, "step {step}");
    }
    assert!(kept > 100 && made > 100, "kept {kept}, made {made}");
    assert!(found > 500, "{found} constraints in all");
}
