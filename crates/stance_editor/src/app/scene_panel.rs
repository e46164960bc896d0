//! The scene panel (the outliner): the characters in the scene's order, the selected one
//! highlighted; add, duplicate, remove, rename, and move or turn the selected one on the
//! floor; the props: add a box, a ball, a bar or a plane, set each one's size, place and turn,
//! remove it. Every change goes to the model as a [`SceneCommand`].

use egui::RichText;
use stance_document::{Prop, PropShape};

use super::ButtonRects;
use crate::model::{Command, EditorModel, FileCommand, KeypointsCommand, Outbox, SceneCommand};

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

/// The scene panel: a section that starts closed while the scene is one character and no
/// prop (the panel below stays where it was), open once there are more.
pub(super) fn show(
    ui: &mut egui::Ui,
    model: &EditorModel,
    outbox: &mut Outbox,
    buttons: &mut ButtonRects,
) {
    let busy = model.character_count() > 1
        || !model.props().is_empty()
        || !model.flippable_limbs().is_empty();
    let title = if busy {
        let count =
            |n: usize, one: &str, many: &str| format!("{n} {}", if n == 1 { one } else { many });
        format!(
            "Scene: {}, {}",
            count(model.character_count(), "character", "characters"),
            count(model.props().len(), "prop", "props")
        )
    } else {
        "Scene".to_owned()
    };
    let header = egui::CollapsingHeader::new(RichText::new(title).heading())
        .id_salt("scene_panel")
        .default_open(busy)
        .show(ui, |ui| scene_contents(ui, model, outbox, buttons));
    buttons.push(("scene_panel", header.header_response.rect));
}

/// A character lifted from keypoints: one button per limb whose depth a single image cannot
/// tell (toward the camera or away), flipping it and solving the keypoints again.
fn depth_flips(ui: &mut egui::Ui, model: &EditorModel, outbox: &mut Outbox) {
    let limbs = model.flippable_limbs();
    if limbs.is_empty() {
        return;
    }
    ui.label("Lifted from keypoints: flip a limb's depth");
    ui.horizontal_wrapped(|ui| {
        for (words, joint) in limbs {
            let flip = ui
                .add_enabled(model.lifting().is_none(), egui::Button::new(words))
                .on_hover_text(format!(
                    "the {words} to the other side in depth, as the camera sees it the same"
                ));
            if flip.clicked() {
                outbox.send(Command::Keypoints(KeypointsCommand::Flip {
                    joint: joint.to_owned(),
                }));
            }
        }
    });
    ui.separator();
}

fn scene_contents(
    ui: &mut egui::Ui,
    model: &EditorModel,
    outbox: &mut Outbox,
    buttons: &mut ButtonRects,
) {
    depth_flips(ui, model, outbox);
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
    between_section(ui, model, outbox, buttons);
    ui.separator();
    props_section(ui, model, outbox, buttons);
}

/// The names the page's tests find the *Hold hands* and the tasks' *Remove* buttons by.
const HOLD_BUTTONS: [&str; 8] = [
    "hold_hands_0",
    "hold_hands_1",
    "hold_hands_2",
    "hold_hands_3",
    "hold_hands_4",
    "hold_hands_5",
    "hold_hands_6",
    "hold_hands_7",
];
const BETWEEN_REMOVE_BUTTONS: [&str; 4] = [
    "between_remove_0",
    "between_remove_1",
    "between_remove_2",
    "between_remove_3",
];

/// Tasks between characters: *Hold hands with* each other character (the two hands nearest
/// each other meet, and the two are posed together), and each task with how far apart its
/// points are and *Remove*. More parts meet from the body's right-click menu.
fn between_section(
    ui: &mut egui::Ui,
    model: &EditorModel,
    outbox: &mut Outbox,
    buttons: &mut ButtonRects,
) {
    if model.character_count() < 2 {
        return;
    }
    ui.horizontal_wrapped(|ui| {
        ui.label("Hold hands with");
        for (index, (character, selected)) in model.characters().enumerate() {
            if selected {
                continue;
            }
            let hold = ui
                .button(character.name())
                .on_hover_text("The nearest hands of the two meet; both are posed together");
            if let Some(name) = HOLD_BUTTONS.get(index) {
                buttons.push((name, hold.rect));
            }
            if hold.clicked()
                && let Some(new) = model.hands_toward(character.id())
            {
                outbox.send(Command::Scene(SceneCommand::AddBetween(new)));
            }
        }
    });
    let distances = model.between_distances();
    for (index, task) in model.between_tasks().iter().enumerate() {
        ui.horizontal_wrapped(|ui| {
            let apart = match distances.get(index).copied().flatten() {
                Some(d) if d < 0.001 => "met".to_owned(),
                Some(d) => format!("{:.0} mm apart", d * 1000.0),
                None => "a part is missing".to_owned(),
            };
            ui.label(format!(
                "{} (level {}): {apart}",
                model.between_description(task),
                task.level
            ));
            let remove = ui.small_button("Remove");
            if let Some(name) = BETWEEN_REMOVE_BUTTONS.get(index) {
                buttons.push((name, remove.rect));
            }
            if remove.clicked() {
                outbox.send(Command::Scene(SceneCommand::RemoveBetween(index)));
            }
        });
    }
}

/// The shapes the *Add prop* row offers, with their first size: a box (a step), a ball, a
/// vertical bar, a table top.
const NEW_PROPS: [(&str, &str, PropShape); 4] = [
    (
        "add_box",
        "Box",
        PropShape::Box {
            size: [0.6, 0.2, 0.4],
        },
    ),
    ("add_sphere", "Ball", PropShape::Sphere { radius: 0.11 }),
    (
        "add_bar",
        "Bar",
        PropShape::Cylinder {
            radius: 0.02,
            height: 2.0,
        },
    ),
    ("add_plane", "Plane", PropShape::Plane { size: [1.2, 0.8] }),
];

/// The props: add one of each shape, and per prop its size, place and turn, and *Remove*.
fn props_section(
    ui: &mut egui::Ui,
    model: &EditorModel,
    outbox: &mut Outbox,
    buttons: &mut ButtonRects,
) {
    ui.horizontal_wrapped(|ui| {
        ui.label("Add prop");
        for (name, label, shape) in NEW_PROPS {
            let button = ui.button(label);
            buttons.push((name, button.rect));
            if button.clicked() {
                outbox.send(Command::Scene(SceneCommand::AddProp(shape)));
            }
        }
        let mesh = ui
            .button("Mesh…")
            .on_hover_text("a static glTF/GLB file (File > Import prop…)");
        buttons.push(("add_mesh", mesh.rect));
        if mesh.clicked() {
            outbox.send(Command::File(FileCommand::PickProp));
        }
    });
    for (index, prop) in model.props().iter().enumerate() {
        egui::CollapsingHeader::new(&prop.name)
            .id_salt(("prop", index))
            .show(ui, |ui| {
                let mut edited = prop.clone();
                if let Some(file) = prop.shape.file() {
                    ui.label(if model.prop_mesh(prop).is_some() {
                        format!("Mesh from {file}")
                    } else {
                        format!("Load {file} to show this prop (File > Import prop…): drawn as its box until then")
                    });
                }
                size_row(ui, &mut edited.shape);
                position_row(ui, &mut edited);
                if ui.button(format!("Remove {}", prop.name)).clicked() {
                    outbox.send(Command::Scene(SceneCommand::RemoveProp(index)));
                } else if edited != *prop {
                    outbox.send(Command::Scene(SceneCommand::EditProp(index, edited)));
                }
            });
    }
}

/// A prop's size fields (m).
fn size_row(ui: &mut egui::Ui, shape: &mut PropShape) {
    let field = |ui: &mut egui::Ui, value: &mut f64, label: &str| {
        ui.add(
            egui::DragValue::new(value)
                .speed(0.005)
                .range(0.005..=stance_document::scene::MAX_PROP_SIZE_M)
                .prefix(format!("{label} "))
                .suffix(" m"),
        );
    };
    ui.horizontal_wrapped(|ui| match shape {
        PropShape::Box { size } | PropShape::Mesh { size, .. } => {
            field(ui, &mut size[0], "width");
            field(ui, &mut size[1], "height");
            field(ui, &mut size[2], "depth");
        }
        PropShape::Sphere { radius } => field(ui, radius, "radius"),
        PropShape::Cylinder { radius, height } => {
            field(ui, radius, "radius");
            field(ui, height, "length");
        }
        PropShape::Plane { size } => {
            field(ui, &mut size[0], "width");
            field(ui, &mut size[1], "depth");
        }
    });
}

/// A prop's centre (m) and its turn about the vertical (degrees; a prop turned about other
/// axes keeps that part of its turn).
fn position_row(ui: &mut egui::Ui, prop: &mut Prop) {
    let rotation = glam::DQuat::from_array(prop.rotation);
    let (yaw, pitch, roll) = rotation.to_euler(glam::EulerRot::YXZ);
    let mut yaw_degrees = yaw.to_degrees();
    ui.horizontal_wrapped(|ui| {
        for (axis, value) in ["centre x", "centre y", "centre z"]
            .into_iter()
            .zip(&mut prop.position)
        {
            ui.add(
                egui::DragValue::new(value)
                    .speed(0.01)
                    .prefix(format!("{axis} "))
                    .suffix(" m"),
            );
        }
        ui.add(
            egui::DragValue::new(&mut yaw_degrees)
                .speed(1.0)
                .range(-180.0..=180.0)
                .prefix("prop turn ")
                .suffix("°"),
        );
    });
    if (yaw_degrees - yaw.to_degrees()).abs() > 1e-9 {
        prop.rotation =
            glam::DQuat::from_euler(glam::EulerRot::YXZ, yaw_degrees.to_radians(), pitch, roll)
                .to_array();
    }
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
    // The model refuses a placement that is not finite.
    if moved != placement {
        outbox.send(Command::Scene(SceneCommand::Place(id, moved)));
    }
}
