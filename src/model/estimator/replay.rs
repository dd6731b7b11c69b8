//! Host side of `cargo run --example replay`: reads a recorded run, runs the
//! same [`Estimator`] the robot runs, and writes the path as CSV (the tool
//! draws it with `sim::svg`).
//!
//! Log format (CSV with a header line):
//! `t_ms,left_cmd,right_cmd,front_mm,right_mm,heading_deg` - time in ms
//! (non-decreasing), the two servo commands (0..180, decimals allowed), the
//! raw lidar readings in mm and the calibrated compass heading in degrees;
//! an empty field means no reading at that row.
//!
//! Replay order, the control loop's: for each row, the motion of the
//! previous row's commands (by `config::actuators::MODEL`) is predicted over
//! the time since that row, in steps of one loop period; then the row's
//! readings correct the estimate (lidar readings go through the lidar models
//! first; "no target" and "too close" are skipped); then the row's commands
//! become the current ones. One output row per input row, the estimate
//! after that row's readings.

use std::fmt::Write as _;
use std::string::String;
use std::vec::Vec;

use super::{Estimator, EstimatorStats, Tracking};
use crate::config;
use crate::math::{Angle, Dt};
use crate::model::actuator::{Motion, ServoCmd};
use crate::model::lidar::Range;
use crate::model::locate::{locate, Fix, LocateError, Readings};
use crate::model::measurement::{Arena, LidarId};
use crate::model::state::Pose;

/// The header a log must start with.
pub const HEADER: &str = "t_ms,left_cmd,right_cmd,front_mm,right_mm,heading_deg";
/// The header of the output.
pub const OUTPUT_HEADER: &str = "t_ms,x_mm,y_mm,theta_deg";

/// One row of a log.
#[derive(Clone, Copy, PartialEq, Debug)]
pub struct Sample {
    pub t_ms: u32,
    pub left: ServoCmd,
    pub right: ServoCmd,
    pub front_mm: Option<u16>,
    pub right_mm: Option<u16>,
    pub heading: Option<Angle>,
}

/// What is wrong with a log (line numbers from 1, the header is line 1).
#[derive(Clone, PartialEq, Eq, Debug)]
pub enum ReplayError {
    /// The first line is not [`HEADER`].
    Header,
    /// A row does not have six fields.
    Fields { line: usize },
    /// A field does not parse (or is out of range).
    Field { line: usize, column: &'static str },
    /// Time went backwards.
    TimeBackwards { line: usize },
}

impl core::fmt::Display for ReplayError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            ReplayError::Header => write!(f, "line 1: expected the header `{HEADER}`"),
            ReplayError::Fields { line } => write!(f, "line {line}: expected 6 comma-separated fields"),
            ReplayError::Field { line, column } => write!(f, "line {line}: bad {column}"),
            ReplayError::TimeBackwards { line } => write!(f, "line {line}: t_ms went backwards"),
        }
    }
}

impl std::error::Error for ReplayError {}

const COLUMNS: [&str; 6] = ["t_ms", "left_cmd", "right_cmd", "front_mm", "right_mm", "heading_deg"];

/// Parses a log.
pub fn parse(text: &str) -> Result<Vec<Sample>, ReplayError> {
    let mut lines = text.lines().enumerate();
    match lines.next() {
        Some((_, h)) if h.trim() == HEADER => {}
        _ => return Err(ReplayError::Header),
    }
    let mut out = Vec::new();
    let mut last_t = 0u32;
    for (i, line) in lines {
        let line_no = i + 1;
        if line.trim().is_empty() {
            continue;
        }
        let f: Vec<&str> = line.split(',').map(str::trim).collect();
        if f.len() != 6 {
            return Err(ReplayError::Fields { line: line_no });
        }
        let bad = |c: usize| ReplayError::Field { line: line_no, column: COLUMNS[c] };
        let t_ms: u32 = f[0].parse().map_err(|_| bad(0))?;
        let cmd = |c: usize| -> Result<ServoCmd, ReplayError> {
            let v: f64 = f[c].parse().map_err(|_| bad(c))?;
            if (0.0..=180.0).contains(&v) {
                Ok(ServoCmd::from_f64(v))
            } else {
                Err(bad(c))
            }
        };
        let reading = |c: usize| -> Result<Option<u16>, ReplayError> {
            if f[c].is_empty() {
                return Ok(None);
            }
            f[c].parse().map(Some).map_err(|_| bad(c))
        };
        let heading = if f[5].is_empty() {
            None
        } else {
            let v: f64 = f[5].parse().map_err(|_| bad(5))?;
            if !v.is_finite() {
                return Err(bad(5));
            }
            Some(Angle::from_degrees_f64(v))
        };
        if t_ms < last_t {
            return Err(ReplayError::TimeBackwards { line: line_no });
        }
        last_t = t_ms;
        out.push(Sample { t_ms, left: cmd(1)?, right: cmd(2)?, front_mm: reading(3)?, right_mm: reading(4)?, heading });
    }
    Ok(out)
}

/// Where a replay starts.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum Start {
    /// A typed pose (`--start`), with the config's initial uncertainty.
    Pose(Pose),
    /// A localization's fix and its uncertainty ([`locate_start`]).
    Fix(Fix),
}

/// The estimate after one row.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub struct Estimate {
    pub t_ms: u32,
    pub pose: Pose,
    /// The id of the hypothesis the reported pose followed
    /// ([`Estimator::best_id`]).
    pub hypothesis: u8,
    pub tracking: Tracking,
}

/// Where the log starts, by the robot's own localization
/// ([`crate::model::locate`]) from the first row with a compass heading and
/// the lidar readings up to it (the newest of each).
pub fn locate_start(samples: &[Sample], arena: Arena) -> Result<Fix, LocateError> {
    let (mut front, mut right) = (None, None);
    for s in samples {
        let distance = |r: Option<u16>, m: &crate::model::LidarModel| r.and_then(|r| m.range(r).distance());
        front = distance(s.front_mm, &config::lidar::FRONT).or(front);
        right = distance(s.right_mm, &config::lidar::RIGHT).or(right);
        if let Some(heading) = s.heading {
            if front.is_some() || right.is_some() {
                return locate(&arena, &[Readings { heading, front, right }]);
            }
        }
    }
    Err(LocateError::NoReading)
}

/// Runs the estimator over a log from `start` (a typed pose, with the
/// config's initial uncertainty, or a localization's fix). Returns one
/// estimate per row and the estimator's counts.
pub fn replay(samples: &[Sample], start: Start, arena: Arena) -> (Vec<Estimate>, EstimatorStats) {
    let mut est = match start {
        Start::Pose(p) => Estimator::with_arena(p, arena),
        Start::Fix(f) => {
            let mut e = Estimator::with_arena(f.pose, arena);
            e.start_at(&f);
            e
        }
    };
    let tick_us = 1_000_000 / config::timing::LOOP_HZ;
    let mut motion = Motion::Stop;
    let mut last_t: Option<u32> = None;
    let mut out = Vec::with_capacity(samples.len());
    for s in samples {
        if let Some(t0) = last_t {
            let mut us = u64::from(s.t_ms.saturating_sub(t0)) * 1000;
            while us > 0 {
                let chunk = us.min(u64::from(tick_us));
                est.predict(motion, Dt::from_micros_saturating(chunk as u32));
                us -= chunk;
            }
        }
        last_t = Some(s.t_ms);
        for (which, reading, model) in
            [(LidarId::Front, s.front_mm, &config::lidar::FRONT), (LidarId::Right, s.right_mm, &config::lidar::RIGHT)]
        {
            if let Some(Range::Target(d)) = reading.map(|r| model.range(r)) {
                est.update_lidar(which, d);
            }
        }
        if let Some(h) = s.heading {
            est.update_heading(h);
        }
        motion = config::actuators::MODEL.motion_from_commands(s.left, s.right);
        out.push(Estimate { t_ms: s.t_ms, pose: est.pose(), hypothesis: est.best_id(), tracking: est.tracking() });
    }
    (out, est.stats())
}

/// The estimates as CSV ([`OUTPUT_HEADER`]), mm with 0.01 and degrees with 0.01 resolution.
pub fn to_csv(estimates: &[Estimate]) -> String {
    let mut s = String::from(OUTPUT_HEADER);
    s.push('\n');
    for e in estimates {
        let _ = writeln!(
            s,
            "{},{:.2},{:.2},{:.2}",
            e.t_ms,
            e.pose.x.to_mm_f64(),
            e.pose.y.to_mm_f64(),
            e.pose.theta.to_radians_f64().to_degrees()
        );
    }
    s
}
