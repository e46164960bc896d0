//! The posing session's unit tests.

use super::*;
use stance_document::TaskKindSpec;

fn session() -> PosingSession {
    PosingSession::new(LevelOfArticulation::Loa2).unwrap()
}

/// Solves frames until the session settles and returns how many it took; panics, with the
/// last solve's report, when it has not within 200 (a test going on unsettled would check a
/// posture still on its way).
fn settle(session: &mut PosingSession) -> usize {
    const LIMIT: usize = 200;
    let mut frames = 0;
    while !session.is_settled() && frames < LIMIT {
        session.solve_frame(None);
        frames += 1;
    }
    assert!(
        session.is_settled(),
        "the session did not settle within {LIMIT} frames: {:?}",
        session.report()
    );
    frames
}

/// Grabs `joint` where it is and pulls it to `goal` over 30 frames, then lets the solver
/// settle (the grab still held); returns where the pull started.
fn pull_to(session: &mut PosingSession, joint: usize, goal: DVec3) -> DVec3 {
    let start = session.frames().joint_position[joint];
    session.begin_grab(joint, start);
    for step in 1..=30 {
        session.move_grab(start + (goal - start) * (f64::from(step) / 30.0));
        session.solve_frame(None);
    }
    settle(session);
    start
}

#[test]
fn the_default_body_stands_with_its_tasks_met() {
    let mut session = session();
    assert_eq!(session.tasks().len(), 4);
    settle(&mut session);
    for (task, status) in session.tasks().iter().zip(session.statuses()) {
        assert!(
            status.problem.is_none(),
            "{}: {:?}",
            task.description(),
            status.problem
        );
        assert!(
            status.gave_way.is_none(),
            "{}: {:?}",
            task.description(),
            status.gave_way
        );
    }
}

#[test]
fn pulling_a_hand_moves_it_while_the_feet_stay_pinned() {
    let mut session = session();
    let wrist = session.skeleton().joint_index("l_radiocarpal").unwrap();
    let feet_before = (
        session.joint_position("l_talocrural").unwrap(),
        session.joint_position("r_talocrural").unwrap(),
    );
    let goal = session.frames().joint_position[wrist] + DVec3::new(0.2, 0.35, 0.25);
    pull_to(&mut session, wrist, goal);
    let reached = session.grabbed_point_world().unwrap();
    assert!(
        (reached - goal).length() < 0.02,
        "the hand is {} m from the cursor",
        (reached - goal).length()
    );
    let feet_after = (
        session.joint_position("l_talocrural").unwrap(),
        session.joint_position("r_talocrural").unwrap(),
    );
    assert!((feet_after.0 - feet_before.0).length() < 1e-4);
    assert!((feet_after.1 - feet_before.1).length() < 1e-4);
    session.end_grab();
    assert!(session.grab().is_none());
}

/// Pulls the right hand 1.2 m ahead and 0.2 m up over 30 frames; returns the centre of
/// mass and how far ahead of the ankles it ends.
fn long_forward_pull(session: &mut PosingSession) -> DVec3 {
    let wrist = session.skeleton().joint_index("r_radiocarpal").unwrap();
    let goal = session.frames().joint_position[wrist] + DVec3::new(0.0, 0.2, 1.2);
    pull_to(session, wrist, goal);
    session.frames().center_of_mass()
}

#[test]
fn a_long_forward_pull_keeps_the_centre_of_mass_over_the_feet() {
    let mut session = session();
    let ankles_z = session
        .joint_position("l_talocrural")
        .unwrap()
        .z
        .max(session.joint_position("r_talocrural").unwrap().z);
    // The toes of the default body end about 16 cm ahead of its ankles.
    let toes_z = ankles_z + 0.16;
    let com = long_forward_pull(&mut session);
    assert!(com.z <= toes_z, "centre of mass {com} ahead of the toes");
    let balance = session
        .tasks()
        .iter()
        .position(|task| matches!(task.kind, TaskKindSpec::Balance { .. }))
        .unwrap();
    assert!(session.statuses()[balance].residual.unwrap() <= MET_TOLERANCE);
    // Without the balance task the same pull carries it past them.
    let mut free = self::session();
    let tasks: Vec<TaskSpec> = free
        .tasks()
        .iter()
        .filter(|task| !matches!(task.kind, TaskKindSpec::Balance { .. }))
        .cloned()
        .collect();
    free.set_tasks(tasks);
    let com = long_forward_pull(&mut free);
    assert!(com.z > toes_z + 0.05, "unbalanced: {com}");
}

/// One frame's solve (without a clock: the iteration budget alone) converges for a pull
/// step with the feet pinned and for the Table 1 example set on the standing body.
#[test]
fn a_pull_and_the_table1_example_converge_within_one_frame() {
    let mut session = session();
    let wrist = session.skeleton().joint_index("l_radiocarpal").unwrap();
    let start = session.frames().joint_position[wrist];
    session.begin_grab(wrist, start);
    let goal = start + DVec3::new(0.2, 0.35, 0.25);
    for step in 1..=30 {
        session.move_grab(start + (goal - start) * (f64::from(step) / 30.0));
        session.solve_frame(None);
        let report = session.report().unwrap();
        assert_eq!(report.status, SolveStatus::Converged, "pull step {step}");
    }
    let mut session = self::session();
    let tasks = crate::model::table1_example(&session);
    session.set_tasks(tasks);
    session.solve_frame(None);
    let report = session.report().unwrap();
    assert_eq!(report.status, SolveStatus::Converged, "{report:?}");
    assert!(report.iterations <= ITERATIONS_PER_FRAME);
    assert!(session.is_settled());
}

#[test]
fn an_unreachable_pull_gives_way_and_says_to_what() {
    let mut session = session();
    let wrist = session.skeleton().joint_index("l_radiocarpal").unwrap();
    let start = session.frames().joint_position[wrist];
    session.begin_grab(wrist, start);
    session.move_grab(start + DVec3::new(3.0, 0.0, 0.0));
    settle(&mut session);
    // The feet hold; the grab is the level that gave way.
    let report = session.report().unwrap();
    assert_eq!(report.gave_way, Some(3));
    for status in &session.statuses()[..2] {
        assert!(status.gave_way.is_none());
    }
}

/// The default body with one more task, `offset` from where `joint` is, at `level`;
/// settled. Returns the reason the new task gives.
fn reason_for_pull(session: &mut PosingSession, joint: &str, offset: DVec3, level: u32) -> String {
    let start = session.joint_position(joint).unwrap();
    let mut tasks = session.tasks().to_vec();
    let mut task = TaskSpec::pin(joint, (start + offset).to_array());
    task.level = level;
    tasks.push(task);
    session.set_tasks(tasks);
    settle(session);
    let status = session.statuses().last().unwrap();
    assert!(
        status.residual.unwrap() > 0.05,
        "the goal is not met: {:?} {:?}",
        status,
        session.contacts()
    );
    status.gave_way.clone().unwrap_or_default()
}

#[test]
fn a_hand_reaching_beyond_the_arm_is_out_of_reach_not_held_by_the_feet() {
    for offset in [DVec3::new(0.0, 2.0, 0.0), DVec3::new(0.0, 0.5, 1.5)] {
        let mut session = session();
        let reason = reason_for_pull(&mut session, "r_radiocarpal", offset, 3);
        // Straight up, the stiff trunk (default stiffness) leaves the arm raised against the
        // shoulder's limit: the limit is what stops it there, and the goal is out of reach.
        let expected: &[&str] = if offset.y > 1.0 {
            &["out of reach", "limited by joint limits"]
        } else {
            &["out of reach"]
        };
        assert!(
            expected.contains(&reason.as_str()),
            "hand pulled by {offset}: {reason}"
        );
        // The feet held meanwhile.
        for status in &session.statuses()[..3] {
            assert!(status.gave_way.is_none(), "{status:?}");
        }
    }
}

/// Catches a task stopped by the body's collision task reported "out of reach" (what it said
/// before: the solver's collision level has no row at a settled posture, where every pair is
/// clear of the margin): the right wrist pinned inside the chest (on the axis of the
/// collarbones' bar, between them) under the default tasks, the chest pinned and collision,
/// stops on the torso and gives way to collision, naming the right arm's part the pin moves and what it is
/// against.
#[test]
fn a_hand_pinned_inside_the_chest_gives_way_to_collision() {
    let mut session = session();
    // Collision on, and the chest held where it stands (it cannot lean away from the hand).
    let mut tasks = session.tasks().to_vec();
    crate::posing::collision_switched(&mut tasks, true);
    let skeleton = session.skeleton();
    let collarbone = skeleton.joint_index("l_sternoclavicular").unwrap();
    let chest_joint = skeleton.joints()[collarbone].parent.unwrap();
    let chest_name = skeleton.joints()[chest_joint].name.clone();
    let held = session.frames().joint_position[chest_joint];
    tasks.insert(0, TaskSpec::pin(&chest_name, held.to_array()));
    session.set_tasks(tasks);
    assert!(session.collision_on());
    let chest = session
        .joint_position("l_sternoclavicular")
        .unwrap()
        .lerp(session.joint_position("r_sternoclavicular").unwrap(), 0.5);
    let wrist = session.joint_position("r_radiocarpal").unwrap();
    let reason = reason_for_pull(&mut session, "r_radiocarpal", chest - wrist, 3);
    println!("the wrist pinned inside the chest: {reason}");
    assert!(
        reason.starts_with("gives way to collision: right ") && reason.contains(" against "),
        "{reason}"
    );
}

#[test]
fn a_pull_fighting_a_pinned_foot_names_that_foot_only() {
    for joint in ["l_talocrural", "l_knee"] {
        let mut session = session();
        let reason = reason_for_pull(&mut session, joint, DVec3::new(0.0, 0.3, 0.25), 3);
        assert!(
            reason.starts_with("conflicts with") && reason.contains("left ankle"),
            "{joint}: {reason}"
        );
        assert!(!reason.contains("right ankle"), "{joint}: {reason}");
    }
}

#[test]
fn lifting_the_pelvis_names_both_feet_that_hold_it_together() {
    let mut session = session();
    let reason = reason_for_pull(&mut session, "sacroiliac", DVec3::new(0.0, 0.5, 0.0), 3);
    assert!(reason.contains("left ankle"), "{reason}");
    assert!(reason.contains("right ankle"), "{reason}");
    assert!(!reason.contains("balance"), "{reason}");
}

#[test]
fn a_mirrored_limb_task_keeps_its_swivel_mirrored() {
    let mut session = session();
    let mut values = session.posture().values().to_vec();
    let elbow = session.skeleton().joint_index("l_elbow").unwrap();
    values[session.skeleton().joints()[elbow].dof_start] = -1.0;
    session.set_posture(Posture::from_values(session.skeleton(), values).unwrap());
    session.set_limb_swivel(LimbName::LeftArm, 0.7);
    let (left, _) = session.limb_swivel(LimbName::LeftArm).unwrap();
    let task = TaskSpec::new(TaskKindSpec::Limb {
        limb: Some(LimbName::LeftArm),
        joints: None,
        target: [0.2, 1.0, 0.3],
        swivel: Some(left),
        orientation: None,
    });
    let mirrored_task = &task.mirrored();
    let mirrored = session.mirrored_posture();
    session.set_posture(mirrored);
    let (right, _) = session.limb_swivel(LimbName::RightArm).unwrap();
    let TaskKindSpec::Limb {
        limb,
        target,
        swivel,
        ..
    } = mirrored_task.kind
    else {
        panic!("{mirrored_task:?}");
    };
    assert_eq!(limb, Some(LimbName::RightArm));
    assert_eq!(target, [-0.2, 1.0, 0.3]);
    // The mirrored posture's right arm has the swivel the mirrored task asks for.
    assert!(
        (swivel.unwrap() - right).abs() < 0.02,
        "{swivel:?} vs {right}"
    );
    assert_eq!(task.mirrored().mirrored(), task);
}

#[test]
fn mirroring_twice_gives_the_posture_back_and_swaps_the_arms() {
    let mut session = session();
    let mut values = session.posture().values().to_vec();
    let shoulder = session.skeleton().joint_index("l_shoulder").unwrap();
    let range = session.skeleton().joints()[shoulder].dof_range();
    for (offset, slot) in values[range.clone()].iter_mut().enumerate() {
        *slot = 0.3 + 0.1 * offset as f64;
    }
    let posture = Posture::from_values(session.skeleton(), values).unwrap();
    session.set_posture(posture.clone());
    let mirrored = session.mirrored_posture();
    let right = session.skeleton().joint_index("r_shoulder").unwrap();
    let right_range = session.skeleton().joints()[right].dof_range();
    assert!(mirrored.values()[right_range].iter().any(|v| v.abs() > 0.1));
    session.set_posture(mirrored);
    let back = session.mirrored_posture();
    for (a, b) in back.values().iter().zip(posture.values()) {
        assert!((a - b).abs() < 1e-12);
    }
    // The mirrored left hand is where the right hand is, reflected.
    let frames = Frames::new(session.skeleton(), &posture);
    let left = frames.joint_position[session.skeleton().joint_index("l_radiocarpal").unwrap()];
    let right_hand = session.joint_position("r_radiocarpal").unwrap();
    assert!((right_hand - DVec3::new(-left.x, left.y, left.z)).length() < 0.02);
}

#[test]
fn documents_round_trip_and_a_bad_one_changes_nothing() {
    let mut session = session();
    let wrist = session.skeleton().joint_index("l_radiocarpal").unwrap();
    session.pin(wrist);
    let document = session.document();
    let mut other = self::session();
    other.load_document(&document).unwrap();
    assert_eq!(other.tasks(), session.tasks());
    let mut broken = document.clone();
    broken.tasks.push(TaskSpec::pin("l_wirst", [0.0; 3]));
    // An unknown joint is reported on the task, not a crash.
    other.load_document(&broken).unwrap();
    assert!(other.statuses().last().unwrap().problem.is_some());
}

/// The effort of the posture against gravity: the sum of the squared shares of maximal
/// voluntary torque.
fn effort(session: &PosingSession) -> f64 {
    stance_hanim::comfort::comfort_report(
        session.skeleton(),
        &stance_hanim::strength::built_axes(session.humanoid()),
        session.posture(),
        &Default::default(),
    )
    .terms
    .effort
}

#[test]
fn a_dof_typed_in_stays_as_typed_under_the_default_comfort() {
    let mut session = session();
    assert!(
        session
            .tasks()
            .iter()
            .any(|task| matches!(task.kind, TaskKindSpec::Comfort { .. })),
        "comfort is a default task"
    );
    settle(&mut session);
    // The right elbow bent to 90 degrees: a load comfort would lower if it could move.
    let elbow = session.skeleton().joint_index("r_elbow").unwrap();
    let dof = session.skeleton().joints()[elbow].rotation_dof[0].unwrap();
    session.set_dof(dof, -1.5);
    let typed = session.posture().values()[dof];
    assert!(typed.abs() > 1.0, "the elbow bent: {typed}");
    settle(&mut session);
    assert_eq!(session.posture().values()[dof], typed, "the elbow stays");

    // A change of tasks lets comfort move it again.
    let mut tasks = session.tasks().to_vec();
    tasks.iter_mut().for_each(|task| {
        if let TaskKindSpec::Comfort { effort, .. } = &mut task.kind {
            *effort *= 2.0;
        }
    });
    session.set_tasks(tasks);
    settle(&mut session);
    assert!(
        (session.posture().values()[dof] - typed).abs() > 0.05,
        "after a change of tasks comfort relaxes the elbow: {} -> {}",
        typed,
        session.posture().values()[dof]
    );
}

#[test]
fn a_hand_pulled_up_and_let_go_stays_up_under_the_default_comfort() {
    let mut session = session();
    let wrist = session.skeleton().joint_index("r_radiocarpal").unwrap();
    let goal = session.frames().joint_position[wrist] + DVec3::new(0.1, 0.5, 0.2);
    pull_to(&mut session, wrist, goal);
    let released = session.frames().joint_position[wrist];
    assert!(
        (released - goal).length() < 0.02,
        "the hand followed the pull: {} m short; {:?}; contacts {:?}",
        (released - goal).length(),
        session.report(),
        session.contacts()
    );
    session.end_grab();
    settle(&mut session);
    let after = session.frames().joint_position[wrist];
    assert!(
        (after - released).length() < 1e-9,
        "the hand stays where it was let go: moved {} m",
        (after - released).length()
    );
}

#[test]
fn after_a_reach_the_default_comfort_settles_a_less_loaded_posture_than_rest_attraction() {
    let mut with_comfort = session();
    settle(&mut with_comfort);
    let feet_before = with_comfort.joint_position("l_talocrural").unwrap();
    let wrist = with_comfort.joint_position("r_radiocarpal").unwrap();
    // The right hand 35 cm ahead and 30 cm up, at level 3 under the feet and balance.
    let mut reach = TaskSpec::pin(
        "r_radiocarpal",
        (wrist + DVec3::new(0.0, 0.3, 0.35)).to_array(),
    );
    reach.level = 3;
    let mut tasks = with_comfort.tasks().to_vec();
    tasks.push(reach);
    let mut with_rest = session();
    settle(&mut with_rest);
    let rest_tasks: Vec<TaskSpec> = tasks
        .iter()
        .map(|task| match task.kind {
            TaskKindSpec::Comfort { .. } => TaskSpec::rest_attraction(),
            _ => task.clone(),
        })
        .collect();
    with_comfort.set_tasks(tasks);
    with_rest.set_tasks(rest_tasks);
    settle(&mut with_comfort);
    settle(&mut with_rest);
    for session in [&with_comfort, &with_rest] {
        let reached = session.joint_position("r_radiocarpal").unwrap();
        let goal = wrist + DVec3::new(0.0, 0.3, 0.35);
        assert!((reached - goal).length() < 1e-4, "the hand reached");
        let feet = session.joint_position("l_talocrural").unwrap();
        assert!((feet - feet_before).length() < 1e-6, "the foot held");
    }
    let (comfort, rest) = (effort(&with_comfort), effort(&with_rest));
    assert!(
        comfort < 0.8 * rest,
        "comfort lowers the effort of the reaching posture: {comfort} against {rest}"
    );
}
