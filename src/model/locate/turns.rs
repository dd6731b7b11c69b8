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

/// One pair of readings during a turn: the tick it came at (counted from
/// the turn's start) and each lidar's distance, whole mm (0: none).
#[derive(Clone, Copy, PartialEq, Eq, Debug, Default)]
pub struct TurnSample {
    pub tick: u16,
    pub front_mm: u16,
    pub right_mm: u16,
}

impl TurnSample {
    /// A lidar's distance in this sample, if it gave one.
    pub fn distance(&self, id: LidarId) -> Option<Length> {
        let mm = match id {
            LidarId::Front => self.front_mm,
            LidarId::Right => self.right_mm,
        };
        (mm != 0).then(|| Length::from_mm(i32::from(mm)))
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
        let mut pair = self.pending.unwrap_or(TurnSample { tick, ..TurnSample::default() });
        if pair.distance(id).is_some() {
            self.close(pair);
            pair = TurnSample { tick, ..TurnSample::default() };
        }
        match id {
            LidarId::Front => pair.front_mm = mm,
            LidarId::Right => pair.right_mm = mm,
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
        assert_eq!(s[0], TurnSample { tick: 2, front_mm: 300, right_mm: 200 });
        assert_eq!(s[1], TurnSample { tick: 5, front_mm: 310, right_mm: 0 });
        assert_eq!(s[2].distance(LidarId::Front), Some(mm(320)));
        assert_eq!(s[2].distance(LidarId::Right), None);
    }

    #[test]
    fn a_longer_turn_keeps_readings_spread_over_all_of_it() {
        let mut t = Turn::new(false, 3);
        for k in 0..30u16 {
            t.push(LidarId::Front, 3 * k, mm(100 + i32::from(k)));
        }
        t.end(99);
        let ticks: Vec<u16> = t.samples().iter().map(|s| s.tick).collect();
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
