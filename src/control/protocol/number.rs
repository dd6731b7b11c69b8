//! Decimal numbers in fixed point, with integer code only: parsing a token
//! like `-0.130` into a scaled integer, and writing a scaled integer back as
//! a decimal. No formatting machinery (whose float code would otherwise
//! reach the robot), no 64-bit multiply or divide: every value is a `u32` magnitude.

use heapless::String;

use super::Overflow;

/// Where the formatters write: a bounded text buffer. Every formatter takes
/// `&mut dyn TextOut` (pass `&mut some_heapless_string`), so its code exists
/// once in the firmware rather than once per buffer size.
pub trait TextOut {
    /// Appends `s`, or fails leaving what fitted.
    fn put_str(&mut self, s: &str) -> Result<(), Overflow>;
    /// Appends one ASCII byte (a non-ASCII byte is written as `?`).
    fn put_byte(&mut self, b: u8) -> Result<(), Overflow>;
}

impl<const N: usize> TextOut for String<N> {
    fn put_str(&mut self, s: &str) -> Result<(), Overflow> {
        self.push_str(s).map_err(|_| Overflow)
    }
    fn put_byte(&mut self, b: u8) -> Result<(), Overflow> {
        self.push(if b.is_ascii() { char::from(b) } else { '?' }).map_err(|_| Overflow)
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
        mag = mag
            .checked_mul(10)
            .and_then(|m| m.checked_add(u32::from(d.saturating_sub(b'0'))))
            .ok_or(NumError::Range)?;
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

/// Appends `magnitude / 10^decimals` as a decimal with exactly `decimals`
/// digits after the point (none and no point when `decimals` is 0), with a
/// `-` in front when `negative` and the magnitude is not zero.
/// `decimals` above 9 is treated as 9.
pub fn push_fixed_parts(out: &mut dyn TextOut, negative: bool, magnitude: u32, decimals: u32) -> Result<(), Overflow> {
    // u32::MAX has 10 digits; with up to 9 decimals a leading zero makes 10.
    let mut digits = [0u8; 10];
    let decimals = decimals.min(9) as usize;
    let mut len = 0usize;
    let mut v = magnitude;
    for slot in digits.iter_mut().rev() {
        *slot = b'0'.saturating_add((v % 10) as u8); // v % 10 < 10
        v /= 10;
        len = len.saturating_add(1); // at most digits.len() = 10
        if v == 0 && len > decimals {
            break;
        }
    }
    if negative && magnitude != 0 {
        push_byte(out, b'-')?;
    }
    // len <= 10 = digits.len(), so the start index cannot underflow
    let used = digits.get(digits.len().saturating_sub(len)..).unwrap_or(&[]);
    let (int, frac) = used.split_at_checked(len.saturating_sub(decimals)).unwrap_or((used, &[])); // len > decimals
    for &d in int {
        push_byte(out, d)?;
    }
    if decimals > 0 {
        push_byte(out, b'.')?;
        for &d in frac {
            push_byte(out, d)?;
        }
    }
    Ok(())
}

/// Appends a signed scaled value as a decimal (see [`push_fixed_parts`]).
pub fn push_fixed(out: &mut dyn TextOut, value: i32, decimals: u32) -> Result<(), Overflow> {
    push_fixed_parts(out, value < 0, value.unsigned_abs(), decimals)
}

/// Appends an unsigned integer.
pub fn push_u32(out: &mut dyn TextOut, value: u32) -> Result<(), Overflow> {
    push_fixed_parts(out, false, value, 0)
}

/// Appends a signed integer.
pub fn push_i32(out: &mut dyn TextOut, value: i32) -> Result<(), Overflow> {
    push_fixed(out, value, 0)
}
