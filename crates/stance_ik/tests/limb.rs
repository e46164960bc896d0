//! The closed-form limb (shoulder-elbow-wrist, hip-knee-ankle) with the swivel angle: goals
//! and swivel reproduced, round trips, joint-limit intervals against dense sampling,
//! continuity through straight configurations, and the hybrid restart of a stalled solve.

// A test crate: on wasm32 `#[test]` becomes `wasm_bindgen_test`, which clippy does not treat
// as a test, and fixture helpers panic on broken fixtures on purpose.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

#[cfg(target_arch = "wasm32")]
use wasm_bindgen_test::wasm_bindgen_test as test;

use crate::common;

use std::f64::consts::{PI, TAU};

use common::*;
use glam::{DQuat, DVec3};
use rand::RngExt;
use rand::rngs::StdRng;
use stance_hanim::scenarios;
use stance_ik::{
    Dof, Frames, IkError, JointDef, Limb, LimbBase, LimbGoal, Posture, Skeleton, SolveStatus,
    Solver, Task, rotation_angle,
};

fn angle_diff(a: f64, b: f64) -> f64 {
    ((a - b + PI).rem_euclid(TAU) - PI).abs()
}

/// The H-Anim limbs of the 50-DOF humanoid (with their anatomical limits).
fn hanim_limbs(skeleton: &Skeleton) -> Vec<Limb> {
    [
        ["l_shoulder", "l_elbow", "l_radiocarpal"],
        ["r_shoulder", "r_elbow", "r_radiocarpal"],
        ["l_hip", "l_knee", "l_talocrural"],
        ["r_hip", "r_knee", "r_talocrural"],
    ]
    .into_iter()
    .map(|names| Limb::from_names(skeleton, names).expect("H-Anim limb"))
    .collect()
}

/// A random limb: base joint with a random offset and 3 DOF, middle with a random hinge axis
/// (sometimes with a second rotational DOF), end with 1..3 DOF; segments neither straight nor
/// perpendicular to the hinge. No limits.
fn random_limb_skeleton(rng: &mut StdRng) -> Skeleton {
    let axes = [Dof::Rx, Dof::Ry, Dof::Rz];
    let hinge = rng.random_range(0..3);
    let mut middle = vec![axes[hinge]];
    if rng.random::<f64>() < 0.3 {
        middle.push(axes[(hinge + 1 + rng.random_range(0..2)) % 3]);
    }
    let end: Vec<Dof> = axes
        .iter()
        .copied()
        .filter(|_| rng.random::<f64>() < 0.7)
        .collect();
    let seg = |rng: &mut StdRng| {
        let d = vec3(rng, 1.0).normalize_or(DVec3::Y);
        d * uniform(rng, 0.15, 0.5)
    };
    Skeleton::new(vec![
        JointDef::new("torso", None, vec3(rng, 1.0), &[Dof::Rx, Dof::Ry, Dof::Rz]),
        JointDef::new("upper", Some("torso"), vec3(rng, 0.3), &axes),
        JointDef::new("middle", Some("upper"), seg(rng), &middle),
        JointDef::new("end", Some("middle"), seg(rng), &end),
    ])
    .expect("valid")
}

/// A goal reachable by the hinge: random direction, random distance inside the reach.
fn reachable_goal(rng: &mut StdRng, limb: &Limb, base: LimbBase) -> DVec3 {
    let (lo, hi) = limb.reach();
    let d = lo + (hi - lo) * uniform(rng, 0.02, 0.98);
    let dir = vec3(rng, 1.0).normalize_or(DVec3::X);
    base.upper_position + dir * d
}

/// A random posture strictly inside the limits (clamping would put many DOF exactly on a
/// limit, where the feasible swivel set may be a single point).
fn interior_posture(rng: &mut StdRng, skeleton: &Skeleton, amplitude: f64) -> Posture {
    let (lo, hi) = (skeleton.lower_limits(), skeleton.upper_limits());
    let values = (0..skeleton.dof_count())
        .map(|i| {
            let (l, h) = (lo[i].max(-amplitude), hi[i].min(amplitude));
            l + (h - l) * uniform(rng, 0.02, 0.98)
        })
        .collect();
    Posture::from_values(skeleton, values).unwrap()
}

fn end_position(skeleton: &Skeleton, posture: &Posture, limb: &Limb) -> DVec3 {
    Frames::new(skeleton, posture).joint_position[limb.joints()[2]]
}

/// Every DOF of the limb within its limits (up to `slack`).
fn limb_within_limits(skeleton: &Skeleton, posture: &Posture, limb: &Limb, slack: f64) -> bool {
    let (lo, hi) = (skeleton.lower_limits(), skeleton.upper_limits());
    limb.joints().iter().all(|&j| {
        skeleton.joints()[j]
            .dof_range()
            .all(|d| posture.values()[d] >= lo[d] - slack && posture.values()[d] <= hi[d] + slack)
    })
}

#[test]
fn closed_form_meets_the_goal_and_the_swivel() {
    let mut rng = rng(41);
    let mut cases = 0;
    // The H-Anim limbs in random body postures (so the base is rotated), and random limbs.
    let body = scenarios::humanoid50().unwrap();
    for trial in 0..120 {
        let (skeleton, limb, start) = if trial % 2 == 0 {
            let limbs = hanim_limbs(&body);
            let limb = limbs[trial / 2 % 4].clone();
            let start = random_posture(&mut rng, &body, 0.6);
            (body.clone(), limb, start)
        } else {
            let s = random_limb_skeleton(&mut rng);
            let limb = Limb::from_names(&s, ["upper", "middle", "end"]).unwrap();
            let start = random_posture(&mut rng, &s, 1.0);
            (s, limb, start)
        };
        let frames = Frames::new(&skeleton, &start);
        let base = limb.base(&skeleton, &frames);
        for _ in 0..10 {
            let goal = reachable_goal(&mut rng, &limb, base);
            let swivel = uniform(&mut rng, -PI, PI);
            let sol = limb.solve(base, &LimbGoal::position(goal), swivel);
            assert!(sol.reached);
            let mut p = start.clone();
            limb.apply(&sol, &mut p);
            let reached = end_position(&skeleton, &p, &limb);
            assert!(
                (reached - goal).length() < 1e-9,
                "trial {trial}: {reached} vs {goal}"
            );
            assert!((sol.end_position - goal).length() < 1e-9);
            let back = limb.swivel_angle(&skeleton, &p);
            assert!(
                angle_diff(back, swivel) < 1e-9,
                "trial {trial}: swivel {swivel} read back as {back}"
            );
            cases += 1;
        }
    }
    assert_eq!(cases, 1200);
}

#[test]
fn goal_orientation_sets_the_end_joint() {
    let mut rng = rng(42);
    for _ in 0..200 {
        let s = random_limb_skeleton(&mut rng);
        let limb = Limb::from_names(&s, ["upper", "middle", "end"]).unwrap();
        let end = limb.joints()[2];
        let full = s.joints()[end].rotation_dof.iter().all(Option::is_some);
        let start = random_posture(&mut rng, &s, 1.0);
        let base = limb.base(&s, &Frames::new(&s, &start));
        let goal = reachable_goal(&mut rng, &limb, base);
        let orientation = DQuat::from_scaled_axis(vec3(&mut rng, 1.5));
        let sol = limb.solve(
            base,
            &LimbGoal {
                position: goal,
                orientation: Some(orientation),
            },
            uniform(&mut rng, -PI, PI),
        );
        let mut p = start.clone();
        limb.apply(&sol, &mut p);
        let frames = Frames::new(&s, &p);
        assert!((frames.joint_position[end] - goal).length() < 1e-9);
        if full {
            let got = frames.rotation(end);
            let diff = got.inverse() * orientation;
            let angle = 2.0 * diff.xyz().length().atan2(diff.w.abs());
            assert!(angle < 1e-9, "{got} vs {orientation}");
        }
    }
}

/// A 3-4-5 arm for hand computations: a torso at the origin turning about y only, the
/// shoulder at its centre, upper arm 0.3 m and forearm 0.4 m hanging along -y, the elbow
/// flexing about x toward -rx (the forearm swings forward to +z, as on the H-Anim body).
fn right_angle_arm() -> Skeleton {
    Skeleton::new(vec![
        JointDef::new("torso", None, DVec3::ZERO, &[Dof::Ry]),
        JointDef::new(
            "shoulder",
            Some("torso"),
            DVec3::ZERO,
            &[Dof::Rx, Dof::Ry, Dof::Rz],
        ),
        JointDef::new(
            "elbow",
            Some("shoulder"),
            DVec3::new(0.0, -0.3, 0.0),
            &[Dof::Rx],
        )
        .with_limit(Dof::Rx, -2.5, 0.0),
        JointDef::new(
            "wrist",
            Some("elbow"),
            DVec3::new(0.0, -0.4, 0.0),
            &[Dof::Rx, Dof::Rz],
        ),
    ])
    .unwrap()
}

#[test]
fn the_swivel_zero_and_sign_match_a_hand_computed_arm() {
    // Catches a swivel convention that is consistent with itself but not the documented one
    // (limb.rs, problem-format.md): a flipped sign or a moved zero in both `solve` and
    // `swivel_angle` passes the round trips above, not this.
    //
    // Hand computation. The wrist goal is 0.5 m from the shoulder: 0.5^2 = 0.3^2 + 0.4^2,
    // so the elbow is a right angle (hinge -pi/2: flexion is -rx). The elbow lies
    // 0.3^2 / 0.5 = 0.18 m along the shoulder-wrist axis n and 0.3 * 0.4 / 0.5 = 0.24 m off
    // it, in the direction r cos(s) + (n x r) sin(s) for swivel s (right-handed about n).
    // The reference r: the pole is the rest direction -y; the elbow flexes (-rx) by swinging
    // the forearm to +z, so the elbow sits behind the shoulder-wrist line: r0 = -z ("elbow
    // behind the arm"). For n other than the pole, r0 is carried by the shortest rotation
    // from -y to n.
    // - Goal (0, -0.5, 0): n = -y = the pole, r = -z, n x r = (-y) x (-z) = +x.
    //   s = 0: 0.18 n + 0.24 r = (0, -0.18, -0.24); s = pi/2: (0.24, -0.18, 0);
    //   s = -pi/2: (-0.24, -0.18, 0); s = pi: (0, -0.18, 0.24).
    // - Goal (0, 0, 0.5), the arm raised forward: n = +z; the shortest rotation from -y to
    //   +z is 90 deg about (-y) x z = -x, which takes -z to -y: r = -y (elbow down),
    //   n x r = z x (-y) = +x. s = 0: (0, -0.24, 0.18); s = pi/2: (0.24, 0, 0.18);
    //   s = -pi/2: (-0.24, 0, 0.18).
    // - The torso turned +90 deg about y (x -> -z, z -> x), goal (0, -0.5, 0): the swivel is
    //   measured in the torso's frame, so s = pi/2 puts the elbow at the torso's +x, in the
    //   world (0, -0.18, -0.24) (not (0.24, -0.18, 0), which a world-frame swivel would give).
    let s = right_angle_arm();
    let limb = Limb::from_names(&s, ["shoulder", "elbow", "wrist"]).unwrap();
    let [_, elbow, wrist] = limb.joints();
    let h = std::f64::consts::FRAC_PI_2;
    let cases: [(f64, DVec3, f64, DVec3); 8] = [
        (
            0.0,
            DVec3::new(0.0, -0.5, 0.0),
            0.0,
            DVec3::new(0.0, -0.18, -0.24),
        ),
        (
            0.0,
            DVec3::new(0.0, -0.5, 0.0),
            h,
            DVec3::new(0.24, -0.18, 0.0),
        ),
        (
            0.0,
            DVec3::new(0.0, -0.5, 0.0),
            -h,
            DVec3::new(-0.24, -0.18, 0.0),
        ),
        (
            0.0,
            DVec3::new(0.0, -0.5, 0.0),
            PI,
            DVec3::new(0.0, -0.18, 0.24),
        ),
        (
            0.0,
            DVec3::new(0.0, 0.0, 0.5),
            0.0,
            DVec3::new(0.0, -0.24, 0.18),
        ),
        (
            0.0,
            DVec3::new(0.0, 0.0, 0.5),
            h,
            DVec3::new(0.24, 0.0, 0.18),
        ),
        (
            0.0,
            DVec3::new(0.0, 0.0, 0.5),
            -h,
            DVec3::new(-0.24, 0.0, 0.18),
        ),
        (
            h,
            DVec3::new(0.0, -0.5, 0.0),
            h,
            DVec3::new(0.0, -0.18, -0.24),
        ),
    ];
    for (torso, goal, swivel, expected) in cases {
        let mut p = Posture::rest(&s);
        p.values_mut()[0] = torso;
        let base = limb.base(&s, &Frames::new(&s, &p));
        let sol = limb.solve(base, &LimbGoal::position(goal), swivel);
        assert!(sol.reached);
        assert!((sol.hinge_angle + h).abs() < 1e-12, "{}", sol.hinge_angle);
        limb.apply(&sol, &mut p);
        let frames = Frames::new(&s, &p);
        let what = format!("torso {torso}, goal {goal}, swivel {swivel}");
        assert!(
            (frames.joint_position[wrist] - goal).length() < 1e-12,
            "{what}"
        );
        let got = frames.joint_position[elbow];
        assert!(
            (got - expected).length() < 1e-12,
            "{what}: elbow at {got}, by hand {expected}"
        );
        assert!(
            angle_diff(limb.swivel_angle(&s, &p), swivel) < 1e-12,
            "{what}"
        );
    }
}

#[test]
fn swivel_zero_bends_the_hanim_elbow_back_and_the_knee_forward() {
    // Catches a swivel zero on the wrong side for the H-Anim limbs (the documented natural
    // bend: "elbow behind the arm, knee in front of the leg"; H-Anim's +z is the front).
    // Goals straight below the upper joint at 90 % of the reach; the middle joint's offset
    // from the upper-end line, seen along z, must point back (elbows) or forward (knees) and
    // barely sideways.
    let body = scenarios::humanoid50().unwrap();
    let rest = Posture::rest(&body);
    let frames = Frames::new(&body, &rest);
    for (limb, forward) in hanim_limbs(&body).into_iter().zip([-1.0, -1.0, 1.0, 1.0]) {
        let base = limb.base(&body, &frames);
        let (_, reach_max) = limb.reach();
        let goal = base.upper_position + DVec3::new(0.0, -0.9 * reach_max, 0.0);
        let sol = limb.solve(base, &LimbGoal::position(goal), 0.0);
        let mut p = rest.clone();
        limb.apply(&sol, &mut p);
        let f = Frames::new(&body, &p);
        let [upper, middle, _] = limb.joints();
        let off = f.joint_position[middle] - f.joint_position[upper];
        // The line is vertical here: the offset from it is the horizontal part.
        let side = DVec3::new(off.x, 0.0, off.z);
        assert!(
            forward * side.z > 0.9 * side.length() && side.length() > 0.02,
            "{:?}: middle joint offset {side} from the line",
            limb.joints()
        );
    }
}

/// The goal's rotation vector with the components off the DOF zeroed (the old projection).
fn zeroed_rotation_vector(q: DQuat, dofs: [bool; 3]) -> DVec3 {
    let q = if q.w < 0.0 { -q } else { q };
    let v = DVec3::new(q.x, q.y, q.z);
    let s = v.length();
    let mut r = if s < 1e-300 {
        DVec3::ZERO
    } else {
        v * (2.0 * s.atan2(q.w) / s)
    };
    for a in 0..3 {
        if !dofs[a] {
            r[a] = 0.0;
        }
    }
    r
}

#[test]
fn goal_orientation_gives_the_nearest_end_rotation() {
    // 1- and 2-DOF end joints (a hinge, a 2-DOF wrist or ankle) cannot take every
    // orientation: the end rotation is the one of their DOF nearest to the goal.
    let mut rng = rng(46);
    let mut cases = [0usize; 2];
    let mut clearly_better = [0usize; 2];
    while cases.iter().any(|&c| c < 40) {
        let s = random_limb_skeleton(&mut rng);
        let limb = Limb::from_names(&s, ["upper", "middle", "end"]).unwrap();
        let [_, middle, end] = limb.joints();
        let dofs = s.joints()[end].rotation_dof.map(|d| d.is_some());
        let count = dofs.iter().filter(|&&d| d).count();
        if !(1..=2).contains(&count) || cases[count - 1] >= 40 {
            continue;
        }
        cases[count - 1] += 1;
        let start = random_posture(&mut rng, &s, 1.0);
        let base = limb.base(&s, &Frames::new(&s, &start));
        let position = reachable_goal(&mut rng, &limb, base);
        let swivel = uniform(&mut rng, -PI, PI);
        let axis = vec3(&mut rng, 1.0).normalize_or(DVec3::X);
        let orientation = DQuat::from_axis_angle(axis, uniform(&mut rng, 0.0, PI));
        let goal = LimbGoal {
            position,
            orientation: Some(orientation),
        };
        let sol = limb.solve(base, &goal, swivel);
        let mut p = start.clone();
        limb.apply(&sol, &mut p);
        let frames = Frames::new(&s, &p);
        assert!((frames.joint_position[end] - position).length() < 1e-9);
        let angle = rotation_angle(frames.rotation(end), orientation);
        // The end joint's parent frame, and the goal in it.
        let world_from_middle = frames.rotation(middle);
        let local = world_from_middle.inverse() * orientation;
        let zeroed = DQuat::from_scaled_axis(zeroed_rotation_vector(local, dofs));
        let zeroing = rotation_angle(zeroed, local);
        assert!(angle <= zeroing + 1e-9, "{angle} vs zeroing {zeroing}");
        if angle < zeroing - 1e-3 {
            clearly_better[count - 1] += 1;
        }
        // Dense sampling of the DOF space (|r| <= pi covers every rotation of the DOF).
        let axes: Vec<usize> = (0..3).filter(|&a| dofs[a]).collect();
        let per_axis: usize = if count == 1 { 20001 } else { 301 };
        let mut sampled = f64::INFINITY;
        for index in 0..per_axis.pow(count as u32) {
            let mut rest = index;
            let mut r = DVec3::ZERO;
            for &a in &axes {
                r[a] = -PI + TAU * (rest % per_axis) as f64 / (per_axis - 1) as f64;
                rest /= per_axis;
            }
            sampled = sampled.min(rotation_angle(DQuat::from_scaled_axis(r), local));
        }
        assert!(angle <= sampled + 1e-6, "{angle} vs sampled {sampled}");

        // An orientation the end joint can take at this swivel is met exactly.
        let mut r = DVec3::ZERO;
        for &a in &axes {
            r[a] = uniform(&mut rng, -0.9 * PI, 0.9 * PI) / count as f64;
        }
        let reachable = world_from_middle * DQuat::from_scaled_axis(r);
        let sol = limb.solve(
            base,
            &LimbGoal {
                position,
                orientation: Some(reachable),
            },
            swivel,
        );
        let mut p = start.clone();
        limb.apply(&sol, &mut p);
        let got = Frames::new(&s, &p).rotation(end);
        assert!(rotation_angle(got, reachable) < 1e-9);
        assert!((sol.end_rotation.unwrap() - r).length() < 1e-9);
    }
    // Not vacuous: zeroing the rotation vector is clearly worse for most random goals.
    assert!(
        clearly_better.iter().all(|&c| c >= 20),
        "{clearly_better:?}"
    );
}

#[test]
fn posture_to_swivel_to_posture_round_trip() {
    let mut rng = rng(43);
    let body = scenarios::humanoid50().unwrap();
    let limbs = hanim_limbs(&body);
    let mut checked = 0;
    for trial in 0..400 {
        let (skeleton, limb) = if trial % 2 == 0 {
            (body.clone(), limbs[trial / 2 % 4].clone())
        } else {
            let s = random_limb_skeleton(&mut rng);
            let limb = Limb::from_names(&s, ["upper", "middle", "end"]).unwrap();
            (s, limb)
        };
        let mut p = random_posture(&mut rng, &skeleton, 0.5);
        let [upper, middle, end] = limb.joints();
        // A posture the closed form can produce: upper rotation below pi, the hinge on the
        // limb's flexion side (strictly bent), the middle joint's other DOF at 0.
        let r = vec3(&mut rng, 1.0).normalize_or(DVec3::X) * uniform(&mut rng, 0.0, 0.95 * PI);
        for (axis, d) in skeleton.joints()[upper].rotation_dof.iter().enumerate() {
            p.values_mut()[d.unwrap()] = r[axis];
        }
        for d in skeleton.joints()[middle].dof_range() {
            p.values_mut()[d] = 0.0;
        }
        let (theta_ext, side) = limb.flexion();
        let (lo, hi) = (skeleton.lower_limits(), skeleton.upper_limits());
        let h = limb.hinge_dof();
        let (a_lo, a_hi) = if side > 0.0 {
            ((lo[h] - theta_ext).max(0.0), (hi[h] - theta_ext).min(PI))
        } else {
            ((theta_ext - hi[h]).max(0.0), (theta_ext - lo[h]).min(PI))
        };
        let alpha = a_lo + (a_hi - a_lo) * uniform(&mut rng, 0.05, 0.95);
        p.values_mut()[h] = theta_ext + side * alpha;
        let frames = Frames::new(&skeleton, &p);
        let base = limb.base(&skeleton, &frames);
        let swivel = limb.swivel_angle(&skeleton, &p);
        let goal = LimbGoal {
            position: frames.joint_position[end],
            orientation: Some(frames.rotation(end)),
        };
        let sol = limb.solve(base, &goal, swivel);
        let mut q = p.clone();
        for d in skeleton.joints()[end].dof_range() {
            q.values_mut()[d] = 0.0;
        }
        limb.apply(&sol, &mut q);
        for j in [upper, middle, end] {
            for d in skeleton.joints()[j].dof_range() {
                assert!(
                    (q.values()[d] - p.values()[d]).abs() < 1e-9,
                    "trial {trial}: {} {} vs {}",
                    skeleton.dof_name(d),
                    q.values()[d],
                    p.values()[d]
                );
            }
        }
        checked += 1;
    }
    assert_eq!(checked, 400);
}

#[test]
fn limits_hold_for_every_returned_swivel() {
    let mut rng = rng(44);
    let body = scenarios::humanoid50().unwrap();
    let limbs = hanim_limbs(&body);
    let (mut feasible, mut end_kept_within) = ([0usize; 3], 0);
    for trial in 0..600 {
        let limb = &limbs[trial % 4];
        let [_, middle, end] = limb.joints();
        // Goals reached by postures inside the limits: at least one feasible swivel exists,
        // with the posture's own end orientation too (the 2-DOF wrist or ankle, limited, then
        // counts). A random end orientation may be out of the end joint's reach.
        let p = interior_posture(&mut rng, &body, 1.5);
        let frames = Frames::new(&body, &p);
        let base = limb.base(&body, &frames);
        let kind = trial / 4 % 3;
        let goal = LimbGoal {
            position: frames.joint_position[end],
            orientation: match kind {
                0 => None,
                1 => Some(frames.rotation(end)),
                _ => Some(DQuat::from_scaled_axis(vec3(&mut rng, 1.2))),
            },
        };
        let preferred = uniform(&mut rng, -PI, PI);
        let intervals = limb.swivel_intervals(base, &goal);
        let sol = limb.solve_within_limits(base, &goal, preferred);
        let mut q = p.clone();
        limb.apply(&sol, &mut q);
        assert!((end_position(&body, &q, limb) - goal.position).length() < 1e-9);
        // The flag tells the truth, and the end joint never leaves its limits.
        assert_eq!(
            sol.within_limits,
            limb_within_limits(&body, &q, limb, 0.0),
            "trial {trial}"
        );
        let (lo, hi) = (body.lower_limits(), body.upper_limits());
        let end_ok = body.joints()[end]
            .dof_range()
            .all(|d| q.values()[d] >= lo[d] && q.values()[d] <= hi[d]);
        assert!(
            kind == 0 || end_ok,
            "trial {trial}: end joint outside its limits"
        );
        if intervals.is_empty() {
            assert_eq!(kind, 2, "trial {trial}: no feasible swivel");
            if sol.within_limits {
                // Only the end joint's limits ruled every swivel out: it took the rotation
                // within them nearest to the goal (no farther than the old projection,
                // clamped).
                end_kept_within += 1;
                let world_from_middle = Frames::new(&body, &q).rotation(middle);
                let local = world_from_middle.inverse() * goal.orientation.unwrap();
                let dofs = body.joints()[end].rotation_dof;
                let mut clamped = zeroed_rotation_vector(local, dofs.map(|d| d.is_some()));
                for (a, d) in dofs.iter().enumerate() {
                    if let Some(d) = *d {
                        clamped[a] = clamped[a].clamp(lo[d], hi[d]);
                    }
                }
                let got = rotation_angle(
                    Frames::new(&body, &q).rotation(end),
                    goal.orientation.unwrap(),
                );
                let old = rotation_angle(
                    world_from_middle * DQuat::from_scaled_axis(clamped),
                    goal.orientation.unwrap(),
                );
                assert!(got <= old + 1e-9, "trial {trial}: {got} vs {old}");
            }
            continue;
        }
        feasible[kind] += 1;
        assert!(sol.within_limits, "trial {trial}");
        assert!(
            limb_within_limits(&body, &q, limb, 0.0),
            "trial {trial}: swivel {} outside the limits",
            sol.swivel_angle
        );
        assert!(intervals.iter().any(|iv| iv.contains(sol.swivel_angle)));
        // Nearest: the preferred swivel itself when feasible, otherwise an interval end no
        // farther than any other.
        if intervals.iter().any(|iv| iv.contains(preferred)) {
            assert!(angle_diff(sol.swivel_angle, preferred) < 1e-12);
        } else {
            let best = intervals
                .iter()
                .flat_map(|iv| [iv.start, iv.end])
                .map(|x| angle_diff(x, preferred))
                .fold(f64::INFINITY, f64::min);
            assert!((angle_diff(sol.swivel_angle, preferred) - best).abs() < 1e-12);
        }
    }
    // The limb joints are inside their limits in `p`, whose swivel is feasible for its own
    // end position and orientation.
    assert_eq!(feasible[..2], [200, 200]);
    // Not vacuous: random orientations give both outcomes.
    assert!(
        feasible[2] >= 20 && end_kept_within >= 20,
        "{feasible:?} {end_kept_within}"
    );
}

#[test]
fn feasible_intervals_agree_with_dense_sampling() {
    let mut rng = rng(45);
    let body = scenarios::humanoid50().unwrap();
    let limbs = hanim_limbs(&body);
    let samples = 4000;
    let mut mismatches = Vec::new();
    let mut partial = 0;
    for trial in 0..48 {
        let limb = &limbs[trial % 4];
        let p = interior_posture(&mut rng, &body, 1.5);
        let frames = Frames::new(&body, &p);
        let base = limb.base(&body, &frames);
        let end = limb.joints()[2];
        // Half of the goals with an orientation (the end joint's limits then count too).
        let goal = LimbGoal {
            position: frames.joint_position[end],
            orientation: (trial % 3 == 0).then(|| frames.rotation(end)),
        };
        let intervals = limb.swivel_intervals(base, &goal);
        let total: f64 = intervals.iter().map(|iv| iv.length()).sum();
        if total > 0.0 && total < TAU {
            partial += 1;
        }
        for i in 0..samples {
            let phi = -PI + TAU * (i as f64 + 0.5) / samples as f64;
            let near_end = intervals
                .iter()
                .any(|iv| angle_diff(phi, iv.start) < 1e-6 || angle_diff(phi, iv.end) < 1e-6);
            if near_end {
                continue;
            }
            let sol = limb.solve(base, &goal, phi);
            let mut q = p.clone();
            limb.apply(&sol, &mut q);
            let direct = limb_within_limits(&body, &q, limb, 0.0);
            let listed = intervals.iter().any(|iv| iv.contains(phi));
            if direct != listed {
                mismatches.push((trial, phi, direct));
            }
        }
    }
    assert!(
        mismatches.is_empty(),
        "{:?}",
        &mismatches[..mismatches.len().min(10)]
    );
    // The check is not vacuous: many goals have a proper subset of feasible swivels.
    assert!(partial >= 10, "{partial}");
}

#[test]
fn no_flip_along_a_path_through_straight_configurations() {
    let humanoid = scenarios::humanoid50().unwrap();
    let arm = straight_arm();
    let mut cases: Vec<(Skeleton, Limb)> = hanim_limbs(&humanoid)
        .into_iter()
        .map(|l| (humanoid.clone(), l))
        .collect();
    // The ideal arm goes exactly straight (the H-Anim limbs stop a little before).
    cases.push((
        arm.clone(),
        Limb::from_names(&arm, ["shoulder", "elbow", "wrist"]).unwrap(),
    ));
    for (body, limb) in cases {
        let base_posture = Posture::rest(&body);
        let frames = Frames::new(&body, &base_posture);
        let base = limb.base(&body, &frames);
        let (_, reach_max) = limb.reach();
        let (theta_ext, side) = limb.flexion();
        let steps = 4000;
        let mut last: Option<(f64, DVec3)> = None;
        for i in 0..=steps {
            let t = i as f64 / steps as f64;
            // The goal sweeps across the limb's rest direction and out to 1.02 x its reach and
            // back: nearly straight, straight, and beyond.
            let dir = DVec3::new((t - 0.5) * 0.8, -1.0, (t - 0.5) * 0.3).normalize();
            let d = reach_max * (0.93 + 0.09 * (PI * t).sin());
            let goal = base.upper_position + dir * d;
            let sol = limb.solve(base, &LimbGoal::position(goal), 0.4);
            let mut p = base_posture.clone();
            limb.apply(&sol, &mut p);
            let f = Frames::new(&body, &p);
            let elbow = f.joint_position[limb.joints()[1]];
            let hinge = sol.hinge_angle;
            assert!(hinge.is_finite() && elbow.is_finite());
            assert!(side * (hinge - theta_ext) >= -1e-12, "flipped at t = {t}");
            if let Some((h0, e0)) = last {
                assert!(
                    (hinge - h0).abs() < 0.05,
                    "hinge jumps at t = {t}: {h0} -> {hinge}"
                );
                assert!((elbow - e0).length() < 0.01, "elbow jumps at t = {t}");
            }
            if d > reach_max {
                assert!(!sol.reached);
                // Nearest reachable point: on the ray, fully extended.
                let got = f.joint_position[limb.joints()[2]];
                assert!(((got - base.upper_position).length() - reach_max).abs() < 1e-9);
                assert!((got - base.upper_position).normalize().dot(dir) > 1.0 - 1e-12);
            }
            last = Some((hinge, elbow));
        }
    }
}

#[test]
fn degenerate_goals_give_defined_answers() {
    let body = scenarios::humanoid50().unwrap();
    let rest = Posture::rest(&body);
    let frames = Frames::new(&body, &rest);
    for limb in hanim_limbs(&body) {
        let base = limb.base(&body, &frames);
        let (reach_min, _) = limb.reach();
        let goals = [
            base.upper_position,
            base.upper_position + DVec3::new(1e-15, 0.0, 0.0),
            base.upper_position + DVec3::new(0.0, 0.0, 5.0),
            DVec3::new(f64::NAN, 0.0, 0.0),
            DVec3::splat(f64::INFINITY),
        ];
        for goal in goals {
            for swivel in [0.0, 2.0, f64::NAN] {
                let sol = limb.solve(base, &LimbGoal::position(goal), swivel);
                let again = limb.solve(base, &LimbGoal::position(goal), swivel);
                assert_eq!(sol, again, "deterministic");
                assert!(sol.upper_rotation.is_finite() && sol.hinge_angle.is_finite());
                assert!(sol.swivel_angle.is_finite() && sol.end_position.is_finite());
                let lim = limb.solve_within_limits(base, &LimbGoal::position(goal), swivel);
                assert!(lim.upper_rotation.is_finite() && lim.hinge_angle.is_finite());
            }
        }
        // At the upper joint: the folded limb, at the shortest reachable distance.
        let sol = limb.solve(base, &LimbGoal::position(base.upper_position), 0.0);
        assert!(!sol.reached || reach_min == 0.0);
        assert!(((sol.end_position - base.upper_position).length() - reach_min).abs() < 1e-9);
    }
}

#[test]
fn bad_limbs_are_rejected() {
    let body = scenarios::humanoid50().unwrap();
    assert!(matches!(
        Limb::from_names(&body, ["l_shoulder", "r_elbow", "r_radiocarpal"]),
        Err(IkError::BadLimb(_))
    ));
    // The elbow as upper joint: one DOF only.
    assert!(matches!(
        Limb::from_names(&body, ["l_elbow", "l_radiocarpal", "l_shoulder"]),
        Err(IkError::BadLimb(_))
    ));
    assert!(matches!(
        Limb::from_names(&body, ["l_shoulder", "l_elbow", "l_wirst"]),
        Err(IkError::UnknownJoint(_))
    ));
}

/// A straight arm hanging from a fixed shoulder, elbow limited to flexion.
fn straight_arm() -> Skeleton {
    Skeleton::new(vec![
        JointDef::new(
            "shoulder",
            None,
            DVec3::new(0.2, 1.4, 0.0),
            &[Dof::Rx, Dof::Ry, Dof::Rz],
        ),
        JointDef::new(
            "elbow",
            Some("shoulder"),
            DVec3::new(0.0, -0.3, 0.0),
            &[Dof::Rx],
        )
        .with_limit(Dof::Rx, -2.5, 0.0),
        JointDef::new(
            "wrist",
            Some("elbow"),
            DVec3::new(0.0, -0.27, 0.0),
            &[Dof::Rx, Dof::Rz],
        ),
    ])
    .unwrap()
}

/// An arm whose shoulder swings in the x-y plane within +-2.5 rad of its rest direction (+x),
/// tilting out of that plane by at most 0.2 rad, and whose elbow flexes one way only
/// (counter-clockwise about z): the upper arm cannot point into the gap of 1.28 rad around
/// -x, behind the shoulder. A wrist 2-DOF as on the humanoid.
fn gap_arm() -> Skeleton {
    Skeleton::new(vec![
        JointDef::new(
            "shoulder",
            None,
            DVec3::new(0.0, 1.4, 0.0),
            &[Dof::Rx, Dof::Ry, Dof::Rz],
        )
        .with_limit(Dof::Rx, -0.2, 0.2)
        .with_limit(Dof::Ry, -0.2, 0.2)
        .with_limit(Dof::Rz, -2.5, 2.5),
        JointDef::new(
            "elbow",
            Some("shoulder"),
            DVec3::new(0.3, 0.0, 0.0),
            &[Dof::Rz],
        )
        .with_limit(Dof::Rz, 0.0, 2.5),
        JointDef::new(
            "wrist",
            Some("elbow"),
            DVec3::new(0.27, 0.0, 0.0),
            &[Dof::Rx, Dof::Rz],
        ),
    ])
    .unwrap()
}

#[test]
fn hybrid_restarts_a_solve_stuck_in_a_joint_limit_local_minimum() {
    // The target lies behind and below the shoulder (polar angle about -2.1 rad in the x-y
    // plane, 93-97 % of the reach); the arm starts raised behind it (upper arm at about
    // +2.2 rad), across the gap. Pulling the wrist straight at the target swings the arm
    // counter-clockwise into the shoulder limit (2.5 rad), the out-of-plane tilt into its
    // limits, and the elbow flexes to the nearest point of the curve it can still sweep: a
    // constrained local minimum about 0.35 m from the target. The target is reachable the
    // other way round (upper arm near -2.35 rad, elbow slightly bent), which the closed form
    // finds. Starts and targets are perturbed: the trap is no measure-zero configuration.
    let s = gap_arm();
    let wrist = s.require_joint("wrist").unwrap();
    let limb = Limb::from_names(&s, ["shoulder", "elbow", "wrist"]).unwrap();
    let shoulder = DVec3::new(0.0, 1.4, 0.0);
    let (lo, hi) = (s.lower_limits().to_vec(), s.upper_limits().to_vec());
    let mut rng = rng(47);
    for trial in 0..12 {
        let angle: f64 = -2.1 + uniform(&mut rng, -0.03, 0.03);
        let distance = 0.57 * uniform(&mut rng, 0.93, 0.97);
        let target = shoulder + distance * DVec3::new(angle.cos(), angle.sin(), 0.0);
        let tasks = vec![Task::position(wrist, DVec3::ZERO, target)];
        let start = Posture::from_values(
            &s,
            vec![
                uniform(&mut rng, -0.15, 0.15),
                uniform(&mut rng, -0.15, 0.15),
                2.2 + uniform(&mut rng, -0.1, 0.1),
                0.3 + uniform(&mut rng, -0.1, 0.1),
                uniform(&mut rng, -0.5, 0.5),
                uniform(&mut rng, -0.5, 0.5),
            ],
        )
        .unwrap();
        let distance_at =
            |p: &Posture| (Frames::new(&s, p).joint_position[wrist] - target).length();

        let mut alone = Solver::default();
        let mut p = start.clone();
        let report = alone.solve(&s, &tasks, &mut p).unwrap();
        assert_eq!(report.status, SolveStatus::Stalled, "trial {trial}");
        let stuck = report.levels[0].residual_after;
        assert!(stuck > 1e-3, "trial {trial}: {stuck}");
        assert!(report.analytic_restarts.is_empty());
        // A genuine local minimum, not a saddle or singular point: no move of up to 1e-2 rad
        // per DOF within the limits brings the wrist closer by more than the stall tolerance
        // leaves (from a saddle some would, at least at second order).
        for _ in 0..200 {
            let mut q = p.clone();
            for (d, v) in q.values_mut().iter_mut().enumerate() {
                *v = (*v + uniform(&mut rng, -1e-2, 1e-2)).clamp(lo[d], hi[d]);
            }
            assert!(
                distance_at(&q) >= stuck - 1e-6,
                "trial {trial}: {} < {stuck} near the stalled posture",
                distance_at(&q)
            );
        }

        let mut hybrid = Solver::default().with_limbs(vec![limb.clone()]);
        let mut p = start.clone();
        let report = hybrid.solve(&s, &tasks, &mut p).unwrap();
        assert_eq!(
            report.status,
            SolveStatus::Converged,
            "trial {trial}: {report:?}"
        );
        assert_eq!(report.analytic_restarts.len(), 1);
        assert_eq!(report.analytic_restarts[0].joints[1], "elbow");
        assert!(distance_at(&p) < 1e-4, "trial {trial}: {}", distance_at(&p));
        assert!(limb_within_limits(&s, &p, &limb, 0.0));
        // The other way round: the upper arm swung clockwise past -2 rad.
        assert!(p.values()[2] < -2.0, "trial {trial}: {:?}", p.values());
    }

    // A solve that converges by itself never restarts.
    let easy = vec![Task::position(
        wrist,
        DVec3::ZERO,
        shoulder + DVec3::new(0.2, 0.35, 0.05),
    )];
    let mut hybrid = Solver::default().with_limbs(vec![limb]);
    let mut p = Posture::rest(&s);
    p.values_mut()[3] = 0.4;
    let report = hybrid.solve(&s, &easy, &mut p).unwrap();
    assert_eq!(report.status, SolveStatus::Converged);
    assert!(report.analytic_restarts.is_empty());
}
