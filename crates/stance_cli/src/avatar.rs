//! Avatar subcommands: `inspect`, `export-posed`, `make-avatar`.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result, anyhow, bail};
use serde_json::{Map, Value, json};
use stance_asset::{Avatar, LoadOptions, export_glb, load_avatar_with, make_default_avatar};
use stance_document::{Document, PostureRest, PostureValues};
use stance_hanim::{
    HumanoidSkeleton, LevelOfArticulation, MatchMethod, SkeletonOptions, joint_by_name,
};
use stance_ik::{Dof, Posture};

/// `stance inspect FILE`.
#[derive(clap::Args, Debug)]
pub struct InspectArgs {
    /// A .glb, .gltf or .vrm file.
    pub file: PathBuf,
}

/// `stance export-posed AVATAR POSTURE.json OUT.glb`.
#[derive(clap::Args, Debug)]
pub struct ExportPosedArgs {
    /// The avatar (.glb, .gltf, .vrm).
    pub avatar: PathBuf,
    /// `{"posture": {joint: {dof: value}}}` (the output of `stance solve`) or the bare
    /// `{joint: {dof: value}}` object; optional `"loa": 1 | 2` (default 2).
    pub posture: PathBuf,
    /// Output GLB.
    pub out: PathBuf,
}

/// `stance make-avatar OUT.glb`.
#[derive(clap::Args, Debug)]
pub struct MakeAvatarArgs {
    /// Output GLB.
    pub out: PathBuf,
}

/// A resolver of a `.gltf`'s external resources: relative paths next to `path` only.
pub fn resolver_next_to(path: &Path) -> impl FnMut(&str) -> Option<Vec<u8>> {
    let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
    move |uri: &str| std::fs::read(dir.join(stance_asset::relative_path(uri)?)).ok()
}

/// Loads an avatar file (external resources next to it only).
pub fn load(path: &Path, options: &LoadOptions) -> Result<Avatar> {
    let bytes = std::fs::read(path).with_context(|| format!("reading {}", path.display()))?;
    load_avatar_with(&bytes, options, &mut resolver_next_to(path))
        .with_context(|| format!("loading {}", path.display()))
}

/// The inspection summary of an avatar.
pub fn inspect_json(avatar: &Avatar) -> Value {
    let joint_nodes: BTreeSet<usize> = if avatar.skins.is_empty() {
        (0..avatar.nodes.len())
            .filter(|&i| avatar.nodes[i].mesh.is_none())
            .collect()
    } else {
        avatar
            .skins
            .iter()
            .flat_map(|s| s.joints.iter().copied())
            .collect()
    };
    let mut mapping = Map::new();
    let mut confidence = Map::new();
    for m in avatar.mapping.matches() {
        if m.method == MatchMethod::Implied {
            continue;
        }
        if let Some(n) = avatar.nodes.get(m.source) {
            mapping.insert(n.name.clone(), json!(m.hanim));
            confidence.insert(
                n.name.clone(),
                json!({
                    "hanim": m.hanim,
                    "method": method_name(m.method, &n.name),
                    // f32 -> f64 without the binary tail (0.95, not 0.949999988).
                    "confidence": (f64::from(m.confidence) * 1000.0).round() / 1000.0,
                }),
            );
        }
    }
    let unmapped: Vec<&str> = joint_nodes
        .iter()
        .filter(|&&i| avatar.mapping.hanim_of(i).is_none())
        .filter_map(|&i| avatar.nodes.get(i).map(|n| n.name.as_str()))
        .collect();
    json!({
        "joints": joint_nodes.len(),
        "mapping": mapping,
        "unmapped": unmapped,
        "meshes": avatar.meshes.len(),
        "vertices": avatar.vertex_count(),
        "extensions": avatar.extensions,
        "warnings": avatar.warnings,
        "confidence": confidence,
    })
}

/// How a joint was matched, as `stance inspect` prints it. Known rig names whose source
/// name carries Mixamo's `mixamorig` prefix are reported as `mixamo`.
pub fn method_name(method: MatchMethod, source_name: &str) -> &'static str {
    match method {
        MatchMethod::Vrm => "vrm_extension",
        MatchMethod::HAnimName => "hanim_name",
        MatchMethod::KnownName
            if source_name
                .get(..9)
                .is_some_and(|p| p.eq_ignore_ascii_case("mixamorig")) =>
        {
            "mixamo"
        }
        MatchMethod::KnownName => "known_rig_name",
        MatchMethod::NamePattern => "name_pattern",
        MatchMethod::Geometry => "geometry",
        MatchMethod::Implied => "implied",
        MatchMethod::User => "user",
    }
}

pub fn inspect(args: InspectArgs) -> Result<()> {
    let avatar = load(
        &args.file,
        &LoadOptions {
            require_humanoid: false,
            ..LoadOptions::default()
        },
    )?;
    println!("{}", serde_json::to_string(&inspect_json(&avatar))?);
    Ok(())
}

fn parse_posture(skeleton: &stance_ik::Skeleton, v: &Value) -> Result<(Posture, Vec<String>)> {
    let mut warnings = Vec::new();
    let joints = v.get("posture").unwrap_or(v);
    let obj = joints
        .as_object()
        .ok_or_else(|| anyhow!("posture: expected an object {{joint: {{dof: value}}}}"))?;
    let mut posture = Posture::rest(skeleton);
    for (name, dofs) in obj {
        if name == "loa" {
            continue;
        }
        let Some(j) = skeleton.joint_index(name) else {
            if joint_by_name(name).is_none() {
                bail!("posture: `{name}` is not an H-Anim joint");
            }
            warnings.push(format!(
                "joint `{name}` is not in this avatar's skeleton; ignored"
            ));
            continue;
        };
        let dofs = dofs
            .as_object()
            .ok_or_else(|| anyhow!("posture.{name}: expected {{dof: value}}"))?;
        let joint = &skeleton.joints()[j];
        for (dof_name, value) in dofs {
            let dof = Dof::from_name(dof_name)
                .ok_or_else(|| anyhow!("posture.{name}: unknown DOF `{dof_name}`"))?;
            let value = value
                .as_f64()
                .filter(|x| x.is_finite())
                .ok_or_else(|| anyhow!("posture.{name}.{dof_name}: expected a finite number"))?;
            match joint.dofs.iter().position(|&d| d == dof) {
                Some(k) => posture.values_mut()[joint.dof_start + k] = value,
                None => warnings.push(format!("{name} has no DOF {dof_name} here; ignored")),
            }
        }
    }
    Ok((posture, warnings))
}

/// The posture input with its values relative to the H-Anim standard pose: a document made on
/// an avatar before a posture meant the same pose on every body (`"rest": "avatar"`, or an
/// avatar URL without `rest`) has its `posture` converted from `body`'s own rest, as the
/// editor converts it (docs/document-format.md); anything else is taken as it is.
fn in_standard_rest(v: &Value, body: &HumanoidSkeleton) -> Result<Value> {
    let own_rest = match v.get("rest") {
        Some(Value::String(rest)) if rest == "avatar" => true,
        Some(Value::String(rest)) if rest == "standard" => false,
        Some(other) => bail!("rest: {other} (expected \"standard\" or \"avatar\")"),
        None => v.get("avatar").is_some_and(Value::is_object),
    };
    let Some(posture) = v.get("posture").filter(|_| own_rest) else {
        return Ok(v.clone());
    };
    let document = Document {
        posture: PostureValues::from_json_value(posture, "posture")?,
        rest: PostureRest::Avatar,
        ..Document::default()
    };
    let converted = document.in_standard_rest(body);
    eprintln!(
        "note: the posture's values are relative to this avatar's own rest (made before a posture meant the same pose on every body); converted to the H-Anim standard pose"
    );
    let mut out = v.clone();
    out["posture"] = serde_json::to_value(&converted.posture)?;
    Ok(out)
}

pub fn export_posed(args: ExportPosedArgs) -> Result<()> {
    let mut avatar = load(&args.avatar, &LoadOptions::default())?;
    let text = std::fs::read_to_string(&args.posture)
        .with_context(|| format!("reading {}", args.posture.display()))?;
    let v: Value = serde_json::from_str(&text)
        .with_context(|| format!("parsing {}", args.posture.display()))?;
    let loa = match v.get("loa").and_then(Value::as_u64) {
        None | Some(2) => LevelOfArticulation::Loa2,
        Some(1) => LevelOfArticulation::Loa1,
        Some(other) => bail!("loa {other} is not supported (1 or 2)"),
    };
    let body = avatar.skeleton(&SkeletonOptions {
        loa,
        ..SkeletonOptions::default()
    })?;
    let v = in_standard_rest(&v, &body)?;
    let (posture, warnings) = parse_posture(&body.skeleton, &v)?;
    for w in warnings {
        eprintln!("warning: {w}");
    }
    avatar.apply_posture(&body, &posture)?;
    let bytes = export_glb(&avatar)?;
    std::fs::write(&args.out, bytes).with_context(|| format!("writing {}", args.out.display()))?;
    Ok(())
}

pub fn make_avatar(args: MakeAvatarArgs) -> Result<()> {
    let avatar = make_default_avatar()?;
    let bytes = export_glb(&avatar)?;
    std::fs::write(&args.out, bytes).with_context(|| format!("writing {}", args.out.display()))?;
    Ok(())
}
