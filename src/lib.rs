//! Firmware for the ESP8266 paperbot: a paper-chassis robot with two FS90R
//! continuous servos, two VL53L0X lidars and an MPU9250 magnetometer.
//!
//! # Layers
//! Dependencies point one way, each layer using only those before it:
//!
//! math -> model -> driver -> control -> board / sim / host / bin
//!
//! - [`math`]: fixed-point types and arithmetic, no knowledge of robots;
//! - [`model`]: the lab report's models, the state update, the estimator,
//!   the compass calibration;
//! - [`driver`]: the chips through embedded-hal traits (it defines what it
//!   needs from a board, e.g. `driver::servo::PulseOutput`);
//! - [`control`]: the tick and the serial protocol;
//! - the edges, which never use each other: `board` (ESP8266), `sim`
//!   (host simulator), `host` (host tools), and the firmware binary.
//!
//! [`config`] holds every tuned number: any layer may use it, and it only
//! instantiates `math` and `model` types. `tests/layers.rs` checks every
//! `crate::` path in `src/` against this rule.
//!
//! Frame: x to north, y to east, heading clockwise from north, lengths in mm.
#![no_std]
// Nothing on the robot's path may panic (issue 8): the lints that catch a
// panic path are errors (Cargo.toml's `[lints.clippy]`; `cargo clippy
// --all-targets -- -D warnings` in CI). Test code allows them (a panic fails
// a test), and so do the host-only modules (`sim`, `host`, `std` helpers) at
// module level; the fixed-point kernels (`math`, `model`) allow
// `arithmetic_side_effects` at module level because every operation there
// carries a bound proof in a comment and runs under overflow checks in the
// property, soak and lx106 bit-exact tests; everywhere else arithmetic is
// checked, saturating or wrapping, or locally allowed with its bound.

#[cfg(feature = "std")]
extern crate std;

pub mod board;
pub mod config;
pub mod control;
pub mod driver;
// Host-only tools (std): a panic there fails a host command, not the robot.
#[cfg(feature = "std")]
#[allow(clippy::arithmetic_side_effects, clippy::indexing_slicing, clippy::unwrap_used, clippy::expect_used)]
pub mod host;
// Fixed-point kernels: every operation's bound is proven in a comment and
// runs under overflow checks in the proptest, soak and lx106 tests.
#[allow(clippy::arithmetic_side_effects)]
pub mod math;
#[allow(clippy::arithmetic_side_effects)]
pub mod model;
// The simulator (host only, std, f64): test scaffolding, not robot code.
#[cfg(feature = "sim")]
#[allow(clippy::arithmetic_side_effects, clippy::indexing_slicing, clippy::unwrap_used, clippy::expect_used)]
pub mod sim;
