//! Fixed-point types and trigonometry. No knowledge of robots.
//!
//! The lx106 has no FPU, no hardware divide and no 32x32->64 high multiply,
//! so every type here is an integer with a documented scale, and the hot
//! paths use [`mul_hi`] (three 16x16 products) instead of a 64-bit multiply.
//!
//! | type | storage | one LSB | range |
//! | --- | --- | --- | --- |
//! | [`Angle`] | `u32` | 2^-32 turn (1.46e-9 rad) | one turn, wraps for free |
//! | [`Length`] | `i32` | 2^-16 mm | +-32.7 m |
//! | [`Coord`] | `i64` | 2^-32 mm | +-2.1e6 m (pose position) |
//! | [`Speed`] | `i32` | 2^-32 mm/us (2.3e-7 m/s) | +-[`Speed::MAX`] |
//! | [`TurnRate`] | `i32` | 2^-16 angle LSB/us (2.2e-8 rad/s) | +-[`TurnRate::MAX`] |
//! | [`Dt`] | `u16` | 1 us | 0..65.535 ms |
//! | sin/cos | `i32` | 2^-30 (Q2.30) | +-1 |
//!
//! Why not the `fixed` or `cordic` crates: the per-step path needs
//! `mul_hi`-style products that never widen to `i64` (a `__muldi3` call of
//! ~40 instructions on the lx106, which `fixed`'s generic multiply uses), and
//! `fixed` crashes LLVM's Xtensa backend at opt-level 0. CORDIC needs one
//! iteration per bit (16+ iterations for 1e-5); the 257-entry table with a
//! second-order correction in [`sin_cos`] gives 1.2e-7 in five multiplies.
//! The `*_f64` constructors are `const fn`s for the config module: they are
//! evaluated by the compiler, so no float code reaches the robot.

mod mul;
mod recip;
mod shift;
mod sin_table;
mod sqrt;
mod trig;

pub use mul::{mul_hi, mul_hi_u, mul_hi_u32, mul_q30, mul_q30_unsat, mul_u31, mul_wide};
pub use recip::{quotient, reciprocal};
pub use shift::{normalize, shift};
pub use sqrt::{isqrt, isqrt64};
pub use trig::{atan2, sin_cos};

/// Rounds an `f64` to the nearest `i64` in a `const fn` (`f64::round` is not
/// const on Rust 1.82).
/// cos(x) for |x| <= pi, by its series (const: for the config's angles).
pub const fn cos_f64(x: f64) -> f64 {
    let (mut term, mut sum, mut k) = (1.0, 1.0, 1);
    while k < 20 {
        term = -term * x * x / ((2 * k - 1) as f64 * (2 * k) as f64);
        sum += term;
        k += 1;
    }
    sum
}

/// ln(x) for x > 0 (const: for the config's constants): halved or
/// doubled into [0.75, 1.5], then the series of `2 atanh((x - 1) / (x +
/// 1))`, whose ratio is then at most 1/5 a term.
pub const fn ln_f64(x: f64) -> f64 {
    const fn series(x: f64) -> f64 {
        let y = (x - 1.0) / (x + 1.0);
        let (mut power, mut sum, mut k) = (y, 0.0, 0);
        while k < 30 {
            sum += power / (2 * k + 1) as f64;
            power *= y * y;
            k += 1;
        }
        2.0 * sum
    }
    let (mut x, mut halvings) = (x, 0i32);
    while x > 1.5 {
        x /= 2.0;
        halvings += 1;
    }
    while x < 0.75 {
        x *= 2.0;
        halvings -= 1;
    }
    series(x) + halvings as f64 * series(2.0)
}

pub const fn round_f64(x: f64) -> i64 {
    if x >= 0.0 {
        (x + 0.5) as i64
    } else {
        (x - 0.5) as i64
    }
}

/// Saturating `i64 -> i32` (const).
pub const fn sat_i32(x: i64) -> i32 {
    if x > i32::MAX as i64 {
        i32::MAX
    } else if x < i32::MIN as i64 {
        i32::MIN
    } else {
        x as i32
    }
}

/// `n / d` for `u64`, `None` when `d == 0`.
///
/// The lx106 has no divide instruction: on the robot this is a call of the
/// ESP8266 ROM's `__udivdi3` (libgcc's, linked at its ROM address by
/// `rom-functions.x`; Espressif's lx106 libgcc leaves the ROM's helpers out
/// for that reason), so no division code is in flash. The call sites are
/// cold (commands, `status`, telemetry's turn rate, the calibration's
/// result): nothing on the state update's or the estimator's path divides.
/// Every division in the robot's code is here, in [`div_i64`] (the ROM's
/// `__divdi3`) or in [`div_round`] (one division of magnitudes).
// a call: inlined, a division of small constants would become a 32-bit
// `__udivsi3`, which the ROM linking leaves out
#[inline(never)]
pub const fn div_u64(n: u64, d: u64) -> Option<u64> {
    n.checked_div(d)
}

/// `n / d` truncated toward zero, as [`i64::checked_div`]: `None` when
/// `d == 0` or for `i64::MIN / -1` (on the robot a call of the ROM's
/// `__divdi3`, see [`div_u64`]).
pub fn div_i64(n: i64, d: i64) -> Option<i64> {
    n.checked_div(d)
}

/// `n / d` rounded to nearest (halves away from zero); `None` when `d == 0`
/// or the quotient does not fit (`i64::MIN / -1`). Off the per-step path
/// only (see [`div_u64`]).
pub fn div_round(n: i64, d: i64) -> Option<i64> {
    // on the magnitudes, `(|n| + floor(|d| / 2)) / |d|` rounds half up:
    // for an even |d| that is the half; for an odd one the remainder
    // reaches ceil(|d| / 2) exactly when it is more than half. No wrap:
    // |n| <= 2^63 and |d| / 2 <= 2^62.
    let d_abs = d.unsigned_abs();
    let q = div_u64(n.unsigned_abs() + (d_abs >> 1), d_abs)?;
    // the magnitude with its sign, if it fits an i64 (-2^63 is i64::MIN)
    if (n < 0) != (d < 0) {
        (q <= 1 << 63).then(|| (q as i64).wrapping_neg())
    } else {
        i64::try_from(q).ok()
    }
}

/// Binary angle: `u32` where 2^32 is one full turn, so adding and
/// subtracting wrap at 360 degrees for free and never lose precision.
/// Headings use it clockwise from north (see the crate docs).
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug, Default, PartialOrd, Ord)]
pub struct Angle(pub u32);

impl Angle {
    pub const ZERO: Angle = Angle(0);
    pub const QUARTER_TURN: Angle = Angle(1 << 30);
    pub const HALF_TURN: Angle = Angle(1 << 31);

    /// From degrees (const: for the config module and host code).
    pub const fn from_degrees_f64(deg: f64) -> Angle {
        let turns = deg / 360.0;
        let frac = turns - (turns as i64) as f64; // in (-1, 1)
        Angle(round_f64(frac * 4_294_967_296.0) as u32)
    }
    /// From radians (const: for the config module and host code).
    pub const fn from_radians_f64(rad: f64) -> Angle {
        Angle::from_degrees_f64(rad * (180.0 / core::f64::consts::PI))
    }
    /// From integer millidegrees (any value; wraps).
    /// Exact to the nearest LSB: `2^32 / 360000 = 2^26 / 5625`. Not on the
    /// per-step path (one division).
    pub fn from_millidegrees(mdeg: i32) -> Angle {
        // 2^32 / 360_000 = 2^26 / 5625, and 360_000 mdeg is exactly 2^32:
        // rounding commutes with the wrap (5625 is odd: no ties), so a
        // negative value needs no rem_euclid. |mdeg| 2^26 < 2^57.
        Angle(div_round(i64::from(mdeg) << 26, 5625).unwrap_or(0) as u32)
    }
    /// Millidegrees in `0..360_000` (rounded).
    pub fn to_millidegrees(self) -> u32 {
        // round(a 360000 / 2^32) = (a 360000 + 2^31) >> 32: the product's
        // high word plus the carry of adding 2^31 to its low word. It is
        // 360_000 only when rounding up just below a full turn: that is 0.
        let hi = mul_hi_u32(self.0, 360_000);
        let m = hi.wrapping_add(self.0.wrapping_mul(360_000) >> 31); // <= 360_000
        if m == 360_000 {
            0
        } else {
            m
        }
    }
    /// Signed millidegrees in `-180_000..180_000` (rounded).
    pub fn to_signed_millidegrees(self) -> i32 {
        ((i64::from(self.0 as i32) * 360_000 + (1 << 31)) >> 32) as i32
    }
    /// Radians in `[0, 2 pi)` (host code and tests).
    pub fn to_radians_f64(self) -> f64 {
        f64::from(self.0) * (core::f64::consts::TAU / 4_294_967_296.0)
    }
    /// Signed difference `self - other` in angle LSBs (`-2^31..2^31`).
    pub fn diff(self, other: Angle) -> i32 {
        self.0.wrapping_sub(other.0) as i32
    }
    pub fn wrapping_add(self, other: Angle) -> Angle {
        Angle(self.0.wrapping_add(other.0))
    }
    pub fn wrapping_sub(self, other: Angle) -> Angle {
        Angle(self.0.wrapping_sub(other.0))
    }
}

/// A length or distance: `i32` in units of 2^-16 mm (range +-32.7 m).
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug, Default, PartialOrd, Ord)]
pub struct Length(pub i32);

impl Length {
    pub const ZERO: Length = Length(0);
    pub const MAX: Length = Length(i32::MAX);
    pub const fn from_mm_f64(mm: f64) -> Length {
        Length(sat_i32(round_f64(mm * 65536.0)))
    }
    /// From whole millimetres (saturating).
    pub const fn from_mm(mm: i32) -> Length {
        Length(mm.saturating_mul(65536))
    }
    /// From micrometres (saturating).
    pub fn from_um(um: i32) -> Length {
        let bits = div_i64(i64::from(um) << 16, 1000).unwrap_or(0);
        Length(sat_i32(bits))
    }
    /// Whole millimetres, rounded to nearest.
    pub fn to_mm(self) -> i32 {
        ((i64::from(self.0) + (1 << 15)) >> 16) as i32
    }
    /// Micrometres, rounded to nearest.
    pub fn to_um(self) -> i32 {
        ((i64::from(self.0) * 1000 + (1 << 15)) >> 16) as i32
    }
    pub fn to_mm_f64(self) -> f64 {
        f64::from(self.0) / 65536.0
    }
    pub fn saturating_add(self, o: Length) -> Length {
        Length(self.0.saturating_add(o.0))
    }
    pub fn saturating_sub(self, o: Length) -> Length {
        Length(self.0.saturating_sub(o.0))
    }
}

/// A pose coordinate: `i64` in units of 2^-32 mm. The state update adds
/// steps of 2^-22 mm resolution to it, so no rounding error builds up over
/// hours of updates.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug, Default, PartialOrd, Ord)]
pub struct Coord(pub i64);

impl Coord {
    pub const ZERO: Coord = Coord(0);
    pub const fn from_mm_f64(mm: f64) -> Coord {
        Coord(round_f64(mm * 4_294_967_296.0))
    }
    pub const fn from_length(l: Length) -> Coord {
        Coord((l.0 as i64) << 16)
    }
    /// The coordinate as a [`Length`], rounded and saturated to +-32.7 m.
    pub fn to_length(self) -> Length {
        let bits = self.0.saturating_add(1 << 15) >> 16;
        Length(sat_i32(bits))
    }
    pub fn to_mm_f64(self) -> f64 {
        self.0 as f64 / 4_294_967_296.0
    }
    /// Adds a step in units of 2^-22 mm (what [`mul_hi`] of a Q24 length and
    /// a Q30 sine gives). Wrapping: a coordinate wraps only after 2^31 mm =
    /// 2147 km of travel in one direction (days of driving at the robot's top
    /// speed), and a saturating i64 add costs 20 lx106 instructions where
    /// this costs 4.
    // step bar
    #[inline(always)]
    pub fn add_q22(self, step: i32) -> Coord {
        Coord(self.0.wrapping_add(i64::from(step) << 10))
    }
    /// The same for a step in Q21 mm.
    // step bar
    #[inline(always)]
    pub fn add_q21(self, step: i32) -> Coord {
        Coord(self.0.wrapping_add(i64::from(step) << 11))
    }
}

/// Linear speed: `i32` in units of 2^-32 mm/us (2.3e-7 m/s), signed.
/// Constructors clamp to +-[`Speed::MAX`], which keeps one step's distance
/// (at most 65.5 ms) inside the state update's 32-bit products.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug, Default, PartialOrd, Ord)]
pub struct Speed(i32);

impl Speed {
    pub const ZERO: Speed = Speed(0);
    /// 1 m/s (the paperbot does about 0.15).
    pub const MAX: Speed = Speed(4_294_967);
    /// Units of this type per mm/s: 2^32 / 1e6.
    const PER_MM_S: f64 = 4_294_967_296.0 / 1_000_000.0;
    const PER_MM_S_Q16: i64 = round_f64(Self::PER_MM_S * 65536.0);

    pub const fn from_bits(bits: i32) -> Speed {
        if bits > Self::MAX.0 {
            Self::MAX
        } else if bits < -Self::MAX.0 {
            Speed(-Self::MAX.0)
        } else {
            Speed(bits)
        }
    }
    pub const fn to_bits(self) -> i32 {
        self.0
    }
    pub const fn from_mps_f64(mps: f64) -> Speed {
        Speed::from_bits(sat_i32(round_f64(mps * 1000.0 * Self::PER_MM_S)))
    }
    /// From mm/s in Q16 (clamped).
    pub fn from_mm_s_q16(mm_s_q16: i32) -> Speed {
        let bits = (i64::from(mm_s_q16) * Self::PER_MM_S_Q16) >> 32;
        Speed::from_bits(sat_i32(bits))
    }
    /// From whole mm/s (clamped).
    pub fn from_mm_s(mm_s: i32) -> Speed {
        Speed::from_mm_s_q16(mm_s.saturating_mul(65536))
    }
    /// Speed in mm/s, rounded.
    pub fn to_mm_s(self) -> i32 {
        ((i64::from(self.0) * 1_000_000 + (1 << 31)) >> 32) as i32
    }
    pub fn to_mps_f64(self) -> f64 {
        f64::from(self.0) / Self::PER_MM_S / 1000.0
    }
    pub fn abs(self) -> Speed {
        Speed(self.0.wrapping_abs()) // |bits| <= MAX: no wrap
    }
    #[allow(clippy::should_implement_trait)] // also implemented: `-speed`
    pub fn neg(self) -> Speed {
        Speed(-self.0) // |bits| <= MAX, so negation cannot overflow
    }

    /// Distance covered in `dt`, in units of 2^-24 mm (|result| < 2^31: at
    /// most 65.5 mm, `MAX` over `Dt::MAX`).
    /// Two 16x16 products: `v = vh * 2^16 + vl`, `v dt / 2^8 = vh dt 2^8 + vl dt / 2^8`.
    // step bar
    #[inline(always)]
    pub fn distance_q24(self, dt: Dt) -> i32 {
        let dt = u32::from(dt.0);
        let vh = self.0 >> 16; // |vh| <= 66 (MAX >> 16)
        let vl = (self.0 & 0xFFFF) as u32;
        let hi = vh * (dt as i32); // |.| < 2^23
        let lo = (vl * dt + (1 << 7)) >> 8; // vl*dt < 2^32 - 2^17
        (hi << 8) + lo as i32
    }
}

impl core::ops::Neg for Speed {
    type Output = Speed;
    fn neg(self) -> Speed {
        Speed::neg(self)
    }
}

/// Turn rate: `i32` in units of 2^-16 [`Angle`] LSB per microsecond
/// (2.2e-8 rad/s), positive clockwise. Clamped to +-[`TurnRate::MAX`].
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug, Default, PartialOrd, Ord)]
pub struct TurnRate(i32);

impl TurnRate {
    pub const ZERO: TurnRate = TurnRate(0);
    /// 20 rad/s (the paperbot turns at about 3).
    pub const MAX: TurnRate = TurnRate(round_f64(20.0 * Self::PER_RAD_S) as i32);
    /// Units of this type per rad/s: 2^32 / (2 pi) / 1e6 * 2^16.
    const PER_RAD_S: f64 = 4_294_967_296.0 / core::f64::consts::TAU / 1_000_000.0 * 65536.0;
    const PER_RAD_S_Q16: i64 = round_f64(Self::PER_RAD_S);

    pub const fn from_bits(bits: i32) -> TurnRate {
        if bits > Self::MAX.0 {
            Self::MAX
        } else if bits < -Self::MAX.0 {
            TurnRate(-Self::MAX.0)
        } else {
            TurnRate(bits)
        }
    }
    pub const fn to_bits(self) -> i32 {
        self.0
    }
    pub const fn from_rad_s_f64(rad_s: f64) -> TurnRate {
        TurnRate::from_bits(sat_i32(round_f64(rad_s * Self::PER_RAD_S)))
    }
    /// From rad/s in Q16 (clamped).
    pub fn from_rad_s_q16(rad_s_q16: i32) -> TurnRate {
        let bits = (i64::from(rad_s_q16) * Self::PER_RAD_S_Q16) >> 16;
        TurnRate::from_bits(sat_i32(bits))
    }
    /// From whole milliradians per second (clamped).
    pub fn from_mrad_s(mrad_s: i32) -> TurnRate {
        let bits = div_i64(i64::from(mrad_s) * Self::PER_RAD_S_Q16, 1000).unwrap_or(0);
        TurnRate::from_bits(sat_i32(bits))
    }
    /// Milliradians per second, rounded.
    pub fn to_mrad_s(self) -> i32 {
        let n = i64::from(self.0) * 1000;
        let half = Self::PER_RAD_S_Q16 / 2;
        div_i64(if n >= 0 { n + half } else { n - half }, Self::PER_RAD_S_Q16).unwrap_or(0) as i32
    }
    /// rad/s in Q16, rounded.
    pub fn to_rad_s_q16(self) -> i32 {
        let n = i64::from(self.0) << 16;
        div_round(n, Self::PER_RAD_S_Q16).unwrap_or(0) as i32
    }
    pub fn to_rad_s_f64(self) -> f64 {
        f64::from(self.0) / Self::PER_RAD_S
    }
    pub fn abs(self) -> TurnRate {
        TurnRate(self.0.wrapping_abs()) // |bits| <= MAX: no wrap
    }
    #[allow(clippy::should_implement_trait)] // also implemented: `-rate`
    pub fn neg(self) -> TurnRate {
        TurnRate(-self.0) // |bits| <= MAX
    }

    /// Rotation over `dt` as (whole angle LSBs, 2^-16 fraction). Exact:
    /// `w = wh 2^16 + wl`, `w dt = wh dt 2^16 + wl dt`, and the angle is
    /// modulo one turn, so the wrapping multiply is the right answer.
    // step bar
    #[inline(always)]
    pub fn rotation(self, dt: Dt) -> (Angle, u16) {
        let dt = u32::from(dt.0);
        let wh = (self.0 >> 16) as u32; // two's complement: wraps mod 2^32
        let wl = (self.0 & 0xFFFF) as u32;
        let lo = wl * dt; // < 2^32
        (Angle(wh.wrapping_mul(dt).wrapping_add(lo >> 16)), lo as u16)
    }
}

impl core::ops::Neg for TurnRate {
    type Output = TurnRate;
    fn neg(self) -> TurnRate {
        TurnRate::neg(self)
    }
}

/// A time step for the state update: whole microseconds, at most 65.535 ms.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug, Default, PartialOrd, Ord)]
pub struct Dt(u16);

/// A time step longer than [`Dt::MAX`].
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub struct DtTooLong;

impl Dt {
    pub const MAX: Dt = Dt(u16::MAX);
    pub const fn from_micros(us: u32) -> Result<Dt, DtTooLong> {
        if us > u16::MAX as u32 {
            Err(DtTooLong)
        } else {
            Ok(Dt(us as u16))
        }
    }
    /// Clamped to [`Dt::MAX`].
    pub const fn from_micros_saturating(us: u32) -> Dt {
        if us > u16::MAX as u32 {
            Dt::MAX
        } else {
            Dt(us as u16)
        }
    }
    pub const fn as_micros(self) -> u32 {
        self.0 as u32
    }
}
