//! BVH out: the clip's skeleton and frames, with H-Anim names, in a chosen Euler order and
//! unit.

use std::fmt::Write as _;

use glam::{DQuat, DVec3};

use super::EulerOrder;
use crate::clip::Clip;

/// How [`write_bvh`] writes a clip.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BvhWriteOptions {
    /// The rotation channel order of every joint (default ZXY).
    pub order: EulerOrder,
    /// Metres per file unit (1 = metres, 0.01 = centimetres).
    pub metres_per_unit: f64,
    /// Mapped joints take their H-Anim names (default true); others keep theirs.
    pub hanim_names: bool,
}

impl Default for BvhWriteOptions {
    fn default() -> Self {
        Self {
            order: EulerOrder::Zxy,
            metres_per_unit: 1.0,
            hanim_names: true,
        }
    }
}

/// Writes a clip as BVH text.
///
/// - Joints in depth-first order (the order [`super::read_bvh`] produces), named with their
///   H-Anim names when mapped (unique: a repeated name gets `_2`, `_3`...).
/// - The root has 6 channels; other joints 3 rotation channels, plus 3 position channels
///   where a frame's translation differs from the offset by more than 1e-9 m. Position
///   channels hold absolute local translations and the joint's OFFSET is the first frame's
///   translation (MotionBuilder's convention, which the reader recognises exactly).
/// - A leaf joint named `..._End` that never moves (as the reader makes of an `End Site`) is
///   written back as an `End Site`.
/// - `Frames:` is the frame count, `Frame Time:` the clip's, printed to round-trip exactly;
///   angles in degrees with 9 decimals, lengths with 9 decimals of the unit.
pub fn write_bvh(clip: &Clip, options: &BvhWriteOptions) -> String {
    let n = clip.joints.len();
    let unit = if options.metres_per_unit.is_finite() && options.metres_per_unit > 0.0 {
        options.metres_per_unit
    } else {
        1.0
    };
    let mut children = vec![Vec::new(); n];
    let mut roots = Vec::new();
    for (i, j) in clip.joints.iter().enumerate() {
        match j.parent {
            Some(p) if p < i => children[p].push(i),
            _ => roots.push(i),
        }
    }
    let translation = |f: usize, i: usize| {
        clip.frames
            .get(f)
            .and_then(|fr| fr.translations.get(i))
            .copied()
            .unwrap_or(clip.joints[i].offset)
    };
    let rotation = |f: usize, i: usize| {
        clip.frames
            .get(f)
            .and_then(|fr| fr.rotations.get(i))
            .copied()
            .unwrap_or(DQuat::IDENTITY)
    };
    let moves = |i: usize| {
        (0..clip.frames.len()).any(|f| {
            (translation(f, i) - clip.joints[i].offset)
                .abs()
                .max_element()
                > 1e-9
        })
    };
    let rotates = |i: usize| {
        (0..clip.frames.len()).any(|f| {
            let q = rotation(f, i);
            DVec3::new(q.x, q.y, q.z).length() > 1e-12
        })
    };

    // Names.
    let mut names: Vec<String> = Vec::with_capacity(n);
    for (i, j) in clip.joints.iter().enumerate() {
        let base = match clip.mapping.hanim_of(i) {
            Some(h) if options.hanim_names => h.to_owned(),
            _ => j.name.split_whitespace().collect::<Vec<_>>().join(" "),
        };
        let base = if base.is_empty() {
            format!("joint{i}")
        } else {
            base
        };
        let mut name = base.clone();
        let mut k = 2;
        while names.contains(&name) {
            name = format!("{base}_{k}");
            k += 1;
        }
        names.push(name);
    }

    // Joints in depth-first order with their channels.
    struct Out {
        joint: usize,
        position: bool,
        end_site: bool,
    }
    let mut order: Vec<Out> = Vec::with_capacity(n);
    let mut text = String::from("HIERARCHY\n");
    let mut stack: Vec<(usize, usize, bool)> = roots.iter().rev().map(|&r| (r, 0, false)).collect();
    // (joint, depth, closing)
    while let Some((i, depth, closing)) = stack.pop() {
        let pad = "\t".repeat(depth);
        if closing {
            let _ = writeln!(text, "{pad}}}");
            continue;
        }
        let is_root = clip.joints[i].parent.is_none() || roots.contains(&i);
        let end_site = !is_root
            && children[i].is_empty()
            && clip.joints[i].name.ends_with("_End")
            && !moves(i)
            && !rotates(i);
        let position = is_root || moves(i);
        let offset = if position && !clip.frames.is_empty() {
            translation(0, i)
        } else {
            clip.joints[i].offset
        };
        let o = offset / unit;
        if end_site {
            let _ = writeln!(text, "{pad}End Site\n{pad}{{");
        } else {
            let kw = if is_root { "ROOT" } else { "JOINT" };
            let _ = writeln!(text, "{pad}{kw} {}\n{pad}{{", names[i]);
        }
        let _ = writeln!(text, "{pad}\tOFFSET {:.9} {:.9} {:.9}", o.x, o.y, o.z);
        if !end_site {
            let rot = options.order.channel_names().join(" ");
            if position {
                let _ = writeln!(
                    text,
                    "{pad}\tCHANNELS 6 Xposition Yposition Zposition {rot}"
                );
            } else {
                let _ = writeln!(text, "{pad}\tCHANNELS 3 {rot}");
            }
        }
        order.push(Out {
            joint: i,
            position,
            end_site,
        });
        stack.push((i, depth, true));
        for &c in children[i].iter().rev() {
            stack.push((c, depth + 1, false));
        }
    }
    let _ = writeln!(text, "MOTION\nFrames: {}", clip.frames.len());
    let _ = writeln!(text, "Frame Time: {}", clip.frame_time);
    for f in 0..clip.frames.len() {
        let mut first = true;
        for o in &order {
            if o.end_site {
                continue;
            }
            let mut values = Vec::with_capacity(6);
            if o.position {
                let t: DVec3 = translation(f, o.joint) / unit;
                values.extend([t.x, t.y, t.z]);
            }
            let a = options.order.from_quat(rotation(f, o.joint));
            values.extend(a.map(f64::to_degrees));
            for v in values {
                if !first {
                    text.push(' ');
                }
                first = false;
                let v = if v == 0.0 { 0.0 } else { v };
                let _ = write!(text, "{v:.9}");
            }
        }
        text.push('\n');
    }
    text
}
