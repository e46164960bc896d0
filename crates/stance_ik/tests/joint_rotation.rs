//! The rotation of a joint's DOF nearest to a wanted rotation (`nearest_rotation_vector`),
//! with and without limits: never farther than the old projection (the wanted rotation
//! vector with the missing components zeroed, clamped into the limits) nor than any point of
//! a dense sampling of the DOF box; exact when the wanted rotation is reachable.

// A test crate: on wasm32 `#[test]` becomes `wasm_bindgen_test`, which clippy does not treat
// as a test, and fixture helpers panic on broken fixtures on purpose.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

#[cfg(target_arch = "wasm32")]
use wasm_bindgen_test::wasm_bindgen_test as test;

use crate::common;

use std::f64::consts::PI;

use common::*;
use glam::{DQuat, DVec3};
use rand::RngExt;
use rand::rngs::StdRng;
use stance_ik::{UNLIMITED_RANGE, nearest_rotation_vector, rotation_angle};

/// Log map with the angle in [0, pi].
fn log(q: DQuat) -> DVec3 {
    let q = if q.w < 0.0 { -q } else { q };
    let v = DVec3::new(q.x, q.y, q.z);
    let s = v.length();
    if s < 1e-300 {
        DVec3::ZERO
    } else {
        v * (2.0 * s.atan2(q.w) / s)
    }
}

/// A rotation of random axis and angle in [0, pi].
fn random_rotation(rng: &mut StdRng) -> DQuat {
    let axis = vec3(rng, 1.0).normalize_or(DVec3::X);
    DQuat::from_axis_angle(axis, uniform(rng, 0.0, PI))
}

/// Random DOF axes (`count` of them) and limits: some unlimited, some narrow, some wide.
fn random_box(rng: &mut StdRng, count: usize) -> ([bool; 3], DVec3, DVec3) {
    let mut dofs = [false; 3];
    while dofs.iter().filter(|&&d| d).count() < count {
        dofs[rng.random_range(0..3)] = true;
    }
    let mut lo = DVec3::NEG_INFINITY;
    let mut hi = DVec3::INFINITY;
    for a in 0..3 {
        if dofs[a] && rng.random::<f64>() < 0.85 {
            lo[a] = uniform(rng, -2.5, 0.6);
            hi[a] = lo[a] + uniform(rng, 0.05, 2.5);
        }
    }
    (dofs, lo, hi)
}

/// The box actually searched: unlimited DOF within `UNLIMITED_RANGE`, no others.
fn search_box(dofs: [bool; 3], lo: DVec3, hi: DVec3) -> (DVec3, DVec3) {
    let mut l = DVec3::ZERO;
    let mut h = DVec3::ZERO;
    for a in 0..3 {
        if dofs[a] {
            l[a] = lo[a].max(-UNLIMITED_RANGE);
            h[a] = hi[a].min(UNLIMITED_RANGE);
        }
    }
    (l, h)
}

/// Smallest angle to `target` over a regular grid of `per_axis` points per DOF of the box.
fn sampled_minimum(target: DQuat, dofs: [bool; 3], lo: DVec3, hi: DVec3, per_axis: usize) -> f64 {
    let axes: Vec<usize> = (0..3).filter(|&a| dofs[a]).collect();
    let count = per_axis.pow(axes.len() as u32);
    let mut best = f64::INFINITY;
    for index in 0..count {
        let mut rest = index;
        let mut r = DVec3::ZERO;
        for &a in &axes {
            let i = rest % per_axis;
            rest /= per_axis;
            r[a] = lo[a] + (hi[a] - lo[a]) * i as f64 / (per_axis - 1) as f64;
        }
        best = best.min(rotation_angle(DQuat::from_scaled_axis(r), target));
    }
    best
}

#[test]
fn nearest_within_limits_beats_zeroing_and_dense_sampling() {
    let mut rng = rng(61);
    let mut better_than_zeroing = [0usize; 3];
    for trial in 0..300 {
        let count = trial % 3 + 1;
        let (dofs, lo, hi) = random_box(&mut rng, count);
        let (slo, shi) = search_box(dofs, lo, hi);
        let target = random_rotation(&mut rng);
        let r = nearest_rotation_vector(target, dofs, lo, hi);
        for a in 0..3 {
            if dofs[a] {
                assert!(
                    r[a] >= slo[a] && r[a] <= shi[a],
                    "trial {trial}: {r} outside [{lo}, {hi}]"
                );
            } else {
                assert_eq!(r[a], 0.0, "trial {trial}: {r} off the DOF");
            }
        }
        let angle = rotation_angle(DQuat::from_scaled_axis(r), target);
        // The old projection, clamped into the limits.
        let mut zeroed = log(target);
        for a in 0..3 {
            zeroed[a] = if dofs[a] {
                zeroed[a].clamp(slo[a], shi[a])
            } else {
                0.0
            };
        }
        let zeroing = rotation_angle(DQuat::from_scaled_axis(zeroed), target);
        assert!(
            angle <= zeroing + 1e-12,
            "trial {trial}: {angle} vs zeroing {zeroing}"
        );
        if angle < zeroing - 1e-3 {
            better_than_zeroing[count - 1] += 1;
        }
        let per_axis = [20001, 301, 41][count - 1];
        let sampled = sampled_minimum(target, dofs, slo, shi, per_axis);
        assert!(
            angle <= sampled + 1e-6,
            "trial {trial} ({count} DOF): {angle} vs sampled {sampled}, {r} in [{lo}, {hi}]"
        );

        // A reachable rotation is met exactly.
        let mut reachable = DVec3::ZERO;
        for a in 0..3 {
            if dofs[a] {
                let (l, h) = (slo[a].max(-PI), shi[a].min(PI));
                reachable[a] = uniform(&mut rng, l, h);
            }
        }
        let wanted = DQuat::from_scaled_axis(reachable);
        let got = nearest_rotation_vector(wanted, dofs, lo, hi);
        let miss = rotation_angle(DQuat::from_scaled_axis(got), wanted);
        assert!(
            miss < 1e-9,
            "trial {trial}: {reachable} gave {got} ({miss} rad off)"
        );
    }
    // Not vacuous: the zeroing projection is clearly worse in many cases of each DOF count.
    for (count, better) in better_than_zeroing.iter().enumerate() {
        assert!(*better >= 30, "{} DOF: {better}", count + 1);
    }
}

#[test]
fn without_limits_the_nearest_is_the_projected_quaternion() {
    let mut rng = rng(62);
    for trial in 0..400 {
        let count = trial % 3 + 1;
        let (dofs, _, _) = random_box(&mut rng, count);
        let target = random_rotation(&mut rng);
        let r = nearest_rotation_vector(target, dofs, DVec3::NEG_INFINITY, DVec3::INFINITY);
        assert!(r.length() <= PI + 1e-12, "trial {trial}: {r}");
        // The optimum over the whole DOF space: |p . q| of the projection is
        // sqrt(w^2 + |v on the DOF axes|^2), so the angle is 2 acos of that.
        let q = target;
        let mut kept = q.w * q.w;
        for a in 0..3 {
            if dofs[a] {
                kept += [q.x, q.y, q.z][a].powi(2);
            }
        }
        let optimum = 2.0 * kept.sqrt().min(1.0).acos();
        let angle = rotation_angle(DQuat::from_scaled_axis(r), target);
        assert!(
            (angle - optimum).abs() < 1e-7,
            "trial {trial}: {angle} vs {optimum}"
        );
        if count == 3 {
            assert!(angle < 1e-9);
        }
    }
}

#[test]
fn degenerate_inputs_give_defined_answers() {
    let half_turn_z = DQuat::from_rotation_z(PI);
    // Every rotation about x, y is a half turn from it: the one nearest zero in the limits.
    let r = nearest_rotation_vector(
        half_turn_z,
        [true, true, false],
        DVec3::new(0.2, -1.0, 0.0),
        DVec3::new(1.0, 1.0, 0.0),
    );
    assert_eq!(r, DVec3::new(0.2, 0.0, 0.0));
    for target in [
        DQuat::from_xyzw(f64::NAN, 0.0, 0.0, 1.0),
        DQuat::from_xyzw(0.0, 0.0, 0.0, 0.0),
    ] {
        let r = nearest_rotation_vector(
            target,
            [true, false, true],
            DVec3::NEG_INFINITY,
            DVec3::INFINITY,
        );
        assert_eq!(r, DVec3::ZERO);
    }
    // NaN and inverted limits: finite and within what is left of the box.
    let r = nearest_rotation_vector(
        DQuat::from_rotation_x(1.0),
        [true, true, true],
        DVec3::new(f64::NAN, 0.5, 0.0),
        DVec3::new(0.3, 0.1, f64::NAN),
    );
    assert!(r.is_finite());
    assert_eq!(r.y, 0.5);
    assert!(r.x <= 0.3 && r.z >= 0.0);
    // No DOF: zero.
    assert_eq!(
        nearest_rotation_vector(
            DQuat::from_rotation_y(0.4),
            [false; 3],
            DVec3::ZERO,
            DVec3::ZERO
        ),
        DVec3::ZERO
    );
}
