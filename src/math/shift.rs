//! Shifts by a computed amount: normalising a value to the top of a word,
//! and scaling by a power of two in either direction.

/// `(x << n, n)` with `x << n` in `[2^31, 2^32)`, for `x > 0` (the lx106 has
/// no NSAU: a five-step binary search, ~15 instructions).
pub fn normalize(x: u32) -> (u32, u32) {
    let (mut x, mut n) = (x, 0u32);
    if x < 1 << 16 {
        x <<= 16;
        n += 16;
    }
    if x < 1 << 24 {
        x <<= 8;
        n += 8;
    }
    if x < 1 << 28 {
        x <<= 4;
        n += 4;
    }
    if x < 1 << 30 {
        x <<= 2;
        n += 2;
    }
    if x < 1 << 31 {
        x <<= 1;
        n += 1;
    }
    (x, n)
}

/// `v 2^e`: an arithmetic right shift for `e <= 0`, a saturating left shift
/// for `e > 0` (a correction's gain and covariance terms shift left only
/// while the covariance is large).
// tick bar: inlined into a correction's gain and covariance terms
#[inline(always)]
pub fn shift(v: i32, e: i32) -> i32 {
    if e <= 0 {
        v >> (-e).min(31)
    } else {
        let e = e.clamp(0, 31) as u32;
        // fits when |v| < 2^(31 - e)
        if v.unsigned_abs() < 1u32 << (31 - e) {
            v << e
        } else if v < 0 {
            i32::MIN
        } else {
            i32::MAX
        }
    }
}
