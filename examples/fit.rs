//! Fits the lab's measurements and prints constants ready to paste into
//! `config::actuators` or `config::lidar` (`src/config/`).
//!
//! ```text
//! cargo run --example fit -- tests/data/lab1/servo_runs.csv
//! cargo run --example fit -- tests/data/lab1/lidar_front.csv
//! ```
//! The format is recognised by the CSV header (see tests/data/lab1/README.md).
//! Servo runs give the eight actuator lines (speed per command pair from the
//! mean time, one line per wheel); a lidar file gives its line the report's
//! way: reading on true distance over every reading, inverted
//! (`paperbot::model::fit::fit_lidar` says why). A value that is not a finite
//! number, a time that is not positive or a motion with fewer than two
//! distinct commands is an error: nothing is printed and the exit code is 1.
// Host tool: a panic fails a command on the laptop, never the robot
// (the robot's lints, Cargo.toml).
#![allow(clippy::restriction)]

use paperbot::model::fit::config_constants;
use std::process::ExitCode;

const USAGE: &str =
    "usage: fit <csv>\n  servo_runs.csv, lidar_front.csv or lidar_right.csv (tests/data/lab1/README.md)";

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.iter().any(|a| a == "-h" || a == "--help") {
        println!("{USAGE}");
        return ExitCode::SUCCESS;
    }
    let [path] = args.as_slice() else {
        eprintln!("{USAGE}");
        return ExitCode::from(2);
    };
    if path.starts_with('-') {
        eprintln!("fit: unknown option {path}\n{USAGE}");
        return ExitCode::from(2);
    }
    let text = match std::fs::read_to_string(path) {
        Ok(t) => t,
        Err(e) => {
            eprintln!("fit: {path}: {e}");
            return ExitCode::from(1);
        }
    };
    match config_constants(&text, path) {
        Ok(s) => {
            print!("{s}");
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("fit: {path}: {e}");
            ExitCode::from(1)
        }
    }
}
