//! Contact detection on generated tracks: each test a motion whose contacts are known.

use super::*;

fn track(positions: Vec<DVec3>) -> PointTrack {
    PointTrack {
        joint: "l_talocrural".into(),
        part: ContactPart::Heel,
        point: DVec3::ZERO,
        positions,
        tip: None,
    }
}

fn scale(leg: f64) -> ClipScale {
    ClipScale {
        leg,
        pace: 0.0,
        start: 0,
    }
}

#[test]
fn a_heel_that_stops_on_the_floor_is_one_contact_held_where_it_rested() {
    // 1 m/s swing 12 cm up, rest 20 frames at x = 0.5 on the floor, swing again; the
    // other foot stands on the floor throughout (it sets the ground).
    let dt = 0.01;
    let mut p = Vec::new();
    for f in 0..20 {
        p.push(DVec3::new(f as f64 * 0.025, 0.12, 0.0));
    }
    for _ in 0..20 {
        p.push(DVec3::new(0.5, 0.0, 0.0));
    }
    for f in 0..20 {
        p.push(DVec3::new(0.5 + f as f64 * 0.025, 0.12, 0.0));
    }
    let standing = PointTrack {
        joint: "r_talocrural".into(),
        ..track(vec![DVec3::new(0.0, 0.0, 0.3); 60])
    };
    let s = ContactSettings {
        window: 0.02,
        ..ContactSettings::default()
    };
    let c = detect_contacts(&[track(p), standing], dt, &scale(0.9), &s);
    let left: Vec<&Contact> = c.iter().filter(|c| c.joint == "l_talocrural").collect();
    assert_eq!(left.len(), 1, "{c:?}");
    // The central difference over one frame each side: frame 20 moves 1.25 m/s, frame
    // 39 is still (frame 40 lifts off straight up, 12 cm: too high).
    assert_eq!((left[0].start, left[0].end), (21, 39));
    assert!((left[0].position - DVec3::new(0.5, 0.0, 0.0)).length() < 1e-12);
    assert_eq!(left[0].floor, 0.0);
    assert_eq!(contact_weight(left[0], 30, 5), 1.0);
    assert_eq!(contact_weight(left[0], 10, 5), 0.0);
    let w: Vec<f64> = (15..=21).map(|f| contact_weight(left[0], f, 5)).collect();
    assert!(w.windows(2).all(|p| p[0] < p[1]), "{w:?}");
}

#[test]
fn a_low_but_sliding_foot_slides_and_a_short_touch_is_no_contact() {
    let dt = 1.0 / 30.0;
    // 0.6 m/s along the floor for 20 frames: one sliding contact over all of them, none
    // held still; at 1.5 m/s (over three times the still speed) it is passing low.
    let at = |speed: f64| -> Vec<DVec3> {
        (0..20)
            .map(|f| DVec3::new(f as f64 * speed * dt, 0.0, 0.0))
            .collect()
    };
    let s = ContactSettings::default();
    let c = detect_contacts(&[track(at(0.6))], dt, &scale(0.9), &s);
    assert_eq!(c.len(), 1, "{c:?}");
    assert!(c[0].slides && (c[0].start, c[0].end) == (0, 19), "{c:?}");
    assert!(detect_contacts(&[track(at(1.5))], dt, &scale(0.9), &s).is_empty());
    let mut touch = vec![DVec3::new(0.0, 0.3, 0.0); 10];
    touch[5] = DVec3::new(0.0, 0.0, 0.0);
    let s = ContactSettings {
        speed: 100.0,
        min_duration: 0.1,
        ..Default::default()
    };
    // The other foot stands on the ground; the touch is one frame long.
    let standing = PointTrack {
        joint: "r_talocrural".into(),
        ..track(vec![DVec3::ZERO; 10])
    };
    let c = detect_contacts(&[track(touch), standing], dt, &scale(0.9), &s);
    assert!(c.iter().all(|c| c.joint == "r_talocrural"), "{c:?}");
    assert_eq!(c.len(), 1);
}

#[test]
fn a_foot_slides_only_where_no_contact_of_it_holds_it_still() {
    // At 100 fps: the heel lands sliding at 0.8 m/s for 10 frames, stands still for 20,
    // then rolls up; the ball is low and still from frame 15 to 45, then drags forward at
    // 0.8 m/s on the floor to frame 60. The other foot stands and sets the ground.
    let dt = 0.01;
    let mut heel = Vec::new();
    for f in 0..10 {
        heel.push(DVec3::new(-0.08 + f as f64 * 0.008, 0.0, 0.0));
    }
    heel.extend(std::iter::repeat_n(DVec3::ZERO, 20));
    for f in 0..31 {
        heel.push(DVec3::new(0.0, 0.01 * f as f64, 0.0));
    }
    let mut ball = vec![DVec3::new(0.1, 0.05 + 0.01, 0.0); 15];
    ball.extend(std::iter::repeat_n(DVec3::new(0.2, 0.0, 0.0), 31));
    for f in 0..15 {
        ball.push(DVec3::new(0.2 + 0.008 * (f + 1) as f64, 0.0, 0.0));
    }
    let standing = PointTrack {
        joint: "r_talocrural".into(),
        ..track(vec![DVec3::new(0.0, 0.0, 0.3); 61])
    };
    let tracks = [
        track(heel),
        PointTrack {
            part: ContactPart::Ball,
            ..track(ball)
        },
        standing,
    ];
    let c = detect_contacts(&tracks, dt, &scale(0.9), &ContactSettings::default());
    let left = |slides: bool| -> Vec<(ContactPart, usize, usize)> {
        c.iter()
            .filter(|c| c.joint == "l_talocrural" && c.slides == slides)
            .map(|c| (c.part, c.start, c.end))
            .collect()
    };
    // Held still: the heel while it stands, the ball while it stands (the speed is
    // measured over 4 frames each side, so a still run ends 4 frames from the slide).
    let held = left(false);
    assert!(held.iter().any(|h| h.0 == ContactPart::Heel), "{c:?}");
    assert!(held.iter().any(|h| h.0 == ContactPart::Ball), "{c:?}");
    // Sliding: the heel's landing before any point of that foot is held, and the ball's
    // drag after; nothing sliding at a frame the foot is held.
    let sliding = left(true);
    assert_eq!(sliding.len(), 2, "{c:?}");
    let (first, last) = (sliding[0], sliding[1]);
    assert!(first.0 == ContactPart::Heel && first.1 == 0, "{sliding:?}");
    assert!(last.0 == ContactPart::Ball && last.2 == 60, "{sliding:?}");
    for s in &sliding {
        for h in &held {
            assert!(s.2 < h.1 || s.1 > h.2, "{s:?} slides while {h:?} holds");
        }
    }
    // Kept from sinking under the ground there, not held in place.
    let drag = c.iter().find(|c| c.slides && c.part == ContactPart::Ball);
    assert!(drag.is_some_and(|d| d.floor.abs() < 1e-12 && d.position.y.abs() < 1e-12));
}

#[test]
fn a_ball_raised_over_toes_on_the_floor_rests_on_them() {
    // On tiptoe: the ball still, 6 cm up (over the 5 cm height), the toes' tip under it
    // on the floor; the other foot stands on the floor and sets the ground.
    let dt = 0.01;
    let ball = PointTrack {
        part: ContactPart::Ball,
        tip: Some(vec![DVec3::new(0.05, 0.0, 0.0); 30]),
        ..track(vec![DVec3::new(0.0, 0.06, 0.0); 30])
    };
    let standing = PointTrack {
        joint: "r_talocrural".into(),
        ..track(vec![DVec3::new(0.0, 0.0, 0.3); 30])
    };
    let s = ContactSettings::default();
    let c = detect_contacts(&[ball.clone(), standing.clone()], dt, &scale(0.9), &s);
    let on_toes: Vec<&Contact> = c.iter().filter(|c| c.part == ContactPart::Ball).collect();
    assert_eq!(on_toes.len(), 1, "{c:?}");
    assert_eq!((on_toes[0].start, on_toes[0].end), (0, 29));
    // Without the tip the raised ball is no contact.
    let bare = PointTrack { tip: None, ..ball };
    let c = detect_contacts(&[bare, standing], dt, &scale(0.9), &s);
    assert!(c.iter().all(|c| c.part != ContactPart::Ball), "{c:?}");
}

/// The track of `part` on `joint`.
fn part_track(part: ContactPart, joint: &str, positions: Vec<DVec3>) -> PointTrack {
    PointTrack {
        joint: joint.into(),
        part,
        ..track(positions)
    }
}

#[test]
fn a_crawl_s_hands_rest_at_the_height_the_clip_rests_them() {
    // At 30 fps on hands and knees: the toes on the floor, the knee joints 3 cm over it,
    // each wrist still 10 cm over it (a palm planted: over twice the typical clearance
    // and the contact height together) for 20 frames, then swung 8 cm up and 30 cm
    // forward in 10 frames, then planted again; the right hand a half cycle later.
    let dt = 1.0 / 30.0;
    let hand = |phase: usize| -> Vec<DVec3> {
        (0..60)
            .map(|f| {
                let k = (f + phase) % 30;
                let x = 0.3 * ((f + phase) / 30) as f64;
                if k < 20 {
                    DVec3::new(x, 0.10, 0.0)
                } else {
                    let s = (k - 19) as f64 / 10.0;
                    DVec3::new(
                        x + 0.3 * s,
                        0.10 + 0.08 * (s * std::f64::consts::PI).sin(),
                        0.0,
                    )
                }
            })
            .collect()
    };
    let on_floor = vec![DVec3::ZERO; 60];
    let knee = vec![DVec3::new(0.0, 0.03, 0.0); 60];
    let tracks = [
        part_track(ContactPart::Ball, "l_talocrural", on_floor.clone()),
        part_track(ContactPart::Ball, "r_talocrural", on_floor),
        part_track(ContactPart::Knee, "l_knee", knee.clone()),
        part_track(ContactPart::Knee, "r_knee", knee),
        part_track(ContactPart::Hand, "l_radiocarpal", hand(0)),
        part_track(ContactPart::Hand, "r_radiocarpal", hand(15)),
    ];
    let s = ContactSettings::default();
    let c = detect_contacts(&tracks, dt, &scale(0.9), &s);
    let hands: Vec<(&str, usize, usize)> = c
        .iter()
        .filter(|c| c.part == ContactPart::Hand)
        .map(|c| (c.joint.as_str(), c.start, c.end))
        .collect();
    // Each stance of each hand found (the left's 0-19 and 30-49, the right's 0-4, 15-34
    // and 45-59), none while it swings.
    assert_eq!(hands.len(), 5, "{hands:?}");
    for (joint, start, end) in &hands {
        let phase = if *joint == "l_radiocarpal" { 0 } else { 15 };
        assert!(
            (*start..=*end).all(|f| (f + phase) % 30 < 20),
            "{joint} {start}..{end} swings"
        );
    }
    let held = c.iter().find(|c| c.part == ContactPart::Hand);
    assert!(held.is_some_and(|h| (h.clearance - 0.10).abs() < 1e-9 && h.floor.abs() < 1e-9));
    // The knees too, resting at their own 3 cm.
    assert_eq!(c.iter().filter(|c| c.part == ContactPart::Knee).count(), 2);
}

#[test]
fn sitting_down_on_the_floor_rests_the_pelvis_there_and_standing_up_lifts_it() {
    // At 30 fps: standing (the pelvis joint 0.95 m up) for 20 frames, sitting down over
    // 30, on the floor for 40 (the hip joints 10 cm over it, where the buttocks put
    // them), standing up over 20, standing for 20; both heels on the floor throughout.
    let dt = 1.0 / 30.0;
    let height = |f: usize| -> f64 {
        let ease = |t: f64| t * t * (3.0 - 2.0 * t);
        match f {
            0..20 => 0.95,
            20..50 => 0.95 - 0.85 * ease((f - 20) as f64 / 30.0),
            50..90 => 0.10,
            90..110 => 0.10 + 0.85 * ease((f - 90) as f64 / 20.0),
            _ => 0.95,
        }
    };
    let pelvis: Vec<DVec3> = (0..130).map(|f| DVec3::new(0.0, height(f), -0.1)).collect();
    let tracks = [
        part_track(ContactPart::Heel, "l_talocrural", vec![DVec3::ZERO; 130]),
        part_track(ContactPart::Heel, "r_talocrural", vec![DVec3::ZERO; 130]),
        part_track(ContactPart::Pelvis, "humanoid_root", pelvis),
    ];
    let c = detect_contacts(&tracks, dt, &scale(0.9), &ContactSettings::default());
    let sat: Vec<&Contact> = c.iter().filter(|c| c.part == ContactPart::Pelvis).collect();
    assert_eq!(sat.len(), 1, "{c:?}");
    let (start, end) = (sat[0].start, sat[0].end);
    // Held from when it settles to when it rises (a frame or two of the ease at each
    // end is within the contact height), never while standing.
    assert!(
        (46..=52).contains(&start) && (88..=94).contains(&end),
        "{start}..{end}"
    );
    assert!(
        (sat[0].clearance - 0.10).abs() < 1e-9 && sat[0].floor.abs() < 1e-9,
        "{:?}",
        sat[0]
    );
}

#[test]
fn hands_that_never_come_down_keep_the_typical_clearance_and_get_no_contact() {
    // Standing still: the feet on the floor, the wrists still 0.75 m over it (over the
    // most a hand's rest can be), the knees 0.45 m.
    let dt = 1.0 / 30.0;
    let tracks = [
        part_track(ContactPart::Heel, "l_talocrural", vec![DVec3::ZERO; 30]),
        part_track(
            ContactPart::Hand,
            "l_radiocarpal",
            vec![DVec3::Y * 0.75; 30],
        ),
        part_track(ContactPart::Knee, "l_knee", vec![DVec3::Y * 0.45; 30]),
    ];
    let s = ContactSettings::default();
    let limits = s.thresholds(&scale(0.9));
    let speeds = vec![vec![0.0; 30]; 3];
    let found = clearances(&tracks, &speeds, &limits, &scale(0.9));
    assert_eq!(found, vec![0.0, 0.04 * 0.9, 0.07 * 0.9]);
    let c = detect_contacts(&tracks, dt, &scale(0.9), &s);
    assert!(c.iter().all(|c| c.part.is_foot()), "{c:?}");
}

#[test]
fn a_foot_on_a_step_rests_from_its_landing_and_the_next_step_from_its_own() {
    // At 30 fps, up two 20 cm steps: the left foot swings onto the first step (still on
    // it from frame 10), lifts off at 50; the right stands on the floor to frame 24,
    // swings 30 cm up over the step and lands on the second (40 cm) at 45. While the
    // right swings, the ground of the window (half a second either side) is still the
    // floor for the left on the step: it was found from frame 37 only.
    let dt = 1.0 / 30.0;
    let left: Vec<DVec3> = (0..60)
        .map(|f| match f {
            0..10 => DVec3::new(0.03 * f as f64, 0.25, 0.0),
            10..50 => DVec3::new(0.3, 0.2, 0.0),
            _ => DVec3::new(0.3 + 0.05 * (f - 49) as f64, 0.5, 0.0),
        })
        .collect();
    let right: Vec<DVec3> = (0..60)
        .map(|f| match f {
            0..25 => DVec3::new(0.0, 0.0, 0.2),
            25..45 => DVec3::new(0.05 * (f - 24) as f64, 0.45, 0.2),
            _ => DVec3::new(1.0, 0.4, 0.2),
        })
        .collect();
    let tracks = [
        part_track(ContactPart::Heel, "l_talocrural", left),
        part_track(ContactPart::Heel, "r_talocrural", right),
    ];
    let c = detect_contacts(&tracks, dt, &scale(0.9), &ContactSettings::default());
    let held = |joint: &str| -> Vec<(usize, usize, f64)> {
        c.iter()
            .filter(|c| c.joint == joint && !c.slides)
            .map(|c| (c.start, c.end, c.floor))
            .collect()
    };
    // The central difference over a frame each side: still from the frame after landing
    // to the one before lifting off.
    let (left, right) = (held("l_talocrural"), held("r_talocrural"));
    assert_eq!(left.len(), 1, "{c:?}");
    assert_eq!((left[0].0, left[0].1), (11, 48), "{left:?}");
    assert!((left[0].2 - 0.2).abs() < 1e-9, "{left:?}");
    assert_eq!(right.len(), 2, "{c:?}");
    assert_eq!((right[0].0, right[0].1), (0, 23), "{right:?}");
    assert_eq!((right[1].0, right[1].1), (45, 59), "{right:?}");
    assert!((right[1].2 - 0.4).abs() < 1e-9, "{right:?}");
}

#[test]
fn feet_still_at_the_top_of_a_jump_get_no_contact() {
    // At 30 fps both feet stand, jump straight up (0.5 s in the air, 31 cm high: still
    // horizontally all along, vertically near the top) and land.
    let dt = 1.0 / 30.0;
    let foot = |z: f64| -> Vec<DVec3> {
        (0..75)
            .map(|f| {
                let t = (f as f64 - 30.0) * dt;
                let y = if (0.0..0.5).contains(&t) {
                    t * (2.45 - 4.905 * t)
                } else {
                    0.0
                };
                DVec3::new(0.0, y.max(0.0), z)
            })
            .collect()
    };
    let tracks = [
        part_track(ContactPart::Heel, "l_talocrural", foot(0.1)),
        part_track(ContactPart::Heel, "r_talocrural", foot(-0.1)),
    ];
    let c = detect_contacts(&tracks, dt, &scale(0.9), &ContactSettings::default());
    for c in &c {
        assert!(c.end < 32 || c.start > 43, "{c:?} in the air");
    }
    assert_eq!(c.len(), 4, "{c:?}");
}

#[test]
fn thresholds_scale_with_the_leg_and_rise_with_the_pace() {
    let s = ContactSettings::default();
    let t = s.thresholds(&ClipScale {
        leg: 0.45,
        pace: 0.0,
        start: 0,
    });
    assert!((t.height - 0.025).abs() < 1e-12 && (t.speed - 0.175).abs() < 1e-12);
    let run = s.thresholds(&ClipScale {
        leg: 0.9,
        pace: 4.0,
        start: 0,
    });
    assert!(
        (run.speed - 0.35 * 4.0 / REFERENCE_PACE).abs() < 1e-12,
        "{run:?}"
    );
}
