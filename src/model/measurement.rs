//! The arena measurement model: what the two lidars and the compass should
//! read for a pose in a rectangular box.
//!
//! Frame (PAPERBOT): origin at a corner of the box, x to north along the
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
use crate::math::{mul_hi, mul_q30, sin_cos, Angle, Coord, Length};
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

/// The geometry of one lidar beam in the arena for one pose: which wall it
/// meets first, and how squarely.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub struct Beam {
    /// The wall the beam meets first.
    pub wall: Wall,
    /// Beam direction `phi` (clockwise from north).
    pub direction: Angle,
    /// `(sin phi, cos phi)` in Q2.30.
    pub sin: i32,
    pub cos: i32,
    /// `|cos incidence|` in Q2.30: `|cos phi|` for an x-wall, `|sin phi|`
    /// for a y-wall. 1 when the beam hits the wall square on.
    pub normal: i32,
    /// Distance from the beam origin to the wall, along the wall's normal
    /// (negative if the origin is outside the box).
    pub to_wall: Length,
    /// The other wall's distance along its own normal, and that wall's
    /// `|cos incidence|` (for the corner test).
    other_to_wall: Length,
    other_normal: i32,
    /// The mount's offset across its beam (`lateral`, see the module docs).
    pub lateral: Length,
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
        const ONE: i32 = 1 << 30;
        let ((sin, cos), (sd, cd)) = match mount.direction {
            Angle::ZERO => ((st, ct), (0, ONE)),
            Angle::QUARTER_TURN => ((ct, -st), (ONE, 0)),
            Angle::HALF_TURN => ((-st, -ct), (0, -ONE)),
            Angle(THREE_QUARTERS) => ((-ct, st), (-ONE, 0)),
            _ => (sin_cos(direction), sin_cos(mount.direction)),
        };
        // lateral = -forward sin(dir) + right cos(dir), in the car's frame
        // (exact for quarter turns; the negations saturate).
        let lateral = match mount.direction {
            Angle::ZERO => mount.right,
            Angle::QUARTER_TURN => Length::ZERO.saturating_sub(mount.forward),
            Angle::HALF_TURN => Length::ZERO.saturating_sub(mount.right),
            Angle(THREE_QUARTERS) => mount.forward,
            _ => Length(mul_q30(mount.right.0, cd).saturating_sub(mul_q30(mount.forward.0, sd))),
        };
        // Beam origin o = p + lateral (-sin phi, cos phi): the reference
        // point itself for a mount on its beam's line (both config mounts).
        let (px, py) = (coord_length(pose.x), coord_length(pose.y));
        let (ox, oy) = if lateral.0 == 0 {
            (px, py)
        } else {
            (px.saturating_sub(Length(mul_q30(lateral.0, sin))), py.saturating_add(Length(mul_q30(lateral.0, cos))))
        };
        let (x_wall, ax) = if cos >= 0 { (Wall::North, arena.length_x.saturating_sub(ox)) } else { (Wall::South, ox) };
        let (y_wall, ay) = if sin >= 0 { (Wall::East, arena.width_y.saturating_sub(oy)) } else { (Wall::West, oy) };
        // |sin|, |cos| <= 2^30: the absolute values cannot overflow.
        let (abs_s, abs_c) = (sin.wrapping_abs(), cos.wrapping_abs());
        // x-wall first when A_x / |c| <= A_y / |s|, i.e. A_x |s| <= A_y |c|
        // (a negative A, an origin outside the box, counts as 0).
        let tx = mul_hi(ax.0.max(0), abs_s);
        let ty = mul_hi(ay.0.max(0), abs_c);
        if tx <= ty {
            Beam {
                wall: x_wall,
                direction,
                sin,
                cos,
                normal: abs_c,
                to_wall: ax,
                other_to_wall: ay,
                other_normal: abs_s,
                lateral,
            }
        } else {
            Beam {
                wall: y_wall,
                direction,
                sin,
                cos,
                normal: abs_s,
                to_wall: ay,
                other_to_wall: ax,
                other_normal: abs_c,
                lateral,
            }
        }
    }

    /// How far past the wall, along its normal, a measured distance `z`
    /// (the lidar model's output) lands: `z |cos incidence| - to_wall`.
    /// Zero for a perfect reading; positive when the reading is longer than
    /// expected. `|cos incidence|` times the ordinary innovation
    /// `z - expected`, with no division.
    pub fn normal_miss(&self, z: Length) -> Length {
        Length(mul_q30(z.0, self.normal)).saturating_sub(self.to_wall)
    }

    /// True when the beam meets the wall at less than `max_incidence`
    /// from square on, given as its cosine in Q2.30.
    pub fn square_enough(&self, min_normal: i32) -> bool {
        self.normal >= min_normal
    }

    /// True when the ray passes within `margin` of a corner: its lengths to
    /// the two walls differ by less than `margin`. Division-free:
    /// `|A_x |s| - A_y |c|| < margin |c| |s|`.
    pub fn near_corner(&self, margin: Length) -> bool {
        // In Q14 mm by mul_hi (Q16 * Q30 / 2^32), each within 3 LSB
        // (2^-12 mm) below the exact product: A >= 0 and |c|, |s| <= 2^30
        // keep every product in [0, 2^29), their difference in i32.
        let a = mul_hi(self.to_wall.0.max(0), self.other_normal);
        let b = mul_hi(self.other_to_wall.0.max(0), self.normal);
        // |c s| in Q28 (<= 2^28), << 2 -> Q30; margin (Q16) times it -> Q14.
        let cs = mul_hi(self.normal, self.other_normal) << 2;
        (a - b).abs() < mul_hi(margin.0.max(0), cs)
    }

    /// The expected lidar model output (distance from the reference point
    /// along the beam): `to_wall / |cos incidence|`. `None` when the beam is
    /// closer than 1/1024 to parallel to the wall (the division would blow
    /// up; the beam then meets the other wall first anyway unless the box is
    /// degenerate). One 64-bit division: not for the robot's per-tick path.
    pub fn expected_distance(&self) -> Option<Length> {
        if self.normal < (1 << 20) {
            return None;
        }
        let num = i64::from(self.to_wall.0) << 30;
        let d = crate::math::div_i64(num, i64::from(self.normal)).unwrap_or(0);
        i32::try_from(d).ok().map(Length)
    }

    /// Where the ray ends on the wall, as a point (x, y) in mm (Length).
    /// For tests and the replay tool (one guarded division).
    pub fn hit_point(&self, pose: &Pose) -> Option<(Length, Length)> {
        let t = self.expected_distance()?;
        let (px, py) = (pose.x.to_length(), pose.y.to_length());
        let ox = px.saturating_sub(Length(mul_q30(self.lateral.0, self.sin)));
        let oy = py.saturating_add(Length(mul_q30(self.lateral.0, self.cos)));
        Some((ox.saturating_add(Length(mul_q30(t.0, self.cos))), oy.saturating_add(Length(mul_q30(t.0, self.sin)))))
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
