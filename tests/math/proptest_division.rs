//! Property tests for the robot's divisions: `div_u64`, `div_i64` and
//! `div_round` (every cold path's division; on the robot calls of the
//! ESP8266 ROM's helpers, see `rom-functions.x`) against the host's
//! native `/` and `%` (i128 for the exact rounding), and the conversions
//! rewritten on top of them against their former native formulas.

use paperbot::math::{div_i64, div_round, div_u64, Angle, Length, TurnRate};
use proptest::prelude::*;

/// Numerators and divisors of every size: full range, and small quotients
/// (the common case: `d` near `n`), and exact halves.
fn pair() -> impl Strategy<Value = (u64, u64)> {
    prop_oneof![
        (any::<u64>(), any::<u64>()),
        (any::<u64>(), 1u64..=1 << 32),
        (any::<u32>().prop_map(u64::from), 1u64..100_000),
        (any::<u64>(), 0u32..64).prop_map(|(d, k)| ((d >> k).saturating_mul(3), d >> k)),
        // exact halves, where rounding has to choose: n = (k + 1/2) d
        (any::<u32>(), 1u64..1 << 31).prop_map(|(k, h)| (u64::from(k) * 2 * h + h, 2 * h)),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 20_000, ..ProptestConfig::default() })]

    #[test]
    fn div_u64_is_native_division((n, d) in pair()) {
        prop_assert_eq!(div_u64(n, d), n.checked_div(d));
    }

    #[test]
    fn div_i64_is_checked_div((n, d) in pair(), sn: bool, sd: bool) {
        let n = if sn { (n as i64).wrapping_neg() } else { n as i64 };
        let d = if sd { (d as i64).wrapping_neg() } else { d as i64 };
        prop_assert_eq!(div_i64(n, d), n.checked_div(d));
        prop_assert_eq!(div_i64(i64::MIN, d), i64::MIN.checked_div(d));
    }

    /// Rounded to nearest, halves away from zero, exactly (i128 reference).
    #[test]
    fn div_round_is_exact((n, d) in pair(), sn: bool, sd: bool) {
        let n = if sn { (n as i64).wrapping_neg() } else { n as i64 };
        let d = if sd { (d as i64).wrapping_neg() } else { d as i64 };
        let want = (d != 0).then(|| {
            let (n, d) = (i128::from(n), i128::from(d));
            let q = (2 * n.abs() + d.abs()) / (2 * d.abs());
            if (n < 0) != (d < 0) { -q } else { q }
        });
        prop_assert_eq!(div_round(n, d), want.and_then(|q| i64::try_from(q).ok()));
    }

    /// The conversions that divided natively give the same values as before.
    #[test]
    fn conversions_match_their_native_formulas(m: i32, a: u32, bits: i32, mrad in -20_000i32..=20_000, um: i32) {
        let rem = i64::from(m.rem_euclid(360_000));
        let q = ((rem << 26) * 2 + 5625) / (2 * 5625);
        prop_assert_eq!(Angle::from_millidegrees(m), Angle(q as u32));
        let old = ((u64::from(a) * 360_000 + (1 << 31)) >> 32) as u32 % 360_000;
        prop_assert_eq!(Angle(a).to_millidegrees(), old);
        let w = TurnRate::from_bits(bits);
        // TurnRate's units per rad/s (2^48 / (2 pi 10^6)), rounded: its PER_RAD_S_Q16
        prop_assert_eq!(TurnRate::from_mrad_s(1000).to_bits(), 44_798_134);
        let n = i64::from(w.to_bits()) * 1000;
        let half = 44_798_134 / 2;
        let old = (if n >= 0 { (n + half) / 44_798_134 } else { (n - half) / 44_798_134 }) as i32;
        prop_assert_eq!(w.to_mrad_s(), old);
        prop_assert_eq!(TurnRate::from_mrad_s(mrad), TurnRate::from_bits((i64::from(mrad) * 44_798_134 / 1000) as i32));
        prop_assert_eq!(Length::from_um(um).0 as i64, ((i64::from(um) << 16) / 1000).clamp(i64::from(i32::MIN), i64::from(i32::MAX)));
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 20_000, ..ProptestConfig::default() })]

    /// `quotient` (the refinement's division by a reciprocal) is the exact
    /// `num 2^shift / den` (i128) within a few parts in 2^27, never above
    /// it, and saturates where that does not fit.
    #[test]
    fn quotient_is_the_division_within_its_bound(num: u32, den in 1u64.., shift in 0u32..48) {
        let exact = (u128::from(num) << shift) / u128::from(den);
        let got = paperbot::math::quotient(num, den, shift);
        if exact >= u128::from(u64::MAX) {
            prop_assert_eq!(got, u64::MAX);
        } else {
            let got = u128::from(got);
            prop_assert!(got <= exact + 1, "{} > {}", got, exact);
            prop_assert!(exact - got.min(exact) <= exact / (1 << 26) + 2, "{} far below {}", got, exact);
        }
    }
}
