//! The scene panel (the outliner): the characters in the scene's order, the selected one
//! highlighted; add, duplicate, remove, rename, and move or turn the selected one on the
//! floor. Every change goes to the model as a [`SceneCommand`].

use egui::RichText;
use stance_document::Placement;

use super::ButtonRects;
use crate::model::{Command, EditorModel, Outbox, SceneCommand};

/// The names the page's tests find the scene panel's buttons by.
const CHARACTER_BUTTONS: [&str; 8] = [
    "character_0",
    "character_1",
    "character_2",
    "character_3",
    "character_4",
    "character_5",
    "character_6",
    "character_7",
];

/// The scene panel.
pub(super) fn show(
    ui: &mut egui::Ui,
    model: &EditorModel,
    outbox: &mut Outbox,
    buttons: &mut ButtonRects,
) {
    ui.heading("Scene");
    for (index, (character, selected)) in model.characters().enumerate() {
        let label = if selected {
            RichText::new(character.name()).strong()
        } else {
            RichText::new(character.name())
        };
        let response = ui
            .selectable_label(selected, label)
            .on_hover_text("Select: the tools work on this character (or click it in the view)");
        if let Some(name) = CHARACTER_BUTTONS.get(index) {
            buttons.push((name, response.rect));
        }
        if response.clicked() && !selected {
            outbox.send(Command::Scene(SceneCommand::Select(character.id())));
        }
    }
    ui.horizontal(|ui| {
        let add = ui
            .button("Add character")
            .on_hover_text("A new character on the mannequin, beside the others");
        buttons.push(("scene_add", add.rect));
        if add.clicked() {
            outbox.send(Command::Scene(SceneCommand::Add));
        }
        let duplicate = ui
            .button("Duplicate character")
            .on_hover_text("A copy of the selected character: body, posture, tasks");
        buttons.push(("scene_duplicate", duplicate.rect));
        if duplicate.clicked() {
            outbox.send(Command::Scene(SceneCommand::Duplicate));
        }
        let remove = ui.add_enabled(
            model.character_count() > 1,
            egui::Button::new("Remove character"),
        );
        buttons.push(("scene_remove", remove.rect));
        if remove
            .on_hover_text("Removes the selected character (undo brings it back)")
            .clicked()
        {
            outbox.send(Command::Scene(SceneCommand::Remove(model.character().id())));
        }
    });
    selected_character(ui, model, outbox);
}

/// The selected character's name (sent when the field loses focus or Enter is pressed) and its
/// place on the floor.
fn selected_character(ui: &mut egui::Ui, model: &EditorModel, outbox: &mut Outbox) {
    let character = model.character();
    let id = character.id();
    let buffer_id = egui::Id::unique(("character_name", id));
    let mut name = ui
        .data(|data| data.get_temp::<String>(buffer_id))
        .unwrap_or_else(|| character.name().to_owned());
    let response = ui
        .horizontal(|ui| {
            let label = ui.label("Character name");
            ui.text_edit_singleline(&mut name).labelled_by(label.id)
        })
        .inner;
    if response.changed() {
        ui.data_mut(|data| data.insert_temp(buffer_id, name.clone()));
    }
    if response.lost_focus() {
        ui.data_mut(|data| data.remove::<String>(buffer_id));
        if name != character.name() {
            outbox.send(Command::Scene(SceneCommand::Rename(id, name)));
        }
    }
    let placement = character.placement();
    let mut moved = placement;
    ui.horizontal(|ui| {
        ui.label("Place");
        ui.add(
            egui::DragValue::new(&mut moved.position[0])
                .speed(0.01)
                .prefix("at x ")
                .suffix(" m"),
        );
        ui.add(
            egui::DragValue::new(&mut moved.position[2])
                .speed(0.01)
                .prefix("at z ")
                .suffix(" m"),
        );
        ui.add(
            egui::DragValue::new(&mut moved.yaw_degrees)
                .speed(1.0)
                .range(-180.0..=180.0)
                .prefix("turn ")
                .suffix("°"),
        );
    });
    if moved != placement && placement_is_finite(&moved) {
        outbox.send(Command::Scene(SceneCommand::Place(id, moved)));
    }
}

fn placement_is_finite(placement: &Placement) -> bool {
    placement.validate_at("placement").is_ok()
}
