//! *File > Export control maps…*: a small window with the map's size and the keypoints'
//! options; Export draws the OpenPose map of the posture seen through the viewport's camera
//! (on the CPU: [`stance_render::OpenPose::draw`]) and sends its PNG and JSON to the model,
//! which downloads them as `stance-openpose.png` and `stance-openpose.json`.

use stance_render::{HiddenKeypoints, KeypointUnits, MAX_IMAGE_SIDE_PX, Pixels, encode_png};

use super::ButtonRects;
use super::viewport_panel::ViewportPanel;
use crate::model::{
    Command, EditorModel, FileCommand, NoticeCommand, OPENPOSE_IMAGE_FILE_NAME, Outbox,
};

/// The *Export control maps* window and the options it keeps between uses.
#[derive(Debug)]
pub(crate) struct ControlMapsWindow {
    /// Whether the window shows.
    pub open: bool,
    /// Width and height of the maps, pixels.
    pub size_px: [u32; 2],
    /// Leave out the keypoints the body hides (else keep them).
    pub hidden_missing: bool,
    /// Keypoints as fractions of the image (else pixels).
    pub normalized: bool,
}

impl Default for ControlMapsWindow {
    fn default() -> Self {
        Self {
            open: false,
            size_px: [1024, 1024],
            hidden_missing: false,
            normalized: false,
        }
    }
}

impl ControlMapsWindow {
    /// Shows the window when open; Export sends the OpenPose map of `model` seen through
    /// `viewport`'s camera.
    pub(super) fn show(
        &mut self,
        ctx: &egui::Context,
        (model, outbox): (&EditorModel, &mut Outbox),
        viewport: &ViewportPanel,
        buttons: &mut ButtonRects,
    ) {
        let mut open = self.open;
        let mut export = false;
        egui::Window::new("Export control maps")
            .open(&mut open)
            .resizable(false)
            .collapsible(false)
            .show(ctx, |ui| {
                let sides = 1..=MAX_IMAGE_SIDE_PX;
                ui.horizontal(|ui| {
                    ui.label("Size");
                    ui.add(egui::DragValue::new(&mut self.size_px[0]).range(sides.clone()));
                    ui.label("×");
                    ui.add(egui::DragValue::new(&mut self.size_px[1]).range(sides));
                    ui.label("px");
                });
                if ui.button("Viewport size").clicked() {
                    self.size_px = viewport.size_px.map(|side| side.max(1));
                }
                ui.checkbox(
                    &mut self.hidden_missing,
                    "Leave out keypoints the body hides",
                );
                ui.checkbox(&mut self.normalized, "Keypoints as fractions of the size");
                ui.label("The OpenPose skeleton (body and hands) and its keypoints (JSON).");
                let button = ui.button(format!("Export {OPENPOSE_IMAGE_FILE_NAME} and JSON"));
                buttons.push(("export_control_maps", button.rect));
                export = button.clicked();
            });
        if export {
            outbox.send(self.openpose_command(model, viewport));
            open = false;
        }
        self.open = open;
    }

    /// The OpenPose map of `model` through `viewport`'s camera, as the command that saves it
    /// (or a warning when it cannot be made).
    fn openpose_command(&self, model: &EditorModel, viewport: &ViewportPanel) -> Command {
        let size_px = self.size_px.map(|side| side.clamp(1, MAX_IMAGE_SIDE_PX));
        let hidden = if self.hidden_missing {
            HiddenKeypoints::Missing
        } else {
            HiddenKeypoints::Keep
        };
        let pose = model.openpose(&viewport.camera, size_px, hidden);
        let pixels = Pixels {
            width: size_px[0],
            height: size_px[1],
            rgba: pose.draw(),
        };
        let units = if self.normalized {
            KeypointUnits::Normalized
        } else {
            KeypointUnits::Pixels
        };
        match encode_png(&pixels) {
            Ok(png) => Command::File(FileCommand::SaveOpenPose {
                png,
                json: pose.to_json(units),
                width: size_px[0],
                height: size_px[1],
            }),
            Err(error) => Command::Notice(NoticeCommand::Warn(format!(
                "The OpenPose map could not be made: {error}."
            ))),
        }
    }
}
