//! The editor's observable state as JSON, built when the page's test hook or a script asks
//! (never per frame): the document, joint positions in the world and on screen (CSS pixels),
//! per-task statuses, the notice, the handles on screen, the sensors, the frame's timings and
//! the rectangles of the main buttons.

use serde_json::{Map, Value, json};

use super::viewport_panel::ViewportPanel;
use crate::model::EditorModel;

/// What the page's state is built from.
pub(super) struct PageState<'a> {
    pub model: &'a EditorModel,
    pub viewport: &'a ViewportPanel,
    /// Screen rectangles (points) of named buttons.
    pub buttons: &'a [(&'static str, egui::Rect)],
    /// CPU time of the last frame (ms).
    pub frame_ms: f64,
}

impl PageState<'_> {
    /// The state as a JSON text.
    pub(super) fn to_json(&self) -> String {
        let model = self.model;
        let session = model.session();
        let skeleton = session.skeleton();
        let rect = self.viewport.rect;
        let (joints, screen) = self.joints();
        let document = serde_json::from_str::<Value>(&session.document().to_json(false))
            .unwrap_or(Value::Null);
        json!({
            "revision": session.revision(),
            "settled": session.is_settled(),
            "loa": session.level_of_articulation().number(),
            "document": document,
            "joints": joints,
            "screen": screen,
            "tasks": self.tasks(),
            "gave_way": session.report().and_then(|report| report.gave_way),
            "notice": model.notice().map(|notice| json!({"text": notice.text, "error": notice.is_error})),
            "avatar": model.avatar().map(|avatar| json!({
                "name": avatar.name,
                "vertices": avatar.vertex_count,
                "triangles": avatar.triangle_count,
                "uploaded": self.viewport.avatar_uploaded,
                "upload_tasks": self.viewport.avatar_upload_tasks,
                "mapped": avatar.mapping_summary().0,
                "images_from_host": avatar.images_from_host,
                "imported_in_worker": avatar.load.in_worker,
                "load_ms": {
                    "import": avatar.load.import_ms,
                    "transfer": avatar.load.transfer_ms,
                    "build": avatar.load.build_ms,
                    "session": avatar.load.session_ms,
                    "upload": self.viewport.avatar_upload_ms,
                },
            })),
            "importing": model.importing(),
            "figure": self.viewport.figure_shown(model),
            "selected": model.selected_joint().and_then(|joint| skeleton.joints().get(joint)).map(|joint| joint.name.clone()),
            "pulling": model.is_pulling(),
            "dragging_handle": model.gesture().is_some() && !model.is_pulling(),
            "undo_steps": model.history().undo_steps(),
            "can_redo": model.history().can_redo(),
            "library": model.library().entries().iter().map(|entry| entry.name.clone()).collect::<Vec<_>>(),
            "solver_ms": model.solver_ms(),
            "frame_ms": self.frame_ms,
            "scene_ms": self.viewport.scene_ms,
            "render_ms": self.viewport.render_ms,
            "wasm_memory_bytes": wasm_memory_bytes(),
            "viewport": [rect.min.x, rect.min.y, rect.width(), rect.height()],
            "buttons": self.buttons(),
            "goals": self.goals(),
            "rings": self.rings(),
            "sensors": self.sensors(),
            "swivel": self.viewport.handles(model).swivel_state(),
            "motion": self.motion(),
            "characters": self.characters(),
            "props": self.props(),
            "between": self.between(),
            "photo": self.photo(),
            "lifting": model.lifting().map(|lifting| lifting.words()),
            "collision": self.collision(),
        })
        .to_string()
    }

    /// Collision avoidance: on or off, the capsules shown or not, the contacts held (their
    /// distances, m), and the body's capsules as posed (the joint carrying each, its ends in
    /// the character's frame and its radius, m).
    fn collision(&self) -> Value {
        let model = self.model;
        let session = model.session();
        let skeleton = session.skeleton();
        let capsules: Vec<Value> = model
            .bones()
            .iter()
            .filter_map(|bone| {
                let joint = skeleton.joints().get(bone.owner)?;
                let (a, b) = (bone.capsule.start_world, bone.capsule.end_world);
                Some(json!({
                    "joint": joint.name,
                    "a": [a.x, a.y, a.z],
                    "b": [b.x, b.y, b.z],
                    "radius": bone.capsule.radius_m,
                }))
            })
            .collect();
        json!({
            "on": session.collision_on(),
            "capsules_shown": model.show_capsules(),
            "contacts": session.contacts().iter().map(|c| c.distance).collect::<Vec<_>>(),
            "capsules": capsules,
        })
    }

    /// The scene's characters in order: name, id, whether selected, placement, and where the
    /// middle of the pelvis shows on screen (to click one).
    /// The props with their centres on screen, and the selected one's gizmo (two points of
    /// its ring a quarter turn apart, and its square).
    fn props(&self) -> Value {
        let model = self.model;
        let lens = self.viewport.lens();
        let on_screen = |p: Option<egui::Pos2>| p.map(|p| [p.x, p.y]);
        let props: Vec<Value> = model
            .props()
            .iter()
            .map(|prop| {
                let centre = glam::DVec3::from_array(prop.position);
                json!({
                    "name": prop.name,
                    "shape": prop.shape.name(),
                    "file": prop.shape.file(),
                    "position": prop.position,
                    "rotation": prop.rotation,
                    "dimensions": prop.shape.dimensions(),
                    "screen": on_screen(lens.scene_screen_point(centre)),
                })
            })
            .collect();
        let gizmo = self
            .viewport
            .props
            .handles_on_screen(model, &lens)
            .map(|(ring, square)| {
                json!({
                    // An eighth of a turn from the square, and a quarter further.
                    "ring": on_screen(ring.get(ring.len() / 8).copied()),
                    "ring_quarter": on_screen(ring.get(3 * ring.len() / 8).copied()),
                    "square": [square.x, square.y],
                })
            });
        json!({
            "list": props,
            "selected": self.viewport.props.selected(model),
            "gizmo": gizmo,
        })
    }

    /// The reference photo (*File > Open photo*), if any.
    fn photo(&self) -> Value {
        let model = self.model;
        json!(model.photo().map(|photo| json!({
            "name": photo.name,
            "size": photo.size_px,
            "reference_size": photo.reference_size_px,
            "shown": model.photo_shown(),
            "rect": self.viewport.photo_rect.map(|r| [r.min.x, r.min.y, r.width(), r.height()]),
            "keypoints": photo.keypoints,
            "detect_ms": photo.detect_ms,
            "lift_ms": photo.lift_ms,
        })))
    }

    /// The tasks between characters, each with how far apart its points are.
    fn between(&self) -> Vec<Value> {
        let model = self.model;
        model
            .between_tasks()
            .iter()
            .zip(model.between_distances())
            .map(|(task, distance)| {
                json!({
                    "description": model.between_description(task),
                    "level": task.level,
                    "distance": distance,
                })
            })
            .collect()
    }

    fn characters(&self) -> Vec<Value> {
        let lens = self.viewport.lens();
        self.model
            .characters()
            .map(|(character, selected)| {
                let placement = character.placement();
                let pelvis = character
                    .session()
                    .joint_position("sacroiliac")
                    .and_then(|p| {
                        lens.scene_screen_point(
                            placement.scene_from_character().transform_point3(p),
                        )
                    });
                json!({
                    "name": character.name(),
                    "id": character.id(),
                    "avatar": character.avatar().map(|avatar| avatar.name.clone()),
                    "selected": selected,
                    "position": placement.position,
                    "yaw": placement.yaw_degrees,
                    "pelvis_screen": pelvis.map(|p| [p.x, p.y]),
                })
            })
            .collect()
    }

    /// Joint positions in the world (m) and on screen (points), by joint name.
    fn joints(&self) -> (Map<String, Value>, Map<String, Value>) {
        let session = self.model.session();
        let frames = session.frames();
        let rect = self.viewport.rect;
        let lens = self.viewport.lens();
        let mut joints = Map::new();
        let mut screen = Map::new();
        for (index, joint) in session.skeleton().joints().iter().enumerate() {
            let Some(position) = frames.joint_position.get(index) else {
                continue;
            };
            joints.insert(
                joint.name.clone(),
                json!([position.x, position.y, position.z]),
            );
            if rect.is_positive()
                && let Some(pixel) = lens.screen_point(*position)
            {
                screen.insert(joint.name.clone(), json!([pixel.x, pixel.y]));
            }
        }
        (joints, screen)
    }

    /// Each task in words with its level and status.
    fn tasks(&self) -> Vec<Value> {
        let session = self.model.session();
        session
            .tasks()
            .iter()
            .zip(session.statuses())
            .map(|(task, status)| {
                json!({
                    "description": task.description(),
                    "level": task.level,
                    "active": task.active,
                    "residual": status.residual,
                    "gave_way": status.gave_way,
                    "problem": status.problem,
                })
            })
            .collect()
    }

    fn buttons(&self) -> Map<String, Value> {
        self.buttons
            .iter()
            .map(|(name, rect)| {
                (
                    (*name).to_owned(),
                    json!([rect.min.x, rect.min.y, rect.width(), rect.height()]),
                )
            })
            .collect()
    }

    /// The draggable goals on screen.
    fn goals(&self) -> Vec<Value> {
        let lens = self.viewport.lens();
        self.viewport
            .handles(self.model)
            .goal_handles()
            .into_iter()
            .filter_map(|(task, goal)| {
                let pixel = lens.screen_point(goal)?;
                Some(json!({"task": task, "screen": [pixel.x, pixel.y]}))
            })
            .collect()
    }

    /// The rings of the selected joint on screen, with their DOF and value.
    fn rings(&self) -> Vec<Value> {
        let session = self.model.session();
        let lens = self.viewport.lens();
        let handles = self.viewport.handles(self.model);
        handles
            .rings()
            .iter()
            .filter_map(|ring| {
                let point = handles.ring_points(ring).first().copied()?;
                let centre = lens.screen_point(ring.centre_world)?;
                Some(json!({
                    "dof": session.skeleton().dof_name(ring.dof),
                    "index": ring.dof,
                    "value": session.posture().values().get(ring.dof),
                    "screen": [point.x, point.y],
                    "centre": [centre.x, centre.y],
                }))
            })
            .collect()
    }

    /// The timeline: frames, playhead, playback, keys and the clip's contacts.
    fn motion(&self) -> Value {
        let model = self.model;
        let timeline = model.timeline();
        json!({
            "frames": model.frame_count(),
            "frame": timeline.frame(),
            "fps": 1.0 / model.frame_time(),
            "playing": timeline.is_playing(),
            "looping": timeline.is_looping(),
            "speed": timeline.speed(),
            "keys": model.key_frames(),
            "contacts": timeline.contacts().len(),
            "clip": timeline.clip_name(),
            "opening": timeline.opening().map(|(name, progress)| json!({"name": name, "progress": progress})),
        })
    }

    /// The sensors' state, with the local and world rotation of every joint they drive.
    fn sensors(&self) -> Value {
        let session = self.model.session();
        let mut state = self.model.sensors().state_json();
        let skeleton = session.skeleton();
        let posture = session.posture();
        let frames = session.frames();
        let driven: Map<String, Value> = session
            .held_joints()
            .into_iter()
            .filter_map(|joint| {
                let name = skeleton.joints().get(joint)?.name.clone();
                let local = posture.local_rotation(skeleton, joint);
                let world = frames.rotation(joint);
                Some((
                    name,
                    json!({
                        "local": [local.x, local.y, local.z, local.w],
                        "world": [world.x, world.y, world.z, world.w],
                    }),
                ))
            })
            .collect();
        if let Value::Object(map) = &mut state {
            map.insert("driven".to_owned(), Value::Object(driven));
        }
        state
    }
}

/// The WebAssembly memory the editor holds (bytes); `None` natively.
fn wasm_memory_bytes() -> Option<u64> {
    #[cfg(target_arch = "wasm32")]
    {
        Some(core::arch::wasm32::memory_size::<0>() as u64 * 65_536)
    }
    #[cfg(not(target_arch = "wasm32"))]
    {
        None
    }
}
