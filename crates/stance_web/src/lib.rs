//! The wasm entry of Stance: `WebHandle` starts the editor on a canvas of the page that
//! `web/` serves, tells the page when the first frame is up, and which backend runs it.

pub mod accessibility;
#[cfg(target_arch = "wasm32")]
mod web;

#[cfg(target_arch = "wasm32")]
pub use web::WebHandle;
