//! One Levenberg-Marquardt step in fixed point: the rows' normal equations
//! weighed by the bounded loss (iteratively reweighted), summed a slice of
//! rows at a time ([`Sums`]), scaled by powers of two to a diagonal near
//! one, damped, and solved by Cholesky.
//!
//! Products are `mul_wide`'s (i32 x i32, exact, 25 lx106 instructions)
//! with every factor held within `i32` by its scale; each column divides
//! once (its pivot's reciprocal). A step costs about one pass's slice.

use super::rows::{unit, Loss, Row, MAX_PARAMS, ROBUST};
use crate::math::{div_i64, isqrt64, mul_wide, quotient};

/// Q24: the scaled system's one.
const ONE: i64 = 1 << 24;
/// The damping's exponent: `lambda = 2^damping`, between these (16 keeps
/// the damped diagonal, at most 4 (1 + 16) in Q24, within `i32`).
pub const DAMPING_MIN: i8 = -20;
pub const DAMPING_MAX: i8 = 4;

/// `ROBUST^2`, Q24 (within `i32`: 9 sigmas squared).
const C2: i32 = (ROBUST * ROBUST) as i32;

/// `c^2 / (c^2 + r^2)` for a reading's row, Q16 (1 for a prior's).
fn bound(row: &Row) -> i64 {
    match row.loss {
        Loss::Robust => {
            let den = i64::from(C2).saturating_add(mul_wide(row.r, row.r)).max(1) as u64;
            quotient(C2 as u32, den, 16).min(1 << 16) as i64
        }
        Loss::Square(_) => 1 << 16,
    }
}

/// A row's cost (Q24): the bounded loss `c^2 r^2 / (c^2 + r^2)`
/// (Geman-McClure) for a reading, the square for a prior.
pub fn cost(row: &Row) -> i64 {
    match row.loss {
        Loss::Robust => i64::from(C2).saturating_sub(mul_wide(C2, bound(row) as i32) >> 16),
        Loss::Square(extra) => mul_wide(row.r, row.r).saturating_add(extra),
    }
}

/// The upper triangle's entries.
const TRIANGLE: usize = MAX_PARAMS * (MAX_PARAMS + 1) / 2;

/// Where row `k`'s entries start in the triangle (`k <= l` at `k`'s + `l - k`).
const fn entry(k: usize, l: usize) -> usize {
    k * (2 * MAX_PARAMS - k + 1) / 2 + (l - k)
}

/// The reweighted normal equations' sums, `A` (its upper triangle) and `g`,
/// Q20 (a product of two Q12 derivatives over 16: a reading's derivative
/// is at most a few sigmas a unit, so the sums of a few hundred rows stay
/// within `i32`).
#[derive(Clone, Copy, Debug)]
pub struct Sums {
    a: [i32; TRIANGLE],
    g: [i32; MAX_PARAMS],
}

impl Sums {
    pub const ZERO: Sums = Sums { a: [0; TRIANGLE], g: [0; MAX_PARAMS] };

    /// Adds a row, weighed by its loss (`w = (c^2 / (c^2 + r^2))^2`).
    pub fn add(&mut self, row: &Row) {
        let b = bound(row) as i32;
        let w = (mul_wide(b, b) >> 16) as i32;
        for &(k, jk) in row.cols() {
            let (k, wj) = (usize::from(k), (mul_wide(jk, w) >> 16) as i32);
            if let Some(g) = self.g.get_mut(k) {
                *g =
                    g.saturating_add((mul_wide(wj, row.r) >> 4).clamp(i64::from(i32::MIN), i64::from(i32::MAX)) as i32);
            }
            for &(l, jl) in row.cols() {
                let l = usize::from(l);
                if k <= l && l < MAX_PARAMS {
                    if let Some(a) = self.a.get_mut(entry(k, l)) {
                        *a = a.saturating_add((mul_wide(wj, jl) >> 4) as i32);
                    }
                }
            }
        }
    }

    fn at(&self, k: usize, l: usize) -> i64 {
        let (k, l) = (k.min(l), k.max(l));
        if l >= MAX_PARAMS {
            return 0;
        }
        self.a.get(entry(k, l)).map_or(0, |&v| i64::from(v) << 4)
    }

    /// The step `p + delta` for the damping `2^damping`: `(A + lambda
    /// diag A) delta = -g` for the first `n` parameters (a parameter no row
    /// moves stays put). `None` when the system cannot be solved.
    pub fn step(&self, p: &[i64; MAX_PARAMS], n: usize, damping: i8) -> Option<[i64; MAX_PARAMS]> {
        let n = n.min(MAX_PARAMS);
        // each parameter scaled by 2^-shift so its diagonal is 1 to 4 (Q24)
        let mut shift = [0i32; MAX_PARAMS];
        let mut used = [false; MAX_PARAMS];
        for k in 0..n {
            let d = self.at(k, k);
            if d > 0 {
                let bits = 63i32.saturating_sub(d.leading_zeros() as i32);
                *shift.get_mut(k)? = bits.saturating_sub(24) >> 1;
                *used.get_mut(k)? = true;
            }
        }
        let scale = |v: i64, s: i32| if s >= 0 { v >> s.min(63) } else { v << s.saturating_neg().min(24) };
        let lambda = |d: i64| if damping >= 0 { d << damping.unsigned_abs() } else { d >> damping.unsigned_abs() };
        let mut m = [[0i32; MAX_PARAMS]; MAX_PARAMS];
        let mut b = [0i32; MAX_PARAMS];
        for k in 0..n {
            let sk = *shift.get(k)?;
            for l in 0..=k {
                let v = scale(self.at(k, l), sk.saturating_add(*shift.get(l)?));
                *m.get_mut(k)?.get_mut(l)? = v.clamp(-ONE * 4, ONE * 4) as i32;
            }
            let diag = m.get_mut(k)?.get_mut(k)?;
            // an unused parameter's row: 1 on the diagonal, nothing else
            *diag = if *used.get(k)? {
                i64::from(*diag).saturating_add(lambda(i64::from(*diag))) as i32
            } else {
                ONE as i32
            };
            // the right-hand side in Q12
            let g = scale(i64::from(*self.g.get(k)?) << 4, sk).saturating_neg() >> 12;
            *b.get_mut(k)? = if *used.get(k)? { g.clamp(-(1 << 30), 1 << 30) as i32 } else { 0 };
        }
        let y = cholesky_solve(&mut m, &mut b, n)?;
        let mut q = *p;
        for k in 0..n {
            if *used.get(k)? {
                // delta in units, Q16 (y is Q12, scaled back by 2^-shift)
                let delta = scale(i64::from(*y.get(k)?) << 4, *shift.get(k)?);
                let lsb = mul_wide(delta.clamp(-(1 << 30), 1 << 30) as i32, unit(k) as i32) >> 16;
                *q.get_mut(k)? = q.get(k)?.saturating_add(lsb);
            }
        }
        Some(q)
    }
}

/// Solves `m y = b` for a symmetric positive definite `m` (Q24, its lower
/// triangle, first `n` rows, entries within 4) in place: `m` becomes its
/// Cholesky factor `L`, `b` the solution (in `b`'s scale). `None` when a
/// pivot is not positive.
pub(super) fn cholesky_solve(
    m: &mut [[i32; MAX_PARAMS]; MAX_PARAMS],
    b: &mut [i32; MAX_PARAMS],
    n: usize,
) -> Option<[i32; MAX_PARAMS]> {
    // each pivot's reciprocal, 2^40 / L_jj (L_jj in Q24: 2^12 to 2^27,
    // the damping keeps it near 2^24)
    let mut inv = [0i32; MAX_PARAMS];
    let product = |a: i32, c: i32| mul_wide(a, c) >> 24;
    let fit = |v: i64| v.clamp(i64::from(i32::MIN), i64::from(i32::MAX)) as i32;
    let over = |v: i64, inv: i32| fit(mul_wide(fit(v), inv) >> 16);
    for j in 0..n {
        let mut d = i64::from(*m.get(j)?.get(j)?);
        for k in 0..j {
            let l = *m.get(j)?.get(k)?;
            d = d.saturating_sub(product(l, l));
        }
        if d <= 0 {
            return None;
        }
        let ljj = isqrt64((d as u64) << 24).max(1 << 12) as i32;
        *m.get_mut(j)?.get_mut(j)? = ljj;
        *inv.get_mut(j)? = fit(div_i64(1 << 40, i64::from(ljj))?);
        for i in j.saturating_add(1)..n {
            let mut v = i64::from(*m.get(i)?.get(j)?);
            for k in 0..j {
                v = v.saturating_sub(product(*m.get(i)?.get(k)?, *m.get(j)?.get(k)?));
            }
            *m.get_mut(i)?.get_mut(j)? = over(v, *inv.get(j)?);
        }
    }
    // L z = b, then L^T y = z
    for i in 0..n {
        let mut v = i64::from(*b.get(i)?);
        for k in 0..i {
            v = v.saturating_sub(product(*m.get(i)?.get(k)?, *b.get(k)?));
        }
        *b.get_mut(i)? = over(v, *inv.get(i)?);
    }
    for i in (0..n).rev() {
        let mut v = i64::from(*b.get(i)?);
        for k in i.saturating_add(1)..n {
            v = v.saturating_sub(product(*m.get(k)?.get(i)?, *b.get(k)?));
        }
        *b.get_mut(i)? = over(v, *inv.get(i)?);
    }
    Some(*b)
}
