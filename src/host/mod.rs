//! Host-side tools (feature `std`; f64 and allocation allowed, nothing here
//! reaches the robot): the logic of the teleop tool (`examples/teleop.rs`),
//! kept here so it is tested without a terminal or a serial port, and the
//! option values the other tools share.

pub mod args;
pub mod teleop;
#[cfg(feature = "web")]
pub mod web;
