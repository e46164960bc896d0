//! The editor's subset fonts (stance_editor::fonts) cover what the editor writes and what its
//! users name things in. The subsets leave most of Unicode out to keep the page small: a panel
//! that starts writing a sign outside them would show a missing-glyph box in the native editor
//! (the page falls back to the browser's fonts, drawn differently).

use std::path::Path;

use egui::{FontFamily, FontId};

fn context() -> egui::Context {
    let context = egui::Context::default();
    stance_editor::fonts::install(&context);
    // Fonts are set up when a frame begins.
    let mut output = context.run_ui(egui::RawInput::default(), |_| {});
    output.textures_delta.clear();
    context
}

fn missing(context: &egui::Context, family: &FontFamily, text: &str) -> Vec<char> {
    let font = FontId::new(14.0, family.clone());
    context.fonts_mut(|fonts| {
        let mut missing: Vec<char> = text
            .chars()
            .filter(|c| !c.is_control() && !fonts.has_glyph(&font, *c))
            .collect();
        missing.sort_unstable();
        missing.dedup();
        missing
    })
}

/// Every character outside ASCII in the code (comments left out) of the crates whose words reach
/// the panels (labels, notices, reasons, reports). Catches: a subset regenerated with a narrower range, or
/// a new label with a sign (≤, λ, →) the subset left out.
#[test]
fn every_character_the_sources_write_has_a_glyph() {
    let crates = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let mut text = String::new();
    for name in [
        "stance_editor",
        "stance_web",
        "stance_document",
        "stance_ik",
        "stance_hanim",
        "stance_motion",
        "stance_mocap",
        "stance_asset",
    ] {
        let mut pending = vec![crates.join(name).join("src")];
        while let Some(dir) = pending.pop() {
            for entry in std::fs::read_dir(&dir).expect("a source folder") {
                let path = entry.expect("a folder entry").path();
                if path.is_dir() {
                    pending.push(path);
                } else if path.extension().is_some_and(|e| e == "rs") {
                    let source = std::fs::read_to_string(&path).expect("a source file");
                    for line in source.lines() {
                        let line = line.trim_start();
                        if line.starts_with("//") {
                            continue;
                        }
                        let code = line.split(" // ").next().unwrap_or(line);
                        text.extend(code.chars().filter(|c| !c.is_ascii()));
                    }
                }
            }
        }
    }
    assert!(
        text.contains('°') && text.contains('…') && text.contains('×'),
        "the scan found the degree sign, the ellipsis and the times sign the panels write"
    );
    let context = context();
    for family in [FontFamily::Proportional, FontFamily::Monospace] {
        assert_eq!(
            missing(&context, &family, &text),
            Vec::<char>::new(),
            "{family:?} has no glyph for these characters of the sources"
        );
    }
}

/// Names in the scripts the subset keeps: Western and Central European Latin, Greek and
/// Cyrillic, with the signs of units, ranges and directions.
#[test]
fn names_in_european_scripts_have_glyphs() {
    let names = "Zoë Ærøskøbing Łódź Șerban Ţară Čapek Ğüneş Straße Ελληνικά Привет Україна \
                 “quoted” ‘pose’ – — 90° ±5° ×2 ≤ ≥ ≠ → ← ↑ ↓ ½ µm π λ Σ";
    let context = context();
    assert_eq!(
        missing(&context, &FontFamily::Proportional, names),
        Vec::<char>::new()
    );
    // The monospace face falls back to the proportional one, as egui's defaults do.
    assert_eq!(
        missing(&context, &FontFamily::Monospace, names),
        Vec::<char>::new()
    );
}

/// The subsets are subsets: a CJK name has no glyph in them (the page draws it with the
/// browser's fonts). Catches the test above passing because egui's whole default fonts came
/// back (a feature turned on by another crate), which would also put 319 KiB back in the page.
#[test]
fn the_fonts_are_the_subsets() {
    let context = context();
    assert_eq!(
        missing(&context, &FontFamily::Proportional, "日本"),
        vec!['日', '本']
    );
    let names = context.fonts(|fonts| {
        fonts
            .definitions()
            .font_data
            .keys()
            .cloned()
            .collect::<Vec<_>>()
    });
    assert_eq!(
        names,
        [
            "Hack-Regular-derivative-Stance",
            "Ubuntu-Light-derivative-Stance"
        ]
    );
}
