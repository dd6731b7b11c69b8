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
//!
//! Three worlds ([`Realism::named`], `simulate --realism`):
//! - [`Realism::IDEAL`] (`--ideal`): the exact robot, the model's own
//!   world (rigid turns about the axle, the lines' speeds, the sensor's
//!   cone, an undisturbed compass): what the estimator must track exactly;
//! - [`Realism::LAB`] (`lab`, today's default): the lab's beliefs, each
//!   effect at what the lab measured or assumed (above);
//! - [`Realism::HARD`] (`hard`): what real drives meet and the lab did not
//!   measure (issue #29), each run drawing its own robot from its seed
//!   ([`super::drawn::Drawn`]): each turn direction's rate off the lab's
//!   line by a factor in 0.6 to 1.8, drifting slowly; the straight speed
//!   off by up to 15 %; the pivot 60 +- 20 mm behind the axle; a compass
//!   bias over the floor up to 12 degrees, 20 near the walls; the lidars a
//!   thin beam whose noise grows with incidence, 5 % spurious readings and
//!   mixed returns where the beam's footprint spans a corner. The default
//!   stays [`Realism::LAB`] until the estimator copes with this world.

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
    /// Each turn direction's rate factor, drawn per run uniformly in
    /// (lo, hi); (1, 1): the lab's lines.
    pub turn_scale: (f64, f64),
    /// That factor's slow drift, fraction of itself (0: none) ...
    pub turn_drift: f64,
    /// ... over this period, s.
    pub turn_drift_period_s: f64,
    /// Straight speed factor drawn per run uniformly within this of 1.
    pub speed_scale: f64,
    /// The pivot's mean moves per run uniformly within this, mm.
    pub pivot_run_mm: f64,
    /// The compass's heading error reaches this near the walls, degrees
    /// (no more than `compass_disturbance_deg`: no wall excursion) ...
    pub compass_wall_deg: f64,
    /// ... falling off by e over this distance from the wall, mm ...
    pub compass_wall_decay_mm: f64,
    /// ... in a pattern of this wavelength along the walls, mm.
    pub compass_wall_wavelength_mm: f64,
    /// Lidar noise growing with incidence: one sigma of this fraction of
    /// the range times tan(incidence) (0: none).
    pub lidar_incidence_noise: f64,
    /// Share of all lidar readings that are spurious echoes (0 to 1).
    pub spurious_rate: f64,
    /// A beam whose footprint, this half-angle about its axis (degrees),
    /// spans two walls returns a mix of their ranges (0: none).
    pub corner_mix_half_deg: f64,
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
        turn_scale: (1.0, 1.0),
        turn_drift: 0.0,
        turn_drift_period_s: cfg::HARD_TURN_DRIFT_PERIOD_S,
        speed_scale: 0.0,
        pivot_run_mm: 0.0,
        compass_wall_deg: 0.0,
        compass_wall_decay_mm: cfg::HARD_COMPASS_WALL_DECAY_MM,
        compass_wall_wavelength_mm: cfg::HARD_COMPASS_WALL_WAVELENGTH_MM,
        lidar_incidence_noise: 0.0,
        spurious_rate: 0.0,
        corner_mix_half_deg: 0.0,
    };
    /// The lab's robot ([`crate::config::sim`]): its beliefs, none of the
    /// hard world's effects.
    pub const LAB: Realism = Realism {
        whole_body: true,
        speed_spread: cfg::SPEED_SPREAD,
        pivot_behind_mm: cfg::PIVOT_BEHIND_AXLE_MM,
        pivot_spread_mm: cfg::PIVOT_SPREAD_MM,
        glancing_deg: cfg::GLANCING_DEG,
        spurious_share: cfg::SPURIOUS_SHARE,
        compass_disturbance_deg: cfg::COMPASS_DISTURBANCE_DEG,
        ..Realism::IDEAL
    };
    /// What real drives meet (issue #29; [`crate::config::sim`]'s `HARD_*`):
    /// the lab's effects, then each turn direction's rate, the speed, the
    /// pivot and the compass's bias drawn per run far from the lab's
    /// beliefs, and the lidars a thin beam with noise growing with
    /// incidence, spurious readings and mixed returns near corners.
    pub const HARD: Realism = Realism {
        whole_body: true,
        speed_spread: cfg::SPEED_SPREAD,
        pivot_behind_mm: cfg::HARD_PIVOT_BEHIND_AXLE_MM,
        pivot_spread_mm: cfg::PIVOT_SPREAD_MM,
        cone_deg: 0.0,
        glancing_deg: cfg::GLANCING_DEG,
        spurious_share: cfg::SPURIOUS_SHARE,
        compass_disturbance_deg: cfg::HARD_COMPASS_FLOOR_DEG,
        turn_scale: cfg::HARD_TURN_SCALE,
        turn_drift: cfg::HARD_TURN_DRIFT,
        turn_drift_period_s: cfg::HARD_TURN_DRIFT_PERIOD_S,
        speed_scale: cfg::HARD_SPEED_SCALE,
        pivot_run_mm: cfg::HARD_PIVOT_RUN_MM,
        compass_wall_deg: cfg::HARD_COMPASS_WALL_DEG,
        compass_wall_decay_mm: cfg::HARD_COMPASS_WALL_DECAY_MM,
        compass_wall_wavelength_mm: cfg::HARD_COMPASS_WALL_WAVELENGTH_MM,
        lidar_incidence_noise: cfg::HARD_LIDAR_INCIDENCE_NOISE,
        spurious_rate: cfg::HARD_SPURIOUS_RATE,
        corner_mix_half_deg: cfg::HARD_CORNER_MIX_HALF_DEG,
    };

    /// The world by name: `ideal`, `lab` or `hard`.
    pub fn named(name: &str) -> Option<Realism> {
        match name {
            "ideal" => Some(Realism::IDEAL),
            "lab" => Some(Realism::LAB),
            "hard" => Some(Realism::HARD),
            _ => None,
        }
    }

    /// The long-run tests' world: the environment's `PAPERBOT_REALISM`
    /// (`ideal`, `lab`, `hard`), else `default` (e.g.
    /// `PAPERBOT_REALISM=hard cargo test --test sim realistic_hour::`); an
    /// unknown name is an error (a run that asked for a world must get it).
    pub fn from_env_or(default: Realism) -> Result<Realism, std::string::String> {
        match std::env::var("PAPERBOT_REALISM") {
            Ok(name) => Realism::named(&name).ok_or(std::format!("PAPERBOT_REALISM={name:?}: want ideal, lab or hard")),
            Err(_) => Ok(default),
        }
    }
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

/// The hard world's effects on a reading of range `t` (mm, from the lidar
/// at `ray`'s (x, y) looking along its direction) at `incidence` (radians), before the
/// glancing failures and the sensor's noise: where the beam's footprint
/// ([`Realism::corner_mix_half_deg`] about its axis) spans two walls, a
/// mix of the ranges it spans (its axis's and its edges'), drawn uniformly
/// between the nearest and the farthest; then noise growing
/// with incidence ([`Realism::lidar_incidence_noise`]). Draws nothing
/// with both off (the lab's and the ideal world's streams stay).
pub fn beam_effects(arena: &Arena, ray: (f64, f64, f64), t: f64, incidence: f64, r: &Realism, rng: &mut Rng) -> f64 {
    let (x, y, dir) = ray;
    let mut t = t;
    if r.corner_mix_half_deg > 0.0 {
        let half = r.corner_mix_half_deg.to_radians();
        if let (Some((a, wa)), Some((b, wb))) = (wall_hit(arena, x, y, dir - half), wall_hit(arena, x, y, dir + half)) {
            if wa != wb {
                let (near, far) = (t.min(a).min(b), t.max(a).max(b));
                t = rng.range_f64(near, far);
            }
        }
    }
    if r.lidar_incidence_noise > 0.0 {
        let slope = incidence.min(80f64.to_radians()).tan();
        t += rng.gauss(r.lidar_incidence_noise * t * slope);
    }
    t.max(0.0)
}

/// Whether a reading is a spurious echo regardless of incidence
/// ([`Realism::spurious_rate`]): `Some(factor)` times the true range (0.3
/// to 1.5, as a glancing failure's echo). Draws nothing with the rate 0.
pub fn spurious(r: &Realism, rng: &mut Rng) -> Option<f64> {
    if r.spurious_rate > 0.0 && rng.chance(r.spurious_rate) {
        Some(rng.range_f64(0.3, 1.5))
    } else {
        None
    }
}

/// The thin ray's length from (x, y) along `dir` and which wall it ends on
/// (0: x = 0, 1: x = length, 2: y = 0, 3: y = width).
fn wall_hit(arena: &Arena, x: f64, y: f64, dir: f64) -> Option<(f64, u8)> {
    let t = arena.ray_cast(x, y, dir)?;
    let (px, py) = (x + t * dir.cos(), y + t * dir.sin());
    let gaps = [px.abs(), (px - arena.length_x_mm()).abs(), py.abs(), (py - arena.width_y_mm()).abs()];
    let wall = (0..4u8).min_by(|&a, &b| gaps[usize::from(a)].total_cmp(&gaps[usize::from(b)]))?;
    Some((t, wall))
}

/// The compass's heading error at (x, y) mm, radians: a smooth pattern over
/// the floor with the configured amplitude (two waves across the box, a
/// different phase per seed).
pub fn compass_disturbance(x: f64, y: f64, r: &Realism, phase: f64) -> f64 {
    let k = core::f64::consts::TAU / cfg::COMPASS_DISTURBANCE_WAVELENGTH_MM;
    let a = r.compass_disturbance_deg.to_radians();
    a * (0.6 * (k * x + phase).sin() + 0.4 * (k * y - 2.0 * phase).cos())
}
