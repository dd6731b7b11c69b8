//! The lidar's cone on the box's walls (see [`super`]'s module docs): the
//! cone's incidence on a wall, which of two candidate walls is nearer in
//! the cone, and whether a corner's other wall comes within a margin, all
//! division-free. [`super::Beam`] puts them together.

use super::Beam;
use crate::config;
use crate::math::{mul_hi, mul_hi_u, mul_q30_unsat, reciprocal, Length};

/// cos and sin of half the lidar's cone (Q2.30), from the config.
pub(super) const COS_HALF_CONE: i32 = crate::math::round_f64(
    crate::math::cos_f64(config::lidar::CONE_DEG / 2.0 * core::f64::consts::TAU / 360.0) * 1_073_741_824.0,
) as i32;
pub(super) const SIN_HALF_CONE: i32 = crate::math::round_f64(
    crate::math::cos_f64((90.0 - config::lidar::CONE_DEG / 2.0) * core::f64::consts::TAU / 360.0) * 1_073_741_824.0,
) as i32;
pub(super) const ONE: i32 = 1 << 30;

/// The cone's incidences on a wall, from the axis's `|cos|` and `|sin|`
/// (Q2.30) on it, `n` and `t`, and the half cone `h`: the cone's direction
/// nearest the normal of the wall ahead meets it at `cos(a - h) = n cos h +
/// t sin h` (square on, 1, when the normal is inside the cone: `n >= cos
/// h`), the wall behind at `cos(pi - a - h) = t sin h - n cos h`; the
/// sines are `t cos h - n sin h` and `t cos h + n sin h`.
// tick bar: the products only where a wall is met off square (a wall
// square ahead needs none), each pair shared by the wall behind
#[derive(Clone, Copy)]
pub(super) struct Incidence {
    /// `n cos h` and `t sin h`.
    n_ch: i32,
    t_sh: i32,
}

// tick bar: Incidence and sides_clear are inlined into `Beam::new`, on a
// lidar correction's path
impl Incidence {
    #[inline(always)]
    pub(super) fn new(n: i32, t: i32) -> Incidence {
        // |n|, |t| <= 2^30 and the half cone's below: each product below 2^30
        Incidence { n_ch: mul_q30_unsat(n, COS_HALF_CONE), t_sh: mul_q30_unsat(t, SIN_HALF_CONE) }
    }
    /// The cosine toward the wall ahead (off square) or behind.
    #[inline(always)]
    pub(super) fn cos(&self, ahead: bool) -> i32 {
        if ahead {
            self.n_ch + self.t_sh
        } else {
            self.t_sh - self.n_ch
        }
    }
}

/// The sine of the cone's incidence on the wall ahead (0 when square on)
/// or behind, for the axis's `|cos|` `n` and `|sin|` `t` on it (see
/// [`Incidence`]): only for the wall a beam is taken on.
pub(super) fn cone_sine(n: i32, t: i32, ahead: bool) -> i32 {
    if ahead && n >= COS_HALF_CONE {
        return 0;
    }
    // each product below 2^30
    let t_ch = mul_q30_unsat(t, COS_HALF_CONE);
    let n_sh = mul_q30_unsat(n, SIN_HALF_CONE);
    if ahead {
        t_ch - n_sh
    } else {
        t_ch + n_sh
    }
}

/// Of two opposite walls at distances `a` (the one the axis heads for) and
/// `b` along their normal, with the axis's `|cos|` on them `n` and `|sin|`
/// `t`: whether `b`'s wall is nearer in the cone, and the chosen wall's
/// distance and cone cosine. The far wall is in the cone only when the axis
/// is within half the cone of parallel to it.
// tick bar: the second wall only when the axis runs near parallel
#[inline(always)]
pub(super) fn nearer_of(n: i32, t: i32, a: Length, b: Length) -> (bool, Length, i32) {
    if n >= COS_HALF_CONE {
        return (false, a, ONE);
    }
    let inc = Incidence::new(n, t);
    let ca = inc.cos(true);
    if n > SIN_HALF_CONE {
        return (false, a, ca);
    }
    let cb = inc.cos(false);
    // the wall behind is met less square (cb <= ca): nearer in the cone
    // only when it is nearer along its normal too
    if cb <= 0 || a <= b {
        return (false, a, ca);
    }
    // a / ca <= b / cb, i.e. a cb <= b ca (each distance clamped at 0)
    if ca > 0 && mul_hi(a.0.max(0), cb) <= mul_hi(b.0.max(0), ca) {
        (false, a, ca)
    } else {
        (true, b, cb)
    }
}

/// `mul_hi(a, n)` for a cone cosine `n` (Q2.30): exactly `a >> 2` when
/// the wall is met square on (`n` = 1, the common case).
// tick bar: the square-on case without a product
#[inline(always)]
pub(super) fn mul_cos(a: i32, n: i32) -> i32 {
    if n == ONE {
        a >> 2
    } else {
        mul_hi(a, n)
    }
}

/// A mount offset times a sine or cosine (Q2.30), skipped for a zero
/// offset (each config mount has one).
// tick bar
#[inline(always)]
pub(super) fn mount_product(l: Length, t: i32) -> i32 {
    if l.0 == 0 {
        0
    } else {
        mul_q30_unsat(l.0, t) // |t| <= 2^30: below |l|
    }
}

/// The largest margin [`Beam::near_corner`] tells apart (larger
/// margins are taken as this one; `config::estimator::CORNER_MARGIN_MAX`).
pub const CORNER_MARGIN_MAX: Length = config::estimator::CORNER_MARGIN_MAX;

/// The cone's other candidate wall, for [`Beam::near_corner`].
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub(super) enum Corner {
    /// Farther in the cone than [`CORNER_MARGIN_MAX`] beyond the beam's wall.
    Clear,
    /// The cone's distances to the two candidate walls, cross-multiplied
    /// (division-free): the beam's wall's distance times the other's cone
    /// cosine, and the other's distance times the beam's wall's, Q14 mm;
    /// and the other's cone cosine.
    Cross { cross: i32, other_cross: i32, other_normal: i32 },
}

/// An allowance of 2^-10 (Q2.30) on the side walls' cone cosine in
/// [`sides_clear`], for the fixed point's rounding.
pub(super) const SIDE_ALLOWANCE: i32 = 1 << 20;

/// For a beam whose axis is nearer the normal of the wall ahead than the
/// side walls' (its `|cos|` on that wall `n` at least its `|sin|` `t`), at
/// `ahead` from that wall along its normal, with the cone's cosine there
/// `cone_normal`: whether the side walls, the nearer at `side` along their
/// normal, are certainly farther in the cone than [`CORNER_MARGIN_MAX`]
/// beyond the wall ahead. The cone's cosine on a side wall is at most
/// `t cos h + n sin h <= t + sin h` (half cone `h`), so the side walls are
/// at least `side / (t + sin h)` away in the cone, the wall ahead
/// `ahead / cone_normal`: `(ahead + CORNER_MARGIN_MAX) (t + sin h) <= side
/// cone_normal` is enough. With [`SIDE_ALLOWANCE`] (above 1 mm of the
/// margin in Q14 mm, against a few LSB of rounding) it decides exactly what
/// the cone's products on both axes would: the wall ahead, and never near a
/// corner for a margin up to the largest (the unit test below checks it).
// tick bar (see Incidence)
#[inline(always)]
pub(super) fn sides_clear(ahead: Length, side: Length, t: i32, cone_normal: i32) -> bool {
    // t <= 2^30 / sqrt 2 (t <= n): the sum below 2^30; the products in Q14
    // mm. A side at or behind the lidar (<= 0) is never clear.
    let reach = mul_hi(ahead.0.max(0).saturating_add(CORNER_MARGIN_MAX.0), t + SIN_HALF_CONE + SIDE_ALLOWANCE);
    reach <= mul_hi(side.0, cone_normal)
}

/// The beam's wall when the side walls are not clear ([`sides_clear`]):
/// the wall ahead on the main axis (at `ahead`, cone cosine `cone_normal`,
/// the axis's `|cos|` `n` and `|sin|` `t` on it; the wall behind is out of
/// the cone) or, when nearer in the cone, the side wall ahead or behind the
/// side axis heads for (at `side_ahead`, `side_behind`). Ties go to the
/// x-wall (`x_main`). Returns whether a side wall is met, whether the one
/// behind, and the chosen wall's axis cosine, cone cosine and sine,
/// distance and corner test.
// search bar: inlined into `Beam::new`, the search's beam (once it had a second caller, the
// estimator's `Beam::at`, the search's slice grew 271,568 -> 295,267 lx106 instructions)
#[inline(always)]
pub(super) fn side_search(
    x_main: bool,
    (n, t): (i32, i32),
    (ahead, cone_normal): (Length, i32),
    side_ahead: Length,
    side_behind: Length,
) -> (bool, bool, i32, i32, i32, Length, Corner) {
    let (far, side, side_normal) = nearer_of(t, n, side_ahead, side_behind);
    // The main wall is nearer in the cone when A_m / n_m <= A_s / n_s, i.e.
    // A_m n_s <= A_s n_m (a negative A, a lidar outside the box, counts as
    // 0; a side wall out of the cone, n_s <= 0, is never nearer; the main
    // wall's n_m > 0: its axis is within 45 degrees of its normal).
    let main_cross = mul_cos(ahead.0.max(0), side_normal.max(0));
    let side_cross = mul_cos(side.0.max(0), cone_normal);
    let main_first = side_normal <= 0 || if x_main { main_cross <= side_cross } else { main_cross < side_cross };
    if main_first {
        let corner = Corner::Cross { cross: main_cross, other_cross: side_cross, other_normal: side_normal.max(1) };
        (false, false, n, cone_normal, cone_sine(n, t, true), ahead, corner)
    } else {
        let corner = Corner::Cross { cross: side_cross, other_cross: main_cross, other_normal: cone_normal };
        (true, far, t, side_normal.max(1), cone_sine(t, n, !far), side, corner)
    }
}

/// The largest margin's square, Q12 mm^2 (160 mm: 2^26.6): the corner's
/// variance saturates there.
const MAX_VARIANCE_Q12: i32 = {
    let m = (CORNER_MARGIN_MAX.0 >> 8) as i64; // Q8 mm
    let v = (m * m) >> 4; // Q12 mm^2
    assert!(v < 1 << 30);
    v as i32
};

/// The corner tests of a [`Beam`]: its cone's other candidate
/// wall against a margin, and what a heading error makes of a reading
/// between the two walls.
impl Beam {
    /// True when the cone meets a second wall within [`CORNER_MARGIN_MAX`]
    /// of the beam's (then [`Beam::corner_reading`] tells how near).
    pub fn meets_two_walls(&self) -> bool {
        matches!(self.corner, Corner::Cross { .. })
    }

    /// How a reading's range depends on the cone meeting two walls: `None`
    /// when their ranges are within `mixed` (the sensor mixes their
    /// returns: the reading is not used, as [`Beam::near_corner`] says);
    /// else the corner's variance, Q12 mm^2, 0 when the walls are told
    /// apart. A heading error `e` moves the two walls' nearest points apart
    /// by `r (tan a + tan b) e` for the cone's incidences `a`, `b` on walls
    /// at right angles (`r` the range): `r e sin(a + b) / (cos a cos b)`,
    /// taken with `sin(a + b) = 1` (`a + b` is at least 65 degrees: at most
    /// 10 % more). With `heading_range2()` the heading's variance times the
    /// range squared (Q12 mm^2), the corner's variance is `floor^2 +
    /// heading_range2() / (cos a cos b)^2`, and the reading is ambiguous
    /// when the walls' ranges are within `sigmas` of its root (at most
    /// [`CORNER_MARGIN_MAX`]). The tests are division-free and root-free, in
    /// 32 bits; the variance one [`reciprocal`].
    pub fn corner_reading(
        &self,
        mixed: Length,
        floor: Length,
        heading_range2: impl FnOnce() -> i32,
        sigmas: i32,
    ) -> Option<i32> {
        let Some((apart, cs)) = self.corner_apart() else {
            return Some(0);
        };
        if within(apart, cs, mixed) {
            return None;
        }
        if apart >= mul_hi(CORNER_MARGIN_MAX.0, cs) {
            return Some(0);
        }
        // apart^2 < sigmas^2 (floor^2 cs^2 + heading_range2) in Q8 mm^2,
        // 32-bit (the lx106 multiplies 32 bits natively, not 64): apart is
        // below the largest margin (2^21.3 in Q14), in Q4 below 2^11.3, its
        // square below 2^23; the floor's (within the largest margin) and the
        // heading's Q12 >> 4 each below 2^23; the sum times sigmas^2 (at
        // most 64) below 2^30. The heading's is asked for only now: most
        // cones that meet two walls are past the largest margin.
        let apart = apart >> 10;
        let heading_range2 = heading_range2().clamp(0, MAX_VARIANCE_Q12);
        let floor = floor.0.clamp(0, CORNER_MARGIN_MAX.0);
        let floor_cs = mul_hi(floor, cs) >> 10;
        let sigmas = sigmas.clamp(0, 8);
        if apart * apart >= sigmas * sigmas * (floor_cs * floor_cs + (heading_range2 >> 4)) {
            return Some(0);
        }
        // heading_range2 / cs^2: 1/cs = 2^30/cs is reciprocal(cs << sh)
        // 2^(sh - 32); two high words and the shift back, saturated at
        // the largest margin's square
        let (x, sh) = crate::math::normalize(cs.max(1) as u32);
        let inv = reciprocal(x);
        let (scaled, up) = (mul_hi_u(mul_hi_u(heading_range2 as u32, inv), inv), (2 * sh).min(31));
        let spread = if scaled > (MAX_VARIANCE_Q12 as u32) >> up { MAX_VARIANCE_Q12 } else { (scaled << up) as i32 };
        Some((mul_hi(floor, floor) << 12).saturating_add(spread))
    }

    /// True when the nearest points in the cone on the two candidate walls
    /// are less than `margin` (at most [`CORNER_MARGIN_MAX`]) apart in
    /// range. Division-free:
    /// `|A_x n_y - A_y n_x| < margin n_x n_y` with the cone cosines `n`.
    // tick bar: on a lidar correction's corner path, inlined with its two
    // helpers below (`bar::tick_without_io_4_hypotheses`, lx106/BENCHMARKS.md)
    #[inline(always)]
    pub fn near_corner(&self, margin: Length) -> bool {
        self.corner_apart().is_some_and(|(apart, cs)| within(apart, cs, margin))
    }

    /// The two candidate walls' distance apart times `cs`, Q14 mm (below
    /// 2^29), and `cs`, their cone cosines' product `n_a n_b` in Q30; `None`
    /// when the cone meets one wall.
    // tick bar (see `near_corner`)
    #[inline(always)]
    fn corner_apart(&self) -> Option<(i32, i32)> {
        let Corner::Cross { cross, other_cross, other_normal } = self.corner else {
            return None;
        };
        // The products were made choosing the wall: in Q14 mm by mul_hi
        // (Q16 * Q30 / 2^32), each within 3 LSB (2^-12 mm) below the exact
        // one; A >= 0 and 0 <= n <= 2^30 keep each in [0, 2^29), their
        // difference in i32.
        // n n in Q28 (<= 2^28), << 2 -> Q30.
        let cs = mul_cos(other_normal, self.cone_normal) << 2;
        Some(((cross - other_cross).abs(), cs))
    }
}

/// The walls `apart` (times `cs`, Q14 mm; [`Beam::corner_apart`]) are
/// less than `margin` (at most [`CORNER_MARGIN_MAX`]) apart: the margin
/// (Q16) times `cs` (Q30) is Q14.
// tick bar (see `Beam::near_corner`)
#[inline(always)]
fn within(apart: i32, cs: i32, margin: Length) -> bool {
    apart < mul_hi(margin.0.clamp(0, CORNER_MARGIN_MAX.0), cs)
}
