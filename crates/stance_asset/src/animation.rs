//! glTF animations: the keyframes read from a file ([`Animation`], in
//! [`Avatar::animations`]), their sampling as the glTF 2.0 specification says (Appendix C:
//! LINEAR with slerp for rotations, STEP, CUBICSPLINE Hermite splines with tangents), and
//! their conversion to a motion [`Clip`] on the avatar's skeleton ([`clip_from_animation`]).

use glam::{DMat3, DMat4, DQuat, DVec3, DVec4};
use stance_motion::{Clip, ClipFrame, ClipJoint};

use crate::AssetError;
use crate::model::{Avatar, Trs, orthonormalize};

/// The node property a channel animates.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
pub enum AnimationPath {
    /// `translation` (3 components, file units).
    Translation,
    /// `rotation` (4 components, quaternion `x, y, z, w`).
    Rotation,
    /// `scale` (3 components).
    Scale,
}

impl AnimationPath {
    /// Numbers per value: 3, or 4 for rotations.
    pub fn components(self) -> usize {
        match self {
            AnimationPath::Rotation => 4,
            AnimationPath::Translation | AnimationPath::Scale => 3,
        }
    }

    /// The glTF name of the path.
    pub fn name(self) -> &'static str {
        match self {
            AnimationPath::Translation => "translation",
            AnimationPath::Rotation => "rotation",
            AnimationPath::Scale => "scale",
        }
    }
}

/// How values between keys are computed (glTF `sampler.interpolation`).
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Hash, Default, serde::Serialize, serde::Deserialize,
)]
pub enum Interpolation {
    /// Linear; spherical linear (slerp, the shorter way) for rotations.
    #[default]
    Linear,
    /// The value of the last key at or before the time.
    Step,
    /// Cubic Hermite spline; each key stores an in-tangent, a value and an out-tangent.
    CubicSpline,
}

/// One animated property of one node: a glTF channel with its sampler.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct AnimationChannel {
    /// The node animated (index into [`Avatar::nodes`]).
    pub node: usize,
    /// The property animated.
    pub path: AnimationPath,
    /// How values between keys are computed.
    pub interpolation: Interpolation,
    /// Key times in seconds: finite, the first >= 0, strictly increasing, at least one
    /// (two for CUBICSPLINE).
    #[serde(with = "crate::transfer::pod_vec")]
    pub times: Vec<f64>,
    /// Per key [`AnimationPath::components`] numbers (rotation keys normalised); for
    /// CUBICSPLINE per key three such groups: in-tangent, value, out-tangent.
    #[serde(with = "crate::transfer::pod_vec")]
    pub values: Vec<f64>,
}

/// A glTF animation read from a file.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Animation {
    /// Its name in the file (`animation{i}` when it has none).
    pub name: String,
    /// Its index in the file's `animations` array (a malformed animation is skipped, so the
    /// position in [`Avatar::animations`] may differ).
    pub index: usize,
    /// The channels on node transforms, in file order (morph-target `weights` channels are
    /// left out with a warning).
    pub channels: Vec<AnimationChannel>,
    /// The last key time of all channels, in seconds (the animation plays from 0 to it).
    pub duration: f64,
}

/// Relative tolerance under which a sample time is a key time (times are stored as `f32`
/// in files, relative error under 6e-8): a frame that falls on a key takes the key's value
/// exactly.
pub const KEY_TIME_TOLERANCE: f64 = 1e-6;

/// Most frames [`clip_from_animation`] makes (over 9 hours at 30 fps).
pub const MAX_CLIP_FRAMES: usize = 1 << 20;

/// Most joint transforms (frames x joints) [`clip_from_animation`] makes (2 GiB of clip).
pub const MAX_CLIP_TRANSFORMS: usize = 1 << 26;

fn near(a: f64, b: f64) -> bool {
    (a - b).abs() <= KEY_TIME_TOLERANCE * a.abs().max(1.0)
}

impl AnimationChannel {
    fn stride(&self) -> usize {
        let c = self.path.components();
        if self.interpolation == Interpolation::CubicSpline {
            3 * c
        } else {
            c
        }
    }

    /// Group `group` (0 in-tangent, 1 value, 2 out-tangent; 0 the value unless CUBICSPLINE)
    /// of key `k`; zeros where the data is short.
    fn group(&self, k: usize, group: usize) -> DVec4 {
        let c = self.path.components();
        let at = k.saturating_mul(self.stride()).saturating_add(group * c);
        let get = |i: usize| -> f64 {
            if i < c {
                at.checked_add(i)
                    .and_then(|j| self.values.get(j))
                    .copied()
                    .unwrap_or(0.0)
            } else {
                0.0
            }
        };
        DVec4::new(get(0), get(1), get(2), get(3))
    }

    /// The value of key `k`.
    pub fn key(&self, k: usize) -> DVec4 {
        let v = self.group(
            k,
            usize::from(self.interpolation == Interpolation::CubicSpline),
        );
        self.finish(v)
    }

    /// Rotations normalised (identity when degenerate), other values as they are.
    fn finish(&self, v: DVec4) -> DVec4 {
        if self.path != AnimationPath::Rotation {
            return v;
        }
        let n = v.length();
        if n.is_finite() && n > 1e-12 {
            v / n
        } else {
            DVec4::W
        }
    }

    /// The value at time `t` (seconds) as glTF specifies: the first key's value before it,
    /// the last key's after it; a time within [`KEY_TIME_TOLERANCE`] of a key gives the
    /// key's value exactly. Translations and scales in `x, y, z` (`w` = 0), rotations as a
    /// unit quaternion `x, y, z, w`. `None` when the channel has no key.
    pub fn sample(&self, t: f64) -> Option<DVec4> {
        let n = self.times.len();
        if n == 0 {
            return None;
        }
        // Keys at or before t.
        let i = self.times.partition_point(|&x| x <= t);
        for k in [i.wrapping_sub(1), i] {
            if let Some(&tk) = self.times.get(k)
                && near(tk, t)
            {
                return Some(self.key(k));
            }
        }
        if i == 0 {
            return Some(self.key(0));
        }
        if i >= n {
            return Some(self.key(n - 1));
        }
        let (k0, k1) = (i - 1, i);
        let (t0, t1) = (self.times[k0], self.times[k1]);
        let td = t1 - t0;
        if !(td > 0.0 && td.is_finite()) {
            return Some(self.key(k0));
        }
        let s = ((t - t0) / td).clamp(0.0, 1.0);
        let v = match self.interpolation {
            Interpolation::Step => self.key(k0),
            Interpolation::Linear if self.path == AnimationPath::Rotation => {
                slerp(self.key(k0), self.key(k1), s)
            }
            Interpolation::Linear => self.key(k0).lerp(self.key(k1), s),
            Interpolation::CubicSpline => {
                let (s2, s3) = (s * s, s * s * s);
                let v0 = self.group(k0, 1);
                let b0 = self.group(k0, 2);
                let v1 = self.group(k1, 1);
                let a1 = self.group(k1, 0);
                v0 * (2.0 * s3 - 3.0 * s2 + 1.0)
                    + b0 * (td * (s3 - 2.0 * s2 + s))
                    + v1 * (-2.0 * s3 + 3.0 * s2)
                    + a1 * (td * (s3 - s2))
            }
        };
        Some(self.finish(v))
    }

    /// Sets the animated property of `trs` to its value at time `t`.
    pub fn apply(&self, t: f64, trs: &mut Trs) {
        let Some(v) = self.sample(t) else {
            return;
        };
        match self.path {
            AnimationPath::Translation => trs.translation = v.truncate(),
            AnimationPath::Scale => trs.scale = v.truncate(),
            AnimationPath::Rotation => trs.rotation = DQuat::from_vec4(v),
        }
    }

    /// Checks the invariants documented on the fields (the importer's checks).
    pub fn validate(&self) -> Result<(), String> {
        let n = self.times.len();
        if n == 0 {
            return Err("no keys".into());
        }
        if self.interpolation == Interpolation::CubicSpline && n < 2 {
            return Err("CUBICSPLINE needs at least two keys".into());
        }
        if let Some(k) = self.times.iter().position(|t| !t.is_finite()) {
            return Err(format!("key time {k} is not finite"));
        }
        if self.times[0] < 0.0 {
            return Err(format!(
                "the first key time is negative ({})",
                self.times[0]
            ));
        }
        if let Some(k) = self.times.windows(2).position(|w| w[1] <= w[0]) {
            return Err(format!(
                "key times are not strictly increasing (key {}: {} after {})",
                k + 1,
                self.times[k + 1],
                self.times[k]
            ));
        }
        let expected = n.saturating_mul(self.stride());
        if self.values.len() != expected {
            return Err(format!(
                "{} output numbers for {n} keys, expected {expected}",
                self.values.len()
            ));
        }
        if let Some(k) = self.values.iter().position(|v| !v.is_finite()) {
            return Err(format!("output number {k} is not finite"));
        }
        if self.path == AnimationPath::Rotation
            && let Some(k) = (0..n).find(|&k| {
                let v = self.group(
                    k,
                    usize::from(self.interpolation == Interpolation::CubicSpline),
                );
                v.length() < 1e-6
            })
        {
            return Err(format!("rotation key {k} is not a unit quaternion (zero)"));
        }
        Ok(())
    }
}

/// Spherical linear interpolation as glTF's Appendix C writes it (the shorter way; linear
/// and normalised when the keys are nearly equal).
fn slerp(a: DVec4, b: DVec4, s: f64) -> DVec4 {
    let d = a.dot(b);
    let (b, d) = if d < 0.0 { (-b, -d) } else { (b, d) };
    if d > 1.0 - 1e-12 {
        return a.lerp(b, s);
    }
    let angle = d.min(1.0).acos();
    let sin = angle.sin();
    a * (((1.0 - s) * angle).sin() / sin) + b * ((s * angle).sin() / sin)
}

impl Animation {
    /// Sets the animated properties of `locals` (one per node) to their values at time
    /// `t`; channels on nodes past the end are ignored.
    pub fn apply(&self, t: f64, locals: &mut [Trs]) {
        for c in &self.channels {
            if let Some(trs) = locals.get_mut(c.node) {
                c.apply(t, trs);
            }
        }
    }

    /// The local transforms of all nodes of `avatar` at time `t`: the nodes' own
    /// transforms ([`crate::Node::pose`]) with the animated properties replaced.
    pub fn locals_at(&self, avatar: &Avatar, t: f64) -> Vec<Trs> {
        let mut locals = avatar.pose_locals();
        self.apply(t, &mut locals);
        locals
    }
}

/// Rotation part of a similarity (scale removed).
fn rotation_of(m: DMat4) -> DQuat {
    let q = DQuat::from_mat3(&orthonormalize(DMat3::from_mat4(m)));
    if q.is_finite() && q.length() > 0.5 {
        q.normalize()
    } else {
        DQuat::IDENTITY
    }
}

/// The nodes a clip of `avatar` keeps, parents first, and whether they need a common root
/// above them. Skin joints and mapped nodes with their ancestors; every node when the
/// avatar has neither.
fn clip_nodes(avatar: &Avatar) -> (Vec<usize>, bool) {
    let n = avatar.nodes.len();
    let mut keep = vec![false; n];
    let marked = avatar
        .skins
        .iter()
        .flat_map(|s| s.joints.iter().copied())
        .chain(avatar.mapping.matches().iter().map(|m| m.source));
    for j in marked {
        if let Some(k) = keep.get_mut(j) {
            *k = true;
        }
    }
    if !keep.contains(&true) {
        keep.fill(true);
    }
    for i in 0..n {
        if !keep[i] {
            continue;
        }
        let mut cur = avatar.nodes[i].parent;
        let mut steps = 0;
        while let Some(p) = cur.filter(|&p| p < n) {
            if keep[p] || steps > n {
                break;
            }
            keep[p] = true;
            steps += 1;
            cur = avatar.nodes[p].parent;
        }
    }
    // Children from the parent links (what world_from_locals uses), in node order.
    let mut children: Vec<Vec<usize>> = vec![Vec::new(); n];
    let mut roots = Vec::new();
    for i in (0..n).filter(|&i| keep[i]) {
        match avatar.nodes[i].parent.filter(|&p| p < n && keep[p]) {
            Some(p) => children[p].push(i),
            None => roots.push(i),
        }
    }
    let mut order = Vec::new();
    let mut seen = vec![false; n];
    for &r in &roots {
        let mut stack = vec![r];
        while let Some(i) = stack.pop() {
            if std::mem::replace(&mut seen[i], true) {
                continue;
            }
            order.push(i);
            stack.extend(children[i].iter().rev());
        }
    }
    (order, roots.len() > 1)
}

/// A glTF animation of `avatar` (index into [`Avatar::animations`]) as a motion [`Clip`]
/// sampled at `fps` frames per second.
///
/// - Frames: `round(duration x fps) + 1`, at `k / fps` seconds; a frame that falls on a key
///   takes the key's value exactly (so keys uniform at `fps` are the frames themselves);
///   between keys the channels interpolate as the file says ([`AnimationChannel::sample`]).
/// - Joints: the skin joints and mapped nodes with their ancestors (every node when there
///   are none), parents first, named as the nodes; several roots get a common root joint
///   `(root)` at the origin. The clip's mapping is the avatar's on the clip's joints.
/// - Transforms, in the H-Anim frame (through [`Avatar::hanim_from_file`], rotations with
///   the file's unit scale removed): per node `n` the world rotation delta
///   `D(n) = rot(H W(n, t)) rot(H W_rest(n))^-1` and position `P(n) = H W(n, t) 0`; the clip
///   joint's rotation is `D(parent)^-1 D(n)`, its translation `D(parent)^-1 (P(n) -
///   P(parent))` (the root's: `P(root)`), its offset the rest value of that translation.
pub fn clip_from_animation(
    avatar: &Avatar,
    animation: usize,
    fps: f64,
) -> Result<Clip, AssetError> {
    let anim = avatar
        .animations
        .get(animation)
        .ok_or(AssetError::BadIndex {
            what: "clip_from_animation".into(),
            kind: "animation",
            index: animation,
            count: avatar.animations.len(),
        })?;
    let fail = |reason: String| AssetError::Animation {
        animation: format!("{} `{}`", anim.index, anim.name),
        reason,
    };
    if !(fps.is_finite() && fps > 0.0) {
        return Err(fail(format!("the frame rate must be positive, got {fps}")));
    }
    let duration = if anim.duration.is_finite() {
        anim.duration.max(0.0)
    } else {
        return Err(fail(format!("duration {} is not finite", anim.duration)));
    };
    let frames_f = (duration * fps).round() + 1.0;
    if !frames_f.is_finite() || frames_f > MAX_CLIP_FRAMES as f64 {
        return Err(AssetError::TooLarge {
            what: format!("clip of animation `{}` (frames)", anim.name),
            size: if frames_f.is_finite() {
                frames_f as u64
            } else {
                u64::MAX
            },
            limit: MAX_CLIP_FRAMES as u64,
        });
    }
    let frame_count = frames_f as usize;

    let (order, synthetic_root) = clip_nodes(avatar);
    let shift = usize::from(synthetic_root);
    let joint_count = order.len() + shift;
    if frame_count.saturating_mul(joint_count) > MAX_CLIP_TRANSFORMS {
        return Err(AssetError::TooLarge {
            what: format!("clip of animation `{}` (frames x joints)", anim.name),
            size: frame_count.saturating_mul(joint_count) as u64,
            limit: MAX_CLIP_TRANSFORMS as u64,
        });
    }
    let n = avatar.nodes.len();
    let mut new_index: Vec<Option<usize>> = vec![None; n];
    for (k, &node) in order.iter().enumerate() {
        new_index[node] = Some(k + shift);
    }
    // Clip parent of each clip joint (the synthetic root, when there is one, is joint 0).
    let parents: Vec<Option<usize>> = (0..joint_count)
        .map(|j| {
            if j < shift {
                return None;
            }
            avatar.nodes[order[j - shift]]
                .parent
                .and_then(|p| new_index.get(p).copied().flatten())
                .or(if shift == 1 { Some(0) } else { None })
        })
        .collect();

    let h = avatar.hanim_from_file;
    // Per clip joint: rotation and position in the H-Anim frame, from world transforms.
    let placed = |world: &[DMat4]| -> Vec<(DQuat, DVec3)> {
        (0..joint_count)
            .map(|j| {
                if j < shift {
                    return (DQuat::IDENTITY, DVec3::ZERO);
                }
                let w = world.get(order[j - shift]).copied().unwrap_or_default();
                let m = h * w;
                (rotation_of(m), m.w_axis.truncate())
            })
            .collect()
    };
    let rest = placed(&avatar.rest_world());
    let rest_inverse: Vec<DQuat> = rest.iter().map(|(q, _)| q.inverse()).collect();
    let joints: Vec<ClipJoint> = (0..joint_count)
        .map(|j| ClipJoint {
            name: if j < shift {
                "(root)".into()
            } else {
                avatar.nodes[order[j - shift]].name.clone()
            },
            parent: parents[j],
            offset: match parents[j] {
                Some(p) => rest[j].1 - rest[p].1,
                None => rest[j].1,
            },
        })
        .collect();

    let mut frames = Vec::with_capacity(frame_count);
    for k in 0..frame_count {
        let t = k as f64 / fps;
        let world = avatar.world_from_locals(&anim.locals_at(avatar, t));
        let now = placed(&world);
        let delta: Vec<DQuat> = now
            .iter()
            .zip(&rest_inverse)
            .map(|((q, _), r)| (*q * *r).normalize())
            .collect();
        let mut frame = ClipFrame {
            translations: Vec::with_capacity(joint_count),
            rotations: Vec::with_capacity(joint_count),
        };
        for j in 0..joint_count {
            let (rotation, translation) = match parents[j] {
                Some(p) => {
                    let inv = delta[p].inverse();
                    ((inv * delta[j]).normalize(), inv * (now[j].1 - now[p].1))
                }
                None => (delta[j], now[j].1),
            };
            frame.rotations.push(rotation);
            frame.translations.push(translation);
        }
        frames.push(frame);
    }
    let mut on_keys = true;
    for c in &anim.channels {
        on_keys &= c.times.iter().all(|&t| {
            let f = t * fps;
            near(f.round() / fps, t)
        });
    }
    let last = (frame_count - 1) as f64 / fps;
    let mut notes = vec![format!(
        "glTF animation {} `{}` ({} channels, {duration} s) sampled at {fps} fps: {frame_count} frames (round(duration x fps) + 1), at 0 to {last} s",
        anim.index,
        anim.name,
        anim.channels.len()
    )];
    notes.push(if on_keys {
        format!("every key falls on a frame at {fps} fps: the frames are the keys' values")
    } else {
        format!("keys off the {fps} fps grid: frames between keys interpolated as the file says")
    });
    if synthetic_root {
        notes.push("several root nodes: a joint `(root)` at the origin holds them".into());
    }
    Ok(Clip {
        name: anim.name.clone(),
        frame_time: 1.0 / fps,
        joints,
        frames,
        mapping: avatar.mapping.remapped(&new_index, joint_count),
        notes,
    })
}
