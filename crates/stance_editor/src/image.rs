//! *File > Save image*: the posture rendered offscreen through the viewport's camera, at the
//! chosen size, with or without background and overlays, as a PNG download. The image is
//! drawn here, beside the views, with the GPU: the viewport's [`ImageExport`] takes the
//! request, whoever has the GPU (the viewport, or a test) calls [`ImageExport::advance`]
//! every frame until it is done (the read-back is asynchronous: in the browser it completes
//! on a later frame), and the finished PNG goes to the model as a command
//! ([`FileCommand::SaveImage`]), which hands it to the host. *Export control maps* asks for
//! its depth, normal and mask maps the same way, one after another
//! ([`FileCommand::SaveControlMap`]).

use crate::cast_models::CastModels;
use crate::cast_view::{other_capsules, placed_capsule, placed_palettes, scene_from_character};
use crate::model::Outbox;
use crate::model::{FileCommand, NoticeCommand};
use glam::DVec3;
use stance_render::{
    BODY_COLOR_LINEAR, Capsule, GOAL_COLOR_LINEAR, ImageError, ImageOptions, OrbitCamera,
    PendingImage, Pixels, Scene, SceneRenderer, Shading, encode_png, line_art, render_image,
};

use crate::model::{Command, EditorModel, RenderedMap};

pub use crate::model::IMAGE_FILE_NAME;

/// Goal marker of a task that gave way or has a problem (linear RGB).
const GOAL_UNMET_LINEAR: [f32; 4] = [0.85, 0.3, 0.04, 1.0];
/// Goal marker of an inactive task (linear RGB).
const GOAL_INACTIVE_LINEAR: [f32; 4] = [0.25, 0.25, 0.25, 1.0];

/// An image the user asked for: size, background and overlays, and the camera it is seen
/// through (the viewport's when the user asked).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ImageRequest {
    /// Size, transparency, overlays.
    pub options: ImageOptions,
    /// The view.
    pub camera: OrbitCamera,
    /// A control map instead of the picture (then without background or overlays).
    pub map: Option<RenderedMap>,
}

/// The *Save image* work in progress: asked, then on its way back from the GPU.
#[derive(Debug, Default)]
pub struct ImageExport {
    /// The images asked for and not yet started, the next first.
    asked: std::collections::VecDeque<ImageRequest>,
    /// The image on its way back, and the map it is (none: the picture).
    pending: Option<(PendingImage, Option<RenderedMap>)>,
    /// Line art's depth map, back and waiting for its normal map.
    lines_depth: Option<Pixels>,
}

impl ImageExport {
    /// Asks for an image (replacing those asked and not yet started).
    pub fn request(&mut self, request: ImageRequest) {
        self.request_all(vec![request]);
    }

    /// Asks for images, made one after another (replacing those asked and not yet started).
    pub fn request_all(&mut self, requests: Vec<ImageRequest>) {
        self.asked = requests.into();
        self.lines_depth = None;
    }

    /// Whether an image is asked for or on its way.
    pub fn is_busy(&self) -> bool {
        !self.asked.is_empty() || self.pending.is_some()
    }

    /// Moves *Save image* along with the viewport's GPU: renders an asked image of `model`,
    /// and sends a finished one to the model, which hands it to the host as
    /// `stance-posture.png` (a control map under its own name). Never blocks; returns whether
    /// an image is still on its way (call again next frame). `renderer` draws each character
    /// on its model where it holds it, as `cast` says (the viewport's: which model is where),
    /// else as its capsules.
    pub fn advance(
        &mut self,
        model: &EditorModel,
        outbox: &mut Outbox,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        renderer: &mut SceneRenderer,
        cast: &CastModels,
    ) -> bool {
        if self.pending.is_none()
            && let Some(request) = self.asked.pop_front()
        {
            self.start(request, model, outbox, (device, queue, renderer), cast);
        }
        let Some((result, map)) = self
            .pending
            .as_mut()
            .and_then(|(pending, map)| Some((pending.poll(device)?, *map)))
        else {
            return self.is_busy();
        };
        self.pending = None;
        let result = match (map, result) {
            // Line art's first pass: keep the depth, render the normals next.
            (Some(RenderedMap::Lines), Ok(depth)) if self.lines_depth.is_none() => {
                self.lines_depth = Some(depth);
                return true;
            }
            // Its depth pass failed: not its normal pass either.
            (Some(RenderedMap::Lines), Err(error)) if self.lines_depth.is_none() => {
                if self
                    .asked
                    .front()
                    .is_some_and(|next| next.map == Some(RenderedMap::Lines))
                {
                    self.asked.pop_front();
                }
                Err(error)
            }
            (Some(RenderedMap::Lines), Ok(normal)) => self
                .lines_depth
                .take()
                .and_then(|depth| {
                    let rgba = line_art(&depth.rgba, &normal.rgba, depth.width, depth.height)?;
                    Some(Pixels { rgba, ..depth })
                })
                .ok_or(ImageError::Encode("the line art's maps differ".to_owned())),
            (_, result) => result,
        };
        match result.and_then(|pixels| encode_png(&pixels).map(|png| (pixels, png))) {
            Ok((pixels, png)) => outbox.send(Command::File(match map {
                None => FileCommand::SaveImage {
                    png,
                    width: pixels.width,
                    height: pixels.height,
                },
                Some(map) => FileCommand::SaveControlMap {
                    map,
                    png,
                    width: pixels.width,
                    height: pixels.height,
                },
            })),
            Err(error) => outbox.send(Command::Notice(NoticeCommand::Warn(format!(
                "The image could not be made: {error}."
            )))),
        }
        self.is_busy()
    }

    /// Renders `request` and starts reading it back (line art: its depth pass first, asking
    /// again for its normal pass).
    fn start(
        &mut self,
        request: ImageRequest,
        model: &EditorModel,
        outbox: &mut Outbox,
        (device, queue, renderer): (&wgpu::Device, &wgpu::Queue, &mut SceneRenderer),
        cast: &CastModels,
    ) {
        let mut scene = image_scene(model, renderer, cast);
        let camera = &request.camera;
        let mut options = request.options;
        let first_pass = self.lines_depth.is_none();
        if let Some(map) = request.map {
            scene.shading = shading(map, camera, model, first_pass);
            options.transparent = false;
            options.overlays = false;
        }
        match render_image(device, queue, renderer, camera, &scene, &options) {
            Ok(pending) => {
                self.pending = Some((pending, request.map));
                if request.map == Some(RenderedMap::Lines) && first_pass {
                    // The normal pass next.
                    self.asked.push_front(request);
                }
            }
            Err(error) => {
                self.lines_depth = None;
                outbox.send(Command::Notice(NoticeCommand::Warn(format!(
                    "The image could not be made: {error}."
                ))));
            }
        }
    }
}

/// How `map` colours the body: the depth map spans the mannequin's depth seen by `camera`;
/// line art is drawn from a depth map (its `first_pass`), then a normal map.
fn shading(
    map: RenderedMap,
    camera: &OrbitCamera,
    model: &EditorModel,
    first_pass: bool,
) -> Shading {
    let depth = || {
        let place = scene_from_character(model.character());
        let mut capsules: Vec<Capsule> = model
            .bones()
            .iter()
            .map(|bone| placed_capsule(bone.capsule, place))
            .collect();
        capsules.extend(other_capsules(model));
        Shading::depth_seen_by(camera, &capsules)
    };
    match map {
        RenderedMap::Depth => depth(),
        RenderedMap::Lines if first_pass => depth(),
        RenderedMap::Normal | RenderedMap::Lines => Shading::Normal,
        RenderedMap::Mask => Shading::Mask,
    }
}

/// What an image of `model` shows: each character on its model where `renderer` holds it (as
/// `cast` says), else as its capsules (the selected one's in its plain colour), the floor, and
/// each task's goal as a marker coloured by its status (met, gave way, inactive);
/// [`ImageOptions::scene`] drops the last two without overlays.
fn image_scene(model: &EditorModel, renderer: &SceneRenderer, cast: &CastModels) -> Scene {
    let session = model.session();
    let palettes = match model.avatar() {
        Some(avatar) if cast.avatar_in_place(avatar, renderer) => {
            avatar.palettes(session.humanoid(), session.posture())
        }
        None if cast.selected_as_figure(model, renderer) => cast
            .figure(session.level_of_articulation())
            .and_then(|figure| figure.palettes(session.skeleton(), session.posture())),
        _ => None,
    };
    let place = scene_from_character(model.character());
    let mut capsules: Vec<Capsule> = if palettes.is_some() {
        Vec::new()
    } else {
        model
            .bones()
            .iter()
            .map(|bone| Capsule {
                color_linear: BODY_COLOR_LINEAR,
                ..placed_capsule(bone.capsule, place)
            })
            .collect()
    };
    let others = cast.others(model, Some(renderer));
    capsules.extend(others.capsules);
    let avatar_palettes = palettes
        .map(|palettes| placed_palettes(palettes, place))
        .unwrap_or_default();
    Scene {
        capsules,
        props: crate::cast_view::prop_instances(model),
        mesh_props: crate::cast_view::mesh_prop_instances(model),
        shadows: crate::cast_view::contact_shadows(model),
        show_floor: true,
        show_avatar: !avatar_palettes.is_empty() || !others.more_avatar_poses.is_empty(),
        avatar_palettes,
        more_avatar_poses: others.more_avatar_poses,
        cast_poses: others.cast_poses,
        markers: goal_markers(model),
        ..Scene::default()
    }
}

/// Each task's goal as a marker, placed, coloured by its status (met, gave way, inactive).
fn goal_markers(model: &EditorModel) -> Vec<Capsule> {
    let session = model.session();
    let place = scene_from_character(model.character());
    session
        .tasks()
        .iter()
        .zip(session.statuses())
        .filter_map(|(task, status)| {
            let color = if !task.active {
                GOAL_INACTIVE_LINEAR
            } else if status.gave_way.is_some() || status.problem.is_some() {
                GOAL_UNMET_LINEAR
            } else {
                GOAL_COLOR_LINEAR
            };
            let goal = task.kind.goal_point()?;
            Some(placed_capsule(
                Capsule::marker(DVec3::from_array(goal).as_vec3(), color),
                place,
            ))
        })
        .collect()
}
