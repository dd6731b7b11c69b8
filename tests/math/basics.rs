//! The fixed-point unit types: conversions, rounding, clamping, wrapping.
use paperbot::math::{div_round, Angle, Coord, Dt, Length, Speed, TurnRate};

#[test]
fn angle_conversions() {
    let table =
        [(0, 0u32), (90_000, 1 << 30), (180_000, 1 << 31), (-90_000, 3 << 30), (450_000, 1 << 30), (360_000, 0)];
    for (mdeg, bits) in table {
        assert_eq!(Angle::from_millidegrees(mdeg), Angle(bits), "{mdeg}");
    }
    for deg in [0.0, 11.0 + 56.0 / 60.0, 123.456, 359.999, -0.5, 720.25] {
        let a = Angle::from_degrees_f64(deg);
        let want = deg.rem_euclid(360.0);
        assert!((a.to_radians_f64().to_degrees() - want).abs() < 1e-6, "{deg}");
        assert_eq!(a.to_millidegrees(), ((want * 1000.0).round() as u32) % 360_000, "{deg}");
    }
    assert_eq!(Angle::from_degrees_f64(-10.0).to_signed_millidegrees(), -10_000);
    assert_eq!(Angle::from_degrees_f64(190.0).to_signed_millidegrees(), -170_000);
    assert_eq!(
        Angle::from_degrees_f64(10.0).diff(Angle::from_degrees_f64(350.0)),
        Angle::from_degrees_f64(20.0).0 as i32
    );
    // every millidegree survives the round trip
    for mdeg in (0..360_000).step_by(7) {
        assert_eq!(Angle::from_millidegrees(mdeg).to_millidegrees(), mdeg as u32);
    }
}

#[test]
fn speed_and_turn_rate_conversions_round_trip() {
    for mm_s in [-1000, -137, -1, 0, 1, 130, 149, 1000] {
        assert_eq!(Speed::from_mm_s(mm_s).to_mm_s(), mm_s);
        assert!((Speed::from_mm_s(mm_s).to_mps_f64() * 1000.0 - f64::from(mm_s)).abs() < 1e-3);
    }
    assert_eq!(Speed::from_mm_s(5000), Speed::MAX, "clamped to 1 m/s");
    assert_eq!(Speed::from_mps_f64(-7.0), Speed::MAX.neg());
    for mrad in [-20_000, -3200, -1, 0, 1, 2170, 3300, 20_000] {
        assert_eq!(TurnRate::from_mrad_s(mrad).to_mrad_s(), mrad);
        assert!((TurnRate::from_mrad_s(mrad).to_rad_s_f64() * 1000.0 - f64::from(mrad)).abs() < 1e-3);
    }
    assert_eq!(TurnRate::from_rad_s_f64(100.0), TurnRate::MAX);
    let w = TurnRate::from_rad_s_f64(2.5);
    assert!((f64::from(w.to_rad_s_q16()) / 65536.0 - 2.5).abs() < 2e-5);
    assert_eq!(TurnRate::from_rad_s_q16(w.to_rad_s_q16()).to_mrad_s(), 2500);
}

#[test]
fn distance_and_rotation_per_step_are_exact() {
    for (mps, us) in [(0.13, 10_000u32), (-0.149, 65_535), (1.0, 65_535), (-1.0, 65_535), (0.0001, 5_000)] {
        let v = Speed::from_mps_f64(mps);
        let d = v.distance_q24(Dt::from_micros(us).unwrap());
        let want = v.to_mps_f64() * 1000.0 * f64::from(us) * 1e-6;
        assert!((f64::from(d) / f64::from(1 << 24) - want).abs() <= 1.0 / f64::from(1 << 24), "{mps} {us}");
    }
    for (rad_s, us) in [(2.5, 10_000u32), (-3.3, 65_535), (20.0, 65_535), (-20.0, 1)] {
        let w = TurnRate::from_rad_s_f64(rad_s);
        let (a, frac) = w.rotation(Dt::from_micros(us).unwrap());
        let got = (a.0 as i32) as f64 + f64::from(frac) / 65536.0;
        let want = f64::from(w.to_bits()) * f64::from(us) / 65536.0;
        assert!((got - want).abs() < 1e-9, "{rad_s} {us}: {got} vs {want}");
    }
}

#[test]
fn lengths_coords_and_steps() {
    assert_eq!(Length::from_mm(56).to_mm(), 56);
    assert_eq!(Length::from_um(-1500).to_um(), -1500);
    assert_eq!(Length::from_mm(100_000), Length::MAX, "saturates past 32 m");
    assert_eq!(Coord::from_length(Length::from_mm(-7)).to_length(), Length::from_mm(-7));
    assert_eq!(Coord(i64::MAX).to_length(), Length::MAX);
    assert_eq!(Coord(7 << 10).add_q22(-7), Coord(0), "a Q22 step is 2^10 Coord units");
    assert_eq!(Coord(i64::MAX).add_q22(1), Coord(i64::MIN + 1023), "wraps (2147 km out), never panics");
    assert_eq!(Dt::from_micros(65_536), Err(paperbot::math::DtTooLong));
    assert_eq!(Dt::from_micros_saturating(1_000_000), Dt::MAX);
}

#[test]
fn div_round_rounds_half_away_from_zero() {
    for (n, d, q) in [(5, 2, 3), (-5, 2, -3), (5, -2, -3), (-5, -2, 3), (4, 3, 1), (-4, 3, -1), (0, 7, 0), (7, 7, 1)] {
        assert_eq!(div_round(n, d), Some(q), "{n}/{d}");
    }
    assert_eq!(div_round(1, 0), None);
}

#[test]
fn mul_wide_is_the_exact_i64_product() {
    use paperbot::math::mul_wide;
    // the corners and the 16-bit seams, then a pseudo-random sweep
    let edges = [
        0,
        1,
        -1,
        2,
        0xFFFF,
        0x1_0000,
        -0x1_0000,
        0x7FFF_FFFF,
        i32::MIN,
        i32::MIN + 1,
        0x7FFF_0000,
        -0x7FFF_0001,
        0x1234_5678,
        -0x0FED_CBA9,
        1 << 30,
        -(1 << 30),
    ];
    for &a in &edges {
        for &b in &edges {
            assert_eq!(mul_wide(a, b), i64::from(a) * i64::from(b), "{a} * {b}");
        }
    }
    let mut x = 0x2545_F491_4F6C_DD1Du64;
    for _ in 0..200_000 {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        let (a, b) = (x as i32, (x >> 32) as i32);
        assert_eq!(mul_wide(a, b), i64::from(a) * i64::from(b), "{a} * {b}");
        // and with small operands (the estimator's typical ones)
        let (c, d) = (a >> (x % 24) as u32, b >> ((x >> 8) % 24) as u32);
        assert_eq!(mul_wide(c, d), i64::from(c) * i64::from(d), "{c} * {d}");
    }
}
