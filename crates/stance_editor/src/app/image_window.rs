//! *File > Save image…*: a small window with the image's size, background and overlays; Save
//! asks the model for the image (seen through the viewport's camera), which downloads it as
//! `stance-posture.png` once the GPU has drawn and returned it.

use stance_render::{ImageOptions, MAX_IMAGE_SIDE_PX};

use super::ButtonRects;
use super::viewport_panel::ViewportPanel;
use crate::image::{IMAGE_FILE_NAME, ImageRequest};

/// The *Save image* window and the options it keeps between uses.
#[derive(Debug, Default)]
pub(crate) struct ImageWindow {
    /// Whether the window shows.
    pub open: bool,
    /// Size, transparency, overlays.
    pub options: ImageOptions,
}

impl ImageWindow {
    /// Shows the window when open; Save asks `viewport` for the image, seen through its camera.
    pub(super) fn show(
        &mut self,
        ctx: &egui::Context,
        viewport: &mut ViewportPanel,
        buttons: &mut ButtonRects,
    ) {
        let mut open = self.open;
        let mut save = false;
        egui::Window::new("Save image")
            .open(&mut open)
            .resizable(false)
            .collapsible(false)
            .show(ctx, |ui| {
                let options = &mut self.options;
                size_row(ui, &mut options.size_px, viewport);
                ui.checkbox(&mut options.transparent, "Transparent background");
                ui.checkbox(&mut options.overlays, "Overlays (floor grid, task goals)");
                let busy = viewport.image.is_busy();
                let button = ui
                    .add_enabled(
                        viewport.has_gpu() && !busy,
                        egui::Button::new(format!("Save {IMAGE_FILE_NAME}")),
                    )
                    .on_disabled_hover_text(if busy {
                        "an image is on its way"
                    } else {
                        "the 3D view has no GPU"
                    });
                buttons.push(("save_image", button.rect));
                save = button.clicked();
            });
        if save {
            let camera = viewport.camera;
            viewport.image.request(ImageRequest {
                options: self.options,
                camera,
                map: None,
            });
            open = false;
        }
        self.open = open;
    }
}

/// An exported image's size in pixels (each side 1 to [`MAX_IMAGE_SIDE_PX`]), and a button
/// that takes the viewport's.
pub(super) fn size_row(ui: &mut egui::Ui, size_px: &mut [u32; 2], viewport: &ViewportPanel) {
    let sides = 1..=MAX_IMAGE_SIDE_PX;
    ui.horizontal(|ui| {
        ui.label("Size");
        ui.add(egui::DragValue::new(&mut size_px[0]).range(sides.clone()));
        ui.label("×");
        ui.add(egui::DragValue::new(&mut size_px[1]).range(sides));
        ui.label("px");
    });
    if ui.button("Viewport size").clicked() {
        *size_px = viewport.size_px.map(|side| side.max(1));
    }
}
