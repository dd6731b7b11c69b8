//! The arena measurement model: what the two lidars and the compass should
//! read for a pose in a rectangular box.
//!
//! Frame (fact sheet, `docs/paperbot.md`): origin at a corner of the box, x to north along the
//! box's `length_x`, y to east along its `width_y`, heading clockwise from
//! north. The walls are `x = 0` (south), `x = length_x` (north), `y = 0`
//! (west) and `y = width_y` (east).
//!
//! # What a lidar should read
//! A lidar sits at `mount` (mm forward and right of the car's reference
//! point) and looks along `phi = theta + mount.direction`, unit vector
//! `u = (cos phi, sin phi)`. The lidar model ([`crate::model::lidar`]) turns
//! its raw reading into a distance *from the car's reference point*, so the
//! expected model output is
//!
//! `expected = (ray length from the mount to the first wall) - setback`,
//!
//! where `setback = -(mount . beam)` is how far the mount sits behind the
//! reference point along its own beam (front lidar: 50 mm; right lidar:
//! 53 mm, with the config's mounts). Equivalently it is the ray length from
//! the *beam origin* `o = p + lateral * n`, the point of the beam's line
//! level with the reference point (`n = (-sin phi, cos phi)` is the beam's
//! right, `lateral` the mount's offset along it: 0 for both config mounts,
//! so `o` is the reference point itself). The two rays run along the same
//! line, so they meet the same wall whenever the beam origin is inside the
//! box (the reference point is part of the car, so it always is).
//!
//! The first wall met is found without a division: the ray reaches the
//! x-wall after `A_x / |cos phi|` and the y-wall after `A_y / |sin phi|`,
//! where `A` is the beam origin's distance to the wall it is heading for;
//! the x-wall is first when `A_x |sin phi| <= A_y |cos phi|`.
//!
//! The estimator does not divide by `|cos|`: it compares `z |n| - A` (how
//! far past the wall, along the wall's normal, a measured distance `z`
//! lands), which is zero for a perfect reading. [`Beam::expected_distance`]
//! does the division (guarded) for telemetry, the replay tool and tests.
//!
//! # What the compass should read
//! The heading itself: the compass model already turns the field into the
//! heading clockwise from north, in the same frame ([`expected_heading`]).

use crate::config;
use crate::math::{mul_hi, mul_q30, mul_q30_unsat, sin_cos, Angle, Coord, Length};
use crate::model::lidar::LidarMount;
use crate::model::state::Pose;

/// A rectangular arena with its origin at a corner (see the module docs).
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub struct Arena {
    /// Extent along x (north), mm.
    pub length_x: Length,
    /// Extent along y (east), mm.
    pub width_y: Length,
}

impl Arena {
    /// The team's box from the config (762.5 x 495 mm).
    pub const DEFAULT: Arena = Arena { length_x: config::arena::LENGTH_X, width_y: config::arena::WIDTH_Y };

    /// Its centre, facing north: where a robot that does not know where it
    /// is starts (with the estimator's initial uncertainty).
    pub fn centre(&self) -> crate::model::state::Pose {
        let half = |l: Length| crate::math::Coord::from_length(Length(l.0 / 2));
        crate::model::state::Pose::new(half(self.length_x), half(self.width_y), crate::math::Angle::ZERO)
    }
}

impl Default for Arena {
    fn default() -> Arena {
        Arena::DEFAULT
    }
}

/// Which lidar.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
pub enum LidarId {
    Front,
    Right,
}

impl LidarId {
    /// The lidar's mount from the config.
    pub const fn mount(self) -> LidarMount {
        match self {
            LidarId::Front => config::geometry::FRONT_LIDAR,
            LidarId::Right => config::geometry::RIGHT_LIDAR,
        }
    }
}

/// One of the four walls.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
pub enum Wall {
    /// `x = 0`.
    South,
    /// `x = length_x`.
    North,
    /// `y = 0`.
    West,
    /// `y = width_y`.
    East,
}

impl Wall {
    /// True for the walls of constant x (their normal is the x axis).
    pub const fn is_x_wall(self) -> bool {
        matches!(self, Wall::South | Wall::North)
    }
}

/// Three quarters of a turn, as an [`Angle`]'s bits.
const THREE_QUARTERS: u32 = 3 << 30;

/// [`Coord::to_length`] (rounded to nearest, saturated to +-32.7 m) without
/// the 64-bit saturating add: `(c + 2^15) >> 16` is `(c >> 16)` plus bit 15
/// of `c`, which cannot overflow (about 12 lx106 instructions against ~50).
// tick bar
#[inline(always)]
fn coord_length(c: Coord) -> Length {
    let v = (c.0 >> 16) + ((c.0 >> 15) & 1); // |c >> 16| <= 2^47
    let lo = v as i32;
    if i64::from(lo) == v {
        Length(lo)
    } else if v < 0 {
        Length(i32::MIN)
    } else {
        Length::MAX
    }
}

/// cos and sin of half the lidar's cone (Q2.30), from the config.
const COS_HALF_CONE: i32 = crate::math::round_f64(
    crate::math::cos_f64(config::lidar::CONE_DEG / 2.0 * core::f64::consts::TAU / 360.0) * 1_073_741_824.0,
) as i32;
const SIN_HALF_CONE: i32 = crate::math::round_f64(
    crate::math::cos_f64((90.0 - config::lidar::CONE_DEG / 2.0) * core::f64::consts::TAU / 360.0) * 1_073_741_824.0,
) as i32;
const ONE: i32 = 1 << 30;

/// The cone's incidences on a wall, from the axis's `|cos|` and `|sin|`
/// (Q2.30) on it, `n` and `t`, and the half cone `h`: the cone's direction
/// nearest the normal of the wall ahead meets it at `cos(a - h) = n cos h +
/// t sin h` (square on, 1, when the normal is inside the cone: `n >= cos
/// h`), the wall behind at `cos(pi - a - h) = t sin h - n cos h`; the
/// sines are `t cos h - n sin h` and `t cos h + n sin h`.
// tick bar: the products only where a wall is met off square (a wall
// square ahead needs none), each pair shared by the wall behind
#[derive(Clone, Copy)]
struct Incidence {
    /// `n cos h` and `t sin h`.
    n_ch: i32,
    t_sh: i32,
}

// tick bar: Incidence and sides_clear are inlined into `Beam::new`, on a
// lidar correction's path
impl Incidence {
    #[inline(always)]
    fn new(n: i32, t: i32) -> Incidence {
        // |n|, |t| <= 2^30 and the half cone's below: each product below 2^30
        Incidence { n_ch: mul_q30_unsat(n, COS_HALF_CONE), t_sh: mul_q30_unsat(t, SIN_HALF_CONE) }
    }
    /// The cosine toward the wall ahead (off square) or behind.
    #[inline(always)]
    fn cos(&self, ahead: bool) -> i32 {
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
fn cone_sine(n: i32, t: i32, ahead: bool) -> i32 {
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
fn nearer_of(n: i32, t: i32, a: Length, b: Length) -> (bool, Length, i32) {
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
fn mul_cos(a: i32, n: i32) -> i32 {
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
fn mount_product(l: Length, t: i32) -> i32 {
    if l.0 == 0 {
        0
    } else {
        mul_q30_unsat(l.0, t) // |t| <= 2^30: below |l|
    }
}

/// The largest margin [`Beam::near_corner`] tells apart: twice the
/// estimator's (larger margins are taken as this one).
pub const CORNER_MARGIN_MAX: Length = Length(config::estimator::CORNER_MARGIN.0 * 2);

/// The cone's other candidate wall, for [`Beam::near_corner`].
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
enum Corner {
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
const SIDE_ALLOWANCE: i32 = 1 << 20;

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
fn sides_clear(ahead: Length, side: Length, t: i32, cone_normal: i32) -> bool {
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
fn side_search(
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

/// The geometry of one lidar reading in the arena for one pose: which wall
/// the nearest point in the lidar's cone is on, and how the reading
/// depends on the pose (see the module docs).
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub struct Beam {
    /// The wall the nearest point in the cone is on.
    pub wall: Wall,
    /// Beam (axis) direction `phi` (clockwise from north).
    pub direction: Angle,
    /// `(sin phi, cos phi)` in Q2.30.
    pub sin: i32,
    pub cos: i32,
    /// `|cos incidence|` of the axis on the wall in Q2.30. 1 when the beam
    /// hits the wall square on.
    pub normal: i32,
    /// The cone's: cos of the incidence of the cone's direction nearest the
    /// wall's normal (1 inside the cone; see `Incidence`), and its sine.
    pub cone_normal: i32,
    cone_tangent: i32,
    /// Distance from the lidar to the wall, along the wall's normal
    /// (negative if the lidar is outside the box).
    pub to_wall: Length,
    /// How near the cone's other candidate wall is (for the corner test;
    /// not searched when it is clear by [`CORNER_MARGIN_MAX`]).
    corner: Corner,
    /// How far the lidar sits behind the reference point along its beam
    /// (the model output is the range from the lidar less this).
    pub setback: Length,
    /// The lidar position's share of `d(reading)/d(heading)` (see
    /// [`Beam::heading_lever`]).
    mount_lever: Length,
}

impl Beam {
    /// The beam of `mount` for `pose` in `arena`. No division; the sine and
    /// cosine of the heading come from the pose's cache (one [`sin_cos`]
    /// when it is stale), turned by the mount's direction: exactly for a
    /// multiple of a quarter turn (both of the config's mounts), otherwise by
    /// two more [`sin_cos`].
    pub fn new(arena: &Arena, pose: &Pose, mount: &LidarMount) -> Beam {
        let direction = pose.theta.wrapping_add(mount.direction);
        // a copy: `Pose::sin_cos` refreshes its cache, and only reads it when current
        let (st, ct) = { *pose }.sin_cos();
        // |sin|, |cos| <= 2^30: the negations cannot overflow.
        let ((sin, cos), (sd, cd)) = match mount.direction {
            Angle::ZERO => ((st, ct), (0, ONE)),
            Angle::QUARTER_TURN => ((ct, -st), (ONE, 0)),
            Angle::HALF_TURN => ((-st, -ct), (0, -ONE)),
            Angle(THREE_QUARTERS) => ((-ct, st), (-ONE, 0)),
            _ => (sin_cos(direction), sin_cos(mount.direction)),
        };
        // setback = -(mount . beam) in the car's frame (exact for quarter turns)
        let (f, r) = (mount.forward, mount.right);
        let setback = match mount.direction {
            Angle::ZERO => Length::ZERO.saturating_sub(f),
            Angle::QUARTER_TURN => Length::ZERO.saturating_sub(r),
            Angle::HALF_TURN => f,
            Angle(THREE_QUARTERS) => r,
            _ => Length(-(mul_q30(f.0, cd).saturating_add(mul_q30(r.0, sd)))),
        };
        // The lidar: p + f (cos th, sin th) + r (-sin th, cos th); each
        // component's products only when it is not zero (each config mount
        // has one). fx = f cos - r sin, fy = f sin + r cos.
        let dx = mount_product(f, ct).saturating_sub(mount_product(r, st));
        let dy = mount_product(f, st).saturating_add(mount_product(r, ct));
        let lx = coord_length(pose.x).saturating_add(Length(dx));
        let ly = coord_length(pose.y).saturating_add(Length(dy));
        // |sin|, |cos| <= 2^30: the absolute values cannot overflow.
        let (abs_s, abs_c) = (sin.wrapping_abs(), cos.wrapping_abs());
        let (north, south) = (arena.length_x.saturating_sub(lx), lx);
        let (east, west) = (arena.width_y.saturating_sub(ly), ly);
        // The wall the axis heads for on the axis it runs nearer (x when
        // |cos| >= |sin|): its cone's cosine, and whether the side walls are
        // clear of the cone ahead of it (see `sides_clear`). Then the side
        // walls need none of the cone's work.
        // tick bar: beams from the middle of the box are such
        let x_main = abs_c >= abs_s;
        let (x_ahead, x_behind) = if cos >= 0 { (north, south) } else { (south, north) };
        let (y_ahead, y_behind) = if sin >= 0 { (east, west) } else { (west, east) };
        let (n, t, ahead, side_ahead, side_behind) = if x_main {
            (abs_c, abs_s, x_ahead, y_ahead, y_behind)
        } else {
            (abs_s, abs_c, y_ahead, x_ahead, x_behind)
        };
        // n >= 1/sqrt(2): the wall behind is out of the cone
        let cone_normal = if n >= COS_HALF_CONE { ONE } else { Incidence::new(n, t).cos(true) };
        let (on_side, behind, normal, cone_normal, cone_tangent, to_wall, corner) =
            if sides_clear(ahead, side_ahead.min(side_behind), t, cone_normal) {
                (false, false, n, cone_normal, cone_sine(n, t, true), ahead, Corner::Clear)
            } else {
                side_search(x_main, (n, t), (ahead, cone_normal), side_ahead, side_behind)
            };
        // the wall met: on the x axis when the main axis is x and the main
        // wall is met, or the main axis is y and a side wall is
        let wall = match (x_main != on_side, cos >= 0, sin >= 0, behind) {
            (true, true, _, false) | (true, false, _, true) => Wall::North,
            (true, _, _, _) => Wall::South,
            (false, _, true, false) | (false, _, false, true) => Wall::East,
            (false, _, _, _) => Wall::West,
        };
        // d(to_wall)/d(theta) with the sign the module docs give the lever:
        // x-walls f sin th + r cos th = dy, y-walls -(f cos th - r sin th) = -dx
        let mount_lever = if wall.is_x_wall() { dy } else { dx.saturating_neg() };
        Beam {
            wall,
            direction,
            sin,
            cos,
            normal,
            cone_normal,
            cone_tangent,
            to_wall,
            corner,
            setback,
            mount_lever: Length(mount_lever),
        }
    }

    /// How far past the wall, along its normal, a measured distance `z`
    /// (the lidar model's output) lands: `(z + setback) cos - to_wall`, with
    /// `cos` the cone's incidence ([`Beam::cone_normal`]). Zero for a
    /// perfect reading; positive when the reading is longer than expected.
    /// The cone's cosine times the ordinary innovation `z - expected`, with
    /// no division.
    pub fn normal_miss(&self, z: Length) -> Length {
        // 0 < cone_normal <= 2^30: the product is below |z + setback|
        Length(mul_q30_unsat(z.saturating_add(self.setback).0, self.cone_normal)).saturating_sub(self.to_wall)
    }

    /// How much longer than the cone's nearest point a reading `z` from the
    /// beam's axis is, along the wall's normal: `(z + setback)(cos_cone -
    /// cos_axis)`, at least 0 (0 met square on). Where in this spot the sensor's range comes
    /// from is learned (`model::estimator`'s spot.rs).
    pub fn spot_spread(&self, z: Length) -> Length {
        // 0 <= cone_normal - normal <= 2^30: the product is below |z + setback|
        Length(mul_q30_unsat(z.saturating_add(self.setback).0, self.cone_normal.saturating_sub(self.normal).max(0)))
    }

    /// `-d(normal_miss)/d(theta)` for a reading `z`, signed for the north and
    /// east walls (the south and west walls' is its negation), mm per rad
    /// (Q16): `(z + setback)` times the cone's sine with the sign of the
    /// incidence's change (0 inside the cone), plus the lidar position's
    /// share (see the module docs).
    pub fn heading_lever(&self, z: Length) -> Length {
        let range = z.saturating_add(self.setback).0;
        let turn = if self.cone_tangent == 0 {
            0
        } else {
            // x-walls: sign(sin phi); y-walls: -sign(cos phi)
            // 0 <= cone_tangent <= 2^30: the product is below |range|
            let t = mul_q30_unsat(range, self.cone_tangent);
            let up = if self.wall.is_x_wall() { self.sin >= 0 } else { self.cos < 0 };
            if up {
                t
            } else {
                t.wrapping_neg()
            }
        };
        Length(turn).saturating_add(self.mount_lever)
    }

    /// True when the beam's axis meets the wall at less than
    /// `max_incidence` from square on, given as its cosine in Q2.30.
    pub fn square_enough(&self, min_normal: i32) -> bool {
        self.normal >= min_normal
    }

    /// True when the nearest points in the cone on the two candidate walls
    /// are less than `margin` (at most [`CORNER_MARGIN_MAX`]) apart in
    /// range. Division-free:
    /// `|A_x n_y - A_y n_x| < margin n_x n_y` with the cone cosines `n`.
    pub fn near_corner(&self, margin: Length) -> bool {
        let Corner::Cross { cross, other_cross, other_normal } = self.corner else {
            return false;
        };
        // The products were made choosing the wall: in Q14 mm by mul_hi
        // (Q16 * Q30 / 2^32), each within 3 LSB (2^-12 mm) below the exact
        // one; A >= 0 and 0 <= n <= 2^30 keep each in [0, 2^29), their
        // difference in i32.
        // n n in Q28 (<= 2^28), << 2 -> Q30; margin (Q16) times it -> Q14.
        let cs = mul_cos(other_normal, self.cone_normal) << 2;
        let margin = margin.0.clamp(0, CORNER_MARGIN_MAX.0);
        (cross - other_cross).abs() < mul_hi(margin, cs)
    }

    /// The expected lidar model output (distance from the reference point
    /// along the beam): `to_wall / cone_normal - setback`. `None` when the
    /// cone's cosine is below 1/1024 (the division would blow up). One
    /// 64-bit division: not for the robot's per-tick path.
    pub fn expected_distance(&self) -> Option<Length> {
        if self.cone_normal < (1 << 20) {
            return None;
        }
        let num = i64::from(self.to_wall.0) << 30;
        let d = crate::math::div_i64(num, i64::from(self.cone_normal)).unwrap_or(0);
        i32::try_from(d).ok().map(|d| Length(d).saturating_sub(self.setback))
    }
}

/// The expected lidar model output for `which` at `pose`, or `None` for a
/// beam parallel to a wall (see [`Beam::expected_distance`]).
pub fn expected_lidar(arena: &Arena, pose: &Pose, which: LidarId) -> Option<Length> {
    Beam::new(arena, pose, &which.mount()).expected_distance()
}

/// The expected compass heading: the pose's heading (the compass model
/// already gives the heading clockwise from north in the arena's frame).
pub fn expected_heading(pose: &Pose) -> Angle {
    pose.theta
}

#[cfg(test)]
#[allow(clippy::restriction)] // test code: a panic fails the test
mod tests {
    use super::*;

    /// The reference: the wall the nearest point in the cone is on, found
    /// with the cone's products on both axes (the walls' distances along
    /// their normals from the lidar, the axis's sine and cosine): the wall,
    /// the axis's and the cone's cosines on it, the cone's sine, its
    /// distance and the corner test.
    fn cone_walls(
        north: Length,
        south: Length,
        east: Length,
        west: Length,
        sin: i32,
        cos: i32,
    ) -> (Wall, i32, i32, i32, Length, Corner) {
        // |sin|, |cos| <= 2^30: the absolute values cannot overflow.
        let (abs_s, abs_c) = (sin.wrapping_abs(), cos.wrapping_abs());
        // Each axis: the wall the axis heads for, or the one behind when the
        // axis runs within half the cone of parallel and that one is nearer.
        let (x_far, ax, nx) =
            if cos >= 0 { nearer_of(abs_c, abs_s, north, south) } else { nearer_of(abs_c, abs_s, south, north) };
        let x_wall = match (cos >= 0, x_far) {
            (true, false) | (false, true) => Wall::North,
            _ => Wall::South,
        };
        let (y_far, ay, ny) =
            if sin >= 0 { nearer_of(abs_s, abs_c, east, west) } else { nearer_of(abs_s, abs_c, west, east) };
        let y_wall = match (sin >= 0, y_far) {
            (true, false) | (false, true) => Wall::East,
            _ => Wall::West,
        };
        // The x-wall is nearer in the cone when A_x / n_x <= A_y / n_y, i.e.
        // A_x n_y <= A_y n_x (a negative A, a lidar outside the box, counts
        // as 0; a wall out of the cone, n <= 0, is never nearer).
        let (ax_ny, ay_nx) = (mul_cos(ax.0.max(0), ny.max(0)), mul_cos(ay.0.max(0), nx.max(0)));
        let x_first = ny <= 0 || (nx > 0 && ax_ny <= ay_nx);
        let (wall, normal, cone_normal, to_wall, cross, other_cross, other_normal) =
            if x_first { (x_wall, abs_c, nx, ax, ax_ny, ay_nx, ny) } else { (y_wall, abs_s, ny, ay, ay_nx, ax_ny, nx) };
        let cone_tangent = if x_first { cone_sine(abs_c, abs_s, !x_far) } else { cone_sine(abs_s, abs_c, !y_far) };
        let corner = Corner::Cross { cross, other_cross, other_normal: other_normal.max(1) };
        (wall, normal, cone_normal.max(1), cone_tangent, to_wall, corner)
    }

    /// `Beam::new` (the side walls spared when `sides_clear`, else
    /// `side_search`) decides exactly as the full search on both axes
    /// ([`cone_walls`]): the same wall, cosines, sine and distance, and the
    /// same corner test (none within the largest margin when spared). Poses
    /// every 15 x 10 mm and 1 degree over the box, both mounts.
    #[test]
    fn beam_decides_as_the_full_search() {
        let arena = Arena::DEFAULT;
        let (mut clear, mut full) = (0u32, 0u32);
        for x in (5..760).step_by(15) {
            for y in (5..495).step_by(10) {
                for deg in 0..360 {
                    let pose = Pose::from_mm(x, y, Angle::from_millidegrees(deg * 1000));
                    for id in [LidarId::Front, LidarId::Right] {
                        let beam = Beam::new(&arena, &pose, &id.mount());
                        let mount = id.mount();
                        let (st, ct) = { pose }.sin_cos();
                        let dx = mount_product(mount.forward, ct).saturating_sub(mount_product(mount.right, st));
                        let dy = mount_product(mount.forward, st).saturating_add(mount_product(mount.right, ct));
                        let px = coord_length(pose.x).saturating_add(Length(dx));
                        let py = coord_length(pose.y).saturating_add(Length(dy));
                        let (north, south) = (arena.length_x.saturating_sub(px), px);
                        let (east, west) = (arena.width_y.saturating_sub(py), py);
                        let (wall, normal, cone_normal, cone_tangent, to_wall, corner) =
                            cone_walls(north, south, east, west, beam.sin, beam.cos);
                        let at = (x, y, deg, id);
                        assert_eq!(
                            (wall, normal, cone_normal, cone_tangent, to_wall),
                            (beam.wall, beam.normal, beam.cone_normal, beam.cone_tangent, beam.to_wall),
                            "{at:?}"
                        );
                        if beam.corner == Corner::Clear {
                            clear += 1;
                            assert!(!Beam { corner, ..beam }.near_corner(CORNER_MARGIN_MAX), "{at:?}");
                        } else {
                            full += 1;
                            assert_eq!(beam.corner, corner, "{at:?}");
                        }
                    }
                }
            }
        }
        // both ways are taken (about a third of these beams take the short one)
        assert!(clear > 0 && full > 0, "{clear} clear, {full} searched");
    }
}
