//! stance_lift's integration tests as one binary.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

mod postures;
mod round_trip;
