//! The benchmark's float versions (Rust f32 `src/float.rs`, C float
//! `csrc/step_c.c`) compute the same state update as the fixed-point core:
//! a benchmark of a wrong port would compare nothing.

use super::{Mismatches, Test, TestResult};
use crate::float::{c_step_safe, step as f32_step, PoseF, STOP, STRAIGHT, TURN};
use crate::println;
use core::hint::black_box;
use paperbot::config::geometry::ROTATION_TO_REFERENCE;
use paperbot::math::{Angle, Coord, Dt, Speed, TurnRate};
use paperbot::model::{step, Motion, Pose};

pub const TESTS: &[Test] = &[("f32_and_c_match_fixed", f32_and_c_match_fixed)];

/// The benchmark's cases: (name, kind, rate in mm/s or rad/s).
pub const CASES: [(&str, i32, f32); 3] = [("Stop", STOP, 0.0), ("Straight", STRAIGHT, 140.0), ("Turn", TURN, 3.0)];
pub const DT_S: f32 = 0.01;

pub fn fixed_motion(kind: i32, rate: f32) -> Motion {
    match kind {
        STRAIGHT => Motion::Straight(Speed::from_mm_s(rate as i32)),
        TURN => Motion::Turn(TurnRate::from_mrad_s((rate * 1000.0) as i32)),
        _ => Motion::Stop,
    }
}

pub fn fixed_pose(p: &PoseF) -> Pose {
    Pose::new(Coord::from_mm_f64(p.x as f64), Coord::from_mm_f64(p.y as f64), Angle::from_radians_f64(p.th as f64))
}

pub fn d_mm() -> f32 {
    ROTATION_TO_REFERENCE.to_mm_f64() as f32
}

fn f32_and_c_match_fixed() -> TestResult {
    let mut m = Mismatches::new();
    let mut worst = 0.0f32;
    for (name, kind, rate) in CASES {
        for k in 0..12 {
            let p0 = PoseF { x: 100.0, y: -50.0, th: k as f32 * 0.5 - 3.0 };
            let (mut pf, mut pc) = (p0, p0);
            f32_step(&mut pf, black_box(kind), rate, DT_S, d_mm());
            c_step_safe(&mut pc, black_box(kind), rate, DT_S, d_mm());
            let q = step(&fixed_pose(&p0), fixed_motion(kind, rate), Dt::from_micros_saturating(10_000));
            let (qx, qy) = (q.x.to_mm_f64() as f32, q.y.to_mm_f64() as f32);
            // f32 at 100 mm: 8e-6 mm per ulp; 1e-4 mm covers a few roundings
            let e = (pf.x - qx).abs().max((pf.y - qy).abs()).max((pc.x - qx).abs()).max((pc.y - qy).abs());
            worst = worst.max(e);
            if e > 1e-4 || (pf.th - pc.th).abs() > 1e-6 {
                m.fail(format_args!(
                    "{name} th {}: fixed ({qx}, {qy}) f32 ({}, {}) C ({}, {})",
                    p0.th, pf.x, pf.y, pc.x, pc.y
                ));
            }
        }
    }
    println!("      36 steps, worst |f32 or C - fixed| = {:.1e} mm", worst);
    m.result("the float ports do not compute the same step")
}
