//! The effects that make the simulated robot as hard as the real one
//! (host only, f64), each an option of `simulate` with its default from the
//! lab's data where the lab measured it ([`crate::config::sim`]):
//!
//! - the whole body stays in the box: the reference point, both wheels, the
//!   skid and both lidars (a motion that would take any of them through a
//!   wall is refused: a collision);
//! - trial-to-trial speed spread: each new motion runs at its line's speed
//!   times a factor drawn once for that motion (one sigma per motion as
//!   the lab's timed runs of one command pair spread, `servo_runs.csv`);
//! - turns about a point off the axle: the paper skid drags, so a turn in
//!   place pivots about a point behind the axle's midpoint, drawn per turn;
//! - the VL53L0X's cone: a reading is the nearest wall point within the
//!   cone, not the length of a thin ray;
//! - glancing readings fail: past an incidence the return is too weak, and
//!   a reading is lost (no target) or spurious (a short or long echo);
//! - compass disturbance: the field is bent by what is under and around the
//!   box, a heading error that varies smoothly over the floor.

use super::arena::Arena;
use super::body::{wrap_pi, MotionF64};
use super::noise::Rng;
use crate::config::sim as cfg;

/// The effects' settings (see the module docs); [`Realism::IDEAL`] turns
/// them all off but the cone (the rigid, undisturbed robot).
#[derive(Clone, Copy, PartialEq, Debug)]
pub struct Realism {
    /// Keep the lidars and the skid inside the box too (not only the
    /// reference point and the wheels).
    pub whole_body: bool,
    /// Speed factor spread per motion, one sigma (fraction): forward,
    /// backward, clockwise, counter-clockwise.
    pub speed_spread: [f64; 4],
    /// Turns pivot this far behind the axle's midpoint on average, mm.
    pub pivot_behind_mm: f64,
    /// Spread of that point from turn to turn, one sigma, mm.
    pub pivot_spread_mm: f64,
    /// The lidar's full cone angle, degrees (0: a thin ray).
    pub cone_deg: f64,
    /// Incidence (of the beam's axis on the wall it reads) past which
    /// readings start failing, degrees; all fail at 90. 90: none fail.
    pub glancing_deg: f64,
    /// Of the failed readings, the share that is a spurious echo rather
    /// than "no target".
    pub spurious_share: f64,
    /// Compass disturbance: amplitude of the heading error over the
    /// floor, degrees.
    pub compass_disturbance_deg: f64,
}

impl Realism {
    /// Everything off but the lidar's cone, which is the sensor's geometry
    /// (the firmware's measurement model has it too); `cone_deg: 0.0` for
    /// thin rays.
    pub const IDEAL: Realism = Realism {
        whole_body: false,
        speed_spread: [0.0; 4],
        pivot_behind_mm: 0.0,
        pivot_spread_mm: 0.0,
        cone_deg: cfg::LIDAR_CONE_DEG,
        glancing_deg: 90.0,
        spurious_share: 0.0,
        compass_disturbance_deg: 0.0,
    };
    /// The lab's robot ([`crate::config::sim`]).
    pub const LAB: Realism = Realism {
        whole_body: true,
        speed_spread: cfg::SPEED_SPREAD,
        pivot_behind_mm: cfg::PIVOT_BEHIND_AXLE_MM,
        pivot_spread_mm: cfg::PIVOT_SPREAD_MM,
        cone_deg: cfg::LIDAR_CONE_DEG,
        glancing_deg: cfg::GLANCING_DEG,
        spurious_share: cfg::SPURIOUS_SHARE,
        compass_disturbance_deg: cfg::COMPASS_DISTURBANCE_DEG,
    };
}

impl Default for Realism {
    fn default() -> Realism {
        Realism::LAB
    }
}

/// What a motion's trial draws once: its speed factor and, for a turn, its
/// pivot's distance behind the axle.
#[derive(Clone, Copy, PartialEq, Debug)]
pub struct Trial {
    /// The motion the draw is for (a new motion draws again).
    motion: MotionF64,
    pub speed_factor: f64,
    pub pivot_behind_mm: f64,
}

impl Trial {
    pub const NONE: Trial = Trial { motion: MotionF64::Stop, speed_factor: 1.0, pivot_behind_mm: 0.0 };

    /// The trial for `motion`: this one while the motion is the same, else a
    /// new draw.
    pub fn for_motion(self, motion: MotionF64, r: &Realism, rng: &mut Rng) -> Trial {
        if motion == self.motion {
            return self;
        }
        let spread = match motion {
            MotionF64::Stop => 0.0,
            MotionF64::Straight(v) if v >= 0.0 => r.speed_spread[0],
            MotionF64::Straight(_) => r.speed_spread[1],
            MotionF64::Turn(w) if w >= 0.0 => r.speed_spread[2],
            MotionF64::Turn(_) => r.speed_spread[3],
        };
        let pivot =
            if matches!(motion, MotionF64::Turn(_)) { r.pivot_behind_mm + rng.gauss(r.pivot_spread_mm) } else { 0.0 };
        Trial { motion, speed_factor: 1.0 + rng.gauss(spread), pivot_behind_mm: pivot }
    }
}

/// What a lidar at (x, y) looking along `dir` (radians clockwise from
/// north) reads: the distance to the nearest wall point within the cone
/// and the incidence of the beam's axis on the wall that point is on
/// (radians); `None` when nothing is in the cone.
pub fn lidar_range(arena: &Arena, x: f64, y: f64, dir: f64, r: &Realism) -> Option<(f64, f64)> {
    let half = r.cone_deg.to_radians() / 2.0;
    if half <= 0.0 || !arena.contains(x, y) {
        let t = arena.ray_cast(x, y, dir)?;
        return Some((t, incidence_of_ray(arena, x, dir, t)));
    }
    // each wall: its outward normal's direction and the distance to it
    let walls = [
        (0.0, arena.length_x_mm() - x),
        (core::f64::consts::PI, x),
        (core::f64::consts::FRAC_PI_2, arena.width_y_mm() - y),
        (-core::f64::consts::FRAC_PI_2, y),
    ];
    let mut best: Option<(f64, f64)> = None;
    for (normal, a) in walls {
        let alpha = wrap_pi(dir - normal); // the beam's incidence on this wall
                                           // the cone's direction nearest the wall's normal
        let off = alpha.abs() - half;
        let (t, ray) = if off <= 0.0 {
            (a, normal)
        } else if off < core::f64::consts::FRAC_PI_2 {
            (a / off.cos(), normal + alpha.signum() * off)
        } else {
            continue;
        };
        // the point must be on this wall, not beyond a corner (where the
        // other wall is nearer anyway)
        let (px, py) = (x + t * ray.cos(), y + t * ray.sin());
        if px < -1e-6 || py < -1e-6 || px > arena.length_x_mm() + 1e-6 || py > arena.width_y_mm() + 1e-6 {
            continue;
        }
        if best.is_none_or(|(b, _)| t < b) {
            best = Some((t, alpha.abs()));
        }
    }
    best
}

/// The incidence of a thin ray of length `t` on the wall it ends on.
fn incidence_of_ray(arena: &Arena, x: f64, dir: f64, t: f64) -> f64 {
    let (s, c) = dir.sin_cos();
    let px = x + t * c;
    let on_x_wall = px.abs() < 1e-6 || (px - arena.length_x_mm()).abs() < 1e-6;
    if on_x_wall {
        c.abs().acos()
    } else {
        s.abs().acos()
    }
}

/// Whether a reading at `incidence` (radians) fails, and how: `None` for a
/// good reading, `Some(None)` for "no target", `Some(Some(factor))` for a
/// spurious echo at `factor` times the true distance. The chance of failing
/// grows linearly from 0 at `glancing_deg` to 1 at 90 degrees.
pub fn glancing_failure(incidence: f64, r: &Realism, rng: &mut Rng) -> Option<Option<f64>> {
    let start = r.glancing_deg.to_radians();
    let right = core::f64::consts::FRAC_PI_2;
    if incidence <= start || start >= right {
        return None;
    }
    if !rng.chance(((incidence - start) / (right - start)).min(1.0)) {
        return None;
    }
    if rng.chance(r.spurious_share) {
        Some(Some(rng.range_f64(0.3, 1.5)))
    } else {
        Some(None)
    }
}

/// The compass's heading error at (x, y) mm, radians: a smooth pattern over
/// the floor with the configured amplitude (two waves across the box, a
/// different phase per seed).
pub fn compass_disturbance(x: f64, y: f64, r: &Realism, phase: f64) -> f64 {
    let k = core::f64::consts::TAU / cfg::COMPASS_DISTURBANCE_WAVELENGTH_MM;
    let a = r.compass_disturbance_deg.to_radians();
    a * (0.6 * (k * x + phase).sin() + 0.4 * (k * y - 2.0 * phase).cos())
}
