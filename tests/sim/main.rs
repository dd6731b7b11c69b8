//! The simulator and long simulated drives.
// Test code: a panic fails the test (the robot's lints, Cargo.toml).
#![allow(clippy::restriction)]

#[path = "../common/mod.rs"]
mod common;

mod hard_world;
mod pivot;
mod realism;
mod realistic_hour;
mod simulate;
mod spot;
mod survey_room;
