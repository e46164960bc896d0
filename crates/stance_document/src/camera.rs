//! The camera a document can be saved with: where the view looks from, so that opening the
//! document shows it as its author framed it.

use serde::ser::SerializeMap;
use serde::{Serialize, Serializer};
use serde_json::Value;

use crate::error::DocumentError;
use crate::json::{field, number, obj, vec3};

/// An orbit camera: a target point, the direction it is seen from, the distance and the
/// projection.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CameraSpec {
    /// The point looked at (m, H-Anim frame).
    pub target: [f64; 3],
    /// Turn about +Y from the front (rad; 0 looks at the body's front).
    pub yaw: f64,
    /// Elevation, positive looking down (rad, within ±1.5).
    pub pitch: f64,
    /// Distance from the target (m, > 0).
    pub distance: f64,
    /// Orthographic projection instead of perspective.
    pub orthographic: bool,
}

impl CameraSpec {
    /// Checks every number.
    pub fn validate(&self) -> Result<(), DocumentError> {
        if !self.target.iter().all(|x| x.is_finite()) {
            return Err(DocumentError::field("camera.target", "must be finite"));
        }
        if !self.yaw.is_finite() {
            return Err(DocumentError::field("camera.yaw", "must be finite"));
        }
        if !(self.pitch.is_finite() && self.pitch.abs() <= 1.5) {
            return Err(DocumentError::field(
                "camera.pitch",
                "must be within -1.5 to 1.5 rad",
            ));
        }
        if !(self.distance.is_finite() && self.distance > 0.0 && self.distance <= 1000.0) {
            return Err(DocumentError::field(
                "camera.distance",
                "must be in (0, 1000] m",
            ));
        }
        Ok(())
    }

    /// Reads `camera` from a document's JSON.
    pub fn from_json_value(v: &Value) -> Result<Self, DocumentError> {
        let at = "camera";
        let o = obj(v, at)?;
        let orthographic = match o.get("orthographic").filter(|v| !v.is_null()) {
            None => false,
            Some(Value::Bool(b)) => *b,
            Some(_) => {
                return Err(DocumentError::field(
                    "camera.orthographic",
                    "expected true or false",
                ));
            }
        };
        let camera = Self {
            target: vec3(field(o, "target", at)?, "camera.target")?,
            yaw: number(field(o, "yaw", at)?, "camera.yaw")?,
            pitch: number(field(o, "pitch", at)?, "camera.pitch")?,
            distance: number(field(o, "distance", at)?, "camera.distance")?,
            orthographic,
        };
        camera.validate()?;
        Ok(camera)
    }
}

impl Serialize for CameraSpec {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let mut m = s.serialize_map(Some(5))?;
        m.serialize_entry("target", &self.target)?;
        m.serialize_entry("yaw", &self.yaw)?;
        m.serialize_entry("pitch", &self.pitch)?;
        m.serialize_entry("distance", &self.distance)?;
        m.serialize_entry("orthographic", &self.orthographic)?;
        m.end()
    }
}
