//! Host-side tools (feature `std`; f64 and allocation allowed, nothing here
//! reaches the robot): the logic of the teleop tool (`examples/teleop.rs`),
//! kept here so it is tested without a terminal or a serial port, the
//! option values the other tools share, and what `replay` says about how a
//! replayed estimate agrees with its readings.

pub mod args;
pub mod replay_stats;
pub mod teleop;
#[cfg(feature = "web")]
pub mod web;
