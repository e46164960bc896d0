//! The scene's characters as the renderer draws them: each character's capsules and skinning
//! palettes are in its own frame, put in the scene by its placement
//! ([`stance_document::Placement::scene_from_character`]; `stance_render::placed` does the
//! placing, as `stance render` does). The characters that are not selected are drawn skinned on
//! their own models as the selected one is (`crate::cast_models`), or as their capsules in a
//! quieter colour while the capsules are shown or their model is on its way to the GPU.

use glam::{Mat4, Vec3};
use stance_render::{
    Capsule, ContactShadow, MeshPropInstance, PropInstance, character_shadow, mesh_prop_instance,
    prop_instance, prop_shadow,
};
pub(crate) use stance_render::{placed_capsule, placed_palettes};

use crate::model::{Character, EditorModel};

/// The colour of the characters that are not selected when drawn as capsules (linear RGB): the
/// body's, greyer.
pub const OTHER_COLOR_LINEAR: [f32; 4] = [0.42, 0.42, 0.45, 1.0];

/// Every prop of the scene drawn as a unit shape (a mesh prop whose file is not loaded: its
/// box).
pub(crate) fn prop_instances(model: &EditorModel) -> Vec<PropInstance> {
    model
        .props()
        .iter()
        .filter(|prop| model.prop_mesh(prop).is_none())
        .map(prop_instance)
        .collect()
}

/// Every mesh prop of the scene whose file is loaded, drawn with its triangles.
pub(crate) fn mesh_prop_instances(model: &EditorModel) -> Vec<MeshPropInstance> {
    model
        .props()
        .iter()
        .filter_map(|prop| Some(mesh_prop_instance(prop, model.prop_mesh(prop)?)))
        .collect()
}

/// The contact shadows of the scene: one under each character (its bones, placed) and one
/// under each prop (its box's corners).
pub(crate) fn contact_shadows(model: &EditorModel) -> Vec<ContactShadow> {
    let characters = model.characters().filter_map(|(character, _)| {
        let place = scene_from_character(character);
        let capsules: Vec<Capsule> = character
            .bones()
            .iter()
            .map(|bone| placed_capsule(bone.capsule, place))
            .collect();
        character_shadow(&capsules)
    });
    let props = model.props().iter().filter_map(prop_shadow);
    characters.chain(props).collect()
}

/// The character's frame in the scene, for the GPU.
pub(crate) fn scene_from_character(character: &Character) -> Mat4 {
    stance_render::scene_from_character(&character.placement())
}

/// `character`'s capsules, placed in the scene, in [`OTHER_COLOR_LINEAR`]: a character other
/// than the selected one drawn as capsules (the capsules view, or its model not on the GPU
/// yet; `crate::cast_models::CastModels::others`).
pub(crate) fn other_capsules_of(character: &Character) -> impl Iterator<Item = Capsule> + '_ {
    let place = scene_from_character(character);
    character.bones().iter().map(move |bone| Capsule {
        color_linear: OTHER_COLOR_LINEAR,
        ..placed_capsule(bone.capsule, place)
    })
}

/// The capsules of every character but the selected one, in the scene (their bodies as
/// shapes: the depth range of a control map).
pub(crate) fn other_capsules(model: &EditorModel) -> Vec<Capsule> {
    model
        .other_characters()
        .iter()
        .flat_map(other_capsules_of)
        .collect()
}

/// The character whose body the scene ray `origin + t direction` meets first among those not
/// selected, and the distance along the ray.
pub(crate) fn pick_other(model: &EditorModel, origin: Vec3, direction: Vec3) -> Option<(u64, f32)> {
    model
        .other_characters()
        .iter()
        .filter_map(|character| {
            let place = scene_from_character(character);
            let capsules: Vec<Capsule> = character
                .bones()
                .iter()
                .map(|bone| placed_capsule(bone.capsule, place))
                .collect();
            let hit = stance_render::pick_capsule(&capsules, origin, direction)?;
            Some((character.id(), (hit.point_world - origin).length()))
        })
        .min_by(|a, b| a.1.total_cmp(&b.1))
}
