//! The textbook oracle's own checks, and Stance measured against it on the problem families.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

mod common;
mod families;
mod jacobians;
mod line_plane;
