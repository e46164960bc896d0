//! *File > Export control maps…*: a small window with the maps' size, which maps, and the
//! keypoints' options; Export draws the OpenPose map of the posture seen through the
//! viewport's camera (on the CPU: [`stance_render::OpenPose::draw`]) and sends its PNG and
//! JSON to the model, which downloads them as `stance-openpose.png` and
//! `stance-openpose.json`, and asks the viewport's GPU for the depth, normal, mask and line-art
//! maps (`stance-depth.png`...), rendered one after another as *Save image* renders.

use stance_render::{
    HiddenKeypoints, ImageOptions, KeypointUnits, MAX_IMAGE_SIDE_PX, Pixels, encode_png,
};

use super::ButtonRects;
use super::viewport_panel::ViewportPanel;
use crate::image::ImageRequest;
use crate::model::{
    Command, EditorModel, FileCommand, NoticeCommand, OPENPOSE_IMAGE_FILE_NAME, Outbox, RenderedMap,
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
    /// Export the OpenPose map.
    pub openpose: bool,
    /// Export each rendered map (depth, normal, mask, line art: [`RenderedMap::ALL`]'s
    /// order).
    pub rendered: [bool; 4],
}

impl Default for ControlMapsWindow {
    fn default() -> Self {
        Self {
            open: false,
            size_px: [1024, 1024],
            hidden_missing: false,
            normalized: false,
            openpose: true,
            rendered: [true; 4],
        }
    }
}

impl ControlMapsWindow {
    /// Shows the window when open; Export sends the OpenPose map of `model` seen through
    /// `viewport`'s camera and asks `viewport` for the rendered maps.
    pub(super) fn show(
        &mut self,
        ctx: &egui::Context,
        (model, outbox): (&EditorModel, &mut Outbox),
        viewport: &mut ViewportPanel,
        buttons: &mut ButtonRects,
    ) {
        let mut open = self.open;
        let mut export = false;
        egui::Window::new("Export control maps")
            .open(&mut open)
            .resizable(false)
            .collapsible(false)
            .show(ctx, |ui| export = self.contents(ui, viewport, buttons));
        if export {
            if self.openpose {
                outbox.send(self.openpose_command(model, viewport));
            }
            let requests = RenderedMap::ALL
                .into_iter()
                .zip(self.rendered)
                .filter(|&(_, wanted)| wanted && viewport.has_gpu())
                .map(|(map, _)| ImageRequest {
                    options: ImageOptions {
                        size_px: self.size_px,
                        transparent: false,
                        overlays: false,
                    },
                    camera: viewport.camera,
                    map: Some(map),
                })
                .collect();
            viewport.image.request_all(requests);
            open = false;
        }
        self.open = open;
    }

    /// The window's controls; whether Export was clicked.
    fn contents(
        &mut self,
        ui: &mut egui::Ui,
        viewport: &ViewportPanel,
        buttons: &mut ButtonRects,
    ) -> bool {
        super::image_window::size_row(ui, &mut self.size_px, viewport);
        ui.checkbox(&mut self.openpose, "OpenPose skeleton and keypoints (JSON)");
        ui.indent("openpose_options", |ui| {
            ui.checkbox(
                &mut self.hidden_missing,
                "Leave out keypoints the body hides",
            );
            ui.checkbox(&mut self.normalized, "Keypoints as fractions of the size");
        });
        let has_gpu = viewport.has_gpu();
        for (map, wanted) in RenderedMap::ALL.into_iter().zip(&mut self.rendered) {
            ui.add_enabled(has_gpu, egui::Checkbox::new(wanted, map.label()))
                .on_disabled_hover_text("the 3D view has no GPU");
        }
        let busy = viewport.image.is_busy();
        let button = ui
            .add_enabled(!busy, egui::Button::new("Export"))
            .on_hover_text(format!(
                "{OPENPOSE_IMAGE_FILE_NAME}, stance-openpose.json, stance-depth.png, stance-normal.png, stance-mask.png, stance-lines.png"
            ))
            .on_disabled_hover_text("an image is on its way");
        buttons.push(("export_control_maps", button.rect));
        button.clicked()
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
