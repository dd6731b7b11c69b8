//! Reciprocals without a division (the lx106 has no divide instruction).

use super::{mul_hi, mul_hi_u};

/// Seeds for [`reciprocal`]: `2^23 / (129 + 2 i)`, 2^15 / the middle of
/// interval `i` of 64 over `[1/2, 1)`; 65028 at most. (Evaluated by the
/// compiler: an index out of range would be a build error, not a panic.)
#[allow(clippy::indexing_slicing)]
const RECIP_SEED: [u16; 64] = {
    let mut t = [0u16; 64];
    let mut i = 0;
    while i < 64 {
        t[i] = ((1u32 << 23) / (129 + 2 * i as u32)) as u16;
        i += 1;
    }
    t
};

/// `2^62 / x` for `x` in `[2^31, 2^32)` (a result in `(2^30, 2^31]`), at most
/// a few 2^-28 below the exact value and never above it: a 64-entry seed
/// (relative error below 2^-7) and two Newton steps `y += y (1 - x y)`
/// (2^-14, then 2^-28) in [`mul_hi`] arithmetic. About 50 instructions,
/// where a 64-bit division is ~430.
// tick bar: inlined into its one call, in a correction
#[inline(always)]
pub fn reciprocal(x: u32) -> u32 {
    // x >> 25 is 64..127: the index is below 64
    let seed = RECIP_SEED.get(((x >> 25) & 63) as usize).copied().unwrap_or(1 << 15);
    let mut y = u32::from(seed) << 15; // Q30, (2^30, 2^31)
    for _ in 0..2 {
        // x y / 2^32 in Q30 (~2^30); d = (1 - x y) 2^30, |d| < 2^23 after the seed
        let d = (1u32 << 30).wrapping_sub(mul_hi_u(x, y)) as i32;
        // y d / 2^30 = mul_hi(y / 2, 8 d): y / 2 < 2^30, |8 d| < 2^26
        y = y.wrapping_add_signed(mul_hi((y >> 1) as i32, d << 3));
    }
    // mul_hi's floors can leave y a few LSB above 1/x: step below it
    y.saturating_sub(16)
}

/// `num 2^shift / den`, for `den > 0` (`u64::MAX` for 0), from
/// [`reciprocal`]: within a few parts in 2^27 below the exact quotient.
/// About 150 lx106 instructions, where a 64-bit division is about 720
/// (lx106/BENCHMARKS.md): for the localization's refinement, which
/// divides a few times a reading. Saturates at `u64::MAX`.
pub fn quotient(num: u32, den: u64, shift: u32) -> u64 {
    if den == 0 {
        return u64::MAX;
    }
    // den's top 32 bits, normalised: den = (d << sh) 2^(t - sh) for the
    // reciprocal's x = d << sh in [2^31, 2^32)
    let t = 32u32.saturating_sub(den.leading_zeros());
    let (x, sh) = super::normalize((den >> t) as u32);
    // num 2^shift / den = num (2^62 / x) 2^(shift + sh - t - 62); the
    // product is below 2^32 2^31
    let p = u64::from(num).wrapping_mul(u64::from(reciprocal(x)));
    let up = shift.saturating_add(sh);
    let down = t.saturating_add(62);
    if up >= down {
        let e = up.saturating_sub(down);
        if e >= p.leading_zeros() {
            u64::MAX
        } else {
            p << e
        }
    } else {
        p.checked_shr(down.saturating_sub(up)).unwrap_or(0)
    }
}
