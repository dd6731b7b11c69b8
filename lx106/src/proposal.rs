//! NOT the core: a variant of `paperbot::model::step` built from the core's
//! public pieces, to put numbers on the changes proposed in BENCHMARKS.md
//! ("Where the step's instructions go"). Checked against the same f64
//! vectors as the real step (suite `state::proposal_matches_vectors`), so its
//! counts are for a correct state update.
//!
//! Differences from `src/model/state.rs`:
//! 1. positions add with `wrapping_add` instead of `saturating_add` (an i64
//!    saturating add is ~20 lx106 instructions, a wrapping one 4); a Coord
//!    only wraps after 2^63 * 2^-32 mm = 2147 km of travel in one direction;
//! 2. a turn takes one product per axis, `D (cos th' - cos th)` with the
//!    difference of the Q30 values halved (Q29, cannot overflow) and D in
//!    Q25 (56 mm * 2^25 < 2^31), instead of two products and a difference;
//! 3. the pose is stepped in place (`&mut Pose`) instead of copied: Stop
//!    costs a call and a return, Straight writes only x and y.

use paperbot::config::geometry::ROTATION_TO_REFERENCE;
use paperbot::math::{mul_hi, sin_cos, Angle, Coord, Dt};
use paperbot::model::{Motion, Pose};

/// D in Q25 mm (the config asserts D < 128 mm, so D * 2^25 < 2^32; at 56 mm it is below 2^31).
const D_Q25: i32 = ROTATION_TO_REFERENCE.0 << 9;

#[inline(always)]
fn add_q22(c: Coord, step: i32) -> Coord {
    Coord(c.0.wrapping_add(i64::from(step) << 10))
}

/// The vector tests' signature (the core's): a copy, stepped in place.
pub fn step(pose: &Pose, motion: Motion, dt: Dt) -> Pose {
    let mut p = *pose;
    step_mut(&mut p, motion, dt);
    p
}

/// Steps the pose in place: Stop touches nothing, Straight writes x and y only.
#[inline(never)]
pub fn step_mut(pose: &mut Pose, motion: Motion, dt: Dt) {
    match motion {
        Motion::Stop => {}
        Motion::Straight(v) => {
            let d = v.distance_q24(dt);
            let (s, c) = sin_cos(pose.theta);
            pose.x = add_q22(pose.x, mul_hi(d, c));
            pose.y = add_q22(pose.y, mul_hi(d, s));
        }
        Motion::Turn(w) => {
            let (rot, frac) = w.rotation(dt);
            let (f, carry) = pose.theta_frac.overflowing_add(frac);
            let theta = pose.theta.wrapping_add(rot).wrapping_add(Angle(u32::from(carry)));
            let (s0, c0) = sin_cos(pose.theta);
            let (s1, c1) = sin_cos(theta);
            // |c1/2 - c0/2| <= 2^30: Q29; D Q25 * Q29 / 2^32 = Q22
            pose.x = add_q22(pose.x, mul_hi(D_Q25, (c1 >> 1) - (c0 >> 1)));
            pose.y = add_q22(pose.y, mul_hi(D_Q25, (s0 >> 1) - (s1 >> 1)));
            pose.theta = theta;
            pose.theta_frac = f;
        }
    }
}
