//! Sine/cosine from a quarter-wave table with a second-order correction, and
//! a CORDIC `atan2` that returns an [`Angle`]. Integer only.

use super::sin_table::SIN_Q30;
use super::Angle;

/// Table index bits per turn: 1024 entries per turn, 256 per quadrant.
const INDEX_BITS: u32 = 10;
const SHIFT: u32 = 32 - INDEX_BITS;
/// The table step in radians, pi/512, times 2^15 / 32: converts an angle
/// offset of (2^-32 turn << 5) into radians Q24. round(2 pi / 8 * 2^15).
const DELTA_TO_Q24_Q15: i32 = 25_736;

// step bar
#[inline(always)]
fn table(i: u32) -> i32 {
    // i <= 256 by construction; `get` keeps the robot's path free of panics.
    SIN_Q30.get(i as usize).copied().unwrap_or(0)
}

/// `(sin a, cos a)` in Q2.30 (2^30 = 1). Max error 1.2e-7 (checked against f64
/// over every table interval in `tests/math/trig.rs`). About 40 lx106
/// instructions, no division, no 64-bit multiply.
///
/// `sin(t + d) = s0 (1 - d^2/2) + c0 d` and `cos(t + d) = c0 (1 - d^2/2) - s0 d`,
/// with `t` the nearest table angle (1024 per turn) and `|d| <= pi/1024`;
/// the dropped terms are below 5e-9.
// step bar: inlined into the turn step
#[inline(always)]
pub fn sin_cos(a: Angle) -> (i32, i32) {
    let k = a.0.wrapping_add(1 << (SHIFT - 1)) >> SHIFT; // nearest index, 0..1023
    let delta = a.0.wrapping_sub(k << SHIFT) as i32; // [-2^21, 2^21)
    let i = k & 0xFF;
    let (sa, sb) = (table(i), table(256 - i)); // sin(i h), sin((256 - i) h) = cos(i h)
    let (s0, c0) = match k >> 8 {
        0 => (sa, sb),
        1 => (sb, -sa),
        2 => (-sa, -sb),
        _ => (-sb, sa),
    };
    // d in radians Q24: |d| <= pi/1024 * 2^24 = 51472 < 2^16
    let d = ((((delta + 16) >> 5) * DELTA_TO_Q24_Q15) + (1 << 14)) >> 15;
    // d^2/2 in Q30: d^2 < 2^32 as u32 (Q48), >> 19 -> Q30 / 2, <= 5060
    let d2 = ((d.unsigned_abs() * d.unsigned_abs()) >> 19) as i32;
    let (s15, c15) = ((s0 + (1 << 14)) >> 15, (c0 + (1 << 14)) >> 15); // Q15, rounded, |.| <= 2^15
    let sin = s0 - ((s15 * d2) >> 15) + ((c15 * d) >> 9);
    let cos = c0 - ((c15 * d2) >> 15) - ((s15 * d) >> 9);
    (sin, cos)
}

/// CORDIC arctangent table: `round(atan(2^-i) / (2 pi) * 2^32)`.
const ATAN_BAM: [u32; 24] = [
    536_870_912,
    316_933_406,
    167_458_907,
    85_004_756,
    42_667_331,
    21_354_465,
    10_679_838,
    5_340_245,
    2_670_163,
    1_335_087,
    667_544,
    333_772,
    166_886,
    83_443,
    41_722,
    20_861,
    10_430,
    5_215,
    2_608,
    1_304,
    652,
    326,
    163,
    81,
];

/// `atan2(y, x)` as an [`Angle`] measured counter-clockwise from +x, i.e.
/// the angle of the vector (x, y) (any magnitudes; `(0, 0)` gives 0).
/// CORDIC vectoring, 24 iterations, error below 2e-7 rad plus the inputs'
/// own resolution. Shifts and adds only.
pub fn atan2(y: i32, x: i32) -> Angle {
    if x == 0 && y == 0 {
        return Angle::ZERO;
    }
    // Work in i64-free headroom: scale down to |v| < 2^29 so the CORDIC
    // gain (1.65) cannot overflow.
    let (mut x, mut y) = (i64::from(x), i64::from(y));
    let mut z: u32 = 0;
    // Rotate into the right half-plane.
    if x < 0 {
        x = -x;
        y = -y;
        z = Angle::HALF_TURN.0;
    }
    let mag = x.max(y.abs());
    let scale = if mag >= 1 << 29 { 64 - (mag.leading_zeros() as i32) - 29 } else { 0 };
    let (mut x, mut y) = ((x >> scale) as i32, (y >> scale) as i32);
    // Small vectors lose precision: bring them up to ~2^28.
    let lz = (x.max(y.abs()).max(1) as u32).leading_zeros() as i32;
    let up = (lz - 3).max(0);
    x <<= up;
    y <<= up;
    for (i, step) in ATAN_BAM.iter().enumerate() {
        let (dx, dy) = (y >> i, x >> i);
        if y > 0 {
            x += dx;
            y -= dy;
            z = z.wrapping_add(*step);
        } else {
            x -= dx;
            y += dy;
            z = z.wrapping_sub(*step);
        }
    }
    Angle(z)
}
