//! Firmware for the ESP8266 paperbot: a paper-chassis robot with two FS90R
//! continuous servos, two VL53L0X lidars and an MPU9250 magnetometer.
//!
//! Layers, each depending only on the ones above it:
//! [`config`] (every tuned number), [`math`] (fixed-point types),
//! [`model`] (the lab report's models and the state update), `driver` (the
//! chips through embedded-hal), `control` (the tick and the serial
//! protocol), and the edges: `board` (ESP8266) and `sim` (host).
//!
//! Frame: x to north, y to east, heading clockwise from north, lengths in mm.
#![no_std]

#[cfg(feature = "std")]
extern crate std;

pub mod config;
pub mod control;
pub mod driver;
#[cfg(feature = "std")]
pub mod host;
pub mod math;
pub mod model;
#[cfg(feature = "sim")]
pub mod sim;
pub mod board;
