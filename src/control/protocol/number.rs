//! Decimal numbers in fixed point, with integer code only: parsing a token
//! like `-0.130` into a scaled integer, and writing a scaled integer back as
//! a decimal. No formatting machinery (whose float code would otherwise
//! reach the robot), no 64-bit arithmetic and no division: the lx106 has no
//! divide instruction (`/ 10` is a ~65-instruction `__udivsi3` call per
//! digit), so digits come from multiplications by reciprocals that stay in
//! 32 bits ([`div_rem_10k`], [`div_rem_1000`]).

use heapless::String;

use crate::math::mul_hi_u32;

use super::Overflow;

/// Where the formatters write: a bounded text buffer. Every formatter takes
/// `&mut dyn TextOut` (pass `&mut some_heapless_string`), so its code exists
/// once in the firmware rather than once per buffer size.
pub trait TextOut {
    /// Appends `s`, or fails leaving what fitted.
    fn put_str(&mut self, s: &str) -> Result<(), Overflow>;
    /// Appends one ASCII byte (a non-ASCII byte is written as `?`).
    fn put_byte(&mut self, b: u8) -> Result<(), Overflow>;
    /// Appends ASCII bytes (each non-ASCII byte is written as `?`), or
    /// fails leaving what fitted. One call per number or cell, rather than
    /// one per byte.
    fn put_ascii(&mut self, bytes: &[u8]) -> Result<(), Overflow> {
        for &b in bytes {
            self.put_byte(b)?;
        }
        Ok(())
    }
}

impl<const N: usize> TextOut for String<N> {
    fn put_str(&mut self, s: &str) -> Result<(), Overflow> {
        self.push_str(s).map_err(|_| Overflow)
    }
    fn put_byte(&mut self, b: u8) -> Result<(), Overflow> {
        self.push(if b.is_ascii() { char::from(b) } else { '?' }).map_err(|_| Overflow)
    }
    fn put_ascii(&mut self, bytes: &[u8]) -> Result<(), Overflow> {
        for &b in bytes {
            self.push(if b.is_ascii() { char::from(b) } else { '?' }).map_err(|_| Overflow)?;
        }
        Ok(())
    }
}

/// Why a token is not a number.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum NumError {
    /// Not of the form `[+-]digits[.digits]` (or too many decimals).
    Bad,
    /// A number, but too large for the value type.
    Range,
}

/// Parses `[+-]?(digits)?(.digits)?` (at least one digit, and at least one
/// after a `.`) into `value * 10^decimals`. Digits past `decimals` must be
/// zeros (`0.1300` is `0.130`, `0.1305` is [`NumError::Bad`]): the value is
/// exact or refused, never rounded.
pub fn parse_fixed(token: &[u8], decimals: u32) -> Result<i32, NumError> {
    let (negative, mag) = parse_fixed_parts(token, decimals)?;
    // i64 only for the sign: -2^31 is an i32, +2^31 is not
    let v = if negative { i64::from(mag).wrapping_neg() } else { i64::from(mag) };
    i32::try_from(v).map_err(|_| NumError::Range)
}

/// [`parse_fixed`] as (sign, magnitude): the sign as written (`-0` is
/// negative), the magnitude `value * 10^decimals` up to `u32::MAX`.
pub fn parse_fixed_parts(token: &[u8], decimals: u32) -> Result<(bool, u32), NumError> {
    let (negative, body) = match token.split_first() {
        Some((b'-', rest)) => (true, rest),
        Some((b'+', rest)) => (false, rest),
        _ => (false, token),
    };
    let mut parts = body.splitn(2, |&b| b == b'.');
    let int = parts.next().unwrap_or(&[]);
    let frac = parts.next();
    // "", "-", "5." and "." are not numbers; ".5" is
    if frac.is_some_and(<[u8]>::is_empty) || (int.is_empty() && frac.is_none()) {
        return Err(NumError::Bad);
    }
    let mut mag: u32 = 0;
    let mut push_digit = |d: u8| -> Result<(), NumError> {
        if !d.is_ascii_digit() {
            return Err(NumError::Bad);
        }
        // mag * 10 overflows exactly when mag > u32::MAX / 10 (a compare: an
        // overflow-checked multiply would be a 64-bit product on the lx106)
        const MAG_MAX: u32 = u32::MAX / 10; // const-evaluated
        if mag > MAG_MAX {
            return Err(NumError::Range);
        }
        mag = mag.wrapping_mul(10).checked_add(u32::from(d.saturating_sub(b'0'))).ok_or(NumError::Range)?;
        Ok(())
    };
    for &d in int {
        push_digit(d)?;
    }
    let frac = frac.unwrap_or(&[]);
    let mut taken: u32 = 0;
    for &d in frac {
        if taken < decimals {
            push_digit(d)?;
            taken = taken.saturating_add(1);
        } else if d != b'0' {
            // a digit finer than the value's resolution (or not a digit)
            return Err(NumError::Bad);
        }
    }
    while taken < decimals {
        push_digit(b'0')?;
        taken = taken.saturating_add(1);
    }
    Ok((negative, mag))
}

/// Appends `s`.
pub fn push_str(out: &mut dyn TextOut, s: &str) -> Result<(), Overflow> {
    out.put_str(s)
}

/// Appends one ASCII byte (non-ASCII bytes become `?`).
pub fn push_byte(out: &mut dyn TextOut, b: u8) -> Result<(), Overflow> {
    out.put_byte(b)
}

/// Appends text, with any byte that is not printable ASCII replaced by `?`
/// (keeps a line one line, whatever text it is given).
pub fn push_text(out: &mut dyn TextOut, text: &str) -> Result<(), Overflow> {
    for b in text.bytes() {
        push_byte(out, if (0x20..0x7F).contains(&b) { b } else { b'?' })?;
    }
    Ok(())
}

/// `(v / 10_000, v % 10_000)` for every `u32`, without a division:
/// `q = floor(v * m / 2^45)` with `m = ceil(2^45 / 10^4) = 0xD1B7_1759` (the
/// reciprocal GCC and LLVM use). `m = 2^45 / 10^4 + e` with `e < 0.12`, so
/// `v * m / 2^45` exceeds `v / 10^4` by less than `2^32 * 0.12 / 2^45 < 1.5e-5`,
/// less than the gap of `10^-4` from `v / 10^4` up to the next integer: the
/// floor is exact (tests check every `v` just below a multiple of 10^4, the
/// only place an error could show).
#[inline]
pub fn div_rem_10k(v: u32) -> (u32, u32) {
    let q = mul_hi_u32(v, 0xD1B7_1759) >> 13;
    // q * 10^4 <= v: neither wraps
    (q, v.wrapping_sub(q.wrapping_mul(10_000)))
}

/// `(v / 1000, v % 1000)` for every `u32`, without a division: `m =
/// ceil(2^38 / 1000) = 0x1062_4DD3 = 2^38 / 1000 + e`, `e < 0.06`; the excess
/// `2^32 * 0.06 / 2^38 < 1e-3` stays below the gap of `10^-3` (see
/// [`div_rem_10k`]; tests check every `v` just below a multiple of 1000).
#[inline]
pub fn div_rem_1000(v: u32) -> (u32, u32) {
    let q = mul_hi_u32(v, 0x1062_4DD3) >> 6;
    // q * 1000 <= v: neither wraps
    (q, v.wrapping_sub(q.wrapping_mul(1000)))
}

/// `(v / 10, v % 10)` for `v < 81_920`: `(v * 0xCCCD) >> 19` (`0xCCCD =
/// ceil(2^19 / 10)`, the product < 2^32; exact in that range, a test checks
/// every value).
#[inline]
fn div_rem_10_small(v: u32) -> (u32, u32) {
    let q = v.wrapping_mul(0xCCCD) >> 19;
    // q * 10 <= v
    (q, v.wrapping_sub(q.wrapping_mul(10)))
}

/// Decimal digits of `v` (1 for 0), by comparisons.
#[inline]
fn digit_count(v: u32) -> usize {
    if v < 10_000 {
        if v < 100 {
            if v < 10 {
                1
            } else {
                2
            }
        } else if v < 1_000 {
            3
        } else {
            4
        }
    } else if v < 100_000_000 {
        if v < 1_000_000 {
            if v < 100_000 {
                5
            } else {
                6
            }
        } else if v < 10_000_000 {
            7
        } else {
            8
        }
    } else if v < 1_000_000_000 {
        9
    } else {
        10
    }
}

/// Capacity of a [`Cursor`], bytes: a power of two, so that masked indexes
/// need no bounds check.
pub(super) const CURSOR: usize = 128;

/// Text written left to right into a fixed buffer: the formatters' fast
/// path (a telemetry row is built in one and handed to
/// [`TextOut::put_ascii`] in three pieces). A piece that does not fit is
/// dropped and remembered.
pub(super) struct Cursor {
    buf: [u8; CURSOR],
    len: usize,
    overflow: bool,
}

impl Cursor {
    pub(super) fn new() -> Cursor {
        Cursor { buf: [0; CURSOR], len: 0, overflow: false }
    }

    /// Stores `b` at `i` (masked: always in the buffer).
    fn set(&mut self, i: usize, b: u8) {
        if let Some(slot) = self.buf.get_mut(i & (CURSOR - 1)) {
            *slot = b;
        }
    }

    pub(super) fn push(&mut self, b: u8) {
        if self.len < CURSOR {
            self.set(self.len, b);
            self.len = self.len.wrapping_add(1); // < CURSOR before
        } else {
            self.overflow = true;
        }
    }

    pub(super) fn push_bytes(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.push(b);
        }
    }

    /// `magnitude / 10^decimals` as in [`push_fixed_parts`]: the length is
    /// counted first, then the text is written from its last byte, four
    /// digits per reciprocal multiply by 10^4 and one per multiply by the
    /// reciprocal of 10 (no division).
    pub(super) fn number(&mut self, negative: bool, magnitude: u32, decimals: u32) {
        let decimals = decimals.min(9) as usize;
        let minus = negative && magnitude != 0;
        // digits <= 10 (u32::MAX has 10, decimals + 1 <= 10): text <= 12 bytes
        let digits = digit_count(magnitude).max(decimals.wrapping_add(1));
        let text_len = digits.wrapping_add(usize::from(decimals > 0)).wrapping_add(usize::from(minus));
        let end = self.len.wrapping_add(text_len); // both <= CURSOR
        if end > CURSOR {
            self.overflow = true;
            return;
        }
        // the point's index (none without decimals): decimals digits after it
        let point = if decimals == 0 { usize::MAX } else { end.wrapping_sub(decimals).wrapping_sub(1) };
        let mut p = end; // the next byte goes to p - 1
        let mut v = magnitude;
        let mut left = digits;
        // whole groups of four while more than four digits are left (at most
        // twice); then v < 10^left <= 10^4 (v has at most `left` digits)
        while left > 4 {
            let (q, mut r) = div_rem_10k(v);
            for _ in 0..4 {
                let (q10, d) = div_rem_10_small(r); // r < 10^4
                self.digit(&mut p, point, d);
                r = q10;
            }
            v = q;
            left = left.wrapping_sub(4);
        }
        for _ in 0..left {
            let (q10, d) = div_rem_10_small(v); // v < 10^4
            self.digit(&mut p, point, d);
            v = q10;
        }
        if minus {
            p = p.wrapping_sub(1);
            self.set(p, b'-');
        }
        self.len = end;
    }

    /// Writes digit `d` (< 10) in front of `p`, after the point if `p` has
    /// reached it.
    fn digit(&mut self, p: &mut usize, point: usize, d: u32) {
        *p = p.wrapping_sub(1);
        if *p == point {
            self.set(*p, b'.');
            *p = p.wrapping_sub(1);
        }
        self.set(*p, b'0'.wrapping_add(d as u8)); // d < 10
    }

    /// Bytes left in the buffer.
    pub(super) fn room(&self) -> usize {
        CURSOR.saturating_sub(self.len)
    }

    /// Starts again at the beginning of the buffer.
    pub(super) fn clear(&mut self) {
        self.len = 0;
        self.overflow = false;
    }

    /// What was written.
    pub(super) fn bytes(&self) -> &[u8] {
        self.buf.get(..self.len).unwrap_or(&[])
    }

    /// Appends what was written to `out`; fails if anything was dropped.
    pub(super) fn flush(&self, out: &mut dyn TextOut) -> Result<(), Overflow> {
        out.put_ascii(self.bytes())?;
        if self.overflow {
            Err(Overflow)
        } else {
            Ok(())
        }
    }
}

/// Appends `magnitude / 10^decimals` as a decimal with exactly `decimals`
/// digits after the point (none and no point when `decimals` is 0), with a
/// `-` in front when `negative` and the magnitude is not zero, in one
/// [`TextOut::put_ascii`]. `decimals` above 9 is treated as 9.
pub fn push_fixed_parts(out: &mut dyn TextOut, negative: bool, magnitude: u32, decimals: u32) -> Result<(), Overflow> {
    let mut text = Cursor::new();
    text.number(negative, magnitude, decimals);
    text.flush(out)
}

/// Appends a signed scaled value as a decimal (see [`push_fixed_parts`]).
pub fn push_fixed(out: &mut dyn TextOut, value: i32, decimals: u32) -> Result<(), Overflow> {
    push_fixed_parts(out, value < 0, value.unsigned_abs(), decimals)
}

/// Appends an unsigned integer.
pub fn push_u32(out: &mut dyn TextOut, v: u32) -> Result<(), Overflow> {
    push_fixed_parts(out, false, v, 0)
}

/// Appends `0x` and the value in lower-case hex, without leading zeros
/// (flash addresses).
pub fn push_hex(out: &mut dyn TextOut, v: u32) -> Result<(), Overflow> {
    const DIGITS: &[u8; 16] = b"0123456789abcdef";
    push_str(out, "0x")?;
    let digits = (32u32.saturating_sub(v.leading_zeros()).div_ceil(4)).max(1); // 1..=8
    for k in (0..digits).rev() {
        let nibble = (v >> k.saturating_mul(4)) & 0xF; // k < 8
        push_byte(out, DIGITS.get(nibble as usize).copied().unwrap_or(b'?'))?;
    }
    Ok(())
}

/// Appends a signed integer.
pub fn push_i32(out: &mut dyn TextOut, v: i32) -> Result<(), Overflow> {
    push_fixed(out, v, 0)
}
