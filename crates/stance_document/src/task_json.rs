//! A task's JSON form, read (with errors naming the field) and written: the `tasks` of
//! documents and problem files (`docs/document-format.md`, `docs/problem-format.md`).

use serde::ser::SerializeMap;
use serde::{Deserialize, Deserializer, Serialize, Serializer};
use serde_json::Value;
use stance_hanim::capsules::COLLISION_MARGIN;
use stance_ik::Axes;

use crate::DocumentError;
use crate::document::{
    DEFAULT_BALANCE_MARGIN, DEFAULT_COMFORT, LimbName, PostureValues, TaskKindSpec, TaskSpec,
};
use crate::json::{arr, field, number, numbers, obj, optional_bool, string, vec3};
use crate::motion::TaskInterval;

impl TaskSpec {
    /// Parses a `tasks` array; `at` is its path (e.g. `tasks`).
    pub fn list_from_json_value(v: &Value, at: &str) -> Result<Vec<Self>, DocumentError> {
        arr(v, at)?
            .iter()
            .enumerate()
            .map(|(i, t)| TaskSpec::from_json_value(t, &format!("{at}[{i}]")))
            .collect()
    }

    /// Parses one task object; `at` is its path (e.g. `tasks[2]`). Unknown fields are ignored.
    pub fn from_json_value(v: &Value, at: &str) -> Result<Self, DocumentError> {
        let o = obj(v, at)?;
        let here = |name: &str| format!("{at}.{name}");
        let f = |name: &str| field(o, name, at);
        let opt = |name: &str| o.get(name).filter(|v| !v.is_null());
        let kind_name = string(f("kind")?, &here("kind"))?;
        let point = match opt("point") {
            None => [0.0; 3],
            Some(p) => vec3(p, &here("point"))?,
        };
        let axes = match opt("axes") {
            None => Axes::XYZ,
            Some(a) => {
                let s = string(a, &here("axes"))?;
                Axes::parse(s).ok_or_else(|| {
                    DocumentError::field(
                        here("axes"),
                        format!("`{s}` is not a non-empty subset of \"xyz\""),
                    )
                })?
            }
        };
        let joint = |name: &str| -> Result<String, DocumentError> {
            Ok(string(f(name)?, &here(name))?.to_owned())
        };
        let kind = match kind_name {
            "position" => TaskKindSpec::Position {
                joint: joint("joint")?,
                point,
                axes,
                target: vec3(f("target")?, &here("target"))?,
            },
            "orientation" => {
                let q = numbers(f("target")?, &here("target"), 4)?;
                if q.iter().map(|x| x * x).sum::<f64>().sqrt() < 1e-9 {
                    return Err(DocumentError::field(
                        here("target"),
                        "the quaternion has zero length",
                    ));
                }
                TaskKindSpec::Orientation {
                    joint: joint("joint")?,
                    target: [q[0], q[1], q[2], q[3]],
                }
            }
            "gaze" => {
                let axis = match opt("axis") {
                    None => [0.0, 0.0, 1.0],
                    Some(a) => vec3(a, &here("axis"))?,
                };
                if axis.iter().map(|x| x * x).sum::<f64>().sqrt() < 1e-9 {
                    return Err(DocumentError::field(here("axis"), "zero-length axis"));
                }
                TaskKindSpec::Gaze {
                    joint: joint("joint")?,
                    axis,
                    point,
                    target: vec3(f("target")?, &here("target"))?,
                }
            }
            "direction" => {
                let axis = match opt("axis") {
                    None => [0.0, 1.0, 0.0],
                    Some(a) => vec3(a, &here("axis"))?,
                };
                if axis.iter().map(|x| x * x).sum::<f64>().sqrt() < 1e-9 {
                    return Err(DocumentError::field(here("axis"), "zero-length axis"));
                }
                let target = vec3(f("target")?, &here("target"))?;
                if target.iter().map(|x| x * x).sum::<f64>().sqrt() < 1e-9 {
                    return Err(DocumentError::field(
                        here("target"),
                        "zero-length direction",
                    ));
                }
                TaskKindSpec::Direction {
                    joint: joint("joint")?,
                    axis,
                    target,
                }
            }
            "balance" => {
                let support = match opt("support") {
                    None => None,
                    Some(list) => {
                        let names = arr(list, &here("support"))?
                            .iter()
                            .enumerate()
                            .map(|(k, j)| {
                                string(j, &format!("{}[{k}]", here("support"))).map(str::to_owned)
                            })
                            .collect::<Result<Vec<_>, _>>()?;
                        if names.is_empty() {
                            return Err(DocumentError::field(
                                here("support"),
                                "empty (leave it out for the pinned contacts)",
                            ));
                        }
                        Some(names)
                    }
                };
                let margin = match opt("margin") {
                    None => DEFAULT_BALANCE_MARGIN,
                    Some(m) => {
                        let m = number(m, &here("margin"))?;
                        if m < 0.0 {
                            return Err(DocumentError::field(here("margin"), "must be >= 0"));
                        }
                        m
                    }
                };
                TaskKindSpec::Balance { support, margin }
            }
            "com" => TaskKindSpec::Com {
                axes,
                target: vec3(f("target")?, &here("target"))?,
            },
            "posture" => {
                let reference = match opt("reference") {
                    None => None,
                    Some(r) => Some(PostureValues::from_json_value(r, &here("reference"))?),
                };
                let joints = match opt("joints") {
                    None => None,
                    Some(list) => Some(
                        arr(list, &here("joints"))?
                            .iter()
                            .enumerate()
                            .map(|(k, j)| {
                                string(j, &format!("{}[{k}]", here("joints"))).map(str::to_owned)
                            })
                            .collect::<Result<Vec<_>, _>>()?,
                    ),
                };
                TaskKindSpec::Posture { joints, reference }
            }
            "comfort" => {
                let weight = |name: &str, default: f64| -> Result<f64, DocumentError> {
                    match opt(name) {
                        None => Ok(default),
                        Some(v) => number(v, &here(name)),
                    }
                };
                TaskKindSpec::Comfort {
                    effort: weight("effort", DEFAULT_COMFORT.0)?,
                    range: weight("range", DEFAULT_COMFORT.1)?,
                    rula: weight("rula", DEFAULT_COMFORT.2)?,
                }
            }
            "collision" => {
                let margin = match opt("margin") {
                    None => COLLISION_MARGIN,
                    Some(m) => {
                        let m = number(m, &here("margin"))?;
                        if m < 0.0 {
                            return Err(DocumentError::field(here("margin"), "must be >= 0"));
                        }
                        m
                    }
                };
                TaskKindSpec::Collision {
                    margin,
                    self_collision: optional_bool(o, at, "self")?.unwrap_or(true),
                    floor: optional_bool(o, at, "floor")?.unwrap_or(true),
                }
            }
            "limb" => {
                let limb = match opt("limb") {
                    None => None,
                    Some(l) => {
                        let s = string(l, &here("limb"))?;
                        Some(LimbName::from_name(s).ok_or_else(|| {
                            DocumentError::field(
                                here("limb"),
                                format!(
                                    "unknown limb `{s}` (expected l_arm, r_arm, l_leg or r_leg)"
                                ),
                            )
                        })?)
                    }
                };
                let joints = match opt("joints") {
                    None => None,
                    Some(list) => {
                        let a = arr(list, &here("joints"))?;
                        if a.len() != 3 {
                            return Err(DocumentError::field(
                                here("joints"),
                                format!(
                                    "expected 3 joint names (root, middle, end), found {}",
                                    a.len()
                                ),
                            ));
                        }
                        let name = |k: usize| -> Result<String, DocumentError> {
                            Ok(string(&a[k], &format!("{}[{k}]", here("joints")))?.to_owned())
                        };
                        Some([name(0)?, name(1)?, name(2)?])
                    }
                };
                match (&limb, &joints) {
                    (Some(_), Some(_)) => {
                        return Err(DocumentError::field(
                            at,
                            "give either `joints` or `limb`, not both",
                        ));
                    }
                    (None, None) => {
                        return Err(DocumentError::field(
                            here("joints"),
                            "missing (or give `limb`)",
                        ));
                    }
                    _ => {}
                }
                let swivel = match opt("swivel") {
                    None => None,
                    Some(s) => Some(number(s, &here("swivel"))?),
                };
                let orientation = match opt("orientation") {
                    None => None,
                    Some(q) => {
                        let q = numbers(q, &here("orientation"), 4)?;
                        if q.iter().map(|x| x * x).sum::<f64>().sqrt() < 1e-9 {
                            return Err(DocumentError::field(
                                here("orientation"),
                                "the quaternion has zero length",
                            ));
                        }
                        Some([q[0], q[1], q[2], q[3]])
                    }
                };
                TaskKindSpec::Limb {
                    limb,
                    joints,
                    target: vec3(f("target")?, &here("target"))?,
                    swivel,
                    orientation,
                }
            }
            "line" => TaskKindSpec::Line {
                joint: joint("joint")?,
                point,
                origin: vec3(f("origin")?, &here("origin"))?,
                direction: nonzero_vec3(f("direction")?, &here("direction"))?,
            },
            "plane" => TaskKindSpec::Plane {
                joint: joint("joint")?,
                point,
                origin: vec3(f("origin")?, &here("origin"))?,
                normal: match opt("normal") {
                    None => [0.0, 1.0, 0.0],
                    Some(n) => nonzero_vec3(n, &here("normal"))?,
                },
                above: match opt("above") {
                    None => false,
                    Some(Value::Bool(b)) => *b,
                    Some(_) => {
                        return Err(DocumentError::field(
                            here("above"),
                            "expected true or false",
                        ));
                    }
                },
            },
            other => {
                return Err(DocumentError::field(
                    here("kind"),
                    format!(
                        "unknown kind `{other}` (expected position, orientation, direction, gaze, com, balance, posture, comfort, collision, limb, line or plane)"
                    ),
                ));
            }
        };
        let level = match opt("level") {
            None => 1,
            Some(l) => {
                let n = number(l, &here("level"))?;
                if n < 1.0 || n.fract() != 0.0 || n > f64::from(u32::MAX) {
                    return Err(DocumentError::field(
                        here("level"),
                        "levels are integers from 1 (highest priority)",
                    ));
                }
                n as u32
            }
        };
        let weight = match opt("weight") {
            None => 1.0,
            Some(w) => {
                let w = number(w, &here("weight"))?;
                if w < 0.0 {
                    return Err(DocumentError::field(here("weight"), "must be >= 0"));
                }
                w
            }
        };
        let active = match opt("active") {
            None => true,
            Some(Value::Bool(b)) => *b,
            Some(_) => {
                return Err(DocumentError::field(
                    here("active"),
                    "expected true or false",
                ));
            }
        };
        let interval = match opt("interval") {
            None => None,
            Some(i) => Some(TaskInterval::from_json_value(i, &here("interval"))?),
        };
        let on = match opt("on") {
            None => None,
            Some(name) => Some(
                crate::scene::clean_name(string(name, &here("on"))?)
                    .ok_or_else(|| DocumentError::field(here("on"), "an empty prop name"))?,
            ),
        };
        Ok(TaskSpec {
            level,
            weight,
            active,
            kind,
            interval,
            on,
        })
    }
}

/// A non-zero 3-vector (a line's direction, a plane's normal).
fn nonzero_vec3(v: &Value, at: &str) -> Result<[f64; 3], DocumentError> {
    let v3 = vec3(v, at)?;
    if v3.iter().map(|x| x * x).sum::<f64>().sqrt() < 1e-9 {
        return Err(DocumentError::field(at, "zero-length vector"));
    }
    Ok(v3)
}

impl Serialize for TaskSpec {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let mut m = s.serialize_map(None)?;
        m.serialize_entry("level", &self.level)?;
        m.serialize_entry("kind", self.kind.name())?;
        match &self.kind {
            TaskKindSpec::Position {
                joint,
                point,
                axes,
                target,
            } => {
                m.serialize_entry("joint", joint)?;
                m.serialize_entry("point", point)?;
                m.serialize_entry("axes", &axes.to_letters())?;
                m.serialize_entry("target", target)?;
            }
            TaskKindSpec::Orientation { joint, target } => {
                m.serialize_entry("joint", joint)?;
                m.serialize_entry("target", target)?;
            }
            TaskKindSpec::Gaze {
                joint,
                axis,
                point,
                target,
            } => {
                m.serialize_entry("joint", joint)?;
                m.serialize_entry("axis", axis)?;
                m.serialize_entry("point", point)?;
                m.serialize_entry("target", target)?;
            }
            TaskKindSpec::Direction {
                joint,
                axis,
                target,
            } => {
                m.serialize_entry("joint", joint)?;
                m.serialize_entry("axis", axis)?;
                m.serialize_entry("target", target)?;
            }
            TaskKindSpec::Balance { support, margin } => {
                if let Some(names) = support {
                    m.serialize_entry("support", names)?;
                }
                m.serialize_entry("margin", margin)?;
            }
            TaskKindSpec::Com { axes, target } => {
                m.serialize_entry("axes", &axes.to_letters())?;
                m.serialize_entry("target", target)?;
            }
            TaskKindSpec::Posture { joints, reference } => {
                if let Some(j) = joints {
                    m.serialize_entry("joints", j)?;
                }
                if let Some(r) = reference {
                    m.serialize_entry("reference", r)?;
                }
            }
            TaskKindSpec::Comfort {
                effort,
                range,
                rula,
            } => {
                m.serialize_entry("effort", effort)?;
                m.serialize_entry("range", range)?;
                m.serialize_entry("rula", rula)?;
            }
            TaskKindSpec::Collision {
                margin,
                self_collision,
                floor,
            } => {
                m.serialize_entry("margin", margin)?;
                m.serialize_entry("self", self_collision)?;
                m.serialize_entry("floor", floor)?;
            }
            TaskKindSpec::Limb {
                limb,
                joints,
                target,
                swivel,
                orientation,
            } => {
                if let Some(l) = limb {
                    m.serialize_entry("limb", l.name())?;
                }
                if let Some(j) = joints {
                    m.serialize_entry("joints", j)?;
                }
                m.serialize_entry("target", target)?;
                if let Some(s) = swivel {
                    m.serialize_entry("swivel", s)?;
                }
                if let Some(q) = orientation {
                    m.serialize_entry("orientation", q)?;
                }
            }
            TaskKindSpec::Line {
                joint,
                point,
                origin,
                direction,
            } => {
                m.serialize_entry("joint", joint)?;
                m.serialize_entry("point", point)?;
                m.serialize_entry("origin", origin)?;
                m.serialize_entry("direction", direction)?;
            }
            TaskKindSpec::Plane {
                joint,
                point,
                origin,
                normal,
                above,
            } => {
                m.serialize_entry("joint", joint)?;
                m.serialize_entry("point", point)?;
                m.serialize_entry("origin", origin)?;
                m.serialize_entry("normal", normal)?;
                m.serialize_entry("above", above)?;
            }
        }
        m.serialize_entry("weight", &self.weight)?;
        m.serialize_entry("active", &self.active)?;
        if let Some(on) = &self.on {
            m.serialize_entry("on", on)?;
        }
        if let Some(interval) = &self.interval {
            m.serialize_entry("interval", interval)?;
        }
        m.end()
    }
}

impl<'de> Deserialize<'de> for TaskSpec {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let v = Value::deserialize(d)?;
        let t = TaskSpec::from_json_value(&v, "task").map_err(serde::de::Error::custom)?;
        t.validate()
            .map_err(|e| serde::de::Error::custom(e.within("task")))?;
        Ok(t)
    }
}
