//! Going to a point or a heading on the estimate: `goto` and `face`.
//!
//! The robot turns in place about its axle and drives straight; the pose
//! it reports (and the target) is its reference point, `D` =
//! [`config::geometry::ROTATION_TO_REFERENCE`] ahead of the axle. So the
//! plan is made from the axle `A = P - D u` (`u` the heading's unit
//! vector): turning in place leaves `A` where it is, and once the heading
//! points from `A` at the target `T`, a straight leg of `|T - A| - D`
//! (forward, or backward when the target is within `D` of the axle)
//! brings the reference point onto it. Each tick [`Nav::step`] plans again
//! from the newest estimate: a leg whose heading has drifted past
//! [`config::goto::STEER_TOLERANCE_MDEG`] turns again, a leg ends where
//! the target is abeam, and the goto ends when the reference point is
//! within [`config::goto::ARRIVE_MM`] of the target.
//!
//! Integer only: positions in 1/16 mm, angles as [`Angle`]s.

use crate::config;
use crate::math::{atan2, isqrt64, sin_cos, Angle, Speed, TurnRate};
use crate::model::measurement::Arena;
use crate::model::{Motion, Pose};

/// Positions in 1/16 mm (`|x| <= 32767 mm` fits an i32 many times over).
const Q4: u32 = 4;
/// `D` in 1/16 mm.
const D_Q4: i64 = (config::geometry::ROTATION_TO_REFERENCE.0 >> (16 - Q4)) as i64;
/// Below this axle-to-target distance the bearing from the axle means
/// little: the leg is driven straight without turning first (1/16 mm, 10 mm).
const MIN_BEARING_Q4: i64 = 10 << Q4;
/// A straight leg ends when the target is abeam within this, 1/16 mm
/// (1 mm: a loop tick at 0.13 m/s is 1.3 mm).
const ABEAM_Q4: i64 = 1 << Q4;

/// Where to go.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum Target {
    /// The reference point to `(x, y)`, mm.
    Point { x_mm: i32, y_mm: i32 },
    /// The heading to this one (turning in place).
    Heading(Angle),
}

/// What a [`Nav`] is doing now.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum Leg {
    Turn,
    Straight,
}

/// A `goto` or `face` under way.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub struct Nav {
    pub target: Target,
    pub leg: Leg,
    /// Since when (the loop's us) the front lidar has seen something in
    /// the way, if it does now.
    pub obstacle_since: Option<u32>,
    /// It started from a localization's fix (an estimate that grows too
    /// uncertain on the way then stops it, instead of localizing again).
    pub after_fix: bool,
}

/// What to do this tick.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum NavStep {
    /// Drive this motion; `ahead_mm` is how far the target is along the
    /// heading (forward legs: for the obstacle check).
    Drive {
        motion: Motion,
        ahead_mm: i32,
    },
    Arrived,
}

/// Why a `goto` or `face` cannot start.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum Refusal {
    /// The target is outside the box or nearer a wall than
    /// [`config::goto::TARGET_WALL_MARGIN_MM`].
    TooNearWall,
    /// The estimate's one-sigma position (mm) or heading (millidegrees) is
    /// above [`config::goto::MAX_SIGMA_MM`] / [`config::goto::MAX_SIGMA_MDEG`].
    Uncertain,
}

impl Refusal {
    pub fn text(self) -> &'static str {
        match self {
            Refusal::TooNearWall => "target outside the box or too close to a wall for the body",
            Refusal::Uncertain => "estimate too uncertain to steer by, even after locating: set the pose",
        }
    }
}

/// One-sigma position uncertainties `x`, `y` small enough to steer by:
/// `slack` times [`config::goto::MAX_SIGMA_MM`] (1 to start, 2 on the way, as the
/// uncertainty breathes between corrections).
pub fn position_steerable(x: crate::math::Length, y: crate::math::Length, slack: i32) -> bool {
    let limit = crate::math::Length::from_mm(config::goto::MAX_SIGMA_MM.saturating_mul(slack));
    x <= limit && y <= limit
}

/// Checks a target against the arena's walls (a heading always passes).
pub fn check_target(target: Target, arena: &Arena) -> Result<(), Refusal> {
    let Target::Point { x_mm, y_mm } = target else { return Ok(()) };
    let m = config::goto::TARGET_WALL_MARGIN_MM;
    let inside = |v: i32, size: i32| v >= m && v <= size.saturating_sub(m);
    // whole mm of the arena (Length is Q16): the floor keeps the test inward
    if inside(x_mm, arena.length_x.0 >> 16) && inside(y_mm, arena.width_y.0 >> 16) {
        Ok(())
    } else {
        Err(Refusal::TooNearWall)
    }
}

impl Nav {
    pub fn new(target: Target) -> Nav {
        Nav { target, leg: Leg::Turn, obstacle_since: None, after_fix: false }
    }

    /// Plans this tick from the estimated `pose` (see the module docs).
    pub fn step(&mut self, pose: &Pose) -> NavStep {
        let turn_tolerance = angle_lsb(config::goto::TURN_TOLERANCE_MDEG);
        let (tx, ty) = match self.target {
            Target::Heading(h) => {
                let e = h.diff(pose.theta);
                return if e.unsigned_abs() <= turn_tolerance { NavStep::Arrived } else { turn(e) };
            }
            Target::Point { x_mm, y_mm } => (i64::from(x_mm) << Q4, i64::from(y_mm) << Q4),
        };
        let (px, py) = (q4(pose.x.0), q4(pose.y.0));
        let (sin, cos) = sin_cos(pose.theta);
        let (ux, uy) = (i64::from(cos), i64::from(sin)); // Q30
                                                         // target from the reference point and from the axle
        let (dx, dy) = (tx.saturating_sub(px), ty.saturating_sub(py));
        // along the heading from the reference point (Q4)
        let ahead = dx.saturating_mul(ux).saturating_add(dy.saturating_mul(uy)) >> 30;
        // there: a straight leg first drives on until the target is abeam
        if length(dx, dy) <= i64::from(config::goto::ARRIVE_MM) << Q4
            && (self.leg == Leg::Turn || ahead.abs() <= ABEAM_Q4)
        {
            return NavStep::Arrived;
        }
        let (ax, ay) =
            (dx.saturating_add(D_Q4.saturating_mul(ux) >> 30), dy.saturating_add(D_Q4.saturating_mul(uy) >> 30));
        let r = length(ax, ay);
        let e = if r < MIN_BEARING_Q4 { 0 } else { bearing(ax, ay).diff(pose.theta) };
        let limit =
            if self.leg == Leg::Straight { angle_lsb(config::goto::STEER_TOLERANCE_MDEG) } else { turn_tolerance };
        if e.unsigned_abs() > limit {
            self.leg = Leg::Turn;
            return turn(e);
        }
        if ahead.abs() <= ABEAM_Q4 {
            // abeam but not there (a lateral miss): turn again from here
            self.leg = Leg::Turn;
            return turn(if e == 0 { 1 } else { e });
        }
        self.leg = Leg::Straight;
        let v = Speed::from_mm_s(config::goto::SPEED_MM_S);
        let ahead_mm = (ahead >> Q4) as i32; // |ahead| < 2^36 / 16: the box is far smaller
        NavStep::Drive { motion: Motion::Straight(if ahead > 0 { v } else { v.neg() }), ahead_mm }
    }
}

/// A turn in place towards a signed heading error (positive: clockwise).
fn turn(e: i32) -> NavStep {
    let w = TurnRate::from_mrad_s(config::goto::TURN_MRAD_S);
    NavStep::Drive { motion: Motion::Turn(if e > 0 { w } else { w.neg() }), ahead_mm: 0 }
}

/// Millidegrees as angle LSBs (2^32 a turn), positive.
fn angle_lsb(mdeg: i32) -> u32 {
    Angle::from_millidegrees(mdeg).0
}

/// A [`crate::math::Coord`]'s bits (Q32 mm) in 1/16 mm.
fn q4(c: i64) -> i64 {
    c >> (32 - Q4)
}

/// `|(x, y)|`, rounded down.
fn length(x: i64, y: i64) -> i64 {
    let sq = x.saturating_mul(x).saturating_add(y.saturating_mul(y));
    i64::from(isqrt64(sq.unsigned_abs()))
}

/// The heading (clockwise from north, x north and y east) of `(x, y)`.
/// `atan2` measures from +x towards +y, which is this frame's clockwise.
fn bearing(x: i64, y: i64) -> Angle {
    // scaled into i32: |x|, |y| < 2^36 (box coordinates in 1/16 mm)
    let shift = {
        let m = x.unsigned_abs().max(y.unsigned_abs());
        64u32.saturating_sub(m.leading_zeros()).saturating_sub(30)
    };
    atan2((y >> shift) as i32, (x >> shift) as i32)
}

#[cfg(test)]
#[allow(clippy::restriction)] // test code: a panic fails the test
mod tests {
    use super::*;
    use crate::math::Dt;
    use crate::model::step;

    fn pose(x: f64, y: f64, deg: f64) -> Pose {
        Pose::new(crate::math::Coord::from_mm_f64(x), crate::math::Coord::from_mm_f64(y), Angle::from_degrees_f64(deg))
    }

    /// Runs the planner on the exact kinematics (`model::step`, 10 ms
    /// ticks) and returns the pose it stops at and the ticks it took.
    fn drive(start: Pose, target: Target) -> (Pose, u32) {
        let mut nav = Nav::new(target);
        let mut p = start;
        for n in 0..5_000 {
            match nav.step(&p) {
                NavStep::Arrived => return (p, n),
                NavStep::Drive { motion, .. } => p = step(&p, motion, Dt::from_micros_saturating(10_000)),
            }
        }
        panic!("no arrival from {start:?} to {target:?}");
    }

    #[test]
    fn goto_arrives_from_every_side_and_heading() {
        let target = Target::Point { x_mm: 400, y_mm: 250 };
        for (x, y) in [(150.0, 100.0), (650.0, 400.0), (400.0, 100.0), (390.0, 240.0), (420.0, 280.0), (400.0, 250.0)] {
            for deg in [0.0, 45.0, 90.0, 179.0, 200.0, 315.0] {
                let (p, ticks) = drive(pose(x, y, deg), target);
                let miss = (p.x.to_mm_f64() - 400.0).hypot(p.y.to_mm_f64() - 250.0);
                // within the tolerance; a goto that drove there ends with the
                // target abeam (exact kinematics: 3.7 mm at most)
                let bound = if ticks > 50 { 4.0 } else { f64::from(config::goto::ARRIVE_MM) + 0.1 };
                assert!(miss <= bound, "from ({x}, {y}, {deg}): {miss:.1} mm off after {ticks} ticks");
            }
        }
    }

    #[test]
    fn face_stops_within_its_tolerance_turning_the_short_way() {
        for (from, to) in [(0.0, 90.0), (90.0, 0.0), (350.0, 10.0), (10.0, 350.0), (0.0, 179.0), (30.0, 30.5)] {
            let (p, ticks) = drive(pose(300.0, 200.0, from), Target::Heading(Angle::from_degrees_f64(to)));
            let off = (p.theta.diff(Angle::from_degrees_f64(to)) as f64 / 4_294_967_296.0 * 360.0).abs();
            assert!(off <= 1.0, "{from} -> {to}: {off:.2} degrees off");
            // the short way round at 2.4 rad/s (1.375 degrees a tick)
            let mut turn = (to - from + 360.0) % 360.0;
            if turn > 180.0 {
                turn = 360.0 - turn;
            }
            assert!(f64::from(ticks) <= turn / 1.375 + 1.0, "{from} -> {to}: {ticks} ticks");
        }
    }

    #[test]
    fn targets_near_a_wall_or_outside_are_refused() {
        let arena = Arena::DEFAULT; // 762.5 x 495
        let m = config::goto::TARGET_WALL_MARGIN_MM;
        assert_eq!(check_target(Target::Point { x_mm: m, y_mm: m }, &arena), Ok(()));
        assert_eq!(check_target(Target::Point { x_mm: 762 - m, y_mm: 495 - m }, &arena), Ok(()));
        for (x, y) in [(m - 1, 200), (200, m - 1), (763 - m, 200), (200, 496 - m), (-100, 200), (2000, 200)] {
            assert_eq!(check_target(Target::Point { x_mm: x, y_mm: y }, &arena), Err(Refusal::TooNearWall), "{x} {y}");
        }
        assert_eq!(check_target(Target::Heading(Angle::ZERO), &arena), Ok(()));
    }
}
