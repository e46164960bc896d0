//! The side panel's comfort section: the RULA score with its parts, the five highest joint
//! loads against gravity, the heat map switch and RULA's inputs that a posture does not show.

use crate::model::Outbox;
use egui::{Color32, RichText};
use stance_hanim::comfort::rula::{RulaLoad, RulaReport, RulaVariant};
use stance_hanim::readable_name;

use crate::model::{ComfortCommand, Command, EditorModel};

/// RULA's loads as the panel names them.
const LOADS: [(RulaLoad, &str); 6] = [
    (RulaLoad::None, "none or under 2 kg"),
    (RulaLoad::Intermittent2To10, "2-10 kg, intermittent"),
    (RulaLoad::Static2To10, "2-10 kg, static or repeated"),
    (RulaLoad::Intermittent10Plus, "over 10 kg, intermittent"),
    (RulaLoad::Static10Plus, "over 10 kg, static or repeated"),
    (RulaLoad::Shock, "shock or rapid build-up"),
];

/// Draws the section.
pub(super) fn show(ui: &mut egui::Ui, model: &EditorModel, outbox: &mut Outbox) {
    ui.heading("Comfort");
    let report = model.comfort_report();
    match &report.rula {
        Some(rula) => rula_section(ui, rula),
        None => {
            ui.label("RULA: this body lacks a joint RULA measures");
        }
    }
    ui.label(RichText::new("Highest joint loads").strong())
        .on_hover_text("static torque of gravity at the joint, as a share of its strength");
    for load in report.highest(5) {
        let share = load
            .share
            .map_or_else(String::new, |s| format!(", {:.0} %", 100.0 * s));
        let text = RichText::new(format!(
            "{}: {:.1} N·m{share}",
            readable_name(&load.joint),
            load.torque_nm
        ));
        ui.label(if load.flagged {
            text.color(Color32::from_rgb(210, 40, 30))
        } else {
            text
        })
        .on_hover_text(if load.flagged {
            "above 15 % of the joint's strength"
        } else {
            "below 15 % of the joint's strength"
        });
    }
    let mut heat_map = model.comfort().heat_map();
    if ui
        .checkbox(&mut heat_map, "Heat map of joint loads")
        .changed()
    {
        outbox.send(Command::Comfort(ComfortCommand::ShowHeatMap(heat_map)));
    }
    settings(ui, model, outbox);
}

/// RULA's inputs that a posture does not show.
fn settings(ui: &mut egui::Ui, model: &EditorModel, outbox: &mut Outbox) {
    let mut settings = model.comfort().settings();
    let rula = &mut settings.rula_settings;
    egui::CollapsingHeader::new("RULA inputs").show(ui, |ui| {
        let current = LOADS
            .iter()
            .find(|(load, _)| *load == rula.load)
            .map_or("", |(_, name)| name);
        egui::ComboBox::from_label("load")
            .selected_text(current)
            .show_ui(ui, |ui| {
                for (load, name) in LOADS {
                    ui.selectable_value(&mut rula.load, load, name);
                }
            });
        ui.checkbox(
            &mut rula.muscle_use,
            "static over 1 min or repeated over 4/min",
        );
        ui.checkbox(&mut rula.arm_supported, "arm supported or leaning");
        ui.checkbox(&mut rula.seated_supported, "seated, trunk supported");
        let mut worksheet = rula.variant == RulaVariant::Worksheet;
        ui.checkbox(&mut worksheet, "worksheet bands (upper arm +-15 deg)")
            .on_hover_text("the 1993 paper uses +-20 deg for the upper arm's first band");
        rula.variant = if worksheet {
            RulaVariant::Worksheet
        } else {
            RulaVariant::Paper
        };
    });
    if settings != model.comfort().settings() {
        outbox.send(Command::Comfort(ComfortCommand::SetSettings(settings)));
    }
}

/// The RULA score, its action level and its parts.
fn rula_section(ui: &mut egui::Ui, rula: &RulaReport) {
    let colour = match rula.action_level {
        1 => Color32::from_rgb(60, 160, 70),
        2 => Color32::from_rgb(200, 160, 30),
        3 => Color32::from_rgb(220, 110, 30),
        _ => Color32::from_rgb(210, 40, 30),
    };
    ui.label(
        RichText::new(format!(
            "RULA {} (action level {})",
            rula.score, rula.action_level
        ))
        .strong()
        .color(colour),
    )
    .on_hover_text(
        "1-2 acceptable; 3-4 investigate; 5-6 investigate and change soon; 7 change now",
    );
    egui::Grid::new("rula_parts").num_columns(3).show(ui, |ui| {
        ui.label("");
        ui.label("left");
        ui.label("right");
        ui.end_row();
        let rows = [
            ("upper arm", rula.left.upper_arm, rula.right.upper_arm),
            ("lower arm", rula.left.lower_arm, rula.right.lower_arm),
            ("wrist", rula.left.wrist, rula.right.wrist),
            ("wrist twist", rula.left.wrist_twist, rula.right.wrist_twist),
            ("score C", rula.left.score_c, rula.right.score_c),
        ];
        for (name, left, right) in rows {
            ui.label(name);
            ui.label(left.to_string());
            ui.label(right.to_string());
            ui.end_row();
        }
    });
    ui.label(format!(
        "neck {}, trunk {}, legs {}; score D {}",
        rula.body.neck, rula.body.trunk, rula.body.legs, rula.body.score_d
    ));
}
