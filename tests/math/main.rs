//! Fixed-point arithmetic: the types, sin/cos/atan2, the state update against f64.
// Test code: a panic fails the test (the robot's lints, Cargo.toml).
#![allow(clippy::restriction)]

#[path = "../common/mod.rs"]
mod common;

mod basics;
mod proptest_angle;
mod proptest_division;
mod state;
mod trig;
