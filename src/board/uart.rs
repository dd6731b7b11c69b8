//! UART0 baud rate arithmetic. esp8266-hal 0.5 has no baud API: the board
//! writes [`UART0_DIVIDER`] into `UART_CLKDIV` through the PAC.
//!
//! The ESP8266 UART divides its clock (the 80 MHz APB clock,
//! [`config::board::APB_HZ`]) by an integer: `baud = clk / divider`, so the
//! best divider is `round(clk / baud)`. For 115200 baud that is 694, which
//! gives 115 273.8 baud, +0.064 % (UART frames tolerate a few percent).

use crate::config;

/// Widest divider `UART_CLKDIV` holds (20 bits, ESP8266 Technical Reference 11.3).
pub const CLKDIV_MAX: u32 = (1 << 20) - 1;

/// The integer divider closest to `clk_hz / baud` (round half up), or
/// `None` if `baud` is 0, above the clock, or needs a divider wider than
/// [`CLKDIV_MAX`].
pub const fn divider(clk_hz: u32, baud: u32) -> Option<u32> {
    if baud > clk_hz {
        return None;
    }
    // clk_hz / baud + (remainder >= baud / 2) avoids the clk + baud/2 overflow.
    let (Some(q), Some(r)) = (clk_hz.checked_div(baud), clk_hz.checked_rem(baud)) else {
        return None; // baud == 0
    };
    // Round half up: 2r >= baud, i.e. r >= baud - r (exact: r < baud).
    let half_up = r >= baud.saturating_sub(r);
    // q + 1 only saturates for baud == 1 and clk_hz == u32::MAX, where r == 0
    // and half_up is false; a saturated divider would be refused below anyway.
    let d = if half_up { q.saturating_add(1) } else { q };
    if d == 0 || d > CLKDIV_MAX {
        None
    } else {
        Some(d)
    }
}

/// The baud rate a divider really produces, rounded to the nearest Hz (0 for
/// a 0 divider).
pub const fn actual_baud(clk_hz: u32, divider: u32) -> u32 {
    // clk_hz + divider / 2 < 2^33: exact in u64, the saturation never bites.
    let num = (clk_hz as u64).saturating_add(divider as u64 / 2);
    match num.checked_div(divider as u64) {
        // divider >= 1: the quotient is at most clk_hz, so it fits a u32.
        Some(baud) => baud as u32,
        None => 0,
    }
}

/// Parts per million in one.
const PPM: i64 = 1_000_000;

/// Baud rate error of `divider` against the wanted `baud`, in parts per
/// million (positive: the UART runs fast). `i64::MAX` for a 0 `baud` or
/// `divider`; an error too negative for an `i64` (a divider billions of
/// times too large) saturates at `-i64::MAX`, so `abs()` stays defined.
pub const fn error_ppm(clk_hz: u32, baud: u32, divider: u32) -> i64 {
    if divider == 0 || baud == 0 {
        return i64::MAX;
    }
    // baud * divider < 2^64 may pass i64::MAX: then the UART is hopelessly slow.
    let Some(wanted) = (baud as i64).checked_mul(divider as i64) else {
        return -i64::MAX;
    };
    // 0 <= clk_hz < 2^32 and 0 < wanted <= i64::MAX: the difference is exact.
    let diff = (clk_hz as i64).saturating_sub(wanted);
    // Positive side: diff < 2^32, diff * 10^6 < 2^52. Negative side may overflow.
    let Some(num) = diff.checked_mul(PPM) else {
        return -i64::MAX;
    };
    // wanted > 0: never None (and never i64::MIN / -1).
    match num.checked_div(wanted) {
        Some(e) => e,
        None => i64::MAX,
    }
}

/// `UART_CLKDIV` for UART0 at [`config::serial::BAUD`].
pub const UART0_DIVIDER: u32 = match divider(config::board::APB_HZ, config::serial::BAUD) {
    Some(d) => d,
    None => panic!("config::serial::BAUD cannot be made from the APB clock"),
};

/// A UART receiver samples mid-bit; over a 10-bit 8N1 frame it tolerates
/// about +-2 % between the two ends. Keep our share well inside: 1 %.
pub const MAX_ERROR_PPM: i64 = 10_000;

const _: () = {
    let e = error_ppm(config::board::APB_HZ, config::serial::BAUD, UART0_DIVIDER);
    assert!(e <= MAX_ERROR_PPM && e >= -MAX_ERROR_PPM, "UART0 baud error above 1 %");
};

#[cfg(test)]
#[allow(clippy::restriction)] // test code: a panic fails the test
mod tests {
    use super::*;

    #[test]
    fn uart0_at_115200_divides_by_694() {
        assert_eq!(UART0_DIVIDER, 694);
        assert_eq!(actual_baud(80_000_000, 694), 115_274);
        // 80e6 / 694 = 115273.78 -> +0.0640 %
        assert_eq!(error_ppm(80_000_000, 115_200, 694), 640);
        let exact: f64 = 80e6 / 694.0;
        let err = (exact - 115_200.0) / 115_200.0 * 1e6;
        assert!(err > 640.40 && err < 640.42, "{err}");
    }

    #[test]
    fn divider_rounds_to_nearest_against_f64() {
        // (baud, divider), checked against round(80e6 / baud) in f64 too.
        let table: &[(u32, u32)] =
            &[(9_600, 8_333), (57_600, 1_389), (74_880, 1_068), (115_200, 694), (230_400, 347), (921_600, 87)];
        for &(baud, want) in table {
            let d = divider(80_000_000, baud);
            assert_eq!(d, Some(want), "baud {baud}");
            let f = (80e6 / f64::from(baud)).round() as u32;
            assert_eq!(d, Some(f), "baud {baud} vs f64");
        }
    }

    #[test]
    fn rounding_is_half_up_and_each_neighbour_is_worse() {
        // 80e6 / 160_000 = 500 exactly; 80e6 / 123_077 = 649.99...
        assert_eq!(divider(80_000_000, 160_000), Some(500));
        assert_eq!(divider(80_000_000, 123_077), Some(650));
        for baud in [1_200u32, 19_200, 38_400, 115_200, 250_000, 460_800, 1_000_000] {
            let d = divider(80_000_000, baud).unwrap();
            let e = error_ppm(80_000_000, baud, d).abs();
            assert!(e <= error_ppm(80_000_000, baud, d - 1).abs(), "{baud}");
            assert!(e <= error_ppm(80_000_000, baud, d + 1).abs(), "{baud}");
        }
    }

    #[test]
    fn impossible_rates_are_refused() {
        assert_eq!(divider(80_000_000, 0), None);
        assert_eq!(divider(80_000_000, 80_000_001), None);
        // 80e6 / 76 = 1_052_631 > 2^20 - 1
        assert_eq!(divider(80_000_000, 76), None);
        assert_eq!(divider(80_000_000, 77), Some(1_038_961));
        assert_eq!(divider(u32::MAX, u32::MAX), Some(1));
        // q + 1 would overflow were r >= baud / 2; with baud 1 it never is.
        assert_eq!(divider(u32::MAX, 1), None);
        assert_eq!(divider(2 * CLKDIV_MAX + 1, 2), None);
        assert_eq!(divider(2 * CLKDIV_MAX - 1, 2), Some(CLKDIV_MAX));
    }

    #[test]
    fn extreme_arguments_give_defined_answers() {
        assert_eq!(actual_baud(80_000_000, 0), 0);
        assert_eq!(actual_baud(u32::MAX, 1), u32::MAX);
        assert_eq!(actual_baud(u32::MAX, u32::MAX), 1);
        assert_eq!(error_ppm(80_000_000, 0, 694), i64::MAX);
        assert_eq!(error_ppm(80_000_000, 115_200, 0), i64::MAX);
        // the UART at twice the wanted rate, and at half of it
        assert_eq!(error_ppm(80_000_000, 100, 400_000), 1_000_000);
        assert_eq!(error_ppm(80_000_000, 100, 1_600_000), -500_000);
        // baud * divider past i64::MAX, and diff * 10^6 past i64::MIN
        assert_eq!(error_ppm(1, u32::MAX, u32::MAX), -i64::MAX);
        assert_eq!(error_ppm(1, 1 << 31, 1 << 20), -i64::MAX);
        // near the limit but inside: (1 - 2^42) * 10^6 / 2^42, truncated toward 0
        assert_eq!(error_ppm(1, 1 << 21, 1 << 21), -999_999);
    }
}
