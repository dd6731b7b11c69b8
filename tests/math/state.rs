//! The fixed-point state update against the f64 reference of the report's
//! equations.
use crate::common;
use common::reference::{self, heading_error, PoseF64};
use common::rng::Rng;
use paperbot::config::geometry::ROTATION_TO_REFERENCE;
use paperbot::math::{Angle, Coord, Dt, Speed, TurnRate};
use paperbot::model::{step, Motion, Pose};

fn ms(n: u32) -> Dt {
    Dt::from_micros(n * 1000).unwrap()
}

fn assert_close(p: &Pose, r: &PoseF64, pos_mm: f64, theta_rad: f64, what: &str) {
    let f = PoseF64::from_pose(p);
    let (ex, ey, et) = ((f.x - r.x).abs(), (f.y - r.y).abs(), heading_error(f.theta, r.theta).abs());
    assert!(ex < pos_mm && ey < pos_mm && et < theta_rad, "{what}: fixed {f:?} vs reference {r:?}");
}

#[test]
fn stop_changes_nothing() {
    let p = Pose::from_mm(123, -45, Angle::from_degrees_f64(33.0));
    assert_eq!(step(&p, Motion::Stop, ms(50)), p);
}

#[test]
fn straight_cases_follow_the_heading() {
    // (heading deg, speed m/s, expected dx mm, dy mm) for 1 s in 20 steps of 50 ms
    let table = [
        (0.0, 0.1, 100.0, 0.0),    // north: +x
        (90.0, 0.1, 0.0, 100.0),   // east: +y
        (180.0, 0.1, -100.0, 0.0), // south
        (270.0, 0.1, 0.0, -100.0), // west
        (45.0, 0.1, 70.710678, 70.710678),
        (30.0, -0.1, -86.602540, -50.0), // backward
    ];
    for (deg, v, dx, dy) in table {
        let mut p = Pose::from_mm(0, 0, Angle::from_degrees_f64(deg));
        for _ in 0..20 {
            p = step(&p, Motion::Straight(Speed::from_mps_f64(v)), ms(50));
        }
        let f = PoseF64::from_pose(&p);
        assert!((f.x - dx).abs() < 1e-3 && (f.y - dy).abs() < 1e-3, "heading {deg}: {f:?}");
        assert_eq!(p.theta, Angle::from_degrees_f64(deg), "straight motion keeps the heading");
    }
}

#[test]
fn turn_case_swings_the_reference_point_about_the_axle() {
    let d = ROTATION_TO_REFERENCE.to_mm_f64();
    // a quarter turn clockwise from north: theta 0 -> 90 deg; the reference
    // point D ahead of the axle swings from north of it to east of it:
    // x' = x - D (cos 0 - cos 90) = -D, y' = y - D (sin 0 - sin 90) = +D
    let w = TurnRate::from_rad_s_f64(std::f64::consts::FRAC_PI_2); // 90 deg in 1 s
    let mut p = Pose::from_mm(0, 0, Angle::ZERO);
    for _ in 0..20 {
        p = step(&p, Motion::Turn(w), ms(50));
    }
    let f = PoseF64::from_pose(&p);
    assert!((f.theta.to_degrees() - 90.0).abs() < 1e-4, "{f:?}");
    assert!((f.x + d).abs() < 1e-3 && (f.y - d).abs() < 1e-3, "{f:?}");
    // and back counter-clockwise returns exactly where it started
    for _ in 0..20 {
        p = step(&p, Motion::Turn(w.neg()), ms(50));
    }
    let f = PoseF64::from_pose(&p);
    assert!(f.x.abs() < 1e-5 && f.y.abs() < 1e-5 && heading_error(f.theta, 0.0).abs() < 1e-8, "{f:?}");
}

#[test]
fn heading_wraps_at_0_and_360() {
    // clockwise through 360: from 350 deg, +20 deg
    let w = TurnRate::from_rad_s_f64(20f64.to_radians());
    let mut p = Pose::from_mm(0, 0, Angle::from_degrees_f64(350.0));
    let mut r = PoseF64::from_pose(&p);
    for _ in 0..100 {
        p = step(&p, Motion::Turn(w), ms(10));
        r = reference::step(r, Motion::Turn(w), ms(10));
    }
    assert!((p.theta.to_millidegrees() as i64 - 10_000).abs() <= 1, "{:?}", p.theta);
    assert_close(&p, &r, 1e-4, 1e-8, "cw through 360");
    // counter-clockwise through 0: back to 350
    for _ in 0..100 {
        p = step(&p, Motion::Turn(w.neg()), ms(10));
        r = reference::step(r, Motion::Turn(w.neg()), ms(10));
    }
    assert!((p.theta.to_millidegrees() as i64 - 350_000).abs() <= 1, "{:?}", p.theta);
    assert_close(&p, &r, 1e-4, 1e-8, "ccw through 0");
    // many full turns lose nothing: 100 turns at 2 pi rad/s, 1000 steps of 10 ms... per turn
    let w = TurnRate::from_rad_s_f64(std::f64::consts::TAU);
    let start = Pose::from_mm(5, 7, Angle::from_degrees_f64(123.0));
    let mut p = start;
    let mut r = PoseF64::from_pose(&p);
    for _ in 0..10_000 {
        p = step(&p, Motion::Turn(w), ms(10));
        r = reference::step(r, Motion::Turn(w), ms(10));
    }
    assert_close(&p, &r, 1e-3, 1e-6, "100 turns");
}

/// The bar: 100,000 steps of random motions with dt in 5..50 ms stay
/// within 1 mm and 1e-4 rad of the f64 reference.
#[test]
fn random_motions_track_the_f64_reference() {
    for seed in [1u64, 2, 3] {
        let mut rng = Rng::new(seed);
        let mut p = Pose::new(Coord::ZERO, Coord::ZERO, Angle(rng.next_u32()));
        let mut r = PoseF64::from_pose(&p);
        let mut motion = Motion::Stop;
        let (mut worst_pos, mut worst_th): (f64, f64) = (0.0, 0.0);
        for i in 0..100_000 {
            // hold a motion for a random number of steps, like a driven robot
            if i % 37 == 0 || rng.range_u32(0, 20) == 0 {
                motion = match rng.range_u32(0, 4) {
                    0 => Motion::Stop,
                    1 => Motion::Straight(Speed::from_mps_f64(rng.range_f64(0.12, 0.15))),
                    2 => Motion::Straight(Speed::from_mps_f64(-rng.range_f64(0.12, 0.15))),
                    3 => Motion::Turn(TurnRate::from_rad_s_f64(rng.range_f64(2.1, 3.3))),
                    _ => Motion::Turn(TurnRate::from_rad_s_f64(-rng.range_f64(2.1, 3.3))),
                };
            }
            let dt = Dt::from_micros(rng.range_u32(5_000, 50_000)).unwrap();
            p = step(&p, motion, dt);
            r = reference::step(r, motion, dt);
            let f = PoseF64::from_pose(&p);
            worst_pos = worst_pos.max((f.x - r.x).abs()).max((f.y - r.y).abs());
            worst_th = worst_th.max(heading_error(f.theta, r.theta).abs());
        }
        println!("seed {seed}: worst position error {worst_pos:.2e} mm, heading {worst_th:.2e} rad, end {r:?}");
        assert!(worst_pos < 1.0, "position drifted {worst_pos} mm");
        assert!(worst_th < 1e-4, "heading drifted {worst_th} rad");
    }
}

/// Constant motion at the loop rate for an hour: rounding must not build up.
#[test]
fn an_hour_of_constant_motion_does_not_drift() {
    let dt = ms(10);
    let v = Motion::Straight(Speed::from_mps_f64(0.137));
    let w = Motion::Turn(TurnRate::from_rad_s_f64(2.71));
    let mut p = Pose::from_mm(0, 0, Angle::from_degrees_f64(17.0));
    let mut r = PoseF64::from_pose(&p);
    for i in 0..360_000 {
        let m = if (i / 500) % 2 == 0 { v } else { w };
        p = step(&p, m, dt);
        r = reference::step(r, m, dt);
    }
    assert_close(&p, &r, 1.0, 1e-4, "an hour at 100 Hz");
}

/// The pose caches sin/cos of its heading; a heading written from outside
/// (the estimator's correction, a pose reset) must never use a stale cache.
#[test]
fn heading_set_from_outside_is_honoured() {
    let v = Motion::Straight(Speed::from_mps_f64(0.1));
    let mut p = Pose::from_mm(0, 0, Angle::ZERO);
    p = step(&p, v, ms(10)); // cache now holds 0 deg
    p.theta = Angle::from_degrees_f64(90.0);
    let q = step(&p, v, ms(10));
    let f = PoseF64::from_pose(&q);
    assert!((f.x - 1.0).abs() < 1e-6 && (f.y - 1.0).abs() < 1e-6, "{f:?}: moved east by 1 mm after 1 mm north");
    // a turn after an outside change starts from the new heading too
    let mut t = Pose::from_mm(0, 0, Angle::ZERO);
    t = step(&t, Motion::Turn(TurnRate::from_rad_s_f64(1.0)), ms(10));
    t.theta = Angle::from_degrees_f64(180.0);
    let r = reference::step(PoseF64::from_pose(&t), Motion::Turn(TurnRate::from_rad_s_f64(1.0)), ms(10));
    assert_close(&step(&t, Motion::Turn(TurnRate::from_rad_s_f64(1.0)), ms(10)), &r, 1e-5, 1e-8, "turn after reset");
}
