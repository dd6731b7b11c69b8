//! The state update (report section 3.1), in fixed point.
//!
//! Frame: x to north, y to east, heading theta clockwise from north.
//! - Straight: `x += v t cos(theta)`, `y += v t sin(theta)`.
//! - Turn in place about the axle, `theta' = theta + w t`:
//!   `x' = x - D (cos(theta) - cos(theta'))`, `y' = y + D (sin(theta) - sin(theta'))`,
//!   exactly as the report writes it (D from the config).
//! - Stop: nothing moves.
//!
//! Integer only: two or four [`mul_hi`] products and one or two
//! [`sin_cos`] per step, no division, no 64-bit multiply. The heading keeps
//! a 16-bit sub-LSB fraction, so no rounding builds up with time.

use crate::config;
use crate::math::{mul_hi, sin_cos, Angle, Coord, Dt, Length};
use crate::model::actuator::Motion;

/// Position of the car's reference point and its heading.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug, Default)]
pub struct Pose {
    pub x: Coord,
    pub y: Coord,
    pub theta: Angle,
    /// Fraction of an [`Angle`] LSB (2^-16), carried between steps.
    pub theta_frac: u16,
}

impl Pose {
    pub const fn new(x: Coord, y: Coord, theta: Angle) -> Pose {
        Pose { x, y, theta, theta_frac: 0 }
    }
    pub fn from_mm(x_mm: i32, y_mm: i32, theta: Angle) -> Pose {
        Pose::new(Coord::from_length(Length::from_mm(x_mm)), Coord::from_length(Length::from_mm(y_mm)), theta)
    }
}

/// `D` in Q24 mm (the config asserts it is below 128 mm).
const D_Q24: i32 = config::geometry::ROTATION_TO_REFERENCE.0 << 8;

/// Advances `pose` by `motion` held for `dt`.
#[inline(never)]
pub fn step(pose: &Pose, motion: Motion, dt: Dt) -> Pose {
    match motion {
        Motion::Stop => *pose,
        Motion::Straight(v) => {
            let d = v.distance_q24(dt);
            let (s, c) = sin_cos(pose.theta);
            Pose { x: pose.x.add_q22(mul_hi(d, c)), y: pose.y.add_q22(mul_hi(d, s)), ..*pose }
        }
        Motion::Turn(w) => {
            let (rot, frac) = w.rotation(dt);
            let (f, carry) = pose.theta_frac.overflowing_add(frac);
            let theta = pose.theta.wrapping_add(rot).wrapping_add(Angle(u32::from(carry)));
            let (s0, c0) = sin_cos(pose.theta);
            let (s1, c1) = sin_cos(theta);
            // each product is at most D = 2^31 / 2^8 in Q22: the differences fit
            let dx = mul_hi(D_Q24, c1) - mul_hi(D_Q24, c0);
            let dy = mul_hi(D_Q24, s0) - mul_hi(D_Q24, s1);
            Pose { x: pose.x.add_q22(dx), y: pose.y.add_q22(dy), theta, theta_frac: f }
        }
    }
}
