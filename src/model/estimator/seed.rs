//! Where the estimator starts: a typed pose, or a localization's fix as
//! one hypothesis per place the readings fit (see the module docs of
//! [`super`]).

use super::constants::{CATCH_UP_STANDING_Q16, P_MAX, R_COMPASS};
use super::covariance::{T, X, Y};
use super::predict::Filter;
use super::{Estimator, EvidenceSet, Seed, Tracking};
use crate::config::estimator as cfg;
use crate::math::Length;
use crate::model::state::Pose;

impl Estimator {
    /// Forgets everything but the counts, the learned pivot and lidar spot
    /// too (a typed `pose` starts over: the robot may be on another floor,
    /// in another box): one hypothesis at `pose` with the config's initial
    /// uncertainty, `Unknown`.
    pub fn reset(&mut self, pose: Pose) {
        self.pivot = super::pivot::Pivot::START;
        self.spot = super::spot::Spot::START;
        self.lose_place(pose);
    }

    /// The place is lost (a localization failed), the robot is the same:
    /// as [`Estimator::reset`] at `pose`, keeping the learned pivot and
    /// lidar spot.
    pub fn lose_place(&mut self, pose: Pose) {
        let mut f = Filter::new(pose);
        f.keep_in(&self.bounds);
        self.start(&[(f, 0)], Tracking::Unknown);
    }

    /// Forgets everything but the counts and starts at a localization's
    /// fix ([`crate::model::locate`]): one hypothesis per place the
    /// readings fit (its clusters, never their mean), each with its spread
    /// and weight; a fix of one place is one seed, its pose and position
    /// uncertainty. The heading's uncertainty is the compass's.
    pub fn start_at(&mut self, fix: &crate::model::locate::Fix) {
        let whole = Seed { pose: fix.pose, sigma_x: fix.sigma_x, sigma_y: fix.sigma_y, weight: 1 };
        let mut seeds = [whole; cfg::MAX_HYPOTHESES];
        let clusters = fix.clusters();
        if clusters.len() < 2 {
            self.seed(&[whole]);
            return;
        }
        for (seed, c) in seeds.iter_mut().zip(clusters) {
            *seed = Seed { pose: fix.pose_of(c), sigma_x: c.sigma_x, sigma_y: c.sigma_y, weight: c.weight };
        }
        self.seed(seeds.get(..clusters.len().min(cfg::MAX_HYPOTHESES)).unwrap_or(&[whole]));
    }

    /// Forgets everything but the counts and starts from up to
    /// [`cfg::MAX_HYPOTHESES`] seeds (a localization's clusters; the rest
    /// are ignored). With no seed nothing changes. `Located` when one seed
    /// outweighs the others by [`cfg::DOMINATE_COST`], else `Ambiguous`.
    pub fn seed(&mut self, seeds: &[Seed]) {
        // sigma in mm Q16 -> variance Q12 mm^2: (s >> 8)^2 is Q16 mm^2, >> 4;
        // capped at the largest variance kept
        let var = |s: Length| {
            let q8 = i64::from(s.0 >> 8);
            i32::try_from((q8 * q8) >> 4).unwrap_or(P_MAX).min(P_MAX)
        };
        // a weight's cost: 2 ln(w_max / w) ~ 2 ln 2 per bit (Q8: 355)
        let bits = |w: u32| 32 - w.max(1).leading_zeros() as i32;
        let top = seeds.iter().map(|s| bits(s.weight)).max().unwrap_or(0);
        if seeds.is_empty() {
            return;
        }
        // written in place (not built beside the hypotheses and copied: four
        // filters are 1.2 kB on the robot's stack, on its deepest call,
        // `cargo fw-image`'s stack check)
        let mut n = 0;
        for ((h, c), s) in self.hyps.iter_mut().zip(self.costs.iter_mut()).zip(seeds.iter()) {
            *h = Filter::new(s.pose);
            h.p.set(X, X, var(s.sigma_x));
            h.p.set(Y, Y, var(s.sigma_y));
            h.p.set(T, T, R_COMPASS);
            h.p.condition();
            h.keep_in(&self.bounds);
            *c = (top - bits(s.weight)).saturating_mul(355);
            n += 1;
        }
        self.started(n, Tracking::Located);
    }

    fn start(&mut self, hyps: &[(Filter, i32)], tracking: Tracking) {
        for ((h, c), (f, cost)) in self.hyps.iter_mut().zip(self.costs.iter_mut()).zip(hyps.iter()) {
            (*h, *c) = (*f, *cost);
        }
        self.started(hyps.len(), tracking);
    }

    /// The first `live` hypotheses and their costs are set: each a new id,
    /// and the tracker starts over from them.
    fn started(&mut self, live: usize, tracking: Tracking) {
        self.pivot.interrupt();
        for id in self.ids.iter_mut().take(live) {
            *id = self.next_id;
            self.next_id = self.next_id.wrapping_add(1);
        }
        self.live = live.clamp(1, cfg::MAX_HYPOTHESES);
        self.tracking = tracking;
        self.evidence = EvidenceSet::FRESH;
        self.slack = CATCH_UP_STANDING_Q16;
        self.standing = true;
        // the reported pose starts at the best seed (the cheapest)
        self.best = self.costs.iter().take(self.live).enumerate().min_by_key(|&(_, c)| *c).map_or(0, |(i, _)| i);
        self.reported = self.best_filter().pose;
        self.settle();
    }
}
