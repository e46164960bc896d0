//! The problem-file reader: the skeleton (parents before children, whatever the file's
//! order), the tasks by level and the start posture, from the problem format alone.

use std::collections::HashMap;

use nalgebra::{UnitQuaternion, Vector3};
use serde_json::Value;

use crate::{Dof, Goal, Joint, Problem, ProblemError, Weighted, bad};

fn vector(v: &Value, at: &str) -> Result<Vector3<f64>, ProblemError> {
    let a = v
        .as_array()
        .filter(|a| a.len() == 3)
        .ok_or_else(|| bad(format!("{at}: expected 3 numbers")))?;
    let mut out = Vector3::zeros();
    for (i, x) in a.iter().enumerate() {
        out[i] = x
            .as_f64()
            .ok_or_else(|| bad(format!("{at}[{i}]: expected a number")))?;
    }
    Ok(out)
}

fn axes(v: Option<&Value>, at: &str) -> Result<[bool; 3], ProblemError> {
    let Some(s) = v.and_then(Value::as_str) else {
        return Ok([true; 3]);
    };
    let mut out = [false; 3];
    for c in s.chars() {
        match c {
            'x' | 'X' => out[0] = true,
            'y' | 'Y' => out[1] = true,
            'z' | 'Z' => out[2] = true,
            _ => return Err(bad(format!("{at}: unknown axis `{c}`"))),
        }
    }
    Ok(out)
}

fn dof_of(name: &str) -> Option<Dof> {
    Some(match name {
        "tx" => Dof::Translation(0),
        "ty" => Dof::Translation(1),
        "tz" => Dof::Translation(2),
        "rx" => Dof::Rotation(0),
        "ry" => Dof::Rotation(1),
        "rz" => Dof::Rotation(2),
        _ => return None,
    })
}

impl Problem {
    /// Reads a problem file (the subset of the format the families use: `position`,
    /// `orientation`, `direction`, `gaze`, `com`).
    pub fn from_json(text: &str) -> Result<Self, ProblemError> {
        let root: Value = serde_json::from_str(text)?;
        let listed = root
            .pointer("/skeleton/joints")
            .and_then(Value::as_array)
            .ok_or_else(|| bad("skeleton.joints: expected a list"))?;
        // Parents before children, whatever the file's order.
        let mut pending: Vec<&Value> = listed.iter().collect();
        let mut joints: Vec<Joint> = Vec::new();
        let mut by_name: HashMap<String, usize> = HashMap::new();
        let mut lower = Vec::new();
        let mut upper = Vec::new();
        let mut dof_names = Vec::new();
        while !pending.is_empty() {
            let before = pending.len();
            let mut rest = Vec::new();
            for j in pending {
                let name = j
                    .get("name")
                    .and_then(Value::as_str)
                    .ok_or_else(|| bad("skeleton.joints[]: a joint without a name"))?;
                let parent = match j.get("parent").and_then(Value::as_str) {
                    None => None,
                    Some(p) => match by_name.get(p) {
                        Some(&i) => Some(i),
                        None => {
                            rest.push(j);
                            continue;
                        }
                    },
                };
                let offset = match j.get("offset") {
                    Some(v) => vector(v, &format!("{name}.offset"))?,
                    None => Vector3::zeros(),
                };
                let mut dofs = Vec::new();
                for d in j
                    .get("dofs")
                    .and_then(Value::as_array)
                    .into_iter()
                    .flatten()
                {
                    let dn = d.as_str().unwrap_or("");
                    let dof = dof_of(dn).ok_or_else(|| bad(format!("{name}: unknown DOF {d}")))?;
                    let limit = j
                        .pointer(&format!("/limits/{dn}"))
                        .and_then(Value::as_array);
                    let bound = |k: usize, default: f64| {
                        limit
                            .and_then(|l| l.get(k))
                            .and_then(Value::as_f64)
                            .unwrap_or(default)
                    };
                    lower.push(bound(0, f64::NEG_INFINITY));
                    upper.push(bound(1, f64::INFINITY));
                    dof_names.push((name.to_owned(), dn.to_owned()));
                    dofs.push((dof, lower.len() - 1));
                }
                let com = match j.get("com") {
                    Some(v) if !v.is_null() => vector(v, &format!("{name}.com"))?,
                    _ => Vector3::zeros(),
                };
                by_name.insert(name.to_owned(), joints.len());
                joints.push(Joint {
                    name: name.to_owned(),
                    parent,
                    offset,
                    dofs,
                    mass: j.get("mass").and_then(Value::as_f64).unwrap_or(0.0),
                    com,
                });
            }
            if rest.len() == before {
                return Err(bad(
                    "skeleton: a parent is missing or the parents form a cycle",
                ));
            }
            pending = rest;
        }
        let ancestor: Vec<Vec<bool>> = (0..joints.len())
            .map(|j| {
                let mut row = vec![false; joints.len()];
                let mut at = Some(j);
                while let Some(a) = at {
                    row[a] = true;
                    at = joints[a].parent;
                }
                row
            })
            .collect();
        let joint = |t: &Value, at: &str| -> Result<usize, ProblemError> {
            let name = t
                .get("joint")
                .and_then(Value::as_str)
                .ok_or_else(|| bad(format!("{at}.joint: missing")))?;
            by_name
                .get(name)
                .copied()
                .ok_or_else(|| bad(format!("{at}.joint: unknown joint `{name}`")))
        };
        let mut owner = vec![0; lower.len()];
        let mut rotational = vec![false; lower.len()];
        for (j, joint) in joints.iter().enumerate() {
            for &(dof, i) in &joint.dofs {
                owner[i] = j;
                rotational[i] = matches!(dof, Dof::Rotation(_));
            }
        }
        let mut problem = Self {
            owner,
            rotational,
            joints,
            ancestor,
            lower,
            upper,
            dof_names,
            levels: Vec::new(),
            start: Vec::new(),
            tolerance: root
                .pointer("/settings/tolerance")
                .and_then(Value::as_f64)
                .unwrap_or(1e-6),
        };
        let mut by_level: Vec<(u64, Weighted)> = Vec::new();
        for (i, t) in root
            .get("tasks")
            .and_then(Value::as_array)
            .into_iter()
            .flatten()
            .enumerate()
        {
            let at = format!("tasks[{i}]");
            if t.get("active").and_then(Value::as_bool) == Some(false) {
                continue;
            }
            let target = || {
                vector(
                    t.get("target").unwrap_or(&Value::Null),
                    &format!("{at}.target"),
                )
            };
            let point = || match t.get("point") {
                Some(v) => vector(v, &format!("{at}.point")),
                None => Ok(Vector3::zeros()),
            };
            let axis = |default: Vector3<f64>| match t.get("axis") {
                Some(v) => vector(v, &format!("{at}.axis")).map(|a| a.normalize()),
                None => Ok(default),
            };
            let goal =
                match t.get("kind").and_then(Value::as_str) {
                    Some("position") => Goal::Position {
                        joint: joint(t, &at)?,
                        point: point()?,
                        axes: axes(t.get("axes"), &at)?,
                        target: target()?,
                    },
                    Some("orientation") => {
                        let q = t
                            .get("target")
                            .and_then(Value::as_array)
                            .filter(|q| q.len() == 4)
                            .ok_or_else(|| bad(format!("{at}.target: expected 4 numbers")))?;
                        let c = |k: usize| q[k].as_f64().unwrap_or(0.0);
                        let quaternion = UnitQuaternion::from_quaternion(
                            nalgebra::Quaternion::new(c(3), c(0), c(1), c(2)),
                        );
                        Goal::Orientation {
                            joint: joint(t, &at)?,
                            target: quaternion.to_rotation_matrix(),
                        }
                    }
                    Some("direction") => Goal::Direction {
                        joint: joint(t, &at)?,
                        axis: axis(Vector3::y())?,
                        target: target()?.normalize(),
                    },
                    Some("gaze") => Goal::Gaze {
                        joint: joint(t, &at)?,
                        point: point()?,
                        axis: axis(Vector3::z())?,
                        target: target()?,
                    },
                    Some("com") => Goal::Com {
                        axes: axes(t.get("axes"), &at)?,
                        target: target()?,
                    },
                    Some("balance") => {
                        let names: Vec<&str> = t
                            .get("support")
                            .and_then(Value::as_array)
                            .ok_or_else(|| {
                                bad(format!(
                                    "{at}.support: the oracle reads listed supports only"
                                ))
                            })?
                            .iter()
                            .map(|v| v.as_str().unwrap_or(""))
                            .collect();
                        Goal::Balance {
                            support: problem.support_points(&names).ok_or_else(|| {
                                bad(format!(
                                    "{at}.support: an unknown joint or a foot without an ankle"
                                ))
                            })?,
                            margin: t.get("margin").and_then(Value::as_f64).unwrap_or(0.02),
                        }
                    }
                    Some("line") => Goal::Line {
                        joint: joint(t, &at)?,
                        point: point()?,
                        origin: vector(
                            t.get("origin").unwrap_or(&Value::Null),
                            &format!("{at}.origin"),
                        )?,
                        direction: vector(
                            t.get("direction").unwrap_or(&Value::Null),
                            &format!("{at}.direction"),
                        )?
                        .normalize(),
                    },
                    Some("plane") => Goal::Plane {
                        joint: joint(t, &at)?,
                        point: point()?,
                        origin: vector(
                            t.get("origin").unwrap_or(&Value::Null),
                            &format!("{at}.origin"),
                        )?,
                        normal: match t.get("normal") {
                            Some(v) => vector(v, &format!("{at}.normal"))?.normalize(),
                            None => Vector3::y(),
                        },
                        above: t.get("above").and_then(Value::as_bool).unwrap_or(false),
                    },
                    other => return Err(bad(format!("{at}.kind: {other:?} is not read here"))),
                };
            let weight = t.get("weight").and_then(Value::as_f64).unwrap_or(1.0);
            let level = t.get("level").and_then(Value::as_u64).unwrap_or(1);
            by_level.push((
                level,
                Weighted {
                    goal,
                    scale: weight.max(0.0).sqrt(),
                },
            ));
        }
        by_level.sort_by_key(|(level, _)| *level);
        let mut levels: Vec<Vec<Weighted>> = Vec::new();
        let mut last = None;
        for (level, task) in by_level {
            if last != Some(level) {
                levels.push(Vec::new());
                last = Some(level);
            }
            if let Some(l) = levels.last_mut() {
                l.push(task);
            }
        }
        problem.levels = levels;
        problem.start = match root.get("posture") {
            Some(p) if !p.is_null() => problem.posture_from_json(p)?,
            _ => vec![0.0; problem.dof_count()],
        };
        Ok(problem)
    }
}
