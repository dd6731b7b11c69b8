//! The covariance of one hypothesis and its upkeep: the prediction's
//! `F P F^T + Q` as a few shears, a correction's removal term, and the
//! conditioning that keeps it valid after every step (see the module docs
//! of [`super`], "Numerical safety").

use super::constants::{P_MAX, P_MIN};
use crate::math::{isqrt64, mul_hi, mul_q30, mul_u31, shift};

/// The filter's states, in the covariance's order. Every state's error is
/// carried in mm (see [`Covariance`]): the heading, the scales and the
/// compass bias through the lever [`super::HEADING_LEVER_MM`].
pub const N: usize = 7;
/// North position, mm.
pub const X: usize = 0;
/// East position, mm.
pub const Y: usize = 1;
/// Heading, `L dtheta`.
pub const T: usize = 2;
/// Straight speed scale, `L dscale`.
pub const SPEED: usize = 3;
/// Clockwise turn-rate scale, `L dscale`.
pub const CW: usize = 4;
/// Counter-clockwise turn-rate scale, `L dscale`.
pub const CCW: usize = 5;
/// The compass's bias, `L dbias`.
pub const BIAS: usize = 6;

/// Entries of the upper triangle.
const LEN: usize = N * (N + 1) / 2;

/// Where `P_ij` (`= P_ji`) is kept: row `a = min(i, j)` starts at
/// `a (2N - a - 1) / 2`, then column `b = max(i, j)`. Below [`LEN`] for
/// `i, j < N`; a larger index reads 0 and writes nothing.
const fn index(i: usize, j: usize) -> usize {
    let (a, b) = if i <= j { (i, j) } else { (j, i) };
    a * (2 * N - a - 1) / 2 + b
}

/// The error covariance of one hypothesis, symmetric by storage (the upper
/// triangle), every entry in Q12 mm^2 (2^-12 mm^2) over the states' errors
/// in mm (see [`N`]). Invariants after every step: `P_MIN <= P_ii <= P_MAX
/// (2^28)` and `P_ij^2 <= P_ii P_jj`, so every entry is at most 2^28 in
/// magnitude: a shear by a factor below 1/2 and the noise a step adds
/// stay far inside i32 before the next conditioning.
///
/// Why Q12 (issue 29): in Q14 the compass's variance had to stay below
/// 2^22 (3.6 degrees one sigma) and a turn's pivot noise below 2^30 (18 mm);
/// in Q12 with `P_MAX` at 2^28 a measurement noise up to `P_MAX` (57
/// degrees, 256 mm) fits a correction's 32-bit `S`, and the pivot's noise
/// is its own term (`constants::K_PIVOT`, 45 mm asserted to fit). The
/// floor, 0.1 mm, is still 41 LSB.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug, Default)]
pub struct Covariance {
    upper: [i32; LEN],
}

impl Covariance {
    /// A diagonal covariance (each entry Q12 mm^2).
    pub fn diagonal_of(d: [i32; N]) -> Covariance {
        let mut p = Covariance::default();
        for (i, v) in d.into_iter().enumerate() {
            p.set(i, i, v);
        }
        p
    }

    /// `P_ij` (Q12 mm^2); 0 for an index past [`N`].
    // tick bar: inlined, as its five kin (lx106/BENCHMARKS.md, "Control
    // tick")
    #[inline(always)]
    pub fn get(&self, i: usize, j: usize) -> i32 {
        self.upper.get(index(i, j)).copied().unwrap_or(0)
    }

    // tick bar: inlined, as its five kin (lx106/BENCHMARKS.md, "Control
    // tick")
    #[inline(always)]
    pub(super) fn set(&mut self, i: usize, j: usize, v: i32) {
        if let Some(e) = self.upper.get_mut(index(i, j)) {
            *e = v;
        }
    }

    // tick bar: inlined, as its five kin (lx106/BENCHMARKS.md, "Control
    // tick")
    #[inline(always)]
    pub(super) fn add(&mut self, i: usize, j: usize, v: i32) {
        self.set(i, j, self.get(i, j).saturating_add(v));
    }

    /// Row `r` (`P_rk` for every `k`), walked by its packed indices.
    // tick bar: inlined (a returned array is a memset and a memcpy call)
    #[inline(always)]
    pub(super) fn row(&self, r: usize) -> [i32; N] {
        each(
            #[inline(always)]
            |k| self.get(r, k),
        )
    }

    /// The diagonal, Q12 mm^2.
    pub fn diagonal(&self) -> [i32; N] {
        // tick bar: a literal of constant indices (a filled array is a
        // memset call)
        let at = |i: usize| self.get(i, i);
        [at(X), at(Y), at(T), at(SPEED), at(CW), at(CCW), at(BIAS)]
    }

    /// Zeroes row and column `i` but the diagonal (the state is taken as
    /// independent of the others: still positive semi-definite).
    pub(super) fn decouple(&mut self, i: usize) {
        for k in 0..N {
            if k != i {
                self.set(i, k, 0);
            }
        }
    }

    /// `M P M^T` for `M = I + fa e_i e_a^T + fb e_i e_b^T` (`i` not `a`, `b`):
    /// the prediction's Jacobian is a product of such shears (state `i`
    /// moves by `fa` times state `a` and `fb` times state `b`), the factors
    /// in Q30 with `|f| <= 2^29` (clamped; the callers' are far below). New
    /// row `i`: `P_ik + fa P_ak + fb P_bk`; new `P_ii`: `P_ii + fa P_ia + fb
    /// P_ib + fa (new P_ia) + fb (new P_ib)`. Entries at most 2^28
    /// (conditioned) stay below 2^30.
    // tick bar: row `i`, `a` and `b` walked by their packed indices (no
    // index arithmetic per entry)
    pub(super) fn shear(&mut self, i: usize, (a, fa): (usize, i32), (b, fb): (usize, i32)) {
        let (fa, fb) = (fa.clamp(-(1 << 29), 1 << 29), fb.clamp(-(1 << 29), 1 << 29));
        let (pia, pib) = (self.get(i, a), self.get(i, b));
        let (mut ri, mut ra, mut rb) = (i, a, b); // index(0, i), index(0, a), index(0, b)
        for k in 0..N {
            if k != i {
                let pak = self.upper.get(ra).copied().unwrap_or(0);
                let pbk = self.upper.get(rb).copied().unwrap_or(0);
                if let Some(e) = self.upper.get_mut(ri) {
                    *e = e.saturating_add(mul_q30_fine(pak, fa));
                    // tick bar: a turn's heading shear has one factor (a
                    // product by 0 is 0)
                    if fb != 0 {
                        *e = e.saturating_add(mul_q30_fine(pbk, fb));
                    }
                }
            }
            ri += step(k, i);
            ra += step(k, a);
            rb += step(k, b);
        }
        let ii = mul_q30_fine(pia, fa)
            .saturating_add(mul_q30_fine(pib, fb))
            .saturating_add(mul_q30_fine(self.get(i, a), fa))
            .saturating_add(mul_q30_fine(self.get(i, b), fb));
        self.add(i, i, ii);
    }

    /// Adds `v g g^T` on the states `idx` (`g` in Q30, `|g_i| <= 1`, `v >= 0`
    /// below 2^30): a motion's noise along one direction.
    pub(super) fn add_outer<const M: usize>(&mut self, v: i32, idx: [usize; M], g: [i32; M]) {
        let mut a = 0;
        while a < M {
            let (i, gi) = (idx.get(a).copied().unwrap_or(N), g.get(a).copied().unwrap_or(0));
            let mut b = a;
            while b < M {
                let (j, gj) = (idx.get(b).copied().unwrap_or(N), g.get(b).copied().unwrap_or(0));
                self.add(i, j, mul_q30_fine(v, mul_q30(gi, gj)));
                b += 1;
            }
            a += 1;
        }
    }

    /// A correction's removal, `P_ij -= mul_hi(t_i, beta_j) 2^e` over the
    /// upper triangle in its packed order (saturating, [`shift`]; see
    /// `Filter::correct`); the diagonal's products from `|t|`, `|beta|`.
    // tick bar: the packed array walked in order
    pub(super) fn remove_outer(&mut self, t: &[i32; N], beta: &[i32; N], e: i32) {
        let (mut i, mut j) = (0usize, 0usize);
        for pij in self.upper.iter_mut() {
            let (ti, bj) = (t.get(i).copied().unwrap_or(0), beta.get(j).copied().unwrap_or(0));
            let d = if i == j { mul_hi(ti.abs(), bj.abs()) } else { mul_hi(ti, bj) };
            *pij = pij.saturating_sub(shift(d, e));
            j += 1;
            if j == N {
                i += 1;
                j = i;
            }
        }
    }

    /// The diagonal's upkeep (after a prediction: a congruence and noise
    /// keep the correlations valid): a variance past the cap scales its row
    /// and column by 1/2 (`D P D`, still PSD), one under the floor is raised.
    pub(super) fn condition_diagonal(&mut self) {
        let mut ii = 0; // index(i, i)
        for i in 0..N {
            let pii = self.upper.get(ii).copied().unwrap_or(P_MIN);
            if pii > P_MAX {
                self.halve(i);
            }
            if let Some(e) = self.upper.get_mut(ii) {
                *e = (*e).max(P_MIN);
            }
            ii += N - i;
        }
    }

    /// Row and column `i` by 1/2 (the diagonal by 1/4): rare, out of line.
    #[cold]
    #[inline(never)]
    pub(super) fn halve(&mut self, i: usize) {
        for k in 0..N {
            let v = self.get(i, k);
            self.set(i, k, if k == i { v >> 2 } else { v >> 1 });
        }
    }

    /// Keeps the covariance valid (see the module docs, after a correction):
    /// the diagonal's upkeep, then a correlation past 1 is clamped. Returns
    /// the number of clamps (repairs).
    pub(super) fn condition(&mut self) -> u32 {
        self.condition_diagonal();
        let d = self.diagonal();
        let mut repairs = 0u32;
        // tick bar: row by row, each row's P_ii at hand (the packed rows:
        // P_ii, then P_ij for j > i)
        let mut rest: &mut [i32] = &mut self.upper;
        for (i, &pii) in d.iter().enumerate() {
            let Some((_, tail)) = rest.split_first_mut() else { break };
            let Some((row, next)) = tail.split_at_mut_checked(N - 1 - i) else { break };
            for (pij, &pjj) in row.iter_mut().zip(d.iter().skip(i + 1)) {
                repairs += bound_correlation(pij, pii, pjj);
            }
            rest = next;
        }
        repairs
    }
}

/// An array of the states by its entries, `f(0)` to `f(N - 1)`.
// tick bar: a literal (`from_fn`, or a zeroed array filled in a loop, is a
// memset and a memcpy call on the lx106)
#[inline(always)]
pub(super) fn each(f: impl Fn(usize) -> i32) -> [i32; N] {
    [f(X), f(Y), f(T), f(SPEED), f(CW), f(CCW), f(BIAS)]
}
const _: () = assert!(N == 7 && X == 0 && Y == 1 && T == 2 && SPEED == 3 && CW == 4 && CCW == 5 && BIAS == 6);

/// How far the packed index of `P_k,r` moves from `k` to `k + 1` (row `r`
/// read down its column above the diagonal, then along its row).
// tick bar: inlined, as its five kin (lx106/BENCHMARKS.md, "Control
// tick")
#[inline(always)]
fn step(k: usize, r: usize) -> usize {
    if k < r {
        N - k - 1
    } else {
        1
    }
}

/// `a f` for `f` in Q30 (`|f| <= 1`), rounded to nearest for the small
/// entries of steady state: below 2^23 (2,048 mm^2) `a << 8` keeps 8 more
/// bits through [`mul_hi`] (its 3 LSB of error become 0.05); larger ones
/// by [`mul_q30`] (within 12 LSB, saturating). A floor of a few LSB per
/// product and tick made the small variances 3 % too small against the f64
/// reference (`tests/estimator/reference.rs`); the noise a tick adds is
/// tens of LSB.
// tick bar: inlined, as its five kin (lx106/BENCHMARKS.md, "Control
// tick")
#[inline(always)]
pub(super) fn mul_q30_fine(a: i32, f: i32) -> i32 {
    if a.unsigned_abs() < 1 << 23 {
        (mul_hi(a << 8, f) + 32) >> 6
    } else {
        mul_q30(a, f)
    }
}

/// Keeps `|P_ij| <= sqrt(P_ii P_jj)` (`0 < P_ii, P_jj <= 2^30`, capped and
/// floored by [`Covariance::condition`]); 1 if it had to change `P_ij`.
// tick bar: the quick test inline, the rare exact one out of line
#[inline(always)]
pub(super) fn bound_correlation(pij: &mut i32, pii: i32, pjj: i32) -> u32 {
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

#[cfg(test)]
#[allow(clippy::restriction)] // test code: a panic fails the test
mod tests {
    use super::*;

    #[test]
    fn the_upper_triangle_is_packed_without_gaps() {
        let mut seen = [false; LEN];
        for i in 0..N {
            for j in i..N {
                assert_eq!(index(i, j), index(j, i));
                assert!(!seen[index(i, j)]);
                seen[index(i, j)] = true;
            }
        }
        assert!(seen.iter().all(|&s| s));
    }

    /// A shear is `M P M^T` (f64, to the products' rounding).
    #[test]
    fn a_shear_is_the_congruence() {
        let mut p = Covariance::default();
        for i in 0..N {
            for j in i..N {
                p.set(i, j, if i == j { 1 << 24 } else { ((i * 7 + j * 3) as i32 - 20) << 18 });
            }
        }
        let f = -(3 << 27); // -0.375
        let mut q = p;
        q.shear(X, (T, f), (SPEED, 0));
        let ff = f as f64 / (1u64 << 30) as f64;
        for i in 0..N {
            for j in 0..N {
                let m = |a: usize, b: usize| {
                    if a == b {
                        1.0
                    } else if (a, b) == (X, T) {
                        ff
                    } else {
                        0.0
                    }
                };
                let mut e = 0.0;
                for a in 0..N {
                    for b in 0..N {
                        e += m(i, a) * p.get(a, b) as f64 * m(j, b);
                    }
                }
                assert!((q.get(i, j) as f64 - e).abs() <= 32.0, "{i} {j}: {} vs {e}", q.get(i, j));
            }
        }
    }
}
