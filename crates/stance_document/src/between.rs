//! Tasks between characters, a scene's `between[]`: a hand in another's hand, a hand on the
//! other's shoulder (`"meet"`: a point of one character and a point of another meet). The
//! characters a task joins are solved together, as one prioritized problem over their bodies'
//! DOF ([`JoinedProblem`], on `stance_ik::Bodies`); each keeps its own tasks and levels.

use glam::{DQuat, DVec3};
use serde_json::{Map, Value, json};
use stance_ik::{
    Axes, Bodies, BodyPlacement, Effector, IkError, Posture, Skeleton, SolveReport, Solver, Task,
    TaskKind,
};

use crate::error::DocumentError;
use crate::json::{number, obj, optional_bool, string};
use crate::problem::Problem;
use crate::scene::{Placement, Scene};

/// The most tasks between characters a scene holds.
pub const MAX_BETWEEN_TASKS: usize = 64;

/// A point of one character of a scene.
#[derive(Debug, Clone, PartialEq)]
pub struct CharacterPoint {
    /// The character's index in the scene.
    pub character: usize,
    /// The joint's name (H-Anim).
    pub joint: String,
    /// The point in the joint's frame (m).
    pub point: [f64; 3],
}

/// A task between characters (`"meet"`): `a` and `b` meet along `axes`.
#[derive(Debug, Clone, PartialEq)]
pub struct BetweenTask {
    /// Priority level, >= 1, among the levels of the characters it joins.
    pub level: u32,
    /// Weight inside the level, >= 0.
    pub weight: f64,
    /// Inactive tasks are kept but not solved.
    pub active: bool,
    /// The first character's point.
    pub a: CharacterPoint,
    /// The second character's point.
    pub b: CharacterPoint,
    /// The scene axes along which they meet.
    pub axes: Axes,
}

impl BetweenTask {
    /// `a` and `b` meet at level `level`, weight 1, on every axis.
    pub fn meet(a: CharacterPoint, b: CharacterPoint, level: u32) -> Self {
        Self {
            level,
            weight: 1.0,
            active: true,
            a,
            b,
            axes: Axes::XYZ,
        }
    }

    /// The two characters it joins.
    pub fn characters(&self) -> [usize; 2] {
        [self.a.character, self.b.character]
    }

    /// Checks it against a scene of `characters` characters; paths relative to the task.
    pub fn validate(&self, characters: usize) -> Result<(), DocumentError> {
        crate::document::check_level_and_weight(self.level, self.weight)?;
        for (side, p) in [("a", &self.a), ("b", &self.b)] {
            if p.character >= characters {
                return Err(DocumentError::field(
                    format!("{side}.character"),
                    format!("character {} of {characters}", p.character),
                ));
            }
            if let Some(i) = p.point.iter().position(|v| !v.is_finite()) {
                return Err(DocumentError::field(
                    format!("{side}.point[{i}]"),
                    "not a finite number",
                ));
            }
        }
        Ok(())
    }

    /// Parses `{"kind": "meet", "a": {...}, "b": {...}, "axes", "level", "weight", "active"}`.
    pub fn from_json_value(v: &Value, at: &str) -> Result<Self, DocumentError> {
        let o = obj(v, at)?;
        match o.get("kind").map(|k| string(k, &format!("{at}.kind"))) {
            Some(Ok("meet")) => {}
            Some(Ok(other)) => {
                return Err(DocumentError::field(
                    format!("{at}.kind"),
                    format!("unknown kind `{other}` of task between characters (expected `meet`)"),
                ));
            }
            Some(Err(e)) => return Err(e),
            None => return Err(DocumentError::field(format!("{at}.kind"), "missing")),
        }
        let point = |side: &str| -> Result<CharacterPoint, DocumentError> {
            let at = format!("{at}.{side}");
            let p = obj(
                o.get(side)
                    .ok_or_else(|| DocumentError::field(&at, "missing"))?,
                &at,
            )?;
            let character = p
                .get("character")
                .ok_or_else(|| DocumentError::field(format!("{at}.character"), "missing"))
                .and_then(|c| number(c, &format!("{at}.character")))?;
            if character.fract() != 0.0 || character < 0.0 {
                return Err(DocumentError::field(
                    format!("{at}.character"),
                    "expected an index >= 0",
                ));
            }
            let joint = p
                .get("joint")
                .ok_or_else(|| DocumentError::field(format!("{at}.joint"), "missing"))
                .and_then(|j| string(j, &format!("{at}.joint")))?
                .to_owned();
            let point = match p.get("point") {
                None | Some(Value::Null) => [0.0; 3],
                Some(v) => crate::json::vec3(v, &format!("{at}.point"))?,
            };
            Ok(CharacterPoint {
                character: character as usize,
                joint,
                point,
            })
        };
        let level = match o.get("level") {
            None | Some(Value::Null) => 1.0,
            Some(l) => number(l, &format!("{at}.level"))?,
        };
        if level.fract() != 0.0 || !(1.0..=f64::from(u32::MAX)).contains(&level) {
            return Err(DocumentError::field(
                format!("{at}.level"),
                "levels are integers from 1 (highest priority)",
            ));
        }
        let weight = match o.get("weight") {
            None | Some(Value::Null) => 1.0,
            Some(w) => number(w, &format!("{at}.weight"))?,
        };
        let axes = match o.get("axes") {
            None | Some(Value::Null) => Axes::XYZ,
            Some(a) => Axes::parse(string(a, &format!("{at}.axes"))?).ok_or_else(|| {
                DocumentError::field(format!("{at}.axes"), "expected letters among x, y, z")
            })?,
        };
        Ok(Self {
            level: level as u32,
            weight,
            active: optional_bool(o, at, "active")?.unwrap_or(true),
            a: point("a")?,
            b: point("b")?,
            axes,
        })
    }

    /// The JSON value [`BetweenTask::from_json_value`] reads.
    pub fn to_json_value(&self) -> Value {
        let point = |p: &CharacterPoint| json!({ "character": p.character, "joint": p.joint, "point": p.point });
        let mut o = Map::new();
        o.insert("kind".into(), json!("meet"));
        o.insert("a".into(), point(&self.a));
        o.insert("b".into(), point(&self.b));
        if self.axes != Axes::XYZ {
            o.insert("axes".into(), json!(self.axes.to_letters()));
        }
        o.insert("level".into(), json!(self.level));
        if self.weight != 1.0 {
            o.insert("weight".into(), json!(self.weight));
        }
        if !self.active {
            o.insert("active".into(), json!(false));
        }
        Value::Object(o)
    }

    /// The index of the same task once character `removed` is gone (`None`: it joined it).
    pub fn without_character(&self, removed: usize) -> Option<Self> {
        if self.characters().contains(&removed) {
            return None;
        }
        let shift = |p: &CharacterPoint| CharacterPoint {
            character: p.character - usize::from(p.character > removed),
            ..p.clone()
        };
        Some(Self {
            a: shift(&self.a),
            b: shift(&self.b),
            ..self.clone()
        })
    }
}

/// The placement as the solver reads it.
pub fn body_placement(placement: &Placement) -> BodyPlacement {
    BodyPlacement {
        rotation: DQuat::from_rotation_y(placement.yaw_degrees.to_radians()),
        translation: DVec3::from_array(placement.position),
    }
}

/// The scene's characters in groups solved together: each group the characters that tasks
/// between characters join (directly or through others), in scene order; a character no
/// active task joins is a group of its own.
pub fn joined_groups(scene: &Scene) -> Vec<Vec<usize>> {
    joined_groups_of(scene.characters.len(), &scene.between)
}

/// [`joined_groups`] of `n` characters and the tasks `between` them.
pub fn joined_groups_of(n: usize, between: &[BetweenTask]) -> Vec<Vec<usize>> {
    let mut group: Vec<usize> = (0..n).collect();
    fn find(group: &mut [usize], i: usize) -> usize {
        let mut i = i;
        while group[i] != i {
            group[i] = group[group[i]];
            i = group[i];
        }
        i
    }
    for task in between.iter().filter(|t| t.active) {
        let [a, b] = task.characters();
        if a < n && b < n {
            let (ra, rb) = (find(&mut group, a), find(&mut group, b));
            group[ra.max(rb)] = ra.min(rb);
        }
    }
    let mut groups: Vec<Vec<usize>> = Vec::new();
    let mut first_of = vec![usize::MAX; n];
    for i in 0..n {
        let root = find(&mut group, i);
        if first_of[root] == usize::MAX {
            first_of[root] = groups.len();
            groups.push(Vec::new());
        }
        groups[first_of[root]].push(i);
    }
    groups
}

/// Characters of a scene solved as one problem: each character's own problem (its tasks and
/// start, [`Problem::from_document`]) moved onto the joined bodies, their collision tasks
/// joined into one that also keeps the characters apart, and the tasks between them. The
/// tasks that cannot be moved (comfort: built for one body) are left out, each with a
/// message.
#[derive(Debug, Clone)]
pub struct JoinedProblem {
    /// The joined bodies (in the order of the group it was made for).
    pub bodies: Bodies,
    /// Every solver task on the joined skeleton.
    pub tasks: Vec<Task>,
    /// The start: each character's start (its limb tasks' closed forms applied), joined.
    pub start: Posture,
    /// What was left out of the joined solve, one message each.
    pub left_out: Vec<String>,
}

impl JoinedProblem {
    /// The characters `group` of `scene` (scene indices), character `group[i]` on the body
    /// of `problems[i]`.
    pub fn new(
        scene: &Scene,
        group: &[usize],
        problems: &[Problem],
    ) -> Result<Self, DocumentError> {
        let ik = |e: IkError| DocumentError::field("characters", e.to_string());
        if group.len() != problems.len() {
            return Err(DocumentError::field(
                "characters",
                format!("{} problems for {} characters", problems.len(), group.len()),
            ));
        }
        let mut placed = Vec::with_capacity(group.len());
        for (&c, problem) in group.iter().zip(problems) {
            let character = scene
                .characters
                .get(c)
                .ok_or_else(|| DocumentError::field("characters", format!("no character {c}")))?;
            placed.push((&problem.skeleton, body_placement(&character.placement)));
        }
        let bodies = Bodies::new(&placed).map_err(ik)?;
        let own: Vec<&[Task]> = problems.iter().map(|p| p.tasks.as_slice()).collect();
        let skeletons: Vec<&Skeleton> = problems.iter().map(|p| &p.skeleton).collect();
        let (tasks, refused) = joined_tasks(&bodies, group, &own, &skeletons, &scene.between)?;
        let left_out = refused
            .into_iter()
            .map(|(b, task, e)| {
                let c = group.get(b).copied().unwrap_or(b);
                let name = scene.characters.get(c).map_or("", |ch| ch.name.as_str());
                format!(
                    "character {c} ({name}): a {} task at level {} is left out of the joined solve: {e}",
                    kind_word(&task.kind),
                    task.level
                )
            })
            .collect();
        let starts: Vec<Posture> = problems.iter().map(|p| p.start_posture().0).collect();
        let start = bodies
            .posture(&starts.iter().collect::<Vec<_>>())
            .map_err(ik)?;
        Ok(Self {
            bodies,
            tasks,
            start,
            left_out,
        })
    }

    /// Solves it with default settings: each character's posture in its own frame, and the
    /// joined solve's report.
    pub fn solve(&self) -> Result<(Vec<Posture>, SolveReport), IkError> {
        let mut posture = self.start.clone();
        let report = Solver::default().solve(self.bodies.skeleton(), &self.tasks, &mut posture)?;
        Ok((self.bodies.split(&posture)?, report))
    }
}

/// The tasks of characters `group` (scene indices) joined on `bodies`: each body's own solver
/// tasks (`own[b]`, on `skeletons[b]`, in its own frame) moved into the scene, their collision
/// tasks joined into one that also keeps the bodies apart but for the limbs a task between
/// them joins, and the tasks `between` the characters of the group (joints by name). Also
/// returns the tasks that could not move (the body, the task, why). One builder for
/// `stance solve`, the package and the editor's joined frames.
pub fn joined_tasks(
    bodies: &Bodies,
    group: &[usize],
    own: &[&[Task]],
    skeletons: &[&Skeleton],
    between: &[BetweenTask],
) -> Result<JoinedTasks, DocumentError> {
    let ik = |e: IkError| DocumentError::field("characters", e.to_string());
    let mut tasks = Vec::new();
    let mut refused = Vec::new();
    let mut collisions = Vec::new();
    for (b, own) in own.iter().enumerate() {
        for task in own.iter() {
            if matches!(task.kind, TaskKind::Collision(_)) {
                collisions.push((b, task));
                continue;
            }
            match bodies.task(b, task) {
                Ok(moved) => tasks.push(moved),
                Err(e) => refused.push((b, task.clone(), e)),
            }
        }
    }
    let mut touching = Vec::new();
    for (i, task) in between.iter().enumerate() {
        let [ca, cb] = task.characters();
        let (Some(ba), Some(bb)) = (
            group.iter().position(|&c| c == ca),
            group.iter().position(|&c| c == cb),
        ) else {
            continue;
        };
        let at = format!("between[{i}]");
        let point = |b: usize, p: &CharacterPoint, side: &str| {
            let joint = skeletons
                .get(b)
                .and_then(|skeleton| skeleton.joint_index(&p.joint))
                .ok_or_else(|| {
                    DocumentError::field(
                        format!("{at}.{side}.joint"),
                        format!("unknown joint `{}`", p.joint),
                    )
                })?;
            bodies
                .effector(
                    b,
                    Effector {
                        joint,
                        point: DVec3::from_array(p.point),
                    },
                )
                .map_err(ik)
        };
        let (a, b) = (point(ba, &task.a, "a")?, point(bb, &task.b, "b")?);
        touching.push((a.joint, b.joint));
        tasks.push(Task {
            kind: TaskKind::Meet {
                a,
                b,
                axes: task.axes,
            },
            level: task.level,
            weight: task.weight,
            active: task.active,
        });
    }
    if let Some(collision) = bodies.collision(&collisions, &touching).map_err(ik)? {
        tasks.push(collision);
    }
    Ok((tasks, refused))
}

/// [`joined_tasks`]'s tasks, and the ones that could not move: (body, task, why).
pub type JoinedTasks = (Vec<Task>, Vec<(usize, Task, IkError)>);

fn kind_word(kind: &TaskKind) -> &'static str {
    match kind {
        TaskKind::Comfort { .. } => "comfort",
        TaskKind::Collision(_) => "collision",
        _ => "solver",
    }
}

/// Reads a scene's `between` list (absent: none).
pub(crate) fn between_from_json(o: &Map<String, Value>) -> Result<Vec<BetweenTask>, DocumentError> {
    match o.get("between") {
        None | Some(Value::Null) => Ok(Vec::new()),
        Some(Value::Array(list)) => {
            if list.len() > MAX_BETWEEN_TASKS {
                return Err(DocumentError::field(
                    "between",
                    format!("more than {MAX_BETWEEN_TASKS} tasks between characters"),
                ));
            }
            list.iter()
                .enumerate()
                .map(|(i, v)| BetweenTask::from_json_value(v, &format!("between[{i}]")))
                .collect()
        }
        Some(_) => Err(DocumentError::field(
            "between",
            "expected an array of tasks between characters",
        )),
    }
}
