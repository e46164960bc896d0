//! The few raster primitives of the OpenPose skeleton image, drawn pixel for pixel as OpenCV
//! draws them without antialiasing (its default `LINE_8`): the common ControlNet
//! preprocessors (`controlnet-aux`, the ControlNet annotators) draw their skeletons with
//! OpenCV's `ellipse2Poly`, `fillConvexPoly`, `circle` and `line`, and a control image
//! should match theirs to the pixel. Re-implemented here from the algorithms of OpenCV's
//! `imgproc/src/drawing.cpp` (Apache-2.0): polygons are filled by two edges walked down in
//! 16.16 fixed point and outlined by 8-connected lines, discs by the midpoint circle, thick
//! lines as a filled quadrilateral with a disc at each end.

/// Fixed-point fraction bits of sub-pixel coordinates.
const XY_SHIFT: u32 = 16;
const XY_ONE: i64 = 1 << XY_SHIFT;
const HALF: i64 = XY_ONE >> 1;

/// A point in pixels, or in 16.16 fixed point where said.
pub(crate) type Point = (i64, i64);

/// An RGB image, rows top to bottom.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct Canvas {
    pub width: i64,
    pub height: i64,
    pub rgb: Vec<u8>,
}

impl Canvas {
    /// A black canvas.
    pub fn new(width: u32, height: u32) -> Canvas {
        Canvas {
            width: i64::from(width),
            height: i64::from(height),
            rgb: vec![0; width as usize * height as usize * 3],
        }
    }

    fn put(&mut self, (x, y): Point, color: [u8; 3]) {
        if (0..self.width).contains(&x) && (0..self.height).contains(&y) {
            let at = ((y * self.width + x) * 3) as usize;
            if let Some(pixel) = self.rgb.get_mut(at..at + 3) {
                pixel.copy_from_slice(&color);
            }
        }
    }

    /// Pixels `x1..=x2` of row `y`, clipped to the canvas.
    fn row(&mut self, y: i64, x1: i64, x2: i64, color: [u8; 3]) {
        if !(0..self.height).contains(&y) {
            return;
        }
        let (x1, x2) = (x1.max(0), x2.min(self.width - 1));
        for x in x1..=x2 {
            self.put((x, y), color);
        }
    }

    /// An 8-connected line between two pixels, walked from its left end (Bresenham, as
    /// OpenCV's `LineIterator`), clipped to the canvas first.
    pub fn line(&mut self, from: Point, to: Point, color: [u8; 3]) {
        let Some((mut from, mut to)) = clip_line(self.width, self.height, from, to) else {
            return;
        };
        if to.0 < from.0 {
            std::mem::swap(&mut from, &mut to);
        }
        let (dx, dy) = (to.0 - from.0, to.1 - from.1);
        let y_step = if dy < 0 { -1 } else { 1 };
        let dy = dy.abs();
        // The major axis is stepped every pixel, the minor one when the error says.
        let steep = dy > dx;
        let (major, minor) = if steep { (dy, dx) } else { (dx, dy) };
        let (major_step, minor_step) = if steep {
            ((0, y_step), (1, 0))
        } else {
            ((1, 0), (0, y_step))
        };
        let mut error = major - 2 * minor;
        let mut point = from;
        for _ in 0..=major {
            self.put(point, color);
            let diagonal = error < 0;
            error += -2 * minor + if diagonal { 2 * major } else { 0 };
            point.0 += major_step.0 + if diagonal { minor_step.0 } else { 0 };
            point.1 += major_step.1 + if diagonal { minor_step.1 } else { 0 };
        }
    }

    /// A line between two 16.16 fixed-point points (OpenCV's `Line2`: the outline of a
    /// polygon with sub-pixel vertices).
    fn fixed_line(&mut self, from: Point, to: Point, color: [u8; 3]) {
        let Some((mut from, mut to)) =
            clip_line(self.width << XY_SHIFT, self.height << XY_SHIFT, from, to)
        else {
            return;
        };
        let (ax, ay) = ((to.0 - from.0).abs(), (to.1 - from.1).abs());
        let horizontal = ax > ay;
        // Walk along the major axis in increasing order.
        if (horizontal && to.0 < from.0) || (!horizontal && to.1 < from.1) {
            std::mem::swap(&mut from, &mut to);
        }
        let (dx, dy) = (to.0 - from.0, to.1 - from.1);
        let (x_step, y_step, mut count) = if horizontal {
            (
                XY_ONE,
                (dy << XY_SHIFT) / (ax | 1),
                (to.0 - from.0) >> XY_SHIFT,
            )
        } else {
            (
                (dx << XY_SHIFT) / (ay | 1),
                XY_ONE,
                (to.1 - from.1) >> XY_SHIFT,
            )
        };
        let (mut x, mut y) = (from.0 + HALF, from.1 + HALF);
        self.put(
            ((to.0 + HALF) >> XY_SHIFT, (to.1 + HALF) >> XY_SHIFT),
            color,
        );
        if horizontal {
            x >>= XY_SHIFT;
            while count >= 0 {
                self.put((x, y >> XY_SHIFT), color);
                x += 1;
                y += y_step;
                count -= 1;
            }
        } else {
            y >>= XY_SHIFT;
            while count >= 0 {
                self.put((x >> XY_SHIFT, y), color);
                x += x_step;
                y += 1;
                count -= 1;
            }
        }
    }

    /// A filled convex polygon (OpenCV's `fillConvexPoly`), its vertices in pixels
    /// (`shift` 0) or in fixed point with `shift` fraction bits (16 at most).
    pub fn fill_convex(&mut self, vertices: &[Point], shift: u32, color: [u8; 3]) {
        let count = vertices.len();
        let (Some(&first), Some(&last)) = (vertices.first(), vertices.last()) else {
            return;
        };
        let up = XY_SHIFT - shift.min(XY_SHIFT);
        let delta = (1i64 << shift) >> 1;
        // The outline.
        let mut previous = (last.0 << up, last.1 << up);
        for &(x, y) in vertices {
            let point = (x << up, y << up);
            if shift == 0 {
                self.line(
                    (previous.0 >> XY_SHIFT, previous.1 >> XY_SHIFT),
                    (point.0 >> XY_SHIFT, point.1 >> XY_SHIFT),
                    color,
                );
            } else {
                self.fixed_line(previous, point, color);
            }
            previous = point;
        }
        // The top vertex (the first of the topmost) and the extent.
        let (mut top, mut y_min, mut y_max) = (0, first.1, first.1);
        let (mut x_min, mut x_max) = (first.0, first.0);
        for (index, &(x, y)) in vertices.iter().enumerate() {
            if y < y_min {
                y_min = y;
                top = index;
            }
            y_max = y_max.max(y);
            x_min = x_min.min(x);
            x_max = x_max.max(x);
        }
        let [x_min, x_max, y_min, y_max] =
            [x_min, x_max, y_min, y_max].map(|v| (v + delta) >> shift);
        if count < 3 || x_max < 0 || y_max < 0 || x_min >= self.width || y_min >= self.height {
            return;
        }
        let y_max = y_max.min(self.height - 1);
        // Two edges walked down from the top vertex, one each way round the polygon.
        let mut edges = [Edge::new(top, 1, y_min), Edge::new(top, count - 1, y_min)];
        let mut edges_left = count as i64;
        let mut y = y_min;
        loop {
            for edge in &mut edges {
                if y >= edge.y_end {
                    edge.advance(vertices, y, shift, delta, &mut edges_left);
                }
            }
            if edges_left < 0 {
                break;
            }
            if y >= 0 {
                let (left, right) = if edges[0].x > edges[1].x {
                    (edges[1].x, edges[0].x)
                } else {
                    (edges[0].x, edges[1].x)
                };
                let (x1, x2) = ((left + HALF) >> XY_SHIFT, (right + HALF) >> XY_SHIFT);
                if x2 >= 0 && x1 < self.width {
                    self.row(y, x1, x2, color);
                }
            }
            for edge in &mut edges {
                edge.x += edge.dx;
            }
            y += 1;
            if y > y_max {
                break;
            }
        }
    }

    /// A filled disc (OpenCV's `circle` with `thickness` -1: the midpoint circle's rows).
    pub fn disc(&mut self, (cx, cy): Point, radius: i64, color: [u8; 3]) {
        let (mut err, mut dx, mut dy, mut plus, mut minus) =
            (0i64, radius, 0i64, 1i64, 2 * radius - 1);
        while dx >= dy {
            self.row(cy - dy, cx - dx, cx + dx, color);
            self.row(cy + dy, cx - dx, cx + dx, color);
            self.row(cy - dx, cx - dy, cx + dy, color);
            self.row(cy + dx, cx - dy, cx + dy, color);
            dy += 1;
            err += plus;
            plus += 2;
            if err > 0 {
                err -= minus;
                dx -= 1;
                minus -= 2;
            }
        }
    }

    /// A line `thickness` pixels wide with round ends (OpenCV's `line`, thickness above 1).
    pub fn thick_line(&mut self, from: Point, to: Point, thickness: i64, color: [u8; 3]) {
        let (p0, p1) = (
            (from.0 << XY_SHIFT, from.1 << XY_SHIFT),
            (to.0 << XY_SHIFT, to.1 << XY_SHIFT),
        );
        let inverse_one = 1.0 / XY_ONE as f64;
        let dx = (p0.0 - p1.0) as f64 * inverse_one;
        let dy = (p1.1 - p0.1) as f64 * inverse_one;
        let length_squared = dx * dx + dy * dy;
        let odd = thickness & 1;
        let half_width = thickness << (XY_SHIFT - 1);
        if length_squared.abs() > f64::EPSILON {
            let r = (half_width as f64 + odd as f64 * XY_ONE as f64 * 0.5) / length_squared.sqrt();
            let across = (round_even(dy * r), round_even(dx * r));
            let corners = [
                (p0.0 + across.0, p0.1 + across.1),
                (p0.0 - across.0, p0.1 - across.1),
                (p1.0 - across.0, p1.1 - across.1),
                (p1.0 + across.0, p1.1 + across.1),
            ];
            self.fill_convex(&corners, XY_SHIFT, color);
        }
        let end_radius = (half_width + HALF) >> XY_SHIFT;
        for end in [p0, p1] {
            self.disc(
                ((end.0 + HALF) >> XY_SHIFT, (end.1 + HALF) >> XY_SHIFT),
                end_radius,
                color,
            );
        }
    }
}

/// One of the two edges a convex fill walks down.
#[derive(Debug, Clone, Copy)]
struct Edge {
    /// The vertex it left from.
    index: usize,
    /// Step round the polygon: 1, or the count less one (backwards).
    step: usize,
    /// Its x on the current row, 16.16.
    x: i64,
    /// Its x step per row, 16.16.
    dx: i64,
    /// The row of its lower vertex.
    y_end: i64,
}

impl Edge {
    fn new(index: usize, step: usize, y: i64) -> Edge {
        Edge {
            index,
            step,
            x: -XY_ONE,
            dx: 0,
            y_end: y,
        }
    }

    /// Moves on to the next polygon side that reaches below row `y`, each side counted once
    /// against both edges' budget.
    fn advance(&mut self, vertices: &[Point], y: i64, shift: u32, delta: i64, left: &mut i64) {
        let count = vertices.len();
        let up = XY_SHIFT - shift.min(XY_SHIFT);
        let mut from = self.index;
        let mut to = (from + self.step) % count;
        loop {
            let more = *left > 0;
            *left -= 1;
            if !more {
                return;
            }
            let (Some(&start), Some(&end)) = (vertices.get(from), vertices.get(to)) else {
                return;
            };
            let row_end = (end.1 + delta) >> shift;
            if row_end > y {
                let (xs, xe) = (start.0 << up, end.0 << up);
                self.y_end = row_end;
                self.dx = ((xe - xs) * 2 + (row_end - y)) / (2 * (row_end - y));
                self.x = xs;
                self.index = to;
                return;
            }
            from = to;
            to = (to + self.step) % count;
        }
    }
}

/// Rounds half to even, as OpenCV's `cvRound`.
pub(crate) fn round_even(value: f64) -> i64 {
    value.round_ties_even() as i64
}

/// The part of the segment inside a `width` x `height` area (OpenCV's `clipLine`: the
/// Cohen-Sutherland outcodes, integer intersections); `None` when it misses the area.
fn clip_line(width: i64, height: i64, mut p1: Point, mut p2: Point) -> Option<(Point, Point)> {
    if width <= 0 || height <= 0 {
        return None;
    }
    let (right, bottom) = (width - 1, height - 1);
    let code = |(x, y): Point| {
        i32::from(x < 0)
            + i32::from(x > right) * 2
            + i32::from(y < 0) * 4
            + i32::from(y > bottom) * 8
    };
    let (mut c1, mut c2) = (code(p1), code(p2));
    if (c1 & c2) == 0 && (c1 | c2) != 0 {
        if c1 & 12 != 0 {
            let a = if c1 < 8 { 0 } else { bottom };
            p1.0 += (a - p1.1) * (p2.0 - p1.0) / (p2.1 - p1.1);
            p1.1 = a;
            c1 = i32::from(p1.0 < 0) + i32::from(p1.0 > right) * 2;
        }
        if c2 & 12 != 0 {
            let a = if c2 < 8 { 0 } else { bottom };
            p2.0 += (a - p2.1) * (p2.0 - p1.0) / (p2.1 - p1.1);
            p2.1 = a;
            c2 = i32::from(p2.0 < 0) + i32::from(p2.0 > right) * 2;
        }
        if (c1 & c2) == 0 && (c1 | c2) != 0 {
            if c1 != 0 {
                let a = if c1 == 1 { 0 } else { right };
                p1.1 += (a - p1.0) * (p2.1 - p1.1) / (p2.0 - p1.0);
                p1.0 = a;
                c1 = 0;
            }
            if c2 != 0 {
                let a = if c2 == 1 { 0 } else { right };
                p2.1 += (a - p2.0) * (p2.1 - p1.1) / (p2.0 - p1.0);
                p2.0 = a;
                c2 = 0;
            }
        }
    }
    ((c1 | c2) == 0).then_some((p1, p2))
}

/// `sin` of whole degrees 0 to 450 as OpenCV tabulates it (`SinTable`: 7 decimals, single
/// precision).
fn table_sin(degrees: i64) -> f64 {
    let exact = (degrees as f64).to_radians().sin();
    (((exact * 1e7).round() / 1e7) as f32).into()
}

/// The polygon of a full ellipse (OpenCV's `ellipse2Poly` from 0 to 360 degrees in steps of
/// `step_degrees`): centre and semi-axes in pixels, turned by `angle_degrees`; repeated
/// consecutive points dropped.
pub(crate) fn ellipse_polygon(
    centre: Point,
    axes: Point,
    angle_degrees: i64,
    step_degrees: i64,
) -> Vec<Point> {
    let angle = angle_degrees.rem_euclid(360);
    let (cos_angle, sin_angle) = (table_sin(450 - angle), table_sin(angle));
    let (cx, cy) = (centre.0 as f64, centre.1 as f64);
    let mut points: Vec<Point> = Vec::with_capacity(362);
    let step = step_degrees.clamp(1, 180);
    let mut degrees = 0;
    while degrees < 360 + step {
        let at = degrees.min(360);
        let x = axes.0 as f64 * table_sin(450 - at);
        let y = axes.1 as f64 * table_sin(at);
        let point = (
            round_even(cx + x * cos_angle - y * sin_angle),
            round_even(cy + x * sin_angle + y * cos_angle),
        );
        if points.last() != Some(&point) {
            points.push(point);
        }
        degrees += step;
    }
    if points.len() == 1 {
        points = vec![centre, centre];
    }
    points
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lit(canvas: &Canvas) -> Vec<Point> {
        (0..canvas.height)
            .flat_map(|y| (0..canvas.width).map(move |x| (x, y)))
            .filter(|&(x, y)| canvas.rgb[((y * canvas.width + x) * 3) as usize] > 0)
            .collect()
    }

    #[test]
    fn a_disc_of_radius_4_has_opencvs_rows() {
        // OpenCV's filled circle of radius 4: rows of half-widths 4, 3, 3, 2, 0 from the
        // centre out (the midpoint circle), 49 pixels. Catches a radius off by one or rows
        // left out where the octants meet.
        let mut canvas = Canvas::new(16, 16);
        canvas.disc((8, 8), 4, [255, 0, 0]);
        let pixels = lit(&canvas);
        assert_eq!(pixels.len(), 9 + 7 * 2 + 7 * 2 + 5 * 2 + 2);
        for (dy, half) in [(0, 4), (1, 3), (2, 3), (3, 2), (4, 0)] {
            for y in [8 - dy, 8 + dy] {
                let row: Vec<i64> = pixels.iter().filter(|p| p.1 == y).map(|p| p.0).collect();
                assert_eq!(row, (8 - half..=8 + half).collect::<Vec<_>>(), "row {y}");
            }
        }
    }

    #[test]
    fn an_ellipse_polygon_closes_and_spans_its_axes() {
        let polygon = ellipse_polygon((50, 40), (20, 4), 0, 1);
        assert_eq!(polygon.first(), polygon.last());
        let xs: Vec<i64> = polygon.iter().map(|p| p.0).collect();
        let ys: Vec<i64> = polygon.iter().map(|p| p.1).collect();
        assert_eq!((xs.iter().min(), xs.iter().max()), (Some(&30), Some(&70)));
        assert_eq!((ys.iter().min(), ys.iter().max()), (Some(&36), Some(&44)));
        // Turned a quarter: the long axis is vertical.
        let turned = ellipse_polygon((50, 40), (20, 4), 90, 1);
        let ys: Vec<i64> = turned.iter().map(|p| p.1).collect();
        assert_eq!((ys.iter().min(), ys.iter().max()), (Some(&20), Some(&60)));
    }

    #[test]
    fn a_filled_polygon_covers_its_inside_and_outline_only() {
        let mut canvas = Canvas::new(20, 20);
        canvas.fill_convex(&[(2, 2), (12, 2), (12, 8), (2, 8)], 0, [9, 9, 9]);
        let pixels = lit(&canvas);
        assert_eq!(pixels.len(), 11 * 7);
        assert!(
            pixels
                .iter()
                .all(|&(x, y)| (2..=12).contains(&x) && (2..=8).contains(&y))
        );
    }

    #[test]
    fn lines_are_8_connected_and_clipped() {
        let mut canvas = Canvas::new(10, 10);
        canvas.line((0, 0), (9, 3), [1, 1, 1]);
        let pixels = lit(&canvas);
        assert_eq!(pixels.len(), 10, "one pixel per column: {pixels:?}");
        assert_eq!((pixels[0], pixels[pixels.len() - 1]), ((0, 0), (9, 3)));
        let mut clipped = Canvas::new(10, 10);
        clipped.line((-5, 5), (20, 5), [1, 1, 1]);
        assert_eq!(lit(&clipped).len(), 10);
        let mut thick = Canvas::new(20, 20);
        thick.thick_line((3, 10), (15, 10), 2, [1, 1, 1]);
        let rows: std::collections::BTreeSet<i64> = lit(&thick).iter().map(|p| p.1).collect();
        assert_eq!(rows.into_iter().collect::<Vec<_>>(), vec![9, 10, 11]);
    }
}
