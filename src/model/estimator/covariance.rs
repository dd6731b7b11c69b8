//! The covariance's upkeep: its growth in a prediction (`F P F^T + Q`), a
//! correction's removal term, and the conditioning that keeps it valid
//! after every step (see the module docs of [`super`], "Numerical safety").

use super::constants::{P_MAX, P_MIN};
use super::Estimator;
use crate::math::{isqrt64, mul_hi, mul_q30_unsat, mul_u31, shift};

/// The error covariance, symmetric, over `(dx, dy, L dtheta)` with
/// `L` = [`super::HEADING_LEVER_MM`]: every entry in Q14 mm^2 (2^-14 mm^2).
/// Invariants after every step: `MIN <= P_ii <= MAX` and
/// `P_ij^2 <= P_ii P_jj`, so every entry is at most 2^30 in magnitude.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug, Default)]
pub struct Covariance {
    pub xx: i32,
    pub xy: i32,
    pub xt: i32,
    pub yy: i32,
    pub yt: i32,
    pub tt: i32,
}

impl Estimator {
    /// Keeps the covariance valid (see the module docs).
    pub(super) fn condition(&mut self) {
        let p = &mut self.p;
        // Cap: scale row and column i by 1/2 (D P D, still PSD).
        if p.xx > P_MAX {
            p.xx >>= 2;
            p.xy >>= 1;
            p.xt >>= 1;
        }
        if p.yy > P_MAX {
            p.yy >>= 2;
            p.xy >>= 1;
            p.yt >>= 1;
        }
        if p.tt > P_MAX {
            p.tt >>= 2;
            p.xt >>= 1;
            p.yt >>= 1;
        }
        // Floor: adding to the diagonal keeps P PSD.
        p.xx = p.xx.max(P_MIN);
        p.yy = p.yy.max(P_MIN);
        p.tt = p.tt.max(P_MIN);
        // (tick bar: three calls, not a loop over an array; at opt-level "z" the
        // array's iterator is a call per element)
        let repairs = bound_correlation(&mut p.xy, p.xx, p.yy)
            + bound_correlation(&mut p.xt, p.xx, p.tt)
            + bound_correlation(&mut p.yt, p.yy, p.tt);
        self.stats.repairs = self.stats.repairs.saturating_add(repairs);
    }
}

/// Keeps `|P_ij| <= sqrt(P_ii P_jj)` (`0 < P_ii, P_jj <= 2^30`, capped and
/// floored by [`Estimator::condition`]); 1 if it had to change `P_ij`.
// tick bar: the quick test inline, the rare exact one out of line
#[inline(always)]
fn bound_correlation(pij: &mut i32, pii: i32, pjj: i32) -> u32 {
    // |P_ij| <= min(P_ii, P_jj) implies P_ij^2 <= P_ii P_jj; so does the
    // same in 32 bits on the top bits, |P_ij| rounded up and the diagonal
    // down: a < (a / 2^15 + 1) 2^15. a <= 2^30 keeps that square below 2^31,
    // the diagonal's product is below 2^32. The exact test (two 64-bit
    // products) only past both: a correlation within about 2^-14 of 1.
    let a = pij.unsigned_abs();
    let (ii, jj) = (pii.unsigned_abs(), pjj.unsigned_abs());
    if a <= ii.min(jj) {
        return 0;
    }
    let up = (a >> 15) + 1;
    if a <= 1 << 30 && up.wrapping_mul(up) <= (ii >> 15).wrapping_mul(jj >> 15) {
        return 0;
    }
    bound_correlation_exact(pij, pii, pjj)
}

/// [`bound_correlation`] past its quick test, out of line (a correlation
/// above `min(P_ii, P_jj) / sqrt(P_ii P_jj)`: rare in steady state).
// tick bar: see `bound_correlation`
#[inline(never)]
fn bound_correlation_exact(pij: &mut i32, pii: i32, pjj: i32) -> u32 {
    let a = pij.unsigned_abs();
    // Past max(P_ii, P_jj) it is a violation without a product, so the
    // exact test sees |P_ij| <= 2^30 too.
    let bound = mul_u31(pii.unsigned_abs(), pjj.unsigned_abs());
    if a > pii.max(pjj).unsigned_abs() || mul_u31(a, a) > bound {
        // The smallest change that restores |P_ij| <= sqrt(P_ii P_jj): only
        // rounding at a correlation of 1 gets here.
        let m = isqrt64(bound).min(i32::MAX as u32) as i32;
        *pij = if *pij < 0 { -m } else { m };
        return 1;
    }
    0
}

/// One covariance entry's part of a correction, `P_ij -= mul_hi(t_i,
/// beta_j) 2^e` (saturating, [`shift`]; see [`Estimator::correct`]).
pub(super) fn remove(pij: &mut i32, ti: i32, bj: i32, e: i32) {
    *pij = pij.saturating_sub(shift(mul_hi(ti, bj), e));
}

/// Adds `v g g^T` to the position block of `P` (`g = (g1, g2)` in Q30,
/// `|g| <= 1`, `v` small: see [`Estimator::predict`]) and returns
/// `(v g1, v g2)`, the heading column's share of a turn's noise. Both
/// motions' noise has this shape (a straight step's `g` is the heading's
/// `(cos, sin)`).
pub(super) fn add_noise(p: &mut Covariance, v: i32, g1: i32, g2: i32) -> (i32, i32) {
    let (v1, v2) = (mul_q30_unsat(v, g1), mul_q30_unsat(v, g2));
    p.xx = p.xx.saturating_add(mul_q30_unsat(v1, g1));
    p.xy = p.xy.saturating_add(mul_q30_unsat(v1, g2));
    p.yy = p.yy.saturating_add(mul_q30_unsat(v2, g2));
    (v1, v2)
}

/// `F P F^T` for `F = I + f1 e_x e_t^T + f2 e_y e_t^T` (f in Q30, |f| < 2^29,
/// i.e. below 1/2). With `|P_ij| <= 2^30` (conditioned): `u` below 1.5 2^30
/// fits i32; the other sums can pass 2^31 only for a P near its cap, and
/// saturate.
pub(super) fn propagate(p: &mut Covariance, f1: i32, f2: i32) {
    // new P_xt = P_xt + f1 P_tt, new P_yt = P_yt + f2 P_tt
    let u1 = p.xt + mul_q30_unsat(p.tt, f1);
    let u2 = p.yt + mul_q30_unsat(p.tt, f2);
    // P_xx + 2 f1 P_xt + f1^2 P_tt = P_xx + f1 (P_xt + u1)
    p.xx = p.xx.saturating_add(mul_q30_unsat(p.xt, f1)).saturating_add(mul_q30_unsat(u1, f1));
    p.yy = p.yy.saturating_add(mul_q30_unsat(p.yt, f2)).saturating_add(mul_q30_unsat(u2, f2));
    // P_xy + f1 P_yt + f2 P_xt + f1 f2 P_tt = P_xy + f1 P_yt + f2 u1
    p.xy = p.xy.saturating_add(mul_q30_unsat(p.yt, f1)).saturating_add(mul_q30_unsat(u1, f2));
    p.xt = u1;
    p.yt = u2;
}
