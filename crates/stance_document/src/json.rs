//! JSON helpers whose errors name the field (`tasks[2].target[0]: expected a number`), shared
//! by the document and problem-file parsers.

use serde_json::{Map, Value};

use crate::DocumentError;

/// `value` as JSON text, pretty or compact. Serialising plain maps, strings and numbers cannot
/// fail (an empty text if it ever did).
pub(crate) fn text(value: &impl serde::Serialize, pretty: bool) -> String {
    let text = if pretty {
        serde_json::to_string_pretty(value)
    } else {
        serde_json::to_string(value)
    };
    text.unwrap_or_default()
}

pub(crate) fn obj<'a>(v: &'a Value, at: &str) -> Result<&'a Map<String, Value>, DocumentError> {
    v.as_object()
        .ok_or_else(|| DocumentError::field(at, "expected an object"))
}

pub(crate) fn arr<'a>(v: &'a Value, at: &str) -> Result<&'a Vec<Value>, DocumentError> {
    v.as_array()
        .ok_or_else(|| DocumentError::field(at, "expected an array"))
}

pub(crate) fn field<'a>(
    o: &'a Map<String, Value>,
    name: &str,
    at: &str,
) -> Result<&'a Value, DocumentError> {
    let path = if at.is_empty() {
        name.to_owned()
    } else {
        format!("{at}.{name}")
    };
    o.get(name)
        .filter(|v| !v.is_null())
        .ok_or_else(|| DocumentError::field(path, "missing"))
}

pub(crate) fn string<'a>(v: &'a Value, at: &str) -> Result<&'a str, DocumentError> {
    v.as_str()
        .ok_or_else(|| DocumentError::field(at, "expected a string"))
}

/// The boolean field `name` of `o` (`None`: absent or null); errors at `{at}.{name}`.
pub(crate) fn optional_bool(
    o: &Map<String, Value>,
    at: &str,
    name: &str,
) -> Result<Option<bool>, DocumentError> {
    match o.get(name) {
        None | Some(Value::Null) => Ok(None),
        Some(Value::Bool(b)) => Ok(Some(*b)),
        Some(_) => Err(DocumentError::field(
            format!("{at}.{name}"),
            "expected true or false",
        )),
    }
}

pub(crate) fn number(v: &Value, at: &str) -> Result<f64, DocumentError> {
    let n = v
        .as_f64()
        .ok_or_else(|| DocumentError::field(at, "expected a number"))?;
    if !n.is_finite() {
        return Err(DocumentError::field(at, "not a finite number"));
    }
    Ok(n)
}

pub(crate) fn numbers(v: &Value, at: &str, len: usize) -> Result<Vec<f64>, DocumentError> {
    let a = arr(v, at)?;
    if a.len() != len {
        return Err(DocumentError::field(
            at,
            format!("expected {len} numbers, found {}", a.len()),
        ));
    }
    a.iter()
        .enumerate()
        .map(|(i, x)| number(x, &format!("{at}[{i}]")))
        .collect()
}

pub(crate) fn vec3(v: &Value, at: &str) -> Result<[f64; 3], DocumentError> {
    let n = numbers(v, at, 3)?;
    Ok([n[0], n[1], n[2]])
}
