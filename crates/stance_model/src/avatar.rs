//! A user's avatar in the editor: the imported glTF/GLB/VRM file, its H-Anim skeleton, and the
//! GPU model (vertices, materials, textures) with the palettes that pose it every frame.

use std::sync::Arc;

use glam::Mat4;
use stance_asset::{
    Avatar, HostImages, LoadOptions, export_glb, find_resource, load_avatar_with_images,
};
use stance_hanim::{
    HumanoidSkeleton, LevelOfArticulation, Mapping, SkeletonOptions, build_skeleton,
};
use stance_ik::Posture;
use stance_render::{AvatarPalettes, SkinnedModel, avatar_model};

use crate::host::ImportedAvatar;

/// A loaded avatar.
pub struct LoadedAvatar {
    /// File name or URL it came from.
    pub name: String,
    /// The imported file (H-Anim mapping included).
    pub avatar: Avatar,
    /// The GPU model until the renderer took it for its upload
    /// ([`AvatarCommand::MeshTaken`](crate::model::AvatarCommand::MeshTaken)).
    model: Option<Arc<SkinnedModel>>,
    palettes: AvatarPalettes,
    /// What the user should know (unmapped joints, clamped skins...).
    pub warnings: Vec<String>,
    /// Vertices of all its meshes, for the panels.
    pub vertex_count: usize,
    /// Triangles of all its meshes, for the panels.
    pub triangle_count: usize,
    /// Texture images the host decoded for it (the others were decoded by the importer).
    pub images_from_host: usize,
    /// How long its loading took.
    pub load: LoadTimes,
}

/// How long an avatar's loading took, phase by phase, in ms.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct LoadTimes {
    /// The file's import (textures decoded by the host excluded).
    pub import_ms: f64,
    /// Whether the import ran off the editor's thread (the page's import worker).
    pub in_worker: bool,
    /// Handing the imported avatar to the editor's thread.
    pub transfer_ms: f64,
    /// Its skeleton and GPU model.
    pub build_ms: f64,
    /// The posing session on its skeleton (with the mapping corrections and the document
    /// that waited for it).
    pub session_ms: f64,
}

impl std::fmt::Debug for LoadedAvatar {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("LoadedAvatar")
            .field("name", &self.name)
            .field("vertices", &self.vertex_count)
            .finish_non_exhaustive()
    }
}

impl LoadedAvatar {
    /// Imports `bytes` (GLB, glTF with data URIs, VRM) and builds its skeleton at `loa`.
    pub fn load(
        name: &str,
        bytes: &[u8],
        loa: LevelOfArticulation,
    ) -> Result<(Self, HumanoidSkeleton), String> {
        Self::from_imported(name, Self::import(bytes, &[], HostImages::default())?, loa)
    }

    /// Imports `bytes` (GLB, glTF with data URIs, VRM; a `.gltf` with its `resources`:
    /// `.bin` buffers and images, found by the URIs the file uses, a missing one named),
    /// taking the texture images the host already `decoded` as they are.
    pub fn import(
        bytes: &[u8],
        resources: &[(String, Vec<u8>)],
        images: HostImages,
    ) -> Result<ImportedAvatar, String> {
        let mut resolve = |uri: &str| find_resource(resources, uri).map(<[u8]>::to_vec);
        // (Images whose pixels follow count where the host fills them.)
        let images_from_host = images.decoded.len();
        let started = web_time::Instant::now();
        let avatar = load_avatar_with_images(bytes, &LoadOptions::default(), &mut resolve, images)
            .map_err(|error| error.to_string())?;
        Ok(ImportedAvatar {
            avatar,
            import_ms: started.elapsed().as_secs_f64() * 1e3,
            in_worker: false,
            transfer_ms: 0.0,
            images_from_host,
        })
    }

    /// An imported avatar (here or by the host), its skeleton built at `loa`.
    pub fn from_imported(
        name: &str,
        imported: ImportedAvatar,
        loa: LevelOfArticulation,
    ) -> Result<(Self, HumanoidSkeleton), String> {
        let started = web_time::Instant::now();
        let (mut loaded, humanoid) = Self::from_avatar(name, imported.avatar, loa)?;
        loaded.images_from_host = imported.images_from_host;
        loaded.load = LoadTimes {
            import_ms: imported.import_ms,
            in_worker: imported.in_worker,
            transfer_ms: imported.transfer_ms,
            build_ms: started.elapsed().as_secs_f64() * 1e3,
            ..LoadTimes::default()
        };
        Ok((loaded, humanoid))
    }

    /// An imported (or generated) avatar, its skeleton built at `loa`.
    pub fn from_avatar(
        name: &str,
        avatar: Avatar,
        loa: LevelOfArticulation,
    ) -> Result<(Self, HumanoidSkeleton), String> {
        let humanoid = avatar
            .skeleton(&SkeletonOptions {
                loa,
                ..SkeletonOptions::default()
            })
            .map_err(|error| error.to_string())?;
        Ok((Self::with_mesh(name, avatar)?, humanoid))
    }

    /// An imported (or generated) avatar's GPU model and palettes, its skeleton built by the
    /// caller.
    pub fn with_mesh(name: &str, avatar: Avatar) -> Result<Self, String> {
        let (model, palettes, mut warnings) = avatar_model(&avatar);
        warnings.extend(avatar.warnings.iter().cloned());
        let vertex_count = model.primitives.iter().map(|p| p.vertices.len()).sum();
        let triangle_count = model.primitives.iter().map(|p| p.indices.len() / 3).sum();
        if vertex_count == 0 {
            return Err("the file has no mesh to show".to_owned());
        }
        Ok(Self {
            name: name.to_owned(),
            avatar,
            model: Some(Arc::new(model)),
            palettes,
            warnings,
            vertex_count,
            triangle_count,
            images_from_host: 0,
            load: LoadTimes::default(),
        })
    }

    /// A copy for another character: the same file and mapping, its GPU model made again
    /// for that character's upload.
    pub fn duplicate(&self) -> Self {
        let (model, palettes, _) = avatar_model(&self.avatar);
        Self {
            name: self.name.clone(),
            avatar: self.avatar.clone(),
            model: Some(Arc::new(model)),
            palettes,
            warnings: self.warnings.clone(),
            vertex_count: self.vertex_count,
            triangle_count: self.triangle_count,
            images_from_host: self.images_from_host,
            load: self.load,
        }
    }

    /// The avatar to be shown again (undo or redo brings it back): its GPU model made again
    /// when the renderer took it.
    pub fn shown_again(mut self) -> Self {
        if self.model.is_none() {
            let (model, palettes, _) = avatar_model(&self.avatar);
            self.model = Some(Arc::new(model));
            self.palettes = palettes;
        }
        self
    }

    /// The skeleton of this avatar at another level of articulation.
    pub fn skeleton(&self, loa: LevelOfArticulation) -> Result<HumanoidSkeleton, String> {
        self.avatar
            .skeleton(&SkeletonOptions {
                loa,
                ..SkeletonOptions::default()
            })
            .map_err(|error| error.to_string())
    }

    /// The GPU model (vertices, materials, textures) until the renderer took it.
    pub fn mesh(&self) -> Option<&Arc<SkinnedModel>> {
        self.model.as_ref()
    }

    /// Takes the GPU model for the renderer's upload: the avatar no longer holds it.
    pub fn take_mesh(&mut self) -> Option<Arc<SkinnedModel>> {
        self.model.take()
    }

    /// The palettes that show `posture` (mesh space -> H-Anim world), or `None` when the
    /// posture does not fit the skeleton.
    pub fn palettes(
        &self,
        humanoid: &HumanoidSkeleton,
        posture: &Posture,
    ) -> Option<Vec<Vec<Mat4>>> {
        self.palettes.pose(&self.avatar, humanoid, posture)
    }

    /// The skeleton that `mapping` (a corrected mapping of this avatar's nodes) gives at
    /// `loa`; the avatar's own mapping is left as it is.
    pub fn skeleton_with_mapping(
        &self,
        mapping: &Mapping,
        loa: LevelOfArticulation,
    ) -> Result<HumanoidSkeleton, String> {
        build_skeleton(
            mapping,
            &self.avatar.hanim_rest_positions(),
            &SkeletonOptions {
                loa,
                ..SkeletonOptions::default()
            },
        )
        .map_err(|error| error.to_string())
    }

    /// The nodes that are joints, in file order: the skins' joints (every node without a mesh
    /// when the file has no skin), and any other node the mapping uses.
    pub fn joint_nodes(&self) -> Vec<usize> {
        let nodes = &self.avatar.nodes;
        let mut joint = vec![false; nodes.len()];
        if self.avatar.skins.is_empty() {
            for (index, node) in nodes.iter().enumerate() {
                joint[index] = node.mesh.is_none();
            }
        } else {
            for &index in self.avatar.skins.iter().flat_map(|skin| &skin.joints) {
                if let Some(flag) = joint.get_mut(index) {
                    *flag = true;
                }
            }
        }
        for found in self.avatar.mapping.matches() {
            if let Some(flag) = joint.get_mut(found.source) {
                *flag = true;
            }
        }
        (0..nodes.len()).filter(|&index| joint[index]).collect()
    }

    /// The file posed like `posture` (of `humanoid`, built from this avatar) as GLB bytes,
    /// written like `stance export-posed` writes it. The avatar itself is left as it was.
    pub fn posed_glb(
        &mut self,
        humanoid: &HumanoidSkeleton,
        posture: &Posture,
    ) -> Result<Vec<u8>, String> {
        let kept = self.avatar.pose_locals();
        let exported = self
            .avatar
            .apply_posture(humanoid, posture)
            .and_then(|()| export_glb(&self.avatar))
            .map_err(|error| error.to_string());
        for (node, pose) in self.avatar.nodes.iter_mut().zip(kept) {
            node.pose = pose;
        }
        exported
    }

    /// The H-Anim joints found in the file and the source joints left unmapped.
    pub fn mapping_summary(&self) -> (usize, usize) {
        let mapped = self.avatar.mapping.matches().len();
        let sources = self.avatar.mapping.source_count();
        (mapped, sources.saturating_sub(mapped))
    }
}

/// `Avatars/Jane.vrm?x=1` -> `Jane-posed.vrm` (a VRM stays a VRM: its extension is written
/// back), `Bob.gltf` -> `Bob-posed.glb`.
pub fn posed_file_name(name: &str) -> String {
    let path = name.split(['?', '#']).next().unwrap_or(name);
    let base = path.rsplit(['/', '\\']).next().unwrap_or(path);
    let (stem, extension) = base.rsplit_once('.').unwrap_or((base, ""));
    let stem = stem.trim();
    let stem = if stem.is_empty() { "avatar" } else { stem };
    let extension = if extension.eq_ignore_ascii_case("vrm") {
        "vrm"
    } else {
        "glb"
    };
    format!("{stem}-posed.{extension}")
}

/// Whether an avatar's name is where it can be fetched again (links and autosave name it).
pub fn is_url(name: &str) -> bool {
    name.starts_with("http://")
        || name.starts_with("https://")
        || (!name.contains(['\\', ':']) && name.contains('/'))
        || name == "default-avatar.glb"
}

/// Whether a file is an avatar (glTF, GLB, VRM) by its name or its first bytes.
pub fn is_avatar_file(name: &str, bytes: &[u8]) -> bool {
    let lower = name.to_ascii_lowercase();
    let path = lower.split(['?', '#']).next().unwrap_or("");
    [".glb", ".gltf", ".vrm"]
        .iter()
        .any(|extension| path.ends_with(extension))
        || bytes.starts_with(b"glTF")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_bundled_avatar_loads_and_its_palettes_pose_it() {
        let bytes = std::fs::read(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../public/default-avatar.glb"
        ))
        .unwrap();
        let (loaded, humanoid) =
            LoadedAvatar::load("default-avatar.glb", &bytes, LevelOfArticulation::Loa2).unwrap();
        assert!(loaded.vertex_count > 1000);
        let rest = Posture::rest(&humanoid.skeleton);
        let palettes = loaded.palettes(&humanoid, &rest).unwrap();
        assert!(!palettes.is_empty());
        assert!(palettes.iter().flatten().all(|matrix| matrix.is_finite()));
    }

    #[test]
    fn a_broken_file_is_refused_with_a_reason() {
        let error = LoadedAvatar::load("x.glb", b"glTF\x02\x00\x00\x00", LevelOfArticulation::Loa2)
            .err()
            .unwrap();
        assert!(!error.is_empty());
    }

    #[test]
    fn the_posed_file_is_named_after_the_avatar() {
        assert_eq!(posed_file_name("Jane.vrm"), "Jane-posed.vrm");
        assert_eq!(posed_file_name("Avatars/Jane.VRM?x=1"), "Jane-posed.vrm");
        assert_eq!(
            posed_file_name("https://example.org/a/Bob.glb?v=2#top"),
            "Bob-posed.glb"
        );
        assert_eq!(posed_file_name("C:\\models\\x.gltf"), "x-posed.glb");
        assert_eq!(posed_file_name(""), "avatar-posed.glb");
    }
}
