//! Telemetry: one CSV row per report, with a fixed header. Every value is
//! written from integers at a fixed resolution, and [`TelemetryRow`] is
//! exactly what a row holds, so parsing a row gives back the row's values.

use super::number::{Cursor, TextOut};
use super::Overflow;
use crate::driver::{CompassSample, LidarSample};
use crate::math::Length;
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
}

/// The CSV header: one name per column, units in the names.
pub const HEADER: &str = "t_ms,x_mm,y_mm,heading_deg,motion,v_mps,w_radps,left_cmd,right_cmd,\
front_raw_mm,front_mm,right_raw_mm,right_mm,mag_x,mag_y,mag_z,field_x,field_y,field_z,compass_deg,\
f_bus,f_timeout,f_missing,f_bad_sample,f_outliers,f_overruns";

/// Number of columns in a row.
pub const COLUMNS: usize = 26;

/// Longest possible row, bytes: every column at its widest (t_ms 10,
/// x/y 8 each, heading 7, motion 4, v 6, w 7, commands 6 each, raw
/// readings 5 each, distances 8 each, raw mag 6 each, field 9 each
/// (clamped to +-2^24), compass 7, counters 10 each) and 25 commas.
pub const MAX_ROW: usize = 10 + 8 + 8 + 7 + 4 + 6 + 7 + 6 + 6 + 5 + 8 + 5 + 8 + 3 * 6 + 3 * 9 + 7 + 6 * 10 + 25;

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
}

/// A length in 0.1 mm, rounded (|result| <= 327_680): `(10 l + 2^15) >> 16`
/// in 32 bits. With `l = h 2^16 + f` (`h = l >> 16` in -2^15..2^15, `f` in
/// 0..2^16) that is `10 h + ((10 f + 2^15) >> 16)`, as `10 h 2^16` is a
/// multiple of 2^16; `10 f + 2^15 < 2^20` and `|10 h| <= 327_680`.
fn length_dmm(l: Length) -> i32 {
    let (h, f) = (l.0 >> 16, l.0 & 0xFFFF);
    h.wrapping_mul(10).wrapping_add(f.wrapping_mul(10).wrapping_add(1 << 15) >> 16)
}

/// A row as [`format_row`] writes it: one 32-bit cell per column (an
/// `i32`'s bits in the [`SIGNED`] columns, 0 in the motion column), a mask
/// of the empty columns (bit `i` for column `i`) and the motion.
struct Cells {
    v: [u32; COLUMNS],
    empty: u32,
    motion: MotionKind,
}

/// How [`Cells::write`] writes a column: the decimals in the low two bits,
/// whether the cell's bits are an `i32`, or the motion word.
const SIGNED: u8 = 4;
const WORD: u8 = 8;
/// Per column, in [`HEADER`] order.
const FORMAT: [u8; COLUMNS] = [
    0,          // t_ms
    SIGNED | 1, // x_mm
    SIGNED | 1, // y_mm
    3,          // heading_deg
    WORD,       // motion
    SIGNED | 3, // v_mps
    SIGNED | 3, // w_radps
    2,          // left_cmd
    2,          // right_cmd
    0,          // front_raw_mm
    SIGNED | 1, // front_mm
    0,          // right_raw_mm
    SIGNED | 1, // right_mm
    SIGNED,     // mag_x
    SIGNED,     // mag_y
    SIGNED,     // mag_z
    SIGNED,     // field_x
    SIGNED,     // field_y
    SIGNED,     // field_z
    3,          // compass_deg
    0,          // f_bus
    0,          // f_timeout
    0,          // f_missing
    0,          // f_bad_sample
    0,          // f_outliers
    0,          // f_overruns
];

/// The first of the columns a reading fills (raw, then distance; raw x, y,
/// z, field x, y, z, heading).
const FRONT: u32 = 9;
const RIGHT: u32 = 11;
const COMPASS: u32 = 13;
/// The first fault counter's column (`f_bus`; the others follow in
/// [`FaultCounters`]' order).
const FAULTS: u32 = 20;

impl Cells {
    /// The cells of `t` (the firmware's path: no [`TelemetryRow`] between).
    fn of(t: &Telemetry) -> Cells {
        let (v_mm_s, w_mrad_s) = match t.motion {
            Motion::Stop => (0, 0),
            Motion::Straight(v) => (v.to_mm_s(), 0),
            Motion::Turn(w) => (0, w.to_mrad_s()),
        };
        let mut empty = 0;
        // raw reading and distance; a missing one leaves its columns empty
        let mut lidar = |s: &Option<LidarSample>, column: u32| match s {
            Some(LidarSample { raw_mm, range: Range::Target(d) }) => (u32::from(*raw_mm), length_dmm(*d) as u32),
            Some(LidarSample { raw_mm, .. }) => {
                empty |= 2 << column;
                (u32::from(*raw_mm), 0)
            }
            None => {
                empty |= 3 << column;
                (0, 0)
            }
        };
        let (front_raw, front) = lidar(&t.front, FRONT);
        let (right_raw, right) = lidar(&t.right, RIGHT);
        let c = match &t.compass {
            Some(c) => *c,
            None => {
                empty |= 0x7F << COMPASS;
                CompassSample {
                    raw: crate::model::compass::MagCounts { x: 0, y: 0, z: 0 },
                    field: crate::model::compass::MagField { x: 0, y: 0, z: 0 },
                    heading: crate::math::Angle::ZERO,
                }
            }
        };
        let f = &t.faults;
        let v = [
            t.t_ms,
            length_dmm(t.pose.x.to_length()) as u32,
            length_dmm(t.pose.y.to_length()) as u32,
            t.pose.theta.to_millidegrees(),
            0,
            v_mm_s as u32,
            w_mrad_s as u32,
            t.left_cmd.to_centi(),
            t.right_cmd.to_centi(),
            front_raw,
            front,
            right_raw,
            right,
            i32::from(c.raw.x) as u32,
            i32::from(c.raw.y) as u32,
            i32::from(c.raw.z) as u32,
            c.field.x as u32,
            c.field.y as u32,
            c.field.z as u32,
            c.heading.to_millidegrees(),
            f.bus,
            f.timeout,
            f.missing,
            f.bad_sample,
            f.rejected_outliers,
            f.overruns,
        ];
        Cells { v, empty, motion: t.motion.kind() }
    }

    /// Appends the cells as CSV (no terminator): one loop over the columns
    /// and their [`FORMAT`], into a local buffer that goes out in a few
    /// pieces rather than byte by byte.
    #[inline(never)]
    fn write(&self, out: &mut dyn TextOut) -> Result<(), Overflow> {
        let mut row = Cursor::new();
        for i in 0..COLUMNS {
            let (Some(&v), Some(&format)) = (self.v.get(i), FORMAT.get(i)) else { break };
            // the widest column is 13 bytes with its comma (a negative i32
            // with decimals, e.g. -214748364.8): a piece goes out when fewer
            // are left
            if row.room() < 13 {
                row.flush(out)?;
                row.clear();
            }
            if i > 0 {
                row.push(b',');
            }
            if self.empty >> i & 1 != 0 {
                // an empty field
            } else if format & WORD != 0 {
                row.push_bytes(motion_word(self.motion).as_bytes());
            } else {
                let negative = format & SIGNED != 0 && (v as i32) < 0;
                let magnitude = if negative { (v as i32).unsigned_abs() } else { v };
                row.number(negative, magnitude, u32::from(format & 3));
            }
        }
        row.flush(out)
    }
}

impl From<&Telemetry> for TelemetryRow {
    fn from(t: &Telemetry) -> TelemetryRow {
        TelemetryRow::from_cells(&Cells::of(t))
    }
}

impl TelemetryRow {
    /// The row's cells (see [`Cells`]).
    fn cells(&self) -> Cells {
        let mut empty = 0;
        // an Option's value, or 0 and its column marked empty
        let mut cell = |v: Option<i32>, column: u32| {
            v.map_or_else(
                || {
                    empty |= 1 << column;
                    0
                },
                |v| v as u32,
            )
        };
        let axis = |g: Option<[i32; 3]>, k: usize| g.and_then(|m| m.get(k).copied());
        let (raw, field) = (self.mag_raw.map(|m| m.map(i32::from)), self.mag_field);
        let f = &self.faults;
        let v = [
            self.t_ms,
            self.x_dmm as u32,
            self.y_dmm as u32,
            self.heading_mdeg,
            0,
            self.v_mm_s as u32,
            self.w_mrad_s as u32,
            self.left_cmd_centi,
            self.right_cmd_centi,
            cell(self.front_raw_mm.map(i32::from), FRONT),
            cell(self.front_dmm, FRONT + 1),
            cell(self.right_raw_mm.map(i32::from), RIGHT),
            cell(self.right_dmm, RIGHT + 1),
            cell(axis(raw, 0), COMPASS),
            cell(axis(raw, 1), COMPASS + 1),
            cell(axis(raw, 2), COMPASS + 2),
            cell(axis(field, 0), COMPASS + 3),
            cell(axis(field, 1), COMPASS + 4),
            cell(axis(field, 2), COMPASS + 5),
            // a u32's bits (the column is unsigned)
            cell(self.compass_mdeg.map(|d| d as i32), COMPASS + 6),
            f.bus,
            f.timeout,
            f.missing,
            f.bad_sample,
            f.rejected_outliers,
            f.overruns,
        ];
        Cells { v, empty, motion: self.motion }
    }

    /// The row that `cells` hold (the inverse of [`TelemetryRow::cells`];
    /// a group of magnetometer axes is present when its first column is).
    fn from_cells(c: &Cells) -> TelemetryRow {
        let at = |i: u32| c.v.get(i as usize).copied().unwrap_or(0);
        let opt = |i: u32| (c.empty >> i & 1 == 0).then(|| at(i) as i32);
        let group = |i: u32| opt(i).map(|_| [at(i) as i32, at(i.wrapping_add(1)) as i32, at(i.wrapping_add(2)) as i32]);
        TelemetryRow {
            t_ms: at(0),
            x_dmm: at(1) as i32,
            y_dmm: at(2) as i32,
            heading_mdeg: at(3),
            motion: c.motion,
            v_mm_s: at(5) as i32,
            w_mrad_s: at(6) as i32,
            left_cmd_centi: at(7),
            right_cmd_centi: at(8),
            // a raw reading is a u16 (from a LidarSample)
            front_raw_mm: opt(FRONT).map(|r| r as u16),
            front_dmm: opt(FRONT + 1),
            right_raw_mm: opt(RIGHT).map(|r| r as u16),
            right_dmm: opt(RIGHT + 1),
            // the raw axes are i16 (from MagCounts)
            mag_raw: group(COMPASS).map(|m| m.map(|a| a as i16)),
            mag_field: group(COMPASS + 3),
            compass_mdeg: opt(COMPASS + 6).map(|d| d as u32),
            faults: FaultCounters {
                bus: at(FAULTS),
                timeout: at(FAULTS + 1),
                missing: at(FAULTS + 2),
                bad_sample: at(FAULTS + 3),
                rejected_outliers: at(FAULTS + 4),
                overruns: at(FAULTS + 5),
            },
        }
    }
}

/// Appends one telemetry row (no terminator) for `t`. On [`Overflow`] the
/// string holds a partial row: clear it. A `String<`[`MAX_ROW`]`>` always fits.
pub fn format_telemetry(t: &Telemetry, out: &mut dyn TextOut) -> Result<(), Overflow> {
    Cells::of(t).write(out)
}

/// Appends a row's values as CSV (no terminator), as [`format_telemetry`]
/// writes the telemetry it came from.
pub fn format_row(r: &TelemetryRow, out: &mut dyn TextOut) -> Result<(), Overflow> {
    r.cells().write(out)
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
        })
    }
}
