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

mod cone;

pub use cone::CORNER_MARGIN_MAX;

use crate::config;
use crate::math::{mul_q30, mul_q30_unsat, sin_cos, Angle, Coord, Length};
use crate::model::lidar::LidarMount;
use crate::model::state::Pose;
use cone::{cone_sine, mount_product, side_search, sides_clear, Corner, Incidence, COS_HALF_CONE, ONE};

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
        // a copy: `Pose::sin_cos` refreshes its cache, and only reads it when current
        Beam::at(arena, pose.x, pose.y, pose.theta, { *pose }.sin_cos(), mount)
    }

    /// [`Beam::new`] from a place, a heading and its sine and cosine (Q30).
    // tick bar: inlined into `new` and the estimator's row (one beam each)
    #[inline(always)]
    pub fn at(arena: &Arena, x: Coord, y: Coord, theta: Angle, (st, ct): (i32, i32), mount: &LidarMount) -> Beam {
        let direction = theta.wrapping_add(mount.direction);
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
        let lx = coord_length(x).saturating_add(Length(dx));
        let ly = coord_length(y).saturating_add(Length(dy));
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
    // tick bar (this and the next three): inlined into the estimator's
    // correction; the refinement, a second caller, had LLVM call them,
    // +38 instructions on the four-hypothesis tick (lx106/BENCHMARKS.md)
    #[inline(always)]
    pub fn normal_miss(&self, z: Length) -> Length {
        // 0 < cone_normal <= 2^30: the product is below |z + setback|
        Length(mul_q30_unsat(z.saturating_add(self.setback).0, self.cone_normal)).saturating_sub(self.to_wall)
    }

    /// How much longer than the cone's nearest point a reading `z` from the
    /// beam's axis is, along the wall's normal: `(z + setback)(cos_cone -
    /// cos_axis)`, at least 0 (0 met square on). Where in this spot the sensor's range comes
    /// from is learned (`model::estimator`'s spot.rs).
    #[inline(always)]
    pub fn spot_spread(&self, z: Length) -> Length {
        // 0 <= cone_normal - normal <= 2^30: the product is below |z + setback|
        Length(mul_q30_unsat(z.saturating_add(self.setback).0, self.cone_normal.saturating_sub(self.normal).max(0)))
    }

    /// `-d(normal_miss)/d(theta)` for a reading `z`, signed for the north and
    /// east walls (the south and west walls' is its negation), mm per rad
    /// (Q16): `(z + setback)` times the cone's sine with the sign of the
    /// incidence's change (0 inside the cone), plus the lidar position's
    /// share (see the module docs).
    #[inline(always)]
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
    use super::cone::{mul_cos, nearer_of};
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
