//! The editor's UI fonts: subsets of egui's Ubuntu Light and Hack (see `fonts/README.md` and
//! `scripts/subset-fonts.py`), embedded instead of egui's whole default fonts to keep the
//! page's download small.

use std::sync::Arc;

use egui::{FontData, FontDefinitions, FontFamily};

const PROPORTIONAL: &str = "Ubuntu-Light-derivative-Stance";
const MONOSPACE: &str = "Hack-Regular-derivative-Stance";

/// The fonts every egui context of the editor uses: proportional text in the Ubuntu subset,
/// falling back to the Hack subset for the arrows, operators and superscripts Ubuntu lacks;
/// monospace in the Hack subset, falling back to the Ubuntu one (the order egui's defaults use).
/// In the page, what neither has is drawn with the browser's fonts (eframe's canvas glyphs).
pub fn definitions() -> FontDefinitions {
    let mut fonts = FontDefinitions::empty();
    fonts.font_data.insert(
        PROPORTIONAL.to_owned(),
        Arc::new(FontData::from_static(include_bytes!(
            "../fonts/Ubuntu-Light-derivative-Stance.ttf"
        ))),
    );
    fonts.font_data.insert(
        MONOSPACE.to_owned(),
        Arc::new(FontData::from_static(include_bytes!(
            "../fonts/Hack-Regular-derivative-Stance.ttf"
        ))),
    );
    fonts.families.insert(
        FontFamily::Proportional,
        vec![PROPORTIONAL.to_owned(), MONOSPACE.to_owned()],
    );
    fonts.families.insert(
        FontFamily::Monospace,
        vec![MONOSPACE.to_owned(), PROPORTIONAL.to_owned()],
    );
    fonts
}

/// Puts the editor's fonts in `context` (from its next frame on).
pub fn install(context: &egui::Context) {
    context.set_fonts(definitions());
}
