//! Comfort of an H-Anim body's posture: RULA ([`rula`]) and the comfort cost and report
//! (`model`): joint loads against gravity as shares of strength, joint ranges, RULA.

mod model;
pub mod rula;

pub use model::{ComfortReport, ComfortSettings, JointLoad, comfort_model, comfort_report};
