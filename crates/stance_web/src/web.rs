//! Browser glue (wasm32 only).

use eframe::wasm_bindgen::{self, prelude::*};
use stance_editor::{BackendSummary, HostHooks, StanceApp};

/// Tells the page about the editor's progress through attributes on `<body>` and by hiding
/// the loading indicator: `data-backend`, `data-adapter`, `data-first-frame-ms`.
struct PageHooks;

impl HostHooks for PageHooks {
    fn first_frame_rendered(&self, backend: &BackendSummary) {
        let Some(window) = web_sys::window() else {
            return;
        };
        let elapsed_ms = window
            .performance()
            .map_or(0.0, |performance| performance.now());
        let Some(body) = window.document().and_then(|document| document.body()) else {
            return;
        };
        let _ = body.set_attribute("data-backend", &backend.backend);
        let _ = body.set_attribute("data-adapter", &backend.adapter);
        let _ = body.set_attribute("data-first-frame-ms", &format!("{elapsed_ms:.0}"));
        if let Some(loading) = window
            .document()
            .and_then(|document| document.get_element_by_id("loading"))
        {
            let _ = loading.set_attribute("hidden", "");
        }
        log::info!(
            "first frame after {elapsed_ms:.0} ms on {} ({})",
            backend.backend,
            backend.adapter
        );
    }
}

/// The running editor, held by the page.
#[wasm_bindgen]
pub struct WebHandle {
    runner: eframe::WebRunner,
}

#[wasm_bindgen]
impl WebHandle {
    /// Installs the panic hook and logger; call `start` next.
    #[wasm_bindgen(constructor)]
    #[allow(clippy::new_without_default)]
    pub fn new() -> Self {
        console_error_panic_hook::set_once();
        eframe::WebLogger::init(log::LevelFilter::Info).ok();
        Self {
            runner: eframe::WebRunner::new(),
        }
    }

    /// Starts the editor on `canvas`; rejects with a readable reason when no graphics
    /// backend can start.
    #[wasm_bindgen]
    pub async fn start(&self, canvas: web_sys::HtmlCanvasElement) -> Result<(), JsValue> {
        self.runner
            .start(
                canvas,
                eframe::WebOptions::default(),
                Box::new(|creation| {
                    if creation.wgpu_render_state.is_none() {
                        return Err("neither WebGPU nor WebGL2 could start".into());
                    }
                    Ok(Box::new(StanceApp::new(creation, Box::new(PageHooks))))
                }),
            )
            .await
    }

    /// Stops the editor and frees its resources.
    #[wasm_bindgen]
    pub fn destroy(&self) {
        self.runner.destroy();
    }

    /// The panic message, if the editor has crashed.
    #[wasm_bindgen]
    pub fn panic_message(&self) -> Option<String> {
        self.runner.panic_summary().map(|summary| summary.message())
    }
}
