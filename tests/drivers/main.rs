//! The drivers against mocked and simulated buses: servos, lidars, compass, the shared bus, bit-banged I2C, faults.
// Test code: a panic fails the test (the robot's lints, Cargo.toml).
#![allow(clippy::restriction)]

#[path = "../common/mod.rs"]
mod common;

mod bitbang_i2c;
mod bringup;
mod bus;
mod compass;
mod faults;
mod lidar;
mod servo;
mod wire;
