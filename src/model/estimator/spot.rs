//! Where in its spot a lidar's range comes from, learned from the leader's
//! innovations (issue 29: a beam meeting its wall off square lights a spot
//! along it, and which part of the spot the sensor reports differs from
//! sensor to sensor and surface to surface).
//!
//! The lidar model's prediction is the nearest wall point in the cone
//! (`model::measurement::Beam`): what the lab's real drive shows, "a beam
//! 25 degrees wide that sees the nearest thing in its cone" (the lab 2
//! README). A sensor that reports the spot's centre instead, the beam's
//! axis, reads long past half the cone's incidence: along the wall's
//! normal by `g = (z + setback)(cos_cone - cos_axis)`, the spot's spread
//! ([`crate::model::measurement::Beam::spot_spread`]). The filters predict
//! `share g` of it, `share` learned here between 0 (the cone's nearest
//! point) and 1 (the axis): when `share` is off by `e`, a reading's
//! innovation is about `e g` (and noise, and the pose's error). Batches of
//! [`cfg::SPOT_BATCH`] counted readings give a least-squares sample of
//! `e`, `sum(nu g) / sum(g^2)`, each reading's innovation clamped at twice
//! its spread and glancing readings (spread past
//! `cfg::SPOT_MAX_SPREAD_MM`) left out (a spurious echo must not decide a
//! batch), weighed against the learned share's variance by a scalar
//! Kalman step on the next standing tick (the divisions' cost, see
//! [`Spot::standing`]). The oracle bar it closes in on: told the hard
//! world's thin beam exactly, the tracking's median RMS there went from
//! 31.2 mm to 10.7 (`tests/sim/hard_world.rs`, known start); learned,
//! 16.5.
//!
//! Why not a state of every filter: for the same reason as the pivot's
//! (`pivot`), a column in every correction costs the tick more than its bar
//! leaves, and the share moves slowly: a robot's, not a hypothesis's.

use super::constants::{
    SPOT_MAX_SPREAD_Q3, SPOT_MIN_SPREAD_Q3, SPOT_SAMPLE_VAR, SPOT_SHARE_START, SPOT_START_VAR, SPOT_WALK,
};
use crate::config::estimator as cfg;
use crate::math::div_i64;

/// One in Q30.
const ONE: i32 = 1 << 30;

/// The learned share and the batch it is learning from.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub(super) struct Spot {
    /// From the cone's nearest point (0) to the axis (1), Q30.
    pub share: i32,
    /// Its variance, Q30.
    pub var: i32,
    /// The batch: `sum(nu g)`, `sum(g^2)` and `sum(nu^2)` in 1/64 mm^2
    /// (each reading's `g` in 1/8 mm below 2^11, `nu` within `2 g`, the
    /// config's batch below 2^7 readings: the sums stay below 2^31), and
    /// its readings.
    sum_ng: i32,
    sum_gg: i32,
    sum_nn: i32,
    readings: u16,
    /// Batches learned from.
    pub samples: u16,
}

const _: () = assert!(cfg::SPOT_BATCH > 0 && cfg::SPOT_BATCH < 128);

impl Spot {
    /// The config's starting share and uncertainty.
    pub const START: Spot =
        Spot { share: SPOT_SHARE_START, var: SPOT_START_VAR, sum_ng: 0, sum_gg: 0, sum_nn: 0, readings: 0, samples: 0 };

    /// A counted reading of the leader (the estimate not `Unknown`): its
    /// innovation `nu` with the learned share, and its spot's spread `g`
    /// (both Q16 mm). A reading met square on (a spread below
    /// `cfg::SPOT_MIN_SPREAD_MM`) says nothing about the share, a glancing
    /// one (above `cfg::SPOT_MAX_SPREAD_MM`) too much; a full batch waits
    /// for [`Spot::standing`].
    // tick bar: inlined into the leader's correction
    #[inline(always)]
    pub fn observe(&mut self, nu: i32, g: i32) {
        let g = g >> 13;
        if !(SPOT_MIN_SPREAD_Q3..=SPOT_MAX_SPREAD_Q3).contains(&g) || self.readings >= cfg::SPOT_BATCH {
            return;
        }
        let nu = (nu >> 13).clamp(-2 * g, 2 * g);
        // |nu g|, g^2 and nu^2 below 2^24: a batch's sums below 2^31
        self.sum_ng = self.sum_ng.wrapping_add(nu.wrapping_mul(g));
        self.sum_gg = self.sum_gg.wrapping_add(g.wrapping_mul(g));
        self.sum_nn = self.sum_nn.wrapping_add(nu.wrapping_mul(nu));
        self.readings = self.readings.wrapping_add(1);
    }

    /// The servos stand: a full batch is learned from now, when the tick's
    /// prediction is cheapest (its two divisions, about 1,500 lx106
    /// instructions, would take a moving tick past its bar).
    // tick bar: a compare inlined into every prediction
    #[inline(always)]
    pub fn standing(&mut self) {
        if self.readings >= cfg::SPOT_BATCH {
            self.learn();
        }
    }

    /// The batch's sample `e = sum(nu g) / sum(g^2)` (Q30), with variance
    /// `s^2 / sum(g^2)`, `s^2` the readings' scatter about the sample's
    /// line and at least `cfg::SPOT_SAMPLE_SIGMA_MM^2` (a batch that the
    /// share's line fits badly, a pose's error or an echo, teaches less),
    /// weighed by a scalar Kalman step after the share's random walk; a
    /// new batch starts.
    // tick bar: once a batch, kept out of the standing tick's line
    #[cold]
    #[inline(never)]
    fn learn(&mut self) {
        let (ng, gg, nn, n) = (self.sum_ng, i64::from(self.sum_gg), self.sum_nn, i32::from(self.readings));
        (self.sum_ng, self.sum_gg, self.sum_nn, self.readings) = (0, 0, 0, 0);
        let Some(e) = div_i64(i64::from(ng) << 30, gg) else { return };
        // the residuals' sum of squares, sum(nu^2) - e sum(nu g), over n - 1
        // (1/64 mm^2; e sum(nu g) <= sum(nu^2) by Cauchy-Schwarz)
        let fitted = ((e * i64::from(ng)) >> 30) as i32;
        let scatter = (nn.saturating_sub(fitted) / (n - 1).max(1)).max(SPOT_SAMPLE_VAR);
        // the gain var / (var + scatter / gg) = var gg / (var gg + scatter), Q30
        let var = self.var.saturating_add(SPOT_WALK).min(SPOT_START_VAR);
        let var_gg = (i64::from(var) * gg) >> 30;
        let Some(gain) = div_i64(var_gg << 30, var_gg + i64::from(scatter)) else { return };
        let step = (e * gain) >> 30;
        self.share = (i64::from(self.share) + step).clamp(0, i64::from(ONE)) as i32;
        self.var = (((i64::from(ONE) - gain) * i64::from(var)) >> 30).clamp(1, i64::from(SPOT_START_VAR)) as i32;
        self.samples = self.samples.saturating_add(1);
    }
}

#[cfg(test)]
#[allow(clippy::restriction)] // test code: a panic fails the test
mod tests {
    use super::*;

    fn q16(mm: f64) -> i32 {
        (mm * 65536.0) as i32
    }

    /// A batch of readings each `e` of its spread long samples `e`: when
    /// the servos stand, the share moves toward it by the Kalman gain; a
    /// reading square on (no spread) teaches nothing, and a spurious echo
    /// counts as at most twice its spread.
    #[test]
    fn a_batch_of_long_readings_moves_the_share_by_its_gain() {
        let batch = |e: f64, spread: f64| {
            let mut s = Spot::START;
            for _ in 0..cfg::SPOT_BATCH {
                s.observe(q16(e * spread), q16(spread));
            }
            s.observe(q16(9.0 * spread), q16(spread)); // a full batch takes no more
            s.standing();
            s
        };
        let s = batch(0.8, 30.0);
        let gg = f64::from(cfg::SPOT_BATCH) * 30.0 * 30.0;
        let sample_var = cfg::SPOT_SAMPLE_SIGMA_MM * cfg::SPOT_SAMPLE_SIGMA_MM / gg;
        let var = f64::from(SPOT_START_VAR) / f64::from(ONE);
        let want = cfg::SPOT_SHARE_START + 0.8 * var / (var + sample_var);
        let got = f64::from(s.share) / f64::from(ONE);
        assert!((got - want).abs() < 1e-3, "{got} against {want}");
        assert_eq!(s.samples, 1);
        assert!(f64::from(s.var) / f64::from(ONE) < sample_var * 1.01);
        // square on: no spread, no sample
        assert_eq!(batch(0.8, 0.5), Spot::START);
        // among readings that fit the cone, one echo 200 mm long on a 10 mm
        // spread counts as a share of 2: the batch's sample at most 2/16
        let mut echo = Spot::START;
        for i in 0..cfg::SPOT_BATCH {
            let e = if i == 0 { 20.0 } else { 0.0 };
            echo.observe(q16(e * 10.0), q16(10.0));
        }
        echo.standing();
        let sample = 2.0 / f64::from(cfg::SPOT_BATCH);
        assert!(f64::from(echo.share) / f64::from(ONE) <= sample, "{}", echo.share);
        assert!(echo.share > 0);
        // a glancing reading (its spread past the most) teaches nothing
        assert_eq!(batch(0.8, cfg::SPOT_MAX_SPREAD_MM + 1.0), Spot::START);
        // short readings cannot take the share below the cone's nearest point
        assert_eq!(batch(-1.0, 30.0).share, 0);
    }
}
