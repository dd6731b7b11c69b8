//! Replays a recorded run through the robot's pose estimator.
//!
//! `cargo run --example replay -- LOG.csv [--start X_MM,Y_MM,THETA_DEG]
//! [--arena LENGTH_X_MM,WIDTH_Y_MM] [--svg PATH]`
//!
//! LOG.csv has the header `t_ms,left_cmd,right_cmd,front_mm,right_mm,heading_deg`
//! (see `paperbot::model::estimator::replay`). Writes `t_ms,x_mm,y_mm,theta_deg`
//! to stdout and the path as SVG (default `replay.svg`). The start pose
//! defaults to the arena's centre facing north, the arena to the config's.

use paperbot::math::{Angle, Coord, Length};
use paperbot::model::estimator::replay;
use paperbot::model::measurement::Arena;
use paperbot::model::Pose;
use std::process::ExitCode;

fn numbers(s: &str, n: usize) -> Result<Vec<f64>, String> {
    let v: Vec<f64> =
        s.split(',').map(|f| f.trim().parse::<f64>()).collect::<Result<_, _>>().map_err(|e| e.to_string())?;
    if v.len() != n || v.iter().any(|x| !x.is_finite()) {
        return Err(format!("expected {n} comma-separated numbers, got `{s}`"));
    }
    Ok(v)
}

fn run() -> Result<(), String> {
    let mut args = std::env::args().skip(1);
    let mut log = None;
    let mut arena = Arena::DEFAULT;
    let mut start = None;
    let mut svg = String::from("replay.svg");
    while let Some(a) = args.next() {
        let mut value = |name: &str| args.next().ok_or(format!("{name} needs a value"));
        match a.as_str() {
            "--start" => start = Some(numbers(&value("--start")?, 3)?),
            "--arena" => {
                let v = numbers(&value("--arena")?, 2)?;
                if v.iter().any(|&x| !(1.0..=30_000.0).contains(&x)) {
                    return Err("arena sides must be 1..30000 mm".into());
                }
                arena = Arena { length_x: Length::from_mm_f64(v[0]), width_y: Length::from_mm_f64(v[1]) };
            }
            "--svg" => svg = value("--svg")?,
            "-h" | "--help" => {
                println!("usage: replay LOG.csv [--start X_MM,Y_MM,THETA_DEG] [--arena LX_MM,WY_MM] [--svg PATH]");
                return Ok(());
            }
            _ if log.is_none() && !a.starts_with("--") => log = Some(a),
            _ => return Err(format!("unexpected argument `{a}`")),
        }
    }
    let log = log.ok_or("usage: replay LOG.csv [--start X_MM,Y_MM,THETA_DEG] [--arena LX_MM,WY_MM] [--svg PATH]")?;
    let start = match start {
        Some(v) => Pose::new(Coord::from_mm_f64(v[0]), Coord::from_mm_f64(v[1]), Angle::from_degrees_f64(v[2])),
        None => Pose::new(
            Coord::from_mm_f64(arena.length_x.to_mm_f64() / 2.0),
            Coord::from_mm_f64(arena.width_y.to_mm_f64() / 2.0),
            Angle::ZERO,
        ),
    };
    let text = std::fs::read_to_string(&log).map_err(|e| format!("{log}: {e}"))?;
    let samples = replay::parse(&text).map_err(|e| format!("{log}: {e}"))?;
    let (estimates, stats) = replay::replay(&samples, start, arena);
    print!("{}", replay::to_csv(&estimates));
    std::fs::write(&svg, replay::to_svg(&estimates, arena)).map_err(|e| format!("{svg}: {e}"))?;
    eprintln!("{} rows; {stats:?}; path drawn in {svg}", estimates.len());
    Ok(())
}

fn main() -> ExitCode {
    match run() {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("replay: {e}");
            ExitCode::FAILURE
        }
    }
}
