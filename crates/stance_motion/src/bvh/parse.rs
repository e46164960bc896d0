//! The BVH text: hierarchy and motion rows, in file units, with every size checked
//! against [`BvhLimits`] before anything is allocated for it.

use glam::DVec3;

use super::{BvhError, BvhLimits};

/// One channel of a joint.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Channel {
    /// Position along an axis (0 = X).
    Position(usize),
    /// Rotation about an axis (0 = X), degrees.
    Rotation(usize),
}

impl Channel {
    fn parse(token: &str) -> Option<Self> {
        Some(match token.to_ascii_lowercase().as_str() {
            "xposition" => Self::Position(0),
            "yposition" => Self::Position(1),
            "zposition" => Self::Position(2),
            "xrotation" => Self::Rotation(0),
            "yrotation" => Self::Rotation(1),
            "zrotation" => Self::Rotation(2),
            _ => return None,
        })
    }

    pub(crate) fn name(self) -> &'static str {
        match self {
            Self::Position(0) => "Xposition",
            Self::Position(1) => "Yposition",
            Self::Position(_) => "Zposition",
            Self::Rotation(0) => "Xrotation",
            Self::Rotation(1) => "Yrotation",
            Self::Rotation(_) => "Zrotation",
        }
    }
}

/// A joint as written in the file.
#[derive(Debug, Clone)]
pub(crate) struct RawJoint {
    pub name: String,
    pub parent: Option<usize>,
    pub offset: DVec3,
    pub channels: Vec<Channel>,
    /// An `End Site` (named `<parent>_End`).
    pub end_site: bool,
    has_offset: bool,
    line: usize,
}

/// The parsed file.
#[derive(Debug, Clone)]
pub(crate) struct RawBvh {
    pub joints: Vec<RawJoint>,
    pub frame_time: f64,
    /// `Frames:` as written, and its line.
    pub declared_frames: usize,
    pub frames_line: usize,
    /// Rows read.
    pub rows: usize,
    /// `rows * channel_count` values, row by row.
    pub values: Vec<f64>,
    pub channel_count: usize,
}

fn err(line: usize, field: impl Into<String>, message: impl Into<String>) -> BvhError {
    BvhError::Syntax {
        line,
        field: field.into(),
        message: message.into(),
    }
}

fn limit(line: usize, field: impl Into<String>, message: impl Into<String>) -> BvhError {
    BvhError::Limit {
        line,
        field: field.into(),
        message: message.into(),
    }
}

/// A token as shown in messages: escaped, at most 24 characters.
pub(crate) fn show(token: &str) -> String {
    let mut s: String = token.chars().take(24).collect();
    if token.chars().count() > 24 {
        s.push_str("...");
    }
    format!("{s:?}")
}

/// Splits one whitespace-free token into numbers: `0.0-7.5` is `0.0`, `-7.5`;
/// `1.5e-3-2` is `1.5e-3`, `-2`. `Err(())` when it is not a run of numbers.
pub(crate) fn split_numbers(token: &str, out: &mut Vec<f64>) -> Result<(), ()> {
    let b = token.as_bytes();
    let mut i = 0;
    while i < b.len() {
        let start = i;
        if matches!(b.get(i), Some(b'+' | b'-')) {
            i += 1;
        }
        let digits_before = count_digits(b, i);
        i += digits_before;
        let mut digits_after = 0;
        if b.get(i) == Some(&b'.') {
            i += 1;
            digits_after = count_digits(b, i);
            i += digits_after;
        }
        if digits_before + digits_after == 0 {
            return Err(());
        }
        if matches!(b.get(i), Some(b'e' | b'E')) {
            let mut j = i + 1;
            if matches!(b.get(j), Some(b'+' | b'-')) {
                j += 1;
            }
            let exp = count_digits(b, j);
            if exp == 0 {
                return Err(());
            }
            i = j + exp;
        }
        // The next number must start with a sign (numbers glued together).
        if i < b.len() && !matches!(b.get(i), Some(b'+' | b'-')) {
            return Err(());
        }
        let text = token.get(start..i).ok_or(())?;
        let v: f64 = text.parse().map_err(|_| ())?;
        out.push(v);
    }
    Ok(())
}

fn count_digits(b: &[u8], from: usize) -> usize {
    b.get(from..)
        .map_or(0, |r| r.iter().take_while(|c| c.is_ascii_digit()).count())
}

/// Lines with their 1-based numbers; `\n`, `\r\n` and a lone `\r` all end a line.
fn lines(text: &str) -> Vec<(usize, &str)> {
    let mut out = Vec::new();
    let mut rest = text;
    let mut n = 1usize;
    while !rest.is_empty() {
        let end = rest.find(['\r', '\n']).unwrap_or(rest.len());
        let (line, tail) = rest.split_at(end);
        out.push((n, line));
        n = n.saturating_add(1);
        rest = if let Some(t) = tail.strip_prefix("\r\n") {
            t
        } else {
            tail.get(1..).unwrap_or("")
        };
    }
    out
}

/// Whether the joint on top of the stack is waiting for its `{`.
struct Pending {
    joint: usize,
}

pub(crate) fn parse(bytes: &[u8], limits: &BvhLimits) -> Result<RawBvh, BvhError> {
    if bytes.len() > limits.max_bytes {
        return Err(limit(
            1,
            "file",
            format!(
                "{} bytes, over the limit of {} bytes",
                bytes.len(),
                limits.max_bytes
            ),
        ));
    }
    let text = String::from_utf8_lossy(bytes);
    let lines = lines(&text);
    let mut it = lines
        .iter()
        .filter(|(_, l)| !l.trim().is_empty())
        .peekable();
    let last_line = lines.last().map_or(1, |(n, _)| *n);

    // HIERARCHY
    match it.next() {
        Some((n, l)) => {
            let first = l.split_whitespace().next().unwrap_or("");
            let first = first.trim_start_matches('\u{feff}');
            if !first.eq_ignore_ascii_case("hierarchy") {
                return Err(err(
                    *n,
                    "HIERARCHY",
                    format!("expected HIERARCHY, got {}", show(first)),
                ));
            }
            if l.split_whitespace().nth(1).is_some() {
                return Err(err(*n, "HIERARCHY", "unexpected text after HIERARCHY"));
            }
        }
        None => {
            return Err(err(1, "HIERARCHY", "expected HIERARCHY, got an empty file"));
        }
    }

    let mut joints: Vec<RawJoint> = Vec::new();
    let mut stack: Vec<usize> = Vec::new();
    let mut pending: Option<Pending> = None;
    let mut channel_count = 0usize;
    let mut closed_root = false;
    let mut motion_line = None;

    'lines: for &(n, line) in it.by_ref() {
        let toks: Vec<&str> = line.split_whitespace().collect();
        let mut i = 0;
        while let Some(&tok) = toks.get(i) {
            let kw = tok.to_ascii_lowercase();
            if closed_root && kw != "motion" {
                return Err(err(
                    n,
                    "MOTION",
                    format!("expected MOTION after the hierarchy, got {}", show(tok)),
                ));
            }
            if pending.is_some() && kw != "{" {
                return Err(err(n, "{", format!("expected '{{', got {}", show(tok))));
            }
            match kw.as_str() {
                "root" | "joint" | "end" => {
                    let keyword = if kw == "end" {
                        "End Site"
                    } else if kw == "root" {
                        "ROOT"
                    } else {
                        "JOINT"
                    };
                    let mut rest: Vec<&str> = toks.get(i + 1..).unwrap_or(&[]).to_vec();
                    let opened = rest.last() == Some(&"{");
                    if opened {
                        rest.pop();
                    }
                    let parent = stack.last().copied();
                    let name = if kw == "end" {
                        if !rest.first().is_some_and(|s| s.eq_ignore_ascii_case("site"))
                            || rest.len() != 1
                        {
                            return Err(err(n, "End Site", "expected 'End Site'"));
                        }
                        let Some(p) = parent.and_then(|p| joints.get(p)) else {
                            return Err(err(n, "End Site", "an End Site outside any joint"));
                        };
                        if p.end_site {
                            return Err(err(n, "End Site", "an End Site inside an End Site"));
                        }
                        format!("{}_End", p.name)
                    } else {
                        if rest.is_empty() {
                            return Err(err(n, keyword, "the joint has no name"));
                        }
                        rest.join(" ")
                    };
                    if kw == "root" && (!joints.is_empty()) {
                        return Err(err(
                            n,
                            "ROOT",
                            "a second ROOT (only one skeleton per file is read)",
                        ));
                    }
                    if kw != "root" && parent.is_none() {
                        return Err(err(n, keyword, "a joint outside the ROOT"));
                    }
                    if parent
                        .and_then(|p| joints.get(p))
                        .is_some_and(|p| p.end_site)
                    {
                        return Err(err(n, keyword, "a joint inside an End Site"));
                    }
                    if joints.len() >= limits.max_joints {
                        return Err(limit(
                            n,
                            keyword,
                            format!("more than {} joints", limits.max_joints),
                        ));
                    }
                    joints.push(RawJoint {
                        name,
                        parent,
                        offset: DVec3::ZERO,
                        channels: Vec::new(),
                        end_site: kw == "end",
                        has_offset: false,
                        line: n,
                    });
                    let index = joints.len() - 1;
                    if opened {
                        stack.push(index);
                    } else {
                        pending = Some(Pending { joint: index });
                    }
                    continue 'lines;
                }
                "{" => {
                    let Some(p) = pending.take() else {
                        return Err(err(n, "{", "a '{' that opens no joint"));
                    };
                    stack.push(p.joint);
                    i += 1;
                }
                "}" => {
                    let Some(j) = stack.pop() else {
                        return Err(err(n, "}", "a '}' that closes no joint"));
                    };
                    if let Some(joint) = joints.get(j)
                        && !joint.has_offset
                    {
                        return Err(err(
                            n,
                            "OFFSET",
                            format!(
                                "joint {} (line {}) has no OFFSET",
                                show(&joint.name),
                                joint.line
                            ),
                        ));
                    }
                    if stack.is_empty() {
                        closed_root = true;
                    }
                    i += 1;
                }
                "offset" => {
                    let Some(joint) = stack.last().and_then(|&j| joints.get_mut(j)) else {
                        return Err(err(n, "OFFSET", "an OFFSET outside any joint"));
                    };
                    if joint.has_offset {
                        return Err(err(n, "OFFSET", "a second OFFSET for the joint"));
                    }
                    let mut v = Vec::with_capacity(3);
                    let mut k = i + 1;
                    while v.len() < 3 {
                        let Some(t) = toks.get(k) else {
                            return Err(err(
                                n,
                                "OFFSET",
                                format!("expected 3 numbers, got {}", v.len()),
                            ));
                        };
                        if split_numbers(t, &mut v).is_err() {
                            return Err(err(
                                n,
                                "OFFSET",
                                format!("expected a number, got {}", show(t)),
                            ));
                        }
                        k += 1;
                    }
                    let [x, y, z] = [v[0], v[1], v[2]];
                    if v.len() > 3 {
                        return Err(err(n, "OFFSET", "expected 3 numbers, got more"));
                    }
                    let o = DVec3::new(x, y, z);
                    if !o.is_finite() {
                        return Err(err(n, "OFFSET", "a number that is not finite"));
                    }
                    joint.offset = o;
                    joint.has_offset = true;
                    i = k;
                }
                "channels" => {
                    let Some(joint) = stack.last().and_then(|&j| joints.get_mut(j)) else {
                        return Err(err(n, "CHANNELS", "CHANNELS outside any joint"));
                    };
                    if joint.end_site {
                        return Err(err(n, "CHANNELS", "an End Site has no channels"));
                    }
                    if !joint.channels.is_empty() {
                        return Err(err(n, "CHANNELS", "a second CHANNELS for the joint"));
                    }
                    let count = toks.get(i + 1).copied().unwrap_or("");
                    let Ok(count) = count.parse::<usize>() else {
                        return Err(err(
                            n,
                            "CHANNELS",
                            format!("expected the channel count, got {}", show(count)),
                        ));
                    };
                    if count != 3 && count != 6 {
                        return Err(err(
                            n,
                            "CHANNELS",
                            format!("expected 3 or 6 channels, got {count}"),
                        ));
                    }
                    let names = toks.get(i + 2..).unwrap_or(&[]);
                    if names.len() != count {
                        return Err(err(
                            n,
                            "CHANNELS",
                            format!("{count} channels declared, {} named", names.len()),
                        ));
                    }
                    let mut channels = Vec::with_capacity(count);
                    for name in names {
                        let Some(c) = Channel::parse(name) else {
                            return Err(err(
                                n,
                                "CHANNELS",
                                format!("unknown channel {}", show(name)),
                            ));
                        };
                        if channels.contains(&c) {
                            return Err(err(
                                n,
                                "CHANNELS",
                                format!("channel {} given twice", c.name()),
                            ));
                        }
                        channels.push(c);
                    }
                    let rotations = channels
                        .iter()
                        .filter(|c| matches!(c, Channel::Rotation(_)))
                        .count();
                    if rotations != 3 && rotations != 0 {
                        return Err(err(
                            n,
                            "CHANNELS",
                            format!("expected 0 or 3 rotation channels, got {rotations}"),
                        ));
                    }
                    channel_count = channel_count.saturating_add(count);
                    if channel_count > limits.max_channels {
                        return Err(limit(
                            n,
                            "CHANNELS",
                            format!("more than {} channels", limits.max_channels),
                        ));
                    }
                    joint.channels = channels;
                    continue 'lines;
                }
                "motion" => {
                    if !closed_root {
                        let field = if joints.is_empty() { "ROOT" } else { "}" };
                        return Err(err(
                            n,
                            field,
                            format!(
                                "MOTION before the hierarchy is complete ({} joint(s) still open)",
                                stack.len()
                            ),
                        ));
                    }
                    if toks.len() > 1 {
                        return Err(err(n, "MOTION", "unexpected text after MOTION"));
                    }
                    motion_line = Some(n);
                    break 'lines;
                }
                "hierarchy" => {
                    return Err(err(n, "HIERARCHY", "a second HIERARCHY"));
                }
                _ => {
                    let field = if joints.is_empty() {
                        "ROOT"
                    } else {
                        "hierarchy"
                    };
                    return Err(err(n, field, format!("unknown keyword {}", show(tok))));
                }
            }
        }
    }
    let Some(motion_line) = motion_line else {
        if let Some(&j) = stack.last() {
            let name = joints.get(j).map_or("", |j| j.name.as_str());
            return Err(err(
                last_line,
                "}",
                format!(
                    "expected '}}' to close joint {}, got the end of the file",
                    show(name)
                ),
            ));
        }
        if pending.is_some() {
            return Err(err(last_line, "{", "expected '{', got the end of the file"));
        }
        if joints.is_empty() {
            return Err(err(
                last_line,
                "ROOT",
                "expected ROOT, got the end of the file",
            ));
        }
        return Err(err(
            last_line,
            "MOTION",
            "expected MOTION, got the end of the file",
        ));
    };

    // Frames:
    let Some(&(frames_line, line)) = it.next() else {
        return Err(err(
            motion_line,
            "Frames:",
            "expected 'Frames:', got the end of the file",
        ));
    };
    let after = strip_keyword(line, &["frames"]).ok_or_else(|| {
        err(
            frames_line,
            "Frames:",
            format!("expected 'Frames:', got {}", show(line.trim())),
        )
    })?;
    let declared: u64 = after.parse().map_err(|_| {
        err(
            frames_line,
            "Frames:",
            format!("expected a frame count, got {}", show(after)),
        )
    })?;
    let declared = usize::try_from(declared)
        .ok()
        .filter(|&d| d <= limits.max_frames)
        .ok_or_else(|| {
            limit(
                frames_line,
                "Frames:",
                format!("{declared} frames, over the limit of {}", limits.max_frames),
            )
        })?;

    // Frame Time:
    let Some(&(time_line, line)) = it.next() else {
        return Err(err(
            frames_line,
            "Frame Time:",
            "expected 'Frame Time:', got the end of the file",
        ));
    };
    let after = strip_keyword(line, &["frame", "time"])
        .or_else(|| strip_keyword(line, &["frametime"]))
        .ok_or_else(|| {
            err(
                time_line,
                "Frame Time:",
                format!("expected 'Frame Time:', got {}", show(line.trim())),
            )
        })?;
    let mut v = Vec::new();
    if split_numbers(after, &mut v).is_err() || v.len() != 1 {
        return Err(err(
            time_line,
            "Frame Time:",
            format!("expected a number of seconds, got {}", show(after)),
        ));
    }
    let frame_time = v.first().copied().unwrap_or(0.0);
    if !(frame_time.is_finite() && frame_time > 0.0) {
        return Err(err(
            time_line,
            "Frame Time:",
            format!("the frame time must be positive and finite, got {after}"),
        ));
    }

    // The rows.
    let mut values = Vec::with_capacity(
        declared
            .saturating_mul(channel_count)
            .min(limits.max_values)
            .min(bytes.len() / 2 + 1),
    );
    let mut rows = 0usize;
    for &(n, line) in it {
        if rows >= declared.saturating_add(1) || (rows >= declared && channel_count > 0) {
            // Past the declared count: only one more row is tolerated, and only numbers.
            let mut probe = Vec::new();
            let numeric = line
                .split_whitespace()
                .all(|t| split_numbers(t, &mut probe).is_ok());
            if !numeric || rows > declared {
                return Err(err(
                    n,
                    "after the last frame",
                    format!(
                        "unexpected {} after the {} frames declared (line {frames_line})",
                        show(line.trim()),
                        declared
                    ),
                ));
            }
        }
        if channel_count == 0 {
            return Err(err(
                n,
                "motion row",
                "the skeleton has no channels, so the rows must be empty",
            ));
        }
        if rows >= limits.max_frames {
            return Err(limit(
                n,
                "motion row",
                format!("more than {} frames", limits.max_frames),
            ));
        }
        let start = values.len();
        if start.saturating_add(channel_count) > limits.max_values {
            return Err(limit(
                n,
                "motion row",
                format!("more than {} motion values", limits.max_values),
            ));
        }
        for tok in line.split_whitespace() {
            let before = values.len();
            if split_numbers(tok, &mut values).is_err() {
                let k = before - start;
                return Err(err(
                    n,
                    value_field(&joints, k, rows),
                    format!("expected a number, got {}", show(tok)),
                ));
            }
            for k in before..values.len() {
                if values.get(k).is_some_and(|v| !v.is_finite()) {
                    return Err(err(
                        n,
                        value_field(&joints, k - start, rows),
                        format!("{} is not finite", show(tok)),
                    ));
                }
            }
            if values.len() - start > channel_count {
                return Err(err(
                    n,
                    "motion row",
                    format!(
                        "frame {}: expected {channel_count} values (one per channel), got more",
                        rows + 1
                    ),
                ));
            }
        }
        let got = values.len() - start;
        if got != channel_count {
            return Err(err(
                n,
                "motion row",
                format!(
                    "frame {}: expected {channel_count} values (one per channel), got {got}",
                    rows + 1
                ),
            ));
        }
        rows += 1;
    }
    if channel_count == 0 {
        rows = declared;
    } else if rows.saturating_add(1) < declared {
        return Err(err(
            frames_line,
            "Frames:",
            format!("{declared} frames declared, the file has {rows}"),
        ));
    }
    Ok(RawBvh {
        joints,
        frame_time,
        declared_frames: declared,
        frames_line,
        rows,
        values,
        channel_count,
    })
}

/// `motion value 17 of frame 3 (channel Xrotation of LeftArm)` for the 0-based value
/// `k` of the 0-based row `row`.
fn value_field(joints: &[RawJoint], k: usize, row: usize) -> String {
    let mut left = k;
    let mut channel = None;
    for j in joints {
        if left < j.channels.len() {
            channel = j.channels.get(left).map(|c| (c.name(), j.name.as_str()));
            break;
        }
        left -= j.channels.len();
    }
    match channel {
        Some((c, j)) => format!(
            "motion value {} of frame {} (channel {c} of {j})",
            k + 1,
            row + 1
        ),
        None => format!("motion value {} of frame {}", k + 1, row + 1),
    }
}

/// The text after the keywords (case-insensitive, any spacing) and an optional colon.
fn strip_keyword<'a>(line: &'a str, words: &[&str]) -> Option<&'a str> {
    let mut rest = line.trim();
    for w in words {
        let head = rest.get(..w.len())?;
        if !head.eq_ignore_ascii_case(w) {
            return None;
        }
        rest = rest.get(w.len()..)?.trim_start();
    }
    let rest = rest.strip_prefix(':').unwrap_or(rest);
    Some(rest.trim())
}
