#!/usr/bin/env python3
"""Makes the editor's two UI fonts (crates/stance_editor/fonts/) from egui's default fonts.

egui's `default_fonts` embed Ubuntu Light and Hack whole, with their TrueType hinting: 671 KB
of the page's wasm, 319 KiB gzipped. Stance ships subsets instead: the scripts its users write
names in (Latin with its extensions and Vietnamese, Greek, Cyrillic), the punctuation, symbols,
arrows and mathematical signs its panels and egui's widgets draw, and no hinting instructions
(egui hints the outlines itself with skrifa's auto-hinter when a font has none). The result is
about 90 KiB gzipped; `stance_editor::fonts` embeds it and a test checks that every character
the editor's sources write is covered.

Not run by the build or the tests: the subsets are committed beside their licences. Run it
again (after `pip install fonttools`) when egui's fonts change or a panel needs a character
outside the ranges below:

    python3 scripts/subset-fonts.py [EPAINT_DEFAULT_FONTS_DIR]

The directory defaults to the epaint_default_fonts crate in cargo's registry. The Ubuntu Font
Licence (2c) asks a modified version that is not substantially changed to keep the name and add
"derivative X": the subset is named "Ubuntu Light derivative Stance"; Hack's MIT licence asks
nothing of the name, and the subset is renamed the same way to tell it from the original.
"""

import glob
import os
import sys

from fontTools import subset
from fontTools.ttLib import TTFont

# Scripts users write in (names of documents, poses, avatars, joints) and the signs the UI uses.
TEXT_RANGES = [
    (0x0020, 0x007E),  # Basic Latin
    (0x00A0, 0x00FF),  # Latin-1 Supplement
    (0x0100, 0x017F),  # Latin Extended-A
    (0x0180, 0x024F),  # Latin Extended-B
    (0x0250, 0x02AF),  # IPA extensions
    (0x02B0, 0x02FF),  # spacing modifier letters
    (0x0300, 0x036F),  # combining diacritical marks
    (0x0370, 0x03FF),  # Greek and Coptic
    (0x0400, 0x052F),  # Cyrillic and its supplement
    (0x1E00, 0x1EFF),  # Latin Extended Additional (what Ubuntu has of it)
    (0x2000, 0x206F),  # general punctuation
    (0x2070, 0x209F),  # superscripts and subscripts
    (0x20A0, 0x20CF),  # currency symbols
    (0x2100, 0x214F),  # letterlike symbols
    (0x2150, 0x218F),  # number forms
    (0x2190, 0x21FF),  # arrows
    (0x2200, 0x22FF),  # mathematical operators
    (0x2300, 0x23FF),  # miscellaneous technical (egui's keyboard signs)
    (0x2500, 0x257F),  # box drawing
    (0x25A0, 0x25FF),  # geometric shapes
    (0xFB00, 0xFB06),  # Latin ligatures
    (0xFFFD, 0xFFFD),  # the replacement character
]
# The monospace face: egui falls back to Ubuntu for what it lacks (as with egui's defaults).
# Stance's panels write no monospace text (egui's code labels and editors would), but Hack
# also gives the proportional face the arrows, operators and superscripts Ubuntu lacks.
MONOSPACE_RANGES = [
    (0x0020, 0x007E),
    (0x00A0, 0x00FF),
    (0x2000, 0x206F),
    (0x2070, 0x209F),
    (0x2190, 0x21FF),
    (0x2200, 0x22FF),
    (0x2300, 0x23FF),
]

FONTS = [
    ("Ubuntu-Light.ttf", "Ubuntu-Light-derivative-Stance.ttf", "Ubuntu", "Light", TEXT_RANGES),
    ("Hack-Regular.ttf", "Hack-Regular-derivative-Stance.ttf", "Hack", "Regular", MONOSPACE_RANGES),
]


def rename(font, family, style):
    """Names the subset "FAMILY derivative Stance" in every name record that names the font."""
    derived = f"{family} derivative Stance"
    full = f"{family} {style} derivative Stance" if style != "Regular" else derived
    postscript = f"{family}-{style}-derivative-Stance".replace(" ", "")
    names = {1: derived, 3: f"{postscript};subset", 4: full, 6: postscript, 16: derived}
    for record in font["name"].names:
        if record.nameID in names:
            record.string = names[record.nameID]


def main():
    if len(sys.argv) > 1:
        source = sys.argv[1]
    else:
        found = glob.glob(
            os.path.expanduser("~/.cargo/registry/src/*/epaint_default_fonts-*/fonts")
        )
        if not found:
            sys.exit("epaint_default_fonts is not in cargo's registry: build the editor once")
        source = sorted(found)[-1]
    out = os.path.join(os.path.dirname(__file__), "..", "crates", "stance_editor", "fonts")
    for original, target, family, style, ranges in FONTS:
        options = subset.Options()
        options.hinting = False
        options.layout_features = ["*"]
        options.name_IDs = ["*"]
        options.name_languages = ["*"]
        options.drop_tables += ["DSIG", "TTFA", "hdmx", "VDMX", "LTSH"]
        font = TTFont(os.path.join(source, original))
        subsetter = subset.Subsetter(options)
        subsetter.populate(unicodes=[c for lo, hi in ranges for c in range(lo, hi + 1)])
        subsetter.subset(font)
        rename(font, family, style)
        path = os.path.join(out, target)
        font.save(path)
        print(f"{path}: {os.path.getsize(path)} bytes, {len(font.getBestCmap())} characters")


if __name__ == "__main__":
    main()
