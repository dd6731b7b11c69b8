//! Least-squares line fitting and readers for the lab's CSV formats
//! (host only, feature `std`; floats are fine here: nothing in this module
//! runs on the robot). `tests/data/lab1/README.md` describes the formats.

use std::string::{String, ToString};
use std::vec::Vec;

/// `y = slope x + intercept` fitted by ordinary least squares.
#[derive(Clone, Copy, PartialEq, Debug)]
pub struct LineFit {
    pub slope: f64,
    pub intercept: f64,
    /// Number of points.
    pub n: usize,
    /// Coefficient of determination.
    pub r2: f64,
}

/// Ordinary least squares of y on x. `None` with fewer than two distinct x.
pub fn fit_line<I: IntoIterator<Item = (f64, f64)>>(points: I) -> Option<LineFit> {
    let pts: Vec<(f64, f64)> = points.into_iter().collect();
    let n = pts.len();
    if n < 2 {
        return None;
    }
    let nf = n as f64;
    let mx = pts.iter().map(|p| p.0).sum::<f64>() / nf;
    let my = pts.iter().map(|p| p.1).sum::<f64>() / nf;
    let sxx: f64 = pts.iter().map(|p| (p.0 - mx) * (p.0 - mx)).sum();
    let sxy: f64 = pts.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    let syy: f64 = pts.iter().map(|p| (p.1 - my) * (p.1 - my)).sum();
    if sxx <= 0.0 {
        return None;
    }
    let slope = sxy / sxx;
    let intercept = my - slope * mx;
    let r2 = if syy > 0.0 { (sxy * sxy) / (sxx * syy) } else { 1.0 };
    Some(LineFit { slope, intercept, n, r2 })
}

/// A CSV problem, with its 1-based line number.
#[derive(Clone, PartialEq, Debug)]
pub struct CsvError {
    pub line: usize,
    pub message: String,
}

impl core::fmt::Display for CsvError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(f, "line {}: {}", self.line, self.message)
    }
}

/// Rows of a CSV with the given header (exact column names, in order).
fn rows<'a>(text: &'a str, header: &[&str]) -> Result<Vec<(usize, Vec<&'a str>)>, CsvError> {
    let mut lines = text.lines().enumerate().filter(|(_, l)| !l.trim().is_empty());
    let (_, head) = lines.next().ok_or(CsvError { line: 1, message: "empty file".to_string() })?;
    let cols: Vec<&str> = head.split(',').map(str::trim).collect();
    if cols != header {
        return Err(CsvError {
            line: 1,
            message: std::format!("expected header {:?}, found {:?}", header.join(","), head),
        });
    }
    lines
        .map(|(i, l)| {
            let f: Vec<&str> = l.split(',').map(str::trim).collect();
            if f.len() != header.len() {
                Err(CsvError {
                    line: i + 1,
                    message: std::format!("expected {} fields, found {}", header.len(), f.len()),
                })
            } else {
                Ok((i + 1, f))
            }
        })
        .collect()
}

/// A finite number (`nan` and `inf` parse as f64 but are no measurement).
fn num(line: usize, s: &str) -> Result<f64, CsvError> {
    match s.parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(v),
        _ => Err(CsvError { line, message: std::format!("not a finite number: {s:?}") }),
    }
}

/// Header of `servo_runs.csv`.
pub const SERVO_RUNS_HEADER: [&str; 6] = ["motion", "left_cmd", "right_cmd", "trial", "seconds", "what_was_timed"];
/// Header of `lidar_front.csv` / `lidar_right.csv`.
pub const LIDAR_HEADER: [&str; 2] = ["actual_mm", "reading_mm"];
/// Header of `magnetometer_heading.csv`.
pub const MAGNETOMETER_HEADER: [&str; 2] = ["compass_deg", "reading_deg"];

/// One timed trial of `servo_runs.csv`.
#[derive(Clone, PartialEq, Debug)]
pub struct ServoRun {
    pub motion: String,
    pub left_cmd: f64,
    pub right_cmd: f64,
    pub seconds: f64,
}

pub fn parse_servo_runs(text: &str) -> Result<Vec<ServoRun>, CsvError> {
    rows(text, &SERVO_RUNS_HEADER)?
        .into_iter()
        .map(|(line, f)| {
            let motion = f[0].to_string();
            if !["forward", "backward", "cw", "ccw"].contains(&motion.as_str()) {
                return Err(CsvError { line, message: std::format!("unknown motion {motion:?}") });
            }
            let cmd = |s: &str| match num(line, s)? {
                c if (0.0..=180.0).contains(&c) => Ok(c),
                c => Err(CsvError { line, message: std::format!("servo command {c} outside 0..180") }),
            };
            let seconds = num(line, f[4])?;
            if seconds <= 0.0 {
                return Err(CsvError { line, message: std::format!("time {seconds} s is not positive") });
            }
            Ok(ServoRun { motion, left_cmd: cmd(f[1])?, right_cmd: cmd(f[2])?, seconds })
        })
        .collect()
}

/// Straight runs timed over this distance, m (`servo_runs.csv`).
pub const STRAIGHT_DISTANCE_M: f64 = 0.45;
/// Turn runs timed over this many full turns (`servo_runs.csv`).
pub const TURNS_TIMED: f64 = 5.0;

/// The lines of one motion, fitted the way the lab README describes: speed
/// per command pair from the mean time, wheel speed = car speed / r for
/// straight motions, the car's turn rate for turns; one line per wheel of
/// speed against that wheel's command.
#[derive(Clone, Copy, PartialEq, Debug)]
pub struct MotionFit {
    pub left: LineFit,
    pub right: LineFit,
    pub left_range: (f64, f64),
    pub right_range: (f64, f64),
}

pub fn fit_motion(runs: &[ServoRun], motion: &str, wheel_radius_m: f64) -> Option<MotionFit> {
    let mut pairs: Vec<(f64, f64, Vec<f64>)> = Vec::new();
    for r in runs.iter().filter(|r| r.motion == motion) {
        match pairs.iter_mut().find(|p| p.0 == r.left_cmd && p.1 == r.right_cmd) {
            Some(p) => p.2.push(r.seconds),
            None => pairs.push((r.left_cmd, r.right_cmd, std::vec![r.seconds])),
        }
    }
    let straight = motion == "forward" || motion == "backward";
    let speeds: Vec<(f64, f64, f64)> = pairs
        .iter()
        .map(|(l, r, t)| {
            let mean = t.iter().sum::<f64>() / t.len() as f64;
            let y = if straight {
                STRAIGHT_DISTANCE_M / mean / wheel_radius_m
            } else {
                TURNS_TIMED * core::f64::consts::TAU / mean
            };
            (*l, *r, y)
        })
        .collect();
    let range = |v: Vec<f64>| {
        (v.iter().cloned().fold(f64::INFINITY, f64::min), v.iter().cloned().fold(f64::NEG_INFINITY, f64::max))
    };
    Some(MotionFit {
        left: fit_line(speeds.iter().map(|s| (s.0, s.2)))?,
        right: fit_line(speeds.iter().map(|s| (s.1, s.2)))?,
        left_range: range(speeds.iter().map(|s| s.0).collect()),
        right_range: range(speeds.iter().map(|s| s.1).collect()),
    })
}

/// `(actual_mm, reading_mm)` rows of a lidar CSV.
pub fn parse_lidar(text: &str) -> Result<Vec<(f64, f64)>, CsvError> {
    rows(text, &LIDAR_HEADER)?.into_iter().map(|(line, f)| Ok((num(line, f[0])?, num(line, f[1])?))).collect()
}

/// The lidar model the firmware uses, distance on reading, fitted the
/// report's way (3.3): the reading on the true distance by least squares
/// over every reading (the distance is set exactly, the noise is in the
/// reading), then the line inverted. Fitting distance on reading directly
/// would put the reading's noise on the regressor and flatten the slope
/// (regression dilution: 0.9836 instead of 0.9849 on `lidar_front.csv`).
/// `None` with fewer than two distinct distances.
pub fn fit_lidar(rows: &[(f64, f64)]) -> Option<LineFit> {
    let reading_on_distance = fit_line(rows.iter().copied())?;
    if reading_on_distance.slope == 0.0 {
        return None;
    }
    let slope = 1.0 / reading_on_distance.slope;
    Some(LineFit { slope, intercept: -reading_on_distance.intercept * slope, ..reading_on_distance })
}

/// `(compass_deg, reading_deg)` rows of `magnetometer_heading.csv`.
pub fn parse_magnetometer(text: &str) -> Result<Vec<(f64, f64)>, CsvError> {
    rows(text, &MAGNETOMETER_HEADER)?.into_iter().map(|(line, f)| Ok((num(line, f[0])?, num(line, f[1])?))).collect()
}

/// Signed difference `a - b` of two headings in degrees, in (-180, 180].
pub fn heading_error_deg(a: f64, b: f64) -> f64 {
    let d = (a - b).rem_euclid(360.0);
    if d > 180.0 {
        d - 360.0
    } else {
        d
    }
}

/// Fits a lab CSV (recognised by its header) and renders the result as
/// constants ready to paste into `config::actuators` or `config::lidar`.
/// `path` names the lidar (front/right).
pub fn config_constants(text: &str, path: &str) -> Result<String, String> {
    let header = text.lines().next().unwrap_or("").trim();
    if header == SERVO_RUNS_HEADER.join(",") {
        servo_constants(text)
    } else if header == LIDAR_HEADER.join(",") {
        lidar_constants(text, path)
    } else {
        Err(std::format!("unrecognised header {header:?} (servo_runs or lidar CSV expected)"))
    }
}

fn servo_constants(text: &str) -> Result<String, String> {
    let runs = parse_servo_runs(text).map_err(|e| e.to_string())?;
    if runs.is_empty() {
        return Err("no trials to fit".to_string());
    }
    let r = crate::config::geometry::WHEEL_RADIUS.to_mm_f64() / 1000.0;
    let mut s = std::format!("// actuator lines fitted from {} trials (wheel radius {r} m)\n", runs.len());
    for (motion, name) in [("forward", "FORWARD"), ("backward", "BACKWARD"), ("cw", "CW"), ("ccw", "CCW")] {
        if !runs.iter().any(|run| run.motion == motion) {
            s += &std::format!("// {motion}: no trials in this file\n");
            continue;
        }
        let f = fit_motion(&runs, motion, r)
            .ok_or(std::format!("{motion}: fewer than two distinct commands per wheel, no line to fit"))?;
        let wheel = |l: &LineFit, (lo, hi): (f64, f64)| {
            std::format!("WheelLine::new({:.4}, {:.4}, {}, {})", l.slope, l.intercept, lo as u8, hi as u8)
        };
        s += &std::format!(
            "// {motion}: R^2 left {:.3}, right {:.3}\npub const {name}: MotionLines =\n    MotionLines {{ left: {}, right: {} }};\n",
            f.left.r2,
            f.right.r2,
            wheel(&f.left, f.left_range),
            wheel(&f.right, f.right_range)
        );
    }
    Ok(s)
}

fn lidar_constants(text: &str, path: &str) -> Result<String, String> {
    let rows = parse_lidar(text).map_err(|e| e.to_string())?;
    let f = fit_lidar(&rows).ok_or("fewer than two distinct distances, no line to fit")?;
    let name = if path.contains("right") { "RIGHT" } else { "FRONT" };
    Ok(std::format!(
        "// distance = {:.4} * reading {:+.4} mm, {} readings (reading on distance, inverted), R^2 {:.5}\n\
         pub const {name}: LidarModel = LidarModel::new({:.4}, {:.4}, MIN_DISTANCE_MM, MAX_READING_MM);\n",
        f.slope,
        f.intercept,
        rows.len(),
        f.r2,
        f.slope,
        f.intercept
    ))
}
