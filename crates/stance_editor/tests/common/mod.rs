//! Helpers shared by the editor's kittest suites: a harness around `StanceApp::show`, frames
//! until the solver settles, the published state, and clicks where a hand would make them.

#![allow(dead_code)]
// Test-support code (not itself a #[test]): panicking on broken fixtures is what we want.
// Since the tests became one binary (tests/all.rs) the allowances of the files that include
// this module no longer reach it.
#![allow(clippy::expect_used, clippy::unwrap_used, clippy::panic)]

use egui::{Modifiers, PointerButton, Pos2};
use egui_kittest::Harness;
use serde_json::Value;
use stance_editor::StanceApp;

pub use crate::clocked::{editor_on, open};

/// The editor in a window of `size` points, run until it settles.
pub fn harness_sized(app: StanceApp, size: egui::Vec2) -> Harness<'static, StanceApp> {
    let frame = eframe::Frame::_new_kittest();
    let mut harness = Harness::builder()
        .with_size(size)
        .with_context_setup(stance_editor::fonts::install)
        .build_ui_state(move |ui, app: &mut StanceApp| app.show(ui, &frame), app);
    settle(&mut harness);
    harness
}

/// The editor in a 1280 x 720 window (the smallest layout it supports), settled.
pub fn harness_for(app: StanceApp) -> Harness<'static, StanceApp> {
    harness_sized(app, egui::vec2(1280.0, 720.0))
}

/// Runs frames until the solver has settled, then two more; panics, saying where the solver
/// stands, when it has not within 400 frames (a test that goes on unsettled would check a
/// posture still on its way).
pub fn settle(harness: &mut Harness<'static, StanceApp>) {
    const LIMIT: usize = 400;
    let mut settled = false;
    for _ in 0..LIMIT {
        harness.step();
        if harness.state().model().session().is_settled() {
            settled = true;
            break;
        }
    }
    assert!(
        settled,
        "{}",
        crate::clocked::unsettled(harness.state().model(), LIMIT)
    );
    harness.run_steps(2);
}

/// The state the page's test hook sees.
pub fn state(harness: &Harness<'static, StanceApp>) -> Value {
    serde_json::from_str(&harness.state().state_json()).unwrap()
}

/// Where a joint is on screen (points).
pub fn screen_position(harness: &Harness<'static, StanceApp>, joint: &str) -> Pos2 {
    let state = state(harness);
    let xy = &state["screen"][joint];
    Pos2::new(
        xy[0].as_f64().unwrap() as f32,
        xy[1].as_f64().unwrap() as f32,
    )
}

/// A click like a hand makes it: the pointer comes, presses, and releases a frame later.
pub fn click_at(harness: &mut Harness<'static, StanceApp>, pos: Pos2) {
    harness.event(egui::Event::PointerMoved(pos));
    harness.step();
    for pressed in [true, false] {
        harness.event(egui::Event::PointerButton {
            pos,
            button: PointerButton::Primary,
            pressed,
            modifiers: Modifiers::NONE,
        });
        harness.step();
    }
    harness.run_steps(2);
}

/// Clicks the button the editor published under `name` (see `buttons` in the state).
pub fn click_button(harness: &mut Harness<'static, StanceApp>, name: &str) {
    let state = state(harness);
    let rect = &state["buttons"][name];
    assert!(rect.is_array(), "no button {name} in {}", state["buttons"]);
    let [x, y, w, h] = [0, 1, 2, 3].map(|i| rect[i].as_f64().unwrap() as f32);
    click_at(harness, egui::pos2(x + w / 2.0, y + h / 2.0));
}

/// Presses on the right forearm (below the elbow, on the side away from the body) and drags
/// the pointer up and inward in 20 frames, still holding the button. Returns where the press
/// started and where the pointer is (release there with [`release_at`]).
pub fn drag_right_forearm_up(harness: &mut Harness<'static, StanceApp>) -> (Pos2, Pos2) {
    let wrist = screen_position(harness, "r_radiocarpal");
    let elbow = screen_position(harness, "r_elbow");
    let pelvis = screen_position(harness, "sacroiliac");
    let outward = egui::vec2((wrist.x - pelvis.x).signum() * 3.0, 0.0);
    let start = elbow + (wrist - elbow) * 0.6 + outward;
    let end = start + egui::vec2(-60.0, -120.0);
    press_at(harness, start);
    for step in 1..=20 {
        let t = step as f32 / 20.0;
        harness.event(egui::Event::PointerMoved(start + (end - start) * t));
        harness.step();
    }
    (start, end)
}

/// Moves the pointer to `pos` and presses the primary button there (a drag starts).
pub fn press_at(harness: &mut Harness<'static, StanceApp>, pos: Pos2) {
    harness.event(egui::Event::PointerMoved(pos));
    harness.step();
    harness.event(egui::Event::PointerButton {
        pos,
        button: PointerButton::Primary,
        pressed: true,
        modifiers: Modifiers::NONE,
    });
    harness.step();
}

/// Releases the primary button at `pos`.
pub fn release_at(harness: &mut Harness<'static, StanceApp>, pos: Pos2) {
    harness.event(egui::Event::PointerButton {
        pos,
        button: PointerButton::Primary,
        pressed: false,
        modifiers: Modifiers::NONE,
    });
}

/// Opens the side panel's *Scene* section (closed while the scene is one character) unless it
/// shows its buttons already.
pub fn open_scene_panel(harness: &mut Harness<'static, StanceApp>) {
    if state(harness)["buttons"]["scene_add"].is_array() {
        return;
    }
    click_button(harness, "scene_panel");
    harness.run_steps(2);
}
