//! The host tools: teleop (line mode, missions, a pty), the examples' command lines.
// Test code: a panic fails the test (the robot's lints, Cargo.toml).
#![allow(clippy::restriction)]

#[path = "../common/mod.rs"]
mod common;

mod basics;
mod teleop;
mod teleop_mission;
mod teleop_pty;
