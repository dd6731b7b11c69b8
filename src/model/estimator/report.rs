//! The reported pose: it follows the leading hypothesis only while that
//! dominates, and then at a bounded pace (see the module docs of
//! [`super`], "No teleports").

use super::constants::{AMBIGUOUS_GAP_Q16, LOCATED_VAR};
use super::covariance::{X, Y};
use super::{Estimator, Tracking};
#[allow(unused_imports)] // the docs' links
use crate::config::estimator as cfg;
use crate::math::Coord;

impl Estimator {
    /// The reported position is within [`cfg::AMBIGUOUS_GAP_MM`] of the best
    /// hypothesis's on each axis.
    pub(super) fn caught_up(&self) -> bool {
        let best = self.best_filter().pose;
        let near = |u: Coord, v: Coord| (u.0.wrapping_sub(v.0) >> 16).unsigned_abs() <= AMBIGUOUS_GAP_Q16 as u64;
        near(self.reported.x, best.x) && near(self.reported.y, best.y)
    }

    /// The best hypothesis's position variances are below the config's
    /// steering limit: an unknown start has become a located one.
    pub(super) fn settled(&self) -> bool {
        let p = &self.best_filter().p;
        let limit = LOCATED_VAR;
        p.get(X, X) <= limit && p.get(Y, Y) <= limit
    }

    /// The reported pose: while the estimate is unknown it is the best's;
    /// while one hypothesis dominates it moves toward it by at most the
    /// slack saved up (per axis); while ambiguous it only dead-reckons.
    pub(super) fn follow(&mut self) {
        // tick bar: the best pose's fields, not a copy of the pose (a memcpy call)
        let (best, best_x, best_y) = (self.best, self.best_filter().pose.x, self.best_filter().pose.y);
        match self.tracking {
            Tracking::Unknown => {
                if let Some(h) = self.hyps.get(best) {
                    self.reported.take(&h.pose);
                }
            }
            Tracking::Ambiguous if !self.dominant => {}
            Tracking::Ambiguous | Tracking::Located => {
                // (max/min, not clamp: clamp's panic for bounds the wrong way
                // round would reach the image)
                let toward = |c: Coord, to: Coord, most: i32| -> i32 {
                    let most = i64::from(most.max(0));
                    (to.0.wrapping_sub(c.0) >> 16).max(-most).min(most) as i32
                };
                let sx = toward(self.reported.x, best_x, self.slack);
                let sy = toward(self.reported.y, best_y, self.slack);
                self.reported.x = Coord(self.reported.x.0.wrapping_add(i64::from(sx) << 16));
                self.reported.y = Coord(self.reported.y.0.wrapping_add(i64::from(sy) << 16));
                self.slack = self.slack.saturating_sub(sx.saturating_abs().max(sy.saturating_abs()));
                let b = &self.best_filter().pose;
                (self.reported.theta, self.reported.theta_frac) = (b.theta, b.theta_frac);
            }
        }
        // a located (or ambiguous) robot is inside the box; a typed pose
        // (unknown) is kept as the hypothesis keeps it
        if self.tracking != Tracking::Unknown {
            let b = self.inside;
            super::predict::clamp_mm(&mut self.reported.x, b.low_mm, b.high_x_mm);
            super::predict::clamp_mm(&mut self.reported.y, b.low_mm, b.high_y_mm);
        }
    }
}
