//! The scene's characters as the renderer draws them: each character's capsules and skinning
//! palettes are in its own frame, put in the scene by its placement
//! ([`stance_document::Placement::scene_from_character`]; `stance_render::placed` does the
//! placing, as `stance render` does). The characters that are not selected are drawn as their
//! mannequin capsules in a quieter colour.

use glam::{Mat4, Vec3};
use stance_render::{
    Capsule, ContactShadow, MeshPropInstance, PropInstance, character_shadow, mesh_prop_instance,
    prop_instance, prop_shadow,
};
pub(crate) use stance_render::{placed_capsule, placed_palettes};

use crate::figure::MannequinFigure;
use crate::model::{Character, EditorModel};

/// The colour of the characters that are not selected (linear RGB): the body's, greyer.
pub(crate) const OTHER_COLOR_LINEAR: [f32; 4] = [0.42, 0.42, 0.45, 1.0];

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

/// The model on the GPU this frame, which characters other than the selected one are drawn
/// with when it is theirs too.
#[derive(Clone, Copy)]
pub(crate) enum Uploaded<'a> {
    /// The mannequin's figure: every character on the mannequin.
    Figure(&'a MannequinFigure),
    /// The selected character's avatar: the characters on the same avatar file.
    Avatar,
    /// Nothing (or the capsules are shown): the others are capsules.
    None,
}

/// How the characters other than the selected one are drawn: skinned with the uploaded model
/// where it is theirs (their poses, placed: `more_avatar_poses`), else as their capsules in
/// [`OTHER_COLOR_LINEAR`].
pub(crate) fn other_figures(
    model: &EditorModel,
    uploaded: Uploaded<'_>,
) -> (Vec<Capsule>, Vec<Vec<Vec<Mat4>>>) {
    let selected_avatar = model.avatar().map(|avatar| avatar.name.as_str());
    let mut capsules = Vec::new();
    let mut poses = Vec::new();
    for character in model.other_characters() {
        let place = scene_from_character(character);
        let session = character.session();
        let palettes = match (uploaded, character.avatar()) {
            (Uploaded::Figure(figure), None) => {
                figure.palettes(session.skeleton(), session.posture())
            }
            (Uploaded::Avatar, Some(avatar)) if Some(avatar.name.as_str()) == selected_avatar => {
                avatar.palettes(session.humanoid(), session.posture())
            }
            _ => None,
        };
        match palettes {
            Some(palettes) => poses.push(placed_palettes(palettes, place)),
            None => capsules.extend(character.bones().iter().map(|bone| Capsule {
                color_linear: OTHER_COLOR_LINEAR,
                ..placed_capsule(bone.capsule, place)
            })),
        }
    }
    (capsules, poses)
}

/// The capsules of every character but the selected one, in the scene (their bodies as
/// shapes: the depth range of a control map).
pub(crate) fn other_capsules(model: &EditorModel) -> Vec<Capsule> {
    other_figures(model, Uploaded::None).0
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
