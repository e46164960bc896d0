//! `stance render DOC.json --out IMAGE.png`: the document's posture on the default H-Anim body
//! (the mannequin) or on an avatar (its skinned mesh), drawn natively with wgpu on any adapter
//! (lavapipe will do) through the same image path as the editor's *File > Save image*. A scene
//! (`stance_document::Scene`) draws every character at its `Placement` and its props, placed
//! by `stance_render::placed` as the editor places them.
//!
//! `--map openpose|depth|normal|mask` writes a control map for image generation instead, seen
//! by the same camera: the OpenPose skeleton (drawn on the CPU; with `--keypoints-out` its
//! keypoints as OpenPose JSON), or the figure's depth, normals, mask or line art (rendered
//! like the picture, unlit, on black). See docs/control-maps.md.

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

use anyhow::{Context, Result, anyhow, bail};
use glam::{DVec3, Vec3};
use stance_asset::{LoadOptions, PropMesh, load_prop_mesh, make_default_avatar};
use stance_document::{AvatarReference, Document, Placement, PostureRest, Prop, SceneCharacter};
use stance_hanim::keypoints::KeypointFinder;
use stance_hanim::{HumanoidSkeleton, LevelOfArticulation, SkeletonOptions, default_skeleton};
use stance_ik::{Frames, Posture};
use stance_render::{
    Capsule, GOAL_COLOR_LINEAR, HiddenKeypoints, ImageOptions, KeypointUnits, OpenPose,
    OrbitCamera, Pixels, Scene, SceneRenderer, Shading, ViewPreset, avatar_model, character_shadow,
    encode_png, headless_gpu, line_art, mesh_prop_instance, placed_capsule, placed_keypoints,
    placed_palettes, posed_mannequin_bones, prop_corners, prop_instance, prop_shadow, render_image,
    scene_from_character,
};

use crate::avatar;

/// `stance render DOC.json --out IMAGE.png [--avatar FILE] [--view VIEW] [--size WxH]
/// [--map openpose [--keypoints-out K.json] [--normalized] [--hidden keep|missing]]
/// [--map depth|normal|mask|lines]`.
#[derive(clap::Args, Debug)]
pub struct RenderArgs {
    /// The document or scene (JSON, as the editor exports it): a scene's characters are all
    /// drawn at their placements on the same body, with its props, one OpenPose person each.
    pub document: PathBuf,
    /// The PNG to write.
    #[arg(long)]
    pub out: PathBuf,
    /// An avatar (.glb, .gltf, .vrm) to pose instead of the default body (every character of
    /// a scene; a document's own avatar URL is not loaded).
    #[arg(long)]
    pub avatar: Option<PathBuf>,
    /// A standard view framed on the body; without it the document's saved camera (or the
    /// editor's default view, framed on the body).
    #[arg(long, value_enum)]
    pub view: Option<View>,
    /// Image size, WIDTHxHEIGHT pixels (each side 1 to 8192).
    #[arg(long, default_value = "1280x960")]
    pub size: String,
    /// Alpha 0 where nothing is drawn (PNG with straight alpha).
    #[arg(long)]
    pub transparent: bool,
    /// Draw the overlays: the floor grid and the tasks' goals (off: the figure alone).
    #[arg(long)]
    pub overlays: bool,
    /// Level of articulation of the body (1-4; an avatar: 1 or 2).
    #[arg(long, default_value_t = 2)]
    pub loa: u8,
    /// Draw the mannequin as capsules (the editor's capsule view) instead of its skinned
    /// figure; no effect with --avatar.
    #[arg(long)]
    pub capsules: bool,
    /// Write a control map for image generation instead of the picture: `openpose`, the
    /// OpenPose skeleton (COCO-18 body and hands) as the ControlNet preprocessors draw it;
    /// `depth` (near bright), `normal` (ControlNet's normal colours), `mask` (white on
    /// black) or `lines` (line art: silhouettes, contours, creases), rendered like the picture.
    #[arg(long, value_enum)]
    pub map: Option<ControlMap>,
    /// With --map openpose: also write the keypoints as OpenPose JSON (pixels unless
    /// --normalized).
    #[arg(long)]
    pub keypoints_out: Option<PathBuf>,
    /// With --keypoints-out: positions as fractions of the image's width and height.
    #[arg(long)]
    pub normalized: bool,
    /// With --map openpose: what becomes of a keypoint the body hides from the camera
    /// (default: keep).
    #[arg(long, value_enum)]
    pub hidden: Option<Hidden>,
    /// The folder a scene's mesh props' files (`"file": "chair.glb"`) are read from (default:
    /// the document's folder); a file not found there is drawn as its box, with a warning.
    #[arg(long)]
    pub assets: Option<PathBuf>,
}

/// The control maps.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum ControlMap {
    /// The OpenPose skeleton: body, hands (no face).
    Openpose,
    /// Depth, near bright, over the figure's depth range.
    Depth,
    /// View-space normals, ControlNet's normal (BAE) colours.
    Normal,
    /// The figure white on black.
    Mask,
    /// Line art: silhouettes, contours and creases, white on black.
    Lines,
}

impl ControlMap {
    fn name(self) -> &'static str {
        match self {
            ControlMap::Openpose => "openpose",
            ControlMap::Depth => "depth",
            ControlMap::Normal => "normal",
            ControlMap::Mask => "mask",
            ControlMap::Lines => "lines",
        }
    }
}

/// The shading of `map`: a depth map spans the figure's depth seen by `camera`.
fn shading(map: Option<ControlMap>, camera: &OrbitCamera, capsules: &[Capsule]) -> Shading {
    match map {
        None | Some(ControlMap::Openpose) => Shading::Shaded,
        Some(ControlMap::Normal) => Shading::Normal,
        Some(ControlMap::Mask) => Shading::Mask,
        Some(ControlMap::Depth) => Shading::depth_seen_by(camera, capsules),
        // Drawn from a depth and a normal map (`render_picture`).
        Some(ControlMap::Lines) => Shading::Normal,
    }
}

/// A keypoint hidden behind the body.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum Hidden {
    /// Kept, drawn and listed.
    Keep,
    /// Left out as missing (0, 0, 0 in the JSON).
    Missing,
}

impl Hidden {
    fn keypoints(self) -> HiddenKeypoints {
        match self {
            Hidden::Keep => HiddenKeypoints::Keep,
            Hidden::Missing => HiddenKeypoints::Missing,
        }
    }
}

/// The standard views.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum View {
    /// From the front.
    Front,
    /// From behind.
    Back,
    /// At the body's left side.
    Left,
    /// At the body's right side.
    Right,
    /// From above.
    Top,
    /// From the front-left, a little above.
    ThreeQuarter,
}

impl View {
    fn preset(self) -> ViewPreset {
        match self {
            View::Front => ViewPreset::Front,
            View::Back => ViewPreset::Back,
            View::Left => ViewPreset::Left,
            View::Right => ViewPreset::Right,
            View::Top => ViewPreset::Top,
            View::ThreeQuarter => ViewPreset::ThreeQuarter,
        }
    }
}

/// `WxH` -> `[W, H]`, checked against the image limits.
pub fn parse_size(text: &str) -> Result<[u32; 2]> {
    let parsed = text
        .split_once(['x', 'X'])
        .and_then(|(w, h)| Some([w.trim().parse().ok()?, h.trim().parse().ok()?]));
    let size_px = parsed
        .ok_or_else(|| anyhow!("--size {text}: expected WIDTHxHEIGHT in pixels, e.g. 1280x960"))?;
    ImageOptions {
        size_px,
        ..ImageOptions::default()
    }
    .check(u32::MAX)
    .map_err(|error| anyhow!("--size {text}: {error}"))?;
    Ok(size_px)
}

/// The body the document poses, and the skinned mesh drawn for it (none: capsules).
struct Figure {
    /// The skeleton the document's posture is read on.
    humanoid: HumanoidSkeleton,
    mesh: Option<MeshFigure>,
}

/// A skinned mesh, posed on its own H-Anim skeleton.
struct MeshFigure {
    avatar: stance_asset::Avatar,
    palettes: stance_render::AvatarPalettes,
    model: stance_render::SkinnedModel,
    /// The mesh's skeleton: the avatar's (`--avatar`), or the generated mannequin figure's,
    /// which the mannequin's posture is carried onto joint by joint, as the editor draws it.
    skeleton: HumanoidSkeleton,
}

impl MeshFigure {
    fn new(avatar: stance_asset::Avatar, skeleton: HumanoidSkeleton, what: &str) -> Result<Self> {
        let (model, palettes, warnings) = avatar_model(&avatar);
        for warning in warnings.iter().chain(&avatar.warnings) {
            eprintln!("warning: {warning}");
        }
        if model.primitives.is_empty() {
            bail!("{what}: the file has no mesh to draw");
        }
        Ok(Self {
            avatar,
            palettes,
            model,
            skeleton,
        })
    }
}

fn figure(args: &RenderArgs) -> Result<Figure> {
    let loa = LevelOfArticulation::from_number(args.loa)
        .ok_or_else(|| anyhow!("--loa {}: expected 1, 2, 3 or 4", args.loa))?;
    let options = SkeletonOptions {
        loa,
        ..SkeletonOptions::default()
    };
    let Some(path) = &args.avatar else {
        let humanoid = default_skeleton(&options)?;
        if args.capsules {
            return Ok(Figure {
                humanoid,
                mesh: None,
            });
        }
        // The editor's figure: the generated default avatar (its skeleton at LOA 2 where
        // the mesh has no joints of a higher level).
        let avatar = make_default_avatar()?;
        let skeleton = avatar.skeleton_or_loa2(&options)?;
        let mesh = MeshFigure::new(avatar, skeleton, "the default figure")?;
        return Ok(Figure {
            humanoid,
            mesh: Some(mesh),
        });
    };
    let loaded = avatar::load(path, &LoadOptions::default())?;
    let humanoid = loaded
        .skeleton(&options)
        .with_context(|| format!("{}: no H-Anim skeleton", path.display()))?;
    let mesh = MeshFigure::new(loaded, humanoid.clone(), &path.display().to_string())?;
    Ok(Figure {
        humanoid,
        mesh: Some(mesh),
    })
}

/// The bodies' extent: each capsule's ends widened by its radius.
fn extent_points<'a>(capsules: impl IntoIterator<Item = &'a Capsule>) -> Vec<Vec3> {
    capsules
        .into_iter()
        .flat_map(|capsule| {
            [capsule.start_world, capsule.end_world]
                .into_iter()
                .flat_map(move |point| {
                    [Vec3::X, Vec3::Y, Vec3::Z]
                        .into_iter()
                        .flat_map(move |axis| {
                            [-1.0, 1.0].map(|s| point + axis * s * capsule.radius_m)
                        })
                })
        })
        .collect()
}

/// One character of the scene posed on the figure.
struct PosedCharacter {
    /// Its name (the outliner's): what notes and errors call it.
    name: String,
    placement: Placement,
    document: Document,
    posture: Posture,
    frames: Frames,
    /// The mannequin's capsules of the posed body, in the scene (drawn without an avatar; the
    /// body that hides keypoints in a control map).
    capsules: Vec<Capsule>,
}

/// The scene's characters posed on their body, its props (each mesh prop's file's
/// triangles when found), and the camera that sees them.
struct Posed {
    figure: Figure,
    characters: Vec<PosedCharacter>,
    props: Vec<Prop>,
    prop_meshes: Vec<Option<Arc<PropMesh>>>,
    camera: OrbitCamera,
}

/// The triangles of each of `props` that is a mesh prop whose file is in `args.assets` (or
/// the document's folder); `None` for the others. A file not found is drawn as its box (with
/// a warning); one that is not a static mesh is an error naming it.
fn prop_meshes(args: &RenderArgs, props: &[Prop]) -> Result<Vec<Option<Arc<PropMesh>>>> {
    let folder = match &args.assets {
        Some(folder) => folder.clone(),
        None => args
            .document
            .parent()
            .map(Path::to_path_buf)
            .unwrap_or_default(),
    };
    let mut read: Vec<(String, Option<Arc<PropMesh>>)> = Vec::new();
    let mut meshes = Vec::with_capacity(props.len());
    for prop in props {
        let Some(file) = prop.shape.file() else {
            meshes.push(None);
            continue;
        };
        if let Some((_, mesh)) = read.iter().find(|(name, _)| name == file) {
            meshes.push(mesh.clone());
            continue;
        }
        let path = folder.join(file);
        let mesh = match std::fs::read(&path) {
            Ok(bytes) => {
                let mesh = load_prop_mesh(&bytes, &mut avatar::resolver_next_to(&path))
                    .map_err(|e| anyhow!("prop {} ({}): {e}", prop.name, path.display()))?;
                Some(Arc::new(mesh))
            }
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
                eprintln!(
                    "warning: prop {}: {} not found (--assets DIR): drawn as its box",
                    prop.name,
                    path.display()
                );
                None
            }
            Err(e) => {
                return Err(anyhow!(
                    "prop {}: cannot read {}: {e}",
                    prop.name,
                    path.display()
                ));
            }
        };
        read.push((file.to_owned(), mesh.clone()));
        meshes.push(mesh);
    }
    Ok(meshes)
}

impl Posed {
    fn new(args: &RenderArgs, size_px: [u32; 2]) -> Result<Posed> {
        let path = args.document.display();
        let text = std::fs::read_to_string(&args.document)
            .with_context(|| format!("cannot read {path}"))?;
        // A plain document is a scene of one character at the origin.
        let scene = stance_document::Scene::from_json(&text)
            .map_err(|e| anyhow!("invalid document {path}: {e}"))?;
        let figure = figure(args)?;
        let several = scene.characters.len() > 1;
        let characters = scene
            .characters
            .into_iter()
            .enumerate()
            .map(|(index, character)| {
                // A scene's error names the character (its index and name in the outliner).
                let which = if several {
                    format!("character {index} ({})", character.name)
                } else {
                    String::new()
                };
                pose_character(args, &figure, character).map_err(|e| {
                    if several {
                        anyhow!("{path}: {which}: {e:#}")
                    } else {
                        anyhow!("{path}: {e:#}")
                    }
                })
            })
            .collect::<Result<Vec<_>>>()?;
        let selected = characters
            .get(scene.selected)
            .or(characters.first())
            .ok_or_else(|| anyhow!("{path}: the scene has no character"))?;
        let mut extent = extent_points(characters.iter().flat_map(|c| &c.capsules));
        extent.extend(scene.props.iter().flat_map(prop_corners));
        let camera = camera(args.view, &selected.document, &extent, size_px);
        Ok(Posed {
            figure,
            characters,
            prop_meshes: prop_meshes(args, &scene.props)?,
            props: scene.props,
            camera,
        })
    }

    /// Every character's capsules, in the scene.
    fn capsules(&self) -> Vec<Capsule> {
        self.characters
            .iter()
            .flat_map(|character| character.capsules.iter().copied())
            .collect()
    }
}

/// `character`'s document posed on `figure`, its capsules placed in the scene.
fn pose_character(
    args: &RenderArgs,
    figure: &Figure,
    character: SceneCharacter,
) -> Result<PosedCharacter> {
    let SceneCharacter {
        name,
        placement,
        document,
    } = character;
    if let (None, AvatarReference::Url(url)) = (&args.avatar, &document.avatar) {
        // The CLI loads avatars from --avatar alone: a document's URL is the browser's.
        eprintln!(
            "note: {name} names the avatar {url}; drawn on the mannequin (--avatar poses every character on a file)"
        );
    }
    // Made on an avatar before a posture meant the same pose on every body: relative to
    // that avatar's own rest, taken to be the one drawn (as `export-posed` takes it).
    let document = if args.avatar.is_some() && document.rest == PostureRest::Avatar {
        eprintln!(
            "note: {name}: the document's values are relative to the avatar's own rest (made before a posture meant the same pose on every body); converted to the H-Anim standard pose"
        );
        document.in_standard_rest(&figure.humanoid)
    } else {
        document
    };
    let skeleton = &figure.humanoid.skeleton;
    let posture = document.to_posture(skeleton)?;
    let frames = Frames::new(skeleton, &posture);
    let place = scene_from_character(&placement);
    let capsules: Vec<Capsule> = posed_mannequin_bones(skeleton, &frames)
        .into_iter()
        .map(|bone| placed_capsule(bone.capsule, place))
        .collect();
    Ok(PosedCharacter {
        name,
        placement,
        document,
        posture,
        frames,
        capsules,
    })
}

/// `--view` framed on the scene, else the selected character's saved camera, else the
/// editor's default view framed on the scene (`extent`: its points).
fn camera(
    view: Option<View>,
    document: &Document,
    extent: &[Vec3],
    size_px: [u32; 2],
) -> OrbitCamera {
    let aspect = size_px[0] as f32 / size_px[1] as f32;
    match (view, &document.camera) {
        (Some(view), _) => {
            let mut camera = OrbitCamera::default();
            camera.set_view(view.preset());
            camera.frame_points(extent, aspect);
            camera
        }
        (None, Some(spec)) => OrbitCamera::saved(
            spec.target,
            spec.yaw,
            spec.pitch,
            spec.distance,
            spec.orthographic,
        ),
        (None, None) => {
            let mut camera = OrbitCamera::default();
            camera.frame_points(extent, aspect);
            camera
        }
    }
}

pub fn run(args: RenderArgs) -> Result<()> {
    let started = Instant::now();
    let size_px = parse_size(&args.size)?;
    check_map_options(&args)?;
    let posed = Posed::new(&args, size_px)?;
    match args.map {
        Some(ControlMap::Openpose) => write_openpose(&args, &posed, size_px, started),
        None
        | Some(ControlMap::Depth | ControlMap::Normal | ControlMap::Mask | ControlMap::Lines) => {
            render_picture(&args, posed, size_px, started)
        }
    }
}

/// The options that only a control map takes, or that a control map does not take.
fn check_map_options(args: &RenderArgs) -> Result<()> {
    let openpose = args.map == Some(ControlMap::Openpose);
    if !openpose {
        for (given, option) in [
            (args.keypoints_out.is_some(), "--keypoints-out"),
            (args.normalized, "--normalized"),
            (args.hidden.is_some(), "--hidden"),
        ] {
            if given {
                bail!("{option} goes with --map openpose (the keypoints of an OpenPose map)");
            }
        }
    }
    if let Some(map) = args.map {
        for (given, option, why) in [
            (
                args.transparent,
                "--transparent",
                "a control map is drawn on black",
            ),
            (
                args.overlays,
                "--overlays",
                "a control map shows the body alone",
            ),
            (
                openpose && args.capsules,
                "--capsules",
                "the OpenPose map draws the skeleton, not the body",
            ),
        ] {
            if given {
                bail!("{option} does not go with --map {}: {why}", map.name());
            }
        }
    }
    let same = |a: &PathBuf, b: &PathBuf| {
        a == b || matches!((a.canonicalize(), b.canonicalize()), (Ok(a), Ok(b)) if a == b)
    };
    for (path, option) in [
        (Some(&args.out), "--out"),
        (args.keypoints_out.as_ref(), "--keypoints-out"),
    ] {
        if let Some(path) = path
            && same(path, &args.document)
        {
            bail!(
                "{option} {}: the document itself (it would be overwritten)",
                path.display()
            );
        }
    }
    if args
        .keypoints_out
        .as_ref()
        .is_some_and(|path| same(path, &args.out))
    {
        bail!(
            "--keypoints-out {}: the same file as --out",
            args.out.display()
        );
    }
    Ok(())
}

/// `--map openpose`: the skeleton image (and the keypoints' JSON) drawn on the CPU: one person
/// per character in view, in the scene's order, each hidden by every body of the scene.
fn write_openpose(
    args: &RenderArgs,
    posed: &Posed,
    size_px: [u32; 2],
    started: Instant,
) -> Result<()> {
    let skeleton = &posed.figure.humanoid.skeleton;
    let finder = KeypointFinder::new(skeleton);
    let bodies = posed.capsules();
    let hidden = args.hidden.unwrap_or(Hidden::Keep).keypoints();
    let people: Vec<_> = posed
        .characters
        .iter()
        .map(|character| {
            placed_keypoints(
                &finder.find(skeleton, &character.frames),
                &character.placement,
            )
        })
        .collect();
    let pose = OpenPose::of_scene(&people, &posed.camera, size_px, &bodies, hidden);
    let png = encode_png(&Pixels {
        width: size_px[0],
        height: size_px[1],
        rgba: pose.draw(),
    })?;
    let units = if args.normalized {
        KeypointUnits::Normalized
    } else {
        KeypointUnits::Pixels
    };
    if let Some(path) = &args.keypoints_out {
        std::fs::write(path, pose.to_json_seen_by(units, &posed.camera))
            .with_context(|| format!("cannot write {}", path.display()))?;
    }
    std::fs::write(&args.out, png)
        .with_context(|| format!("cannot write {}", args.out.display()))?;
    let seen: usize = pose
        .people
        .iter()
        .map(|p| p.body.iter().flatten().count())
        .sum();
    let hands: usize = pose
        .people
        .iter()
        .map(|p| p.left_hand.iter().chain(&p.right_hand).flatten().count())
        .sum();
    let people = pose.people.len();
    eprintln!(
        "{}: OpenPose {}x{}, {people} of {} people in view, {seen} of {} body and {hands} of {} hand keypoints in view, in {:.2} s",
        args.out.display(),
        size_px[0],
        size_px[1],
        posed.characters.len(),
        18 * posed.characters.len(),
        42 * posed.characters.len(),
        started.elapsed().as_secs_f64()
    );
    Ok(())
}

/// The picture itself, or a depth, normal or mask map, rendered with wgpu.
fn render_picture(
    args: &RenderArgs,
    posed: Posed,
    size_px: [u32; 2],
    started: Instant,
) -> Result<()> {
    let capsules = posed.capsules();
    let Posed {
        figure,
        characters,
        props,
        prop_meshes,
        camera,
    } = posed;
    let skeleton = &figure.humanoid.skeleton;
    // Every character on the one uploaded mesh: the first's poses as the avatar's, the others'
    // as more poses of it (the renderer holds one skinned model).
    let mut poses = Vec::with_capacity(characters.len());
    if let Some(mesh) = &figure.mesh {
        for character in &characters {
            let carried =
                Posture::carried_over(&mesh.skeleton.skeleton, skeleton, &character.posture);
            let palettes = mesh
                .palettes
                .pose(&mesh.avatar, &mesh.skeleton, &carried)
                .ok_or_else(|| {
                    anyhow!(
                        "{}: the posture does not fit the avatar's skeleton",
                        character.name
                    )
                })?;
            poses.push(placed_palettes(
                palettes,
                scene_from_character(&character.placement),
            ));
        }
    }
    let mut poses = poses.into_iter();
    let avatar_palettes = poses.next().unwrap_or_default();
    let more_avatar_poses = poses.collect();
    let markers = characters
        .iter()
        .flat_map(|character| {
            let place = scene_from_character(&character.placement);
            character
                .document
                .tasks
                .iter()
                .filter_map(|task| task.kind.goal_point())
                .map(move |goal| {
                    placed_capsule(
                        Capsule::marker(DVec3::from_array(goal).as_vec3(), GOAL_COLOR_LINEAR),
                        place,
                    )
                })
        })
        .collect();
    // The contact shadows as the editor draws them: one under each character, one under
    // each prop.
    let shadows = characters
        .iter()
        .filter_map(|character| character_shadow(&character.capsules))
        .chain(props.iter().filter_map(prop_shadow))
        .collect();
    let scene = Scene {
        capsules: if figure.mesh.is_some() {
            Vec::new()
        } else {
            capsules.clone()
        },
        show_floor: true,
        show_avatar: figure.mesh.is_some(),
        avatar_palettes,
        more_avatar_poses,
        props: props
            .iter()
            .zip(&prop_meshes)
            .filter(|(_, mesh)| mesh.is_none())
            .map(|(prop, _)| prop_instance(prop))
            .collect(),
        mesh_props: props
            .iter()
            .zip(&prop_meshes)
            .filter_map(|(prop, mesh)| Some(mesh_prop_instance(prop, mesh.as_ref()?)))
            .collect(),
        shadows,
        markers,
        transparent_background: false,
        shading: shading(args.map, &camera, &capsules),
    };
    let options = ImageOptions {
        size_px,
        transparent: args.transparent,
        overlays: args.overlays,
    };
    let gpu = headless_gpu()?;
    let mut renderer = SceneRenderer::new(&gpu.device);
    renderer.set_avatar(
        &gpu.device,
        &gpu.queue,
        figure.mesh.as_ref().map(|mesh| &mesh.model),
    );
    let mut render = |scene: &Scene| {
        render_image(
            &gpu.device,
            &gpu.queue,
            &mut renderer,
            &camera,
            scene,
            &options,
        )?
        .wait(&gpu.device)
    };
    let pixels = if args.map == Some(ControlMap::Lines) {
        // Line art: from the depth and normal maps of the same view.
        let depth = render(&Scene {
            shading: Shading::depth_seen_by(&camera, &capsules),
            ..scene.clone()
        })?;
        let normal = render(&Scene {
            shading: Shading::Normal,
            ..scene
        })?;
        let rgba = line_art(&depth.rgba, &normal.rgba, depth.width, depth.height)
            .ok_or_else(|| anyhow!("the depth and normal maps differ in size"))?;
        Pixels { rgba, ..depth }
    } else {
        render(&scene)?
    };
    let png = encode_png(&pixels)?;
    std::fs::write(&args.out, png)
        .with_context(|| format!("cannot write {}", args.out.display()))?;
    eprintln!(
        "{}: {}x{} on {} ({:?}) in {:.2} s",
        args.out.display(),
        pixels.width,
        pixels.height,
        gpu.adapter.name,
        gpu.adapter.backend,
        started.elapsed().as_secs_f64()
    );
    Ok(())
}
