//! The estimator against an f64 truth simulation and the real drive.
// Test code: a panic fails the test (the robot's lints, Cargo.toml).
#![allow(clippy::restriction)]

#[path = "../common/mod.rs"]
mod common;

mod basics;
mod invariants;
mod lab2_drive;
mod longrun;
mod reference;
mod replay;
mod tracker;
