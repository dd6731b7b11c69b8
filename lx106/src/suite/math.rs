//! `paperbot::math`: mul_hi, the unit types' conversions, sin_cos and atan2
//! (against f64 values from the host, `crate::vectors`).

use super::{check, Mismatches, Test, TestResult};
use crate::println;
use crate::vectors::{ATAN2, SIN_COS};
use core::hint::black_box;
use paperbot::math::{atan2, mul_hi, sin_cos, Angle, Dt, Length, Speed, TurnRate};

pub const TESTS: &[Test] = &[
    ("mul_hi_within_3_lsb", mul_hi_within_3_lsb),
    ("angle_millidegrees", angle_millidegrees),
    ("length_units", length_units),
    ("speed_distance_q24", speed_distance_q24),
    ("turn_rate_rotation_exact", turn_rate_rotation_exact),
    ("sin_cos_vs_f64", sin_cos_vs_f64),
    ("atan2_vs_f64", atan2_vs_f64),
];

/// xorshift32 for input sweeps.
pub fn rng(s: &mut u32) -> u32 {
    *s ^= *s << 13;
    *s ^= *s >> 17;
    *s ^= *s << 5;
    *s
}

fn mul_hi_within_3_lsb() -> TestResult {
    let edges = [0, 1, -1, 2, 0xFFFF, 0x10000, -0x10000, i32::MAX, i32::MIN, i32::MIN + 1, 1 << 30, -(1 << 30)];
    let mut m = Mismatches::new();
    let mut worst = 0i64;
    let mut s = 0x1234_5678;
    let mut one = |a: i32, b: i32| {
        let exact = (i64::from(a) * i64::from(b)) >> 32;
        let got = i64::from(mul_hi(black_box(a), black_box(b)));
        let e = (got - exact).abs();
        worst = worst.max(e);
        if e > 3 {
            m.fail(format_args!("mul_hi({a}, {b}) = {got}, exact floor {exact}"));
        }
    };
    for a in edges {
        for b in edges {
            one(a, b);
        }
    }
    for _ in 0..2000 {
        let (a, b) = (rng(&mut s) as i32, rng(&mut s) as i32);
        one(a, b);
    }
    println!("      {} products, worst |mul_hi - floor(a b / 2^32)| = {} LSB", 2000 + edges.len() * edges.len(), worst);
    m.result("mul_hi off by more than 3 LSB")
}

fn angle_millidegrees() -> TestResult {
    let a = |m: i32| Angle::from_millidegrees(black_box(m)).0;
    check(a(0) == 0 && a(90_000) == 1 << 30 && a(180_000) == 1 << 31, "from_millidegrees quarter/half turn")?;
    check(a(-90_000) == 3 << 30 && a(360_000) == 0 && a(-360_000) == 0, "from_millidegrees wraps")?;
    check(Angle(black_box(3 << 30)).to_signed_millidegrees() == -90_000, "to_signed_millidegrees(270 deg)")?;
    check(Angle(black_box(1 << 31)).to_signed_millidegrees() == -180_000, "to_signed_millidegrees(180 deg)")?;
    check(Angle(black_box(u32::MAX)).to_millidegrees() == 0, "to_millidegrees rounds up to a full turn = 0")?;
    let mut m = Mismatches::new();
    let mut mdeg = -720_000;
    while mdeg <= 720_000 {
        let back = Angle::from_millidegrees(black_box(mdeg)).to_millidegrees();
        let want = mdeg.rem_euclid(360_000) as u32;
        if back != want {
            m.fail(format_args!("{mdeg} mdeg -> {back}"));
        }
        let diff = Angle::from_millidegrees(mdeg).diff(Angle::from_millidegrees(black_box(mdeg - 1000)));
        // 1 degree = 2^32 / 360 = 11930464.7 LSB
        if (diff - 11_930_465).abs() > 1 {
            m.fail(format_args!("diff over 1 deg at {mdeg}: {diff}"));
        }
        mdeg += 997;
    }
    m.result("millidegree round trip")
}

fn length_units() -> TestResult {
    check(Length::from_mm(black_box(5)).0 == 5 << 16 && Length::from_mm(5).to_mm() == 5, "from_mm/to_mm")?;
    check(Length::from_mm(black_box(i32::MAX)) == Length::MAX, "from_mm saturates")?;
    check(Length::from_um(black_box(1500)).to_um() == 1500, "um round trip")?;
    check(Length(black_box(3 << 15)).to_mm() == 2, "to_mm rounds 1.5 up")?;
    check(Length(black_box(-(3 << 15))).to_mm() == -1, "to_mm rounds -1.5 up")
}

fn speed_distance_q24() -> TestResult {
    let mut m = Mismatches::new();
    let mut s = 0x0bad_5eed;
    for i in 0..1000u32 {
        let bits = (rng(&mut s) as i32) % (Speed::MAX.to_bits() + 1);
        let dt = if i < 3 { [0, 1, u16::MAX][i as usize] } else { rng(&mut s) as u16 };
        let v = Speed::from_bits(bits);
        let got = v.distance_q24(Dt::from_micros_saturating(u32::from(black_box(dt))));
        // v dt in 2^-32 mm; the result is in 2^-24 mm: within 1 LSB = 2^8
        let exact = i64::from(bits) * i64::from(dt);
        if (i64::from(got) * 256 - exact).abs() > 256 {
            m.fail(format_args!("{bits} x {dt} us -> {got}, exact {exact} / 256"));
        }
    }
    check(Speed::from_bits(black_box(i32::MAX)) == Speed::MAX, "Speed clamps")?;
    m.result("distance_q24 off by more than 1 LSB")
}

fn turn_rate_rotation_exact() -> TestResult {
    let mut m = Mismatches::new();
    let mut s = 0xfeed_beef;
    let max = TurnRate::MAX.to_bits();
    for i in 0..1000u32 {
        let bits = if i < 2 { [max, -max][i as usize] } else { (rng(&mut s) as i32) % (max + 1) };
        let dt = rng(&mut s) as u16;
        let (a, f) = TurnRate::from_bits(bits).rotation(Dt::from_micros_saturating(u32::from(black_box(dt))));
        // w dt in 2^-48 turn, exactly, modulo a turn
        let exact = (i64::from(bits) * i64::from(dt)).rem_euclid(1 << 48);
        let got = (i64::from(a.0) << 16) | i64::from(f);
        if got != exact {
            m.fail(format_args!("{bits} x {dt} us -> {got:#x}, exact {exact:#x}"));
        }
    }
    m.result("rotation not exact")
}

fn sin_cos_vs_f64() -> TestResult {
    // documented bound: 2e-7 (Q30: 2e-7 * 2^30 = 214.7 LSB)
    const TOL: i32 = 214;
    let mut m = Mismatches::new();
    let mut worst = 0;
    for v in SIN_COS {
        let (s, c) = sin_cos(Angle(black_box(v.angle)));
        let e = (s - v.sin).abs().max((c - v.cos).abs());
        worst = worst.max(e);
        if e > TOL {
            m.fail(format_args!("angle {:#010x}: ({s}, {c}), f64 ({}, {})", v.angle, v.sin, v.cos));
        }
    }
    println!(
        "      {} angles, worst error {} LSB of Q30 = {:.2e} (bound 2e-7)",
        SIN_COS.len(),
        worst,
        worst as f32 / 1073741824.0
    );
    m.result("sin_cos error above 2e-7")
}

fn atan2_vs_f64() -> TestResult {
    // documented bound: 2e-7 rad = 136.8 angle LSB, plus the inputs' resolution
    const TOL: i32 = 137;
    let mut m = Mismatches::new();
    let mut worst = 0;
    for v in ATAN2 {
        let got = atan2(black_box(v.y), black_box(v.x));
        let e = got.diff(Angle(v.angle)).abs();
        worst = worst.max(e);
        if e > TOL {
            m.fail(format_args!("atan2({}, {}) = {:#010x}, f64 {:#010x}", v.y, v.x, got.0, v.angle));
        }
    }
    println!(
        "      {} points, worst error {} angle LSB = {:.2e} rad (bound 2e-7)",
        ATAN2.len(),
        worst,
        worst as f32 * 1.4629181e-9
    );
    m.result("atan2 error above 2e-7 rad")
}
