//! The corrections: a lidar's or the compass's reading through the scalar
//! Kalman update, with the innovation gate and re-acquisition (see the
//! module docs of [`super`]).

use super::constants::{
    GATE_SQ_Q8, LSB_PER_TILDE_MM_Q9, MIN_NORMAL, P_MAX, P_REACQUIRE, R_COMPASS, R_LIDAR, TILDE_Q16_PER_LSB,
};
use super::covariance::{remove, Covariance};
use super::{Estimator, SensorStats, Update};
use crate::config::estimator as cfg;
use crate::math::{
    isqrt64, mul_hi, mul_hi_u, mul_q30, mul_q30_unsat, mul_wide, normalize, reciprocal, shift, Angle, Coord,
};

/// 1 in Q2.30.
const ONE: i32 = 1 << 30;
use crate::model::measurement::{Beam, LidarId, Wall};

/// One row of `H` for a scalar measurement: `sign` times a unit on x or y
/// (or nothing), plus `theta` (Q16, per mm of `L dtheta`) on the heading.
#[derive(Clone, Copy)]
struct Row {
    /// 0 = x, 1 = y, with the sign of the unit entry; `None` for the compass.
    pos: Option<(u8, bool)>,
    /// Q16; |theta| <= THETA_MAX < 2^19 ((|z| + |lateral|) / L with |z| <= 2^11 mm, clamped).
    theta: i32,
}

impl Estimator {
    /// Corrects the pose with a lidar's model output (distance from the
    /// reference point along the beam, see [`crate::model::lidar`]).
    pub fn update_lidar(&mut self, which: LidarId, distance: crate::math::Length) -> Update {
        let mount = which.mount();
        // Refresh the pose's sin/cos cache in place (a no-op when it is
        // current): the beam takes the heading's sin/cos from it.
        self.pose.sin_cos();
        let beam = Beam::new(&self.arena, &self.pose, &mount);
        let result = if !beam.square_enough(MIN_NORMAL) || beam.near_corner(cfg::CORNER_MARGIN) {
            Update::Unusable
        } else {
            // |z| < 2^11 mm keeps H's heading entry below 2^19 (Q16).
            let z = crate::math::Length(distance.0.clamp(-(1 << 27), 1 << 27));
            let nu = beam.normal_miss(z);
            // -d(normal_miss)/d(theta) for the north and east walls (see
            // `Beam::heading_lever`); mm Q16, / L -> Q16 per (L rad) mm; |z|
            // <= 2^11 mm and the mounts' few cm keep it near 2^19: clamped
            // to the bound `correct` relies on.
            let lever = beam.heading_lever(z).0;
            let axis = if beam.wall.is_x_wall() { 0u8 } else { 1u8 };
            let sign_pos = matches!(beam.wall, Wall::North | Wall::East);
            let theta = (lever >> 8).clamp(-THETA_MAX, THETA_MAX);
            // North and East: H = (-1 on the axis, +lever); South and West: (+1, -lever).
            let row = if sign_pos {
                Row { pos: Some((axis, false)), theta }
            } else {
                Row { pos: Some((axis, true)), theta: -theta }
            };
            // R = sigma^2 cos^2 (the cone's incidence): in Q30 via mul_hi (Q28) * 4.
            // (square on, the normal in the cone: R itself)
            let r = if beam.cone_normal >= ONE {
                R_LIDAR
            } else {
                let n2 = mul_hi(beam.cone_normal, beam.cone_normal) << 2; // <= 2^30
                mul_q30_unsat(R_LIDAR, n2).max(1)
            };
            match self.correct(row, nu.0, r) {
                Update::Accepted => {
                    *self.run_of(which) = 0;
                    Update::Accepted
                }
                _ => self.lidar_outlier(which, row, nu, r, &beam),
            }
        };
        self.stats_of(which).count(result);
        result
    }

    fn stats_of(&mut self, which: LidarId) -> &mut SensorStats {
        match which {
            LidarId::Front => &mut self.stats.front,
            LidarId::Right => &mut self.stats.right,
        }
    }

    fn run_of(&mut self, which: LidarId) -> &mut u8 {
        match which {
            LidarId::Front => &mut self.streaks.front,
            LidarId::Right => &mut self.streaks.right,
        }
    }

    /// A lidar reading failed the gate: counted into the lidar's run of
    /// outliers, and at [`cfg::REACQUIRE_AFTER`] the position is taken as
    /// lost (see the module docs).
    // tick bar: the accepted path carries none of this
    #[cold]
    #[inline(never)]
    fn lidar_outlier(&mut self, which: LidarId, row: Row, nu: crate::math::Length, r: i32, beam: &Beam) -> Update {
        // The reference point's distance to the wall along its normal that
        // the reading implies (the lidar's, less its setback):
        // one that puts the reference point outside the arena (a lidar
        // against an obstacle or pressed to a wall) is no evidence the
        // position is lost, and does not count.
        let implied =
            nu.saturating_add(beam.to_wall).saturating_sub(crate::math::Length(mul_q30(beam.setback.0, beam.normal)));
        let extent = if beam.wall.is_x_wall() { self.arena.length_x } else { self.arena.width_y };
        if implied.0 < 0 || implied > extent {
            return Update::Outlier;
        }
        let run = self.run_of(which);
        *run = run.saturating_add(1);
        if *run < cfg::REACQUIRE_AFTER {
            return Update::Outlier;
        }
        *run = 0;
        // The position is what is in doubt (the heading has the compass),
        // on both axes: the beam may meet another wall than the estimate
        // thinks. Its variances grow to the re-acquisition's (never shrink).
        let q = &mut self.p;
        (q.xx, q.yy, q.xy, q.xt, q.yt) = (q.xx.max(P_REACQUIRE), q.yy.max(P_REACQUIRE), 0, 0, 0);
        let st = self.stats_of(which);
        st.reacquired = st.reacquired.saturating_add(1);
        self.correct_clipped(row, nu.0, r)
    }

    /// [`Estimator::correct`] with the innovation clipped to the gate,
    /// `nu_used = sign(nu) min(|nu|, gate sqrt(S))` (re-acquisition only):
    /// the reading then passes the gate, and the step `K nu_used` obeys
    /// `step^T P^-1 step = nu_used^2 H P H^T / S^2 <= gate^2` under the
    /// covariance it starts from.
    // tick bar: the accepted path carries none of this
    #[cold]
    #[inline(never)]
    fn correct_clipped(&mut self, row: Row, nu: i32, r: i32) -> Update {
        let (_, s, k) = innovation(&self.p, row, r);
        // gate sqrt(S) in Q16 mm, rounded down: its square is within the gate
        // (the bound is below 2^62, its root below 2^31)
        let most = isqrt64(gate_bound(s, k).unsigned_abs()) as i32;
        self.correct(row, nu.clamp(-most, most), r)
    }

    /// A compass reading failed the gate: counted into the compass's run of
    /// outliers, and at [`cfg::REACQUIRE_AFTER`] the heading is taken as
    /// lost: its variance to the cap, uncorrelated, and the reading used
    /// (clipped to the gate, which at the cap passes any heading: half a
    /// turn is 3.1 sigma).
    // tick bar: the accepted path carries none of this
    #[cold]
    #[inline(never)]
    fn heading_outlier(&mut self, row: Row, nu: i32) -> Update {
        let run = &mut self.streaks.compass;
        *run = run.saturating_add(1);
        if *run < cfg::REACQUIRE_AFTER {
            return Update::Outlier;
        }
        *run = 0;
        let q = &mut self.p;
        (q.tt, q.xt, q.yt) = (P_MAX, 0, 0);
        self.stats.compass.reacquired = self.stats.compass.reacquired.saturating_add(1);
        self.correct_clipped(row, nu, R_COMPASS)
    }

    /// Corrects the heading with a compass reading (clockwise from north).
    pub fn update_heading(&mut self, heading: Angle) -> Update {
        let diff = heading.diff(self.pose.theta);
        // angle LSB -> (L rad) mm Q16: |result| < 2^31 * 0.025
        let nu = mul_hi(diff, TILDE_Q16_PER_LSB);
        let row = Row { pos: None, theta: 1 << 16 };
        let result = match self.correct(row, nu, R_COMPASS) {
            Update::Accepted => {
                self.streaks.compass = 0;
                Update::Accepted
            }
            _ => self.heading_outlier(row, nu),
        };
        self.stats.compass.count(result);
        result
    }

    /// The scalar Kalman correction for innovation `nu` (Q16 mm), row `h`,
    /// noise `r` (Q14 mm^2, > 0), gated. All 32-bit but the state update's
    /// three products (see the module docs, "Arithmetic of a correction").
    fn correct(&mut self, h: Row, nu: i32, r: i32) -> Update {
        let (b, s, k) = innovation(&self.p, h, r);
        // Gate: nu^2 (Q32) against gate^2 S; nu^2 <= 2^62.
        if mul_wide(nu, nu) > gate_bound(s, k) {
            return Update::Outlier;
        }
        // 1/S = y 2^(ns - 62): S normalised to [2^31, 2^32), its reciprocal
        // by two Newton steps (no division).
        let (sn, ns) = normalize(s as u32); // s > 0
        let y = reciprocal(sn);
        // b normalised too: beta = b 2^sb with max |beta| in [2^29, 2^30).
        let mb = b[0].unsigned_abs() | b[1].unsigned_abs() | b[2].unsigned_abs();
        if mb == 0 {
            // P H^T = 0: the reading says nothing about the state
            return Update::Accepted;
        }
        // |b| < 2^27: sb >= 3
        let sb = normalize(mb).1 - 2;
        // t = beta / S 2^(30 - ns) (|t| < 2^29), rounded toward zero.
        // (tick bar: element by element, not `map`: at opt-level "z" a closure per
        // element is a call, and this is the tick's hottest path)
        let t = [over_s(b[0], sb, y), over_s(b[1], sb, y), over_s(b[2], sb, y)];
        // K = b / S = t 2^(ns - sb - 30); in Q21: t 2^(ns - sb - 9). For a
        // valid P, |K_i| <= sqrt(P_ii / S) < 2^8; the largest |t| is at
        // least 2^27 - 3, so a shift above 2 means |K| >= 2^9: an invalid P.
        let ek = ns as i32 - sb as i32 - 9;
        if ek > 2 {
            self.stats.repairs = self.stats.repairs.saturating_add(1);
            return Update::Outlier;
        }
        // |t| < 2^29, ek <= 2: K fits i32
        let [kx, ky, kt] = [shift(t[0], ek), shift(t[1], ek), shift(t[2], ek)];
        // State: K nu, Q21 * Q16 = Q37 mm -> Coord (Q32); |K|, |nu| <= 2^31,
        // so the exact products are below 2^62 and the steps below 2^57.
        // The position is within the arena's box (`keep_in_arena` after
        // every step, at most 2^15 mm = 2^47 in Q32): the sums stay below
        // 2^58, so the plain (wrapping) add is exact.
        self.pose.x = Coord(self.pose.x.0.wrapping_add(mul_wide(kx, nu) >> 5));
        self.pose.y = Coord(self.pose.y.0.wrapping_add(mul_wide(ky, nu) >> 5));
        // Heading: K_t nu (L rad) mm -> angle LSB: mul_hi(K_t, 2^32 / (2 pi L)
        // 2^9) nu >> 14; modulo one turn (the low 32 bits).
        let dlsb = (mul_wide(mul_hi(kt, LSB_PER_TILDE_MM_Q9), nu) >> 14) as u32;
        self.pose.theta = self.pose.theta.wrapping_add(Angle(dlsb));
        // P -= K b^T = b b^T / S (upper triangle): b_i b_j / S 2^k in Q14 is
        // mul_hi(t_i, beta_j) 2^(ns - 2 sb + 2 + k). The diagonal's products
        // round down (t and beta taken positive, y below 1/S), so less is
        // removed than exact arithmetic would.
        let ep = ns as i32 - 2 * sb as i32 + 2 + k as i32;
        let [bx, by, bt] = [b[0] << sb, b[1] << sb, b[2] << sb]; // |beta| < 2^30
        let [tx, ty, tt] = t;
        let q = &mut self.p;
        // |t| < 2^29, |beta| < 2^30
        remove(&mut q.xx, tx.abs(), bx.abs(), ep);
        remove(&mut q.yy, ty.abs(), by.abs(), ep);
        remove(&mut q.tt, tt.abs(), bt.abs(), ep);
        remove(&mut q.xy, tx, by, ep);
        remove(&mut q.xt, tx, bt, ep);
        remove(&mut q.yt, ty, bt, ep);
        self.condition();
        self.keep_in_arena();
        Update::Accepted
    }
}

/// `b = P H^T` and `S = H P H^T + R` for row `h` and noise `r`, both scaled
/// by 2^-k (Q(14 - k) mm^2; see [`project`]), and `k`.
// tick bar (as the other inline attributes below)
#[inline(always)]
fn innovation(p: &Covariance, h: Row, r: i32) -> ([i32; 3], i32, u32) {
    let (b, hph, k) = project(p, h);
    // S = H P H^T + R > 0: |hph| < 2^30, r >> k < 2^22, so S < 2^31;
    // H P H^T >= 0 for a valid P, and r >> k >= 1 keeps S positive.
    (b, hph.max(0) + (r >> k).max(1), k)
}

/// `gate^2 S` in Q32 mm^2 (the square of an innovation's Q16) for `S` from
/// [`innovation`]: S 2^k in Q14 is S 2^(18 + k) in Q32, gate^2 is Q8.
/// gate^2 < 2^12 (asserted) shifted by 10 + k <= 19 stays below 2^31, and
/// its product with S below 2^62.
#[inline(always)]
fn gate_bound(s: i32, k: u32) -> i64 {
    mul_wide(s, GATE_SQ_Q8 << (10 + k))
}

/// `beta / S` for one entry of `b`: `|b| 2^sb` times `y` (1/S, see
/// [`reciprocal`]), high word, with `b`'s sign (rounded toward zero).
#[inline(always)]
fn over_s(bi: i32, sb: u32, y: u32) -> i32 {
    let m = mul_hi_u(bi.unsigned_abs() << sb, y) as i32;
    if bi < 0 {
        -m
    } else {
        m
    }
}

/// One entry of `b = theta P_t +- P_axis` (see [`project`]): `ct`, `ca`
/// from P's heading and `axis` columns, `th8` = theta << 8.
#[inline(always)]
fn lidar_b(ct: i32, ca: i32, k: u32, th8: i32, positive: bool) -> i32 {
    let (tp, ap) = (mul_hi((ct >> k) << 8, th8), ca >> k);
    if positive {
        tp + ap
    } else {
        tp - ap
    }
}

/// Bound on H's heading entry (Q16 per (L rad) mm): `|theta| < 2^19`, a
/// lever of 2048 mm, what `correct`'s 32-bit products are sized for.
const THETA_MAX: i32 = (1 << 19) - 1;

/// `b = P H^T` and `H P H^T` for row `h`, both scaled by `2^-k` (Q(14 - k)
/// mm^2), with `k` the smallest shift that brings every covariance entry
/// the row reads below 2^23 (`k = 0` below 512 mm^2, so steady state is
/// exact; `k <= 9`). Then `|b| < 2^27` and `|H P H^T| < 2^30`.
#[inline(always)]
fn project(p: &Covariance, h: Row) -> ([i32; 3], i32, u32) {
    let col_t = [p.xt, p.yt, p.tt];
    let mag = |c: &[i32; 3]| c[0].unsigned_abs() | c[1].unsigned_abs() | c[2].unsigned_abs();
    match h.pos {
        None => {
            // H = (0, 0, 1) (the compass): b = P's heading column, H b = P_tt.
            let k = scale_shift(mag(&col_t));
            let b = [col_t[0] >> k, col_t[1] >> k, col_t[2] >> k];
            let hb = b[2];
            (b, hb, k)
        }
        Some((axis, positive)) => {
            // H = (+-1 on `axis`, theta): b = theta P_t + -P_axis.
            let col_a = if axis == 0 { [p.xx, p.xy, p.xt] } else { [p.xy, p.yy, p.yt] };
            let k = scale_shift(mag(&col_t) | mag(&col_a));
            // |P >> k| < 2^23, so << 8 < 2^31; |theta| < 2^19, << 8 < 2^27:
            // mul_hi gives P theta / 2^16, below 2^26 (+ 3 LSB of rounding).
            // |b| < 2^26 + 2^23 < 2^27 (tick bar: element by element; at opt-level "z"
            // an iterator over the columns is a call per element)
            let th8 = h.theta << 8;
            let b = [
                lidar_b(col_t[0], col_a[0], k, th8, positive),
                lidar_b(col_t[1], col_a[1], k, th8, positive),
                lidar_b(col_t[2], col_a[2], k, th8, positive),
            ];
            // H b = +-b_axis + theta b_t / 2^16: b_t << 4 < 2^31, theta << 12
            // < 2^31, the product below 9 2^26; the sum below 81 2^23 < 2^30.
            let ba = if axis == 0 { b[0] } else { b[1] };
            let tb = mul_hi(b[2] << 4, h.theta << 12);
            let hb = if positive { tb + ba } else { tb - ba };
            (b, hb, k)
        }
    }
}

/// The shift `k` with `m >> k < 2^23` (0 when `m` already is).
#[inline(always)]
fn scale_shift(m: u32) -> u32 {
    if m < 1 << 23 {
        0
    } else {
        9 - normalize(m).1 // m >= 2^23: normalize's shift is at most 8
    }
}
