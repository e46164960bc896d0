//! The OpenPose skeleton image, drawn on the CPU as the ControlNet preprocessors draw it
//! (`controlnet-aux`'s `open_pose/util.py`, `draw_bodypose` and `draw_handpose`, the
//! conventions of the ControlNet 1.0/1.1 OpenPose models):
//!
//! - black background;
//! - each of 17 limbs a filled ellipse between its two keypoints (half-length the
//!   half-distance, half-width [`STICK_WIDTH_PX`], its angle rounded down to whole degrees),
//!   in the limb's colour times 0.6 (painted over, no blending);
//! - each body keypoint a disc of radius [`POINT_RADIUS_PX`] in its colour;
//! - then the left hand, then the right: 20 bones as lines 2 px wide coloured round the hue
//!   circle (bone `i` at hue `i / 20`), and each hand keypoint a blue disc of radius 4; hand
//!   points in the image's first row or column are not drawn (the preprocessors take a zero
//!   coordinate for a point not found).
//!
//! Positions are taken as the preprocessors take them, as fractions of the image scaled back
//! to pixels and rounded down.

use glam::DVec2;

use crate::openpose::{OpenPose, OpenPosePerson};
use crate::raster::{Canvas, ellipse_polygon, round_even};

/// Half-width of a limb's ellipse (pixels).
pub const STICK_WIDTH_PX: i64 = 4;
/// Radius of a keypoint's disc (pixels).
pub const POINT_RADIUS_PX: i64 = 4;
/// Width of a hand bone's line (pixels).
const HAND_LINE_WIDTH_PX: i64 = 2;

/// The limbs, as pairs of COCO-18 keypoint indices, in drawing order (each drawn in the
/// colour of the same index in [`BODY_COLORS`]): neck to each shoulder, the arms, neck to
/// each hip and the legs, neck to nose, nose to eyes to ears.
pub const LIMBS: [(usize, usize); 17] = [
    (1, 2),
    (1, 5),
    (2, 3),
    (3, 4),
    (5, 6),
    (6, 7),
    (1, 8),
    (8, 9),
    (9, 10),
    (1, 11),
    (11, 12),
    (12, 13),
    (1, 0),
    (0, 14),
    (14, 16),
    (0, 15),
    (15, 17),
];

/// The colours of the keypoints (and of the limb of the same index), RGB: round the hue circle
/// from red in steps of 85.
pub const BODY_COLORS: [[u8; 3]; 18] = [
    [255, 0, 0],
    [255, 85, 0],
    [255, 170, 0],
    [255, 255, 0],
    [170, 255, 0],
    [85, 255, 0],
    [0, 255, 0],
    [0, 255, 85],
    [0, 255, 170],
    [0, 255, 255],
    [0, 170, 255],
    [0, 85, 255],
    [0, 0, 255],
    [85, 0, 255],
    [170, 0, 255],
    [255, 0, 255],
    [255, 0, 170],
    [255, 0, 85],
];

/// The bones of a hand, as pairs of its 21 keypoint indices: wrist to each digit's first
/// point, then along the digit.
pub const HAND_BONES: [(usize, usize); 20] = [
    (0, 1),
    (1, 2),
    (2, 3),
    (3, 4),
    (0, 5),
    (5, 6),
    (6, 7),
    (7, 8),
    (0, 9),
    (9, 10),
    (10, 11),
    (11, 12),
    (0, 13),
    (13, 14),
    (14, 15),
    (15, 16),
    (0, 17),
    (17, 18),
    (18, 19),
    (19, 20),
];

/// The colour of a hand keypoint.
pub const HAND_POINT_COLOR: [u8; 3] = [0, 0, 255];

impl OpenPose {
    /// The skeleton image: RGBA, opaque, `size_px` large, rows top to bottom.
    pub fn draw(&self) -> Vec<u8> {
        let [width, height] = self.size_px;
        let mut canvas = Canvas::new(width, height);
        let size = DVec2::new(f64::from(width), f64::from(height));
        for person in &self.people {
            draw_body(&mut canvas, person, size);
            for hand in [&person.left_hand, &person.right_hand] {
                draw_hand(&mut canvas, hand, size);
            }
        }
        canvas
            .rgb
            .chunks_exact(3)
            .flat_map(|rgb| [rgb[0], rgb[1], rgb[2], 255])
            .collect()
    }
}

/// A pixel position as the preprocessors compute it: the fraction of the image (what their
/// keypoints hold) times the image's size.
fn scaled(point: DVec2, size: DVec2) -> DVec2 {
    DVec2::new(point.x / size.x * size.x, point.y / size.y * size.y)
}

fn draw_body(canvas: &mut Canvas, person: &OpenPosePerson, size: DVec2) {
    for (&(a, b), color) in LIMBS.iter().zip(BODY_COLORS) {
        let (Some(Some(from)), Some(Some(to))) = (person.body.get(a), person.body.get(b)) else {
            continue;
        };
        let (from, to) = (scaled(*from, size), scaled(*to, size));
        let middle = DVec2::new((from.x + to.x) / 2.0, (from.y + to.y) / 2.0);
        let length = ((from.y - to.y).powi(2) + (from.x - to.x).powi(2)).sqrt();
        // Python's math.degrees divides by pi / 180.
        let angle = (from.y - to.y).atan2(from.x - to.x) / (std::f64::consts::PI / 180.0);
        let polygon = ellipse_polygon(
            (middle.x as i64, middle.y as i64),
            ((length / 2.0) as i64, STICK_WIDTH_PX),
            angle as i64,
            1,
        );
        let dimmed = color.map(|c| (f64::from(c) * 0.6) as u8);
        canvas.fill_convex(&polygon, 0, dimmed);
    }
    for (point, color) in person.body.iter().zip(BODY_COLORS) {
        if let Some(point) = point {
            let point = scaled(*point, size);
            canvas.disc((point.x as i64, point.y as i64), POINT_RADIUS_PX, color);
        }
    }
}

/// The colour of hand bone `index`: hue `index / 20` at full saturation and value, as
/// matplotlib's `hsv_to_rgb` computes it, times 255 rounded half to even (OpenCV's conversion
/// of a colour to bytes).
pub fn hand_bone_color(index: usize) -> [u8; 3] {
    let hue = index as f64 / HAND_BONES.len() as f64;
    let (saturation, value) = (1.0f64, 1.0f64);
    let sector = (hue * 6.0) as i64;
    let f = hue * 6.0 - sector as f64;
    let p = value * (1.0 - saturation);
    let q = value * (1.0 - saturation * f);
    let t = value * (1.0 - saturation * (1.0 - f));
    let (r, g, b) = match sector.rem_euclid(6) {
        0 => (value, t, p),
        1 => (q, value, p),
        2 => (p, value, t),
        3 => (p, q, value),
        4 => (t, p, value),
        _ => (value, p, q),
    };
    [r, g, b].map(|c| round_even(c * 255.0).clamp(0, 255) as u8)
}

fn draw_hand(canvas: &mut Canvas, hand: &[Option<DVec2>], size: DVec2) {
    if hand.iter().all(Option::is_none) {
        return;
    }
    // A point in the first row or column counts as not found.
    let pixel = |point: &Option<DVec2>| {
        let point = scaled((*point)?, size);
        let (x, y) = (point.x as i64, point.y as i64);
        (x >= 1 && y >= 1).then_some((x, y))
    };
    for (index, &(a, b)) in HAND_BONES.iter().enumerate() {
        let (Some(Some(from)), Some(Some(to))) = (hand.get(a).map(pixel), hand.get(b).map(pixel))
        else {
            continue;
        };
        canvas.thick_line(from, to, HAND_LINE_WIDTH_PX, hand_bone_color(index));
    }
    for point in hand {
        if let Some(at) = pixel(point) {
            canvas.disc(at, POINT_RADIUS_PX, HAND_POINT_COLOR);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_hand_colours_go_round_the_hue_circle_from_red() {
        assert_eq!(hand_bone_color(0), [255, 0, 0]);
        // Hue 0.05 * 6 = 0.3 of the way from red to yellow: green 0.3 * 255 = 76.5, whose
        // float error decides the rounding (matplotlib's t = 1 - (1 - f)).
        let second = hand_bone_color(1);
        assert_eq!((second[0], second[2]), (255, 0));
        assert!(second[1] == 76 || second[1] == 77);
        assert_eq!(hand_bone_color(10), [0, 255, 255]);
    }

    #[test]
    fn a_limb_is_drawn_dimmed_under_full_colour_points() {
        let mut person = OpenPosePerson::EMPTY;
        person.body[1] = Some(DVec2::new(50.0, 20.0));
        person.body[2] = Some(DVec2::new(20.0, 20.0));
        let image = OpenPose {
            size_px: [64, 40],
            people: vec![person],
        }
        .draw();
        let at = |x: usize, y: usize| &image[(y * 64 + x) * 4..(y * 64 + x) * 4 + 4];
        // Neck to right shoulder is limb 0, red times 0.6; the neck's own point is orange.
        assert_eq!(at(35, 20), &[153, 0, 0, 255]);
        assert_eq!(at(35, 23), &[153, 0, 0, 255]);
        assert_eq!(at(35, 26), &[0, 0, 0, 255]);
        assert_eq!(at(50, 20), &[255, 85, 0, 255]);
        assert_eq!(at(20, 20), &[255, 170, 0, 255]);
    }
}
