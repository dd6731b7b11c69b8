//! Localization: the search over the box and the procedure in the loop.
// Test code: a panic fails the test (the robot's lints, Cargo.toml).
#![allow(clippy::restriction)]

#[path = "../common/mod.rs"]
mod common;

mod localize;
mod locate;
mod refine;
