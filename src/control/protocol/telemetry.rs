//! Telemetry: one CSV row per report, with a fixed header. Every value is
//! written from integers at a fixed resolution, and [`TelemetryRow`] is
//! exactly what a row holds, so parsing a row gives back the row's values.

use super::number::{Cursor, TextOut};
use super::Overflow;
use crate::driver::{CompassSample, LidarSample};
use crate::math::Length;
use crate::model::estimator::Tracking;
use crate::model::{Motion, MotionKind, Pose, Range, ServoCmd};

/// Error and fault counts since boot (each saturates at `u32::MAX`).
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug, Default)]
pub struct FaultCounters {
    /// Bus transactions that failed (NACK, stuck line...).
    pub bus: u32,
    /// Chips that did not answer in time.
    pub timeout: u32,
    /// Chips missing at bring-up or re-init.
    pub missing: u32,
    /// Samples the chip flagged as bad (e.g. magnetic overflow).
    pub bad_sample: u32,
    /// Measurements the estimator rejected as outliers.
    pub rejected_outliers: u32,
    /// Loop ticks that ran late.
    pub overruns: u32,
}

/// What one telemetry row reports. `None` readings (nothing fresh since
/// the last row) give empty fields.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub struct Telemetry {
    /// Time since boot, ms.
    pub t_ms: u32,
    pub pose: Pose,
    pub front: Option<LidarSample>,
    pub right: Option<LidarSample>,
    pub compass: Option<CompassSample>,
    /// The motion being driven (what the state update integrates).
    pub motion: Motion,
    pub left_cmd: ServoCmd,
    pub right_cmd: ServoCmd,
    pub faults: FaultCounters,
    /// How sure the estimator is of `pose`.
    pub tracking: Tracking,
}

/// The CSV header: one name per column, units in the names.
pub const HEADER: &str = "t_ms,x_mm,y_mm,heading_deg,motion,v_mps,w_radps,left_cmd,right_cmd,\
front_raw_mm,front_mm,right_raw_mm,right_mm,mag_x,mag_y,mag_z,field_x,field_y,field_z,compass_deg,\
f_bus,f_timeout,f_missing,f_bad_sample,f_outliers,f_overruns,pose";

/// Number of columns in a row.
pub const COLUMNS: usize = 27;

/// Longest possible row, bytes: every column at its widest (t_ms 10,
/// x/y 8 each, heading 7, motion 4, v 6, w 7, commands 6 each, raw
/// readings 5 each, distances 8 each, raw mag 6 each, field 9 each
/// (clamped to +-2^24), compass 7, counters 10 each, the estimator's
/// state 9) and 26 commas.
pub const MAX_ROW: usize = 10 + 8 + 8 + 7 + 4 + 6 + 7 + 6 + 6 + 5 + 8 + 5 + 8 + 3 * 6 + 3 * 9 + 7 + 6 * 10 + 9 + 26;

/// The CSV header line (print it before the first row, and again whenever
/// telemetry is switched on).
pub fn telemetry_header() -> &'static str {
    HEADER
}

/// The word in the `motion` column.
pub fn motion_word(kind: MotionKind) -> &'static str {
    match kind {
        MotionKind::Stop => "stop",
        MotionKind::Forward => "fwd",
        MotionKind::Backward => "back",
        MotionKind::Cw => "cw",
        MotionKind::Ccw => "ccw",
    }
}

/// One row's values, at the resolution written: what a row parser returns.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub struct TelemetryRow {
    pub t_ms: u32,
    /// Pose position, 0.1 mm.
    pub x_dmm: i32,
    pub y_dmm: i32,
    /// Pose heading, millidegrees in `0..360_000`.
    pub heading_mdeg: u32,
    pub motion: MotionKind,
    /// Signed speed, mm/s (written as m/s with 3 decimals).
    pub v_mm_s: i32,
    /// Signed turn rate, mrad/s, positive clockwise (written as rad/s).
    pub w_mrad_s: i32,
    /// Servo commands, 1/100 step (written with 2 decimals).
    pub left_cmd_centi: u32,
    pub right_cmd_centi: u32,
    /// Front lidar: raw reading (mm) and distance from the reference point
    /// (0.1 mm; `None` without a target).
    pub front_raw_mm: Option<u16>,
    pub front_dmm: Option<i32>,
    pub right_raw_mm: Option<u16>,
    pub right_dmm: Option<i32>,
    /// Raw magnetometer counts (chip axes x, y, z).
    pub mag_raw: Option<[i16; 3]>,
    /// Corrected field, counts (chip axes x, y, z).
    pub mag_field: Option<[i32; 3]>,
    /// Compass heading, millidegrees in `0..360_000`.
    pub compass_mdeg: Option<u32>,
    pub faults: FaultCounters,
    /// The estimator's state (`located`, `ambiguous`, `unknown`).
    pub tracking: Tracking,
}

/// A length in 0.1 mm, rounded (|result| <= 327_680): `(10 l + 2^15) >> 16`
/// in 32 bits. With `l = h 2^16 + f` (`h = l >> 16` in -2^15..2^15, `f` in
/// 0..2^16) that is `10 h + ((10 f + 2^15) >> 16)`, as `10 h 2^16` is a
/// multiple of 2^16; `10 f + 2^15 < 2^20` and `|10 h| <= 327_680`.
fn length_dmm(l: Length) -> i32 {
    let (h, f) = (l.0 >> 16, l.0 & 0xFFFF);
    h.wrapping_mul(10).wrapping_add(f.wrapping_mul(10).wrapping_add(1 << 15) >> 16)
}

impl From<&Telemetry> for TelemetryRow {
    fn from(t: &Telemetry) -> TelemetryRow {
        let (v_mm_s, w_mrad_s) = match t.motion {
            Motion::Stop => (0, 0),
            Motion::Straight(v) => (v.to_mm_s(), 0),
            Motion::Turn(w) => (0, w.to_mrad_s()),
        };
        // raw reading and distance (none without a target)
        let lidar = |s: &Option<LidarSample>| match s {
            Some(LidarSample { raw_mm, range: Range::Target(d) }) => (Some(*raw_mm), Some(length_dmm(*d))),
            Some(LidarSample { raw_mm, .. }) => (Some(*raw_mm), None),
            None => (None, None),
        };
        let (front_raw_mm, front_dmm) = lidar(&t.front);
        let (right_raw_mm, right_dmm) = lidar(&t.right);
        TelemetryRow {
            t_ms: t.t_ms,
            x_dmm: length_dmm(t.pose.x.to_length()),
            y_dmm: length_dmm(t.pose.y.to_length()),
            heading_mdeg: t.pose.theta.to_millidegrees(),
            motion: t.motion.kind(),
            v_mm_s,
            w_mrad_s,
            left_cmd_centi: t.left_cmd.to_centi(),
            right_cmd_centi: t.right_cmd.to_centi(),
            front_raw_mm,
            front_dmm,
            right_raw_mm,
            right_dmm,
            mag_raw: t.compass.map(|c| [c.raw.x, c.raw.y, c.raw.z]),
            mag_field: t.compass.map(|c| [c.field.x, c.field.y, c.field.z]),
            compass_mdeg: t.compass.map(|c| c.heading.to_millidegrees()),
            faults: t.faults,
            tracking: t.tracking,
        }
    }
}

/// Writes the columns of a row, comma-separated, into a local buffer that
/// goes out in a few pieces rather than number by number.
struct Columns<'a> {
    out: &'a mut dyn TextOut,
    row: Cursor,
    first: bool,
}

impl Columns<'_> {
    /// The widest column with its comma: a negative i32 with decimals, e.g.
    /// `,-214748364.8`.
    const WIDEST: usize = 13;

    /// Starts the next column: hands the buffer out when the widest column
    /// might not fit, then writes the comma.
    fn next(&mut self) -> Result<(), Overflow> {
        if self.row.room() < Self::WIDEST {
            self.row.flush(self.out)?;
            self.row.clear();
        }
        if !core::mem::replace(&mut self.first, false) {
            self.row.push(b',');
        }
        Ok(())
    }

    /// An unsigned value with `decimals` decimals, or an empty field.
    fn unsigned(&mut self, v: impl Into<Option<u32>>, decimals: u32) -> Result<(), Overflow> {
        self.next()?;
        if let Some(v) = v.into() {
            self.row.number(false, v, decimals);
        }
        Ok(())
    }

    /// A signed value with `decimals` decimals, or an empty field.
    fn signed(&mut self, v: impl Into<Option<i32>>, decimals: u32) -> Result<(), Overflow> {
        self.next()?;
        if let Some(v) = v.into() {
            self.row.number(v < 0, v.unsigned_abs(), decimals);
        }
        Ok(())
    }

    /// Three integer columns (magnetometer axes x, y, z), or three empty fields.
    fn axes(&mut self, axes: Option<[i32; 3]>) -> Result<(), Overflow> {
        let [x, y, z] = axes.map_or([None; 3], |a| a.map(Some));
        self.signed(x, 0)?;
        self.signed(y, 0)?;
        self.signed(z, 0)
    }

    fn word(&mut self, word: &str) -> Result<(), Overflow> {
        self.next()?;
        self.row.push_bytes(word.as_bytes());
        Ok(())
    }

    /// Hands out what is left.
    fn finish(self) -> Result<(), Overflow> {
        self.row.flush(self.out)
    }
}

/// Appends a row's values as CSV (no terminator), in [`HEADER`]'s order.
/// On [`Overflow`] the buffer holds a partial row: clear it. A
/// `String<`[`MAX_ROW`]`>` always fits.
pub fn format_row(r: &TelemetryRow, out: &mut dyn TextOut) -> Result<(), Overflow> {
    let mut c = Columns { out, row: Cursor::new(), first: true };
    c.unsigned(r.t_ms, 0)?;
    c.signed(r.x_dmm, 1)?;
    c.signed(r.y_dmm, 1)?;
    c.unsigned(r.heading_mdeg, 3)?;
    c.word(motion_word(r.motion))?;
    c.signed(r.v_mm_s, 3)?;
    c.signed(r.w_mrad_s, 3)?;
    c.unsigned(r.left_cmd_centi, 2)?;
    c.unsigned(r.right_cmd_centi, 2)?;
    c.unsigned(r.front_raw_mm.map(u32::from), 0)?;
    c.signed(r.front_dmm, 1)?;
    c.unsigned(r.right_raw_mm.map(u32::from), 0)?;
    c.signed(r.right_dmm, 1)?;
    c.axes(r.mag_raw.map(|m| m.map(i32::from)))?;
    c.axes(r.mag_field)?;
    c.unsigned(r.compass_mdeg, 3)?;
    let f = &r.faults;
    for count in [f.bus, f.timeout, f.missing, f.bad_sample, f.rejected_outliers, f.overruns] {
        c.unsigned(count, 0)?;
    }
    c.word(r.tracking.word())?;
    c.finish()
}

/// Appends one telemetry row (no terminator) for `t`, as [`format_row`]
/// writes its [`TelemetryRow`].
pub fn format_telemetry(t: &Telemetry, out: &mut dyn TextOut) -> Result<(), Overflow> {
    format_row(&TelemetryRow::from(t), out)
}

/// What kind of line came from the robot.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum LineKind {
    /// Starts with `#`: a response, help, status or note.
    Comment,
    /// The CSV header.
    Header,
    /// Anything else: a telemetry row (or garbage).
    Row,
}

/// Classifies a received line (terminator already removed).
pub fn classify_line(line: &str) -> LineKind {
    let line = line.trim_end_matches(['\r', '\n']);
    if line.starts_with('#') {
        LineKind::Comment
    } else if line == HEADER {
        LineKind::Header
    } else {
        LineKind::Row
    }
}

#[cfg(feature = "std")]
pub use row_parser::{parse_telemetry_row, RowError};

#[cfg(feature = "std")]
mod row_parser {
    use super::super::number::{parse_fixed, parse_fixed_parts};
    use super::{FaultCounters, TelemetryRow, COLUMNS, HEADER};
    use crate::model::estimator::Tracking;
    use crate::model::MotionKind;

    /// Why a line is not a telemetry row.
    #[derive(Clone, Copy, PartialEq, Eq, Debug)]
    pub enum RowError {
        /// Not [`COLUMNS`] comma-separated fields.
        Columns { found: usize },
        /// The field in this column (its header name) does not parse or is
        /// out of its type's range; a group (magnetometer axes) is partly empty.
        Field { column: &'static str },
    }

    fn name(i: usize) -> &'static str {
        HEADER.split(',').nth(i).unwrap_or("?")
    }

    /// Reads a row written by [`super::format_row`] back into numbers
    /// (host side: the teleop tool and tests). Surrounding `\r`/`\n` are ignored.
    pub fn parse_telemetry_row(line: &str) -> Result<TelemetryRow, RowError> {
        let line = line.trim_end_matches(['\r', '\n']);
        let fields: std::vec::Vec<&str> = line.split(',').collect();
        if fields.len() != COLUMNS {
            return Err(RowError::Columns { found: fields.len() });
        }
        let get = |i: usize| fields.get(i).copied().unwrap_or("");
        let err = |i: usize| RowError::Field { column: name(i) };
        let num = |i: usize, decimals: u32| -> Result<i32, RowError> {
            parse_fixed(get(i).as_bytes(), decimals).map_err(|_| err(i))
        };
        let opt = |i: usize, decimals: u32| -> Result<Option<i32>, RowError> {
            if get(i).is_empty() {
                Ok(None)
            } else {
                num(i, decimals).map(Some)
            }
        };
        let unsigned = |i: usize, decimals: u32| -> Result<u32, RowError> {
            match parse_fixed_parts(get(i).as_bytes(), decimals) {
                Ok((false, v)) => Ok(v),
                _ => Err(err(i)),
            }
        };
        let conv = |i: usize, v: Option<i32>| -> Result<Option<u16>, RowError> {
            v.map(|v| u16::try_from(v).map_err(|_| err(i))).transpose()
        };
        let group = |first: usize| -> Result<Option<[i32; 3]>, RowError> {
            match (opt(first, 0)?, opt(first.saturating_add(1), 0)?, opt(first.saturating_add(2), 0)?) {
                (Some(a), Some(b), Some(c)) => Ok(Some([a, b, c])),
                (None, None, None) => Ok(None),
                _ => Err(err(first)),
            }
        };
        // columns in order, so the first bad one is reported
        Ok(TelemetryRow {
            t_ms: unsigned(0, 0)?,
            x_dmm: num(1, 1)?,
            y_dmm: num(2, 1)?,
            heading_mdeg: unsigned(3, 3)?,
            motion: match get(4) {
                "stop" => MotionKind::Stop,
                "fwd" => MotionKind::Forward,
                "back" => MotionKind::Backward,
                "cw" => MotionKind::Cw,
                "ccw" => MotionKind::Ccw,
                _ => return Err(err(4)),
            },
            v_mm_s: num(5, 3)?,
            w_mrad_s: num(6, 3)?,
            left_cmd_centi: unsigned(7, 2)?,
            right_cmd_centi: unsigned(8, 2)?,
            front_raw_mm: conv(9, opt(9, 0)?)?,
            front_dmm: opt(10, 1)?,
            right_raw_mm: conv(11, opt(11, 0)?)?,
            right_dmm: opt(12, 1)?,
            mag_raw: match group(13)? {
                None => None,
                Some(m) => {
                    let axis =
                        |k: usize| i16::try_from(m.get(k).copied().unwrap_or(0)).map_err(|_| err(k.saturating_add(13)));
                    Some([axis(0)?, axis(1)?, axis(2)?])
                }
            },
            mag_field: group(16)?,
            compass_mdeg: if get(19).is_empty() { None } else { Some(unsigned(19, 3)?) },
            faults: FaultCounters {
                bus: unsigned(20, 0)?,
                timeout: unsigned(21, 0)?,
                missing: unsigned(22, 0)?,
                bad_sample: unsigned(23, 0)?,
                rejected_outliers: unsigned(24, 0)?,
                overruns: unsigned(25, 0)?,
            },
            tracking: Tracking::from_word(get(26)).ok_or(err(26))?,
        })
    }
}
