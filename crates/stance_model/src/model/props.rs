//! The scene's props: added, removed and edited (moved, turned, scaled, renamed) as
//! [`super::SceneCommand`]s, the tasks attached to them following them, and the tasks of a
//! character attached to props keeping their place while the character moves.

use stance_document::scene::MAX_PROPS;
use stance_document::{Placement, Prop, PropShape, clean_name, default_prop_name};

use super::EditorModel;

impl EditorModel {
    /// The scene's props.
    pub fn props(&self) -> &[Prop] {
        &self.cast.props
    }

    /// The task that puts `joint` of the selected character on the prop at `prop`.
    pub(super) fn task_on_prop(
        &self,
        joint: usize,
        prop: usize,
    ) -> Result<stance_document::TaskSpec, String> {
        let prop = self
            .cast
            .props
            .get(prop)
            .ok_or_else(|| format!("the scene has no prop {prop}"))?;
        super::tasks::task_on_prop(
            &self.character.session,
            joint,
            prop,
            self.character.placement.scene_from_character(),
        )
    }

    pub(super) fn add_prop(&mut self, shape: PropShape) -> super::Change {
        let n = 1 + self
            .cast
            .props
            .iter()
            .filter(|p| p.shape.name() == shape.name())
            .count();
        let name = default_prop_name(&shape, n);
        // In front of the selected character, resting on the floor (a plane at table height, a
        // ball at chest height, a bar standing beside it).
        let scene_from_character = self.character.placement.scene_from_character();
        let (ahead, height) = match shape {
            PropShape::Box { size } | PropShape::Mesh { size, .. } => (0.5, size[1] / 2.0),
            PropShape::Sphere { .. } => (0.4, 1.0),
            PropShape::Cylinder { height, .. } => (0.45, height / 2.0),
            PropShape::Plane { .. } => (0.6, 0.75),
        };
        let centre = scene_from_character.transform_point3(glam::DVec3::new(0.0, height, ahead));
        self.push_prop(Prop::new(name, shape, centre.to_array()))
    }

    /// Adds `prop` turned as the selected character is (one undo step); refused when the
    /// scene holds [`MAX_PROPS`].
    pub(super) fn push_prop(&mut self, mut prop: Prop) -> super::Change {
        if self.cast.props.len() >= MAX_PROPS {
            self.warn(format!("A scene holds at most {MAX_PROPS} props."));
            return super::Change::Nothing;
        }
        prop.rotation =
            glam::DQuat::from_rotation_y(self.character.placement.yaw_degrees.to_radians())
                .to_array();
        let name = prop.name.clone();
        let before = self.cast_snapshot();
        self.cast.props.push(prop);
        self.history.record_cast(before, false, self.now_secs);
        self.inform(format!("Added {name} (Scene panel: its size and place)."));
        super::Change::Document
    }

    /// Table 1's sphere and vertical bar where its tasks reach for them (in front of the
    /// selected character): the sphere touched on its near side by the right hand's goal, the
    /// bar's axis through the left hand's; one undo step; props of those names already in the
    /// scene are moved there instead.
    pub(super) fn place_table1_props(&mut self) {
        use super::tasks::{TABLE1_BAR, TABLE1_SPHERE, TABLE1_SPHERE_RADIUS};
        let scene_from_character = self.character.placement.scene_from_character();
        let reach = glam::DVec3::from_array(TABLE1_SPHERE);
        let shoulder = self
            .character
            .session
            .joint_position("r_shoulder")
            .unwrap_or(glam::DVec3::new(-0.2, 1.4, 0.0));
        let centre = reach + (reach - shoulder).normalize_or(glam::DVec3::Z) * TABLE1_SPHERE_RADIUS;
        let turn = glam::DQuat::from_rotation_y(self.character.placement.yaw_degrees.to_radians());
        let props = [
            (
                "Table 1 sphere",
                PropShape::Sphere {
                    radius: TABLE1_SPHERE_RADIUS,
                },
                centre,
            ),
            (
                "Table 1 bar",
                PropShape::Cylinder {
                    radius: 0.02,
                    height: 2.0,
                },
                glam::DVec3::new(TABLE1_BAR[0], 1.0, TABLE1_BAR[2]),
            ),
        ];
        let before = self.cast_snapshot();
        for (name, shape, at) in props {
            let mut prop = Prop::new(
                name.to_owned(),
                shape,
                scene_from_character.transform_point3(at).to_array(),
            );
            prop.rotation = turn.to_array();
            let full = self.cast.props.len() >= MAX_PROPS;
            match self.cast.props.iter_mut().find(|p| p.name == name) {
                Some(existing) => *existing = prop,
                None if !full => self.cast.props.push(prop),
                None => {}
            }
        }
        if before.props != self.cast.props {
            self.history.record_cast(before, false, self.now_secs);
        }
    }

    pub(super) fn remove_prop(&mut self, index: usize) -> super::Change {
        if index >= self.cast.props.len() {
            return super::Change::Nothing;
        }
        let before = self.cast_snapshot();
        let prop = self.cast.props.remove(index);
        self.history.record_cast(before, false, self.now_secs);
        self.inform(format!("Removed {} (undo brings it back).", prop.name));
        super::Change::Document
    }

    pub(super) fn edit_prop(&mut self, index: usize, mut prop: Prop) -> super::Change {
        let Some(current) = self.cast.props.get(index) else {
            return super::Change::Nothing;
        };
        prop.name = clean_name(&prop.name).unwrap_or_else(|| current.name.clone());
        if let Err(error) = prop.validate_at("prop") {
            self.warn(format!("The prop was not changed: {error}"));
            return super::Change::Nothing;
        }
        if *current == prop {
            return super::Change::Nothing;
        }
        let before = self.cast_snapshot();
        let old = std::mem::replace(&mut self.cast.props[index], prop.clone());
        self.history.record_cast(before, true, self.now_secs);
        self.follow_props(&[(old, prop)]);
        super::Change::Document
    }

    /// The tasks attached to props (`TaskSpec::on`) follow each prop from where it was to
    /// where it is (`moves`: the prop before and after: moved, turned or renamed), each
    /// character's goals moved in its own frame.
    pub(super) fn follow_props(&mut self, moves: &[(Prop, Prop)]) {
        let moves: Vec<(&str, &str, glam::DAffine3)> = moves
            .iter()
            .filter(|(old, new)| old != new)
            .map(|(old, new)| {
                let scene_move = new.scene_from_prop() * old.scene_from_prop().inverse();
                (old.name.as_str(), new.name.as_str(), scene_move)
            })
            .collect();
        if moves.is_empty() {
            return;
        }
        let (others, character) = self.cast_and_selected_mut();
        for character in others.iter_mut().chain(std::iter::once(character)) {
            let scene_from_character = character.placement.scene_from_character();
            let tasks: Vec<stance_document::TaskSpec> = character
                .session
                .tasks()
                .iter()
                .map(|task| {
                    match moves
                        .iter()
                        .find(|(old, _, _)| task.on.as_deref() == Some(*old))
                    {
                        Some((_, new, scene_move)) => {
                            let in_character =
                                scene_from_character.inverse() * *scene_move * scene_from_character;
                            let mut moved = task.moved(in_character);
                            moved.on = Some((*new).to_owned());
                            moved
                        }
                        None => task.clone(),
                    }
                })
                .collect();
            if tasks != character.session.tasks() {
                character.session.set_tasks(tasks);
            }
        }
    }

    /// The tasks of character `id` attached to props keep their place in the scene while the
    /// character moves from `before` to its placement now.
    pub(super) fn follow_placement(&mut self, id: u64, before: Placement) {
        let Some(character) = self.character_mut(id) else {
            return;
        };
        let now = character.placement;
        if now == before {
            return;
        }
        let in_character = now.scene_from_character().inverse() * before.scene_from_character();
        let tasks: Vec<stance_document::TaskSpec> = character
            .session
            .tasks()
            .iter()
            .map(|task| match task.on {
                Some(_) => task.moved(in_character),
                None => task.clone(),
            })
            .collect();
        if tasks != character.session.tasks() {
            character.session.set_tasks(tasks);
        }
    }
}
