//! The lidar's cone on the box's walls (see [`super`]'s module docs): the
//! cone's incidence on a wall, which of two candidate walls is nearer in
//! the cone, and whether a corner's other wall comes within a margin, all
//! division-free. [`super::Beam`] puts them together.

use crate::config;
use crate::math::{mul_hi, mul_q30_unsat, Length};

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

/// The largest margin [`super::Beam::near_corner`] tells apart (larger
/// margins are taken as this one; `config::estimator::CORNER_MARGIN_MAX`).
pub const CORNER_MARGIN_MAX: Length = config::estimator::CORNER_MARGIN_MAX;

/// The cone's other candidate wall, for [`super::Beam::near_corner`].
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
