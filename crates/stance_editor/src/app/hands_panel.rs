//! The side panel's hands section (bodies with fingers: LOA 2 and above, avatars with finger
//! joints): which hands, the presets, and a curl slider for the whole hand and each finger.

use crate::model::Outbox;
use stance_hanim::hands::{Finger, HandPreset};

use crate::model::{Command, EditorModel, HandCommand, Hands};

/// Draws the section; nothing when the body has no fingers.
pub(super) fn show(ui: &mut egui::Ui, model: &EditorModel, outbox: &mut Outbox) {
    if !model.has_fingers() {
        return;
    }
    ui.separator();
    ui.heading("Hands");
    // Which hands the buttons and sliders pose: kept by the panel across frames.
    let id = egui::Id::unique("stance_hands_target");
    let mut hands = ui.data_mut(|data| *data.get_temp_mut_or(id, Hands::Both));
    ui.horizontal(|ui| {
        for choice in Hands::ALL {
            ui.selectable_value(&mut hands, choice, choice.name())
                .on_hover_text(match choice {
                    Hands::Both => "both hands, mirror images of each other",
                    _ => "this hand only",
                });
        }
    });
    ui.data_mut(|data| data.insert_temp(id, hands));
    ui.horizontal_wrapped(|ui| {
        for preset in HandPreset::ALL {
            if ui.button(preset.name()).clicked() {
                outbox.send(Command::Hands(HandCommand::Preset { hands, preset }));
            }
        }
    });
    egui::Grid::new("hand_curls").num_columns(2).show(ui, |ui| {
        let rows = std::iter::once(None).chain(Finger::ALL.into_iter().map(Some));
        for finger in rows {
            let Some(current) = model.hand_curl(hands, finger) else {
                continue;
            };
            let label = ui.label(finger.map_or("hand", Finger::name));
            // The slider shows whole percents and reports a change when it rounds the value
            // it is given: only a move away from the shown value is the user's edit (a posture
            // moved by the solver must not become an undo step).
            let shown = (current * 100.0).round();
            let mut percent = shown;
            let slider = egui::Slider::new(&mut percent, 0.0..=100.0)
                .suffix("%")
                .max_decimals(0);
            let response = ui
                .add(slider)
                .labelled_by(label.id)
                .on_hover_text("curl: 0 % straight, 100 % closed as far as the joints allow");
            if response.changed() && percent != shown {
                outbox.send(Command::Hands(HandCommand::Curl {
                    hands,
                    finger,
                    curl: percent / 100.0,
                }));
            }
            ui.end_row();
        }
    });
}
