//! The estimator against an f64 truth simulation and the real drive.
// Test code: a panic fails the test (the robot's lints, Cargo.toml).
#![allow(clippy::restriction)]

#[path = "../common/mod.rs"]
mod common;

mod basics;
mod lab2_drive;
mod longrun;
mod no_teleport;
mod reacquire;
mod replay;
