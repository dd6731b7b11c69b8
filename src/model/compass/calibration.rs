//! Hard- and soft-iron calibration of the magnetometer, the report's method
//! (section 2.4): while the robot turns in place, track the minimum and
//! maximum of each axis; then `bias = (max + min) / 2` and
//! `scale = mean half-range / half-range` per axis.
//!
//! [`MagCalibrator`] is an incremental state machine: the control loop feeds
//! it one raw sample at a time during a turn (no buffer, no float, no
//! allocation) and asks for the [`result`](MagCalibrator::result) at the
//! end. A sweep is only accepted if it has [`config::compass::
//! CALIBRATION_SAMPLES`] samples and the horizontal field vector, seen from
//! the running centre of the min/max box, visited at least
//! [`config::compass::CALIBRATION_MIN_SECTORS`] of the twelve 30-degree
//! sectors (a robot that turned half a circle, or not at all, gives a box
//! that is not the field's). The centre only settles once the turn has
//! passed every extreme, so the first turn counts about 9 sectors: a sweep
//! must be longer than one turn (the configured 1000 samples at 100 Hz are
//! 3.5 to 5 turns at the robot's 2.2 to 3.2 rad/s). [`ConfigLine`] prints
//! the result as a line to paste into `src/config.rs`.

use core::fmt;

use crate::config;
use crate::math::{atan2, div_round};
use crate::model::compass::{apply_asa, AxisMap, MagCalibration, MagCounts};

/// Number of sectors the circle is cut into (30 degrees each).
pub const SECTORS: u8 = 12;

/// Why a sweep was rejected.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum CalibrationError {
    /// Fewer samples than asked for.
    NotEnoughSamples { have: u16, need: u16 },
    /// The turn did not cover enough of the circle.
    SweepIncomplete { sectors: u8, need: u8 },
    /// An axis never changed (or the scale does not fit): no calibration
    /// can be computed from it.
    Degenerate { axis: u8 },
}

/// Where a sweep stands after a sample.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum CalStatus {
    /// Still collecting: samples so far.
    Collecting(u16),
    /// Enough samples; call [`MagCalibrator::result`].
    Done,
}

/// The incremental min/max sweep (see the module docs).
#[derive(Clone, Copy, Debug)]
pub struct MagCalibrator {
    asa: [u8; 3],
    axes: AxisMap,
    need_samples: u16,
    need_sectors: u8,
    min_radius: i32,
    count: u16,
    min: [i32; 3],
    max: [i32; 3],
    /// Bit i set: sector i (of [`SECTORS`]) was visited.
    sectors: u16,
}

impl MagCalibrator {
    /// A sweep over `samples` samples that must visit `min_sectors`
    /// sectors; samples whose horizontal vector is shorter than
    /// `min_radius` counts (larger component) visit no sector. `asa` is the
    /// chip's sensitivity adjustment ([`super::MagCalibrate::asa`]): the
    /// biases are in ASA-adjusted counts, like [`MagCalibration`]'s.
    pub fn new(asa: [u8; 3], axes: AxisMap, samples: u16, min_sectors: u8, min_radius: i32) -> Self {
        MagCalibrator {
            asa,
            axes,
            need_samples: samples,
            need_sectors: min_sectors,
            min_radius,
            count: 0,
            min: [i32::MAX; 3],
            max: [i32::MIN; 3],
            sectors: 0,
        }
    }

    /// A sweep with the configured sizes ([`config::compass`]).
    pub fn with_config(asa: [u8; 3]) -> Self {
        Self::new(
            asa,
            config::compass::AXES,
            config::compass::CALIBRATION_SAMPLES,
            config::compass::CALIBRATION_MIN_SECTORS,
            config::compass::CALIBRATION_MIN_RADIUS,
        )
    }

    /// Feeds one raw sample (chip axes, as read). Samples after the sweep
    /// is complete are ignored.
    pub fn feed(&mut self, raw: MagCounts) -> CalStatus {
        if self.count >= self.need_samples {
            return CalStatus::Done;
        }
        let adj = [
            apply_asa(raw.x, self.asa.first().copied().unwrap_or(128)),
            apply_asa(raw.y, self.asa.get(1).copied().unwrap_or(128)),
            apply_asa(raw.z, self.asa.get(2).copied().unwrap_or(128)),
        ];
        for ((lo, hi), v) in self.min.iter_mut().zip(self.max.iter_mut()).zip(adj) {
            *lo = (*lo).min(v);
            *hi = (*hi).max(v);
        }
        self.count = self.count.saturating_add(1);
        self.visit(&adj);
        if self.count >= self.need_samples {
            CalStatus::Done
        } else {
            CalStatus::Collecting(self.count)
        }
    }

    /// Marks the sector of the horizontal vector from the box's centre.
    fn visit(&mut self, adj: &[i32; 3]) {
        let f = usize::from(self.axes.forward.index);
        let r = usize::from(self.axes.right.index);
        let comp = |i: usize| -> Option<i32> {
            let v = *adj.get(i)?;
            // |adj| < 2^17 (ASA-adjusted i16), so the sums cannot overflow.
            let centre = self.min.get(i)?.saturating_add(*self.max.get(i)?) / 2;
            Some(v.saturating_sub(centre))
        };
        let (Some(df), Some(dr)) = (comp(f), comp(r)) else { return };
        if df.abs().max(dr.abs()) < self.min_radius {
            return;
        }
        let a = atan2(dr, df);
        // sector = floor(angle / (1/12 turn)): < 12, no division.
        let sector = (u64::from(a.0).saturating_mul(u64::from(SECTORS)) >> 32) as u32;
        self.sectors |= 1u16.checked_shl(sector).unwrap_or(0);
    }

    /// Samples fed so far (up to the sweep's size).
    pub fn samples(&self) -> u16 {
        self.count
    }

    /// Sectors visited so far.
    pub fn sectors(&self) -> u8 {
        self.sectors.count_ones() as u8
    }

    /// The per-axis minimum and maximum so far (ASA-adjusted counts).
    pub fn extremes(&self) -> ([i32; 3], [i32; 3]) {
        (self.min, self.max)
    }

    /// The new calibration, if the sweep is complete and covers the circle.
    pub fn result(&self) -> Result<MagCalibration, CalibrationError> {
        if self.count < self.need_samples {
            return Err(CalibrationError::NotEnoughSamples { have: self.count, need: self.need_samples });
        }
        if self.sectors() < self.need_sectors {
            return Err(CalibrationError::SweepIncomplete { sectors: self.sectors(), need: self.need_sectors });
        }
        let mut bias = [0i32; 3];
        let mut range = [0i32; 3];
        for (i, ((lo, hi), (b, r))) in
            self.min.iter().zip(self.max.iter()).zip(bias.iter_mut().zip(range.iter_mut())).enumerate()
        {
            // lo <= hi, both |.| < 2^17: 32-bit sums and differences.
            *r = hi.saturating_sub(*lo);
            if *r <= 0 {
                return Err(CalibrationError::Degenerate { axis: i as u8 });
            }
            // (hi + lo) / 2, halves away from zero (`/ 2` truncates toward zero)
            let s = hi.saturating_add(*lo);
            *b = s.saturating_add(if s < 0 { -1 } else { 1 }) / 2;
        }
        // scale_i = (sum / 3) / range_i = sum / (3 range_i), in Q16: sum < 2^20,
        // so sum 2^16 needs 64 bits.
        let sum = i64::from(range.iter().fold(0i32, |a, &r| a.saturating_add(r)));
        let mut scale_q16 = [0i32; 3];
        for (i, (s, r)) in scale_q16.iter_mut().zip(range.iter()).enumerate() {
            let q = div_round(sum << 16, i64::from(r.saturating_mul(3)))
                .ok_or(CalibrationError::Degenerate { axis: i as u8 })?;
            *s = i32::try_from(q).map_err(|_| CalibrationError::Degenerate { axis: i as u8 })?;
        }
        Ok(MagCalibration { bias, scale_q16 })
    }
}

/// Formats a [`MagCalibration`] as the `CALIBRATION` line of
/// `config::compass`, ready to paste (integer arithmetic only: the scales
/// are printed to six decimals, which round-trip exactly through
/// `MagCalibration::from_f64`).
pub struct ConfigLine<'a>(pub &'a MagCalibration);

/// Writes a Q16 value as a decimal with six places.
fn write_q16(f: &mut fmt::Formatter<'_>, q16: i32) -> fmt::Result {
    let micro = div_round(i64::from(q16).saturating_mul(1_000_000), 65536).unwrap_or(0);
    let sign = if micro < 0 { "-" } else { "" };
    let m = micro.unsigned_abs();
    write!(f, "{sign}{}.{:06}", m / 1_000_000, m % 1_000_000)
}

impl fmt::Display for ConfigLine<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let [bx, by, bz] = self.0.bias;
        let [sx, sy, sz] = self.0.scale_q16;
        write!(f, "pub const CALIBRATION: MagCalibration = MagCalibration::from_f64([{bx}.0, {by}.0, {bz}.0], [")?;
        write_q16(f, sx)?;
        f.write_str(", ")?;
        write_q16(f, sy)?;
        f.write_str(", ")?;
        write_q16(f, sz)?;
        f.write_str("]);")
    }
}
