//! Every number a user tunes, in one place, each with its unit and source:
//! one file per topic, each a module under `config::` (`config::timing::
//! DEADMAN_MS` is in `src/config/timing.rs`).
//!
//! Sources, all in the repository: "report" is the lab report
//! (`docs/lab1-report.txt`), "data" the lab's measurements
//! (`tests/data/lab1/`, `tests/data/lab2/`), "fact sheet" the project's
//! facts about the robot (`docs/paperbot.md`), datasheets and specs by
//! name and section. Values are written in the units people use (mm,
//! degrees, rad/s) and converted to the fixed-point types by `const fn`s at
//! compile time: no float code reaches the robot. To refit from new
//! measurements: `cargo run --example fit -- <csv>` prints constants ready
//! to paste into [`actuators`] or [`lidar`].

use crate::math::{Angle, Length};

// the robot
pub mod arena;
pub mod geometry;
pub mod pins;

// the chips and the bus
pub mod actuators;
pub mod board;
pub mod compass;
pub mod i2c;
pub mod lidar;
pub mod servo;

// the control loop and the protocol
pub mod goto;
pub mod locate;
pub mod log;
pub mod mission;
pub mod serial;
pub mod settings;
pub mod timing;

// the estimator
pub mod estimator;
pub mod refine;

// host only: replay's verdict on a drive
pub mod replay;

// host only: the simulator and the teleop tool
pub mod sim;
pub mod teleop;
