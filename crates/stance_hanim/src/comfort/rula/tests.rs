#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

#[cfg(target_arch = "wasm32")]
use wasm_bindgen_test::wasm_bindgen_test as test;

use stance_ik::comfort::ComfortModel;
use stance_ik::{Dof, Frames, JointDef, Posture, Skeleton};

use super::*;
use crate::{LevelOfArticulation, SkeletonOptions, default_skeleton};

// ---------------------------------------------------------------------------------------------
// Tables: the grids of the research notes (comfort.md, 1.3-1.5), as text.

/// Table A, common table: `UA LA  w1t1 w1t2 w2t1 w2t2 w3t1 w3t2 w4t1 w4t2`.
const GRID_A: &str = "
1 1 1 2 2 2 2 3 3 3
1 2 2 2 2 2 3 3 3 3
1 3 2 3 3 3 3 3 4 4
2 1 2 3 3 3 3 4 4 4
2 2 3 3 3 3 3 4 4 4
2 3 3 4 4 4 4 4 5 5
3 1 3 3 4 4 4 4 5 5
3 2 3 4 4 4 4 4 5 5
3 3 4 4 4 4 4 5 5 5
4 1 4 4 4 4 4 5 5 5
4 2 4 4 4 4 4 5 5 5
4 3 4 4 4 5 5 5 6 6
5 1 5 5 5 5 5 6 6 7
5 2 5 6 6 6 6 7 7 7
5 3 6 6 6 7 7 7 7 8
6 1 7 7 7 7 7 8 8 9
6 2 8 8 8 8 8 9 9 9
6 3 9 9 9 9 9 9 9 9
";

/// Table B: `NECK  t1l1 t1l2 t2l1 t2l2 t3l1 t3l2 t4l1 t4l2 t5l1 t5l2 t6l1 t6l2`.
const GRID_B: &str = "
1 1 3 2 3 3 4 5 5 6 6 7 7
2 2 3 2 3 4 5 5 5 6 7 7 7
3 3 3 3 4 4 5 5 6 6 7 7 7
4 5 5 5 6 6 7 7 7 7 7 8 8
5 7 7 7 7 7 8 8 8 8 8 8 8
6 8 8 8 8 8 8 8 9 9 9 9 9
";

/// Table C: `C  d1 d2 d3 d4 d5 d6 d7`.
const GRID_C: &str = "
1 1 2 3 3 4 5 5
2 2 2 3 4 4 5 5
3 3 3 3 4 4 5 6
4 3 3 3 4 5 6 6
5 4 4 4 5 6 7 7
6 4 4 5 6 6 7 7
7 5 5 6 6 7 7 7
8 5 5 6 7 7 7 7
";

fn parse(grid: &str) -> Vec<Vec<u8>> {
    grid.lines()
        .filter(|l| !l.trim().is_empty())
        .map(|l| l.split(' ').map(|c| c.parse().unwrap()).collect())
        .collect()
}

#[test]
fn table_a_matches_every_cell_of_the_common_grid() {
    let mut cells = 0;
    for row in parse(GRID_A) {
        let (upper, lower) = (row[0], row[1]);
        for wrist in 1..=4u8 {
            for twist in 1..=2u8 {
                let expected = row[2 + 2 * usize::from(wrist - 1) + usize::from(twist - 1)];
                assert_eq!(
                    table_a(upper, lower, wrist, twist),
                    expected,
                    "UA {upper} LA {lower} wrist {wrist} twist {twist}"
                );
                cells += 1;
            }
        }
    }
    assert_eq!(cells, 144);
}

#[test]
fn table_b_matches_every_cell() {
    let mut cells = 0;
    for row in parse(GRID_B) {
        let neck = row[0];
        for trunk in 1..=6u8 {
            for legs in 1..=2u8 {
                let expected = row[1 + 2 * usize::from(trunk - 1) + usize::from(legs - 1)];
                assert_eq!(
                    table_b(neck, trunk, legs),
                    expected,
                    "{neck} {trunk} {legs}"
                );
                cells += 1;
            }
        }
    }
    assert_eq!(cells, 72);
}

#[test]
fn table_c_matches_every_cell() {
    let mut cells = 0;
    for row in parse(GRID_C) {
        let c = row[0];
        for d in 1..=7u8 {
            assert_eq!(table_c(c, d), row[usize::from(d)], "C {c} D {d}");
            cells += 1;
        }
    }
    assert_eq!(cells, 56);
}

#[test]
fn table_inputs_are_clamped() {
    assert_eq!(table_a(0, 0, 0, 0), table_a(1, 1, 1, 1));
    assert_eq!(table_a(9, 7, 8, 5), table_a(6, 3, 4, 2));
    assert_eq!(table_a(7, 1, 1, 1), 7);
    assert_eq!(table_b(0, 0, 0), 1);
    assert_eq!(table_b(9, 9, 9), 9);
    assert_eq!(table_c(0, 0), 1);
    assert_eq!(table_c(8, 7), 7);
    assert_eq!(table_c(12, 1), 5, "C >= 8 reads row 8");
    assert_eq!(table_c(1, 11), 5, "D >= 7 reads column 7");
    assert_eq!(table_c(3, 9), 6);
}

#[test]
fn action_levels_and_load_scores() {
    let levels: Vec<u8> = (0..=9).map(action_level).collect();
    assert_eq!(levels, vec![1, 1, 1, 2, 2, 3, 3, 4, 4, 4]);
    let loads = [
        RulaLoad::None,
        RulaLoad::Intermittent2To10,
        RulaLoad::Static2To10,
        RulaLoad::Intermittent10Plus,
        RulaLoad::Static10Plus,
        RulaLoad::Shock,
    ];
    let scores: Vec<u8> = loads.iter().map(|l| l.score()).collect();
    assert_eq!(scores, vec![0, 1, 2, 2, 3, 3]);
    let settings = RulaSettings::default();
    assert_eq!(settings.variant, RulaVariant::Paper);
    assert_eq!(settings.load, RulaLoad::None);
    assert!(!settings.muscle_use && !settings.arm_supported && !settings.seated_supported);
    assert_eq!(settings.legs_supported, None);
}

// ---------------------------------------------------------------------------------------------
// Scoring hand-made angles: edges, adjustments, C, D and the grand score.

fn arm_with(f: impl FnOnce(&mut ArmAngles)) -> RulaAngles {
    let mut angles = RulaAngles::default();
    f(&mut angles.left);
    angles
}

#[test]
fn an_edge_value_belongs_to_the_lower_band() {
    let paper = RulaSettings::default();
    let worksheet = RulaSettings {
        variant: RulaVariant::Worksheet,
        ..Default::default()
    };
    let ua = |flexion: f64, s: &RulaSettings| {
        score(&arm_with(|a| a.upper_arm_flexion = flexion), s)
            .left
            .upper_arm
    };
    // (flexion, paper, worksheet): 1 within e1 either way (edge included), 2 up to 45
    // (included), 3 up to 90 (included), 4 beyond; extension beyond e1 scores 2.
    for (flexion, p, w) in [
        (-20.0, 1, 2),
        (-15.0, 1, 1),
        (15.0, 1, 1),
        (20.0, 1, 2),
        (45.0, 2, 2),
        (90.0, 3, 3),
        (90.001, 4, 4),
        (150.0, 4, 4),
    ] {
        assert_eq!(ua(flexion, &paper), p, "paper {flexion}");
        assert_eq!(ua(flexion, &worksheet), w, "worksheet {flexion}");
    }
    let la = |e: f64| {
        score(&arm_with(|a| a.elbow_flexion = e), &paper)
            .left
            .lower_arm
    };
    assert_eq!([la(60.0), la(60.001), la(100.0), la(100.001)], [2, 1, 1, 2]);
    let wr = |w: f64| score(&arm_with(|a| a.wrist_flexion = w), &paper).left.wrist;
    assert_eq!([wr(5.0), wr(-5.001), wr(15.0), wr(-15.001)], [1, 2, 2, 3]);
    let body = |f: &dyn Fn(&mut RulaAngles)| {
        let mut angles = RulaAngles::default();
        f(&mut angles);
        score(&angles, &paper).body
    };
    let neck = |n: f64| body(&|a| a.neck_flexion = n).neck;
    assert_eq!(
        [
            neck(-5.0),
            neck(-5.001),
            neck(10.0),
            neck(20.0),
            neck(20.001)
        ],
        [1, 4, 1, 2, 3]
    );
    let trunk = |t: f64| body(&|a| a.trunk_flexion = t).trunk;
    assert_eq!(
        [
            trunk(5.0),
            trunk(-5.0),
            trunk(20.0),
            trunk(60.0),
            trunk(60.001)
        ],
        [1, 1, 2, 3, 4]
    );
    assert_eq!(body(&|a| a.neck_twist = 10.0).neck, 1);
    assert_eq!(body(&|a| a.trunk_side_bend = -10.001).trunk, 2);
}

#[test]
fn adjustments_add_up_and_stay_in_range() {
    let settings = RulaSettings::default();
    // Raised shoulder + abducted + 90+ flexion: 4 + 1 + 1 = 6.
    let angles = arm_with(|a| {
        a.upper_arm_flexion = 100.0;
        a.upper_arm_abduction = 30.0;
        a.shoulder_elevation = Some(12.0);
        a.elbow_flexion = 120.0;
        a.across_midline = true;
        a.out_to_side = true;
        a.wrist_flexion = 30.0;
        a.wrist_deviation = -8.0;
        a.wrist_twist = 2;
    });
    let report = score(&angles, &settings);
    assert_eq!(
        (
            report.left.upper_arm,
            report.left.lower_arm,
            report.left.wrist,
            report.left.wrist_twist
        ),
        (6, 3, 4, 2)
    );
    assert_eq!(report.left.posture_a, 9);
    // Supported arm: -1, never below 1.
    let supported = RulaSettings {
        arm_supported: true,
        ..Default::default()
    };
    assert_eq!(score(&angles, &supported).left.upper_arm, 5);
    assert_eq!(score(&RulaAngles::default(), &supported).left.upper_arm, 1);
    // A shoulder elevation of exactly 10 degrees is not raised; 10.001 is.
    let raised = |e: f64| {
        score(&arm_with(|a| a.shoulder_elevation = Some(e)), &settings)
            .left
            .upper_arm
    };
    assert_eq!([raised(10.0), raised(10.001)], [1, 2]);
    // Neck and trunk: extension 4 + twist + side-bend = 6; trunk 4 + 2 = 6.
    let mut angles = RulaAngles {
        neck_flexion: -30.0,
        neck_twist: -20.0,
        neck_side_bend: 15.0,
        trunk_flexion: 70.0,
        trunk_twist: 11.0,
        trunk_side_bend: -11.0,
        weight_balanced: false,
        ..Default::default()
    };
    let body = score(&angles, &settings).body;
    assert_eq!((body.neck, body.trunk, body.legs), (6, 6, 2));
    assert_eq!(body.posture_b, 9);
    // Seated and supported: a trunk flexed up to 20 degrees (or leaning back) scores 1.
    let seated = RulaSettings {
        seated_supported: true,
        legs_supported: Some(true),
        ..Default::default()
    };
    angles.trunk_twist = 0.0;
    angles.trunk_side_bend = 0.0;
    for (flexion, expected) in [(-15.0, 1), (12.0, 1), (20.0, 1), (25.0, 3)] {
        angles.trunk_flexion = flexion;
        let body = score(&angles, &seated).body;
        assert_eq!(body.trunk, expected, "seated trunk {flexion}");
        assert_eq!(body.legs, 1);
    }
}

#[test]
fn scores_c_and_d_and_the_grand_score() {
    // Rest: A = table_a(1, 2, 1, 1) = 2, B = table_b(1, 1, 1) = 1, grand = table_c(2, 1) = 2.
    let rest = score(&RulaAngles::default(), &RulaSettings::default());
    assert_eq!((rest.left.posture_a, rest.body.posture_b), (2, 1));
    assert_eq!((rest.left.score_c, rest.body.score_d), (2, 1));
    assert_eq!((rest.score, rest.action_level), (2, 1));
    // Muscle use and a static load over 10 kg: C = 2 + 1 + 3 = 6, D = 1 + 1 + 3 = 5, grand
    // table_c(6, 5) = 6: action level 3.
    let loaded = RulaSettings {
        muscle_use: true,
        load: RulaLoad::Static10Plus,
        ..Default::default()
    };
    let report = score(&RulaAngles::default(), &loaded);
    assert_eq!((report.left.muscle_use, report.left.load), (1, 3));
    assert_eq!((report.body.muscle_use, report.body.load), (1, 3));
    assert_eq!((report.left.score_c, report.body.score_d), (6, 5));
    assert_eq!((report.score, report.action_level), (6, 3));
    // The worse side: the right arm raised above 90 with a bent wrist; the left at rest.
    let mut angles = RulaAngles::default();
    angles.right.upper_arm_flexion = 120.0;
    angles.right.elbow_flexion = 80.0;
    angles.right.wrist_flexion = 20.0;
    let report = score(&angles, &RulaSettings::default());
    // Right: table_a(4, 1, 3, 1) = 4, grand table_c(4, 1) = 3; left 2.
    assert_eq!(
        (
            report.right.posture_a,
            report.right.grand,
            report.left.grand
        ),
        (4, 3, 2)
    );
    assert_eq!((report.score, report.action_level), (3, 2));
    // Intermittent loads over 10 kg score 2 (the paper), not 3.
    let heavy = RulaSettings {
        load: RulaLoad::Intermittent10Plus,
        ..Default::default()
    };
    assert_eq!(score(&RulaAngles::default(), &heavy).left.score_c, 4);
    assert_eq!(report.variant, RulaVariant::Paper);
    assert_eq!(report.angles, angles);
}

// ---------------------------------------------------------------------------------------------
// The paper as printed: no tolerance (`RulaTolerances::NONE`).

const AS_PRINTED: RulaSettings = RulaSettings {
    tolerances: RulaTolerances::NONE,
    ..PAPER
};

#[test]
fn paper_as_printed_scores_every_part_at_its_band_edges() {
    // Catches a tolerance left in the paper-as-printed mode (a 5 degree neutral wrist, neck or
    // trunk, a 10 degree twist, the variant's 20 degrees for abduction), a band edge owned by
    // the wrong side, and the default losing its tolerances. The expected scores are the
    // paper's rules read directly (McAtamney & Corlett 1993): upper arm 20 ext. to 20 flex.
    // 1, 20-45 2, 45-90 3, above 90 4, +1 abducted, +1 shoulder raised; lower arm 60-100 1,
    // else 2; wrist 0 = 1, up to 15 either way 2, beyond 3, +1 deviated; neck 0-10 1, 10-20 2,
    // beyond 3, extension 4, +1 twisted, +1 side-bent; trunk 0 = 1, 0-20 2, 20-60 3, beyond
    // 4, +1 twisted, +1 side-bent. An edge belongs to the lower band; 0.001 degrees past it
    // is in the next.
    let arm = |f: &dyn Fn(&mut ArmAngles)| {
        let mut angles = RulaAngles::default();
        f(&mut angles.left);
        let r = score(&angles, &AS_PRINTED).left;
        [r.upper_arm, r.lower_arm, r.wrist]
    };
    let ua = |f: &dyn Fn(&mut ArmAngles)| arm(f)[0];
    for (flexion, expected) in [
        (-20.001, 2),
        (-20.0, 1),
        (0.0, 1),
        (20.0, 1),
        (20.001, 2),
        (45.0, 2),
        (45.001, 3),
        (90.0, 3),
        (90.001, 4),
    ] {
        assert_eq!(
            ua(&|a| a.upper_arm_flexion = flexion),
            expected,
            "upper arm {flexion}"
        );
    }
    // Abducted or raised by anything at all: +1 (Stance's default waits for 20 and 10).
    assert_eq!(ua(&|a| a.upper_arm_abduction = 0.0), 1);
    assert_eq!(ua(&|a| a.upper_arm_abduction = 0.001), 2);
    assert_eq!(
        ua(&|a| a.upper_arm_abduction = -5.0),
        1,
        "adduction adds nothing"
    );
    assert_eq!(ua(&|a| a.shoulder_elevation = Some(0.0)), 1);
    assert_eq!(ua(&|a| a.shoulder_elevation = Some(0.001)), 2);
    let la = |e: f64| arm(&|a| a.elbow_flexion = e)[1];
    assert_eq!([la(60.0), la(60.001), la(100.0), la(100.001)], [2, 1, 1, 2]);
    let wr = |w: f64| arm(&|a| a.wrist_flexion = w)[2];
    assert_eq!(
        [
            wr(0.0),
            wr(0.001),
            wr(-0.001),
            wr(15.0),
            wr(-15.0),
            wr(15.001)
        ],
        [1, 2, 2, 2, 2, 3]
    );
    assert_eq!(arm(&|a| a.wrist_deviation = 0.001)[2], 2, "deviated: +1");
    assert_eq!(arm(&|a| a.wrist_deviation = -0.001)[2], 2, "ulnar too");
    let body = |f: &dyn Fn(&mut RulaAngles)| {
        let mut angles = RulaAngles::default();
        f(&mut angles);
        let b = score(&angles, &AS_PRINTED).body;
        [b.neck, b.trunk]
    };
    let neck = |n: f64| body(&|a| a.neck_flexion = n)[0];
    assert_eq!(
        [
            neck(-0.001),
            neck(0.0),
            neck(10.0),
            neck(10.001),
            neck(20.0),
            neck(20.001)
        ],
        [4, 1, 1, 2, 2, 3]
    );
    assert_eq!(body(&|a| a.neck_twist = 0.001)[0], 2);
    assert_eq!(body(&|a| a.neck_side_bend = -0.001)[0], 2);
    let trunk = |t: f64| body(&|a| a.trunk_flexion = t)[1];
    // Trunk extension has no rule in the paper: Stance scores it as the first flexed band.
    assert_eq!(
        [
            trunk(0.0),
            trunk(0.001),
            trunk(-0.001),
            trunk(20.0),
            trunk(20.001),
            trunk(60.0),
            trunk(60.001)
        ],
        [1, 2, 2, 2, 3, 3, 4]
    );
    assert_eq!(body(&|a| a.trunk_twist = 0.001)[1], 2);
    assert_eq!(body(&|a| a.trunk_side_bend = -0.001)[1], 2);
    // The default keeps Stance's tolerances: the same small angles score neutral.
    assert_eq!(RulaSettings::default().tolerances, RulaTolerances::STANCE);
    let mut small = RulaAngles::default();
    small.left.upper_arm_abduction = 3.0;
    small.left.shoulder_elevation = Some(3.0);
    small.left.wrist_flexion = 3.0;
    small.left.wrist_deviation = 3.0;
    small.neck_flexion = -3.0;
    small.neck_twist = 3.0;
    small.trunk_flexion = 3.0;
    small.trunk_side_bend = 3.0;
    let stance = score(&small, &RulaSettings::default());
    let printed = score(&small, &AS_PRINTED);
    let parts = |r: &RulaReport| [r.left.upper_arm, r.left.wrist, r.body.neck, r.body.trunk];
    // Printed: upper arm 1 + abducted + raised = 3; wrist 2 + deviated = 3; neck extension 4
    // + twisted = 5; trunk 2 + side-bent = 3.
    assert_eq!(parts(&stance), [1, 1, 1, 1]);
    assert_eq!(parts(&printed), [3, 3, 5, 3]);
}

#[test]
fn paper_as_printed_gives_a_hand_computed_grand_score() {
    // Catches tolerances that reach the part scores but not Tables A, B and C (or the other
    // way round), with every part off neutral by less than Stance's tolerances.
    //
    // Angles: upper arm 30 flexion, 5 abduction; elbow 80; wrist 10 flexion, 3 deviation,
    // twist 1; neck 5 flexion, 2 twist; trunk 10 flexion, 1 side-bend; legs supported.
    // As printed: upper arm 2 (20-45) + 1 (abducted) = 3; lower arm 1 (60-100); wrist
    // 2 (0-15) + 1 (deviated) = 3. Table A (UA 3, LA 1, wrist 3, twist 1) = 4 (row "3 1":
    // 3 3 4 4 [4] 4 5 5). Neck 1 (0-10) + 1 (twisted) = 2; trunk 2 (0-20) + 1 (side-bent) =
    // 3; legs 1. Table B (neck 2, trunk 3, legs 1) = 4 (row 2: 2 3 2 3 [4] 5 ...). No muscle
    // use or load: C = 4, D = 4; Table C (4, 4) = 4 (row 4: 3 3 3 [4] 5 6 6); action level 2.
    // With Stance's tolerances: upper arm 2, wrist 2, Table A (2, 1, 2, 1) = 3; neck 1,
    // trunk 2, Table B (1, 2, 1) = 2; Table C (3, 2) = 3.
    let mut angles = RulaAngles::default();
    for arm in [&mut angles.left, &mut angles.right] {
        arm.upper_arm_flexion = 30.0;
        arm.upper_arm_abduction = 5.0;
        arm.elbow_flexion = 80.0;
        arm.wrist_flexion = 10.0;
        arm.wrist_deviation = 3.0;
    }
    angles.neck_flexion = 5.0;
    angles.neck_twist = 2.0;
    angles.trunk_flexion = 10.0;
    angles.trunk_side_bend = 1.0;
    let printed = score(&angles, &AS_PRINTED);
    let arm = |a: &RulaArm| {
        [
            a.upper_arm,
            a.lower_arm,
            a.wrist,
            a.wrist_twist,
            a.posture_a,
        ]
    };
    assert_eq!(arm(&printed.left), [3, 1, 3, 1, 4]);
    assert_eq!(arm(&printed.right), [3, 1, 3, 1, 4]);
    let b = printed.body;
    assert_eq!([b.neck, b.trunk, b.legs, b.posture_b], [2, 3, 1, 4]);
    assert_eq!((printed.left.score_c, b.score_d), (4, 4));
    assert_eq!((printed.score, printed.action_level), (4, 2));
    let stance = score(&angles, &PAPER);
    assert_eq!(arm(&stance.left), [2, 1, 2, 1, 3]);
    assert_eq!(
        [stance.body.neck, stance.body.trunk, stance.body.posture_b],
        [1, 2, 2]
    );
    assert_eq!((stance.score, stance.action_level), (3, 2));
}

#[test]
fn paper_as_printed_scores_a_measured_arm_raised_forward_and_out() {
    // Catches an upper arm whose flexion and abduction are not read as the paper's two
    // separate things (flexion in the sagittal plane, abduction out of it), and an abduction
    // threshold that is not 0 as printed.
    //
    // Hand computation: the left shoulder (LOA 1, H-Anim rest frames) turned 60 deg about the
    // horizontal axis k = (-cos 15, 0, sin 15): rotation vector 60 k = (-57.9555, 0, 15.5291)
    // deg. The arm's rest direction d = (0, -1, 0) goes to
    // d cos 60 + (k x d) sin 60 = (sin 15 sin 60, -cos 60, cos 15 sin 60)
    //   = (0.25882 * 0.86603, -0.5, 0.96593 * 0.86603) = (0.22414, -0.5, 0.83652).
    // Abduction, the angle out of the sagittal plane: asin(0.22414) = 12.953 deg.
    // Flexion, the sagittal projection (0, -0.5, 0.83652) from down: atan2(0.83652, 0.5) =
    // 59.133 deg.
    // As printed: 45 < 59.133 <= 90 -> 3, abducted (12.953 > 0) -> +1: 4. Stance's default
    // (abduction beyond 20) and the worksheet's (beyond 15): 3.
    let s = body(LevelOfArticulation::Loa1);
    let (sin, cos) = 15f64.to_radians().sin_cos();
    let angles = measured(
        &s,
        &[
            ("l_shoulder", Rx, -60.0 * cos),
            ("l_shoulder", Rz, 60.0 * sin),
        ],
    );
    let a = angles.left;
    assert!((a.upper_arm_abduction - 12.953).abs() < 1e-3, "{a:?}");
    assert!((a.upper_arm_flexion - 59.133).abs() < 1e-3, "{a:?}");
    assert_eq!(score(&angles, &AS_PRINTED).left.upper_arm, 4);
    assert_eq!(score(&angles, &PAPER).left.upper_arm, 3);
    assert_eq!(score(&angles, &WORKSHEET).left.upper_arm, 3);
}

// ---------------------------------------------------------------------------------------------
// Postures on the default body.

fn body(loa: LevelOfArticulation) -> Skeleton {
    default_skeleton(&SkeletonOptions {
        loa,
        ..Default::default()
    })
    .unwrap()
    .skeleton
}

/// A posture with the given rotation DOF set (degrees).
fn posture(skeleton: &Skeleton, moves: &[(&str, Dof, f64)]) -> Posture {
    let mut p = Posture::rest(skeleton);
    for &(name, dof, degrees) in moves {
        let j = skeleton
            .joint_index(name)
            .unwrap_or_else(|| panic!("no joint {name}"));
        let d = skeleton.joints()[j].rotation_dof[dof.axis_index()]
            .unwrap_or_else(|| panic!("{name} has no {dof:?}"));
        p.values_mut()[d] = degrees.to_radians();
    }
    p
}

fn measured(skeleton: &Skeleton, moves: &[(&str, Dof, f64)]) -> RulaAngles {
    let frames = Frames::new(skeleton, &posture(skeleton, moves));
    measure(skeleton, &frames).unwrap()
}

use Dof::{Rx, Ry, Rz};

/// An arm's expected `[upper arm, lower arm, wrist, wrist twist]`.
type ArmScores = [u8; 4];
/// The expected `[neck, trunk, legs]`.
type BodyScores = [u8; 3];

/// The neutral arm: upper arm 1, a straight elbow (below 60 degrees) 2, wrist 1, twist 1.
const ARM: ArmScores = [1, 2, 1, 1];
/// Neck 1, upright trunk 1, legs 1.
const BODY: BodyScores = [1, 1, 1];

const PAPER: RulaSettings = RulaSettings {
    variant: RulaVariant::Paper,
    tolerances: RulaTolerances::STANCE,
    muscle_use: false,
    load: RulaLoad::None,
    arm_supported: false,
    legs_supported: None,
    seated_supported: false,
};
const WORKSHEET: RulaSettings = RulaSettings {
    variant: RulaVariant::Worksheet,
    ..PAPER
};
const SEATED: RulaSettings = RulaSettings {
    seated_supported: true,
    ..PAPER
};
const SUPPORTED_ARMS: RulaSettings = RulaSettings {
    arm_supported: true,
    ..PAPER
};
const LEGS_SUPPORTED: RulaSettings = RulaSettings {
    legs_supported: Some(true),
    ..PAPER
};
const LEGS_UNSUPPORTED: RulaSettings = RulaSettings {
    legs_supported: Some(false),
    ..PAPER
};

/// One posture and its expected part scores, worked out by hand from the paper's rules with
/// Stance's tolerances (a wrist, neck or trunk within 5 degrees is neutral, twist and
/// side-bend count beyond 10; see the module documentation; edges belong to the lower band).
/// The paper as printed, without them: `paper_as_printed_*` below. Left arm: shoulder flexion is
/// `-rx`, abduction `+rz`, elbow flexion `-rx`, forearm rotation `ry`, wrist flexion `-rz`,
/// deviation `rx`; the right arm mirrors `ry` and `rz`. Neck and spine flexion is `+rx`.
struct Case {
    name: &'static str,
    loa: u8,
    settings: RulaSettings,
    moves: &'static [(&'static str, Dof, f64)],
    left: ArmScores,
    right: ArmScores,
    body: BodyScores,
}

const fn case(
    name: &'static str,
    moves: &'static [(&'static str, Dof, f64)],
    left: ArmScores,
    body: BodyScores,
) -> Case {
    Case {
        name,
        loa: 1,
        settings: PAPER,
        moves,
        left,
        right: ARM,
        body,
    }
}

const fn with(mut c: Case, settings: RulaSettings) -> Case {
    c.settings = settings;
    c
}

const fn loa2(mut c: Case) -> Case {
    c.loa = 2;
    c
}

const fn right(mut c: Case, right: ArmScores) -> Case {
    c.right = right;
    c
}

const CASES: &[Case] = &[
    case("rest", &[], ARM, BODY),
    // Upper arm, paper edges 20/45/90 (flexion), 20 (extension).
    case("flexion 19.5", &[("l_shoulder", Rx, -19.5)], ARM, BODY),
    case(
        "flexion 20.5",
        &[("l_shoulder", Rx, -20.5)],
        [2, 2, 1, 1],
        BODY,
    ),
    case(
        "flexion 44.5",
        &[("l_shoulder", Rx, -44.5)],
        [2, 2, 1, 1],
        BODY,
    ),
    case(
        "flexion 45.5",
        &[("l_shoulder", Rx, -45.5)],
        [3, 2, 1, 1],
        BODY,
    ),
    case(
        "flexion 89.5",
        &[("l_shoulder", Rx, -89.5)],
        [3, 2, 1, 1],
        BODY,
    ),
    case(
        "flexion 90.5",
        &[("l_shoulder", Rx, -90.5)],
        [4, 2, 1, 1],
        BODY,
    ),
    case(
        "flexion 150",
        &[("l_shoulder", Rx, -150.0)],
        [4, 2, 1, 1],
        BODY,
    ),
    case("extension 19.5", &[("l_shoulder", Rx, 19.5)], ARM, BODY),
    case(
        "extension 20.5",
        &[("l_shoulder", Rx, 20.5)],
        [2, 2, 1, 1],
        BODY,
    ),
    right(
        case(
            "right flexion 45.5",
            &[("r_shoulder", Rx, -45.5)],
            ARM,
            BODY,
        ),
        [3, 2, 1, 1],
    ),
    // Worksheet edges 15/45/90.
    with(
        case("ws flexion 14.5", &[("l_shoulder", Rx, -14.5)], ARM, BODY),
        WORKSHEET,
    ),
    with(
        case(
            "ws flexion 15.5",
            &[("l_shoulder", Rx, -15.5)],
            [2, 2, 1, 1],
            BODY,
        ),
        WORKSHEET,
    ),
    case(
        "paper flexion 15.5",
        &[("l_shoulder", Rx, -15.5)],
        ARM,
        BODY,
    ),
    with(
        case(
            "ws flexion 44.5",
            &[("l_shoulder", Rx, -44.5)],
            [2, 2, 1, 1],
            BODY,
        ),
        WORKSHEET,
    ),
    with(
        case(
            "ws flexion 45.5",
            &[("l_shoulder", Rx, -45.5)],
            [3, 2, 1, 1],
            BODY,
        ),
        WORKSHEET,
    ),
    with(
        case(
            "ws flexion 89.5",
            &[("l_shoulder", Rx, -89.5)],
            [3, 2, 1, 1],
            BODY,
        ),
        WORKSHEET,
    ),
    with(
        case(
            "ws flexion 90.5",
            &[("l_shoulder", Rx, -90.5)],
            [4, 2, 1, 1],
            BODY,
        ),
        WORKSHEET,
    ),
    with(
        case("ws extension 14.5", &[("l_shoulder", Rx, 14.5)], ARM, BODY),
        WORKSHEET,
    ),
    with(
        case(
            "ws extension 15.5",
            &[("l_shoulder", Rx, 15.5)],
            [2, 2, 1, 1],
            BODY,
        ),
        WORKSHEET,
    ),
    // Abduction beyond the neutral edge: +1 (elbow at 90 keeps the hand near the body: lower
    // arm 1).
    case(
        "abduction 19.5",
        &[("l_shoulder", Rz, 19.5), ("l_elbow", Rx, -90.0)],
        [1, 1, 1, 1],
        BODY,
    ),
    case(
        "abduction 20.5",
        &[("l_shoulder", Rz, 20.5), ("l_elbow", Rx, -90.0)],
        [2, 1, 1, 1],
        BODY,
    ),
    with(
        case(
            "ws abduction 15.5",
            &[("l_shoulder", Rz, 15.5), ("l_elbow", Rx, -90.0)],
            [2, 1, 1, 1],
            BODY,
        ),
        WORKSHEET,
    ),
    right(
        case(
            "right abduction 20.5",
            &[("r_shoulder", Rz, -20.5), ("r_elbow", Rx, -90.0)],
            ARM,
            BODY,
        ),
        [2, 1, 1, 1],
    ),
    with(
        case(
            "arm supported",
            &[("l_shoulder", Rx, -50.0)],
            [2, 2, 1, 1],
            BODY,
        ),
        SUPPORTED_ARMS,
    ),
    // Lower arm: 1 for more than 60 up to 100 degrees.
    case("elbow 59.5", &[("l_elbow", Rx, -59.5)], ARM, BODY),
    case("elbow 60.5", &[("l_elbow", Rx, -60.5)], [1, 1, 1, 1], BODY),
    case("elbow 99.5", &[("l_elbow", Rx, -99.5)], [1, 1, 1, 1], BODY),
    case("elbow 100.5", &[("l_elbow", Rx, -100.5)], ARM, BODY),
    right(
        case("right elbow 80", &[("r_elbow", Rx, -80.0)], ARM, BODY),
        [1, 1, 1, 1],
    ),
    // Across the midline / out to the side: +1.
    case(
        "across the midline",
        &[("l_shoulder", Ry, -80.0), ("l_elbow", Rx, -90.0)],
        [1, 2, 1, 1],
        BODY,
    ),
    case(
        "out to the side",
        &[("l_shoulder", Ry, 80.0), ("l_elbow", Rx, -90.0)],
        [1, 2, 1, 1],
        BODY,
    ),
    // Wrist: neutral up to 5 degrees, 2 up to 15, 3 beyond; deviation beyond 5: +1.
    case(
        "wrist flexion 4.5",
        &[("l_radiocarpal", Rz, -4.5)],
        ARM,
        BODY,
    ),
    case(
        "wrist flexion 5.5",
        &[("l_radiocarpal", Rz, -5.5)],
        [1, 2, 2, 1],
        BODY,
    ),
    case(
        "wrist flexion 14.5",
        &[("l_radiocarpal", Rz, -14.5)],
        [1, 2, 2, 1],
        BODY,
    ),
    case(
        "wrist flexion 15.5",
        &[("l_radiocarpal", Rz, -15.5)],
        [1, 2, 3, 1],
        BODY,
    ),
    case(
        "wrist extension 15.5",
        &[("l_radiocarpal", Rz, 15.5)],
        [1, 2, 3, 1],
        BODY,
    ),
    case(
        "wrist deviation 4.5",
        &[("l_radiocarpal", Rx, 4.5)],
        ARM,
        BODY,
    ),
    case(
        "wrist deviation 5.5",
        &[("l_radiocarpal", Rx, 5.5)],
        [1, 2, 2, 1],
        BODY,
    ),
    right(
        case(
            "right wrist flexion 15.5",
            &[("r_radiocarpal", Rz, 15.5)],
            ARM,
            BODY,
        ),
        [1, 2, 3, 1],
    ),
    // Wrist twist: the outer quarter of the -80..80 forearm range (beyond 40).
    case("forearm 39.5", &[("l_elbow", Ry, 39.5)], ARM, BODY),
    case("forearm 40.5", &[("l_elbow", Ry, 40.5)], [1, 2, 1, 2], BODY),
    case(
        "forearm -40.5",
        &[("l_elbow", Ry, -40.5)],
        [1, 2, 1, 2],
        BODY,
    ),
    // Neck: 1 up to 10, 2 up to 20, 3 beyond, 4 in extension (beyond 5); twist, side-bend.
    case("neck 9.5", &[("skullbase", Rx, 9.5)], ARM, BODY),
    case("neck 10.5", &[("skullbase", Rx, 10.5)], ARM, [2, 1, 1]),
    case("neck 19.5", &[("skullbase", Rx, 19.5)], ARM, [2, 1, 1]),
    case("neck 20.5", &[("skullbase", Rx, 20.5)], ARM, [3, 1, 1]),
    case("neck extension 4.5", &[("skullbase", Rx, -4.5)], ARM, BODY),
    case(
        "neck extension 5.5",
        &[("skullbase", Rx, -5.5)],
        ARM,
        [4, 1, 1],
    ),
    case("neck twist 9.5", &[("skullbase", Ry, 9.5)], ARM, BODY),
    case(
        "neck twist 10.5",
        &[("skullbase", Ry, 10.5)],
        ARM,
        [2, 1, 1],
    ),
    case("neck side-bend 9.5", &[("skullbase", Rz, -9.5)], ARM, BODY),
    case(
        "neck side-bend 10.5",
        &[("skullbase", Rz, -10.5)],
        ARM,
        [2, 1, 1],
    ),
    case(
        "neck flexed, twisted, bent",
        &[
            ("skullbase", Rx, 25.0),
            ("skullbase", Ry, 15.0),
            ("skullbase", Rz, 15.0),
        ],
        ARM,
        [5, 1, 1],
    ),
    // Trunk: upright within 5 degrees 1, 2 up to 20, 3 up to 60, 4 beyond; extension 2.
    case("trunk 4.5", &[("vl5", Rx, 4.5)], ARM, BODY),
    case("trunk 5.5", &[("vl5", Rx, 5.5)], ARM, [1, 2, 1]),
    case("trunk 19.5", &[("vl5", Rx, 19.5)], ARM, [1, 2, 1]),
    case("trunk 20.5", &[("vl5", Rx, 20.5)], ARM, [1, 3, 1]),
    case("trunk 59.5", &[("vl5", Rx, 59.5)], ARM, [1, 3, 1]),
    case("trunk 60.5", &[("vl5", Rx, 60.5)], ARM, [1, 4, 1]),
    case("trunk extension 4.5", &[("vl5", Rx, -4.5)], ARM, BODY),
    case("trunk extension 5.5", &[("vl5", Rx, -5.5)], ARM, [1, 2, 1]),
    case(
        "whole body pitched 30",
        &[("humanoid_root", Rx, 30.0)],
        ARM,
        [1, 3, 1],
    ),
    case("trunk twist 9.5", &[("vl5", Ry, 9.5)], ARM, BODY),
    case("trunk twist 10.5", &[("vl5", Ry, 10.5)], ARM, [1, 2, 1]),
    case("trunk side-bend 9.5", &[("vl5", Rz, 9.5)], ARM, BODY),
    case("trunk side-bend 10.5", &[("vl5", Rz, 10.5)], ARM, [1, 2, 1]),
    with(
        case("seated trunk 15", &[("vl5", Rx, 15.0)], ARM, BODY),
        SEATED,
    ),
    with(
        case("seated trunk -10", &[("vl5", Rx, -10.0)], ARM, BODY),
        SEATED,
    ),
    with(
        case("seated trunk 20.5", &[("vl5", Rx, 20.5)], ARM, [1, 3, 1]),
        SEATED,
    ),
    // Legs: a lifted foot, or the weight off to one side: 2; overrides.
    case("left foot lifted", &[("l_hip", Rx, -30.0)], ARM, [1, 1, 2]),
    case(
        "leaning far to the right",
        &[("vl5", Rz, 40.0)],
        ARM,
        [1, 2, 2],
    ),
    with(
        case("legs said supported", &[("l_hip", Rx, -30.0)], ARM, BODY),
        LEGS_SUPPORTED,
    ),
    with(
        case("legs said unsupported", &[], ARM, [1, 1, 2]),
        LEGS_UNSUPPORTED,
    ),
    // LOA 2: a fuller spine and neck, clavicles, hands with knuckles.
    loa2(case("loa2 rest", &[], ARM, BODY)),
    loa2(case(
        "loa2 shoulder raised 9.5",
        &[("l_sternoclavicular", Rz, 9.5)],
        ARM,
        BODY,
    )),
    loa2(case(
        "loa2 shoulder raised 10.5",
        &[("l_sternoclavicular", Rz, 10.5)],
        [2, 2, 1, 1],
        BODY,
    )),
    loa2(right(
        case(
            "loa2 right shoulder raised 10.5",
            &[("r_sternoclavicular", Rz, -10.5)],
            ARM,
            BODY,
        ),
        [2, 2, 1, 1],
    )),
    loa2(case(
        "loa2 flexion 45.5",
        &[("l_shoulder", Rx, -45.5)],
        [3, 2, 1, 1],
        BODY,
    )),
    loa2(case(
        "loa2 wrist flexion 14.5",
        &[("l_radiocarpal", Rz, -14.5)],
        [1, 2, 2, 1],
        BODY,
    )),
    loa2(case(
        "loa2 wrist flexion 15.5",
        &[("l_radiocarpal", Rz, -15.5)],
        [1, 2, 3, 1],
        BODY,
    )),
    loa2(case(
        "loa2 neck 20.5",
        &[("skullbase", Rx, 20.5)],
        ARM,
        [3, 1, 1],
    )),
    loa2(case(
        "loa2 trunk 20.5",
        &[("vl5", Rx, 20.5)],
        ARM,
        [1, 3, 1],
    )),
];

#[test]
fn postures_score_their_parts_by_the_paper_with_stances_tolerances() {
    assert!(CASES.len() >= 40, "{} postures", CASES.len());
    let loa1 = body(LevelOfArticulation::Loa1);
    let loa2 = body(LevelOfArticulation::Loa2);
    let mut failures = Vec::new();
    for c in CASES {
        let skeleton = if c.loa == 1 { &loa1 } else { &loa2 };
        let angles = measured(skeleton, c.moves);
        let report = score(&angles, &c.settings);
        let arm = |a: &RulaArm| [a.upper_arm, a.lower_arm, a.wrist, a.wrist_twist];
        let got = (
            arm(&report.left),
            arm(&report.right),
            [report.body.neck, report.body.trunk, report.body.legs],
        );
        if got != (c.left, c.right, c.body) {
            failures.push(format!(
                "{}: got {got:?}, expected {:?}\n  {angles:?}",
                c.name,
                (c.left, c.right, c.body)
            ));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

// ---------------------------------------------------------------------------------------------
// Measurement.

#[test]
fn the_rest_posture_is_neutral_at_every_level() {
    for loa in LevelOfArticulation::ALL {
        let skeleton = body(loa);
        let a = measured(&skeleton, &[]);
        for arm in [&a.left, &a.right] {
            for (what, v) in [
                ("upper arm flexion", arm.upper_arm_flexion),
                ("abduction", arm.upper_arm_abduction),
                ("elbow", arm.elbow_flexion),
                ("wrist flexion", arm.wrist_flexion),
                ("wrist deviation", arm.wrist_deviation),
                ("forearm", arm.forearm_rotation.unwrap()),
                ("clavicle", arm.shoulder_elevation.unwrap_or_default()),
            ] {
                assert!(v.abs() < 1e-6, "{loa:?} {what}: {v}");
            }
            assert_eq!(
                arm.shoulder_elevation.is_some(),
                loa != LevelOfArticulation::Loa1
            );
            assert!(!arm.across_midline && !arm.out_to_side, "{loa:?}");
            assert_eq!(arm.wrist_twist, 1);
        }
        for (what, v) in [
            ("neck flexion", a.neck_flexion),
            ("neck twist", a.neck_twist),
            ("neck side", a.neck_side_bend),
            ("trunk flexion", a.trunk_flexion),
            ("trunk twist", a.trunk_twist),
            ("trunk side", a.trunk_side_bend),
        ] {
            assert!(v.abs() < 1e-6, "{loa:?} {what}: {v}");
        }
        assert!(a.weight_balanced, "{loa:?}");
        let report = rula(
            &skeleton,
            &Frames::new(&skeleton, &Posture::rest(&skeleton)),
            &RulaSettings::default(),
        )
        .unwrap();
        assert_eq!((report.score, report.action_level), (2, 1), "{loa:?}");
    }
}

#[test]
fn known_rotations_measure_as_set() {
    let close = |got: f64, want: f64, what: &str| {
        assert!((got - want).abs() < 0.5, "{what}: {got}, expected {want}");
    };
    for loa in [LevelOfArticulation::Loa1, LevelOfArticulation::Loa2] {
        let s = body(loa);
        let m = |moves: &[(&str, Dof, f64)]| measured(&s, moves);
        close(
            m(&[("l_shoulder", Rx, -50.0)]).left.upper_arm_flexion,
            50.0,
            "l flexion",
        );
        close(
            m(&[("r_shoulder", Rx, -50.0)]).right.upper_arm_flexion,
            50.0,
            "r flexion",
        );
        close(
            m(&[("l_shoulder", Rx, 30.0)]).left.upper_arm_flexion,
            -30.0,
            "extension",
        );
        close(
            m(&[("l_shoulder", Rz, 30.0)]).left.upper_arm_abduction,
            30.0,
            "l abduction",
        );
        close(
            m(&[("r_shoulder", Rz, -30.0)]).right.upper_arm_abduction,
            30.0,
            "r abduction",
        );
        close(
            m(&[("l_shoulder", Rz, -20.0)]).left.upper_arm_abduction,
            -20.0,
            "adduction",
        );
        close(
            m(&[("l_shoulder", Rz, 30.0)]).left.upper_arm_flexion,
            0.0,
            "abducted, flexion",
        );
        // Raised sideways above the shoulder: past 90, not extension.
        assert!(m(&[("l_shoulder", Rz, 130.0)]).left.upper_arm_flexion > 90.0);
        close(
            m(&[("l_elbow", Rx, -50.0)]).left.elbow_flexion,
            50.0,
            "elbow",
        );
        close(
            m(&[("l_radiocarpal", Rz, -20.0)]).left.wrist_flexion,
            20.0,
            "l wrist",
        );
        close(
            m(&[("l_radiocarpal", Rz, 20.0)]).left.wrist_flexion,
            -20.0,
            "l wrist ext",
        );
        close(
            m(&[("r_radiocarpal", Rz, 20.0)]).right.wrist_flexion,
            20.0,
            "r wrist",
        );
        close(
            m(&[("l_radiocarpal", Rx, -12.0)]).left.wrist_deviation,
            12.0,
            "deviation",
        );
        close(
            m(&[("l_elbow", Ry, 30.0)]).left.forearm_rotation.unwrap(),
            -30.0,
            "supination",
        );
        close(
            m(&[("r_elbow", Ry, 30.0)]).right.forearm_rotation.unwrap(),
            30.0,
            "pronation",
        );
        close(m(&[("skullbase", Rx, 15.0)]).neck_flexion, 15.0, "neck");
        close(
            m(&[("skullbase", Rx, -15.0)]).neck_flexion,
            -15.0,
            "neck extension",
        );
        close(m(&[("skullbase", Ry, 25.0)]).neck_twist, 25.0, "neck twist");
        close(
            m(&[("skullbase", Rz, -25.0)]).neck_side_bend,
            25.0,
            "neck side-bend",
        );
        close(m(&[("vl5", Rx, 30.0)]).trunk_flexion, 30.0, "trunk");
        close(m(&[("vl5", Ry, 25.0)]).trunk_twist, 25.0, "trunk twist");
        close(
            m(&[("vl5", Rz, 25.0)]).trunk_side_bend,
            -25.0,
            "trunk side-bend",
        );
        // The trunk leans, the arm hangs with it: no arm flexion relative to the trunk.
        let leaning = m(&[("vl5", Rx, 30.0)]);
        close(
            leaning.left.upper_arm_flexion,
            0.0,
            "arm in a leaning trunk",
        );
        close(leaning.neck_flexion, 0.0, "neck in a leaning trunk");
        // Pelvis and trunk turned together: no twist.
        close(
            m(&[("humanoid_root", Ry, 40.0)]).trunk_twist,
            0.0,
            "whole body turned",
        );
    }
    let s = body(LevelOfArticulation::Loa2);
    let raised = measured(&s, &[("l_sternoclavicular", Rz, 12.0)]);
    close(raised.left.shoulder_elevation.unwrap(), 12.0, "clavicle");
    close(
        raised.right.shoulder_elevation.unwrap(),
        0.0,
        "other clavicle",
    );
    // A hand rotated with its knuckles (LOA 2): the wrist's rotation, not the knuckle's.
    close(
        measured(&s, &[("l_radiocarpal", Rz, -30.0)])
            .left
            .wrist_flexion,
        30.0,
        "loa2 wrist",
    );
}

#[test]
fn a_skeleton_without_the_joints_rula_needs_is_not_measured() {
    let skeleton = Skeleton::new(vec![
        JointDef::new("humanoid_root", None, DVec3::ZERO, &[Rx]),
        JointDef::new("l_shoulder", Some("humanoid_root"), DVec3::Y, &[Rx]),
    ])
    .unwrap();
    let frames = Frames::new(&skeleton, &Posture::rest(&skeleton));
    assert!(measure(&skeleton, &frames).is_none());
    assert!(rula(&skeleton, &frames, &RulaSettings::default()).is_none());
    assert!(rula_bands(&skeleton, RulaVariant::Paper).is_empty());
    // Frames of another skeleton.
    let loa1 = body(LevelOfArticulation::Loa1);
    assert!(measure(&loa1, &frames).is_none());
}

// ---------------------------------------------------------------------------------------------
// The smooth stand-in.

fn band_cost(skeleton: &Skeleton, band: &AngleBand, moves: &[(&str, Dof, f64)]) -> f64 {
    let p = posture(skeleton, moves);
    let model = ComfortModel {
        band_weight: 1.0,
        bands: vec![band.clone()],
        ..Default::default()
    };
    model
        .terms(skeleton, &Frames::new(skeleton, &p), p.values())
        .bands
}

/// The costs of `band` along a sweep of one DOF over `degrees` (as set), and a check that
/// they rise (`rising`) or fall between consecutive samples.
fn sweep(
    skeleton: &Skeleton,
    band: &AngleBand,
    joint: &str,
    dof: Dof,
    degrees: impl Iterator<Item = f64>,
    rising: bool,
) {
    let mut last: Option<(f64, f64)> = None;
    for q in degrees {
        let cost = band_cost(skeleton, band, &[(joint, dof, q)]);
        if let Some((q0, c0)) = last {
            let ok = if rising {
                cost >= c0 - 1e-12
            } else {
                cost <= c0 + 1e-12
            };
            assert!(ok, "{}: {q0} -> {q}: {c0} -> {cost}", band.name);
        }
        last = Some((q, cost));
    }
}

fn steps(from: f64, to: f64) -> impl Iterator<Item = f64> {
    let n = ((to - from).abs() / 0.5).round() as i32;
    (0..=n).map(move |k| from + (to - from) * f64::from(k) / f64::from(n))
}

fn find<'a>(bands: &'a [AngleBand], name: &str) -> &'a AngleBand {
    bands
        .iter()
        .find(|b| b.name == name)
        .unwrap_or_else(|| panic!("no band {name}"))
}

#[test]
fn bands_are_well_formed_at_every_level() {
    for loa in LevelOfArticulation::ALL {
        let skeleton = body(loa);
        let bands = rula_bands(&skeleton, RulaVariant::Paper);
        let names: Vec<&str> = bands.iter().map(|b| b.name.as_str()).collect();
        assert_eq!(
            names,
            [
                "l_upper_arm",
                "l_lower_arm",
                "l_wrist",
                "r_upper_arm",
                "r_lower_arm",
                "r_wrist",
                "neck",
                "neck_extension",
                "trunk"
            ]
        );
        let model = ComfortModel {
            band_weight: 1.0,
            bands,
            ..Default::default()
        };
        model.validate(&skeleton).unwrap();
    }
}

#[test]
fn band_costs_rise_through_each_edge() {
    let s = body(LevelOfArticulation::Loa1);
    for (variant, first) in [(RulaVariant::Paper, 20.0), (RulaVariant::Worksheet, 15.0)] {
        let bands = rula_bands(&s, variant);
        // Upper arm: flexion 0 to 130, each edge a step of about 1.
        let upper = find(&bands, "l_upper_arm");
        sweep(&s, upper, "l_shoulder", Rx, steps(0.0, -130.0), true);
        for edge in [first, 45.0, 90.0] {
            let below = band_cost(&s, upper, &[("l_shoulder", Rx, -(edge - 9.0))]);
            let above = band_cost(&s, upper, &[("l_shoulder", Rx, -(edge + 9.0))]);
            assert!(
                above - below > 0.85,
                "{variant:?} edge {edge}: {below} {above}"
            );
        }
        // The right arm, and extension: the angle from the trunk axis, either way.
        let right = find(&bands, "r_upper_arm");
        sweep(&s, right, "r_shoulder", Rx, steps(0.0, -130.0), true);
        sweep(&s, upper, "l_shoulder", Rx, steps(0.0, 50.0), true);
    }
    let bands = rula_bands(&s, RulaVariant::Paper);
    // Lower arm: down through 60, up through 100.
    let lower = find(&bands, "l_lower_arm");
    sweep(&s, lower, "l_elbow", Rx, steps(0.0, -80.0), false);
    sweep(&s, lower, "l_elbow", Rx, steps(-80.0, -145.0), true);
    let at = |q: f64| band_cost(&s, lower, &[("l_elbow", Rx, -q)]);
    assert!(at(51.0) - at(69.0) > 0.85 && at(109.0) - at(91.0) > 0.85);
    // Wrist: flexion and extension, edges 5 and 15.
    let wrist = find(&bands, "l_wrist");
    sweep(&s, wrist, "l_radiocarpal", Rz, steps(0.0, -40.0), true);
    sweep(&s, wrist, "l_radiocarpal", Rz, steps(0.0, 40.0), true);
    let at = |q: f64| band_cost(&s, wrist, &[("l_radiocarpal", Rz, -q)]);
    assert!(at(24.0) - at(10.0) > 0.85 && at(10.0) - at(0.0) > 0.7);
    // Neck: flexion edges 10 and 20; extension steps by 3.
    let neck = find(&bands, "neck");
    sweep(&s, neck, "skullbase", Rx, steps(0.0, 45.0), true);
    let at = |q: f64| band_cost(&s, neck, &[("skullbase", Rx, q)]);
    // The edges are 10 degrees apart: each step is about 1 over its own +-5 degrees.
    assert!(at(15.0) - at(5.0) > 0.6 && at(25.0) - at(15.0) > 0.6);
    assert!(at(35.0) - at(0.0) > 1.9);
    let extension = find(&bands, "neck_extension");
    sweep(&s, extension, "skullbase", Rx, steps(0.0, -40.0), true);
    sweep(&s, extension, "skullbase", Rx, steps(0.0, 40.0), false);
    let at = |q: f64| band_cost(&s, extension, &[("skullbase", Rx, q)]);
    assert!(at(-15.0) - at(5.0) > 2.5);
    // Trunk: edges 5, 20 and 60 from vertical.
    let trunk = find(&bands, "trunk");
    sweep(&s, trunk, "vl5", Rx, steps(0.0, 90.0), true);
    let at = |q: f64| band_cost(&s, trunk, &[("vl5", Rx, q)]);
    assert!(at(12.0) - at(0.0) > 0.7);
    assert!(at(29.0) - at(11.0) > 0.85 && at(69.0) - at(51.0) > 0.85);
    // At LOA 2, the wrist band follows the hand (knuckles present) as well.
    let s2 = body(LevelOfArticulation::Loa2);
    let bands2 = rula_bands(&s2, RulaVariant::Paper);
    sweep(
        &s2,
        find(&bands2, "l_wrist"),
        "l_radiocarpal",
        Rz,
        steps(0.0, -40.0),
        true,
    );
    sweep(
        &s2,
        find(&bands2, "trunk"),
        "vl5",
        Rx,
        steps(0.0, 90.0),
        true,
    );
    // At rest the hand is at its neutral (angle 0): only the tails of the steps at 5 and 15.
    let tails = smooth(0.0, &[(5.0, 1.0), (15.0, 1.0)]);
    let rest = band_cost(&s2, find(&bands2, "l_wrist"), &[]);
    assert!((rest - tails).abs() < 1e-6, "{rest} {tails}");
}

/// A band's cost at `angle` (degrees) written out from its definition: per edge the logistic
/// step and, on the costly side, the ramp's softplus (width and ramp: the module's constants).
fn smooth(angle: f64, edges: &[(f64, f64)]) -> f64 {
    let logistic = |x: f64| 1.0 / (1.0 + (-x).exp());
    let softplus = |x: f64| (1.0 + x.exp()).ln();
    edges
        .iter()
        .map(|&(edge, step)| {
            let x = (angle - edge) / BAND_WIDTH_DEG;
            step * logistic(x) + BAND_RAMP * step.abs() * softplus(step.signum() * x)
        })
        .sum()
}

#[test]
fn bands_read_the_measured_angles() {
    // The upper-arm band's angle is the arm's angle from the trunk axis: at rest the cost is
    // the sum of the tails of its steps, nearly 0; at 45 degrees flexion it is half a step
    // more than 1.
    let s = body(LevelOfArticulation::Loa1);
    let bands = rula_bands(&s, RulaVariant::Paper);
    let upper = find(&bands, "l_upper_arm");
    let edges = [(20.0, 1.0), (45.0, 1.0), (90.0, 1.0)];
    let at_rest = band_cost(&s, upper, &[]);
    assert!((at_rest - smooth(0.0, &edges)).abs() < 1e-3, "{at_rest}");
    let at_45 = band_cost(&s, upper, &[("l_shoulder", Rx, -45.0)]);
    assert!((at_45 - smooth(45.0, &edges)).abs() < 0.01, "{at_45}");
    let lower = find(&bands, "l_lower_arm");
    let at_60 = band_cost(&s, lower, &[("l_elbow", Rx, -60.0)]);
    let expected = smooth(60.0, &[(60.0, -1.0), (100.0, 1.0)]);
    assert!((at_60 - expected).abs() < 0.01, "{at_60} {expected}");
}
