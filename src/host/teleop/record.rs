//! The session log in the replay tool's format (`cargo run --example replay
//! -- LOG.csv`, see `model::estimator::replay`):
//!
//! ```text
//! t_ms,left_cmd,right_cmd,front_mm,right_mm,heading_deg
//! 1200,107.00,61.00,412,8190,353.117
//! 1220,107.00,61.00,,,353.002
//! ```
//!
//! One line per telemetry row: the robot's clock, the servo commands it
//! applied (0..180 scale), the RAW lidar readings in mm (8190/8191 = no
//! target, as the chip said; the replay applies the lidar models itself)
//! and the calibrated compass heading in degrees clockwise from north. An
//! empty field means no fresh reading since the previous row. A row whose
//! time goes back (the robot rebooted) is skipped and counted: a replay log
//! never goes back in time.

use std::fmt::Write as _;
use std::io::{self, Write};
use std::string::String;

use crate::control::protocol::TelemetryRow;

/// The replay log's header (the same as the replay tool's).
pub const REPLAY_HEADER: &str = "t_ms,left_cmd,right_cmd,front_mm,right_mm,heading_deg";

/// `v` (in units of `10^-decimals`) as a decimal.
fn fixed(s: &mut String, v: u32, decimals: u32) {
    let d = 10u32.pow(decimals);
    let _ = write!(s, "{}.{:0width$}", v / d, v % d, width = decimals as usize);
}

/// The replay line for one telemetry row (no terminator).
pub fn replay_row(r: &TelemetryRow) -> String {
    let mut s = String::with_capacity(48);
    let _ = write!(s, "{},", r.t_ms);
    fixed(&mut s, r.left_cmd_centi, 2);
    s.push(',');
    fixed(&mut s, r.right_cmd_centi, 2);
    s.push(',');
    if let Some(v) = r.front_raw_mm {
        let _ = write!(s, "{v}");
    }
    s.push(',');
    if let Some(v) = r.right_raw_mm {
        let _ = write!(s, "{v}");
    }
    s.push(',');
    if let Some(h) = r.compass_mdeg {
        fixed(&mut s, h, 3);
    }
    s
}

/// Writes a replay log, row by row (flushed per row: a crash keeps the drive).
pub struct Recorder<W: Write> {
    out: W,
    last_t: Option<u32>,
    rows: u64,
    skipped: u64,
    first: Option<TelemetryRow>,
}

impl<W: Write> Recorder<W> {
    /// Starts a log (writes the header).
    pub fn new(mut out: W) -> io::Result<Recorder<W>> {
        writeln!(out, "{REPLAY_HEADER}")?;
        out.flush()?;
        Ok(Recorder { out, last_t: None, rows: 0, skipped: 0, first: None })
    }

    /// Records a row; `Ok(false)` when it was skipped (time went back).
    pub fn record(&mut self, row: &TelemetryRow) -> io::Result<bool> {
        if self.last_t.is_some_and(|t| row.t_ms < t) {
            self.skipped = self.skipped.saturating_add(1);
            return Ok(false);
        }
        writeln!(self.out, "{}", replay_row(row))?;
        self.out.flush()?;
        self.last_t = Some(row.t_ms);
        self.rows = self.rows.saturating_add(1);
        self.first.get_or_insert(*row);
        Ok(true)
    }

    /// Rows written.
    pub fn rows(&self) -> u64 {
        self.rows
    }
    /// Rows skipped because their time went back.
    pub fn skipped(&self) -> u64 {
        self.skipped
    }
    /// The first row written (its pose is the replay's start pose).
    pub fn first(&self) -> Option<&TelemetryRow> {
        self.first.as_ref()
    }

    /// The replay tool's `--start X,Y,DEG` for this log: the robot's own
    /// pose at the first row (the replay would otherwise start in the
    /// arena's centre).
    pub fn replay_start(&self) -> Option<String> {
        self.first.map(|r| {
            let mut s = String::new();
            let mm = |dmm: i32| f64::from(dmm) / 10.0;
            let _ = write!(s, "{:.1},{:.1},{:.3}", mm(r.x_dmm), mm(r.y_dmm), f64::from(r.heading_mdeg) / 1000.0);
            s
        })
    }

    pub fn into_inner(self) -> W {
        self.out
    }
}
