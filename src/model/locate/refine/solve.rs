//! One Levenberg-Marquardt step in fixed point: the rows' normal equations
//! weighed by the bounded loss (iteratively reweighted), summed a slice of
//! rows at a time ([`Sums`]), scaled by powers of two to a diagonal near
//! one, damped, and solved by Cholesky on the lower triangle, packed (the
//! robot's stack runs through here: `cargo fw-image`).
//!
//! Products are `mul_wide`'s (i32 x i32, exact, 25 lx106 instructions)
//! with every factor held within `i32` by its scale; each column divides
//! once (its pivot's reciprocal). A step costs about one pass's slice.

use super::rows::{unit, Loss, Params, Row, MAX_PARAMS, ROBUST};
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

/// A symmetric matrix's entries, its lower triangle packed by rows
/// ([`lower`]).
pub(super) const TRIANGLE: usize = MAX_PARAMS * (MAX_PARAMS + 1) / 2;

/// The reweighted normal equations' sums, `A` (its lower triangle) and `g`,
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
                    if let Some(a) = self.a.get_mut(lower(l, k)) {
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
        self.a.get(lower(l, k)).map_or(0, |&v| i64::from(v) << 4)
    }

    /// The step `p + delta` for the damping `2^damping`, into `q`: `(A +
    /// lambda diag A) delta = -g` for the first `n` parameters (a parameter
    /// no row moves stays put). False when the system cannot be solved.
    pub fn step(&self, p: &Params, n: usize, damping: i8, q: &mut Params) -> bool {
        self.solve(p, n.min(MAX_PARAMS), damping, q).is_some()
    }

    fn solve(&self, p: &Params, n: usize, damping: i8, q: &mut Params) -> Option<()> {
        // each parameter scaled by 2^-shift so its diagonal is 1 to 4
        // (Q24); a parameter no row moves is marked `UNUSED`
        let mut shifts = [UNUSED; MAX_PARAMS];
        for k in 0..n {
            let d = self.at(k, k);
            if d > 0 {
                let bits = 63i32.saturating_sub(d.leading_zeros() as i32);
                // within -12..20: the diagonal is a positive i64
                *shifts.get_mut(k)? = (bits.saturating_sub(24) >> 1) as i8;
            }
        }
        // (an unused parameter's scale: none, its entries are all zero)
        let shift = |k: usize| shifts.get(k).filter(|&&s| s != UNUSED).map_or(0, |&s| i32::from(s));
        let scale = |v: i64, s: i32| if s >= 0 { v >> s.min(63) } else { v << s.saturating_neg().min(24) };
        let lambda = |d: i64| if damping >= 0 { d << damping.unsigned_abs() } else { d >> damping.unsigned_abs() };
        // the lower triangle, packed by rows (`lower`): the stack's worst
        // case runs through here (`cargo fw-image`)
        let mut m = [0i32; TRIANGLE];
        let mut b = [0i32; MAX_PARAMS];
        for k in 0..n {
            let used = shifts.get(k) != Some(&UNUSED);
            let sk = shift(k);
            for l in 0..=k {
                let v = if used { scale(self.at(k, l), sk.saturating_add(shift(l))) } else { 0 };
                *m.get_mut(lower(k, l))? = v.clamp(-ONE * 4, ONE * 4) as i32;
            }
            let diag = m.get_mut(lower(k, k))?;
            // an unused parameter's row: 1 on the diagonal, nothing else
            *diag = if used { i64::from(*diag).saturating_add(lambda(i64::from(*diag))) as i32 } else { ONE as i32 };
            // the right-hand side in Q12
            let g = scale(i64::from(*self.g.get(k)?) << 4, sk).saturating_neg() >> 12;
            *b.get_mut(k)? = if used { g.clamp(-(1 << 30), 1 << 30) as i32 } else { 0 };
        }
        cholesky_solve(&mut m, &mut b, n)?;
        *q = *p;
        for k in 0..n {
            if shifts.get(k) != Some(&UNUSED) {
                // delta in units, Q16 (y is Q12, scaled back by 2^-shift)
                let delta = scale(i64::from(*b.get(k)?) << 4, shift(k));
                let lsb = mul_wide(delta.clamp(-(1 << 30), 1 << 30) as i32, unit(k) as i32) >> 16;
                // (an angle wraps; a place or a rate stays far from the bounds)
                *q.get_mut(k)? = q.get(k)?.wrapping_add(lsb.clamp(i64::from(i32::MIN), i64::from(i32::MAX)) as i32);
            }
        }
        Some(())
    }
}

/// A parameter no row moves (its shift).
const UNUSED: i8 = i8::MIN;

/// Where `(k, l)`, `l <= k`, sits in a lower triangle packed by rows.
pub(super) const fn lower(k: usize, l: usize) -> usize {
    k * (k + 1) / 2 + l
}

/// Solves `m y = b` for a symmetric positive definite `m` (Q24, its lower
/// triangle packed by rows ([`lower`]), first `n` rows, entries within 4)
/// in place: `m` becomes its Cholesky factor `L`, `b` the solution (in
/// `b`'s scale; `L`'s diagonal holds each pivot's reciprocal, `2^40 /
/// L_jj`, L_jj in Q24: 2^12 to 2^27, the damping keeps it near 2^24).
/// `None` when a pivot is not positive.
pub(super) fn cholesky_solve(m: &mut [i32; TRIANGLE], b: &mut [i32; MAX_PARAMS], n: usize) -> Option<()> {
    let product = |a: i32, c: i32| mul_wide(a, c) >> 24;
    let fit = |v: i64| v.clamp(i64::from(i32::MIN), i64::from(i32::MAX)) as i32;
    let over = |v: i64, inv: i32| fit(mul_wide(fit(v), inv) >> 16);
    for j in 0..n {
        let mut d = i64::from(*m.get(lower(j, j))?);
        for k in 0..j {
            let l = *m.get(lower(j, k))?;
            d = d.saturating_sub(product(l, l));
        }
        if d <= 0 {
            return None;
        }
        let ljj = isqrt64((d as u64) << 24).max(1 << 12) as i32;
        let inv = fit(div_i64(1 << 40, i64::from(ljj))?);
        *m.get_mut(lower(j, j))? = inv;
        for i in j.saturating_add(1)..n {
            let mut v = i64::from(*m.get(lower(i, j))?);
            for k in 0..j {
                v = v.saturating_sub(product(*m.get(lower(i, k))?, *m.get(lower(j, k))?));
            }
            *m.get_mut(lower(i, j))? = over(v, inv);
        }
    }
    // L z = b, then L^T y = z
    for i in 0..n {
        let mut v = i64::from(*b.get(i)?);
        for k in 0..i {
            v = v.saturating_sub(product(*m.get(lower(i, k))?, *b.get(k)?));
        }
        *b.get_mut(i)? = over(v, *m.get(lower(i, i))?);
    }
    for i in (0..n).rev() {
        let mut v = i64::from(*b.get(i)?);
        for k in i.saturating_add(1)..n {
            v = v.saturating_sub(product(*m.get(lower(k, i))?, *b.get(k)?));
        }
        *b.get_mut(i)? = over(v, *m.get(lower(i, i))?);
    }
    Some(())
}
