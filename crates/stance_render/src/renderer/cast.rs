//! The cast's models: characters each on an avatar of their own, drawn in one frame
//! ([`Scene::cast_poses`](crate::Scene::cast_poses)). Each model is known by a key its caller
//! chooses (the editor: the avatar file the characters on it share), so that it is uploaded
//! once, kept while characters are drawn on it, and dropped when none is; the avatar's place
//! ([`SceneRenderer::set_avatar`]) can hand its model to the cast and take one from it without
//! uploading it again.

use crate::CastPose;
use crate::skinned::SkinnedModel;
use crate::skinned_gpu::{AvatarGpu, AvatarUpload};

use super::SceneRenderer;

/// One of the cast's models on the GPU and its key.
#[derive(Debug)]
pub(super) struct CastModel {
    pub(super) key: u64,
    pub(super) gpu: AvatarGpu,
}

impl SceneRenderer {
    /// Uploads the models of a cast whose characters are each on an avatar of their own
    /// (replacing those uploaded before; none: dropped), drawn in
    /// [`Scene::cast_poses`](crate::Scene::cast_poses): the model at index `i` is known by the
    /// key `i`.
    pub fn set_cast_models(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        models: &[&SkinnedModel],
    ) {
        self.cast = models
            .iter()
            .enumerate()
            .map(|(key, model)| CastModel {
                key: key as u64,
                gpu: AvatarGpu::new(device, queue, &self.skinned_pipeline, model),
            })
            .collect();
    }

    /// Puts `model` among the cast's models under `key`, replacing the one there (which is
    /// dropped). A model that is new goes last: the indices of the others stay.
    pub fn insert_cast_model(&mut self, key: u64, model: AvatarGpu) {
        match self.cast.iter_mut().find(|cast| cast.key == key) {
            Some(cast) => cast.gpu = model,
            None => self.cast.push(CastModel { key, gpu: model }),
        }
    }

    /// Takes the cast's model `key` out (to drop it, or to put it in the avatar's place);
    /// the models after it come one index nearer.
    pub fn remove_cast_model(&mut self, key: u64) -> Option<AvatarGpu> {
        let at = self.cast.iter().position(|cast| cast.key == key)?;
        Some(self.cast.remove(at).gpu)
    }

    /// Keeps the cast's models whose key `keep` accepts; the others are dropped.
    pub fn retain_cast_models(&mut self, mut keep: impl FnMut(u64) -> bool) {
        self.cast.retain(|cast| keep(cast.key));
    }

    /// The index of the cast's model `key`, as [`CastPose::model`] names it.
    pub fn cast_model_index(&self, key: u64) -> Option<usize> {
        self.cast.iter().position(|cast| cast.key == key)
    }

    /// The keys of the cast's models, in the order of their indices.
    pub fn cast_model_keys(&self) -> impl Iterator<Item = u64> + '_ {
        self.cast.iter().map(|cast| cast.key)
    }

    /// How many models the cast holds on the GPU.
    pub fn cast_model_count(&self) -> usize {
        self.cast.len()
    }

    /// Takes the avatar out of its place (an upload under way goes on): to keep it among the
    /// cast's models while another takes its place.
    pub fn take_avatar(&mut self) -> Option<AvatarGpu> {
        self.avatar.take()
    }

    /// Puts a model uploaded before (one of the cast's) in the avatar's place, replacing the
    /// avatar there and an upload under way.
    pub fn put_avatar(&mut self, avatar: AvatarGpu) {
        self.upload = None;
        self.avatar = Some(avatar);
    }

    /// Takes the avatar's upload under way out, to go on with it elsewhere (among the cast's
    /// uploads, stepped by [`SceneRenderer::step_upload`]).
    pub fn take_avatar_upload(&mut self) -> Option<AvatarUpload> {
        self.upload.take()
    }

    /// Goes on with `upload` (begun for the cast) as the avatar's
    /// ([`SceneRenderer::continue_avatar_upload`]); the avatar in place stays until it is
    /// complete.
    pub fn resume_avatar_upload(&mut self, upload: AvatarUpload) {
        self.upload = Some(upload);
    }

    /// One step of `upload` (a model on its way to the cast, stepped by the caller as
    /// [`SceneRenderer::continue_avatar_upload`] steps the avatar's): the model once complete.
    pub fn step_upload(
        &self,
        upload: &mut AvatarUpload,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
    ) -> Option<AvatarGpu> {
        upload.step(device, queue, &self.skinned_pipeline)
    }

    /// Writes `poses`' palettes, each into the next pose of its model; returns how many poses
    /// of each model to draw.
    pub(super) fn write_cast_poses(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        poses: &[CastPose],
    ) -> Vec<usize> {
        let mut counts = vec![0; self.cast.len()];
        for pose in poses {
            if let Some(count) = counts.get_mut(pose.model) {
                *count += 1;
            }
        }
        for (model, count) in self.cast.iter_mut().zip(&counts) {
            model
                .gpu
                .ensure_poses(device, &self.skinned_pipeline, *count);
        }
        let mut next = vec![0; self.cast.len()];
        for pose in poses {
            if let (Some(model), Some(slot)) = (self.cast.get(pose.model), next.get_mut(pose.model))
            {
                model.gpu.write_palettes(queue, *slot, &pose.palettes);
                *slot += 1;
            }
        }
        counts
    }
}
