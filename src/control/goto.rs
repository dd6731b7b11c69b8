//! Going to a point or a heading on the estimate: `goto` and `face`.
//!
//! The robot turns in place about a turning centre `C` and drives
//! straight; the pose it reports (and the target) is its reference point
//! `P`. The caller says how far behind `P` the turns pivot, `c` (the axle's
//! `D` = [`config::geometry::ROTATION_TO_REFERENCE`] if the wheels turned
//! the body about their midpoint; a dragging skid pulls the centre further
//! back: [`config::goto::TURN_CENTRE_BEHIND_REFERENCE`] until the
//! estimator learns it). So the plan is made from `C = P - c u` (`u` the
//! heading's unit vector): turning in place leaves `C` where it is, and
//! once the heading points from `C` at the target `T`, a straight leg of
//! `|T - C| - c` (forward, or backward when the target is within `c` of
//! the centre) brings the reference point onto it. Each tick [`Nav::step`]
//! plans again from the newest estimate: a leg whose heading has drifted
//! past [`config::goto::STEER_TOLERANCE_MDEG`] turns again, a leg ends
//! where the target is abeam, and the goto ends when the reference point
//! is within [`config::goto::ARRIVE_MM`] of the target.
//!
//! A turn sweeps the body on a circle about `C` (`goto::room`). Before a
//! turn begins, that circle must clear every wall by
//! [`config::goto::TURN_WALL_MARGIN_MM`]; if it does not, the robot first
//! drives along its heading, forward or backward, whichever moves `C`
//! towards the safe middle of the box, until it does, then turns (once
//! begun, a turn is not checked again, so the two never alternate). Where
//! neither way along the heading makes room (it runs along a wall `C` is
//! too near), it turns where it stands, as before. A `face` turns where it
//! stands.
//!
//! Integer only: positions in 1/16 mm, angles as [`Angle`]s.

use crate::config;
use crate::math::{atan2, isqrt64, sin_cos, Angle, Length, Speed, TurnRate};
use crate::model::measurement::Arena;
use crate::model::{Motion, Pose};
use room::{may_drive, room, swept_radius, Room};

pub(crate) mod room;

/// Positions in 1/16 mm (`|x| <= 32767 mm` fits an i32 many times over).
const Q4: u32 = 4;
/// Below this centre-to-target distance the bearing from the centre means
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
    /// Not moving yet.
    Start,
    /// Turning in place (its room was checked as it began).
    Turn,
    Straight,
    /// Driving along the heading to make room for a turn.
    Room,
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
    /// Ticks it has stood waiting for an estimate too uncertain to steer
    /// by to settle ([`config::goto::SETTLE_MS`]); 0 while it steers.
    pub settling: u16,
    /// `# ok` said: false while a `goto` that found the estimate too
    /// uncertain at the start waits for it to settle.
    pub answered: bool,
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

/// A one-sigma heading uncertainty small enough to steer by: `slack` times
/// [`config::goto::MAX_SIGMA_MDEG`] (as [`position_steerable`]).
pub fn heading_steerable(theta: Angle, slack: i32) -> bool {
    // a one-sigma heading is small and positive: compare the LSBs
    theta.0 <= Angle::from_millidegrees(config::goto::MAX_SIGMA_MDEG.saturating_mul(slack)).0
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
        Nav { target, leg: Leg::Start, obstacle_since: None, after_fix: false, settling: 0, answered: true }
    }

    /// The slack on the steering limits ([`position_steerable`]): 1 to
    /// start, 2 once under way.
    pub fn slack(&self) -> i32 {
        if self.answered {
            2
        } else {
            1
        }
    }

    /// Plans this tick from the estimated `pose`, for turns pivoting
    /// `centre_behind` behind the reference point, in `arena` (see the
    /// module docs).
    pub fn step(&mut self, pose: &Pose, centre_behind: Length, arena: &Arena) -> NavStep {
        let turn_tolerance = angle_lsb(config::goto::TURN_TOLERANCE_MDEG);
        let (tx, ty) = match self.target {
            Target::Heading(h) => {
                let e = h.diff(pose.theta);
                return if e.unsigned_abs() <= turn_tolerance { NavStep::Arrived } else { turn(e) };
            }
            Target::Point { x_mm, y_mm } => (i64::from(x_mm) << Q4, i64::from(y_mm) << Q4),
        };
        let c = i64::from(centre_behind.0 >> (16 - Q4));
        let (px, py) = (q4(pose.x.0), q4(pose.y.0));
        let (sin, cos) = sin_cos(pose.theta);
        let (ux, uy) = (i64::from(cos), i64::from(sin)); // Q30
        let (cux, cuy) = (c.saturating_mul(ux) >> 30, c.saturating_mul(uy) >> 30);
        // target from the reference point
        let (dx, dy) = (tx.saturating_sub(px), ty.saturating_sub(py));
        // along the heading from the reference point (Q4)
        let ahead = dx.saturating_mul(ux).saturating_add(dy.saturating_mul(uy)) >> 30;
        // there: a straight leg first drives on until the target is abeam
        if length(dx, dy) <= i64::from(config::goto::ARRIVE_MM) << Q4
            && (self.leg != Leg::Straight || ahead.abs() <= ABEAM_Q4)
        {
            return NavStep::Arrived;
        }
        // target from the turning centre
        let (ax, ay) = (dx.saturating_add(cux), dy.saturating_add(cuy));
        let r = length(ax, ay);
        let e = if r < MIN_BEARING_Q4 { 0 } else { bearing(ax, ay).diff(pose.theta) };
        let limit =
            if self.leg == Leg::Straight { angle_lsb(config::goto::STEER_TOLERANCE_MDEG) } else { turn_tolerance };
        let v = Speed::from_mm_s(config::goto::SPEED_MM_S);
        let wanted = if e.unsigned_abs() > limit {
            Some(e)
        } else if ahead.abs() <= ABEAM_Q4 {
            // abeam but not there (a lateral miss): turn again from here
            Some(if e == 0 { 1 } else { e })
        } else {
            None
        };
        if let Some(e) = wanted {
            if self.leg != Leg::Turn {
                // a turn begins: room for the body's sweep about the centre?
                let (cx, cy) = (px.saturating_sub(cux), py.saturating_sub(cuy));
                if let Room::Drive { forward } = room(cx, cy, ux, uy, swept_radius(c), arena) {
                    // no obstacle check (`ahead_mm` 0): `may_drive` and the wall stop guard it
                    if may_drive(px, py, ux, uy, forward, arena) {
                        self.leg = Leg::Room;
                        let v = if forward { v } else { v.neg() };
                        return NavStep::Drive { motion: Motion::Straight(v), ahead_mm: 0 };
                    }
                }
            }
            self.leg = Leg::Turn;
            return turn(e);
        }
        self.leg = Leg::Straight;
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
mod tests;
