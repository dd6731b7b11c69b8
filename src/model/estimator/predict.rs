//! The prediction: the pose moves by the state update, the covariance
//! grows by the motion's noise.

use super::constants::{D_OVER_L_Q31, FLOOR_HEADING, FLOOR_POS, K_DIST, K_DRIFT, K_TURN, K_TURN_POS};
use super::covariance::{add_noise, propagate};
use super::Estimator;
use crate::math::{mul_hi, mul_q30_unsat, Dt};
use crate::model::actuator::Motion;
use crate::model::state::advance;

impl Estimator {
    /// Moves the pose by `motion` held for `dt` and grows the uncertainty.
    pub fn predict(&mut self, motion: Motion, dt: Dt) {
        let p = &mut self.p;
        match motion {
            Motion::Stop => {}
            Motion::Straight(v) => {
                // the heading does not change: the pose's cached sin/cos are
                // those of the step's heading, before and after
                let (s, c) = self.pose.sin_cos();
                advance(&mut self.pose, motion, dt);
                // |d| <= 65.5 mm in Q24 < 2^31 (Speed::MAX over Dt::MAX)
                let d = v.distance_q24(dt);
                // F: dx/d(L theta) = -d s / L, dy/d(L theta) = d c / L; in Q30
                // that is exactly mul_hi(d Q24, s Q30) (2^30 / (2^22 * 256) = 1):
                // |f| <= 65.5 / 256 < 2^-2 (Q30: < 2^28).
                let f1 = -mul_hi(d, s);
                let f2 = mul_hi(d, c);
                propagate(p, f1, f2);
                // Q: distance noise along (c, s), heading drift. |d| < 2^31,
                // K_DIST < 2^21: var_d < 2^20, so every Q30 product below is
                // far inside i32.
                let ad = d.wrapping_abs(); // |d| < 2^31 (above): no wrap
                add_noise(p, mul_hi(ad, K_DIST), c, s);
                p.tt = p.tt.saturating_add(mul_hi(ad, K_DRIFT));
            }
            Motion::Turn(_) => {
                let before = self.pose.theta;
                // both cached: the last step's new heading, and this one's
                // (`advance` stores it)
                let (s0, c0) = self.pose.sin_cos();
                advance(&mut self.pose, motion, dt);
                let (s1, c1) = self.pose.sin_cos();
                // The turn (model::state): x' = x - D (c0 - c1), y' = y - D (s0 - s1):
                // dx'/dtheta = D (s0 - s1), dy'/dtheta = D (c1 - c0). Halves
                // of Q30 values keep the differences in i32 (Q29); D/L Q31
                // times Q29 gives Q28 from mul_hi, hence the << 2:
                // |f| <= 2 D / L < 7/16 (D < 64 mm, asserted): < 2^29 in Q30.
                let f1 = mul_hi(D_OVER_L_Q31, (s0 >> 1) - (s1 >> 1)) << 2;
                let f2 = mul_hi(D_OVER_L_Q31, (c1 >> 1) - (c0 >> 1)) << 2;
                propagate(p, f1, f2);
                // Q: the turned angle's noise enters through G = (-D s1 / L, D c1 / L, 1)
                // (|g| < 2^28 in Q30); |turned| <= 2^31, K_TURN < 2^23: vt < 2^22.
                // The position block also gets the pivot's own uncertainty
                // (the skid drags), across the car like g: K_TURN_POS < 2^30
                // (asserted), so vpos < 2^29.
                let turned = self.pose.theta.diff(before).saturating_abs();
                let vt = mul_hi(turned, K_TURN);
                let vpos = mul_hi(turned, K_TURN_POS);
                let g1 = -(mul_hi(D_OVER_L_Q31, s1) << 1);
                let g2 = mul_hi(D_OVER_L_Q31, c1) << 1;
                add_noise(p, vpos, g1, g2);
                p.xt = p.xt.saturating_add(mul_q30_unsat(vt, g1));
                p.yt = p.yt.saturating_add(mul_q30_unsat(vt, g2));
                p.tt = p.tt.saturating_add(vt);
            }
        }
        // Floors: dt <= 65535 us, so the products fit u32 (asserted above).
        let dt = dt.as_micros();
        let fp = (FLOOR_POS.wrapping_mul(dt) >> 16) as i32;
        let fh = (FLOOR_HEADING.wrapping_mul(dt) >> 16) as i32;
        p.xx = p.xx.saturating_add(fp);
        p.yy = p.yy.saturating_add(fp);
        p.tt = p.tt.saturating_add(fh);
        self.condition();
        if motion != Motion::Stop {
            self.keep_in_arena();
        }
    }
}
