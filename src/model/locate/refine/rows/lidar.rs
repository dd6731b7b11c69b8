//! A lidar reading's row: where the pivot, the lever and the turns' moves
//! put the reference point, the beam from there, its miss in its sigmas
//! (the noise growing with the range, the incidence and at corners) and
//! the miss's derivatives (see the parent's docs).

use super::*;
use crate::math::{isqrt, Coord};
use crate::model::measurement::{Beam, Wall};
use crate::model::state::Pose;

/// A reading whose reference point leaves the box: this many sigmas
/// (the reference's two bounds), no derivative.
const OUTSIDE: i64 = 2 * ROBUST;
/// A lidar reading's variance, mm^2 Q16: the model's spread at square,
/// its growth with the range and the axis's incidence (the range's share
/// squared, Q16, times `tan^2`, at most 16: 76 degrees, the reference's
/// bound), a corner's mixed returns.
const LIDAR_VAR: i64 = (est::LIDAR_SIGMA.0 as i64 * est::LIDAR_SIGMA.0 as i64) >> 16;
const SPREAD: i64 = (cfg::INCIDENCE_SPREAD * 65536.0) as i64;
const CORNER_VAR: i64 = (cfg::CORNER_SIGMA_MM * cfg::CORNER_SIGMA_MM * 65536.0) as i64;
/// The incidence limit's cosine, Q30: a range read at a cosine below
/// this (the axis's or the cone's nearest point's, `Share::read_normal`)
/// says nothing ([`cfg::MAX_INCIDENCE_DEG`]).
const MIN_NORMAL: i32 =
    (crate::math::cos_f64(cfg::MAX_INCIDENCE_DEG * core::f64::consts::PI / 180.0) * Q30 as f64) as i32;
const TAN2_MAX: i64 = 16 << 16;

/// The heading step of the axis's numerical derivative (2 mrad, the
/// reference's), angle LSB, and its inverse in rad.
const TURN_STEP: i64 = 2 * MRAD;
const PER_TURN_STEP: i64 = 500;

impl Model<'_> {
    /// A lidar's reading `z` with the body at heading `at`.
    pub(super) fn lidar(&self, p: &Params, units: &Units, at: At, id: LidarId, z: Length, derivatives: bool) -> Row {
        let get = |k: usize| param(p, k);
        let theta = Angle(at.theta as u32);
        let (s, c) = sin_cos(theta);
        let (s, c) = (i64::from(s), i64::from(c));
        let d = get(LEVER);
        let chords = self.chords(units, &at, (c, s));
        let (mx, my) = chords.iter().fold((0i64, 0i64), |(x, y), &(k, cx, cy)| {
            (x.saturating_add(mul_shr(get(k), cx, 30)), y.saturating_add(mul_shr(get(k), cy, 30)))
        });
        let x = get(PX).saturating_add(mul_shr(d, c, 30)).saturating_add(mx);
        let y = get(PY).saturating_add(mul_shr(d, s, 30)).saturating_add(my);
        let (lx, wy) = (i64::from(self.arena.length_x.0), i64::from(self.arena.width_y.0));
        if !(0..=lx).contains(&x) || !(0..=wy).contains(&y) {
            return Row::new(OUTSIDE, Loss::Robust);
        }
        let pose = Pose::new(Coord::from_length(Length(x as i32)), Coord::from_length(Length(y as i32)), theta);
        let beam = Beam::new(self.arena, &pose, &id.mount());
        let share = self.share.q30();
        // read too far from square: a reading within the noise, no
        // derivative (`cfg::MAX_INCIDENCE_DEG`)
        if self.share.read_normal(&beam) < MIN_NORMAL {
            return Row::new(ONE_SIGMA, Loss::Robust);
        }
        let spread = i64::from(beam.spot_spread(z).0);
        let nu = i64::from(beam.normal_miss(z).0).saturating_sub(mul_shr(spread, share, 30));
        // d(nu)/d(reference point) is +1 along the wall's normal for the
        // north and east walls, -1 for the others; d(nu)/d(heading) is
        // minus that times the beam's lever (`Beam::heading_lever`)
        let north_or_east = matches!(beam.wall, Wall::North | Wall::East);
        let signed = |v: i64| if north_or_east { v } else { v.saturating_neg() };
        let on_x = beam.wall.is_x_wall();
        let (toward, swing) = if on_x { (c, mul_shr(d, -s, 30)) } else { (s, mul_shr(d, c, 30)) };
        let turning = match self.share {
            // the cone's nearest point: the beam's own lever
            Share::Nearest => signed(i64::from(beam.heading_lever(z).0)).saturating_neg(),
            // the axis's: its incidence changes too, by a difference
            // (one more beam, for the derivatives only)
            Share::Axis if derivatives => {
                let turned = Pose::new(pose.x, pose.y, theta.wrapping_add(Angle(TURN_STEP as u32)));
                let beam = Beam::new(self.arena, &turned, &id.mount());
                let spread = i64::from(beam.spot_spread(z).0);
                let turned_nu = i64::from(beam.normal_miss(z).0).saturating_sub(spread);
                mul_shr(turned_nu.saturating_sub(nu), PER_TURN_STEP, 0)
            }
            Share::Axis => 0,
        };
        let per_rad = signed(swing).saturating_add(turning);
        let per_mrad = mul_shr(per_rad, PER_MRAD, 30);
        let inv = self.inverse_sigma(&beam, z);
        let per = |v: i64| mul_shr(v, inv, 28);
        let (px, py) = if on_x { (signed(MM), 0) } else { (0, signed(MM)) };
        let dt = per(per_mrad);
        let row = Row::new(per(nu), Loss::Robust);
        let row = if on_x { row.with(PX, per(px)) } else { row.with(PY, per(py)) };
        let row = row.with(LEVER, per(signed(toward) >> 14));
        let row = row.with(at.from.0, mul_shr(dt, at.from.1, 16));
        let row = if at.to.1 != 0 { row.with(at.to.0, mul_shr(dt, at.to.1, 16)) } else { row };
        chords.iter().fold(row, |row, &(k, cx, cy)| row.with(k, per(signed(if on_x { cx } else { cy }) >> 14)))
    }

    /// How the pivot's moves shift the reference point at `at`: each turn
    /// still ahead moves it by its move times its chord (the heading's
    /// unit vector at the turn's start less the one at its end, Q30), the
    /// turn under way by the chord from `at` on (`unit_at`: the heading's
    /// unit vector at `at`, cos and sin, Q30). (parameter, chord x, chord
    /// y).
    fn chords(
        &self,
        units: &Units,
        at: &At,
        unit_at: (i64, i64),
    ) -> heapless::Vec<(usize, i64, i64), { FIT_VIEWS - 1 }> {
        let turns = self.views.len().min(FIT_VIEWS).saturating_sub(1);
        let unit = |i: usize| units.get(i).map_or((0, 0), |&(c, s)| (i64::from(c), i64::from(s)));
        let mut out = heapless::Vec::new();
        let mut push = |k: usize, a: (i64, i64), b: (i64, i64)| {
            let _ = out.push((MOVE.saturating_add(k), a.0.saturating_sub(b.0), a.1.saturating_sub(b.1)));
        };
        if let Some(j) = at.turning {
            push(j, unit_at, unit(j.saturating_add(1)));
        }
        for k in at.ahead..turns {
            push(k, unit(k), unit(k.saturating_add(1)));
        }
        out
    }

    /// `2^40 / sigma` of a reading `z` along its wall's normal (Q16 mm): the
    /// range's variance (the model's spread, the incidence's at that
    /// range, a corner's) times the squared cosine the miss is measured
    /// with (the cone's nearest point's, or the axis's:
    /// `Share::read_normal`).
    fn inverse_sigma(&self, beam: &Beam, z: Length) -> i64 {
        let axis = i64::from(beam.normal);
        let axis2 = mul_shr(axis, axis, 30);
        let tan2 = quotient(Q30.saturating_sub(axis2) as u32, axis2.max(0) as u64, 16).min(TAN2_MAX as u64) as i64;
        let spread = mul_shr(i64::from(z.0), SPREAD, 16);
        let mut var = LIDAR_VAR.saturating_add(mul_shr(mul_shr(spread, spread, 16), tan2, 16));
        if beam.near_corner(cfg::CORNER_MARGIN) {
            var = var.saturating_add(CORNER_VAR);
        }
        let cos = i64::from(self.share.read_normal(beam));
        let var = mul_shr(var, mul_shr(cos, cos, 30), 30);
        // Q8 from the variance's Q16, then Q16; at least a sixteenth of a
        // mm (a beam along the wall)
        let sigma = (isqrt(var.clamp(1, i64::from(u32::MAX)) as u32) << 8).max(1 << 12);
        quotient(1, u64::from(sigma), 40).min(i32::MAX as u64) as i64
    }
}
