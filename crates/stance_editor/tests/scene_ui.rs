//! Several characters in the editor, driven like a user would (egui_kittest): the Scene
//! panel's buttons add a character beside the first, a pull moves only the selected one,
//! and a click on the other character in the view selects it.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use egui::Pos2;
use stance_editor::{MemoryHost, StanceApp};

use crate::common::{
    click_at, click_button, drag_right_forearm_up, harness_for, open_scene_panel, release_at,
    settle, state,
};

fn characters(harness: &egui_kittest::Harness<'static, StanceApp>) -> Vec<serde_json::Value> {
    state(harness)["characters"].as_array().unwrap().clone()
}

fn pelvis_on_screen(character: &serde_json::Value) -> Pos2 {
    let xy = &character["pelvis_screen"];
    Pos2::new(
        xy[0].as_f64().unwrap() as f32,
        xy[1].as_f64().unwrap() as f32,
    )
}

#[test]
fn a_second_character_is_added_posed_alone_and_selected_by_a_click_on_it() {
    let host = MemoryHost::default();
    let app = StanceApp::without_gpu(Box::new(host.clone())).unwrap();
    let mut harness = harness_for(app);
    settle(&mut harness);
    open_scene_panel(&mut harness);
    click_button(&mut harness, "scene_add");
    settle(&mut harness);
    let cast = characters(&harness);
    assert_eq!(cast.len(), 2, "{cast:?}");
    assert_eq!(cast[1]["selected"], true);
    // The new one stands to the first one's left (+X), seen from the front: to the right on
    // screen.
    let (first, second) = (pelvis_on_screen(&cast[0]), pelvis_on_screen(&cast[1]));
    assert!(second.x > first.x + 20.0, "{first:?} {second:?}");
    // The selected one's joints on screen are its own: its pelvis where the cast says.
    let pelvis = crate::common::screen_position(&harness, "sacroiliac");
    assert!(pelvis.distance(second) < 1.0, "{pelvis:?} {second:?}");

    // A pull on the new one's forearm moves its hand; the first one stays at rest.
    let first_document = harness.state().model().other_characters()[0]
        .session()
        .document();
    let hand_before = state(&harness)["joints"]["r_radiocarpal"].clone();
    let (_, end) = drag_right_forearm_up(&mut harness);
    release_at(&mut harness, end);
    settle(&mut harness);
    assert_ne!(state(&harness)["joints"]["r_radiocarpal"], hand_before);
    assert_eq!(
        harness.state().model().other_characters()[0]
            .session()
            .document(),
        first_document
    );

    // A click on the first one's body selects it.
    click_at(&mut harness, first);
    let cast = characters(&harness);
    assert_eq!(cast[0]["selected"], true, "{cast:?}");
    assert_eq!(harness.state().model().character().name(), "Character 1");
}
