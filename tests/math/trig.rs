//! sin/cos, atan2 and mul_hi against f64.
use crate::common;
use common::rng::Rng;
use paperbot::math::{atan2, mul_hi, sin_cos, Angle};
use std::f64::consts::TAU;

const Q30: f64 = (1u64 << 30) as f64;

fn err_at(a: u32) -> f64 {
    let (s, c) = sin_cos(Angle(a));
    let r = Angle(a).to_radians_f64();
    ((s as f64 / Q30) - r.sin()).abs().max(((c as f64 / Q30) - r.cos()).abs())
}

#[test]
fn sin_table_matches_f64() {
    // the committed table must be exactly round(sin(i pi/512) 2^30): probe it through
    // sin_cos at the exact table angles, where the correction terms vanish
    for i in 0u32..=256 {
        let (s, _) = sin_cos(Angle(i << 22));
        let want = ((i as f64) * std::f64::consts::PI / 512.0).sin() * Q30;
        assert_eq!(s as i64, want.round() as i64, "table entry {i}");
    }
}

#[test]
fn sin_cos_error_below_2e7_everywhere() {
    let mut worst: f64 = 0.0;
    // every table interval, at its centre, its edges (the rounding boundary) and inside
    for k in 0u32..1024 {
        let base = k << 22;
        for off in [0u32, 1, (1 << 21) - 1, 1 << 21, (1 << 21) + 1, (1 << 22) - 1, 12345, 3_000_000] {
            worst = worst.max(err_at(base.wrapping_add(off)));
        }
    }
    let mut rng = Rng::new(7);
    for _ in 0..1_000_000 {
        worst = worst.max(err_at(rng.next_u32()));
    }
    println!("sin_cos max abs error {worst:.3e}");
    assert!(worst < 1.2e-7, "sin_cos error {worst:e}");
}

#[test]
fn sin_cos_quadrants_and_wrap() {
    let table = [
        (0.0, 0.0, 1.0),
        (90.0, 1.0, 0.0),
        (180.0, 0.0, -1.0),
        (270.0, -1.0, 0.0),
        (360.0, 0.0, 1.0),
        (-90.0, -1.0, 0.0),
    ];
    for (deg, s, c) in table {
        let (gs, gc) = sin_cos(Angle::from_degrees_f64(deg));
        assert!((gs as f64 / Q30 - s).abs() < 1e-8 && (gc as f64 / Q30 - c).abs() < 1e-8, "{deg}: {gs} {gc}");
    }
}

#[test]
fn atan2_matches_f64() {
    let mut rng = Rng::new(11);
    let mut worst: f64 = 0.0;
    let mut cases: Vec<(i32, i32)> =
        vec![(0, 1), (1, 0), (0, -1), (-1, 0), (1, 1), (-1, -1), (i32::MAX, i32::MIN), (i32::MIN, i32::MIN), (5, -3)];
    for _ in 0..200_000 {
        let scale = 1 << rng.range_u32(4, 30);
        cases.push(((rng.next_u32() as i32) % scale, (rng.next_u32() as i32) % scale));
    }
    for (y, x) in cases {
        if x == 0 && y == 0 {
            continue;
        }
        let got = atan2(y, x).to_radians_f64();
        let want = (y as f64).atan2(x as f64).rem_euclid(TAU);
        let mut e = (got - want).abs();
        e = e.min(TAU - e);
        // small integer vectors: the inputs themselves limit the precision
        let tol = 2e-7 + 1.0 / (x as f64).hypot(y as f64);
        assert!(e < tol, "atan2({y}, {x}) = {got}, want {want}");
        if (x as f64).hypot(y as f64) > 1e4 {
            worst = worst.max(e);
        }
    }
    println!("atan2 max abs error {worst:.3e} rad");
    assert!(worst < 2e-7);
}

#[test]
fn atan2_of_zero_is_zero() {
    assert_eq!(atan2(0, 0), Angle::ZERO);
}

#[test]
fn mul_hi_within_3_lsb_of_exact() {
    let mut rng = Rng::new(3);
    let edges = [i32::MIN, i32::MIN + 1, -1, 0, 1, i32::MAX, 1 << 30, -(1 << 30), 0xFFFF, -0x10000];
    let mut pairs: Vec<(i32, i32)> = edges.iter().flat_map(|&a| edges.iter().map(move |&b| (a, b))).collect();
    for _ in 0..1_000_000 {
        pairs.push((rng.next_u32() as i32, rng.next_u32() as i32));
    }
    for (a, b) in pairs {
        let exact = (i64::from(a) * i64::from(b)) >> 32;
        let got = i64::from(mul_hi(a, b));
        assert!((0..=3).contains(&(exact - got)), "mul_hi({a}, {b}) = {got}, exact {exact}");
    }
}
