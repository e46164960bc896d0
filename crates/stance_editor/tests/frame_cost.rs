//! The editor's CPU per frame with the shared avatar and the paper's Table 1 while the body is
//! pulled, and with three characters beside one (measured, not asserted): what a frame costs
//! natively, without the GPU draw.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use crate::common;

use std::sync::mpsc::channel;

use egui_kittest::kittest::Queryable;
use stance_editor::{HostMessage, MemoryHost, StanceApp};

use common::{
    click_button, harness_sized, open_scene_panel, press_at, release_at, screen_position, settle,
    state,
};

const AVATAR: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../../tests/fixtures/avatars/Black_F_2_Casual.glb"
);

fn percentile(values: &[f64], p: f64) -> f64 {
    let mut sorted = values.to_vec();
    sorted.sort_by(f64::total_cmp);
    sorted[((sorted.len() - 1) as f64 * p).round() as usize]
}

#[test]
fn frame_cost_with_the_avatar_and_table1_while_pulling() {
    let (sender, receiver) = channel();
    let app = StanceApp::without_gpu(Box::new(MemoryHost::default()))
        .unwrap()
        .with_inbox(receiver);
    let mut harness = harness_sized(app, egui::vec2(1280.0, 720.0));
    sender
        .send(HostMessage::OpenFile {
            name: "Black_F_2_Casual.glb".to_owned(),
            bytes: std::fs::read(AVATAR).unwrap(),
        })
        .unwrap();
    settle(&mut harness);
    harness.get_by_label("Table 1 example").click();
    settle(&mut harness);
    assert!(
        state(&harness)["avatar"].is_object(),
        "the avatar is loaded"
    );
    let knee = screen_position(&harness, "l_knee");
    let ankle = screen_position(&harness, "l_talocrural");
    let grab = knee + (ankle - knee) * 0.3;
    press_at(&mut harness, grab);
    let (mut frame_ms, mut solver_ms, mut scene_ms) = (Vec::new(), Vec::new(), Vec::new());
    for step in 1..=120 {
        let pos = grab + egui::vec2(40.0 * (step as f32 / 10.0).sin(), -(step as f32));
        harness.event(egui::Event::PointerMoved(pos));
        let started = std::time::Instant::now();
        harness.step();
        frame_ms.push(started.elapsed().as_secs_f64() * 1000.0);
        let sample = state(&harness);
        solver_ms.push(sample["solver_ms"].as_f64().unwrap_or(0.0));
        scene_ms.push(sample["scene_ms"].as_f64().unwrap_or(0.0));
    }
    assert_eq!(
        state(&harness)["pulling"],
        true,
        "the drag grabbed the body"
    );
    println!(
        "[frame] native, avatar + Table 1 + pull, 1280x720, no GPU draw: editor CPU per frame median {:.2} ms, p95 {:.2} ms over {} frames; solver median {:.2} ms, scene (skinning palettes) median {:.2} ms",
        percentile(&frame_ms, 0.5),
        percentile(&frame_ms, 0.95),
        frame_ms.len(),
        percentile(&solver_ms, 0.5),
        percentile(&scene_ms, 0.5),
    );
}

/// Pulls the selected character's left shin for `frames` frames; the editor's CPU per frame
/// (ms).
fn pull_frames(harness: &mut egui_kittest::Harness<'static, StanceApp>, frames: usize) -> Vec<f64> {
    let knee = screen_position(harness, "l_knee");
    let ankle = screen_position(harness, "l_talocrural");
    let grab = knee + (ankle - knee) * 0.3;
    press_at(harness, grab);
    let mut frame_ms = Vec::with_capacity(frames);
    let mut pos = grab;
    for step in 1..=frames {
        pos = grab + egui::vec2(30.0 * (step as f32 / 10.0).sin(), -(step as f32) * 0.5);
        harness.event(egui::Event::PointerMoved(pos));
        let started = std::time::Instant::now();
        harness.step();
        frame_ms.push(started.elapsed().as_secs_f64() * 1000.0);
    }
    assert_eq!(
        state(harness)["pulling"],
        true,
        "the drag at {grab:?} grabbed the body"
    );
    release_at(harness, pos);
    settle(harness);
    frame_ms
}

/// Issue 31's target: three LOA 2 characters, Table 1 on one and a pull on another, against
/// the same pull on one character (its default tasks; the same run, the mannequin).
#[test]
fn frame_cost_of_three_characters_against_one() {
    let app = StanceApp::without_gpu(Box::new(MemoryHost::default())).unwrap();
    let mut harness = harness_sized(app, egui::vec2(1280.0, 720.0));
    settle(&mut harness);
    // One character with its default tasks, pulled.
    let one = pull_frames(&mut harness, 90);
    // Table 1 on it, then two more characters.
    harness.get_by_label("Table 1 example").click();
    settle(&mut harness);
    open_scene_panel(&mut harness);
    click_button(&mut harness, "scene_add");
    click_button(&mut harness, "scene_add");
    settle(&mut harness);
    assert_eq!(
        state(&harness)["characters"].as_array().map(Vec::len),
        Some(3)
    );
    // The pull on the second (the third stands at the view's right edge).
    click_button(&mut harness, "character_1");
    settle(&mut harness);
    assert_eq!(state(&harness)["characters"][1]["selected"], true);
    let three = pull_frames(&mut harness, 90);
    let (one, three) = (percentile(&one, 0.5), percentile(&three, 0.5));
    println!(
        "[frame] native, LOA 2 mannequins, 1280x720, no GPU draw: editor CPU per frame while pulling, median over 90 frames: one character {one:.2} ms; three characters (Table 1 on the first, the pull on the second) {three:.2} ms: {:.2}x",
        three / one
    );
}
