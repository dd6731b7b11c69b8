//! The lab's models: actuator lines, lidar lines, measurements, compass calibration, fitting.
// Test code: a panic fails the test (the robot's lints, Cargo.toml).
#![allow(clippy::restriction)]

#[path = "../common/mod.rs"]
mod common;

mod actuator;
mod calibration;
mod fit;
mod lidar_model;
mod measurement;
mod proptest_models;
