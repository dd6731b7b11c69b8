//! One hypothesis's filter, and its prediction: the pose moves by the
//! state update with the learned scales, the covariance by the motion's
//! Jacobian (a few shears) and noise.

use super::constants::{
    BIAS_WALK, FLOOR_HEADING, FLOOR_POS, K_BIAS_MM, K_DIST, K_DRIFT, K_PIVOT, K_TURN, P0_BIAS, P0_HEADING, P0_POS,
    P0_SPEED, P0_TURN, RAD_Q28_PER_LSB, SCALE_ONE, SCALE_WALK,
};
use super::covariance::{Covariance, BIAS, CCW, CW, SPEED, T, X, Y};
use super::pivot::{swing_noise, Turning};
use crate::math::{mul_hi, Angle, Coord, Dt, Speed, TurnRate};
use crate::model::actuator::Motion;
use crate::model::state::{advance, advance_about, Pose};

/// The learned scales of the actuator lines, Q29 (1 = the lines).
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
pub struct Scales {
    pub speed: i32,
    pub cw: i32,
    pub ccw: i32,
}

impl Scales {
    pub const ONE: Scales = Scales { speed: SCALE_ONE, cw: SCALE_ONE, ccw: SCALE_ONE };

    /// The motion the car makes for the lines' `motion`, by these scales.
    pub fn apply(&self, motion: Motion) -> Motion {
        match motion {
            Motion::Stop => Motion::Stop,
            // |bits| <= Speed::MAX < 2^23: << 8 fits; times a Q29 scale below
            // 4 (>> 5 of mul_hi's Q37) kept within Speed::MAX, which
            // `Speed::distance_q24` is sized for
            Motion::Straight(v) => {
                let max = Speed::MAX.to_bits();
                let bits = mul_hi(v.to_bits().clamp(-max, max) << 8, self.speed) >> 5;
                Motion::Straight(Speed::from_bits(bits.clamp(-max, max)))
            }
            Motion::Turn(w) => {
                let s = if w.to_bits() >= 0 { self.cw } else { self.ccw };
                let max = TurnRate::MAX.to_bits();
                Motion::Turn(TurnRate::from_bits(mul_hi(w.to_bits(), s).saturating_mul(8).clamp(-max, max)))
            }
        }
    }
}

/// Where the position is kept: within the arena's margin, whole mm (see
/// `Estimator::with_arena`).
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
pub(super) struct Bounds {
    pub low_mm: i32,
    pub high_x_mm: i32,
    pub high_y_mm: i32,
}

/// One hypothesis: an extended Kalman filter over the pose, the actuator
/// lines' scales and the compass's bias (see [`super::covariance::N`]).
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub struct Filter {
    pub(super) pose: Pose,
    pub(super) scales: Scales,
    /// What the compass reads beyond the heading.
    pub(super) bias: Angle,
    pub(super) p: Covariance,
    /// A secondary's prediction of its pose block not yet applied
    /// (`light`; zero for the leader).
    pub(super) owed: super::light::Owed,
}

impl Filter {
    /// At `pose` with the config's initial uncertainty, the scales at 1 and
    /// no bias.
    pub(super) fn new(pose: Pose) -> Filter {
        Filter {
            pose,
            scales: Scales::ONE,
            bias: Angle::ZERO,
            p: Covariance::diagonal_of([P0_POS, P0_POS, P0_HEADING, P0_SPEED, P0_TURN, P0_TURN, P0_BIAS]),
            owed: super::light::Owed::NONE,
        }
    }

    /// Moves the pose by `motion` (the lines' motion; `scaled`, the same by
    /// this hypothesis's scales) held for `dt`, a turn about the learned
    /// `pivot`, and grows the uncertainty.
    pub(super) fn predict(&mut self, motion: Motion, scaled: Motion, dt: Dt, pivot: &Turning, bounds: &Bounds) {
        let dt_us = dt.as_micros();
        let p = &mut self.p;
        match (motion, scaled) {
            (Motion::Straight(v0), Motion::Straight(v)) => {
                // the heading does not change: the cached sin/cos are the step's
                let (s, c) = self.pose.sin_cos();
                advance(&mut self.pose, scaled, dt);
                // |d| <= 65.5 mm in Q24 (Speed::MAX over Dt::MAX) times the
                // scale (< 4): below 2^31 but for the last bit, saturated
                let d0 = v0.distance_q24(dt);
                let d = v.distance_q24(dt);
                // F: dx/d(L theta) = -d s / L (Q30: mul_hi(d Q24, s Q30), as
                // 2^30 / (2^22 * 256) = 1), and dx/d(L scale) = d0 c / L alike.
                p.shear(X, (T, -mul_hi(d, s)), (SPEED, mul_hi(d0, c)));
                p.shear(Y, (T, mul_hi(d, c)), (SPEED, mul_hi(d0, s)));
                // Q: distance noise along (c, s), heading drift, the bias's
                // walk over the floor, the scale's drift.
                let ad = d0.wrapping_abs(); // |d0| < 2^31 (above): no wrap
                p.add_outer(mul_hi(ad, K_DIST), [X, Y], [c, s]);
                p.add(T, T, mul_hi(ad, K_DRIFT));
                p.add(BIAS, BIAS, mul_hi(ad, K_BIAS_MM));
                p.add(SPEED, SPEED, (SCALE_WALK.wrapping_mul(dt_us) >> 16) as i32);
            }
            (Motion::Turn(w0), Motion::Turn(_)) => {
                let before = self.pose.theta;
                let (s0, c0) = self.pose.sin_cos();
                advance_about(&mut self.pose, scaled, dt, pivot.lever);
                let (s1, c1) = self.pose.sin_cos();
                // The turn (model::state) about the pivot, R = D + p behind:
                // x' = x - R (c0 - c1), y' = y - R (s0 - s1): dx'/dtheta = R
                // (s0 - s1), dy'/dtheta = R (c1 - c0); halves of Q30 keep the
                // differences in i32 (Q29), R/L Q31 times Q29 is Q28 from
                // mul_hi, hence the << 2: far below 1/2 in Q30 for a step.
                let lever = pivot.over_l;
                let f1 = mul_hi(lever, (s0 >> 1) - (s1 >> 1)) << 2;
                let f2 = mul_hi(lever, (c1 >> 1) - (c0 >> 1)) << 2;
                // The turn's direction G = (-R s1 / L, R c1 / L, 1) (Q30, the
                // position entries below 2^30): the turned angle's noise and,
                // times the commanded angle a0, the scale's column.
                let g1 = -(mul_hi(lever, s1) << 1);
                let g2 = mul_hi(lever, c1) << 1;
                // a0: the lines' angle this step, |a0| < 2^30 LSB (TurnRate::MAX
                // over Dt::MAX); in rad Q30 below 1.6 (the shear clamps at 1/2:
                // a step turns 0.2 rad at 3 rad/s for 65 ms)
                let a0 = w0.rotation(dt).0 .0 as i32;
                let a_rad = mul_hi(a0, RAD_Q28_PER_LSB).saturating_mul(4);
                let scale = if w0.to_bits() >= 0 { CW } else { CCW };
                // x and y read the heading and the scale before the heading
                // moves (the shears compose to I + F's off-diagonal part)
                p.shear(X, (T, f1), (scale, crate::math::mul_q30(a_rad, g1)));
                p.shear(Y, (T, f2), (scale, crate::math::mul_q30(a_rad, g2)));
                p.shear(T, (scale, a_rad), (BIAS, 0));
                // Q: the turned angle's noise along G; the pivot's slop and
                // the learned pivot's uncertainty across the car (unit (-s1,
                // c1)); the scale's drift.
                // (per angle turned: |turned| <= 2^31, the factors below
                // 2^31, so each variance below 2^30; the conditioning caps)
                let turned = self.pose.theta.diff(before).saturating_abs();
                p.add_outer(mul_hi(turned, K_TURN), [X, Y, T], [g1, g2, 1 << 30]);
                let across = mul_hi(turned, K_PIVOT).saturating_add(swing_noise(pivot.var, turned));
                p.add_outer(across, [X, Y], [-s1, c1]);
                p.add(scale, scale, (SCALE_WALK.wrapping_mul(dt_us) >> 16) as i32);
            }
            _ => {}
        }
        // Floors and the bias's walk in time: dt <= 65535 us, the products
        // fit u32 (asserted).
        let fp = (FLOOR_POS.wrapping_mul(dt_us) >> 16) as i32;
        p.add(X, X, fp);
        p.add(Y, Y, fp);
        p.add(T, T, (FLOOR_HEADING.wrapping_mul(dt_us) >> 16) as i32);
        p.add(BIAS, BIAS, (BIAS_WALK.wrapping_mul(dt_us) >> 16) as i32);
        // (a congruence and noise keep the correlations valid: the diagonal's
        // upkeep only; the long-run test checks P positive definite every tick)
        p.condition_diagonal();
        if motion != Motion::Stop {
            self.keep_in(bounds);
        }
    }

    /// Keeps the position within the bounds, to the whole mm (a projection
    /// onto what the position can be; the covariance is left alone).
    pub(super) fn keep_in(&mut self, b: &Bounds) {
        clamp_mm(&mut self.pose.x, b.low_mm, b.high_x_mm);
        clamp_mm(&mut self.pose.y, b.low_mm, b.high_y_mm);
    }
}

/// [`Filter::keep_in`] for one coordinate: into `[low, high]` mm by its
/// high word (`|c| < 2^63`: it fits). (For bounds the wrong way round the
/// upper wins: no panic.)
// tick bar: inlined, as its five kin (lx106/BENCHMARKS.md, "Control
// tick")
#[inline(always)]
pub(super) fn clamp_mm(c: &mut Coord, low: i32, high: i32) {
    let mm = (c.0 >> 32) as i32;
    if mm < low {
        *c = Coord(i64::from(low) << 32);
    }
    if mm >= high {
        *c = Coord(i64::from(high) << 32);
    }
}
