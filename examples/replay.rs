//! Replays a recorded run through the robot's pose estimator.
//!
//! ```text
//! cargo run --example replay -- LOG.csv [options]
//!   --start X,Y,DEG    start pose, mm, mm, degrees clockwise from north (default: found by the robot's
//!                      localization from the first readings, as at power-up)
//!   --arena LxW        arena size in mm, x (north) by y (east) (default 762.5x495)
//!   --out FILE         SVG output (default replay.svg; written only when the log has rows)
//! ```
//!
//! LOG.csv has the header `t_ms,left_cmd,right_cmd,front_mm,right_mm,heading_deg`
//! (see `paperbot::model::estimator::replay`). Writes `t_ms,x_mm,y_mm,theta_deg`
//! to stdout and the estimated path as SVG, with each lidar reading drawn
//! from the lidar to where its beam ended (the model's distance along the
//! beam from the estimated pose): blue the front lidar, green the right; the
//! path is coloured by the hypothesis the estimator reported (a legend row
//! per id: an id is given when a hypothesis is seeded or spawned) and dashed
//! where it was not located (ambiguous or unknown). The
//! options take the same syntax as `simulate`'s. Its closing lines say how
//! the estimate agrees with the readings (`paperbot::host::replay_stats`):
//! each lidar's share of readings accepted and mean normalised innovation,
//! and `LOST` when the estimator refused most of them or they disagree with
//! it far beyond their noise.
// Host tool: a panic fails a command on the laptop, never the robot
// (the robot's lints, Cargo.toml).
#![allow(clippy::restriction)]

use paperbot::host::{args, replay_stats};
use paperbot::math::{Angle, Coord};
use paperbot::model::estimator::replay;
use paperbot::model::estimator::Tracking;
use paperbot::model::measurement::Arena;
use paperbot::model::Pose;
use paperbot::sim::body::PoseF64;
use paperbot::sim::svg::{render_with_stretches, Ray, Stretch, Track};
use std::process::ExitCode;

fn usage() -> String {
    let doc = include_str!("replay.rs");
    doc.lines().skip(3).take(5).map(|l| l.trim_start_matches("//! ")).collect::<Vec<_>>().join("\n")
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
    let arena = arena.unwrap_or((default.length_x_mm(), default.width_y_mm()));
    let log = log.ok_or("no log given")?;
    Ok(Some(Args { log, arena, start, out }))
}

fn run(a: Args) -> Result<(), String> {
    let (lx, wy) = a.arena;
    let arena = Arena::from_mm_f64(lx, wy);
    // a typed start is checked before the log is read
    let typed = a.start.as_deref().map(|s| args::start(s, lx, wy)).transpose()?;
    let text = std::fs::read_to_string(&a.log).map_err(|e| format!("{}: {e}", a.log))?;
    let samples = replay::parse(&text).map_err(|e| format!("{}: {e}", a.log))?;
    if samples.is_empty() {
        return Err(format!("{}: the log has a header but no rows; nothing to replay", a.log));
    }
    let start = match typed {
        Some((x, y, deg)) => {
            replay::Start::Pose(Pose::new(Coord::from_mm_f64(x), Coord::from_mm_f64(y), Angle::from_degrees_f64(deg)))
        }
        None => {
            let fix = replay::locate_start(&samples, arena)
                .map_err(|e| format!("{}: no start found by localization ({e:?}); give --start", a.log))?;
            let p = PoseF64::from_pose(&fix.pose);
            eprintln!(
                "replay: located at x {:.0} y {:.0} mm, heading {:.1} deg (sigma {:.0} / {:.0} mm, {} points{})",
                p.x,
                p.y,
                p.theta.to_degrees(),
                fix.sigma_x.to_mm_f64(),
                fix.sigma_y.to_mm_f64(),
                fix.points,
                match (fix.ambiguous, fix.clusters().len()) {
                    (false, _) => String::new(),
                    (true, 1) => ", AMBIGUOUS: the readings fit a stretch of the box".into(),
                    (true, n) => format!(", AMBIGUOUS: the readings fit {n} places far apart; the heaviest taken"),
                }
            );
            replay::Start::Fix(fix)
        }
    };
    let (estimates, stats) = replay::replay(&samples, start, arena);
    print!("{}", replay::to_csv(&estimates));
    let poses: Vec<PoseF64> = estimates
        .iter()
        .map(|e| PoseF64::new(e.pose.x.to_mm_f64(), e.pose.y.to_mm_f64(), e.pose.theta.to_radians_f64()))
        .collect();
    let seconds = f64::from(samples.last().map_or(0, |s| s.t_ms).saturating_sub(samples[0].t_ms)) / 1000.0;
    // the log by its file name: the picture does not carry the path it was made on
    let name = std::path::Path::new(&a.log).file_name().map_or(a.log.clone(), |n| n.to_string_lossy().into_owned());
    let title = format!("paperbot replay of {name}: {} rows, {seconds:.1} s", samples.len());
    let track =
        Track { label: "firmware estimate from the recorded readings", color: "#444444", dashed: false, poses: &poses };
    let rays = lidar_rays(&samples, &estimates);
    let stretches = reported_stretches(&estimates, &poses);
    let svg = render_with_stretches(&arena, &[track], &stretches, &rays, &title);
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
    let agreement = replay_stats::agreement(&samples, &estimates, &stats, &arena);
    let lidar = |name: &str, l: &replay_stats::LidarAgreement| {
        let share = if l.readings == 0 { 100.0 } else { 100.0 * f64::from(l.accepted) / f64::from(l.readings) };
        format!(
            "{name} {:.0} % of {} usable readings accepted, mean normalised innovation {:.1} (over {})",
            share, l.readings, l.mean_normalised, l.innovations
        )
    };
    eprintln!("replay: {}; {}", lidar("front lidar", &agreement.front), lidar("right lidar", &agreement.right));
    if agreement.lost() {
        eprintln!(
            "replay: LOST: the estimate refused {:.0} % of its usable lidar readings, which disagree with it by {:.1} \
             sigmas on average: it does not know where it is",
            100.0 * (1.0 - agreement.accepted_share()),
            agreement.mean_normalised()
        );
    }
    Ok(())
}

/// Each row's lidar readings as rays from the lidar (at the row's estimate)
/// to where the beam ended: the model's distance from the reference point
/// along the beam, plus the mount's setback.
fn lidar_rays<'a>(samples: &[replay::Sample], estimates: &[replay::Estimate]) -> Vec<Ray<'a>> {
    use paperbot::config::{geometry, lidar};
    let mut rays = Vec::new();
    for (s, e) in samples.iter().zip(estimates) {
        let pose = PoseF64::from_pose(&e.pose);
        for (reading, mount, model, color) in [
            (s.front_mm, geometry::FRONT_LIDAR, lidar::FRONT, "#1f77b4"),
            (s.right_mm, geometry::RIGHT_LIDAR, lidar::RIGHT, "#2ca02c"),
        ] {
            let Some(d) = reading.and_then(|r| model.range(r).distance()) else { continue };
            rays.push(Ray::of_reading(&pose, &mount, d.to_mm_f64(), color));
        }
    }
    rays
}

/// Colours of the reported hypotheses, by id (not the lidars' blue and green).
const HYPOTHESIS_COLORS: [&str; 6] = ["#d62728", "#9467bd", "#ff7f0e", "#17becf", "#8c564b", "#e377c2"];

/// The estimated path in stretches by the hypothesis reported (a colour
/// and a legend row per id), then the stretches not located (ambiguous or
/// unknown) drawn dashed over them. Each stretch ends on the next one's
/// first pose, so the path is unbroken.
fn reported_stretches<'a>(estimates: &[replay::Estimate], poses: &'a [PoseF64]) -> Vec<Stretch<'a>> {
    let runs = |key: &dyn Fn(&replay::Estimate) -> Option<String>,
                color: &dyn Fn(&replay::Estimate) -> &'static str| {
        let mut out = Vec::new();
        let mut start = 0;
        for i in 1..=estimates.len() {
            if i < estimates.len() && key(&estimates[i]) == key(&estimates[start]) {
                continue;
            }
            let e = &estimates[start];
            if let Some(label) = key(e) {
                let end = (i + 1).min(poses.len());
                out.push(Stretch { label, color: color(e), dashed: false, poses: &poses[start..end] });
            }
            start = i;
        }
        out
    };
    let by_id = |e: &replay::Estimate| Some(format!("reported: hypothesis {}", e.hypothesis));
    let id_color = |e: &replay::Estimate| HYPOTHESIS_COLORS[usize::from(e.hypothesis) % HYPOTHESIS_COLORS.len()];
    let unlocated = |e: &replay::Estimate| {
        (e.tracking != Tracking::Located).then(|| "dashed: not located (ambiguous or unknown)".to_string())
    };
    let mut stretches = runs(&by_id, &id_color);
    stretches.extend(runs(&unlocated, &|_| "black").into_iter().map(|s| Stretch { dashed: true, ..s }));
    stretches
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
