//! The control loop: commands, untethered missions, long soaks with faults.
// Test code: a panic fails the test (the robot's lints, Cargo.toml).
#![allow(clippy::restriction)]

#[path = "../common/mod.rs"]
mod common;

mod basics;
mod faults_long;
mod kept_log;
mod settings;
mod settings_loop;
mod soak;
mod untethered;
