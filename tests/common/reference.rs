//! The f64 reference of the state update (report section 3.1, with the
//! sign of its turn's y term corrected: see src/model/state.rs), fed the
//! exact values of the fixed-point inputs, so a test compares arithmetic.

use paperbot::config::geometry::ROTATION_TO_REFERENCE;
use paperbot::math::Dt;
use paperbot::model::{Motion, Pose};
use std::f64::consts::TAU;

/// The reference works on the one host pose type (theta in [0, 2 pi)
/// after a turn).
pub use paperbot::sim::body::PoseF64;

pub fn step(p: PoseF64, motion: Motion, dt: Dt) -> PoseF64 {
    let t = f64::from(dt.as_micros()) * 1e-6;
    let d = ROTATION_TO_REFERENCE.to_mm_f64();
    match motion {
        Motion::Stop => p,
        Motion::Straight(v) => {
            let s = v.to_mps_f64() * 1000.0 * t;
            PoseF64 { x: p.x + s * p.theta.cos(), y: p.y + s * p.theta.sin(), theta: p.theta }
        }
        Motion::Turn(w) => {
            let th = p.theta + w.to_rad_s_f64() * t;
            PoseF64 {
                x: p.x - d * (p.theta.cos() - th.cos()),
                y: p.y - d * (p.theta.sin() - th.sin()),
                theta: th.rem_euclid(TAU),
            }
        }
    }
}

/// Signed heading difference in radians, in (-pi, pi].
pub fn heading_error(a: f64, b: f64) -> f64 {
    let e = (a - b).rem_euclid(TAU);
    if e > std::f64::consts::PI {
        e - TAU
    } else {
        e
    }
}
