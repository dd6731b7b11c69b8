//! The secondary hypotheses, lighter filters (issue 29's budget: a
//! correction tick with four hypotheses within 15,000 lx106 instructions).
//!
//! Only the leading hypothesis (the best) runs the whole 7-state filter.
//! The others carry their pose and its 3 x 3 block of the covariance (`x`,
//! `y`, `theta`) and share the leader's scales and compass bias: they move
//! by the leader's scaled motion, and the leader's uncertainty in those
//! states reaches them as noise ([`Shared`]). Their rows of the scales and
//! the bias are left as they were (stale) until one becomes the leader:
//! then it takes the old leader's ([`Filter::take_over`]).
//!
//! A secondary's prediction adds its noise to the diagonal only (the
//! position's noise on both axes: more than the leader's along one
//! direction, never less); its correction is the leader's scalar update on
//! the pose block. See `docs/estimator.md`, "The budget".

use super::constants::{
    FLOOR_HEADING, FLOOR_POS, K_DIST, K_DRIFT, K_PIVOT, K_TURN, P_MAX, P_MIN, R_COMPASS, SPEED_SHARE_Q30,
    TILDE_Q16_PER_LSB, TURN_SHARE_Q27,
};
use super::covariance::{Covariance, BIAS, CCW, CW, SPEED, T, X, Y};
use super::pivot::{swing_noise, Turning};
use super::predict::{Bounds, Filter};
use super::update::{over_s, scale_shift, scaling, Outcome, Row, Scaling};
use super::Update;
use crate::math::{mul_hi, mul_q30, mul_wide, shift, Angle, Coord, Dt};
use crate::model::actuator::Motion;
use crate::model::state::{advance_about, Lever};

// `project_pose` indexes its `b` by the state
const _: () = assert!(X == 0 && Y == 1 && T == 2);

/// What the secondaries take from the leader for one step: the motion by
/// its scales, and the noise its scales' uncertainty adds, with the
/// motion's own noise (computed once a step for all of them).
#[derive(Clone, Copy)]
pub(super) struct Shared {
    /// The lines' motion by the leader's scales.
    pub scaled: Motion,
    /// Position variance added on each axis, Q12 mm^2.
    pub xy: i32,
    /// Heading variance added, Q12 mm^2 (of `L dtheta`).
    pub t: i32,
    /// The learned pivot's lever, `D + pivot` for the state update and
    /// over `L` (Q31) for the Jacobian: a turn swings the secondaries
    /// about it too.
    pub turn_lever: Lever,
    pub over_l: i32,
}

impl Shared {
    /// For the lines' `motion` held for `dt`, from the leader `f`: the
    /// motion's noise as the leader's prediction adds it, but on the
    /// diagonal; the scale's uncertainty as a random walk over the config's
    /// correlation distance or angle (`cfg::SPEED_CORRELATION_MM`,
    /// `cfg::TURN_CORRELATION_DEG`: a quarter turn's error exact, twice as
    /// much turned by a factor sqrt 2 too little).
    pub fn of(f: &Filter, motion: Motion, scaled: Motion, dt: Dt, pivot: &Turning) -> Shared {
        let dt_us = dt.as_micros();
        let floor_xy = (FLOOR_POS.wrapping_mul(dt_us) >> 16) as i32;
        let floor_t = (FLOOR_HEADING.wrapping_mul(dt_us) >> 16) as i32;
        let (xy, t) = match (motion, scaled) {
            (Motion::Straight(v0), _) => {
                let ad = v0.distance_q24(dt).wrapping_abs();
                // |d| Lc / L^2 in Q30, below 1/2 for a step (65.5 mm)
                let share = mul_hi(ad, SPEED_SHARE_Q30);
                (mul_hi(ad, K_DIST).saturating_add(mul_q30(f.p.get(SPEED, SPEED), share)), mul_hi(ad, K_DRIFT))
            }
            (Motion::Turn(w0), Motion::Turn(w)) => {
                let turned = (w.rotation(dt).0 .0 as i32).saturating_abs();
                let scale = if w0.to_bits() >= 0 { CW } else { CCW };
                // |turned| Lc_rad in Q27 (below 4 for a step's 1.3 rad)
                let share = mul_hi(turned, TURN_SHARE_Q27);
                let from_scale = mul_hi(f.p.get(scale, scale), share) << 5;
                // the turned angle's noise and the scale's: the heading's,
                // and the position's by (D + p) / L (the reference point
                // swings about the pivot; its square in Q30), with the
                // pivot's slop and the learned pivot's uncertainty
                let var = mul_hi(turned, K_TURN).saturating_add(from_scale);
                let pos = mul_q30(var, pivot.over_l_sq)
                    .saturating_add(mul_hi(turned, K_PIVOT))
                    .saturating_add(swing_noise(pivot.var, turned));
                (pos, var)
            }
            _ => (0, 0),
        };
        Shared {
            scaled,
            xy: xy.saturating_add(floor_xy),
            t: t.saturating_add(floor_t),
            turn_lever: pivot.lever,
            over_l: pivot.over_l,
        }
    }
}

/// A secondary's prediction owed to its pose block: the steps' shears
/// (position by heading) add up exactly (`e_t^T e_x = 0`: the product of
/// two is the shear by the sum), and their noise; applied when a reading
/// weighs it ([`Filter::pay`]), or once the shear reaches 1/8. The noise's
/// own shearing between is left out (the steps' factors times the
/// heading's noise: second order).
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub(super) struct Owed {
    /// The shear's factors, Q30.
    pub fx: i32,
    pub fy: i32,
    /// Noise on each position axis and on the heading, Q12 mm^2.
    pub xy: i32,
    pub t: i32,
}

impl Owed {
    pub const NONE: Owed = Owed { fx: 0, fy: 0, xy: 0, t: 0 };
}

/// The owed shear paid at once past this (1/8 in Q30).
const OWED_SHEAR_MAX: u32 = 1 << 27;

impl Filter {
    /// A secondary's prediction: the pose by the leader's scaled motion;
    /// the pose block's owed (see [`Owed`]).
    pub(super) fn predict_pose(&mut self, shared: &Shared, dt: Dt, bounds: &Bounds) {
        let (s0, c0) = self.pose.sin_cos();
        advance_about(&mut self.pose, shared.scaled, dt, shared.turn_lever);
        // the Jacobian as the leader's (position by heading)
        let (fx, fy) = match shared.scaled {
            Motion::Straight(v) => {
                // dx/d(L theta) = -d s / L, dy/d(L theta) = d c / L
                let d = v.distance_q24(dt);
                (-mul_hi(d, s0), mul_hi(d, c0))
            }
            Motion::Turn(_) => {
                let (s1, c1) = self.pose.sin_cos();
                let lever = shared.over_l;
                (mul_hi(lever, (s0 >> 1) - (s1 >> 1)) << 2, mul_hi(lever, (c1 >> 1) - (c0 >> 1)) << 2)
            }
            Motion::Stop => (0, 0),
        };
        let o = &mut self.owed;
        o.fx = o.fx.saturating_add(fx);
        o.fy = o.fy.saturating_add(fy);
        o.xy = o.xy.saturating_add(shared.xy);
        o.t = o.t.saturating_add(shared.t);
        if o.fx.unsigned_abs() > OWED_SHEAR_MAX || o.fy.unsigned_abs() > OWED_SHEAR_MAX {
            self.pay();
        }
        if shared.scaled != Motion::Stop {
            self.keep_in(bounds);
        }
    }

    /// Applies the owed prediction to the pose block (before a correction
    /// or when it leads).
    pub(super) fn pay(&mut self) {
        let o = self.owed;
        self.owed = Owed::NONE;
        let p = &mut self.p;
        p.shear_pose(o.fx, o.fy);
        p.add(X, X, o.xy);
        p.add(Y, Y, o.xy);
        p.add(T, T, o.t);
        p.condition_pose_diagonal();
    }

    /// A secondary's compass row, innovation and noise: it reads the heading
    /// plus the leader's `bias`, whose variance `bias_var` adds to the noise.
    pub(super) fn compass_reading_pose(&self, heading: Angle, bias: Angle, bias_var: i32) -> (Row, i32, i32) {
        // as `Filter::compass_reading`: angle LSB -> (L rad) mm Q16
        let diff = heading.diff(self.pose.theta.wrapping_add(bias));
        (Row::unit_on(T), mul_hi(diff, TILDE_Q16_PER_LSB), R_COMPASS.saturating_add(bias_var).min(P_MAX))
    }

    /// [`Filter::correct`] on the pose block: the scalar Kalman correction
    /// for innovation `nu` (Q16 mm), row `h` (on `x`, `y`, `theta` only),
    /// noise `r` (Q12 mm^2, `0 < r <= P_MAX`), gated; the same arithmetic
    /// on three states. Returns the outcome and the repairs made.
    pub(super) fn correct_pose(&mut self, h: Row, nu: i32, r: i32, bounds: &Bounds) -> (Outcome, u32) {
        self.pay();
        let (b, hph, k) = project_pose(&self.p, h);
        let s = hph.max(0) + (r >> k).max(1);
        let mb = b.iter().fold(0u32, |m, v| m | v.unsigned_abs());
        let Scaling { y, ns, sb, ek, nis_q8 } = match scaling(nu, s, k, mb) {
            Ok(sc) => sc,
            Err(done) => return done,
        };
        let t: [i32; 3] = core::array::from_fn(|i| over_s(b.get(i).copied().unwrap_or(0), sb, y));
        let gain = |i: usize| shift(t.get(i).copied().unwrap_or(0), ek);
        self.pose.x = Coord(self.pose.x.0.wrapping_add(mul_wide(gain(X), nu) >> 5));
        self.pose.y = Coord(self.pose.y.0.wrapping_add(mul_wide(gain(Y), nu) >> 5));
        self.pose.theta = self.pose.theta.wrapping_add(super::update::to_angle(gain(T), nu));
        let ep = ns as i32 - 2 * sb as i32 + 2 + k as i32;
        let beta: [i32; 3] = core::array::from_fn(|i| b.get(i).copied().unwrap_or(0) << sb);
        self.p.remove_outer_pose(&t, &beta, ep);
        let repairs = self.p.condition_pose();
        self.keep_in(bounds);
        (Outcome { update: Update::Accepted, nis_q8, nu }, repairs)
    }

    /// This secondary becomes the leader: it takes `leader`'s scales, bias
    /// and their block of the covariance; its pose block is its own, taken
    /// as independent of them (block diagonal: still positive definite).
    pub(super) fn take_over(&mut self, leader: &Filter) {
        self.pay();
        self.scales = leader.scales;
        self.bias = leader.bias;
        for i in [SPEED, CW, CCW, BIAS] {
            for j in [SPEED, CW, CCW, BIAS] {
                self.p.set(i, j, leader.p.get(i, j));
            }
            for k in [X, Y, T] {
                self.p.set(k, i, 0);
            }
        }
    }
}

/// `b = P H^T` and `H P H^T` over the pose block, scaled by `2^-k` as
/// `update::project` does (the same bounds). The pose block's states are
/// the first three ([`X`], [`Y`], [`T`]), so `b`'s index is the state's.
fn project_pose(p: &Covariance, h: Row) -> ([i32; 3], i32, u32) {
    let (u, l) = (h.unit, h.lever);
    let unit = [p.get(u, X), p.get(u, Y), p.get(u, T)];
    let lever = [p.get(l, X), p.get(l, Y), p.get(l, T)];
    let mag = unit.iter().chain(lever.iter()).fold(0u32, |m, v| m | v.unsigned_abs());
    let k = scale_shift(mag);
    let c8 = h.coef << 8;
    let mut b = [0i32; 3];
    for ((bi, &l), &u) in b.iter_mut().zip(lever.iter()).zip(unit.iter()) {
        let (l, u) = (mul_hi((l >> k) << 8, c8), u >> k);
        *bi = if h.positive { l + u } else { l - u };
    }
    let (bu, bl) = (b.get(u).copied().unwrap_or(0), b.get(l).copied().unwrap_or(0));
    let tb = mul_hi(bl << 4, h.coef << 12);
    (b, if h.positive { tb + bu } else { tb - bu }, k)
}

impl Covariance {
    /// `M P M^T` on the pose block for `M = I + f1 e_x e_t^T + f2 e_y
    /// e_t^T` (`f` in Q30, `|f| <= 2^29`): the position moves by `f` times
    /// the heading. The pose block's entries only (a secondary's).
    pub(super) fn shear_pose(&mut self, f1: i32, f2: i32) {
        if f1 == 0 && f2 == 0 {
            return;
        }
        let (f1, f2) = (f1.clamp(-(1 << 29), 1 << 29), f2.clamp(-(1 << 29), 1 << 29));
        let (xt, yt, tt) = (self.get(X, T), self.get(Y, T), self.get(T, T));
        let fine = super::covariance::mul_q30_fine;
        let xt1 = xt.saturating_add(fine(tt, f1));
        let yt1 = yt.saturating_add(fine(tt, f2));
        self.add(X, X, fine(xt, f1).saturating_add(fine(xt1, f1)));
        self.add(Y, Y, fine(yt, f2).saturating_add(fine(yt1, f2)));
        self.add(X, Y, fine(yt, f1).saturating_add(fine(xt1, f2)));
        self.set(X, T, xt1);
        self.set(Y, T, yt1);
    }

    /// `P_ij -= mul_hi(t_i, beta_j) 2^e` on the pose block (see
    /// `Covariance::remove_outer`).
    fn remove_outer_pose(&mut self, t: &[i32; 3], beta: &[i32; 3], e: i32) {
        let (&[t0, t1, t2], &[b0, b1, b2]) = (t, beta);
        self.less(X, X, shift(mul_hi(t0.abs(), b0.abs()), e));
        self.less(X, Y, shift(mul_hi(t0, b1), e));
        self.less(X, T, shift(mul_hi(t0, b2), e));
        self.less(Y, Y, shift(mul_hi(t1.abs(), b1.abs()), e));
        self.less(Y, T, shift(mul_hi(t1, b2), e));
        self.less(T, T, shift(mul_hi(t2.abs(), b2.abs()), e));
    }

    // tick bar (four hypotheses): inlined, as `Covariance::get` and kin
    #[inline(always)]
    fn less(&mut self, i: usize, j: usize, d: i32) {
        self.set(i, j, self.get(i, j).saturating_sub(d));
    }

    /// The pose block's diagonal kept between the floor and the cap (see
    /// `Covariance::condition_diagonal`).
    fn condition_pose_diagonal(&mut self) {
        self.keep_variance(X);
        self.keep_variance(Y);
        self.keep_variance(T);
    }

    // tick bar (four hypotheses): inlined, as `Covariance::get` and kin
    #[inline(always)]
    fn keep_variance(&mut self, i: usize) {
        if self.get(i, i) > P_MAX {
            self.halve(i);
        }
        if self.get(i, i) < P_MIN {
            self.set(i, i, P_MIN);
        }
    }

    /// The pose block kept valid after a correction (see
    /// `Covariance::condition`); returns the repairs.
    fn condition_pose(&mut self) -> u32 {
        self.condition_pose_diagonal();
        self.bound(X, Y) + self.bound(X, T) + self.bound(Y, T)
    }

    // tick bar (four hypotheses): inlined, as `Covariance::get` and kin
    #[inline(always)]
    fn bound(&mut self, i: usize, j: usize) -> u32 {
        let mut pij = self.get(i, j);
        let repairs = super::covariance::bound_correlation(&mut pij, self.get(i, i), self.get(j, j));
        self.set(i, j, pij);
        repairs
    }
}

#[cfg(test)]
#[allow(clippy::restriction)] // test code: a panic fails the test
mod tests {
    use super::super::pivot::Pivot;
    use super::*;
    use crate::math::{Speed, TurnRate};
    use crate::model::state::Pose;

    const BOUNDS: Bounds = Bounds { low_mm: -1000, high_x_mm: 2000, high_y_mm: 2000 };

    /// The pose block's shear is `M P M^T` (f64, to the products' rounding).
    #[test]
    fn the_pose_shear_is_the_congruence() {
        let mut p = Covariance::default();
        for (i, j, v) in
            [(X, X, 1 << 24), (Y, Y, 1 << 23), (T, T, 1 << 22), (X, Y, -(1 << 21)), (X, T, 1 << 21), (Y, T, -(1 << 20))]
        {
            p.set(i, j, v);
        }
        let (f1, f2) = (-(3 << 27), 5 << 26); // -0.375, 0.3125
        let mut q = p;
        q.shear_pose(f1, f2);
        let (g1, g2) = (f64::from(f1) / f64::from(1 << 30), f64::from(f2) / f64::from(1 << 30));
        let m = |a: usize, b: usize| match (a, b) {
            _ if a == b => 1.0,
            (X, T) => g1,
            (Y, T) => g2,
            _ => 0.0,
        };
        for i in [X, Y, T] {
            for j in [X, Y, T] {
                let mut e = 0.0;
                for a in [X, Y, T] {
                    for b in [X, Y, T] {
                        e += m(i, a) * f64::from(p.get(a, b)) * m(j, b);
                    }
                }
                assert!((f64::from(q.get(i, j)) - e).abs() <= 32.0, "{i} {j}: {} vs {e}", q.get(i, j));
            }
        }
    }

    /// A secondary's pose block, predicted step by step as owed and paid
    /// once, against the whole filter's over the same motion: a quarter
    /// turn each way and 450 mm straight (the config's correlation angle and
    /// distance, where its scale noise is exact) from an uncertain start,
    /// about a learned pivot 60 mm behind the axle (3 mm one sigma) and about
    /// the axle with the pivot not yet learned (40 mm).
    /// Its variances are never below the whole filter's (it must not be
    /// surer than it is: it would refuse the readings that save it) and at
    /// most 4.5 times (1.0-4.2 now: its noise on both axes, the turn's by
    /// the lever (D + pivot) / L squared; 1.0-2.3 about the axle).
    #[test]
    fn a_secondary_is_about_as_uncertain_as_a_whole_filter() {
        let start = |p: Pose| {
            let mut f = Filter::new(p);
            f.p = Covariance::diagonal_of([
                400 * 4096,
                900 * 4096,
                super::super::constants::R_COMPASS,
                f.p.get(SPEED, SPEED),
                f.p.get(CW, CW),
                f.p.get(CCW, CCW),
                f.p.get(BIAS, BIAS),
            ]);
            f
        };
        let dt = Dt::from_micros_saturating(10_000);
        let quarter = (0.5 * core::f64::consts::PI / 2.5 / 0.01) as usize; // 2.5 rad/s
        let straight = (450.0 / 130.0 / 0.01) as usize; // 130 mm/s
        let learned = Turning::of(60 << 16, 9 << 12);
        for pivot in [learned, Pivot::START.turning] {
            for (motion, steps) in [
                (Motion::Turn(TurnRate::from_mrad_s(2500)), quarter),
                (Motion::Turn(TurnRate::from_mrad_s(-2500)), quarter),
                (Motion::Straight(Speed::from_mm_s(130)), straight),
            ] {
                let mut whole = start(Pose::from_mm(380, 250, Angle::from_millidegrees(30_000)));
                let mut light = whole;
                for _ in 0..steps {
                    let scaled = whole.scales.apply(motion);
                    let shared = Shared::of(&whole, motion, scaled, dt, &pivot);
                    light.predict_pose(&shared, dt, &BOUNDS);
                    whole.predict(motion, scaled, dt, &pivot, &BOUNDS);
                }
                light.pay();
                assert_eq!(light.pose, whole.pose, "{motion:?}: the same scaled motion");
                for i in [X, Y, T] {
                    let ratio = f64::from(light.p.get(i, i)) / f64::from(whole.p.get(i, i));
                    assert!(
                        (0.99..=4.5).contains(&ratio),
                        "{motion:?}, {pivot:?}: state {i}: {ratio:.3} of the whole filter's variance"
                    );
                }
            }
        }
    }
}
