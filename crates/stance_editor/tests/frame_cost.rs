//! The editor's CPU per frame with the shared avatar and the paper's Table 1 while the body is
//! pulled (measured, not asserted): what a frame costs natively, without the GPU draw.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use std::sync::mpsc::channel;

use egui::{PointerButton, Pos2};
use egui_kittest::Harness;
use egui_kittest::kittest::Queryable;
use stance_editor::{HostMessage, MemoryHost, StanceApp};

const AVATAR: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../../tests/fixtures/avatars/Black_F_2_Casual.glb"
);

fn settle(harness: &mut Harness<'static, StanceApp>) {
    for _ in 0..400 {
        harness.step();
        let state: serde_json::Value = serde_json::from_str(&harness.state().state_json()).unwrap();
        if state["settled"] == true {
            break;
        }
    }
    harness.run_steps(2);
}

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
    let frame = eframe::Frame::_new_kittest();
    let mut harness = Harness::builder()
        .with_size(egui::vec2(1280.0, 720.0))
        .build_ui_state(move |ui, app: &mut StanceApp| app.show(ui, &frame), app);
    sender
        .send(HostMessage::OpenFile {
            name: "Black_F_2_Casual.glb".to_owned(),
            bytes: std::fs::read(AVATAR).unwrap(),
        })
        .unwrap();
    settle(&mut harness);
    harness.get_by_label("Table 1 example").click();
    settle(&mut harness);
    let state: serde_json::Value = serde_json::from_str(&harness.state().state_json()).unwrap();
    assert!(state["avatar"].is_object(), "the avatar is loaded");
    let at = |name: &str| {
        let xy = &state["screen"][name];
        Pos2::new(
            xy[0].as_f64().unwrap() as f32,
            xy[1].as_f64().unwrap() as f32,
        )
    };
    let (knee, ankle) = (at("l_knee"), at("l_talocrural"));
    let grab = knee + (ankle - knee) * 0.3;
    harness.event(egui::Event::PointerMoved(grab));
    harness.step();
    harness.event(egui::Event::PointerButton {
        pos: grab,
        button: PointerButton::Primary,
        pressed: true,
        modifiers: egui::Modifiers::NONE,
    });
    harness.step();
    let mut frame_ms = Vec::new();
    let mut solver_ms = Vec::new();
    let mut scene_ms = Vec::new();
    for step in 1..=120 {
        let pos = grab + egui::vec2(40.0 * (step as f32 / 10.0).sin(), -(step as f32));
        harness.event(egui::Event::PointerMoved(pos));
        let started = std::time::Instant::now();
        harness.step();
        frame_ms.push(started.elapsed().as_secs_f64() * 1000.0);
        let sample: serde_json::Value =
            serde_json::from_str(&harness.state().state_json()).unwrap();
        solver_ms.push(sample["solver_ms"].as_f64().unwrap_or(0.0));
        scene_ms.push(sample["scene_ms"].as_f64().unwrap_or(0.0));
    }
    let state: serde_json::Value = serde_json::from_str(&harness.state().state_json()).unwrap();
    assert_eq!(state["pulling"], true, "the drag grabbed the body");
    println!(
        "[frame] native, avatar + Table 1 + pull, 1280x720, no GPU draw: editor CPU per frame median {:.2} ms, p95 {:.2} ms over {} frames ; solver median {:.2} ms, scene (skinning palettes) median {:.2} ms",
        percentile(&frame_ms, 0.5),
        percentile(&frame_ms, 0.95),
        frame_ms.len(),
        percentile(&solver_ms, 0.5),
        percentile(&scene_ms, 0.5),
    );
}
