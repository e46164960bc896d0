//! A whole scene as one GLB: every character's avatar posed at its place, and static meshes
//! (the props), each under one node named as in the outliner.
//!
//! The scene is gathered into one [`Avatar`] (each avatar's nodes, meshes, skins, materials
//! and textures appended, their indices moved along) and written by [`crate::export_glb`]:
//! one GLB writer for a posed avatar and a scene alike.

use glam::{DAffine3, DMat4};

use crate::AssetError;
use crate::model::{Avatar, Material, Mesh, Node, Primitive, SourceFormat, Trs};

/// A triangle mesh drawn as it is (no skin, no texture): a prop.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct StaticMesh {
    /// Points, in the node's frame (m).
    pub positions: Vec<[f32; 3]>,
    /// Unit normals, one per point (or none).
    pub normals: Vec<[f32; 3]>,
    /// Triangles, counter-clockwise seen from outside.
    pub indices: Vec<u32>,
    /// Linear RGBA.
    pub color_linear: [f32; 4],
}

/// What a node of an exported scene holds.
#[derive(Debug, Clone, Copy)]
pub enum SceneContent<'a> {
    /// An avatar in its current pose (its nodes' `pose`), its file's space put in the H-Anim
    /// frame by `hanim_from_file`.
    Avatar(&'a Avatar),
    /// A static mesh: its parts, one primitive each (each its own colour).
    Mesh(&'a [StaticMesh]),
}

/// One node of an exported scene: a character or a prop.
#[derive(Debug, Clone)]
pub struct SceneNode<'a> {
    /// Its name (the outliner's).
    pub name: String,
    /// Its frame in the scene (a character's placement, a prop's place and turn; no scale).
    pub scene_from_node: DAffine3,
    /// What it holds.
    pub content: SceneContent<'a>,
}

/// Writes `nodes` as one GLB: a root node per entry, named and placed, over the avatar's own
/// nodes (posed; under a node that puts the file's space in the H-Anim frame,
/// `hanim_from_file`) or the mesh. A VRM's extension is not written (one file holds one VRM
/// humanoid; a scene may hold several).
pub fn export_scene_glb(nodes: &[SceneNode<'_>]) -> Result<Vec<u8>, AssetError> {
    crate::export_glb(&gathered(nodes))
}

/// The transform as a node's translation, rotation and scale.
fn trs(transform: DAffine3) -> Trs {
    let (scale, rotation, translation) = DMat4::from(transform).to_scale_rotation_translation();
    Trs {
        translation,
        rotation,
        scale,
    }
}

/// The scene as one avatar whose roots are `nodes`.
fn gathered(nodes: &[SceneNode<'_>]) -> Avatar {
    let mut scene = Avatar {
        format: SourceFormat::Generated,
        nodes: Vec::new(),
        scene_roots: Vec::new(),
        skins: Vec::new(),
        meshes: Vec::new(),
        materials: Vec::new(),
        textures: Vec::new(),
        hanim_from_file: DMat4::IDENTITY,
        mapping: stance_hanim::Mapping::default(),
        animations: Vec::new(),
        extensions: Vec::new(),
        vrm: None,
        warnings: Vec::new(),
    };
    for entry in nodes {
        let root = scene.nodes.len();
        scene.scene_roots.push(root);
        match entry.content {
            SceneContent::Avatar(avatar) => {
                // The character's node is its frame, exactly the placement; the file's space
                // is put in that frame by a node of its own, so that the avatar's nodes are
                // written as they are.
                let place = trs(entry.scene_from_node);
                let file = trs(DAffine3::from_mat4(avatar.hanim_from_file));
                scene.nodes.push(Node {
                    name: entry.name.clone(),
                    parent: None,
                    children: vec![root + 1],
                    rest: place,
                    pose: place,
                    mesh: None,
                    skin: None,
                });
                scene.nodes.push(Node {
                    name: format!("{} (file frame)", entry.name),
                    parent: Some(root),
                    children: Vec::new(),
                    rest: file,
                    pose: file,
                    mesh: None,
                    skin: None,
                });
                let children = append(&mut scene, avatar, root + 1);
                scene.nodes[root + 1].children = children;
            }
            SceneContent::Mesh(parts) => {
                let mut primitives = Vec::with_capacity(parts.len());
                for part in parts {
                    primitives.push(Primitive {
                        positions: part.positions.clone(),
                        normals: part.normals.clone(),
                        indices: part.indices.clone(),
                        material: Some(scene.materials.len()),
                        ..Primitive::default()
                    });
                    scene.materials.push(Material {
                        name: entry.name.clone(),
                        base_color_factor: part.color_linear,
                        ..Material::default()
                    });
                }
                scene.meshes.push(Mesh {
                    name: entry.name.clone(),
                    primitives,
                });
                let place = trs(entry.scene_from_node);
                scene.nodes.push(Node {
                    name: entry.name.clone(),
                    parent: None,
                    children: Vec::new(),
                    rest: place,
                    pose: place,
                    mesh: Some(scene.meshes.len() - 1),
                    skin: None,
                });
            }
        }
    }
    scene
}

/// Appends `avatar`'s nodes (under `parent`), meshes, skins, materials and textures to
/// `scene`, every index moved by what was there before; returns its roots' new indices.
fn append(scene: &mut Avatar, avatar: &Avatar, parent: usize) -> Vec<usize> {
    let node_base = scene.nodes.len();
    let mesh_base = scene.meshes.len();
    let skin_base = scene.skins.len();
    let material_base = scene.materials.len();
    let texture_base = scene.textures.len();
    scene.nodes.extend(avatar.nodes.iter().map(|node| Node {
        parent: Some(node.parent.map_or(parent, |p| p + node_base)),
        children: node.children.iter().map(|c| c + node_base).collect(),
        mesh: node.mesh.map(|m| m + mesh_base),
        skin: node.skin.map(|s| s + skin_base),
        ..node.clone()
    }));
    scene.meshes.extend(avatar.meshes.iter().map(|mesh| {
        Mesh {
            primitives: mesh
                .primitives
                .iter()
                .map(|p| Primitive {
                    material: p.material.map(|m| m + material_base),
                    ..p.clone()
                })
                .collect(),
            ..mesh.clone()
        }
    }));
    scene.skins.extend(avatar.skins.iter().map(|skin| {
        let mut skin = skin.clone();
        for joint in &mut skin.joints {
            *joint += node_base;
        }
        skin
    }));
    scene
        .materials
        .extend(avatar.materials.iter().map(|material| Material {
            base_color_texture: material.base_color_texture.map(|t| t + texture_base),
            ..material.clone()
        }));
    scene.textures.extend(avatar.textures.iter().cloned());
    avatar.scene_roots.iter().map(|r| r + node_base).collect()
}

/// The generated default avatar (the mannequin's figure, as the editor and `stance render`
/// draw it) posed like `posture` of the mannequin's `skeleton`, joint by joint by H-Anim name,
/// its skeleton at `loa` (or LOA 2, the most its mesh has): how a mannequin is exported.
pub fn posed_default_avatar(
    skeleton: &stance_ik::Skeleton,
    posture: &stance_ik::Posture,
    loa: stance_hanim::LevelOfArticulation,
) -> Result<Avatar, AssetError> {
    let mut avatar = crate::make_default_avatar()?;
    let own = avatar.skeleton_or_loa2(&stance_hanim::SkeletonOptions {
        loa,
        ..stance_hanim::SkeletonOptions::default()
    })?;
    let carried = stance_ik::Posture::carried_over(&own.skeleton, skeleton, posture);
    avatar.apply_posture(&own, &carried)?;
    Ok(avatar)
}
