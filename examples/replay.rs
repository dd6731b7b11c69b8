//! Replays a recorded run through the robot's pose estimator.
//!
//! ```text
//! cargo run --example replay -- LOG.csv [options]
//!   --start X,Y,DEG    start pose, mm, mm, degrees clockwise from north (default: the arena's centre facing north)
//!   --arena LxW        arena size in mm, x (north) by y (east) (default 762.5x495)
//!   --out FILE         SVG output (default replay.svg; written only when the log has rows)
//! ```
//!
//! LOG.csv has the header `t_ms,left_cmd,right_cmd,front_mm,right_mm,heading_deg`
//! (see `paperbot::model::estimator::replay`). Writes `t_ms,x_mm,y_mm,theta_deg`
//! to stdout and the estimated path as SVG. The options take the same syntax
//! as `simulate`'s.

use paperbot::host::args;
use paperbot::math::{Angle, Coord, Length};
use paperbot::model::estimator::replay;
use paperbot::model::measurement::Arena;
use paperbot::model::Pose;
use paperbot::sim::body::PoseF64;
use paperbot::sim::svg::{render, Track};
use std::process::ExitCode;

fn usage() -> String {
    let doc = include_str!("replay.rs");
    doc.lines().skip(3).take(4).map(|l| l.trim_start_matches("//! ")).collect::<Vec<_>>().join("\n")
}

struct Args {
    log: String,
    arena: (f64, f64),
    start: Option<String>,
    out: String,
}

/// `Ok(None)` for `--help`.
fn parse_args() -> Result<Option<Args>, String> {
    let mut it = std::env::args().skip(1);
    let (mut log, mut arena, mut start) = (None, None, None);
    let mut out = String::from("replay.svg");
    while let Some(a) = it.next() {
        let mut value = |name: &str| it.next().ok_or(format!("{name} needs a value"));
        match a.as_str() {
            "--start" => start = Some(value("--start")?),
            "--arena" => arena = Some(args::arena(&value("--arena")?)?),
            "--out" => out = value("--out")?,
            "-h" | "--help" => return Ok(None),
            _ if log.is_none() && !a.starts_with('-') => log = Some(a),
            _ => return Err(format!("unexpected argument `{a}`")),
        }
    }
    let default = Arena::DEFAULT;
    let arena = arena.unwrap_or((default.length_x.to_mm_f64(), default.width_y.to_mm_f64()));
    let log = log.ok_or("no log given")?;
    Ok(Some(Args { log, arena, start, out }))
}

fn run(a: Args) -> Result<(), String> {
    let (lx, wy) = a.arena;
    let (x, y, deg) = match &a.start {
        Some(s) => args::start(s, lx, wy)?,
        None => (lx / 2.0, wy / 2.0, 0.0),
    };
    let start = Pose::new(Coord::from_mm_f64(x), Coord::from_mm_f64(y), Angle::from_degrees_f64(deg));
    let arena = Arena { length_x: Length::from_mm_f64(lx), width_y: Length::from_mm_f64(wy) };
    let text = std::fs::read_to_string(&a.log).map_err(|e| format!("{}: {e}", a.log))?;
    let samples = replay::parse(&text).map_err(|e| format!("{}: {e}", a.log))?;
    if samples.is_empty() {
        return Err(format!("{}: the log has a header but no rows; nothing to replay", a.log));
    }
    let (estimates, stats) = replay::replay(&samples, start, arena);
    print!("{}", replay::to_csv(&estimates));
    let poses: Vec<PoseF64> = estimates
        .iter()
        .map(|e| PoseF64::new(e.pose.x.to_mm_f64(), e.pose.y.to_mm_f64(), e.pose.theta.to_radians_f64()))
        .collect();
    let seconds = f64::from(samples.last().map_or(0, |s| s.t_ms).saturating_sub(samples[0].t_ms)) / 1000.0;
    let title = format!("paperbot replay of {}: {} rows, {seconds:.1} s", a.log, samples.len());
    let track =
        Track { label: "firmware estimate from the recorded readings", color: "#d62728", dashed: false, poses: &poses };
    let svg = render(&paperbot::sim::arena::Arena::new(lx, wy), &[track], &title);
    std::fs::write(&a.out, svg).map_err(|e| format!("{}: {e}", a.out))?;
    let sensor = |name: &str, s: &paperbot::model::estimator::SensorStats| {
        format!("{name} {} accepted, {} outliers, {} unusable", s.accepted, s.outliers, s.unusable)
    };
    eprintln!(
        "replay: {} rows; {}; {}; {}; path drawn in {}",
        estimates.len(),
        sensor("front lidar", &stats.front),
        sensor("right lidar", &stats.right),
        sensor("compass", &stats.compass),
        a.out
    );
    Ok(())
}

fn main() -> ExitCode {
    match parse_args() {
        Ok(None) => {
            println!("{}", usage());
            ExitCode::SUCCESS
        }
        Ok(Some(a)) => match run(a) {
            Ok(()) => ExitCode::SUCCESS,
            Err(e) => {
                eprintln!("replay: {e}");
                ExitCode::FAILURE
            }
        },
        Err(e) => {
            eprintln!("replay: {e}\n{}", usage());
            ExitCode::from(2)
        }
    }
}
