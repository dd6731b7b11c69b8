//! The lidars' readings taken while turning in place between two views
//! (issue #29): each at a heading between the two views', in proportion
//! to the ticks the turn had run when it came. The search scores the views
//! only; the refinement of its fix (`tests/localization/refine.rs`, the
//! f64 reference) explains these too, about ten a turn per lidar.

use crate::config::locate as cfg;
use crate::math::Length;
use crate::model::measurement::LidarId;

/// Readings kept a turn, per lidar pair: a lidar's period is 3.3 ticks, so
/// a turn of one [`cfg::TURN_DEG`] step (32 ticks) brings about ten;
/// a longer turn keeps every second, third, ... pair ([`Turn::push`]).
pub const SAMPLES: usize = cfg::TURN_SAMPLES;

/// One pair of readings during a turn: each lidar's distance, whole mm
/// (0: none), and the tick it came at (counted from the turn's start).
/// The two lidars range on their own clocks, so a pair's second reading
/// comes up to a lidar period (3.3 ticks, 4.6 degrees of a turn) after
/// its first: each keeps its own tick.
#[derive(Clone, Copy, PartialEq, Eq, Debug, Default)]
pub struct TurnSample {
    pub front_tick: u16,
    pub front_mm: u16,
    pub right_tick: u16,
    pub right_mm: u16,
}

impl TurnSample {
    /// A lidar's reading in this sample, if it gave one: the tick it came
    /// at, and its distance.
    pub fn reading(&self, id: LidarId) -> Option<(u16, Length)> {
        let (tick, mm) = match id {
            LidarId::Front => (self.front_tick, self.front_mm),
            LidarId::Right => (self.right_tick, self.right_mm),
        };
        (mm != 0).then(|| (tick, Length::from_mm(i32::from(mm))))
    }

    /// The tick the pair's first reading came at (the tests' view of which
    /// pairs a turn kept).
    #[cfg(test)]
    pub fn first_tick(&self) -> u16 {
        match (self.front_mm, self.right_mm) {
            (0, _) => self.right_tick,
            (_, 0) => self.front_tick,
            _ => self.front_tick.min(self.right_tick),
        }
    }
}

/// One turn between two views: its way, its ticks, and the readings
/// taken on it.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Turn {
    pub clockwise: bool,
    /// The ticks the turn ran (set when it ends).
    pub ticks: u16,
    samples: heapless::Vec<TurnSample, SAMPLES>,
    /// Readings to skip between kept ones: 1 for a one-step turn, more
    /// for a longer one, so its readings spread over all of it.
    stride: u8,
    /// Readings come so far (kept and skipped).
    seen: u16,
    /// The pair being gathered (a lidar's reading comes on its own tick).
    pending: Option<TurnSample>,
}

impl Turn {
    /// A turn that way of `steps` survey steps, about to start.
    pub fn new(clockwise: bool, steps: u8) -> Turn {
        Turn { clockwise, stride: steps.max(1), ..Turn::default() }
    }

    /// The readings kept, in the order they came.
    pub fn samples(&self) -> &[TurnSample] {
        &self.samples
    }

    /// A lidar's distance at `tick` of the turn. Each lidar's reading joins
    /// the pair under way until that lidar reads again, which closes it.
    pub fn push(&mut self, id: LidarId, tick: u16, d: Length) {
        let mm = d.to_mm().clamp(1, i32::from(u16::MAX)) as u16;
        let mut pair = self.pending.unwrap_or_default();
        if pair.reading(id).is_some() {
            self.close(pair);
            pair = TurnSample::default();
        }
        match id {
            LidarId::Front => (pair.front_tick, pair.front_mm) = (tick, mm),
            LidarId::Right => (pair.right_tick, pair.right_mm) = (tick, mm),
        }
        self.pending = Some(pair);
    }

    /// The turn is over after `ticks` ticks: its last pair is kept.
    pub fn end(&mut self, ticks: u16) {
        self.ticks = ticks;
        if let Some(pair) = self.pending.take() {
            self.close(pair);
        }
    }

    /// The turn's readings say nothing: forgotten.
    pub fn forget(&mut self) {
        self.samples.clear();
        self.pending = None;
    }

    fn close(&mut self, pair: TurnSample) {
        if self.seen % u16::from(self.stride.max(1)) == 0 {
            // a full turn keeps its first readings
            let _ = self.samples.push(pair);
        }
        self.seen = self.seen.saturating_add(1);
    }
}

#[cfg(test)]
#[allow(clippy::indexing_slicing)]
mod tests {
    use super::*;
    use std::vec::Vec;

    fn mm(v: i32) -> Length {
        Length::from_mm(v)
    }

    #[test]
    fn readings_pair_up_in_the_order_they_come() {
        let mut t = Turn::new(true, 1);
        t.push(LidarId::Front, 2, mm(300));
        t.push(LidarId::Right, 3, mm(200));
        t.push(LidarId::Front, 5, mm(310));
        t.push(LidarId::Front, 8, mm(320)); // the right lidar gave none
        t.end(33);
        let s = t.samples();
        assert_eq!(t.ticks, 33);
        assert_eq!(s.len(), 3);
        assert_eq!(s[0], TurnSample { front_tick: 2, front_mm: 300, right_tick: 3, right_mm: 200 });
        assert_eq!(s[1], TurnSample { front_tick: 5, front_mm: 310, right_tick: 0, right_mm: 0 });
        assert_eq!((s[0].first_tick(), s[1].first_tick()), (2, 5));
        assert_eq!(s[2].reading(LidarId::Front), Some((8, mm(320))));
        assert_eq!(s[2].reading(LidarId::Right), None);
    }

    #[test]
    fn a_longer_turn_keeps_readings_spread_over_all_of_it() {
        let mut t = Turn::new(false, 3);
        for k in 0..30u16 {
            t.push(LidarId::Front, 3 * k, mm(100 + i32::from(k)));
        }
        t.end(99);
        let ticks: Vec<u16> = t.samples().iter().map(|s| s.first_tick()).collect();
        assert_eq!(ticks, (0..10).map(|k| 9 * k).collect::<Vec<u16>>());
        // a turn longer than its room keeps its first readings
        let mut t = Turn::new(true, 1);
        for k in 0..40u16 {
            t.push(LidarId::Right, k, mm(100));
        }
        t.end(40);
        assert_eq!(t.samples().len(), SAMPLES);
    }
}
