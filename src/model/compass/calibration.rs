//! Hard- and soft-iron calibration of the magnetometer, the report's method
//! (section 2.4): while the robot turns in place, track the minimum and
//! maximum of each axis; then `bias = (max + min) / 2` and
//! `scale = mean half-range / half-range` per axis.
//!
//! A turn in place on a flat floor only sweeps the field through the
//! forward and right axes; the vertical one barely changes, so its bias and
//! scale cannot be observed. The sweep measures the two horizontal axes and
//! keeps the vertical axis's bias and scale from
//! [`config::compass::CALIBRATION`]. The mean half-range counts the vertical
//! axis with the half-range its kept scale implies, so the scales keep the
//! report's proportion (`1/s_f + 1/s_r + 1/s_v = 3`): with `r` the ranges,
//! `R = (r_f + r_r) s_v / (3 s_v - 1)` and `s_i = R / r_i`. (The heading
//! uses only the ratio of the horizontal scales; this keeps the scales'
//! level comparable with the config's.)
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
//! that has its samples but not its sectors keeps collecting, up to
//! [`config::compass::CALIBRATION_EXTRA_SAMPLES`] more (so `cal 250`, one
//! turn's samples, ends within about two turns). [`ConfigLine`] prints the
//! result as a line to paste into `config::compass` (`src/config/compass.rs`).

use core::fmt;

use crate::config;
use crate::math::{atan2, div_round};
use crate::model::compass::{apply_asa, AxisMap, MagCalibration, MagCounts};

/// Number of sectors the circle is cut into (30 degrees each).
pub const SECTORS: u8 = 12;

/// The axis a turn on a flat floor cannot observe (chip index): the one
/// neither forward nor right in [`config::compass::AXES`]. Its bias and
/// scale are kept from [`config::compass::CALIBRATION`].
pub const VERTICAL: usize = 3 - (config::compass::AXES.forward.index + config::compass::AXES.right.index) as usize;

/// `s_v / (3 s_v - 1)` in Q24 for the kept vertical scale `s_v`: the mean
/// half-range as a share of the two measured ones' sum (module docs).
const KEPT_SHARE_Q24: i64 = {
    let sv = config::compass::CALIBRATION.scale_q16[VERTICAL] as i64;
    // a kept scale at or below 1/3 leaves no half-range for the horizontal
    // axes; from 1/2 up the share is at most 1 (2^24 in Q24)
    assert!(2 * sv >= 65_536);
    (sv << 24) / (3 * sv - 65_536)
};

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
    /// Enough samples and sectors, or no more samples allowed; call
    /// [`MagCalibrator::result`].
    Done,
}

/// The incremental min/max sweep (see the module docs).
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub struct MagCalibrator {
    asa: [u8; 3],
    axes: AxisMap,
    need_samples: u16,
    /// The most samples the sweep takes while it lacks sectors.
    max_samples: u16,
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
    /// chip's sensitivity adjustment (its ASA, read by the compass driver): the
    /// biases are in ASA-adjusted counts, like [`MagCalibration`]'s.
    pub fn new(asa: [u8; 3], axes: AxisMap, samples: u16, min_sectors: u8, min_radius: i32) -> Self {
        MagCalibrator {
            asa,
            axes,
            need_samples: samples,
            max_samples: samples.saturating_add(config::compass::CALIBRATION_EXTRA_SAMPLES),
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
    /// is complete are ignored. The sweep is complete with its samples and
    /// sectors, or at [`max_samples`](Self::max_samples).
    pub fn feed(&mut self, raw: MagCounts) -> CalStatus {
        if self.is_done() {
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
        if self.is_done() {
            CalStatus::Done
        } else {
            CalStatus::Collecting(self.count)
        }
    }

    /// The sweep has its samples and sectors, or all the samples it may take.
    fn is_done(&self) -> bool {
        (self.count >= self.need_samples && self.sectors() >= self.need_sectors) || self.count >= self.max_samples
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

    /// Samples fed so far (up to [`max_samples`](Self::max_samples)).
    pub fn samples(&self) -> u16 {
        self.count
    }

    /// The most samples the sweep takes: the asked number plus
    /// [`config::compass::CALIBRATION_EXTRA_SAMPLES`] while sectors are missing.
    pub fn max_samples(&self) -> u16 {
        self.max_samples
    }

    /// Sectors visited so far.
    pub fn sectors(&self) -> u8 {
        self.sectors.count_ones() as u8
    }

    /// The per-axis minimum and maximum so far (ASA-adjusted counts).
    pub fn extremes(&self) -> ([i32; 3], [i32; 3]) {
        (self.min, self.max)
    }

    /// The new calibration, if the sweep is complete and covers the circle:
    /// the forward and right axes measured, the [`VERTICAL`] one kept from
    /// [`config::compass::CALIBRATION`] (see the module docs).
    pub fn result(&self) -> Result<MagCalibration, CalibrationError> {
        if self.count < self.need_samples {
            return Err(CalibrationError::NotEnoughSamples { have: self.count, need: self.need_samples });
        }
        if self.sectors() < self.need_sectors {
            return Err(CalibrationError::SweepIncomplete { sectors: self.sectors(), need: self.need_sectors });
        }
        let mut cal = config::compass::CALIBRATION;
        let mut range = [0i32; 3];
        let mut sum = 0i32;
        for (i, ((lo, hi), (b, r))) in
            self.min.iter().zip(self.max.iter()).zip(cal.bias.iter_mut().zip(range.iter_mut())).enumerate()
        {
            if i == VERTICAL {
                continue;
            }
            // lo <= hi, both |.| < 2^17: 32-bit sums and differences.
            *r = hi.saturating_sub(*lo);
            if *r <= 0 {
                return Err(CalibrationError::Degenerate { axis: i as u8 });
            }
            // (hi + lo) / 2, halves away from zero (`/ 2` truncates toward zero)
            let s = hi.saturating_add(*lo);
            *b = s.saturating_add(if s < 0 { -1 } else { 1 }) / 2;
            sum = sum.saturating_add(*r);
        }
        // s_i = (r_f + r_r) share / r_i in Q16: sum < 2^19, share <= 2^24
        let num = i64::from(sum).saturating_mul(KEPT_SHARE_Q24);
        for (i, (s, r)) in cal.scale_q16.iter_mut().zip(range).enumerate() {
            if i == VERTICAL {
                continue;
            }
            let q = div_round(num, i64::from(r) << 8).ok_or(CalibrationError::Degenerate { axis: i as u8 })?;
            *s = i32::try_from(q).map_err(|_| CalibrationError::Degenerate { axis: i as u8 })?;
        }
        Ok(cal)
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
