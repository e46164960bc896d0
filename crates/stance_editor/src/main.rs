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
            let mut app =
                stance_editor::StanceApp::new(creation, Box::new(stance_editor::NoHostHooks))?;
            app.open_startup(None);
            Ok(Box::new(app))
        }),
    )
}

#[cfg(target_arch = "wasm32")]
fn main() {}
