//! The on-board log: telemetry rows kept in RAM while a mission runs, for
//! `dump` to send afterwards in the telemetry CSV format.
//!
//! A [`LogRow`] is a [`TelemetryRow`] packed into 60 bytes (a row of text
//! is about 110): every column is kept exactly except the corrected
//! magnetometer field, kept to +-32767 counts (the earth's field is a few
//! hundred), and the fault counters, kept to 65535 each. [`RingLog`] holds
//! the newest `N` rows: when it is full the oldest goes and is counted as
//! dropped. The firmware keeps its log in a static, so that its size counts
//! in the image's DRAM budget; the control loop reaches it through
//! [`RowLog`]. At a mission's end the loop keeps the log in flash
//! (`control::settings::kept_log`), a row as [`ROW_WORDS`] words
//! ([`LogRow::to_words`]).

use crate::control::protocol::{FaultCounters, TelemetryRow};
use crate::model::estimator::Tracking;
use crate::model::MotionKind;

/// Which optional columns a [`LogRow`] has (bits of `packed`, above the
/// heading's 19 bits and the motion's 3; the estimator's state is the
/// two above them).
const FRONT_RAW: u32 = 1 << 22;
const FRONT_D: u32 = 1 << 23;
const RIGHT_RAW: u32 = 1 << 24;
const RIGHT_D: u32 = 1 << 25;
const COMPASS: u32 = 1 << 26;
const HEADING_BITS: u32 = (1 << 19) - 1; // 360_000 < 2^19
/// The estimator's state, two bits from here.
const TRACKING_SHIFT: u32 = 27;

/// Words of a [`LogRow`] in flash: five 32-bit columns and twenty halves.
pub const ROW_WORDS: usize = 15;

/// One telemetry row, packed (see the module docs).
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub struct LogRow {
    t_ms: u32,
    x_dmm: i32,
    y_dmm: i32,
    /// Heading (mdeg, 19 bits), motion kind (3 bits), presence flags.
    packed: u32,
    compass_mdeg: u32,
    /// The speed (mm/s) or turn rate (mrad/s) of the motion.
    rate: i16,
    left_cmd_centi: u16,
    right_cmd_centi: u16,
    front_raw_mm: u16,
    front_dmm: i16,
    right_raw_mm: u16,
    right_dmm: i16,
    mag_raw: [i16; 3],
    mag_field: [i16; 3],
    faults: [u16; 6],
}

impl LogRow {
    pub const EMPTY: LogRow = LogRow {
        t_ms: 0,
        x_dmm: 0,
        y_dmm: 0,
        packed: 0,
        compass_mdeg: 0,
        rate: 0,
        left_cmd_centi: 0,
        right_cmd_centi: 0,
        front_raw_mm: 0,
        front_dmm: 0,
        right_raw_mm: 0,
        right_dmm: 0,
        mag_raw: [0; 3],
        mag_field: [0; 3],
        faults: [0; 6],
    };

    pub fn pack(r: &TelemetryRow) -> LogRow {
        let kind = match r.motion {
            MotionKind::Stop => 0,
            MotionKind::Forward => 1,
            MotionKind::Backward => 2,
            MotionKind::Cw => 3,
            MotionKind::Ccw => 4,
        };
        let rate = if matches!(r.motion, MotionKind::Cw | MotionKind::Ccw) { r.w_mrad_s } else { r.v_mm_s };
        let tracking = match r.tracking {
            Tracking::Located => 0,
            Tracking::Ambiguous => 1,
            Tracking::Unknown => 2,
        };
        let flag = |present: bool, bit: u32| if present { bit } else { 0 };
        let f = &r.faults;
        LogRow {
            t_ms: r.t_ms,
            x_dmm: r.x_dmm,
            y_dmm: r.y_dmm,
            packed: (r.heading_mdeg & HEADING_BITS)
                | kind << 19
                | flag(r.front_raw_mm.is_some(), FRONT_RAW)
                | flag(r.front_dmm.is_some(), FRONT_D)
                | flag(r.right_raw_mm.is_some(), RIGHT_RAW)
                | flag(r.right_dmm.is_some(), RIGHT_D)
                | flag(r.mag_raw.is_some(), COMPASS)
                | tracking << TRACKING_SHIFT,
            compass_mdeg: r.compass_mdeg.unwrap_or(0),
            rate: sat16(rate),
            left_cmd_centi: r.left_cmd_centi.min(u32::from(u16::MAX)) as u16,
            right_cmd_centi: r.right_cmd_centi.min(u32::from(u16::MAX)) as u16,
            front_raw_mm: r.front_raw_mm.unwrap_or(0),
            front_dmm: sat16(r.front_dmm.unwrap_or(0)),
            right_raw_mm: r.right_raw_mm.unwrap_or(0),
            right_dmm: sat16(r.right_dmm.unwrap_or(0)),
            mag_raw: r.mag_raw.unwrap_or([0; 3]),
            mag_field: r.mag_field.unwrap_or([0; 3]).map(sat16),
            faults: [f.bus, f.timeout, f.missing, f.bad_sample, f.rejected_outliers, f.overruns]
                .map(|n| n.min(u32::from(u16::MAX)) as u16),
        }
    }

    pub fn unpack(&self) -> TelemetryRow {
        let has = |bit: u32| self.packed & bit != 0;
        let kind = match (self.packed >> 19) & 7 {
            1 => MotionKind::Forward,
            2 => MotionKind::Backward,
            3 => MotionKind::Cw,
            4 => MotionKind::Ccw,
            _ => MotionKind::Stop,
        };
        let turning = matches!(kind, MotionKind::Cw | MotionKind::Ccw);
        let rate = i32::from(self.rate);
        let [bus, timeout, missing, bad_sample, rejected_outliers, overruns] = self.faults.map(u32::from);
        TelemetryRow {
            t_ms: self.t_ms,
            x_dmm: self.x_dmm,
            y_dmm: self.y_dmm,
            heading_mdeg: self.packed & HEADING_BITS,
            motion: kind,
            v_mm_s: if turning { 0 } else { rate },
            w_mrad_s: if turning { rate } else { 0 },
            left_cmd_centi: u32::from(self.left_cmd_centi),
            right_cmd_centi: u32::from(self.right_cmd_centi),
            front_raw_mm: has(FRONT_RAW).then_some(self.front_raw_mm),
            front_dmm: has(FRONT_D).then_some(i32::from(self.front_dmm)),
            right_raw_mm: has(RIGHT_RAW).then_some(self.right_raw_mm),
            right_dmm: has(RIGHT_D).then_some(i32::from(self.right_dmm)),
            mag_raw: has(COMPASS).then_some(self.mag_raw),
            mag_field: has(COMPASS).then_some(self.mag_field.map(i32::from)),
            compass_mdeg: has(COMPASS).then_some(self.compass_mdeg),
            faults: FaultCounters { bus, timeout, missing, bad_sample, rejected_outliers, overruns },
            tracking: match (self.packed >> TRACKING_SHIFT) & 3 {
                0 => Tracking::Located,
                1 => Tracking::Ambiguous,
                _ => Tracking::Unknown,
            },
        }
    }
}

impl LogRow {
    /// The row as words for flash: the 32-bit columns, then the 16-bit
    /// ones two to a word, low half first.
    pub fn to_words(&self) -> [u32; ROW_WORDS] {
        let [m0, m1, m2] = self.mag_raw.map(|v| v as u16);
        let [f0, f1, f2] = self.mag_field.map(|v| v as u16);
        let [q0, q1, q2, q3, q4, q5] = self.faults;
        let halves = [
            self.rate as u16,
            self.left_cmd_centi,
            self.right_cmd_centi,
            self.front_raw_mm,
            self.front_dmm as u16,
            self.right_raw_mm,
            self.right_dmm as u16,
            m0,
            m1,
            m2,
            f0,
            f1,
            f2,
            q0,
            q1,
            q2,
            q3,
            q4,
            q5,
            0,
        ];
        let mut words = [0u32; ROW_WORDS];
        let whole = [self.t_ms, self.x_dmm as u32, self.y_dmm as u32, self.packed, self.compass_mdeg];
        let paired = halves.chunks_exact(2).map(|p| match *p {
            [lo, hi] => u32::from(lo) | u32::from(hi) << 16,
            _ => 0, // chunks_exact(2) gives pairs only
        });
        for (slot, w) in words.iter_mut().zip(whole.into_iter().chain(paired)) {
            *slot = w;
        }
        words
    }

    /// The row [`LogRow::to_words`] wrote (any words give a row: the
    /// kept log's CRC is what says they are one).
    pub fn from_words(words: &[u32; ROW_WORDS]) -> LogRow {
        let [t_ms, x, y, packed, compass_mdeg, pairs @ ..] = *words;
        let mut h = [0u16; 20];
        for (half, pair) in h.chunks_exact_mut(2).zip(pairs) {
            if let [lo, hi] = half {
                *lo = pair as u16;
                *hi = (pair >> 16) as u16;
            }
        }
        let [rate, left, right, front_raw, front_d, right_raw, right_d, m0, m1, m2, f0, f1, f2, q0, q1, q2, q3, q4, q5, _] =
            h;
        LogRow {
            t_ms,
            x_dmm: x as i32,
            y_dmm: y as i32,
            packed,
            compass_mdeg,
            rate: rate as i16,
            left_cmd_centi: left,
            right_cmd_centi: right,
            front_raw_mm: front_raw,
            front_dmm: front_d as i16,
            right_raw_mm: right_raw,
            right_dmm: right_d as i16,
            mag_raw: [m0, m1, m2].map(|v| v as i16),
            mag_field: [f0, f1, f2].map(|v| v as i16),
            faults: [q0, q1, q2, q3, q4, q5],
        }
    }
}

fn sat16(v: i32) -> i16 {
    v.clamp(i32::from(i16::MIN), i32::from(i16::MAX)) as i16
}

/// Where the control loop keeps its log rows.
pub trait RowLog {
    /// Forgets every row and the dropped count.
    fn clear(&mut self);
    /// Adds a row (the oldest goes when full, and is counted).
    fn push(&mut self, row: &TelemetryRow);
    /// Rows held.
    fn len(&self) -> usize;
    fn is_empty(&self) -> bool {
        self.len() == 0
    }
    /// Row `i`, oldest first.
    fn row(&self, i: usize) -> Option<TelemetryRow>;
    /// Rows lost since the last `clear` because the log was full.
    fn dropped(&self) -> u32;
}

/// A ring of the newest `N` rows.
#[derive(Clone, PartialEq, Eq, Debug)]
pub struct RingLog<const N: usize> {
    rows: [LogRow; N],
    /// Index of the oldest row.
    first: usize,
    len: usize,
    dropped: u32,
}

impl<const N: usize> Default for RingLog<N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize> RingLog<N> {
    pub const fn new() -> Self {
        RingLog { rows: [LogRow::EMPTY; N], first: 0, len: 0, dropped: 0 }
    }
    /// Index of the `i`-th oldest row in `rows` (`i < N`).
    fn slot(&self, i: usize) -> usize {
        let j = self.first.saturating_add(i); // both < N
        if j >= N {
            j.wrapping_sub(N)
        } else {
            j
        }
    }
}

impl<const N: usize> RowLog for RingLog<N> {
    fn clear(&mut self) {
        self.first = 0;
        self.len = 0;
        self.dropped = 0;
    }
    fn push(&mut self, row: &TelemetryRow) {
        if N == 0 {
            self.dropped = self.dropped.saturating_add(1);
            return;
        }
        // the next free slot, or (full) the oldest row's
        let at = if self.len < N { self.slot(self.len) } else { self.first };
        if let Some(slot) = self.rows.get_mut(at) {
            *slot = LogRow::pack(row);
        }
        if self.len < N {
            self.len = self.len.saturating_add(1);
        } else {
            self.first = self.slot(1);
            self.dropped = self.dropped.saturating_add(1);
        }
    }
    fn len(&self) -> usize {
        self.len
    }
    fn row(&self, i: usize) -> Option<TelemetryRow> {
        if i >= self.len {
            return None;
        }
        self.rows.get(self.slot(i)).map(LogRow::unpack)
    }
    fn dropped(&self) -> u32 {
        self.dropped
    }
}

impl<T: RowLog> RowLog for &mut T {
    fn clear(&mut self) {
        (**self).clear()
    }
    fn push(&mut self, row: &TelemetryRow) {
        (**self).push(row)
    }
    fn len(&self) -> usize {
        (**self).len()
    }
    fn row(&self, i: usize) -> Option<TelemetryRow> {
        (**self).row(i)
    }
    fn dropped(&self) -> u32 {
        (**self).dropped()
    }
}

#[cfg(test)]
#[allow(clippy::restriction)] // test code: a panic fails the test
mod tests {
    use super::*;

    fn row(t_ms: u32) -> TelemetryRow {
        TelemetryRow {
            t_ms,
            x_dmm: -500,
            y_dmm: 81_250,
            heading_mdeg: 359_999,
            motion: MotionKind::Ccw,
            v_mm_s: 0,
            w_mrad_s: -2_400,
            left_cmd_centi: 6_512,
            right_cmd_centi: 18_000,
            front_raw_mm: Some(8_190),
            front_dmm: None,
            right_raw_mm: Some(412),
            right_dmm: Some(-349),
            mag_raw: Some([-32_768, 0, 32_767]),
            mag_field: Some([-66, 4, 300]),
            compass_mdeg: Some(353_117),
            faults: FaultCounters {
                bus: 1,
                timeout: 2,
                missing: 3,
                bad_sample: 4,
                rejected_outliers: 5,
                overruns: 65_535,
            },
            tracking: Tracking::Ambiguous,
        }
    }

    #[test]
    fn a_row_is_kept_exactly() {
        let r = row(1200);
        assert_eq!(LogRow::pack(&r).unpack(), r);
        let mut fwd = r;
        fwd.motion = MotionKind::Forward;
        fwd.v_mm_s = 130;
        fwd.w_mrad_s = 0;
        fwd.mag_raw = None;
        fwd.mag_field = None;
        fwd.compass_mdeg = None;
        fwd.front_raw_mm = None;
        assert_eq!(LogRow::pack(&fwd).unpack(), fwd);
        assert_eq!(core::mem::size_of::<LogRow>(), 60);
        for packed in [LogRow::pack(&r), LogRow::pack(&fwd)] {
            assert_eq!(LogRow::from_words(&packed.to_words()), packed);
        }
    }

    #[test]
    fn the_ring_keeps_the_newest_and_counts_the_dropped() {
        let mut log = RingLog::<4>::new();
        for t in 0..3 {
            log.push(&row(t));
        }
        assert_eq!((log.len(), log.dropped()), (3, 0));
        assert_eq!((0..3).map(|i| log.row(i).unwrap().t_ms).collect::<std::vec::Vec<_>>(), [0, 1, 2]);
        for t in 3..10 {
            log.push(&row(t));
        }
        assert_eq!((log.len(), log.dropped()), (4, 6));
        assert_eq!((0..4).map(|i| log.row(i).unwrap().t_ms).collect::<std::vec::Vec<_>>(), [6, 7, 8, 9]);
        assert_eq!(log.row(4), None);
        log.clear();
        assert_eq!((log.len(), log.dropped(), log.row(0)), (0, 0, None));
        let mut none = RingLog::<0>::new();
        none.push(&row(1));
        assert_eq!((none.len(), none.dropped()), (0, 1));
    }
}
