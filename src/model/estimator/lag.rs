//! A lidar's reading is of the body a little before the tick it comes at
//! (`config::lidar::READING_AGE_US`: the chip measures over its timing
//! budget, the loop polls once a tick). Standing, that is nothing; turning
//! at `goto`'s rate, it is 3 degrees and the reference point's swing about
//! the pivot, which move a range by up to 20 mm, and more where the cone
//! passes a corner (its nearest wall point jumps from one wall to the
//! other). The correction predicts the reading at the body then: the pose
//! moved back by its motion over the age (the heading's sine and cosine
//! turned to first order: 0.1 degree at most), the beam cast from there.
//! (Measured, issue #29's worlds with the chip's measurement window,
//! `sim::vl53l0x`; docs/estimator.md, "A reading's age".)

use crate::math::{mul_hi, Angle, Coord, Dt};
use crate::model::actuator::Motion;
use crate::model::state::Pose;

/// A reading's age as a step of the loop's clock ...
const AGE: Dt = Dt::from_micros_saturating(crate::config::lidar::READING_AGE_US);
/// ... and times 2 pi / 4: a turn rate over it is the angle turned in the
/// age in radians, Q30 (the rotation is linear in the duration: no
/// product).
const AGE_RAD: Dt =
    Dt::from_micros_saturating((crate::config::lidar::READING_AGE_US as f64 * core::f64::consts::TAU / 4.0) as u32);

/// The body's move over a reading's age at the leader's motion (see the
/// module docs). The age spans this step and the last (2.15 ticks of 10
/// ms): the move is the mean of the two steps' motions over it, so a
/// reading as a turn starts or ends takes half the turn's.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub(super) struct Lag {
    now: Move,
    last: Move,
}

/// A motion over the age: a turn's angle (LSB) and in radians (Q30), a
/// straight distance (Q24 mm).
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
struct Move {
    turn: i32,
    rad: i32,
    along: i32,
}

impl Move {
    const NONE: Move = Move { turn: 0, rad: 0, along: 0 };

    fn mean(a: Move, b: Move) -> Move {
        let m = |x: i32, y: i32| (x >> 1).wrapping_add(y >> 1);
        Move { turn: m(a.turn, b.turn), rad: m(a.rad, b.rad), along: m(a.along, b.along) }
    }
}

/// Where the body was a reading's age ago: its place, heading and that
/// heading's sine and cosine (Q30), for [`crate::model::measurement::Beam::at`].
pub(super) struct Then {
    pub x: Coord,
    pub y: Coord,
    pub theta: Angle,
    pub sin_cos: (i32, i32),
}

impl Lag {
    /// Standing: no move.
    pub const NONE: Lag = Lag { now: Move::NONE, last: Move::NONE };

    /// After a step at `scaled` (the leader's motion, by its scales).
    // tick bar: no product
    #[inline(always)]
    pub fn follow(&mut self, scaled: Motion) {
        let step = match scaled {
            Motion::Stop => Move::NONE,
            // a fraction of a turn (TurnRate::MAX over 34 ms: 0.7 rad,
            // Q30 below 2^30), its LSB within i32
            Motion::Turn(w) => {
                Move { turn: w.rotation(AGE).0 .0 as i32, rad: w.rotation(AGE_RAD).0 .0 as i32, along: 0 }
            }
            // at most 65.5 mm (`Speed::distance_q24`): within i32
            Motion::Straight(v) => Move { along: v.distance_q24(AGE), ..Move::NONE },
        };
        self.now = Move::mean(step, self.last);
        self.last = step;
    }

    /// Where the body at `pose` (its sine and cosine cache current,
    /// `Pose::sin_cos`) was a reading's age ago.
    // tick bar: inlined into the lidar's row
    #[inline(always)]
    pub fn then(&self, pose: &Pose) -> Then {
        let m = self.now;
        let (s, c) = pose.cached_sin_cos();
        if m.rad != 0 {
            // back about the pivot: the reference point by (lever sin,
            // -lever cos) a radian (Q21 times Q30 is Q19), the heading's
            // sine and cosine by (-cos, sin) a radian (Q30 times Q30 is Q28)
            let (ls, lc) = pose.cached_swing();
            Then {
                x: pose.x.add_q21(mul_hi(ls, m.rad) << 2),
                y: pose.y.add_q21(mul_hi(lc, m.rad).wrapping_neg() << 2),
                theta: pose.theta.wrapping_sub(Angle(m.turn as u32)),
                sin_cos: (s.wrapping_sub(mul_hi(c, m.rad) << 2), c.wrapping_add(mul_hi(s, m.rad) << 2)),
            }
        } else {
            // back along the heading (Q24 times Q30 is Q22)
            let back = m.along.wrapping_neg();
            Then {
                x: pose.x.add_q22(mul_hi(back, c)),
                y: pose.y.add_q22(mul_hi(back, s)),
                theta: pose.theta,
                sin_cos: (s, c),
            }
        }
    }
}

#[cfg(test)]
#[allow(clippy::restriction)] // test code: a panic fails the test
mod tests {
    use super::*;
    use crate::math::{Angle, Coord, Length, Speed, TurnRate};
    use crate::model::estimator::predict::Filter;
    use crate::model::measurement::{Arena, LidarId};
    use crate::model::state::advance_about;

    /// The innovation a reading gets at `now` with the lag of `motion`
    /// matches the one it gets at the pose a reading's age before, within
    /// 0.6 mm (the sine's and cosine's first order: 0.48 at worst), for
    /// both lidars over headings all round, from the box's middle and near
    /// a corner (where the cone's nearest wall changes with the heading),
    /// turning either way at the survey's rate about the hard world's
    /// pivot and driving; without the lag they differ by up to 16.5 mm.
    #[test]
    fn the_innovation_is_read_at_the_body_a_readings_age_ago() {
        let lever = crate::model::state::Lever::behind_axle(60 << 16);
        let motions = [
            Motion::Turn(TurnRate::from_rad_s_f64(2.4)),
            Motion::Turn(TurnRate::from_rad_s_f64(-2.4)),
            Motion::Straight(Speed::from_mps_f64(0.15)),
        ];
        let (mut worst, mut worst_without): (f64, f64) = (0.0, 0.0);
        for motion in motions {
            let mut lag = Lag::NONE;
            lag.follow(motion);
            lag.follow(motion);
            for (x, y) in [(300.0, 220.0), (170.0, 165.0), (620.0, 380.0)] {
                for deg in (0..360).step_by(5) {
                    let then = Pose::new(
                        Coord::from_mm_f64(x),
                        Coord::from_mm_f64(y),
                        Angle::from_degrees_f64(f64::from(deg)),
                    );
                    let mut now = then;
                    advance_about(&mut now, motion, AGE, lever);
                    for id in [LidarId::Front, LidarId::Right] {
                        let nu = |pose: Pose, lag: &Lag| {
                            let mut f = Filter::new(pose);
                            let z = Length::from_mm(250);
                            f.lidar_reading(&Arena::DEFAULT, id, z, 0, lag).map(|r| f64::from(r.nu) / 65536.0)
                        };
                        let (Some(exact), Some(lagged), Some(plain)) =
                            (nu(then, &Lag::NONE), nu(now, &lag), nu(now, &Lag::NONE))
                        else {
                            continue;
                        };
                        worst = worst.max((lagged - exact).abs());
                        worst_without = worst_without.max((plain - exact).abs());
                    }
                }
            }
        }
        std::println!("lagged {worst:.2} mm off the exact innovation at worst, {worst_without:.1} without");
        assert!(worst < 0.6, "{worst}");
        assert!(worst_without > 12.0, "{worst_without}");
    }
}
