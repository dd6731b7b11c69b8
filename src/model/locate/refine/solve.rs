//! One Levenberg-Marquardt step in fixed point: the rows' normal equations
//! weighed by the bounded loss (iteratively reweighted), scaled to a unit
//! diagonal, damped, and solved by Cholesky. 64-bit integers only (the
//! lx106's divisions are the ROM's `__divdi3`, `math::div_i64`).

use super::rows::{Loss, Model, Params, Row, MAX_PARAMS, ROBUST, UNITS};
use crate::math::{div_i64, isqrt64};

/// Q24: the normal matrix's scale (a product of two Q12 derivatives) and
/// the scaled system's.
const ONE: i64 = 1 << 24;
/// The damping's exponent: `lambda = 2^damping`, between these.
pub const DAMPING_MIN: i8 = -20;
pub const DAMPING_MAX: i8 = 6;

/// `ROBUST^2`, Q24.
const C2: i64 = ROBUST * ROBUST;

/// A row's cost (Q24): the bounded loss `c^2 r^2 / (c^2 + r^2)`
/// (Geman-McClure) for a reading, the square for a prior.
pub fn cost(row: &Row) -> i64 {
    let r2 = row.r.saturating_mul(row.r);
    match row.loss {
        Loss::Robust => C2.saturating_sub(div_i64(C2.saturating_mul(C2), C2.saturating_add(r2)).unwrap_or(0)),
        Loss::Square(extra) => r2.saturating_add(extra),
    }
}

/// A row's weight in the normal equations (Q16): the bounded loss's
/// `(c^2 / (c^2 + r^2))^2`, 1 for a prior.
fn weight(row: &Row) -> i64 {
    match row.loss {
        Loss::Robust => {
            let q = div_i64(C2 << 16, C2.saturating_add(row.r.saturating_mul(row.r))).unwrap_or(0);
            q.saturating_mul(q) >> 16
        }
        Loss::Square(_) => 1 << 16,
    }
}

/// The model's cost at `p` (Q24) and its readings (the bounded rows).
pub fn total(model: &Model, p: &Params) -> (i64, u32) {
    let (mut sum, mut readings) = (0i64, 0u32);
    model.rows(p, false, |row| {
        sum = sum.saturating_add(cost(row));
        readings = readings.saturating_add(u32::from(row.loss == Loss::Robust));
    });
    (sum, readings)
}

/// The reweighted normal equations `A`, `g` (Q24) at `p`.
pub struct Normal {
    a: [[i64; MAX_PARAMS]; MAX_PARAMS],
    g: [i64; MAX_PARAMS],
    n: usize,
}

impl Normal {
    pub fn at(model: &Model, p: &Params) -> Normal {
        let mut ne = Normal { a: [[0; MAX_PARAMS]; MAX_PARAMS], g: [0; MAX_PARAMS], n: model.params() };
        model.rows(p, true, |row| {
            let w = weight(row);
            for &(k, jk) in row.cols() {
                let wj = jk.saturating_mul(w) >> 16;
                if let Some(g) = ne.g.get_mut(k) {
                    *g = g.saturating_add(wj.saturating_mul(row.r));
                }
                let Some(a) = ne.a.get_mut(k) else { continue };
                for &(l, jl) in row.cols() {
                    if let Some(a) = a.get_mut(l) {
                        *a = a.saturating_add(wj.saturating_mul(jl));
                    }
                }
            }
        });
        ne
    }

    /// The step `p + delta` for the damping `2^damping`: `(A + lambda
    /// diag A) delta = -g`, scaled to a unit diagonal (a parameter no row
    /// moves stays put). `None` when the system cannot be solved.
    pub fn step(&self, p: &Params, damping: i8) -> Option<Params> {
        let n = self.n.min(MAX_PARAMS);
        // the diagonal's roots, Q12
        let mut root = [0i64; MAX_PARAMS];
        for (k, s) in root.iter_mut().enumerate().take(n) {
            *s = i64::from(isqrt64((*self.a.get(k)?.get(k)?).max(0) as u64));
        }
        let scaled = |v: i64, k: usize| match root.get(k) {
            Some(&s) if s > 0 => div_i64(v.saturating_mul(1 << 12), s),
            _ => Some(0),
        };
        let mut m = [[0i64; MAX_PARAMS]; MAX_PARAMS];
        let mut b = [0i64; MAX_PARAMS];
        for k in 0..n {
            for l in 0..n {
                let v = scaled(scaled(*self.a.get(k)?.get(l)?, k)?, l)?;
                *m.get_mut(k)?.get_mut(l)? = v;
            }
            let lambda = if damping >= 0 { ONE << damping.unsigned_abs() } else { ONE >> damping.unsigned_abs() };
            let diag = m.get_mut(k)?.get_mut(k)?;
            // an unused parameter's row: 1 on the diagonal, nothing else
            *diag = if root.get(k)? > &0 { diag.saturating_add(lambda) } else { ONE };
            // the scaled right-hand side, Q12 (Q24 over the root's Q12)
            let g = self.g.get(k)?.saturating_neg();
            *b.get_mut(k)? = if root.get(k)? > &0 { div_i64(g, *root.get(k)?)? } else { 0 };
        }
        let y = cholesky_solve(&mut m, &mut b, n)?;
        let mut q = *p;
        for k in 0..n {
            let s = *root.get(k)?;
            if s > 0 {
                // delta in units, Q16, then in the parameter's LSB
                let delta = div_i64(y.get(k)?.saturating_mul(1 << 16), s)?;
                let lsb = delta.saturating_mul(*UNITS.get(k)?) >> 16;
                *q.get_mut(k)? = q.get(k)?.saturating_add(lsb);
            }
        }
        Some(q)
    }
}

/// Solves `m y = b` for a symmetric positive definite `m` (Q24, its
/// first `n` rows and columns) in place: `m` becomes its Cholesky factor
/// `L` (lower), `b` the solution (in `b`'s scale). `None` when a pivot is
/// not positive.
pub(super) fn cholesky_solve(
    m: &mut [[i64; MAX_PARAMS]; MAX_PARAMS],
    b: &mut [i64; MAX_PARAMS],
    n: usize,
) -> Option<[i64; MAX_PARAMS]> {
    for j in 0..n {
        let mut d = *m.get(j)?.get(j)?;
        for k in 0..j {
            let l = *m.get(j)?.get(k)?;
            d = d.saturating_sub(l.saturating_mul(l) >> 24);
        }
        if d <= 0 {
            return None;
        }
        let ljj = i64::from(isqrt64((d as u64) << 24));
        *m.get_mut(j)?.get_mut(j)? = ljj;
        for i in j.saturating_add(1)..n {
            let mut v = *m.get(i)?.get(j)?;
            for k in 0..j {
                v = v.saturating_sub(m.get(i)?.get(k)?.saturating_mul(*m.get(j)?.get(k)?) >> 24);
            }
            *m.get_mut(i)?.get_mut(j)? = div_i64(v.saturating_mul(ONE), ljj)?;
        }
    }
    // L z = b, then L^T y = z
    for i in 0..n {
        let mut v = *b.get(i)?;
        for k in 0..i {
            v = v.saturating_sub(m.get(i)?.get(k)?.saturating_mul(*b.get(k)?) >> 24);
        }
        *b.get_mut(i)? = div_i64(v.saturating_mul(ONE), *m.get(i)?.get(i)?)?;
    }
    for i in (0..n).rev() {
        let mut v = *b.get(i)?;
        for k in i.saturating_add(1)..n {
            v = v.saturating_sub(m.get(k)?.get(i)?.saturating_mul(*b.get(k)?) >> 24);
        }
        *b.get_mut(i)? = div_i64(v.saturating_mul(ONE), *m.get(i)?.get(i)?)?;
    }
    Some(*b)
}
