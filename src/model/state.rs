//! The state update (report section 3.1), in fixed point.
//!
//! Frame: x to north, y to east, heading theta clockwise from north.
//! - Straight: `x += v t cos(theta)`, `y += v t sin(theta)`.
//! - Turn in place about the axle, `theta' = theta + w t`, the reference
//!   point D ahead of the axle swinging round it:
//!   `x' = x - D (cos(theta) - cos(theta'))`, `y' = y - D (sin(theta) - sin(theta'))`.
//!   The x line is the report's; the report prints `y' = y + D (...)`, which
//!   moves the point the wrong way for every heading but 0 and 180 deg (facing
//!   north and turning clockwise, the point ahead of the axle moves east, not
//!   west). No point fixed on the car follows the printed form; a rigid body
//!   follows this one (see docs/architecture.md and `tests/sim/simulate.rs`).
//! - Stop: nothing moves.
//!
//! Integer only: two [`mul_hi`] products and at most one [`sin_cos`] per
//! step, no division, no 64-bit multiply. The heading keeps a 16-bit sub-LSB
//! fraction, so no rounding builds up with time. The pose caches the sine
//! and cosine of its heading (checked against the heading before each use,
//! so a heading set from outside is never paired with a stale cache): a
//! straight step then needs no `sin_cos` at all and a turn only the new one.

use crate::config;
use crate::math::{mul_hi, sin_cos, Angle, Coord, Dt, Length};
use crate::model::actuator::Motion;

/// A turn's lever: how far the reference point is from the point a turn
/// in place leaves where it stands, Q23 mm (0 to 255 mm). About the axle
/// it is `D` ([`Lever::AXLE`]); a car whose skid drags turns about a point
/// further back (`model::estimator::pivot`).
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
pub struct Lever(i32);

impl Lever {
    /// `D`: turns about the axle (the config asserts `D` below 128 mm).
    pub const AXLE: Lever = Lever(config::geometry::ROTATION_TO_REFERENCE.0 << 7);

    /// `D` plus `behind` (Q16 mm, the pivot behind the axle), kept within
    /// 0 to 255 mm.
    pub fn behind_axle(behind: i32) -> Lever {
        let mm_q16 = config::geometry::ROTATION_TO_REFERENCE.0.saturating_add(behind);
        Lever(mm_q16.clamp(0, 255 << 16) << 7)
    }
}

/// `sin_cos(at)` and the lever times it, remembered.
#[derive(Clone, Copy, Debug)]
struct Trig {
    at: Angle,
    lever: Lever,
    /// Q2.30
    sin: i32,
    cos: i32,
    /// `lever sin`, `lever cos` in Q21 mm (|.| < 2^30).
    d_sin: i32,
    d_cos: i32,
}

impl Trig {
    // step bar (as every inline attribute in this file)
    #[inline(always)]
    fn of(at: Angle, lever: Lever) -> Trig {
        Trig::with(at, sin_cos(at), lever)
    }
    #[inline(always)]
    fn with(at: Angle, (sin, cos): (i32, i32), lever: Lever) -> Trig {
        Trig { at, lever, sin, cos, d_sin: mul_hi(lever.0, sin), d_cos: mul_hi(lever.0, cos) }
    }
}

/// Position of the car's reference point and its heading.
#[derive(Clone, Copy, Debug)]
pub struct Pose {
    pub x: Coord,
    pub y: Coord,
    pub theta: Angle,
    /// Fraction of an [`Angle`] LSB (2^-16), carried between steps.
    pub theta_frac: u16,
    trig: Trig,
}

impl PartialEq for Pose {
    fn eq(&self, o: &Pose) -> bool {
        (self.x, self.y, self.theta, self.theta_frac) == (o.x, o.y, o.theta, o.theta_frac)
    }
}
impl Eq for Pose {}

impl core::hash::Hash for Pose {
    fn hash<H: core::hash::Hasher>(&self, h: &mut H) {
        (self.x, self.y, self.theta, self.theta_frac).hash(h)
    }
}

impl Default for Pose {
    fn default() -> Pose {
        Pose::new(Coord::ZERO, Coord::ZERO, Angle::ZERO)
    }
}

impl Pose {
    pub fn new(x: Coord, y: Coord, theta: Angle) -> Pose {
        Pose { x, y, theta, theta_frac: 0, trig: Trig::of(theta, Lever::AXLE) }
    }
    /// With a sub-LSB heading fraction (to restore a pose exactly).
    pub fn from_parts(x: Coord, y: Coord, theta: Angle, theta_frac: u16) -> Pose {
        Pose { theta_frac, ..Pose::new(x, y, theta) }
    }
    pub fn from_mm(x_mm: i32, y_mm: i32, theta: Angle) -> Pose {
        Pose::new(Coord::from_length(Length::from_mm(x_mm)), Coord::from_length(Length::from_mm(y_mm)), theta)
    }
    /// Takes `from`'s place and heading (its own sine and cosine cache
    /// follows when next read).
    // tick bar: field by field (a pose assigned whole is a memmove call,
    // 121 instructions; the cache too, another 80)
    #[inline(always)]
    pub fn take(&mut self, from: &Pose) {
        (self.x, self.y, self.theta, self.theta_frac) = (from.x, from.y, from.theta, from.theta_frac);
    }
    /// `(sin theta, cos theta)` in Q2.30, from the cache when it is current.
    #[inline(always)]
    pub fn sin_cos(&mut self) -> (i32, i32) {
        let t = self.trig();
        (t.sin, t.cos)
    }
    /// `(sin theta, cos theta)` in Q2.30 as the cache holds them: current
    /// after [`Pose::sin_cos`].
    // tick bar: read in the lidar's row (estimator/lag.rs), as the cache
    #[inline(always)]
    pub fn cached_sin_cos(&self) -> (i32, i32) {
        (self.trig.sin, self.trig.cos)
    }
    /// `(lever sin theta, lever cos theta)` in Q21 mm for the lever the
    /// sine and cosine cache holds: how the reference point moves per
    /// radian turned about it. Current after [`Pose::sin_cos`]; a turn's
    /// step leaves the cache for its lever (the pivot's).
    // tick bar: as `cached_sin_cos`
    #[inline(always)]
    pub fn cached_swing(&self) -> (i32, i32) {
        (self.trig.d_sin, self.trig.d_cos)
    }
    /// The cache for the lever it holds.
    // tick bar: the cache's check inlined into the beam and the step
    #[inline(always)]
    fn trig(&mut self) -> Trig {
        self.trig_about(self.trig.lever)
    }
    /// The cache for a turn about `lever`.
    // tick bar: as `trig`
    #[inline(always)]
    fn trig_about(&mut self, lever: Lever) -> Trig {
        if self.trig.at != self.theta || self.trig.lever != lever {
            self.trig = Trig::of(self.theta, lever);
        }
        self.trig
    }
}

/// Advances `pose` in place by `motion` held for `dt`, turning about the
/// axle: the robot's path ([`advance_about`] with [`Lever::AXLE`]).
// step bar: the bar measures this one call (its lever a constant)
#[inline(never)]
pub fn advance(pose: &mut Pose, motion: Motion, dt: Dt) {
    step_about(pose, motion, dt, Lever::AXLE);
}

/// Advances `pose` in place by `motion` held for `dt`, a turn swinging
/// the reference point on `lever` (the module docs' `D`).
// step bar: out of line as `advance` (their one body inlined into each)
#[inline(never)]
pub fn advance_about(pose: &mut Pose, motion: Motion, dt: Dt, lever: Lever) {
    step_about(pose, motion, dt, lever);
}

/// The body of [`advance`] and [`advance_about`].
#[inline(always)]
fn step_about(pose: &mut Pose, motion: Motion, dt: Dt, lever: Lever) {
    match motion {
        Motion::Stop => {}
        Motion::Straight(v) => {
            let d = v.distance_q24(dt); // Q24 mm, |d| < 2^30
            let (s, c) = pose.sin_cos();
            // Q24 * Q30 / 2^32 = Q22
            pose.x = pose.x.add_q22(mul_hi(d, c));
            pose.y = pose.y.add_q22(mul_hi(d, s));
        }
        Motion::Turn(w) => {
            let (rot, frac) = w.rotation(dt);
            let (f, carry) = pose.theta_frac.overflowing_add(frac);
            let theta = pose.theta.wrapping_add(rot).wrapping_add(Angle(u32::from(carry)));
            let t0 = pose.trig_about(lever);
            let t1 = Trig::with(theta, sin_cos(theta), lever);
            // Q21 differences of values below 2^30: no overflow. The products
            // of one step's new heading are the next step's old ones, so a
            // turn telescopes exactly: no rounding builds up.
            pose.x = pose.x.add_q21(t1.d_cos - t0.d_cos);
            pose.y = pose.y.add_q21(t1.d_sin - t0.d_sin);
            pose.theta = theta;
            pose.theta_frac = f;
            pose.trig = t1;
        }
    }
}

/// Returns `pose` advanced by `motion` held for `dt` (a copy; see [`advance`]).
pub fn step(pose: &Pose, motion: Motion, dt: Dt) -> Pose {
    let mut p = *pose;
    advance(&mut p, motion, dt);
    p
}
