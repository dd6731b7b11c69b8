//! Products of 32-bit values without a 64-bit multiply: the lx106 has a
//! 32-bit `MULL` and 16x16 multiplies, but no multiply-high, and a `u64`
//! product is a `__muldi3` call. Each function states its error bound.

/// High 32 bits of the signed 64-bit product `a * b`, i.e. `(a * b) >> 32`,
/// from three 16x16 products (lx106: MULL/MUL16, no MULSH). The result is
/// within 3 LSB of the exact floor (the dropped low partial products and
/// carries); it never overflows.
// step bar: inlined into the state update's products
#[inline(always)]
pub fn mul_hi(a: i32, b: i32) -> i32 {
    let (ah, al) = (a >> 16, (a & 0xFFFF) as u32);
    let (bh, bl) = (b >> 16, (b & 0xFFFF) as u32);
    // |ah|, |bh| <= 2^15 and al, bl < 2^16: every product fits in i32, and
    // the sum is at most 2^30 + 2 * 2^15 in magnitude.
    let hh = ah.wrapping_mul(bh);
    let hl = ah.wrapping_mul(bl as i32) >> 16;
    let lh = (al as i32).wrapping_mul(bh) >> 16;
    hh.wrapping_add(hl).wrapping_add(lh)
}

/// The high 32 bits of the 64-bit product `a * b`, from four 16 x 16-bit
/// products (the lx106 has a 32-bit `MULL` but no multiply-high, and a
/// `u64` product would be a `__muldi3` call).
#[inline]
pub fn mul_hi_u32(a: u32, b: u32) -> u32 {
    let (a1, a0) = (a >> 16, a & 0xFFFF);
    let (b1, b0) = (b >> 16, b & 0xFFFF);
    // each factor < 2^16: every partial product < 2^32
    let lo = a0.wrapping_mul(b0);
    let m1 = a1.wrapping_mul(b0);
    let m2 = a0.wrapping_mul(b1);
    let hi = a1.wrapping_mul(b1);
    // three terms < 2^16 each: < 2^18
    let mid = (lo >> 16).wrapping_add(m1 & 0xFFFF).wrapping_add(m2 & 0xFFFF);
    // the sum is floor(a * b / 2^32) <= (2^32 - 1)^2 / 2^32 < 2^32: no wrap
    hi.wrapping_add(m1 >> 16).wrapping_add(m2 >> 16).wrapping_add(mid >> 16)
}

/// The exact signed product `a * b` as an `i64`, from 16-bit partial
/// products: the low word is one 32-bit multiply (MULL), the high word
/// three more and a carry. About 25 lx106 instructions, against ~55 for
/// `i64::from(a) * i64::from(b)` (a `__muldi3` call) and ~245 for an
/// overflow-checked i64 product.
pub fn mul_wide(a: i32, b: i32) -> i64 {
    let (ah, al) = (a >> 16, a & 0xFFFF);
    let (bh, bl) = (b >> 16, b & 0xFFFF);
    // ah, bh in [-2^15, 2^15), al, bl in [0, 2^16): al bh and ah bl lie in
    // (-2^31, 2^31), ah bh in [-2^30, 2^30], al bl < 2^32 as u32.
    let ll = ((al as u32) * (bl as u32)) >> 16; // < 2^16
    let lh = al * bh;
    let hl = ah * bl;
    // a b = 2^32 (ah bh + lh>>16 + hl>>16) + 2^16 (lh&0xFFFF + hl&0xFFFF + ll) + (al bl)&0xFFFF;
    // the middle sum is below 3 * 2^16, its carry the rest of the high word.
    let mid = (lh & 0xFFFF) + (hl & 0xFFFF) + ll as i32;
    // the exact high word of a 64-bit product: fits i32
    let hi = ah * bh + (lh >> 16) + (hl >> 16) + (mid >> 16);
    let lo = a.wrapping_mul(b) as u32; // the exact low word
    (i64::from(hi) << 32) | i64::from(lo)
}

/// Unsigned [`mul_hi`] (where [`mul_hi_u32`] is exact with four products): `(a * b) >> 32` within 3 LSB below the exact floor
/// (three 16x16 products; the dropped low product and the two floors only
/// ever lower it). Never overflows: the sum is at most the exact high word.
// tick bar: inlined into the reciprocal's Newton steps
#[inline(always)]
pub fn mul_hi_u(a: u32, b: u32) -> u32 {
    let (ah, al) = (a >> 16, a & 0xFFFF);
    let (bh, bl) = (b >> 16, b & 0xFFFF);
    ah * bh + ((ah * bl) >> 16) + ((al * bh) >> 16)
}

/// The exact product of `a, b < 2^31`, from 15-bit halves: `a = ah 2^15 + al`
/// (`ah < 2^16`, `al < 2^15`), so `ah bh < 2^32`, `ah bl + al bh < 2^32` and
/// `al bl < 2^30` fit u32. (A split at 16 bits is the textbook pattern LLVM
/// turns back into a `__muldi3` call when it can prove the operands
/// non-negative.) About 25 lx106 instructions.
// tick bar: inlined into the covariance's correlation bound
#[inline(always)]
pub fn mul_u31(a: u32, b: u32) -> u64 {
    let (ah, al) = (a >> 15, a & 0x7FFF);
    let (bh, bl) = (b >> 15, b & 0x7FFF);
    let mid = ah * bl + al * bh;
    (u64::from(ah * bh) << 30) + (u64::from(mid) << 15) + u64::from(al * bl)
}

/// `a * s` for `s` in Q2.30 (|s| <= 1): [`mul_hi`] gives Q-2, shifted back.
/// Within 12 LSB of the exact product; saturates instead of overflowing.
// tick bar: inlined into the beam geometry
#[inline(always)]
pub fn mul_q30(a: i32, s: i32) -> i32 {
    mul_hi(a, s).saturating_mul(4)
}

/// `a f` for `f` in Q30, where `|a f| < 2^61` (`|f| <= 2^29` for any `a`,
/// or small operands): `mul_hi` gives Q-2 within 3 LSB below the exact
/// product, and the `<< 2` cannot overflow under that bound (where
/// [`mul_q30`] saturates).
// tick bar: inlined into predict's covariance products
#[inline(always)]
pub fn mul_q30_unsat(a: i32, f: i32) -> i32 {
    mul_hi(a, f) << 2
}
