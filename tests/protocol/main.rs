//! The serial protocol: lines, parsing, telemetry, its documentation's examples.
// Test code: a panic fails the test (the robot's lints, Cargo.toml).
#![allow(clippy::restriction)]

#[path = "../common/mod.rs"]
mod common;

mod docs;
mod line;
mod parse;
mod proptest_protocol;
mod telemetry;
