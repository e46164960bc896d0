//! Line art from a depth map and a normal map of the same view (both as the renderer draws
//! them, [`crate::Shading`]): white lines on black, as the ControlNet line-art models take
//! them (`controlnet-aux`'s line-art preprocessors invert their drawing to that). Drawn on the
//! CPU:
//!
//! - **silhouettes**: the figure's pixels beside the background;
//! - **occluding contours**: where the depth jumps between neighbours by more than
//!   [`DEPTH_JUMP`] of the map's range (one body part in front of another), on the nearer
//!   side;
//! - **creases**: where the surface turns by more than [`CREASE_DEGREES`] between neighbours
//!   (where two body parts meet).
//!
//! Lines are one pixel wide, grown by a pixel each way per 1024 pixels of the image's smaller
//! side (3 pixels wide at 1024).

/// The depth difference between neighbours that makes a contour, as a fraction of the depth
/// map's range (white to black).
pub const DEPTH_JUMP: f32 = 0.03;
/// The turn of the surface between neighbours that makes a crease (degrees).
pub const CREASE_DEGREES: f32 = 40.0;
/// A pixel is the figure's where its normal map is brighter than this in any channel (the
/// background is black; antialiased edges blend with it).
const FIGURE_LEVEL: u8 = 64;

/// The line art of a `width` x `height` view from its depth map and normal map (RGBA rows,
/// top first, as read back): RGBA, opaque, white lines on black. `None` when a map is not
/// `width * height * 4` bytes.
pub fn line_art(depth_rgba: &[u8], normal_rgba: &[u8], width: u32, height: u32) -> Option<Vec<u8>> {
    let (w, h) = (width as usize, height as usize);
    let count = w.checked_mul(h)?;
    if depth_rgba.len() != count * 4 || normal_rgba.len() != count * 4 {
        return None;
    }
    let figure: Vec<bool> = normal_rgba
        .chunks_exact(4)
        .map(|p| p[..3].iter().any(|&c| c > FIGURE_LEVEL))
        .collect();
    let depth: Vec<f32> = depth_rgba
        .chunks_exact(4)
        .map(|p| f32::from(p[0]) / 255.0)
        .collect();
    let normal: Vec<[f32; 3]> = normal_rgba
        .chunks_exact(4)
        .map(|p| {
            let n = [0, 1, 2].map(|c| f32::from(p[c]) / 255.0 * 2.0 - 1.0);
            let length = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt().max(1e-6);
            n.map(|c| c / length)
        })
        .collect();
    let crease_cos = CREASE_DEGREES.to_radians().cos();
    let mut line = vec![false; count];
    for y in 0..h {
        for x in 0..w {
            let at = y * w + x;
            if !figure[at] {
                continue;
            }
            let neighbours = [
                (x > 0).then(|| at - 1),
                (x + 1 < w).then(|| at + 1),
                (y > 0).then(|| at - w),
                (y + 1 < h).then(|| at + w),
            ];
            line[at] = neighbours.into_iter().flatten().any(|other| {
                if !figure[other] {
                    return true;
                }
                let nearer = depth[at] - depth[other] > DEPTH_JUMP;
                let [a, b] = [normal[at], normal[other]];
                let turn = a[0] * b[0] + a[1] * b[1] + a[2] * b[2] < crease_cos;
                nearer || turn
            });
        }
    }
    let thick = widen(&line, w, h, w.min(h) / 1024);
    Some(
        thick
            .iter()
            .flat_map(|&on| {
                if on {
                    [255, 255, 255, 255]
                } else {
                    [0, 0, 0, 255]
                }
            })
            .collect(),
    )
}

/// `line` with each set pixel grown to a square of `radius` pixels each way.
fn widen(line: &[bool], w: usize, h: usize, radius: usize) -> Vec<bool> {
    if radius == 0 {
        return line.to_vec();
    }
    let mut thick = vec![false; line.len()];
    for (at, _) in line.iter().enumerate().filter(|(_, on)| **on) {
        let (x, y) = (at % w, at / w);
        for yy in y.saturating_sub(radius)..=(y + radius).min(h - 1) {
            for xx in x.saturating_sub(radius)..=(x + radius).min(w - 1) {
                thick[yy * w + xx] = true;
            }
        }
    }
    thick
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A `size` x `size` view of a square facing the camera at depth level `far`, with a
    /// smaller square in front of it at level `near` whose normals turn by `turn` (x of the
    /// normal).
    fn maps(size: usize, near: u8, far: u8, turn: f32) -> (Vec<u8>, Vec<u8>) {
        let mut depth = vec![0u8; size * size * 4];
        let mut normal = vec![0u8; size * size * 4];
        let encode = |n: [f32; 3]| n.map(|c| ((c + 1.0) * 0.5 * 255.0).round() as u8);
        for y in 0..size {
            for x in 0..size {
                let at = (y * size + x) * 4;
                depth[at + 3] = 255;
                normal[at + 3] = 255;
                let outer = (4..size - 4).contains(&x) && (4..size - 4).contains(&y);
                let inner = (10..20).contains(&x) && (10..20).contains(&y);
                if !outer {
                    continue;
                }
                let (level, n) = if inner {
                    (near, [turn, 0.0, (1.0 - turn * turn).sqrt()])
                } else {
                    (far, [0.0, 0.0, 1.0])
                };
                depth[at..at + 3].fill(level);
                let rgb = encode(n);
                normal[at..at + 3].copy_from_slice(&rgb);
            }
        }
        (depth, normal)
    }

    fn lit(image: &[u8]) -> usize {
        image.chunks(4).filter(|p| p[0] == 255).count()
    }

    #[test]
    fn silhouettes_contours_and_creases_make_lines_and_a_smooth_face_does_not() {
        // Catches: lines inside a flat face (thresholds too fine), an occluding part or a
        // crease without a line, lines on the background side.
        let size = 32;
        // One flat square: only its outline, the 24 x 24 square's border (92 pixels).
        let (depth, normal) = maps(size, 200, 200, 0.0);
        let flat = line_art(&depth, &normal, 32, 32).unwrap();
        assert_eq!(lit(&flat), 92);
        assert_eq!(&flat[..4], &[0, 0, 0, 255], "the background stays black");
        // A part in front: its outline too (on the nearer side: 10 x 10 border, 36 pixels).
        let (depth, normal) = maps(size, 240, 200, 0.0);
        assert_eq!(lit(&line_art(&depth, &normal, 32, 32).unwrap()), 92 + 36);
        // The same depth but the surface turned by 60 degrees: a crease, on both sides.
        let (depth, normal) = maps(size, 200, 200, 60f32.to_radians().sin());
        assert!(lit(&line_art(&depth, &normal, 32, 32).unwrap()) >= 92 + 36 * 2);
        assert!(line_art(&depth, &normal, 31, 32).is_none());
    }
}
