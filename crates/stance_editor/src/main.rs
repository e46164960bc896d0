//! Native development shell of the editor: `cargo run -p stance_editor`.

#[cfg(not(target_arch = "wasm32"))]
fn main() -> eframe::Result {
    let options = eframe::NativeOptions {
        viewport: egui::ViewportBuilder::default()
            .with_title("Stance")
            .with_inner_size([1280.0, 800.0]),
        ..Default::default()
    };
    eframe::run_native(
        "Stance",
        options,
        Box::new(|creation| {
            Ok(Box::new(stance_editor::StanceApp::new(
                creation,
                Box::new(stance_editor::NoHostHooks),
            )))
        }),
    )
}

#[cfg(target_arch = "wasm32")]
fn main() {}
