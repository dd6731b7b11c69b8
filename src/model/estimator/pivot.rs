//! Where the car's turns in place pivot, learned from what each turn
//! leaves the lidars to correct (issue 29: real skids drag the pivot tens
//! of mm behind the axle).
//!
//! A turn about a pivot `p` behind the axle swings the reference point on
//! `D + p` ([`crate::config::geometry::ROTATION_TO_REFERENCE`]): from
//! heading `t0` to `t1` it moves by `(D + p) (u1 - u0)`, `u` the heading's
//! unit vector. The filters swing it about the learned pivot; when that is
//! off by `e`, the lidars' corrections while turning and just after move
//! the leading hypothesis by about `e (u1 - u0)`. Their sum projected on
//! `u1 - u0`, over `|u1 - u0|^2`, is a sample of `e`, weighed against the
//! learned pivot's variance by a scalar Kalman step. Corrections from other
//! causes (noise, the heading) average out over turns; while turning the
//! filters absorb only part of `e`, so a sample falls short of it and the
//! learned pivot closes in over a few turns rather than one.
//!
//! Why not a state of every filter: its column in the turn's shears and
//! its row in every correction cost the tick about 3,300 lx106
//! instructions (four hypotheses 18,183 of the 15,000 bar), and a filter
//! that kept the turn centre instead leaked the pivot's uncertainty into
//! the position with every heading correction (`docs/estimator.md`).

use super::constants::{
    D_OVER_L_Q31, P0_PIVOT, PIVOT_MAX_Q16, PIVOT_MIN_Q16, PIVOT_SAMPLE_VAR, PIVOT_SETTLE_US, PIVOT_WALK,
};
use crate::config::estimator as cfg;
use crate::math::{div_i64, sin_cos, Angle};
use crate::model::state::Lever;

/// A turn being learned from: where the leader's heading started, which
/// hypothesis led, and the leader's position corrections since (Q32 mm).
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
struct Turn {
    from: Angle,
    leader: u8,
    /// The clock (us) at the turn's last step.
    last_us: u32,
    moved_x: i64,
    moved_y: i64,
    /// The corrections summed.
    corrections: u32,
}

/// What a turn's prediction takes from the learned pivot.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub(super) struct Turning {
    /// `D + behind`, the turn's lever for the state update.
    pub lever: Lever,
    /// `(D + behind) / L`, Q31 ([`lever_over_l`]), and its square (Q30).
    pub over_l: i32,
    pub over_l_sq: i32,
    /// The pivot's variance, Q12 mm^2.
    pub var: i32,
}

impl Turning {
    pub fn of(behind: i32, var: i32) -> Turning {
        let over_l = lever_over_l(behind);
        Turning { lever: Lever::behind_axle(behind), over_l, over_l_sq: crate::math::mul_hi(over_l, over_l), var }
    }
}

/// The learned pivot and the turn it is learning from.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub(super) struct Pivot {
    /// Behind the axle, Q16 mm, within `cfg::PIVOT_MIN_MM..=PIVOT_MAX_MM`.
    pub behind: i32,
    /// Its variance, Q12 mm^2, as of `walked_us` (its random walk since is
    /// added when a turn teaches it).
    pub var: i32,
    walked_us: u32,
    /// For the predictions: derived from `behind` and `var` when a turn
    /// teaches them, not each tick (the tick bar).
    pub turning: Turning,
    turn: Option<Turn>,
    /// Turns learned from.
    pub samples: u32,
}

/// The least turn worth a sample (`|u1 - u0|^2 = 2 - 2 cos` at
/// `cfg::PIVOT_MIN_TURN_DEG`), Q30.
const MIN_CHORD_SQ: i64 = {
    let rad = cfg::PIVOT_MIN_TURN_DEG * core::f64::consts::PI / 180.0;
    // 2 - 2 cos by its series to the fourth power (a const fn has no cos);
    // within 1e-4 of it below 60 degrees (asserted in the tests)
    let x2 = rad * rad;
    ((x2 - x2 * x2 / 12.0) * 1_073_741_824.0) as i64
};
const _: () = assert!(cfg::PIVOT_MIN_TURN_DEG > 0.0 && cfg::PIVOT_MIN_TURN_DEG <= 60.0);

impl Pivot {
    /// About the axle, the config's initial uncertainty.
    pub const START: Pivot = Pivot {
        behind: 0,
        var: P0_PIVOT,
        walked_us: 0,
        turning: Turning {
            lever: Lever::AXLE,
            over_l: D_OVER_L_Q31,
            over_l_sq: ((D_OVER_L_Q31 as i64 * D_OVER_L_Q31 as i64) >> 32) as i32,
            var: P0_PIVOT,
        },
        turn: None,
        samples: 0,
    };

    /// One prediction step at `clock_us`, the leader `leader` at heading
    /// `theta` before it: a turning step opens (or extends) the turn; the
    /// first step a settling time after its last closes it, when `located`
    /// (the position is one place, not ambiguous).
    pub fn step(&mut self, turning: bool, theta: Angle, leader: u8, clock_us: u32, located: bool) {
        match (&mut self.turn, turning) {
            (Some(t), true) if t.leader == leader => t.last_us = clock_us,
            (_, true) => {
                self.turn =
                    Some(Turn { from: theta, leader, last_us: clock_us, moved_x: 0, moved_y: 0, corrections: 0 });
            }
            (Some(t), false) if clock_us.wrapping_sub(t.last_us) >= PIVOT_SETTLE_US => {
                let t = *t;
                self.turn = None;
                if located && t.leader == leader {
                    self.learn(&t, theta, clock_us);
                }
            }
            _ => {}
        }
    }

    /// The leader `leader` was moved by `(dx, dy)` (Q32 mm) by a correction.
    pub fn moved(&mut self, leader: u8, dx: i64, dy: i64) {
        if let Some(t) = &mut self.turn {
            if t.leader == leader {
                // (a turn's corrections are far below 2^63 in Q32 mm)
                t.moved_x = t.moved_x.wrapping_add(dx);
                t.moved_y = t.moved_y.wrapping_add(dy);
                t.corrections = t.corrections.wrapping_add(1);
            }
        }
    }

    /// Forgets the turn under way (a new start: its corrections are not
    /// the pivot's).
    pub fn interrupt(&mut self) {
        self.turn = None;
    }

    /// The sample of a turn that ended at heading `to`: the corrections
    /// along the chord `u1 - u0` over its square, weighed by a scalar
    /// Kalman step (sample variance `cfg::PIVOT_SAMPLE_SIGMA_MM^2` over the
    /// chord's square).
    fn learn(&mut self, t: &Turn, to: Angle, clock_us: u32) {
        let ((s0, c0), (s1, c1)) = (sin_cos(t.from), sin_cos(to));
        // halves of Q30: the chord's components in Q29
        let (vx, vy) = (i64::from((c1 >> 1) - (c0 >> 1)), i64::from((s1 >> 1) - (s0 >> 1)));
        let chord_sq = (vx * vx + vy * vy) >> 28; // Q30
        if chord_sq < MIN_CHORD_SQ || t.corrections < cfg::PIVOT_MIN_CORRECTIONS {
            return;
        }
        // the corrections in Q16 mm (|moved| below 2^47 in a box of 2^15 mm)
        let (mx, my) = (t.moved_x >> 16, t.moved_y >> 16);
        // (m . v) Q16 * Q29 = Q45, over |v|^2 Q30: Q15 -> << 1: Q16 mm
        let Some(e) = div_i64(mx.saturating_mul(vx).saturating_add(my.saturating_mul(vy)), chord_sq) else { return };
        let e = (e << 1).clamp(i64::from(PIVOT_MIN_Q16 - PIVOT_MAX_Q16), i64::from(PIVOT_MAX_Q16 - PIVOT_MIN_Q16));
        // the random walk since the last sample (per us times 2^16), then
        // the sample's variance (Q12 mm^2) over the chord's square (Q30)
        let walked = (u64::from(PIVOT_WALK) * u64::from(clock_us.wrapping_sub(self.walked_us))) >> 16;
        self.walked_us = clock_us;
        self.var = i64::from(self.var).saturating_add(walked as i64).min(i64::from(P0_PIVOT)) as i32;
        let Some(sample_var) = div_i64(i64::from(PIVOT_SAMPLE_VAR) << 30, chord_sq) else { return };
        let (var, total) = (i64::from(self.var), i64::from(self.var) + sample_var);
        let (Some(step), Some(after)) = (div_i64(e * var, total), div_i64(var * sample_var, total)) else { return };
        self.behind = (i64::from(self.behind) + step).clamp(i64::from(PIVOT_MIN_Q16), i64::from(PIVOT_MAX_Q16)) as i32;
        self.var = after.clamp(1, i64::from(P0_PIVOT)) as i32;
        self.turning = Turning::of(self.behind, self.var);
        self.samples = self.samples.saturating_add(1);
    }
}

/// The reference point's distance from the pivot over the lever,
/// `(D + behind) / L` in Q31 for `behind` in Q16 mm: below 1 (the
/// constants' asserts).
// tick bar: inlined into the predictions
#[inline(always)]
pub(super) fn lever_over_l(behind: i32) -> i32 {
    D_OVER_L_Q31.saturating_add(behind.clamp(PIVOT_MIN_Q16, PIVOT_MAX_Q16) << 7)
}

/// The position variance (Q12 mm^2) a turn's step of `turned` (angle LSB,
/// below 2^30) adds across the car for the learned pivot's variance `var`:
/// a random walk that gives a quarter turn its chord's, `2 var`: `var 8
/// turned / 2^32`.
// tick bar: inlined into the predictions
#[inline(always)]
pub(super) fn swing_noise(var: i32, turned: i32) -> i32 {
    crate::math::mul_hi(var, turned) << 3
}

#[cfg(test)]
#[allow(clippy::restriction)] // test code: a panic fails the test
mod tests {
    use super::*;

    #[test]
    fn the_least_chord_is_two_minus_two_cos() {
        let rad = cfg::PIVOT_MIN_TURN_DEG.to_radians();
        let exact = (2.0 - 2.0 * rad.cos()) * f64::from(1 << 30);
        assert!((MIN_CHORD_SQ as f64 - exact).abs() < 1e-4 * f64::from(1 << 30), "{MIN_CHORD_SQ} {exact}");
    }

    /// A quarter turn whose corrections moved the leader by `e (u1 - u0)`
    /// samples `e`: the learned pivot moves toward it by the Kalman gain,
    /// and a turn smaller than the least, or ended by another leader, or
    /// not located, or corrected too rarely, teaches nothing.
    #[test]
    fn a_turns_corrections_along_its_chord_are_the_pivots_error() {
        let quarter = Angle::QUARTER_TURN;
        let run = |to: Angle, leader_at_end: u8, located: bool, corrections: u32| {
            let mut p = Pivot::START;
            p.step(true, Angle::ZERO, 0, 0, true);
            // 30 mm along the chord from north (u0 = (1, 0)) to `to`
            let (s1, c1) = sin_cos(to);
            let (vx, vy) = (f64::from(c1) / f64::from(1 << 30) - 1.0, f64::from(s1) / f64::from(1 << 30));
            let q32 = |mm: f64| (mm * 4_294_967_296.0) as i64;
            p.moved(0, q32(30.0 * vx), q32(30.0 * vy));
            for _ in 1..corrections {
                p.moved(0, 0, 0);
            }
            p.step(false, to, leader_at_end, 10_000 + PIVOT_SETTLE_US, located);
            p
        };
        let enough = cfg::PIVOT_MIN_CORRECTIONS;
        let p = run(quarter, 0, true, enough);
        let sample_var = f64::from(PIVOT_SAMPLE_VAR) / 2.0;
        let gain = f64::from(P0_PIVOT) / (f64::from(P0_PIVOT) + sample_var);
        let learned = f64::from(p.behind) / 65536.0;
        assert!((learned - 30.0 * gain).abs() < 0.01, "{learned} against {}", 30.0 * gain);
        assert_eq!(p.samples, 1);
        assert!(p.var < P0_PIVOT / 4);
        for p in [
            run(Angle::from_millidegrees(10_000), 0, true, enough),
            run(quarter, 1, true, enough),
            run(quarter, 0, false, enough),
            run(quarter, 0, true, enough - 1),
        ] {
            assert_eq!((p.behind, p.samples), (0, 0));
        }
    }
}
