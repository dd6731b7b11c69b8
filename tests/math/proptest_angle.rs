//! Property tests for the angle arithmetic and the state update: binary
//! angles against f64 (wrapping add/sub, signed difference, millidegree
//! conversions), sin/cos and atan2 over the whole circle, speed and turn
//! rate conversions, the exact rotation of a turn step, and the state
//! update over any pose, motion and step (no overflow: checks are on).

use paperbot::math::{atan2, sin_cos, Angle, Coord, Dt, Speed, TurnRate};
use paperbot::model::{advance, Motion, Pose};
use proptest::prelude::*;

const TURN: f64 = 4_294_967_296.0;
const Q30: f64 = (1u64 << 30) as f64;

/// Distance between two angles on the circle, in turns (0..=0.5).
fn circle_dist(a: f64, b: f64) -> f64 {
    let d = (a - b).rem_euclid(1.0);
    d.min(1.0 - d)
}

fn motion() -> impl Strategy<Value = Motion> {
    prop_oneof![
        Just(Motion::Stop),
        any::<i32>().prop_map(|b| Motion::Straight(Speed::from_bits(b))),
        any::<i32>().prop_map(|b| Motion::Turn(TurnRate::from_bits(b))),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 5000, ..ProptestConfig::default() })]

    #[test]
    fn add_sub_and_diff_wrap_like_the_circle(a: u32, b: u32) {
        let (x, y) = (Angle(a), Angle(b));
        prop_assert_eq!(x.wrapping_add(y).wrapping_sub(y), x);
        prop_assert_eq!(y.wrapping_add(Angle(x.diff(y) as u32)), x);
        let d = f64::from(x.diff(y)) / TURN; // in [-0.5, 0.5)
        prop_assert!((-0.5..0.5).contains(&d));
        prop_assert!(circle_dist(f64::from(a) / TURN - f64::from(b) / TURN, d) < 1e-12);
        prop_assert!((x.diff(y) as i64 + y.diff(x) as i64 == 0) || x.diff(y) == i32::MIN);
    }

    /// Millidegrees in, millidegrees out: any i32 wraps into 0..360000 and
    /// comes back exactly; an angle's millidegrees are within half of one.
    #[test]
    fn millidegrees_round_trip(m: i32, a: u32) {
        prop_assert_eq!(Angle::from_millidegrees(m).to_millidegrees(), m.rem_euclid(360_000) as u32);
        let md = Angle(a).to_millidegrees();
        prop_assert!(md < 360_000);
        let exact = f64::from(a) / TURN * 360_000.0;
        prop_assert!(circle_dist(f64::from(md) / 360_000.0, exact / 360_000.0) * 360_000.0 <= 0.5 + 1e-6);
        let s = Angle(a).to_signed_millidegrees();
        prop_assert!((-180_000..=180_000).contains(&s), "{}", s);
        prop_assert_eq!(s.rem_euclid(360_000) as u32 % 360_000, md);
    }

    /// sin/cos within 1.3e-7 of f64 everywhere, atan2 inverts them.
    #[test]
    fn sin_cos_and_atan2_match_f64(a: u32) {
        let (s, c) = sin_cos(Angle(a));
        let t = Angle(a).to_radians_f64();
        prop_assert!((f64::from(s) / Q30 - t.sin()).abs() < 1.3e-7, "{} {}", a, s);
        prop_assert!((f64::from(c) / Q30 - t.cos()).abs() < 1.3e-7, "{} {}", a, c);
        // atan2's 2e-7 rad plus sin/cos's 1.3e-7: 226 angle LSBs
        let back = atan2(s, c);
        let tol = ((2e-7 + 1.3e-7) / std::f64::consts::TAU * TURN) as u32;
        prop_assert!(back.diff(Angle(a)).unsigned_abs() <= tol, "{} -> {:?}", a, back);
    }

    /// atan2 of any vector (any magnitudes, including i32::MIN) against f64.
    #[test]
    fn atan2_of_any_vector(y: i32, x: i32) {
        let a = atan2(y, x);
        if x == 0 && y == 0 {
            prop_assert_eq!(a, Angle::ZERO);
        } else {
            let want = f64::from(y).atan2(f64::from(x)) / std::f64::consts::TAU;
            // 2e-7 rad plus the inputs' own resolution
            let tol = 2e-7 / std::f64::consts::TAU + 1.0 / f64::from(x.unsigned_abs().max(y.unsigned_abs()));
            prop_assert!(circle_dist(f64::from(a.0) / TURN, want) <= tol, "{} {} -> {:?}", y, x, a);
        }
    }

    /// Speed and turn-rate conversions: whole mm/s and mrad/s round trip,
    /// and negation is exact for any (clamped) value.
    #[test]
    fn speed_and_rate_conversions(mm_s in -1000i32..=1000, mrad in -20_000i32..=20_000, bits: i32) {
        prop_assert_eq!(Speed::from_mm_s(mm_s).to_mm_s(), mm_s);
        prop_assert_eq!(TurnRate::from_mrad_s(mrad).to_mrad_s(), mrad);
        let v = Speed::from_bits(bits);
        prop_assert_eq!(v.neg().neg(), v);
        prop_assert_eq!(v.abs().to_bits(), v.to_bits().abs());
        let w = TurnRate::from_bits(bits);
        prop_assert_eq!(w.neg().neg(), w);
    }

    /// A turn step's rotation is `w dt` exactly (angle LSBs with a 2^-16
    /// fraction), for any rate and any step.
    #[test]
    fn rotation_is_exact(bits: i32, us in 0u32..=65_535) {
        let w = TurnRate::from_bits(bits);
        let dt = Dt::from_micros(us).unwrap();
        let (rot, frac) = w.rotation(dt);
        let exact = i64::from(w.to_bits()) * i64::from(us); // units of 2^-16 LSB
        let got = (i64::from(rot.0) << 16) | i64::from(frac);
        prop_assert_eq!(got, exact.rem_euclid(1 << 48));
    }

    /// The state update from any pose (anywhere in the +-32 m the pose
    /// reports), with any motion for any step: no overflow, the heading
    /// moves by exactly the rotation, the position by the f64 kinematics.
    #[test]
    fn state_update_matches_f64(
        x in -30_000i64..30_000, y in -30_000i64..30_000, theta: u32, frac: u16,
        m in motion(), us in 0u32..=65_535,
    ) {
        let mut p = Pose::from_parts(Coord(x << 32), Coord(y << 32), Angle(theta), frac);
        let before = p;
        let dt = Dt::from_micros(us).unwrap();
        advance(&mut p, m, dt);
        let t = f64::from(us) * 1e-6;
        let th0 = Angle(theta).to_radians_f64() + f64::from(frac) / 65536.0 / TURN * std::f64::consts::TAU;
        let (dx, dy) = (p.x.to_mm_f64() - before.x.to_mm_f64(), p.y.to_mm_f64() - before.y.to_mm_f64());
        match m {
            Motion::Stop => prop_assert_eq!(p, before),
            Motion::Straight(v) => {
                let d = v.to_mps_f64() * 1000.0 * t;
                prop_assert_eq!(p.theta, before.theta);
                prop_assert!((dx - d * th0.cos()).abs() < 1e-4 && (dy - d * th0.sin()).abs() < 1e-4, "{dx} {dy} {d}");
            }
            Motion::Turn(w) => {
                let (rot, f) = w.rotation(dt);
                let total = (u64::from(theta) << 16 | u64::from(frac)).wrapping_add((u64::from(rot.0) << 16) | u64::from(f));
                prop_assert_eq!(p.theta, Angle((total >> 16) as u32));
                prop_assert_eq!(p.theta_frac, total as u16);
                let dm = paperbot::config::geometry::ROTATION_TO_REFERENCE.to_mm_f64();
                let th1 = th0 + w.to_rad_s_f64() * t;
                let (ex, ey) = (-dm * (th0.cos() - th1.cos()), -dm * (th0.sin() - th1.sin()));
                prop_assert!((dx - ex).abs() < 1e-4 && (dy - ey).abs() < 1e-4, "{dx} {dy} vs {ex} {ey}");
            }
        }
    }
}
