//! The tracker's local re-searches: a sensor that keeps disagreeing with
//! the best hypothesis seeds new ones that take its side (see the module
//! docs of [`super`], "No teleports").

use super::constants::{P_MAX, P_RESEARCH, R_COMPASS, SPAWN_Q8};
use super::covariance::{BIAS, T, X, Y};
use super::predict::Filter;
use super::{Estimator, Sensor, Update};
#[allow(unused_imports)] // the docs' links
use crate::config::estimator as cfg;
use crate::math::{Angle, Coord, Length};
use crate::model::measurement::LidarId;

/// What a lidar reading did to the best hypothesis, kept for a re-search.
struct Disagreement {
    which: LidarId,
    distance: Length,
}

impl Estimator {
    /// A local re-search for a lidar that keeps disagreeing: a copy of the
    /// best with its position uncertain (`cfg::RESEARCH_SIGMA_MM` on each
    /// axis, uncorrelated) takes the reading; if even that gate refuses it,
    /// the copy moves along the wall's normal to where the reading puts it.
    #[cold]
    #[inline(never)]
    pub(super) fn research_lidar(&mut self, which: LidarId, distance: Length) {
        let d = Disagreement { which, distance };
        let (arena, bounds, share, lag) = (self.arena, self.bounds, self.spot.share, self.lag);
        let mut h = *self.best_filter();
        for axis in [X, Y] {
            h.p.set(axis, axis, h.p.get(axis, axis).max(P_RESEARCH));
            h.p.decouple(axis);
        }
        let Some(r) = h.lidar_reading(&arena, d.which, d.distance, share, &lag) else { return };
        if h.correct(r.row, r.nu, r.r, &bounds).0.update != Update::Accepted {
            let step = Coord::from_length(Length(if r.toward_high { r.nu } else { r.nu.saturating_neg() }));
            let c = if r.axis == X { &mut h.pose.x } else { &mut h.pose.y };
            *c = Coord(c.0.saturating_add(step.0));
            h.keep_in(&bounds);
            if let Some(r) = h.lidar_reading(&arena, d.which, d.distance, share, &lag) {
                h.correct(r.row, r.nu, r.r, &bounds);
            }
        }
        self.stats_of(Sensor::of(d.which)).researched += 1;
        self.spawn(h);
    }

    /// A local re-search for a compass that keeps disagreeing: either the
    /// heading is lost (a copy with the heading as uncertain as kept and the
    /// position by `cfg::RESEARCH_SIGMA_MM`, taking the reading) or the compass's bias moved (a copy with the bias as
    /// uncertain, taking it). The lidars decide between them and the best.
    #[cold]
    #[inline(never)]
    pub(super) fn research_compass(&mut self, heading: Angle) {
        let bounds = self.bounds;
        for state in [T, BIAS] {
            let mut h = *self.best_filter();
            let (row, nu) = h.compass_reading(heading);
            // at the cap (57 degrees one sigma) the gate passes half a turn:
            // the correction takes the reading
            h.p.set(state, state, P_MAX);
            h.p.decouple(state);
            if state == T {
                // what lost the heading (a held turn, the skid) moved the
                // position too: the lidars then place it afresh
                for axis in [X, Y] {
                    h.p.set(axis, axis, h.p.get(axis, axis).max(P_RESEARCH));
                    h.p.decouple(axis);
                }
            }
            h.correct(row, nu, R_COMPASS, &bounds);
            self.spawn(h);
        }
        self.stats.compass.researched += 1;
    }

    /// Adds `h` behind the best by [`cfg::SPAWN_COST`], in a free slot or in
    /// place of the costliest other hypothesis.
    fn spawn(&mut self, h: Filter) {
        let cost = self.costs.get(self.best).copied().unwrap_or(0).saturating_add(SPAWN_Q8);
        let slot = if self.live < self.hyps.len() {
            self.live += 1;
            self.live - 1
        } else {
            let best = self.best;
            let worst = self.costs.iter().enumerate().filter(|&(i, _)| i != best).max_by_key(|&(_, c)| *c);
            match worst {
                Some((i, _)) => i,
                None => return,
            }
        };
        if let (Some(f), Some(c), Some(id)) =
            (self.hyps.get_mut(slot), self.costs.get_mut(slot), self.ids.get_mut(slot))
        {
            (*f, *c, *id) = (h, cost, self.next_id);
            self.next_id = self.next_id.wrapping_add(1);
        }
        // a new hypothesis is weighed on every sensor's next reading
        self.evidence = super::EvidenceSet::FRESH;
        self.stats.spawned = self.stats.spawned.saturating_add(1);
    }
}
