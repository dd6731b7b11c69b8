//! The live page (`teleop --web`): its model, its server over real sockets, and the page in headless Chromium.
// Test code: a panic fails the test (the robot's lints, Cargo.toml).
#![allow(clippy::restriction)]

#[path = "../common/mod.rs"]
mod common;

mod basics;
mod browser;
mod model;
