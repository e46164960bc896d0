//! Animations: channels on node transforms with their samplers, checked and read as `f64`.
//!
//! Policy: a malformed animation (a bad or mistyped accessor, a node or sampler out of
//! range, an unknown path or interpolation, key times not finite, negative or not strictly
//! increasing, outputs of the wrong count, non-finite or zero rotations) is skipped whole
//! with a warning naming the animation and the channel; the avatar still loads. Exceeding a
//! [`crate::Limits`] value is an error, as everywhere in the importer.

use gltf::json::{
    accessor::{ComponentType, Type as AccType},
    animation::{Interpolation as JsonInterpolation, Property},
    validation::Checked,
};

use super::{Ctx, check_count};
use crate::AssetError;
use crate::animation::{Animation, AnimationChannel, AnimationPath, Interpolation};

/// Reads every animation of the file (see the module documentation for what is skipped).
pub(super) fn import_animations(
    ctx: &mut Ctx<'_>,
    node_count: usize,
) -> Result<Vec<Animation>, AssetError> {
    let count = ctx.root.animations.len();
    check_count("animations", count, ctx.limits.max_animations)?;
    let sum = |f: fn(&gltf::json::Animation) -> usize| -> usize {
        ctx.root
            .animations
            .iter()
            .map(f)
            .fold(0usize, usize::saturating_add)
    };
    let channels = sum(|a| a.channels.len());
    let samplers = sum(|a| a.samplers.len());
    let limit = ctx.limits.max_animation_channels;
    check_count("animation channels", channels, limit)?;
    check_count("animation samplers", samplers, limit)?;
    let mut out = Vec::new();
    for i in 0..count {
        let name = ctx.root.animations[i]
            .name
            .clone()
            .unwrap_or_else(|| format!("animation{i}"));
        match import_animation(ctx, i, &name, node_count) {
            Ok(a) => out.push(a),
            Err(e @ AssetError::TooLarge { .. }) => return Err(e),
            Err(e) => ctx.warnings.push(format!("{e}; the animation is skipped")),
        }
    }
    Ok(out)
}

fn import_animation(
    ctx: &mut Ctx<'_>,
    index: usize,
    name: &str,
    node_count: usize,
) -> Result<Animation, AssetError> {
    let label = format!("{index} `{name}`");
    let fail = |reason: String| AssetError::Animation {
        animation: label.clone(),
        reason,
    };
    let anim = ctx.root.animations[index].clone();
    let mut channels = Vec::with_capacity(anim.channels.len());
    let mut weights = 0usize;
    for (c, channel) in anim.channels.iter().enumerate() {
        let path = match channel.target.path {
            Checked::Valid(Property::Translation) => AnimationPath::Translation,
            Checked::Valid(Property::Rotation) => AnimationPath::Rotation,
            Checked::Valid(Property::Scale) => AnimationPath::Scale,
            Checked::Valid(Property::MorphTargetWeights) => {
                weights += 1;
                continue;
            }
            Checked::Invalid => return Err(fail(format!("channel {c}: unknown target path"))),
        };
        let node = channel.target.node.value();
        if node >= node_count {
            return Err(fail(format!(
                "channel {c} targets node {node}, but the file has {node_count}"
            )));
        }
        let s = channel.sampler.value();
        let Some(sampler) = anim.samplers.get(s) else {
            return Err(fail(format!(
                "channel {c} uses sampler {s}, but the animation has {}",
                anim.samplers.len()
            )));
        };
        let interpolation = match sampler.interpolation {
            Checked::Valid(JsonInterpolation::Linear) => Interpolation::Linear,
            Checked::Valid(JsonInterpolation::Step) => Interpolation::Step,
            Checked::Valid(JsonInterpolation::CubicSpline) => Interpolation::CubicSpline,
            Checked::Invalid => {
                return Err(fail(format!(
                    "channel {c}: sampler {s} has an unknown interpolation"
                )));
            }
        };
        let what = |part: &str| format!("animation {label} channel {c} {part}");
        let (input, output) = (sampler.input.value(), sampler.output.value());
        check_accessor(ctx, input, AccType::Scalar, false)
            .map_err(|e| fail(format!("channel {c} input: {e}")))?;
        let expected = if path == AnimationPath::Rotation {
            AccType::Vec4
        } else {
            AccType::Vec3
        };
        check_accessor(ctx, output, expected, path == AnimationPath::Rotation)
            .map_err(|e| fail(format!("channel {c} output ({}): {e}", path.name())))?;
        let times = read(ctx, input, &what("input"), &fail, c)?;
        let values = read(ctx, output, &what("output"), &fail, c)?;
        // The f64 copies kept in the avatar.
        ctx.charge(
            times.len().saturating_add(values.len()).saturating_mul(8),
            &what("keys"),
        )?;
        let mut channel = AnimationChannel {
            node,
            path,
            interpolation,
            times: times.into_iter().map(f64::from).collect(),
            values: values.into_iter().map(f64::from).collect(),
        };
        channel
            .validate()
            .map_err(|e| fail(format!("channel {c} ({} of node {node}): {e}", path.name())))?;
        if path == AnimationPath::Rotation {
            normalize_rotations(&mut channel);
        }
        channels.push(channel);
    }
    if weights > 0 {
        ctx.warnings.push(format!(
            "animation {label}: {weights} morph-target weights channel(s) ignored"
        ));
    }
    if channels.is_empty() {
        return Err(fail("no channel on a node transform".into()));
    }
    let duration = channels
        .iter()
        .filter_map(|c| c.times.last().copied())
        .fold(0.0, f64::max);
    Ok(Animation {
        name: name.to_owned(),
        index,
        channels,
        duration,
    })
}

/// Reads an accessor; limits are errors, the rest names the channel.
fn read(
    ctx: &mut Ctx<'_>,
    index: usize,
    what: &str,
    fail: &dyn Fn(String) -> AssetError,
    channel: usize,
) -> Result<Vec<f32>, AssetError> {
    match ctx.read(index, what) {
        Ok((v, _)) => Ok(v),
        Err(AssetError::TooLarge {
            what: w,
            size,
            limit,
        }) => Err(AssetError::TooLarge {
            what: format!("{what}: {w}"),
            size,
            limit,
        }),
        Err(e) => Err(fail(format!("channel {channel}: {e}"))),
    }
}

/// Checks an accessor's type and component type against what glTF allows for animations:
/// float, or for rotations also normalised (unsigned) bytes and shorts.
fn check_accessor(
    ctx: &Ctx<'_>,
    index: usize,
    expected: AccType,
    normalized_ok: bool,
) -> Result<(), String> {
    let count = ctx.root.accessors.len();
    let acc = ctx
        .root
        .accessors
        .get(index)
        .ok_or_else(|| format!("accessor {index} does not exist (the file has {count})"))?;
    let (Checked::Valid(ct), Checked::Valid(ty)) = (acc.component_type, acc.type_) else {
        return Err(format!(
            "accessor {index} has an invalid componentType or type"
        ));
    };
    if ty != expected {
        return Err(format!("accessor {index} is {ty:?}, expected {expected:?}"));
    }
    let ok = match ct.0 {
        ComponentType::F32 => true,
        ComponentType::I8 | ComponentType::U8 | ComponentType::I16 | ComponentType::U16 => {
            normalized_ok && acc.normalized
        }
        ComponentType::U32 => false,
    };
    if !ok {
        return Err(format!(
            "accessor {index} has components {:?}{}, expected float{}",
            ct.0,
            if acc.normalized { " (normalized)" } else { "" },
            if normalized_ok {
                " or normalized integers"
            } else {
                ""
            }
        ));
    }
    Ok(())
}

/// Unit rotation keys (tangents of CUBICSPLINE keys stay as they are).
fn normalize_rotations(channel: &mut AnimationChannel) {
    let cubic = channel.interpolation == Interpolation::CubicSpline;
    let stride = if cubic { 12 } else { 4 };
    let at = if cubic { 4 } else { 0 };
    for key in channel.values.chunks_exact_mut(stride) {
        if let Some(q) = key.get_mut(at..at + 4) {
            let n = q.iter().map(|x| x * x).sum::<f64>().sqrt();
            if n > 0.0 {
                q.iter_mut().for_each(|x| *x /= n);
            }
        }
    }
}
