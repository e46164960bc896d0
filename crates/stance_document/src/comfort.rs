//! Comfort in files: the problem file's `comfort` object (RULA's inputs that a posture does not
//! show, the strength profile) and the comfort report as JSON (`stance comfort`,
//! `report.comfort` of `stance solve`), see `docs/comfort.md`.

use serde_json::{Map, Value, json};
use stance_hanim::comfort::rula::{RulaLoad, RulaTolerances, RulaVariant};
use stance_hanim::comfort::{ComfortReport, ComfortSettings, comfort_report};
use stance_hanim::strength::{Sex, aligned_axes};
use stance_ik::{Posture, Skeleton};

use crate::DocumentError;
use crate::json::{number, obj, optional_bool, string};

/// The file's names of RULA's variants, tolerances, loads and the strength profile's sexes.
const VARIANTS: &[(&str, RulaVariant)] = &[
    ("paper", RulaVariant::Paper),
    ("worksheet", RulaVariant::Worksheet),
];
const TOLERANCES: &[(&str, RulaTolerances)] = &[
    ("stance", RulaTolerances::STANCE),
    ("none", RulaTolerances::NONE),
];
const LOADS: &[(&str, RulaLoad)] = &[
    ("none", RulaLoad::None),
    ("intermittent_2_10", RulaLoad::Intermittent2To10),
    ("static_2_10", RulaLoad::Static2To10),
    ("intermittent_10", RulaLoad::Intermittent10Plus),
    ("static_10", RulaLoad::Static10Plus),
    ("shock", RulaLoad::Shock),
];
const SEXES: &[(&str, Sex)] = &[("male", Sex::Male), ("female", Sex::Female)];

/// The value named by the string field `name` of `o` among `choices` (`None`: absent).
fn choice<T: Copy>(
    o: &Map<String, Value>,
    at: &str,
    name: &str,
    choices: &[(&str, T)],
) -> Result<Option<T>, DocumentError> {
    let Some(v) = o.get(name).filter(|v| !v.is_null()) else {
        return Ok(None);
    };
    let here = format!("{at}.{name}");
    let given = string(v, &here)?;
    match choices.iter().find(|(key, _)| *key == given) {
        Some((_, value)) => Ok(Some(*value)),
        None => {
            let names: Vec<&str> = choices.iter().map(|(key, _)| *key).collect();
            Err(DocumentError::field(
                here,
                format!("`{given}` (expected one of {})", names.join(", ")),
            ))
        }
    }
}

/// Parses `{"variant": "paper" | "worksheet", "tolerances": "stance" | "none", "load": "none"
/// | "intermittent_2_10" | "static_2_10" | "intermittent_10" | "static_10" | "shock",
/// "muscle_use": bool, "arm_supported": bool, "legs_supported": bool, "seated_supported":
/// bool, "sex": "male" | "female", "mass": kg, "stature": m}`; every field optional.
pub fn parse_comfort_settings(v: &Value, at: &str) -> Result<ComfortSettings, DocumentError> {
    let o = obj(v, at)?;
    let mut s = ComfortSettings::default();
    let here = |name: &str| format!("{at}.{name}");
    let flag = |name: &str| optional_bool(o, at, name);
    if let Some(variant) = choice(o, at, "variant", VARIANTS)? {
        s.rula_settings.variant = variant;
    }
    if let Some(tolerances) = choice(o, at, "tolerances", TOLERANCES)? {
        s.rula_settings.tolerances = tolerances;
    }
    if let Some(load) = choice(o, at, "load", LOADS)? {
        s.rula_settings.load = load;
    }
    if let Some(b) = flag("muscle_use")? {
        s.rula_settings.muscle_use = b;
    }
    if let Some(b) = flag("arm_supported")? {
        s.rula_settings.arm_supported = b;
    }
    if let Some(b) = flag("legs_supported")? {
        s.rula_settings.legs_supported = Some(b);
    }
    if let Some(b) = flag("seated_supported")? {
        s.rula_settings.seated_supported = b;
    }
    if let Some(sex) = choice(o, at, "sex", SEXES)? {
        s.profile.sex = sex;
    }
    for (name, slot) in [
        ("mass", &mut s.profile.mass_kg),
        ("stature", &mut s.profile.stature_m),
    ] {
        if let Some(v) = o.get(name).filter(|v| !v.is_null()) {
            let x = number(v, &here(name))?;
            if x <= 0.0 {
                return Err(DocumentError::field(here(name), "expected a number > 0"));
            }
            *slot = x;
        }
    }
    Ok(s)
}

/// The comfort of `posture` as JSON: `{"rula": n, "action_level": n, "rula_parts": {...},
/// "torques_nm": {joint: x}, "shares": {joint: x}, "flagged": [joint], "effort": x,
/// "range": x}` (`rula` and its parts null on a body without the joints RULA reads).
pub fn comfort_json(skeleton: &Skeleton, posture: &Posture, settings: &ComfortSettings) -> Value {
    let report = comfort_report(skeleton, &aligned_axes(skeleton), posture, settings);
    report_json(&report)
}

/// A comfort report as JSON (see [`comfort_json`]).
pub fn report_json(report: &ComfortReport) -> Value {
    let mut torques = Map::new();
    let mut shares = Map::new();
    let mut flagged = Vec::new();
    for load in &report.loads {
        torques.insert(load.joint.clone(), json!(load.torque_nm));
        if let Some(share) = load.share {
            shares.insert(load.joint.clone(), json!(share));
        }
        if load.flagged {
            flagged.push(json!(load.joint));
        }
    }
    let (rula, action_level, parts) = match &report.rula {
        Some(r) => (json!(r.score), json!(r.action_level), rula_parts(r)),
        None => (Value::Null, Value::Null, Value::Null),
    };
    json!({
        "rula": rula,
        "action_level": action_level,
        "rula_parts": parts,
        "torques_nm": torques,
        "shares": shares,
        "flagged": flagged,
        "effort": report.terms.effort,
        "range": report.terms.range,
    })
}

fn rula_parts(r: &stance_hanim::comfort::rula::RulaReport) -> Value {
    let side = |s: &stance_hanim::comfort::rula::RulaArm| {
        json!({
            "upper_arm": s.upper_arm,
            "lower_arm": s.lower_arm,
            "wrist": s.wrist,
            "wrist_twist": s.wrist_twist,
            "posture_a": s.posture_a,
            "score_c": s.score_c,
        })
    };
    json!({
        "left": side(&r.left),
        "right": side(&r.right),
        "neck": r.body.neck,
        "trunk": r.body.trunk,
        "legs": r.body.legs,
        "posture_b": r.body.posture_b,
        "score_d": r.body.score_d,
    })
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use super::*;

    #[test]
    fn the_comfort_object_chooses_rulas_tolerances() {
        // Catches a `tolerances` field that is ignored, read into the wrong setting, or that
        // changes the default when absent.
        let parse = |text: &str| {
            parse_comfort_settings(&serde_json::from_str(text).unwrap(), "comfort")
                .map(|s| s.rula_settings)
        };
        assert_eq!(parse("{}").unwrap().tolerances, RulaTolerances::STANCE);
        let printed = parse(r#"{"tolerances": "none", "variant": "worksheet"}"#).unwrap();
        assert_eq!(printed.tolerances, RulaTolerances::NONE);
        assert_eq!(printed.variant, RulaVariant::Worksheet);
        let stance = parse(r#"{"tolerances": "stance"}"#).unwrap();
        assert_eq!(stance.tolerances, RulaTolerances::STANCE);
        let err = parse(r#"{"tolerances": "paper"}"#).unwrap_err().to_string();
        assert!(
            err.contains("comfort.tolerances") && err.contains("none"),
            "{err}"
        );
    }
}
