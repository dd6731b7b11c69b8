//! Fits the lab's measurements and prints constants ready to paste into
//! `src/config.rs`.
//!
//! ```text
//! cargo run --example fit -- tests/data/lab1/servo_runs.csv
//! cargo run --example fit -- tests/data/lab1/lidar_front.csv [--all-readings]
//! ```
//! The format is recognised by the CSV header (see tests/data/lab1/README.md).

use paperbot::model::fit::config_constants;
use std::process::ExitCode;

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let Some(path) = args.iter().find(|a| !a.starts_with("--")) else {
        eprintln!("usage: fit <csv> [--all-readings]\n  servo_runs.csv, lidar_front.csv, lidar_right.csv");
        return ExitCode::from(2);
    };
    let all = args.iter().any(|a| a == "--all-readings");
    let text = match std::fs::read_to_string(path) {
        Ok(t) => t,
        Err(e) => {
            eprintln!("fit: {path}: {e}");
            return ExitCode::from(1);
        }
    };
    match config_constants(&text, path, all) {
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
