//! Motion-capture sensors for Stance: streaming byte decoders, IMU fusion and calibration.
//!
//! Everything here is pure: bytes (or WebHID reports) go in, [`Sample`]s come out, and
//! [`calibration::Calibration`] turns samples into joint rotations. The browser bridge only moves
//! bytes; native tests and recorded-file replay use exactly the same path. [`device`] knows the
//! devices (protocol, start and stop bytes, decoder settings) and [`rig`] which body segment each
//! sensor drives.
//!
//! Conventions: positions in metres, quaternions are `glam::DQuat` (serialised `[x, y, z, w]`),
//! angles in radians unless a name says otherwise. A sample's orientation maps vectors from the
//! sensor frame into the device's reference frame (transmitter, source or earth frame); the
//! calibration's `world_from_device` rotation brings that frame into the editor's world.

#![warn(missing_docs)]

pub mod ascii;
pub mod calibration;
pub mod decoder;
pub mod device;
pub mod fob;
pub mod framing;
pub mod fusion;
pub mod hid;
pub mod polhemus;
pub mod rig;
pub mod simulate;
pub mod xsens;

pub use decoder::{Decoder, DecoderConfig, DecoderStats, Protocol, Sample, SensorId, new_decoder};
