//! The OpenPose skeleton image against its reference: the same keypoints drawn by
//! `controlnet-aux`'s own `draw_bodypose` and `draw_handpose` (scripts/openpose-reference.py,
//! PNGs committed in tests/fixtures/openpose/ with the keypoints they were drawn from), compared
//! pixel by pixel. No Python here: the fixtures are read as they are.

// A test crate: fixture helpers fail loudly on purpose.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use std::path::{Path, PathBuf};

use glam::DVec2;
use stance_render::{OpenPose, OpenPosePerson};

fn fixtures() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/fixtures/openpose")
}

/// The keypoints of an OpenPose JSON file (pixels; confidence 0 is missing).
fn read_keypoints(path: &Path) -> OpenPose {
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
    let points = |value: &serde_json::Value, into: &mut [Option<DVec2>]| {
        let numbers: Vec<f64> = value
            .as_array()
            .unwrap()
            .iter()
            .map(|n| n.as_f64().unwrap())
            .collect();
        assert_eq!(numbers.len(), into.len() * 3, "{}", path.display());
        for (slot, triple) in into.iter_mut().zip(numbers.chunks(3)) {
            *slot = (triple[2] > 0.0).then(|| DVec2::new(triple[0], triple[1]));
        }
    };
    let people = json["people"]
        .as_array()
        .unwrap()
        .iter()
        .map(|person| {
            let mut seen = OpenPosePerson::EMPTY;
            points(&person["pose_keypoints_2d"], &mut seen.body);
            points(&person["hand_left_keypoints_2d"], &mut seen.left_hand);
            points(&person["hand_right_keypoints_2d"], &mut seen.right_hand);
            seen
        })
        .collect();
    let side = |key: &str| u32::try_from(json[key].as_u64().unwrap()).unwrap();
    OpenPose {
        size_px: [side("canvas_width"), side("canvas_height")],
        people,
    }
}

/// A PNG as RGB bytes and its size.
fn read_rgb(path: &Path) -> ([u32; 2], Vec<u8>) {
    let bytes = std::fs::read(path).unwrap();
    let mut reader = png::Decoder::new(std::io::Cursor::new(bytes))
        .read_info()
        .unwrap();
    let mut data = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut data).unwrap();
    let channels = match info.color_type {
        png::ColorType::Rgb => 3,
        png::ColorType::Rgba => 4,
        other => panic!("{}: {other:?}", path.display()),
    };
    let rgb = data[..info.buffer_size()]
        .chunks(channels)
        .flat_map(|pixel| [pixel[0], pixel[1], pixel[2]])
        .collect();
    ([info.width, info.height], rgb)
}

/// How the drawing differs from the reference: pixels differing at all, the largest
/// difference of a channel, and the colours the reference has that the drawing lacks.
struct Difference {
    pixels: usize,
    differing: usize,
    max_channel: u8,
    colours_lacking: Vec<[u8; 3]>,
}

fn compare(drawn_rgba: &[u8], reference_rgb: &[u8]) -> Difference {
    let drawn: Vec<[u8; 3]> = drawn_rgba.chunks(4).map(|p| [p[0], p[1], p[2]]).collect();
    let reference: Vec<[u8; 3]> = reference_rgb
        .chunks(3)
        .map(|p| [p[0], p[1], p[2]])
        .collect();
    assert_eq!(drawn.len(), reference.len());
    let mut differing = 0;
    let mut max_channel = 0;
    for (a, b) in drawn.iter().zip(&reference) {
        let channel = (0..3).map(|c| a[c].abs_diff(b[c])).max().unwrap_or(0);
        if channel > 0 {
            differing += 1;
            max_channel = max_channel.max(channel);
        }
    }
    let colours = |pixels: &[[u8; 3]]| -> std::collections::BTreeSet<[u8; 3]> {
        pixels.iter().copied().collect()
    };
    let drawn_colours = colours(&drawn);
    let colours_lacking = colours(&reference)
        .into_iter()
        .filter(|colour| !drawn_colours.contains(colour))
        .collect();
    Difference {
        pixels: reference.len(),
        differing,
        max_channel,
        colours_lacking,
    }
}

#[test]
fn the_skeleton_image_matches_controlnet_aux_pixel_for_pixel() {
    // Catches: a limb or hand bone in the wrong colour or order, a limb's ellipse the wrong
    // size or angle, points of the wrong radius, a hand drawn for the wrong side, rounding of
    // positions other than the preprocessors' (each shows as many differing pixels). The
    // drawing re-implements OpenCV's rasterisation, so the two should agree exactly; a
    // tolerance of 0.1 % of the pixels is left for the float corner cases of the ellipse
    // (OpenCV's single-precision sine table, rounding half to even), and no colour of the
    // reference may be missing (no limb or bone left out).
    let mut names: Vec<PathBuf> = std::fs::read_dir(fixtures())
        .unwrap()
        .map(|entry| entry.unwrap().path())
        .filter(|path| path.extension().is_some_and(|e| e == "json"))
        .collect();
    names.sort();
    assert!(names.len() >= 7, "fixtures: {names:?}");
    for json in names {
        let pose = read_keypoints(&json);
        let ([width, height], reference) = read_rgb(&json.with_extension("png"));
        assert_eq!(pose.size_px, [width, height], "{}", json.display());
        let difference = compare(&pose.draw(), &reference);
        eprintln!(
            "{}: {width}x{height}, {} of {} pixels differ, at most by {}",
            json.file_name().unwrap().to_string_lossy(),
            difference.differing,
            difference.pixels,
            difference.max_channel
        );
        assert!(
            difference.differing * 1000 <= difference.pixels,
            "{}: {} pixels differ",
            json.display(),
            difference.differing
        );
        assert!(
            difference.colours_lacking.is_empty(),
            "{}: colours of the reference not drawn: {:?}",
            json.display(),
            difference.colours_lacking
        );
    }
}
