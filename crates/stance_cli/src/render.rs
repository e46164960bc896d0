//! `stance render DOC.json --out IMAGE.png`: the document's posture on its body, drawn natively
//! with wgpu on any adapter (lavapipe will do) through the same image path as the editor's
//! *File > Save image*. A scene (`stance_document::Scene`) draws every character at its
//! `Placement` and its props, placed by `stance_render::placed` as the editor places them.
//! Each character is on its own body (`bodies`): the avatar file its document names (found
//! by file name next to the document, then in `--assets`), else the mannequin; `--avatar
//! FILE` poses every character on that file instead. A mesh prop is drawn with its file: the
//! one the document carries (`Scene::files`), else the one of its name found as an avatar
//! file is (`files`: the one resolver of both).
//!
//! `--map openpose|depth|normal|mask` writes a control map for image generation instead, seen
//! by the same camera: the OpenPose skeleton (drawn on the CPU; with `--keypoints-out` its
//! keypoints as OpenPose JSON), or the figure's depth, normals, mask or line art (rendered
//! like the picture, unlit, on black). See docs/control-maps.md.

use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;

use anyhow::{Context, Result, anyhow, bail};
use glam::{DVec3, Mat4, Vec3};
use stance_asset::{PropMesh, load_prop_mesh};
use stance_document::{Document, Placement, PostureRest, Prop, SceneCharacter};
use stance_hanim::keypoints::KeypointFinder;
use stance_ik::{Frames, Posture};
use stance_render::{
    Capsule, CastPose, GOAL_COLOR_LINEAR, HiddenKeypoints, ImageOptions, KeypointUnits, OpenPose,
    OrbitCamera, Pixels, Scene, SceneRenderer, Shading, SkinnedModel, ViewPreset, character_shadow,
    encode_png, headless_gpu, line_art, mesh_prop_instance, placed_capsule, placed_keypoints,
    placed_palettes, posed_mannequin_bones, prop_corners, prop_instance, prop_shadow, render_image,
    scene_from_character,
};

use crate::avatar;

mod bodies;
mod files;

use bodies::{Bodies, Body, MeshFigure};
use files::{Found, SceneFiles};

/// `stance render DOC.json --out IMAGE.png [--avatar FILE] [--view VIEW] [--size WxH]
/// [--map openpose [--keypoints-out K.json] [--normalized] [--hidden keep|missing]]
/// [--map depth|normal|mask|lines] [--assets DIR]`.
#[derive(clap::Args, Debug)]
pub struct RenderArgs {
    /// The document or scene (JSON, as the editor exports it): a scene's characters are all
    /// drawn at their placements, each on its own avatar, with its props, one OpenPose person
    /// each.
    pub document: PathBuf,
    /// The PNG to write.
    #[arg(long)]
    pub out: PathBuf,
    /// An avatar (.glb, .gltf, .vrm) to pose every character on, overriding each document's
    /// own. Without it each character is drawn on the avatar its document names (the file of
    /// its URL's name, in the document's folder, then in --assets), or on the mannequin: the
    /// default body, and where that file is missing or fails to load (with a warning).
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
    /// Draw the characters on the mannequin as capsules (the editor's capsule view) instead of
    /// its skinned figure; those on an avatar file keep its mesh.
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
    /// A folder the scene's files are looked for in after the document's own: a character's
    /// avatar file, and a mesh prop's file (`"file": "chair.glb"`) that the document does not
    /// carry (a saved document carries them, `"files"`, and its own file is drawn first); a
    /// prop's file found nowhere is drawn as its box, with a warning.
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

/// One character of the scene posed on its body.
struct PosedCharacter {
    /// Its name (the outliner's): what notes and errors call it.
    name: String,
    /// Its body's index in [`Posed::bodies`].
    body: usize,
    placement: Placement,
    document: Document,
    posture: Posture,
    frames: Frames,
    /// The mannequin's capsules of the posed body, in the scene (drawn without an avatar; the
    /// body that hides keypoints in a control map).
    capsules: Vec<Capsule>,
}

/// The scene's characters posed on their bodies, its props (each mesh prop's file's
/// triangles when found), and the camera that sees them.
struct Posed {
    bodies: Vec<Body>,
    characters: Vec<PosedCharacter>,
    props: Vec<Prop>,
    prop_meshes: Vec<Option<Arc<PropMesh>>>,
    camera: OrbitCamera,
}

/// The triangles of each of `props` that is a mesh prop whose file is found (`files`: the
/// document's own, else on disk); `None` for the others. Each file is read once. A file not
/// found is drawn as its box (with a warning); one that is not a static mesh is an error
/// naming it.
fn prop_meshes(files: &SceneFiles, props: &[Prop]) -> Result<Vec<Option<Arc<PropMesh>>>> {
    let mut read: Vec<(&str, Option<Arc<PropMesh>>)> = Vec::new();
    let mut meshes = Vec::with_capacity(props.len());
    for prop in props {
        let Some(file) = prop.shape.file() else {
            meshes.push(None);
            continue;
        };
        let mesh = match read.iter().find(|(name, _)| *name == file) {
            Some((_, mesh)) => mesh.clone(),
            None => {
                let mesh = prop_mesh(files, prop, file)?;
                read.push((file, mesh.clone()));
                mesh
            }
        };
        meshes.push(mesh);
    }
    Ok(meshes)
}

/// The triangles of `file`, the mesh `prop` names, as `files` finds it; `None` (with a
/// warning) when it is nowhere.
fn prop_mesh(files: &SceneFiles, prop: &Prop, file: &str) -> Result<Option<Arc<PropMesh>>> {
    let mesh = match files.find(file) {
        // As the editor reads a file a document carries: on its own, without files beside it.
        Found::Carried(bytes) => load_prop_mesh(&bytes, &mut |_| None)
            .map_err(|e| anyhow!("prop {} ({file}, carried by the document): {e}", prop.name))?,
        Found::OnDisk(path) => {
            let bytes = std::fs::read(&path)
                .with_context(|| format!("prop {}: cannot read {}", prop.name, path.display()))?;
            load_prop_mesh(&bytes, &mut avatar::resolver_next_to(&path))
                .map_err(|e| anyhow!("prop {} ({}): {e}", prop.name, path.display()))?
        }
        Found::Missing => {
            eprintln!(
                "warning: prop {}: {file} not found in {} (--assets DIR): drawn as its box",
                prop.name,
                files.folders_text()
            );
            return Ok(None);
        }
    };
    Ok(Some(Arc::new(mesh)))
}

impl Posed {
    fn new(args: &RenderArgs, size_px: [u32; 2]) -> Result<Posed> {
        let path = args.document.display();
        let text = std::fs::read_to_string(&args.document)
            .with_context(|| format!("cannot read {path}"))?;
        // A plain document is a scene of one character at the origin.
        let mut scene = stance_document::Scene::from_json(&text)
            .map_err(|e| anyhow!("invalid document {path}: {e}"))?;
        let files = SceneFiles::new(args, std::mem::take(&mut scene.files));
        let Bodies {
            bodies,
            of_character,
        } = bodies::bodies(args, &files, &scene.characters)?;
        let several = scene.characters.len() > 1;
        let characters = scene
            .characters
            .into_iter()
            .zip(of_character)
            .enumerate()
            .map(|(index, (character, body))| {
                // A scene's error names the character (its index and name in the outliner).
                let which = if several {
                    format!("character {index} ({})", character.name)
                } else {
                    String::new()
                };
                let on = bodies
                    .get(body)
                    .ok_or_else(|| anyhow!("{path}: no body for {}", character.name))?;
                pose_character(on, body, character).map_err(|e| {
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
            bodies,
            characters,
            prop_meshes: prop_meshes(&files, &scene.props)?,
            props: scene.props,
            camera,
        })
    }

    /// The body `character` is posed on.
    fn body(&self, character: &PosedCharacter) -> Result<&Body> {
        self.bodies
            .get(character.body)
            .ok_or_else(|| anyhow!("{}: no body", character.name))
    }

    /// Every character's capsules, in the scene.
    fn capsules(&self) -> Vec<Capsule> {
        self.characters
            .iter()
            .flat_map(|character| character.capsules.iter().copied())
            .collect()
    }
}

/// `character`'s document posed on `body` (index `body_index`), its capsules placed in the
/// scene.
fn pose_character(
    body: &Body,
    body_index: usize,
    character: SceneCharacter,
) -> Result<PosedCharacter> {
    let SceneCharacter {
        name,
        placement,
        document,
    } = character;
    // Made on an avatar before a posture meant the same pose on every body: relative to
    // that avatar's own rest, taken to be the one drawn (as `export-posed` takes it, and as
    // the editor opens a document on the avatar it names).
    let document = if body.file.is_some() && document.rest == PostureRest::Avatar {
        eprintln!(
            "note: {name}: the document's values are relative to the avatar's own rest (made before a posture meant the same pose on every body); converted to the H-Anim standard pose"
        );
        document.in_standard_rest(&body.humanoid)
    } else {
        document
    };
    let skeleton = &body.humanoid.skeleton;
    let posture = document.to_posture(skeleton)?;
    let frames = Frames::new(skeleton, &posture);
    let place = scene_from_character(&placement);
    let capsules: Vec<Capsule> = posed_mannequin_bones(skeleton, &frames)
        .into_iter()
        .map(|bone| placed_capsule(bone.capsule, place))
        .collect();
    Ok(PosedCharacter {
        name,
        body: body_index,
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
            render_picture(&args, &posed, size_px, started)
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
    // Each character's keypoints found on its own body's skeleton, the one it is drawn on.
    let finders: Vec<KeypointFinder> = posed
        .bodies
        .iter()
        .map(|body| KeypointFinder::new(&body.humanoid.skeleton))
        .collect();
    let bodies = posed.capsules();
    let hidden = args.hidden.unwrap_or(Hidden::Keep).keypoints();
    let people = posed
        .characters
        .iter()
        .map(|character| {
            let skeleton = &posed.body(character)?.humanoid.skeleton;
            let finder = finders
                .get(character.body)
                .ok_or_else(|| anyhow!("{}: no body", character.name))?;
            Ok(placed_keypoints(
                &finder.find(skeleton, &character.frames),
                &character.placement,
            ))
        })
        .collect::<Result<Vec<_>>>()?;
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

/// The palettes of `character`'s posture on its body's mesh (carried over joint by joint onto
/// the mesh's skeleton: the mannequin's figure has its own), in the character's frame.
fn mesh_pose(body: &Body, mesh: &MeshFigure, character: &PosedCharacter) -> Result<Vec<Vec<Mat4>>> {
    let carried = Posture::carried_over(
        &mesh.skeleton.skeleton,
        &body.humanoid.skeleton,
        &character.posture,
    );
    mesh.palettes
        .pose(&mesh.avatar, &mesh.skeleton, &carried)
        .ok_or_else(|| {
            anyhow!(
                "{}: the posture does not fit the avatar's skeleton",
                character.name
            )
        })
}

/// The task goals of every character, as markers placed in the scene.
fn goal_markers(characters: &[PosedCharacter]) -> Vec<Capsule> {
    characters
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
        .collect()
}

/// The picture's scene: each character on its body's mesh (a pose of that body's model among
/// the cast's) or as its capsules (the mannequin with `--capsules`), the props, the goals and
/// the contact shadows; and the cast's models, in the order [`CastPose::model`] counts them.
fn picture_scene<'a>(
    args: &RenderArgs,
    posed: &'a Posed,
) -> Result<(Scene, Vec<&'a SkinnedModel>)> {
    let mut models = Vec::new();
    let model_of: Vec<Option<usize>> = posed
        .bodies
        .iter()
        .map(|body| {
            let mesh = body.mesh.as_ref()?;
            models.push(&mesh.model);
            Some(models.len() - 1)
        })
        .collect();
    let mut cast_poses = Vec::new();
    let mut capsules = Vec::new();
    for character in &posed.characters {
        let body = posed.body(character)?;
        match (&body.mesh, model_of.get(character.body).copied().flatten()) {
            (Some(mesh), Some(model)) => cast_poses.push(CastPose {
                model,
                palettes: placed_palettes(
                    mesh_pose(body, mesh, character)?,
                    scene_from_character(&character.placement),
                ),
            }),
            _ => capsules.extend(character.capsules.iter().copied()),
        }
    }
    // The contact shadows as the editor draws them: one under each character, one under
    // each prop.
    let shadows = posed
        .characters
        .iter()
        .filter_map(|character| character_shadow(&character.capsules))
        .chain(posed.props.iter().filter_map(prop_shadow))
        .collect();
    let props = || posed.props.iter().zip(&posed.prop_meshes);
    let scene = Scene {
        capsules,
        show_floor: true,
        cast_poses,
        props: props()
            .filter(|(_, mesh)| mesh.is_none())
            .map(|(prop, _)| prop_instance(prop))
            .collect(),
        mesh_props: props()
            .filter_map(|(prop, mesh)| Some(mesh_prop_instance(prop, mesh.as_ref()?)))
            .collect(),
        shadows,
        markers: goal_markers(&posed.characters),
        shading: shading(args.map, &posed.camera, &posed.capsules()),
        ..Scene::default()
    };
    Ok((scene, models))
}

/// The picture itself, or a depth, normal or mask map, rendered with wgpu.
fn render_picture(
    args: &RenderArgs,
    posed: &Posed,
    size_px: [u32; 2],
    started: Instant,
) -> Result<()> {
    let (scene, models) = picture_scene(args, posed)?;
    let camera = &posed.camera;
    let options = ImageOptions {
        size_px,
        transparent: args.transparent,
        overlays: args.overlays,
    };
    let gpu = headless_gpu()?;
    let mut renderer = SceneRenderer::new(&gpu.device);
    renderer.set_cast_models(&gpu.device, &gpu.queue, &models);
    let mut render = |scene: &Scene| {
        render_image(
            &gpu.device,
            &gpu.queue,
            &mut renderer,
            camera,
            scene,
            &options,
        )?
        .wait(&gpu.device)
    };
    let pixels = if args.map == Some(ControlMap::Lines) {
        // Line art: from the depth and normal maps of the same view.
        let depth = render(&Scene {
            shading: Shading::depth_seen_by(camera, &posed.capsules()),
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
