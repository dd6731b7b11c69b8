//! The multi-hypothesis tracker: every reading corrects the leader and one
//! other hypothesis in turn and weighs that one against the leader (see
//! `Estimator::weigh`); the weak are pruned, near twins merged; a sensor that
//! keeps disagreeing with the best while the robot moves seeds a new
//! hypothesis that takes its side (a local re-search); the reported pose
//! follows the best only while it dominates, and then at a bounded pace
//! (see the module docs of [`super`], "No teleports").

use super::constants::{
    CATCH_UP_MAX_Q16, CATCH_UP_PER_MM_Q16, CATCH_UP_PER_US, CATCH_UP_STANDING_Q16, DOMINATE_Q8, EVIDENCE_PERIOD_US,
    EVIDENCE_Q16, MERGE_LSB, MERGE_Q16, OUTLIER_COST_Q8, PRUNE_Q8,
};
use super::covariance::BIAS;
use super::light::Shared;
use super::predict::Filter;
use super::update::Outcome;
use super::{Estimator, Sensor, Tracking, Update};
use crate::config::estimator as cfg;
use crate::math::{mul_hi, Angle, Coord, Dt, Length};
use crate::model::actuator::Motion;
use crate::model::measurement::LidarId;
use crate::model::state::advance_about;

/// The travel a turn counts as, mm per radian (its arc at 100 mm), as a
/// factor on angle LSB for `mul_hi`: 100 * 2 pi * 2^16 (Q16 mm) per 2^32 LSB
/// times 2^32 / 2^6 (the `<< 6` after): 100 2 pi 2^10.
const TURN_TRAVEL: i32 = 643_398;

/// One sensor's evidence: the odometer and clock when its last reading counted, and
/// its counted disagreements with the best hypothesis in a row.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug, Default)]
pub(super) struct Evidence {
    pub counted_at: i32,
    /// The estimator's clock then, us.
    pub counted_us: u32,
    pub fresh: bool,
    pub disagreements: u8,
}

impl Estimator {
    /// Live hypotheses and their costs.
    pub(super) fn live_mut(&mut self) -> impl Iterator<Item = (&mut Filter, &mut i32)> {
        self.hyps.iter_mut().zip(self.costs.iter_mut()).take(self.live)
    }

    pub(super) fn best_filter(&self) -> &Filter {
        self.hyps.get(self.best).unwrap_or(&self.hyps[0])
    }

    /// Moves every hypothesis and the reported pose by `motion` for `dt`:
    /// the leader by its whole filter, the others by its scaled motion on
    /// their pose blocks (`light`).
    pub(super) fn predict_all(&mut self, motion: Motion, dt: Dt) {
        let (bounds, best) = (self.bounds, self.best);
        let scaled = self.best_filter().scales.apply(motion);
        let (turning, theta, leader) =
            (matches!(motion, Motion::Turn(_)), self.best_filter().pose.theta, self.best_id());
        let located = self.tracking == Tracking::Located;
        self.pivot.step(turning, theta, leader, self.clock_us, located);
        let pivot = self.pivot.turning;
        self.lag.follow(scaled);
        let shared =
            if self.live > 1 { Some(Shared::of(self.best_filter(), motion, scaled, dt, &pivot)) } else { None };
        for (i, (h, _)) in self.live_mut().enumerate() {
            match &shared {
                Some(s) if i != best => h.predict_pose(s, dt, &bounds),
                _ => h.predict(motion, scaled, dt, &pivot, &bounds),
            }
        }
        // the travel: |d| for a straight step, the arc at 100 mm for a turn
        let travel = match motion {
            Motion::Stop => 0,
            Motion::Straight(v) => (v.distance_q24(dt) >> 8).wrapping_abs(),
            Motion::Turn(w) => mul_hi((w.rotation(dt).0 .0 as i32).wrapping_abs(), TURN_TRAVEL) << 6,
        };
        self.odometer = self.odometer.wrapping_add(travel);
        self.clock_us = self.clock_us.wrapping_add(dt.as_micros());
        // (while unknown the reported pose is the best's: `follow`)
        if self.tracking != Tracking::Unknown {
            advance_about(&mut self.reported, scaled, dt, pivot.lever);
        }
        if motion == Motion::Stop {
            self.spot.standing();
            if !self.standing {
                self.slack = self.slack.min(CATCH_UP_STANDING_Q16);
                self.standing = true;
            }
        } else {
            self.standing = false;
            let more = mul_hi(travel << 1, CATCH_UP_PER_MM_Q16 << 15)
                .saturating_add((CATCH_UP_PER_US.wrapping_mul(dt.as_micros()) >> 8) as i32);
            self.slack = self.slack.saturating_add(more).min(CATCH_UP_MAX_Q16);
        }
        self.follow();
    }

    /// Whether a reading of `sensor` counts as new evidence (the robot moved
    /// far enough since its last counted one, or long enough passed); if so
    /// it is the last. While
    /// `Unknown` every reading counts: a typed guess does not hold against
    /// the sensors.
    fn counts(&mut self, sensor: Sensor) -> bool {
        let (odometer, clock, unknown) = (self.odometer, self.clock_us, self.tracking == Tracking::Unknown);
        let e = self.evidence_of(sensor);
        let new = unknown
            || e.fresh
            || odometer.wrapping_sub(e.counted_at) >= EVIDENCE_Q16
            || clock.wrapping_sub(e.counted_us) >= EVIDENCE_PERIOD_US;
        if new {
            (e.counted_at, e.counted_us, e.fresh) = (odometer, clock, false);
        }
        new
    }

    fn evidence_of(&mut self, sensor: Sensor) -> &mut Evidence {
        match sensor {
            Sensor::Front => &mut self.evidence.front,
            Sensor::Right => &mut self.evidence.right,
            Sensor::Compass => &mut self.evidence.compass,
        }
    }

    /// A lidar's reading through the leader and one secondary (see
    /// [`Estimator::weigh`]).
    pub(super) fn lidar_all(&mut self, which: LidarId, distance: Length) -> Update {
        let counted = self.counts(Sensor::of(which));
        let (arena, bounds, best, other, lag) = (self.arena, self.bounds, self.best, self.next_secondary(), self.lag);
        let share = self.spot.share;
        let mut moved = (0i64, 0i64);
        let mut spot = None;
        let mut through = |i: usize| -> Option<(Outcome, bool)> {
            let h = self.hyps.get_mut(i)?;
            let Some(r) = h.lidar_reading(&arena, which, distance, share, &lag) else {
                return Some((Outcome::UNUSABLE, false));
            };
            let (outcome, repairs) = if i == best {
                // ... and its innovation the spot's share
                spot = Some((r.nu, r.spread));
                // the leader's correction: what it moved teaches the pivot
                let (x, y) = (h.pose.x.0, h.pose.y.0);
                let done = h.correct(r.row, r.nu, r.r, &bounds);
                moved = (h.pose.x.0.wrapping_sub(x), h.pose.y.0.wrapping_sub(y));
                done
            } else {
                h.correct_pose(r.row, r.nu, r.r, &bounds)
            };
            self.stats.repairs = self.stats.repairs.saturating_add(repairs);
            // a reading no position in the arena gives weighs nothing
            Some((outcome, r.possible))
        };
        let lead = through(best).unwrap_or((Outcome::UNUSABLE, false));
        let second = other.and_then(&mut through);
        let leader = self.best_id();
        self.pivot.moved(leader, moved.0, moved.1);
        // the spot learns from new evidence on a placed estimate (ambiguous
        // too: a share still wrong is what keeps a thin beam's estimate so)
        let learns = counted && self.tracking != Tracking::Unknown;
        if let Some((nu, spread)) = spot.filter(|_| learns) {
            self.spot.observe(nu, spread);
        }
        self.weigh(counted, lead, other.zip(second));
        if self.disagreed(Sensor::of(which), lead.0.update, lead.1 && counted) {
            self.research_lidar(which, distance);
        }
        self.settle();
        lead.0.update
    }

    /// The compass's reading through the leader and one secondary (see
    /// [`Estimator::weigh`]); the secondary reads it with the leader's bias.
    pub(super) fn heading_all(&mut self, heading: Angle) -> Update {
        let counted = self.counts(Sensor::Compass);
        let (bounds, best, other) = (self.bounds, self.best, self.next_secondary());
        let (bias, bias_var) = (self.best_filter().bias, self.best_filter().p.get(BIAS, BIAS));
        let mut repairs = 0u32;
        let mut lead = Outcome::UNUSABLE;
        if let Some(h) = self.hyps.get_mut(best) {
            let rep;
            (lead, rep) = h.update_heading(heading, &bounds);
            repairs = repairs.saturating_add(rep);
        }
        let mut second = None;
        if let Some((i, h)) = other.and_then(|i| Some((i, self.hyps.get_mut(i)?))) {
            let (row, nu, r) = h.compass_reading_pose(heading, bias, bias_var);
            let (o, rep) = h.correct_pose(row, nu, r, &bounds);
            repairs = repairs.saturating_add(rep);
            second = Some((i, (o, true)));
        }
        self.stats.repairs = self.stats.repairs.saturating_add(repairs);
        self.weigh(counted, (lead, true), second);
        if self.disagreed(Sensor::Compass, lead.update, counted) {
            self.research_compass(heading);
        }
        self.settle();
        lead.update
    }

    /// The secondary that weighs the next reading: each in turn (none with
    /// one hypothesis).
    fn next_secondary(&mut self) -> Option<usize> {
        if self.live < 2 {
            return None;
        }
        let mut i = usize::from(self.turn);
        for _ in 0..2 {
            i = if i + 1 >= self.live { 0 } else { i + 1 };
            if i != self.best {
                break;
            }
        }
        self.turn = i as u8;
        Some(i)
    }

    /// Weighs a counted reading. The costs are relative to the leader's
    /// (`settle` keeps the cheapest at 0): a reading moves the secondary
    /// that saw it (`second`: its index, outcome and whether the reading
    /// could come from the arena there, as `lead`'s) by how much worse it
    /// explains the reading than the leader. The secondaries that did not
    /// see it stay where they were against the leader: none wins or loses
    /// by a reading it did not see.
    fn weigh(&mut self, counted: bool, lead: (Outcome, bool), second: Option<(usize, (Outcome, bool))>) {
        let weight = |(o, possible): (Outcome, bool)| {
            // a reading no position in the arena gives weighs nothing
            if counted && (possible || o.update == Update::Accepted) {
                weight_of(o)
            } else {
                0
            }
        };
        if let Some((i, seen)) = second {
            if let Some(c) = self.costs.get_mut(i) {
                *c = c.saturating_add(weight(seen)).saturating_sub(weight(lead));
            }
        }
    }

    /// Counts a disagreement of `sensor` with the best hypothesis (only
    /// readings that count as new evidence and could come from the arena:
    /// `counts`); true when the run reaches [`cfg::RESEARCH_AFTER`] (and
    /// restarts it), or at once for a standing robot (its one piece of
    /// evidence until it moves: the new hypotheses are weighed on every
    /// sensor's next reading, and a spurious reading's is refuted there).
    fn disagreed(&mut self, sensor: Sensor, result: Update, counts: bool) -> bool {
        let standing = self.standing;
        let e = self.evidence_of(sensor);
        match result {
            Update::Accepted => e.disagreements = 0,
            Update::Outlier if counts && standing => e.disagreements = cfg::RESEARCH_AFTER,
            Update::Outlier if counts => e.disagreements = e.disagreements.saturating_add(1),
            _ => {}
        }
        if e.disagreements >= cfg::RESEARCH_AFTER {
            e.disagreements = 0;
            true
        } else {
            false
        }
    }

    /// After a correction: costs relative to the best, the weak pruned, near
    /// twins merged, the tracking state, and the reported pose's catch-up.
    pub(super) fn settle(&mut self) {
        // the cheapest (the first of equals) leads; costs relative to it
        let (mut best, mut min) = (0, i32::MAX);
        for (i, &c) in self.costs.iter().take(self.live).enumerate() {
            if c < min {
                (best, min) = (i, c);
            }
        }
        for c in self.costs.iter_mut().take(self.live) {
            *c = c.saturating_sub(min);
        }
        self.lead(best);
        // the weak pruned, the costlier of twins (the later of equals)
        // merged: never the leader, so its whole filter stays
        let mut i = 0;
        while i < self.live {
            let cost = self.cost(i);
            // (the costs first: each pair's position is compared once)
            let twin = i != self.best
                && (0..self.live)
                    .any(|j| j != i && self.cost(j) <= cost && (self.cost(j) < cost || j < i) && self.twins(i, j));
            if cost > PRUNE_Q8 || twin {
                self.remove(i);
            } else {
                i += 1;
            }
        }
        let best = self.best;
        let second = (0..self.live).filter(|&i| i != best).map(|i| self.cost(i)).min();
        let dominant = second.is_none_or(|c| c.saturating_sub(self.cost(best)) >= DOMINATE_Q8);
        self.dominant = dominant;
        let was = self.tracking;
        if was == Tracking::Unknown && dominant {
            // the reported pose was the best's until now: it stays so
            let best = self.best;
            if let Some(h) = self.hyps.get(best) {
                self.reported.take(&h.pose);
            }
        }
        let unknown = was == Tracking::Unknown && dominant && !self.settled();
        self.tracking = if unknown { Tracking::Unknown } else { Tracking::Ambiguous };
        self.follow();
        if !unknown && dominant && self.caught_up() {
            self.tracking = Tracking::Located;
        }
    }

    /// Hypothesis `new` leads: if it did not, it takes the old leader's
    /// scales and bias (`Filter::take_over`).
    fn lead(&mut self, new: usize) {
        if new != self.best {
            let old = *self.best_filter();
            if let Some(h) = self.hyps.get_mut(new) {
                h.take_over(&old);
            }
            self.best = new;
        }
    }

    fn cost(&self, i: usize) -> i32 {
        self.costs.get(i).copied().unwrap_or(i32::MAX)
    }

    /// Two hypotheses within [`cfg::MERGE_MM`] on each axis and
    /// [`cfg::MERGE_DEG`] in heading.
    fn twins(&self, i: usize, j: usize) -> bool {
        let (Some(a), Some(b)) = (self.hyps.get(i), self.hyps.get(j)) else { return false };
        let near = |u: Coord, v: Coord| (u.0.wrapping_sub(v.0) >> 16).unsigned_abs() < MERGE_Q16 as u64;
        near(a.pose.x, b.pose.x)
            && near(a.pose.y, b.pose.y)
            && a.pose.theta.diff(b.pose.theta).unsigned_abs() < MERGE_LSB as u32
    }

    fn remove(&mut self, i: usize) {
        let last = self.live.saturating_sub(1);
        if self.live <= 1 || i > last || last >= self.hyps.len() {
            return;
        }
        self.hyps.swap(i, last);
        self.costs.swap(i, last);
        self.ids.swap(i, last);
        self.live = last;
        if self.best == last {
            self.best = i;
        }
    }
}

/// A reading's weight: its normalised squared innovation when accepted,
/// [`cfg::OUTLIER_COST`] when gated out, nothing when unusable.
fn weight_of(o: Outcome) -> i32 {
    match o.update {
        Update::Accepted => o.nis_q8,
        Update::Outlier => OUTLIER_COST_Q8,
        Update::Unusable => 0,
    }
}
