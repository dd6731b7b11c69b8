//! `paperbot::model::step`, the state update of report 3.1, against poses
//! the host computed in f64 from the report's equations (`crate::vectors`).

use super::{check, Mismatches, Test, TestResult};
use crate::println;
use crate::vectors::{Mv, SEQUENCES, STEP};
use core::hint::black_box;
use paperbot::math::{Angle, Coord, Dt, Speed, TurnRate};
use paperbot::model::{step, Motion, Pose};

pub const TESTS: &[Test] = &[
    ("step_vectors", step_vectors),
    ("step_sequences_no_drift", step_sequences),
    ("zero_dt_moves_nothing", zero_dt),
];

/// One step's position error bound: sin/cos 2e-7 times D = 56 mm (twice for
/// a turn), or times the step length (at most 65.5 mm), plus the Q22
/// rounding of the products: 3e-5 mm, in Coord bits (2^-32 mm).
pub const STEP_TOL: i64 = 128_849; // 3e-5 * 2^32

pub fn motion(m: Mv) -> Motion {
    match m {
        Mv::Stop => Motion::Stop,
        Mv::Straight(v) => Motion::Straight(Speed::from_bits(v)),
        Mv::Turn(w) => Motion::Turn(TurnRate::from_bits(w)),
    }
}

fn dt(us: u16) -> Dt {
    Dt::from_micros_saturating(u32::from(us))
}

fn step_vectors() -> TestResult {
    vectors_with(step, "")
}

fn vectors_with(step: fn(&Pose, Motion, Dt) -> Pose, who: &str) -> TestResult {
    let mut m = Mismatches::new();
    let mut worst = 0i64;
    for (i, v) in STEP.iter().enumerate() {
        let p = Pose::from_parts(Coord(v.x), Coord(v.y), Angle(v.theta), v.frac);
        let q = step(black_box(&p), black_box(motion(v.motion)), black_box(dt(v.dt_us)));
        let (ex, ey) = ((q.x.0 - v.exp_x).abs(), (q.y.0 - v.exp_y).abs());
        worst = worst.max(ex).max(ey);
        if q.theta.0 != v.exp_theta || q.theta_frac != v.exp_frac || ex > STEP_TOL || ey > STEP_TOL {
            m.fail(format_args!(
                "#{i} {:?} dt {}: got ({}, {}, {:#010x}.{:04x}) want ({}, {}, {:#010x}.{:04x})",
                v.motion, v.dt_us, q.x.0, q.y.0, q.theta.0, q.theta_frac, v.exp_x, v.exp_y, v.exp_theta, v.exp_frac
            ));
        }
        if let Mv::Stop = v.motion {
            if q != p {
                m.fail(format_args!("#{i}: Stop changed the pose"));
            }
        }
    }
    println!(
        "      {}{} steps (stop, straight, turn; every quadrant, dt 1 us..65.5 ms): heading exact, worst position error {:.2e} mm (bound 3e-5)",
        who,
        STEP.len(),
        worst as f32 / 4294967296.0
    );
    m.result("state update differs from the f64 reference")
}

fn step_sequences() -> TestResult {
    let mut m = Mismatches::new();
    for s in SEQUENCES {
        let mut p = Pose::default();
        let mut n = 0i64;
        for seg in s.segments {
            for _ in 0..seg.steps {
                p = step(&p, black_box(motion(seg.motion)), dt(seg.dt_us));
            }
            n += i64::from(seg.steps);
        }
        let (ex, ey) = ((p.x.0 - s.exp_x).abs(), (p.y.0 - s.exp_y).abs());
        println!(
            "      {:<14} {:5} steps: end ({:9.3}, {:9.3}) mm, {:8.3} deg; error ({:.1e}, {:.1e}) mm, heading exact: {}",
            s.name,
            n,
            p.x.to_mm_f64() as f32,
            p.y.to_mm_f64() as f32,
            p.theta.to_millidegrees() as f32 / 1000.0,
            ex as f32 / 4294967296.0,
            ey as f32 / 4294967296.0,
            p.theta.0 == s.exp_theta && p.theta_frac == s.exp_frac
        );
        // errors of independent steps add up at worst linearly
        if p.theta.0 != s.exp_theta || p.theta_frac != s.exp_frac || ex > n * STEP_TOL || ey > n * STEP_TOL {
            m.fail(format_args!("{}: ({}, {}) want ({}, {})", s.name, p.x.0, p.y.0, s.exp_x, s.exp_y));
        }
    }
    m.result("a path drifts from the f64 reference")
}

fn zero_dt() -> TestResult {
    let p = Pose::from_parts(Coord(123_456_789_012), Coord(-42), Angle(0x1234_5678), 0xabcd);
    for mv in [Mv::Stop, Mv::Straight(Speed::MAX.to_bits()), Mv::Turn(TurnRate::MAX.to_bits()), Mv::Turn(-1)] {
        check(step(black_box(&p), motion(mv), dt(black_box(0))) == p, "a zero time step moved the pose")?;
    }
    Ok(())
}
