//! One hypothesis's corrections: a lidar's or the compass's reading through
//! the scalar Kalman update, gated (see the module docs of [`super`]).

use super::constants::{
    BIAS_MAX_LSB, CORNER_FLOOR, CORNER_RANGE_SHIFT, CORNER_SIGMAS, GATE_SQ_Q8, LSB_PER_TILDE_MM_Q9, MIN_NORMAL,
    R_COMPASS, R_INCIDENCE, R_LIDAR, SCALE_MAX, SCALE_MIN, TILDE_Q16_PER_LSB,
};
use super::covariance::{each, Covariance, BIAS, CCW, CW, N, SPEED, T, X, Y};
use super::lag::Lag;
use super::predict::{Bounds, Filter};
use super::Update;
use crate::config::estimator as cfg;
use crate::math::{mul_hi, mul_hi_u, mul_q30, mul_q30_unsat, mul_wide, normalize, reciprocal, shift, Angle, Coord};
use crate::model::measurement::{Arena, Beam, LidarId, Wall};

/// 1 in Q2.30.
const ONE: i32 = 1 << 30;

/// One row of `H` for a scalar measurement: a unit entry (with its sign) on
/// state `unit`, plus `coef` (Q16) on state `lever`: a lidar's is its axis
/// and the heading, the compass's the bias and the heading.
#[derive(Clone, Copy)]
pub(super) struct Row {
    pub unit: usize,
    pub positive: bool,
    pub lever: usize,
    /// Q16; |coef| <= THETA_MAX < 2^19.
    pub coef: i32,
}

impl Row {
    /// `H = e_state`: a reading of one state alone.
    pub const fn unit_on(state: usize) -> Row {
        Row { unit: state, positive: true, lever: state, coef: 0 }
    }
}

/// What a correction did, with the reading's normalised squared innovation
/// `nu^2 / S` in Q8 (0 unless accepted) for the hypotheses' weights.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub(super) struct Outcome {
    pub update: Update,
    pub nis_q8: i32,
    /// The innovation, Q16 mm along the row (a lidar's along its wall's
    /// normal; the compass's as `L dtheta`).
    pub nu: i32,
}

impl Outcome {
    pub const UNUSABLE: Outcome = Outcome::not(Update::Unusable);

    const fn not(update: Update) -> Outcome {
        Outcome { update, nis_q8: 0, nu: 0 }
    }
}

/// A lidar reading's geometry for one hypothesis: its row, innovation and
/// noise, or why it cannot be used.
pub(super) struct LidarReading {
    pub row: Row,
    pub nu: i32,
    /// The reading's spot spread along the wall's normal, Q16 mm
    /// ([`Beam::spot_spread`]).
    pub spread: i32,
    pub r: i32,
    /// The wall's axis (X or Y) and the sign of its normal into the box.
    pub axis: usize,
    pub toward_high: bool,
    /// Whether the distance it implies fits in the arena.
    pub possible: bool,
}

impl Filter {
    /// A lidar reading's row, innovation and noise for this hypothesis, or
    /// `None` when the geometry makes it useless (too oblique, near a corner).
    /// The range is predicted `share` (Q30) of the way from the cone's
    /// nearest wall point to the axis's (`spot`).
    pub(super) fn lidar_reading(
        &mut self,
        arena: &Arena,
        which: LidarId,
        distance: crate::math::Length,
        share: i32,
        lag: &Lag,
    ) -> Option<LidarReading> {
        // refresh the pose's sin/cos cache in place (the beam reads it)
        self.pose.sin_cos();
        // the body a reading's age ago (`lag`)
        let then = lag.then(&self.pose);
        let beam = Beam::at(arena, then.x, then.y, then.theta, then.sin_cos, &which.mount());
        if !beam.square_enough(MIN_NORMAL) {
            return None;
        }
        // |z| < 2^11 mm keeps H's heading entry below 2^19 (Q16)
        let z = crate::math::Length(distance.0.clamp(-(1 << 27), 1 << 27));
        let spread = beam.spot_spread(z);
        let nu = beam.normal_miss(z).saturating_sub(crate::math::Length(mul_q30_unsat(spread.0, share)));
        let axis = if beam.wall.is_x_wall() { X } else { Y };
        let north_or_east = matches!(beam.wall, Wall::North | Wall::East);
        let theta = (beam.heading_lever(z).0 >> 8).clamp(-THETA_MAX, THETA_MAX);
        // North and East: H = (-1 on the axis, +lever); South and West: (+1, -lever).
        let row = if north_or_east {
            Row { unit: axis, positive: false, lever: T, coef: theta }
        } else {
            Row { unit: axis, positive: true, lever: T, coef: -theta }
        };
        // R = (sigma^2 + sigma_inc^2 tan^2) cos^2 = sigma^2 cos^2 + sigma_inc^2
        // sin^2 with the cone's incidence (no division); cos^2 in Q30 via
        // mul_hi (Q28) * 4, at most 2^30; each term at most its constant.
        let n2 = if beam.cone_normal >= ONE { ONE } else { mul_hi(beam.cone_normal, beam.cone_normal) << 2 };
        let r = if n2 >= ONE {
            R_LIDAR
        } else {
            mul_q30_unsat(R_LIDAR, n2) + mul_q30_unsat(R_INCIDENCE, ONE - n2.min(ONE))
        }
        .max(1);
        // near a corner the reading may be the other wall's, or both's
        let r = if beam.meets_two_walls() { self.with_corner(r, n2, &beam, distance)? } else { r };
        // The reference point's distance to the wall along its normal that
        // the reading implies: outside [0, extent] no position in the arena
        // gives it (a lidar against an obstacle or pressed to a wall).
        let implied =
            nu.saturating_add(beam.to_wall).saturating_sub(crate::math::Length(mul_q30(beam.setback.0, beam.normal)));
        let extent = if beam.wall.is_x_wall() { arena.length_x } else { arena.width_y };
        let possible = implied.0 >= 0 && implied <= extent;
        Some(LidarReading { row, nu: nu.0, spread: spread.0, r, axis, toward_high: !north_or_east, possible })
    }

    /// A reading's noise `r` (Q12 mm^2, scaled by the cone's cos^2 `n2`)
    /// with the corner's variance added, scaled alike (below 2^28 each), or
    /// `None` when the cone meets two walls within `cfg::CORNER_MARGIN` (the
    /// reading mixes their returns). Out of line: the corners' work stays
    /// off the path of a beam that meets one wall (tick bar: inlined, it
    /// made that path 100 instructions longer).
    #[inline(never)]
    fn with_corner(&self, r: i32, n2: i32, beam: &Beam, distance: crate::math::Length) -> Option<i32> {
        let corner = self.corner_variance(beam, distance)?;
        Some(if corner == 0 { r } else { r.saturating_add(mul_q30_unsat(corner, n2.min(ONE))) })
    }

    /// The variance a reading `distance` gains when its cone meets two
    /// walls at ranges this hypothesis's heading cannot tell apart
    /// ([`Beam::corner_reading`] with `cfg::CORNER_SIGMAS` of the heading's
    /// variance), Q12 mm^2, 0 when they are told apart; `None` within
    /// `cfg::CORNER_MARGIN`.
    fn corner_variance(&self, beam: &Beam, distance: crate::math::Length) -> Option<i32> {
        // the heading's variance times the range squared: P_tt (Q12 (L
        // rad)^2 mm^2) r^2 / L^2 with r in Q4 mm (at most 2 m: its square
        // below 2^30, natively), mul_hi's 2^-32 and the Q4's 2^-8 against
        // L^2: saturated at i32 (far above the largest margin's square)
        let heading_range2 = || {
            let range = distance.saturating_add(beam.setback).0.clamp(0, 2047 << 16) >> 12;
            let product = mul_hi(self.p.get(T, T).clamp(0, 1 << 28), range * range);
            let up = 32 - 8 - CORNER_RANGE_SHIFT;
            if product > i32::MAX >> up {
                i32::MAX
            } else {
                product << up
            }
        };
        beam.corner_reading(cfg::CORNER_MARGIN, CORNER_FLOOR, heading_range2, CORNER_SIGMAS)
    }

    /// The compass's row and innovation: it reads the heading plus the bias.
    pub(super) fn compass_reading(&self, heading: Angle) -> (Row, i32) {
        let diff = heading.diff(self.pose.theta.wrapping_add(self.bias));
        // angle LSB -> (L rad) mm Q16: |result| < 2^31 * 0.025
        (Row { unit: BIAS, positive: true, lever: T, coef: 1 << 16 }, mul_hi(diff, TILDE_Q16_PER_LSB))
    }

    /// Corrects with a compass reading.
    pub(super) fn update_heading(&mut self, heading: Angle, bounds: &Bounds) -> (Outcome, u32) {
        let (row, nu) = self.compass_reading(heading);
        self.correct(row, nu, R_COMPASS, bounds)
    }

    /// The scalar Kalman correction for innovation `nu` (Q16 mm), row `h`,
    /// noise `r` (Q12 mm^2, 0 < r <= P_MAX), gated. All 32-bit but the
    /// state update's products (see the module docs, "Arithmetic of a
    /// correction"). Returns the outcome and the repairs made.
    pub(super) fn correct(&mut self, h: Row, nu: i32, r: i32, bounds: &Bounds) -> (Outcome, u32) {
        let (b, s, k) = innovation(&self.p, h, r);
        let mb = b.iter().fold(0u32, |m, v| m | v.unsigned_abs());
        let Scaling { y, ns, sb, ek, nis_q8 } = match scaling(nu, s, k, mb) {
            Ok(sc) => sc,
            Err(done) => return done,
        };
        // t = beta / S 2^(30 - ns) (|t| < 2^29), rounded toward zero.
        let t = each(
            #[inline(always)]
            |i| over_s(b.get(i).copied().unwrap_or(0), sb, y),
        );
        // |t| < 2^29, ek <= 2: K fits i32
        let gain = |i: usize| shift(t.get(i).copied().unwrap_or(0), ek);
        // State: K nu, Q21 * Q16 = Q37 mm. Position -> Coord (Q32): the
        // products below 2^62, the steps below 2^57, the position within the
        // arena's box (2^47): the plain add is exact.
        self.pose.x = Coord(self.pose.x.0.wrapping_add(mul_wide(gain(X), nu) >> 5));
        self.pose.y = Coord(self.pose.y.0.wrapping_add(mul_wide(gain(Y), nu) >> 5));
        // Heading and bias: (L rad) mm -> angle LSB: mul_hi(K, 2^32 / (2 pi L)
        // 2^9) nu >> 14; modulo one turn (the low 32 bits).
        self.pose.theta = self.pose.theta.wrapping_add(to_angle(gain(T), nu));
        let bias = self.bias.wrapping_add(to_angle(gain(BIAS), nu));
        self.bias = Angle(bias.diff(Angle::ZERO).clamp(-BIAS_MAX_LSB, BIAS_MAX_LSB) as u32);
        // Scales: L dscale mm Q37 -> dscale Q45 (/ 256) -> Q29 (>> 16), kept in bounds.
        let to_scale = |v: i32, k: i32| {
            let step = (mul_wide(k, nu) >> 16).clamp(i64::from(i32::MIN), i64::from(i32::MAX)) as i32;
            v.saturating_add(step).clamp(SCALE_MIN, SCALE_MAX)
        };
        self.scales.speed = to_scale(self.scales.speed, gain(SPEED));
        self.scales.cw = to_scale(self.scales.cw, gain(CW));
        self.scales.ccw = to_scale(self.scales.ccw, gain(CCW));
        // P -= K b^T = b b^T / S (upper triangle): b_i b_j / S 2^k in Q12 is
        // mul_hi(t_i, beta_j) 2^(ns - 2 sb + 2 + k). The diagonal's products
        // round down (t and beta positive, y below 1/S): less is removed
        // than exact arithmetic would.
        let ep = ns as i32 - 2 * sb as i32 + 2 + k as i32;
        let beta = each(
            #[inline(always)]
            |i| b.get(i).copied().unwrap_or(0) << sb,
        ); // |beta| < 2^30
        self.p.remove_outer(&t, &beta, ep);
        let repairs = self.p.condition();
        self.keep_in(bounds);
        (Outcome { update: Update::Accepted, nis_q8, nu }, repairs)
    }
}

/// A scalar correction's gate and scaling, shared by the whole filter
/// ([`Filter::correct`]) and a secondary's pose block (`light`).
pub(super) struct Scaling {
    /// `1/S = y 2^(ns - 62)`.
    pub y: u32,
    pub ns: u32,
    /// `b` normalised: `beta = b 2^sb` with `max |beta|` in `[2^29, 2^30)`.
    pub sb: u32,
    /// The gain's shift: `K = t 2^(ek - 21)` in Q21 for `t = beta / S 2^(30
    /// - ns)`.
    pub ek: i32,
    /// `nu^2 / S`, Q8.
    pub nis_q8: i32,
}

/// The gate and the scaling of a correction with innovation `nu` (Q16 mm),
/// `S` and its shift `k` ([`innovation`]) and `mb`, the bits of `b = P H^T`
/// or-ed together; `Err`: the outcome and repairs when nothing is applied
/// (gated out, `P H^T = 0`, or a gain that only an invalid `P` gives).
// tick bar (four hypotheses): inlined into both corrections
#[inline(always)]
pub(super) fn scaling(nu: i32, s: i32, k: u32, mb: u32) -> Result<Scaling, (Outcome, u32)> {
    // Gate: nu^2 (Q32, <= 2^62; >> 4: Q28) against gate^2 S.
    if mul_wide(nu, nu) >> 4 > gate_bound(s, k) {
        return Err((Outcome { nu, ..Outcome::not(Update::Outlier) }, 0));
    }
    // 1/S = y 2^(ns - 62): S normalised to [2^31, 2^32), its reciprocal by
    // two Newton steps (no division).
    let (sn, ns) = normalize(s as u32); // s > 0
    let y = reciprocal(sn);
    let nis_q8 = normalised_square(nu, y, ns, k);
    if mb == 0 {
        // P H^T = 0: the reading says nothing about the state
        return Err((Outcome { update: Update::Accepted, nis_q8, nu }, 0));
    }
    // |b| < 2^27: sb >= 3
    let sb = normalize(mb).1 - 2;
    // K = b / S = t 2^(ns - sb - 30); in Q21: t 2^(ns - sb - 9). For a valid
    // P, |K_i| <= sqrt(P_ii / S) < 2^8; the largest |t| is at least 2^27 -
    // 3, so a shift above 2 means |K| >= 2^9: an invalid P.
    let ek = ns as i32 - sb as i32 - 9;
    if ek > 2 {
        return Err((Outcome { nu, ..Outcome::not(Update::Outlier) }, 1));
    }
    Ok(Scaling { y, ns, sb, ek, nis_q8 })
}

/// A gain `k` (Q21, per (L rad) mm) times `nu` (Q16 mm) as an angle:
/// `mul_hi(K, 2^32 / (2 pi L) 2^9) nu >> 14`, modulo one turn (the low 32
/// bits).
#[inline(always)]
pub(super) fn to_angle(k: i32, nu: i32) -> Angle {
    Angle((mul_wide(mul_hi(k, LSB_PER_TILDE_MM_Q9), nu) >> 14) as u32)
}

/// `nu^2 / S` in Q8, from the reciprocal `y` of `S` normalised by `ns`
/// (1/S = y 2^(ns - 62), S in Q(12 - k) mm^2, nu Q16 mm): with `nu = a
/// 2^-na` normalised, `nu^2 / S = mul_hi(mul_hi(a, a), y) 2^(ns - 2 na -
/// 18 - k)` (the 2^64 of the two high words against Q32 of nu^2 and
/// Q(12 - k) of S), in Q8 `2^(ns - 2 na - 10 - k)`. Saturates; a gated
/// reading's is at most gate^2 (Q8 below 2^12).
pub(super) fn normalised_square(nu: i32, y: u32, ns: u32, k: u32) -> i32 {
    if nu == 0 {
        return 0;
    }
    let (a, na) = normalize(nu.unsigned_abs());
    let m = mul_hi_u(mul_hi_u(a, a), y) >> 1; // < 2^31
    shift(m as i32, ns as i32 + 1 - 2 * na as i32 - 10 - k as i32)
}

/// `b = P H^T` and `S = H P H^T + R` for row `h` and noise `r`, both scaled
/// by 2^-k (Q(12 - k) mm^2; see [`project`]), and `k`.
#[inline(always)]
pub(super) fn innovation(p: &Covariance, h: Row, r: i32) -> ([i32; N], i32, u32) {
    let (b, hph, k) = project(p, h);
    // S = H P H^T + R > 0: |hph| < 2^30, r >> k <= 2^28 (asserted), so
    // S < 2^31; H P H^T >= 0 for a valid P, and r >> k >= 1 keeps S positive.
    (b, hph.max(0) + (r >> k).max(1), k)
}

/// `gate^2 S` in Q28 mm^2 (the square of an innovation's Q16, >> 4) for
/// `S` from [`innovation`]: S 2^k in Q12 is S 2^(16 + k) in Q28, gate^2 is
/// Q8. gate^2 < 2^12 (asserted) shifted by 8 + k <= 17 stays below 2^29,
/// its product with S below 2^60.
#[inline(always)]
pub(super) fn gate_bound(s: i32, k: u32) -> i64 {
    mul_wide(s, GATE_SQ_Q8 << (8 + k))
}

/// `beta / S` for one entry of `b`: `|b| 2^sb` times `y` (1/S, see
/// [`reciprocal`]), high word, with `b`'s sign (rounded toward zero).
#[inline(always)]
pub(super) fn over_s(bi: i32, sb: u32, y: u32) -> i32 {
    let m = mul_hi_u(bi.unsigned_abs() << sb, y) as i32;
    if bi < 0 {
        -m
    } else {
        m
    }
}

/// Bound on H's lever entry (Q16 per (L rad) mm): `|coef| < 2^19`, a
/// lever of 2048 mm, what the 32-bit products are sized for.
const THETA_MAX: i32 = (1 << 19) - 1;

/// `b = P H^T` and `H P H^T` for row `h`, both scaled by `2^-k` (Q(12 - k)
/// mm^2), with `k` the smallest shift that brings every covariance entry
/// the row reads below 2^23 (`k = 0` below 2,048 mm^2, so steady state is
/// exact; `k <= 8`). Then `|b| < 2^27` and `|H P H^T| < 2^30`.
#[inline(always)]
fn project(p: &Covariance, h: Row) -> ([i32; N], i32, u32) {
    let (unit, lever) = (p.row(h.unit), p.row(h.lever));
    let mag = unit.iter().chain(lever.iter()).fold(0u32, |m, v| m | v.unsigned_abs());
    let k = scale_shift(mag);
    // |P >> k| < 2^23, so << 8 < 2^31; |coef| < 2^19, << 8 < 2^27: mul_hi
    // gives P coef / 2^16, below 2^26 (+ 3 LSB of rounding); |b| < 2^27.
    let c8 = h.coef << 8;
    let b = each(
        #[inline(always)]
        |i| {
            let at = |row: &[i32; N]| row.get(i).copied().unwrap_or(0);
            let (l, u) = (mul_hi((at(&lever) >> k) << 8, c8), at(&unit) >> k);
            if h.positive {
                l + u
            } else {
                l - u
            }
        },
    );
    // H b = +-b_unit + coef b_lever / 2^16: b << 4 < 2^31, coef << 12 < 2^31,
    // the product below 9 2^26; the sum below 81 2^23 < 2^30.
    let bu = b.get(h.unit).copied().unwrap_or(0);
    let bl = b.get(h.lever).copied().unwrap_or(0);
    let tb = mul_hi(bl << 4, h.coef << 12);
    let hb = if h.positive { tb + bu } else { tb - bu };
    (b, hb, k)
}

/// The shift `k` with `m >> k < 2^23` (0 when `m` already is).
#[inline(always)]
pub(super) fn scale_shift(m: u32) -> u32 {
    if m < 1 << 23 {
        0
    } else {
        9 - normalize(m).1 // m >= 2^23: normalize's shift is at most 8
    }
}

#[cfg(test)]
#[allow(clippy::restriction)] // test code: a panic fails the test
mod tests {
    use super::*;
    use crate::math::Length;
    use crate::model::state::Pose;

    const BOUNDS: Bounds = Bounds { low_mm: -1000, high_x_mm: 2000, high_y_mm: 2000 };

    /// A hypothesis 250 mm from the north wall and 180 from the east,
    /// facing 22 degrees (towards the corner), with 8 mm of position sigma
    /// and `heading_deg` of heading sigma; its front cone meets the north
    /// wall 300 mm from the lidar, the east wall 51 mm farther (f64
    /// geometry, the lidar 50 mm behind the reference point).
    fn at_the_corner(heading_deg: f64) -> (Filter, Beam) {
        let arena = Arena::DEFAULT;
        let pose = Pose::new(
            Coord::from_length(arena.length_x.saturating_sub(Length::from_mm(250))),
            Coord::from_length(arena.width_y.saturating_sub(Length::from_mm(180))),
            Angle::from_degrees_f64(22.0),
        );
        let mut f = Filter::new(pose);
        let var = |mm: f64| (mm * mm * 4096.0) as i32;
        f.p.set(X, X, var(8.0));
        f.p.set(Y, Y, var(8.0));
        f.p.set(T, T, var(heading_deg.to_radians() * f64::from(super::super::HEADING_LEVER_MM)));
        let beam = Beam::new(&arena, &f.pose, &LidarId::Front.mount());
        (f, beam)
    }

    /// A reading the east wall gives when the heading is off by the
    /// hypothesis's uncertainty (2 degrees, a 3-sigma error moves the walls
    /// 70 mm apart: the 51 are within it), 25 mm short of the north wall's,
    /// corrects it by less than a third of what the same reading does
    /// without the corner's variance: that passes the gate and moves it by
    /// more than 15 mm (what a turn at
    /// a corner met in the realistic hours, `config::estimator::
    /// CORNER_SIGMAS`). With the heading known to 0.1 degree the walls are
    /// told apart: no corner variance.
    #[test]
    fn a_reading_a_heading_error_could_take_from_the_other_wall_counts_little() {
        let (f, beam) = at_the_corner(2.0);
        assert_eq!(beam.wall, Wall::North);
        assert!(beam.meets_two_walls());
        let expected = beam.expected_distance().unwrap();
        let short = Length::from_mm_f64(expected.to_mm_f64() - 25.0);
        let moved = |mut f: Filter, without_corner: bool| {
            let share = 0;
            let r = f.lidar_reading(&Arena::DEFAULT, LidarId::Front, short, share, &Lag::NONE).unwrap();
            let noise = if without_corner { r.r - corner_part(&f, &beam, short) } else { r.r };
            let before = f.pose;
            let (outcome, _) = f.correct(r.row, r.nu, noise, &BOUNDS);
            let d = (f.pose.x.to_mm_f64() - before.x.to_mm_f64()).hypot(f.pose.y.to_mm_f64() - before.y.to_mm_f64());
            (outcome.update, d)
        };
        let (with, d_with) = moved(f, false);
        let (without, d_without) = moved(f, true);
        std::println!("with the corner's variance {with:?} {d_with:.1} mm; without {without:?} {d_without:.1} mm");
        assert!(d_with < d_without / 3.0);
        assert_eq!(without, Update::Accepted);
        assert!(d_without > 15.0);
        let (sure, beam) = at_the_corner(0.1);
        assert_eq!(sure.corner_variance(&beam, short), Some(0));
    }

    /// The corner's part of a reading's `r` (scaled by the cone's cos^2, as
    /// `with_corner` adds it to a noise of 0).
    fn corner_part(f: &Filter, beam: &Beam, z: Length) -> i32 {
        let cos2 = mul_hi(beam.cone_normal, beam.cone_normal) << 2;
        f.with_corner(0, cos2, beam, z).unwrap()
    }
}
