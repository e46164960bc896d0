//! The GPU models the scene's characters are drawn on. Every character is drawn skinned on its
//! own body: its avatar, or the mannequin's figure (the generated default avatar, one mesh at
//! every level of articulation). The renderer's avatar place holds the selected character's
//! model; the cast's models (`SceneRenderer::insert_cast_model`, kept there by a key) hold
//! those of the other characters that differ from it. A model is on the GPU once, whatever
//! the number of characters on it ([`ModelKey`]: the avatar file, or the figure); a model no
//! character is drawn on any more is dropped at the next frame ([`CastModels::update`]); and
//! when the selection changes, the models change places between the avatar's and the cast's
//! without being uploaded again.
//!
//! Uploads: the selected character's avatar goes up in steps as before (the viewport's
//! `begin_avatar_upload`, by the frames or in the host's tasks). The other characters' models
//! that are not on the GPU yet (an avatar whose model was dropped and is wanted again, a figure
//! where the selected character is on an avatar) go up in the same steps
//! ([`stance_render::AvatarUpload`], a band of texture rows each), stepped by the frames only
//! ([`CastModels::upload_share`], within a frame's share and never in a frame whose share the
//! selected avatar's upload took): the host's tasks step the selected one's alone, since their
//! last step tells the page its avatar is shown. Meanwhile those characters are capsules.

use std::hash::{DefaultHasher, Hash, Hasher};
use std::sync::Arc;

use glam::Mat4;
use stance_hanim::LevelOfArticulation;
use stance_render::{AvatarUpload, Capsule, CastPose, SceneRenderer, SkinnedModel, avatar_model};

use crate::avatar::LoadedAvatar;
use crate::cast_view::{other_capsules_of, placed_palettes, scene_from_character};
use crate::figure::MannequinFigure;
use crate::model::{Character, EditorModel};

/// The model a character is drawn on: the characters of one key share one GPU model.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub enum ModelKey {
    /// The mannequin's figure.
    Figure,
    /// An avatar file: its name, and the size of its mesh (two files of one name differ
    /// there).
    Avatar {
        /// The file's name or URL.
        name: String,
        /// Its meshes' vertices.
        vertices: usize,
        /// Its meshes' triangles.
        triangles: usize,
    },
}

impl ModelKey {
    /// The model of a loaded avatar.
    pub fn of_avatar(avatar: &LoadedAvatar) -> Self {
        Self::Avatar {
            name: avatar.name.clone(),
            vertices: avatar.vertex_count,
            triangles: avatar.triangle_count,
        }
    }

    /// The model `character` is drawn on.
    pub fn of(character: &Character) -> Self {
        character.avatar().map_or(Self::Figure, Self::of_avatar)
    }

    /// The key the renderer keeps its model by.
    fn id(&self) -> u64 {
        let mut hasher = DefaultHasher::new();
        self.hash(&mut hasher);
        hasher.finish()
    }
}

/// Where a model is, once it has taken the avatar's place.
enum Placed {
    /// There, complete.
    Complete,
    /// On its way there (`SceneRenderer::continue_avatar_upload` steps it).
    Uploading,
    /// Neither: to be uploaded.
    Missing,
}

/// How the characters other than the selected one are drawn this frame.
#[derive(Debug, Default)]
pub struct OtherFigures {
    /// The capsules of those drawn as capsules (the capsules view, or their model not on the
    /// GPU yet), in the others' grey.
    pub capsules: Vec<Capsule>,
    /// The poses of those on the model in the avatar's place ([`stance_render::Scene`]'s
    /// `more_avatar_poses`).
    pub more_avatar_poses: Vec<Vec<Vec<Mat4>>>,
    /// The poses of those on the cast's models.
    pub cast_poses: Vec<CastPose>,
}

/// The models on the GPU of one renderer: which is in the avatar's place, those on their way
/// to the cast, and the figures that pose the characters on the mannequin.
#[derive(Debug, Default)]
pub struct CastModels {
    /// The model in the renderer's avatar place, complete or on its way: the selected
    /// character's (or the last one's, until another takes its place).
    place: Option<ModelKey>,
    /// The cast's models on their way to the GPU, the next first.
    uploads: Vec<(ModelKey, AvatarUpload)>,
    /// The figures that pose the characters on the mannequin, one per level of articulation
    /// in use.
    figures: Vec<(LevelOfArticulation, MannequinFigure)>,
    /// Whether the characters on the mannequin are drawn as its figure (else as capsules).
    figures_shown: bool,
}

impl CastModels {
    /// Puts the selected character's avatar (`key`, its GPU model `mesh`) in the renderer's
    /// avatar place: from the cast when it is there (or left in place when it is there
    /// already), the model there before going to the cast; else its upload goes on (one
    /// under way for the cast, or in place) or is begun (`SceneRenderer::continue_avatar_upload`
    /// steps it). Returns whether it is on its way (else it is in place, complete).
    pub fn begin_selected(
        &mut self,
        renderer: &mut SceneRenderer,
        key: ModelKey,
        mesh: Arc<SkinnedModel>,
    ) -> bool {
        match self.take_place(renderer, key) {
            Placed::Complete => false,
            Placed::Uploading => true,
            Placed::Missing => {
                renderer.begin_avatar_upload(mesh);
                true
            }
        }
    }

    /// Brings the models in line with the scene, once a frame before it is drawn (with
    /// `figures_shown`: the characters on the mannequin drawn as its figure): the figures
    /// that pose the characters on the mannequin made for the levels in use; the selected
    /// character on the mannequin with the figure in the avatar's place (from the cast, or
    /// uploaded at once: it is small), or an avatar left there moved to the cast; the models
    /// of the other characters that differ from the one in the avatar's place kept, or their
    /// uploads begun ([`CastModels::upload_share`] steps them); the cast's models and uploads
    /// no character is on any more dropped. An error: the figure could not be made.
    pub fn update(
        &mut self,
        model: &EditorModel,
        renderer: &mut SceneRenderer,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        figures_shown: bool,
    ) -> Result<(), String> {
        self.figures_shown = figures_shown;
        self.keep_figures(model)?;
        if model.avatar().is_none() {
            if figures_shown {
                self.place_figure(renderer, device, queue)?;
            } else if matches!(self.place, Some(ModelKey::Avatar { .. })) {
                self.leave_place(renderer);
            }
        }
        let wanted = self.wanted(model);
        let ids: Vec<u64> = wanted.iter().map(ModelKey::id).collect();
        renderer.retain_cast_models(|id| ids.contains(&id));
        self.uploads.retain(|(key, _)| wanted.contains(key));
        for key in wanted {
            let on_its_way = self.uploads.iter().any(|(k, _)| *k == key);
            if on_its_way || renderer.cast_model_index(key.id()).is_some() {
                continue;
            }
            if let Some(mesh) = self.mesh_of(&key, model) {
                self.uploads.push((key, AvatarUpload::new(mesh)));
            }
        }
        Ok(())
    }

    /// A share of the cast's uploads under way: at most `most_steps` steps, stopping after
    /// `most_ms`; a model complete joins the cast's. Returns whether more is left.
    pub fn upload_share(
        &mut self,
        renderer: &mut SceneRenderer,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        most_steps: usize,
        most_ms: f64,
    ) -> bool {
        let started = web_time::Instant::now();
        let mut steps = 0;
        while steps < most_steps && started.elapsed().as_secs_f64() * 1e3 < most_ms {
            let Some((key, upload)) = self.uploads.first_mut() else {
                break;
            };
            steps += 1;
            if let Some(gpu) = renderer.step_upload(upload, device, queue) {
                let id = key.id();
                self.uploads.remove(0);
                renderer.insert_cast_model(id, gpu);
            }
        }
        !self.uploads.is_empty()
    }

    /// Whether a model of the cast is on its way to the GPU.
    pub fn is_uploading(&self) -> bool {
        !self.uploads.is_empty()
    }

    /// Whether the selected character, on the mannequin, is drawn as the figure: figures are
    /// shown, the figure is in the avatar's place, and neither the heat map nor the capsules
    /// view colours or shows its capsules.
    pub fn selected_as_figure(&self, model: &EditorModel, renderer: &SceneRenderer) -> bool {
        model.avatar().is_none()
            && self.figures_shown
            && self.place == Some(ModelKey::Figure)
            && renderer.avatar().is_some()
            && !model.comfort().heat_map()
            && !model.show_capsules()
    }

    /// Whether `avatar`'s model is in the avatar's place, complete.
    pub fn avatar_in_place(&self, avatar: &LoadedAvatar, renderer: &SceneRenderer) -> bool {
        renderer.avatar().is_some() && self.place == Some(ModelKey::of_avatar(avatar))
    }

    /// The figure that poses a character on the mannequin at `loa` (that level's, else any).
    pub fn figure(&self, loa: LevelOfArticulation) -> Option<&MannequinFigure> {
        self.figures
            .iter()
            .find(|(at, _)| *at == loa)
            .or(self.figures.first())
            .map(|(_, figure)| figure)
    }

    /// How the characters other than the selected one are drawn with the models `renderer`
    /// holds (none: no GPU): each on its model, placed, when that model is on the GPU (in the
    /// avatar's place: more poses of it; else one of the cast's); as capsules in the capsules
    /// view, on the mannequin when figures are not shown, or while its model is on its way.
    pub fn others(&self, model: &EditorModel, renderer: Option<&SceneRenderer>) -> OtherFigures {
        let mut drawn = OtherFigures::default();
        let renderer = renderer.filter(|_| !model.show_capsules());
        for character in model.other_characters() {
            let place = scene_from_character(character);
            match renderer.and_then(|renderer| self.pose(character, renderer)) {
                Some((None, palettes)) => drawn
                    .more_avatar_poses
                    .push(placed_palettes(palettes, place)),
                Some((Some(model), palettes)) => drawn.cast_poses.push(CastPose {
                    model,
                    palettes: placed_palettes(palettes, place),
                }),
                None => drawn.capsules.extend(other_capsules_of(character)),
            }
        }
        drawn
    }

    /// `character`'s palettes (in its own frame) and the model that draws them: `None` the
    /// avatar's place, else the index of one of the cast's. `None` when it is not on the GPU.
    fn pose(
        &self,
        character: &Character,
        renderer: &SceneRenderer,
    ) -> Option<(Option<usize>, Vec<Vec<Mat4>>)> {
        let key = ModelKey::of(character);
        if key == ModelKey::Figure && !self.figures_shown {
            return None;
        }
        let model = if self.place.as_ref() == Some(&key) && renderer.avatar().is_some() {
            None
        } else {
            Some(renderer.cast_model_index(key.id())?)
        };
        let session = character.session();
        let palettes = match character.avatar() {
            Some(avatar) => avatar.palettes(session.humanoid(), session.posture()),
            None => self
                .figure(session.level_of_articulation())?
                .palettes(session.skeleton(), session.posture()),
        }?;
        Some((model, palettes))
    }

    /// Makes `key` the model of the avatar's place: there already, or from the cast, or its
    /// upload for the cast going on there (the model there before, or its upload, goes to the
    /// cast).
    fn take_place(&mut self, renderer: &mut SceneRenderer, key: ModelKey) -> Placed {
        if self.place.as_ref() == Some(&key) {
            if renderer.avatar().is_some() {
                renderer.cancel_avatar_upload();
                return Placed::Complete;
            }
            if renderer.is_uploading_avatar() {
                return Placed::Uploading;
            }
        }
        self.leave_place(renderer);
        let from_cast = renderer.remove_cast_model(key.id());
        let uploading = self.uploads.iter().position(|(k, _)| *k == key);
        let upload = uploading.map(|at| self.uploads.remove(at).1);
        self.place = Some(key);
        match (from_cast, upload) {
            (Some(gpu), _) => {
                renderer.put_avatar(gpu);
                Placed::Complete
            }
            (None, Some(upload)) => {
                renderer.resume_avatar_upload(upload);
                Placed::Uploading
            }
            (None, None) => Placed::Missing,
        }
    }

    /// Empties the avatar's place: its model, complete, goes to the cast, or its upload under
    /// way to the cast's uploads (the next update drops either if no character is on it).
    fn leave_place(&mut self, renderer: &mut SceneRenderer) {
        let upload = renderer.take_avatar_upload();
        match (self.place.take(), renderer.take_avatar(), upload) {
            (Some(key), Some(gpu), _) => renderer.insert_cast_model(key.id(), gpu),
            (Some(key), None, Some(upload)) => self.uploads.push((key, upload)),
            _ => {}
        }
    }

    /// The figure in the avatar's place: from the cast, or uploaded at once.
    fn place_figure(
        &mut self,
        renderer: &mut SceneRenderer,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
    ) -> Result<(), String> {
        if matches!(
            self.take_place(renderer, ModelKey::Figure),
            Placed::Complete
        ) {
            return Ok(());
        }
        // Small: uploaded at once (an upload of it under way for the cast is dropped).
        let mesh = self
            .figures
            .iter()
            .find_map(|(_, figure)| figure.model())
            .ok_or("no figure was made")?;
        renderer.set_avatar(device, queue, Some(&*mesh));
        Ok(())
    }

    /// Makes the figures of the levels of articulation the characters on the mannequin are at
    /// (none when figures are not shown), and drops the others.
    fn keep_figures(&mut self, model: &EditorModel) -> Result<(), String> {
        let mut levels: Vec<LevelOfArticulation> = model
            .characters()
            .filter(|(character, _)| self.figures_shown && character.avatar().is_none())
            .map(|(character, _)| character.session().level_of_articulation())
            .collect();
        levels.sort_unstable();
        levels.dedup();
        self.figures.retain(|(loa, _)| levels.contains(loa));
        for loa in levels {
            if !self.figures.iter().any(|(at, _)| *at == loa) {
                self.figures.push((loa, MannequinFigure::new(loa)?));
            }
        }
        Ok(())
    }

    /// The models the other characters are drawn on that differ from the one in the
    /// avatar's place (the figure only when figures are shown), each once.
    fn wanted(&self, model: &EditorModel) -> Vec<ModelKey> {
        let mut wanted: Vec<ModelKey> = Vec::new();
        for character in model.other_characters() {
            let key = ModelKey::of(character);
            let shown = key != ModelKey::Figure || self.figures_shown;
            if shown && self.place.as_ref() != Some(&key) && !wanted.contains(&key) {
                wanted.push(key);
            }
        }
        wanted
    }

    /// The GPU model of `key` to upload: the figure's, or an avatar's from a character on it
    /// (the one it holds; where every character's was taken by an upload before, made again
    /// from the file: the avatar was on the GPU before and dropped when no one was on it).
    fn mesh_of(&self, key: &ModelKey, model: &EditorModel) -> Option<Arc<SkinnedModel>> {
        if *key == ModelKey::Figure {
            return self.figures.iter().find_map(|(_, figure)| figure.model());
        }
        let avatars: Vec<&LoadedAvatar> = model
            .other_characters()
            .iter()
            .filter_map(Character::avatar)
            .filter(|avatar| ModelKey::of_avatar(avatar) == *key)
            .collect();
        if let Some(mesh) = avatars.iter().find_map(|avatar| avatar.mesh()) {
            return Some(Arc::clone(mesh));
        }
        let avatar = avatars.first()?;
        Some(Arc::new(avatar_model(&avatar.avatar).0))
    }
}
