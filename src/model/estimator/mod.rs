//! Where the robot is: an extended Kalman filter over (x, y, theta) that
//! fuses the state update with the two lidars and the compass in a known
//! rectangular arena. Integer only.
//!
//! # The filter
//! - State: the [`Pose`] itself (x, y as [`crate::math::Coord`], theta as an
//!   [`Angle`]); the covariance is over the error `(dx, dy, L dtheta)` with
//!   `L` = 256 mm, so all three components are in mm and one Q format fits
//!   them all ([`Covariance`]: six `i32`, Q14 mm^2, symmetric by storage).
//! - Predict: the pose moves by [`advance`](crate::model::state::advance) (the report's equations, including
//!   its turn case); the covariance by `F P F^T + Q`, with `F` the Jacobian
//!   of those same equations. `Q` models the lab's speed spread as a random
//!   walk per distance driven (or angle turned) whose variance over one
//!   correlation length (config) equals the spread squared, the heading
//!   drift of two mismatched wheels while driving straight, and a small
//!   floor per second.
//! - Lidar correction: see [`crate::model::measurement`]. The innovation is
//!   `z |cos incidence| - A` (how far past its wall the measured ray ends,
//!   along the wall's normal), with `H` its Jacobian and `R = sigma^2 cos^2`:
//!   the ordinary EKF update scaled by `|cos incidence|` on both sides
//!   (the same gain to first order), so no division by a cosine is needed.
//!   Beams further than the config's incidence limit from square on, or
//!   passing within the corner margin of a corner, are not used
//!   ([`Update::Unusable`]).
//! - Compass correction: `H = (0, 0, 1)`, the innovation the wrapped angle
//!   difference.
//! - Gating: a reading whose innovation `nu` has `nu^2 > gate^2 S` is an
//!   outlier: counted, not used ([`Update::Outlier`]).
//!
//! # Re-acquisition and the arena limit
//! A gate alone locks a lost estimate out for good: a body held still for
//! 0.3 s of a commanded turn (a wheel against a wall) left the heading 41
//! degrees off, further than the gate from every true compass reading, and
//! 60 s of them were all rejected (82 degrees after 0.6 s, 171 after 1 s; a
//! blocked 1 s straight left 143 mm). So:
//! - Each sensor counts its outliers in a row (an accepted reading ends the
//!   run, an unusable one leaves it). At [`cfg::REACQUIRE_AFTER`] the
//!   estimator takes the sensor's side: the compass sets the heading's
//!   variance to the cap and zeroes its correlations; a lidar raises both
//!   position variances to at least [`cfg::REACQUIRE_SIGMA_MM`] squared
//!   and zeroes their correlations (the beam may be meeting another wall
//!   than the estimate thinks, so the other axis is in doubt too: the
//!   other lidar's next reading then passes the wider gate). The reading
//!   that ends the run is then used with its innovation clipped to the
//!   gate, `nu_used = sign(nu) min(|nu|, gate sqrt(S))` (counted as
//!   accepted and in [`SensorStats::reacquired`]). Single outliers and
//!   shorter runs stay rejected; a persistent disagreement wins, in steps.
//!   A lidar reading whose distance to its wall along the normal
//!   (`z |cos incidence|`) lies outside `[0, arena extent]` cannot come
//!   from any position in the arena (a lidar against an obstacle or
//!   pressed to a wall): an outlier that does not count toward a run.
//! - No teleports: every correction's step `K nu` obeys
//!   `step^T P^-1 step = nu^2 H P H^T / S^2 <= nu^2 / S <= gate^2`, with
//!   `P` the covariance it starts from (re-inflated, for a re-acquisition).
//!   A lidar's re-acquisition moves the position at most gate times the
//!   larger of its sigma and the one held (157 mm at 45 mm), so an estimate
//!   lost by more walks back in several runs. The heading's cap is 57
//!   degrees one sigma: half a turn is 3.1 sigma, inside the gate, so the
//!   compass, an absolute sensor whose errors do not build up, sets a lost
//!   heading in one step (the clip never binds for it).
//! - The position is kept within [`cfg::ARENA_MARGIN`] of the arena after
//!   every predict and correction (`max`/`min` on the 64-bit coordinates):
//!   the reference point is on the car, inside the box, so a position
//!   further out is known wrong (dead reckoning of a body held at a wall
//!   drove the estimate about 1 m outside in the soak).
//!
//! Measured: the held turn of 0.3-1 s and the held 1 s straight are back
//! within 5 degrees and 20 mm 0.06-0.36 s after the body is free
//! (`tests/control/soak.rs`); over the soak's million ticks the estimate stays
//! within the margin and the error at checkpoints clear of walls has a 90th
//! percentile of 20 mm / 4 degrees. A standing robot 550 mm and half a turn
//! from where a settled estimate believes it is found again in one compass
//! and four lidar re-acquisitions, every step within the gate of its
//! covariance, within 20 mm after 1.2-1.3 s
//! (`tests/estimator/no_teleport.rs`).
//! Cost on the robot: the accepted paths end a run (a store) and keep the
//! position in bounds (two 32-bit compares per axis on the coordinates'
//! high words; predict skips it standing still); everything about a run of
//! outliers is out of line (`#[cold]`).
//!
//! # Numerical safety
//! - Covariance update `P - K b^T` with `b = P H^T`, `K = b / S`: symmetric
//!   by storage (only the upper triangle exists). The diagonal's products
//!   are rounded down, so less is removed than exact arithmetic would.
//! - After every step the covariance is conditioned: a variance past the
//!   cap scales its row and column by 1/2 (a congruence `D P D`, which keeps
//!   `P` positive semi-definite), a variance under the floor is raised (adds
//!   a positive diagonal term), and a covariance with `P_ij^2 > P_ii P_jj`
//!   (impossible for a valid covariance; only rounding at a correlation of
//!   1 gets there) is clamped to `sqrt(P_ii P_jj)` and counted in
//!   [`EstimatorStats::repairs`]. The per-second noise floors (config) keep
//!   `P` a margin away from singular; the long-run test checks that `P`
//!   stays positive definite (f64 Cholesky, every tick) for hours.
//! - No division at all: a correction needs `1/S` with `S >= R > 0` (the
//!   measurement noise is a positive constant times a squared cosine that is
//!   at least the incidence limit's; the scaling below keeps `S >= 1` LSB),
//!   computed as a reciprocal by Newton's method and kept just below the
//!   exact value. A gain of 2^9 or more (impossible for a valid `P`) is not
//!   applied: counted in `repairs`, the reading reported as an outlier.
//!
//! # Arithmetic of a correction (32-bit but three products)
//! - Scale: the covariance entries the row reads are shifted right by `k`
//!   so that they are below 2^23 (`k = 0` below 512 mm^2: steady state is
//!   exact). Then `b = P H^T` (`mul_hi`, `|b| < 2^27`) and `S = H b + R`
//!   (`< 2^31`) are i32 in Q(14 - k).
//! - Gate: `nu^2` against `gate^2 S` as exact 64-bit products ([`mul_wide`](crate::math::mul_wide)).
//! - `S` is normalised to `[2^31, 2^32)` (a 5-step binary search: the lx106
//!   has no NSAU) and its reciprocal `y` comes from a 64-entry seed table and
//!   two Newton steps (error below 2^-26); `b` is normalised to `beta` with
//!   a common shift.
//! - `t_i = mul_hi(|beta_i|, y)` (signed, rounded toward zero) gives both the
//!   gain `K = b / S` (Q21, by a shift) and the covariance update
//!   `b_i b_j / S = mul_hi(t_i, beta_j)` shifted back: relative precision
//!   about 2^-24 of the largest term, whatever the size of `S`.
//! - The state update `K nu` is exact ([`mul_wide`](crate::math::mul_wide), Q37 -> Coord); the
//!   heading's goes through one `mul_hi` to angle LSB (modulo a turn).
//!
//! # Cost (lx106: no 32x32->64 multiply, no divide)
//! The figures per call (predict per motion, each update accepted) are in
//! `lx106/BENCHMARKS.md`, measured by `lx106/run.sh`.
//!
//! Predict: [`advance`](crate::model::state::advance) on the pose in place (no `sin_cos` going straight,
//! one turning, both from the pose's cache), the Jacobian and noise from
//! the cached sin/cos of the old and new heading, about 17 [`mul_hi`](crate::math::mul_hi) (~11
//! instructions each, the Q30 products unsaturated where `|f| < 1/2` bounds
//! them); no 64-bit multiply, no division. A correction: about 20 `mul_hi`,
//! 5 calls of [`mul_wide`](crate::math::mul_wide) (~23 instructions each, out of line), no
//! runtime helper call; a lidar adds its [`Beam`](crate::model::measurement::Beam) (the cached sin/cos
//! turned by the mount's quarter turn, 6 `mul_hi` with the corner test). Every step ends with the
//! conditioning (~80 instructions; an exact `P_ij^2 <= P_ii P_jj` test from
//! 15-bit partial products only when `|P_ij| > min(P_ii, P_jj)`).

// host only (std): replays CSV rows whose width is checked first
#[cfg(feature = "std")]
#[allow(clippy::indexing_slicing)]
pub mod replay;

mod constants;
mod covariance;
mod predict;
mod update;

use crate::config::estimator as cfg;
use crate::math::{isqrt, Angle, Coord};
use crate::model::measurement::Arena;
use crate::model::state::Pose;
use constants::{P0_HEADING, P0_POS, P_MAX, R_COMPASS};

pub use crate::model::measurement::LidarId;
pub use covariance::Covariance;

/// What a correction did with a reading.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
pub enum Update {
    /// Used to correct the pose.
    Accepted,
    /// Too far from its prediction (innovation gate): counted, not used.
    Outlier,
    /// The geometry makes the reading useless: the beam meets its wall too
    /// obliquely or passes near a corner. Counted, not used.
    Unusable,
}

impl Update {
    pub fn is_accepted(self) -> bool {
        self == Update::Accepted
    }
}

/// Counts of what became of one sensor's readings (saturating).
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug, Default)]
pub struct SensorStats {
    pub accepted: u32,
    pub outliers: u32,
    pub unusable: u32,
    /// Times a run of [`cfg::REACQUIRE_AFTER`] outliers in a row made the
    /// estimator take this sensor's side (the reading that ended the run is
    /// counted as accepted, the run's others as outliers).
    pub reacquired: u32,
}

impl SensorStats {
    fn count(&mut self, u: Update) {
        let c = match u {
            Update::Accepted => &mut self.accepted,
            Update::Outlier => &mut self.outliers,
            Update::Unusable => &mut self.unusable,
        };
        *c = c.saturating_add(1);
    }
    /// All readings seen.
    pub fn total(&self) -> u32 {
        self.accepted.saturating_add(self.outliers).saturating_add(self.unusable)
    }
}

/// Per-sensor counts, and how often the covariance needed repair.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug, Default)]
pub struct EstimatorStats {
    pub front: SensorStats,
    pub right: SensorStats,
    pub compass: SensorStats,
    /// Times the covariance broke `P_ij^2 <= P_ii P_jj` (by rounding, at a
    /// correlation of 1) and was clamped back, or a gain overflowed.
    pub repairs: u32,
}

/// The covariance's diagonal in the units people read (for telemetry):
/// one-sigma position in mm (Q16, a [`crate::math::Length`]'s bits) and heading as an [`Angle`].
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug, Default)]
pub struct PoseSigma {
    pub x: crate::math::Length,
    pub y: crate::math::Length,
    pub theta: Angle,
}

/// The lever that turns a heading error into mm: `L dtheta`, L = 256 mm.
pub const HEADING_LEVER_MM: i32 = 256;

/// Outliers in a row per sensor (see [`cfg::REACQUIRE_AFTER`]).
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug, Default)]
struct Streaks {
    front: u8,
    right: u8,
    compass: u8,
}

/// The pose estimator. See the module docs.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub struct Estimator {
    pose: Pose,
    p: Covariance,
    arena: Arena,
    /// The box the position is kept in, whole mm: the arena plus
    /// [`cfg::ARENA_MARGIN`] on every side, rounded inward (lower bound of
    /// both axes, upper bounds of x and y).
    low_mm: i32,
    high_x_mm: i32,
    high_y_mm: i32,
    streaks: Streaks,
    stats: EstimatorStats,
}

impl Estimator {
    /// Starts at `initial` in the config's arena, with the config's initial
    /// uncertainty.
    pub fn new(initial: Pose) -> Estimator {
        Estimator::with_arena(initial, Arena::DEFAULT)
    }

    /// Starts at `initial` in `arena`.
    pub fn with_arena(initial: Pose, arena: Arena) -> Estimator {
        let m = cfg::ARENA_MARGIN;
        // Length is Q16 mm: >> 16 is the floor in whole mm (rounds each
        // bound inward: -floor(m) >= -m)
        let whole = |l: crate::math::Length| l.0 >> 16;
        let mut est = Estimator {
            pose: initial,
            p: Self::initial_covariance(),
            arena,
            low_mm: -whole(m),
            high_x_mm: whole(arena.length_x.saturating_add(m)),
            high_y_mm: whole(arena.width_y.saturating_add(m)),
            streaks: Streaks::default(),
            stats: EstimatorStats::default(),
        };
        est.keep_in_arena();
        est
    }

    fn initial_covariance() -> Covariance {
        Covariance { xx: P0_POS, xy: 0, xt: 0, yy: P0_POS, yt: 0, tt: P0_HEADING }
    }

    /// The estimated pose.
    pub fn pose(&self) -> Pose {
        self.pose
    }

    pub fn arena(&self) -> Arena {
        self.arena
    }

    /// Forgets everything but the counts: the pose is `pose`, the
    /// uncertainty the config's initial one.
    pub fn reset(&mut self, pose: Pose) {
        self.pose = pose;
        self.p = Self::initial_covariance();
        self.streaks = Streaks::default();
        self.keep_in_arena();
    }

    /// Forgets everything but the counts and starts at a localization's
    /// fix ([`crate::model::locate`]): its pose, its position uncertainty
    /// (uncorrelated), and the compass's for the heading.
    pub fn start_at(&mut self, fix: &crate::model::locate::Fix) {
        // sigma in mm Q16 -> variance Q14 mm^2: (s >> 8)^2 is Q16 mm^2, >> 2;
        // capped at the largest variance kept
        let var = |s: crate::math::Length| {
            let q8 = i64::from(s.0 >> 8);
            i32::try_from((q8 * q8) >> 2).unwrap_or(P_MAX).min(P_MAX)
        };
        self.reset(fix.pose);
        self.p = Covariance { xx: var(fix.sigma_x), xy: 0, xt: 0, yy: var(fix.sigma_y), yt: 0, tt: R_COMPASS };
        self.condition();
    }

    /// Keeps the position within [`cfg::ARENA_MARGIN`] of the arena, to the
    /// whole mm (the heading and the covariance are left alone): a
    /// projection onto what the position can be. The tests look at a
    /// coordinate's high word only (its floor in mm, Coord being Q32): two
    /// 32-bit compares per axis, the 64-bit stores only when out of bounds.
    /// (For an arena of negative size the upper bound wins: no panic.)
    fn keep_in_arena(&mut self) {
        let p = &mut self.pose;
        clamp_mm(&mut p.x, self.low_mm, self.high_x_mm);
        clamp_mm(&mut p.y, self.low_mm, self.high_y_mm);
    }

    /// Counts of accepted and rejected readings per sensor.
    pub fn stats(&self) -> EstimatorStats {
        self.stats
    }

    /// The full covariance (Q14 mm^2, heading as `L dtheta`, see [`Covariance`]).
    pub fn covariance(&self) -> Covariance {
        self.p
    }

    /// The covariance's diagonal: variances of x and y in Q14 mm^2 and of
    /// the heading in Q14 (256 mm rad)^2 (for telemetry).
    pub fn covariance_diagonal(&self) -> [i32; 3] {
        [self.p.xx, self.p.yy, self.p.tt]
    }

    /// One-sigma uncertainties in mm and as an angle (integer square roots,
    /// no division; for telemetry).
    pub fn sigma(&self) -> PoseSigma {
        // sqrt(P Q14 mm^2) = isqrt(P) 2^-7 mm -> Q16: << 9. P <= 2^30: isqrt <= 2^15.
        let len = |v: i32| crate::math::Length((isqrt(v.max(0) as u32) << 9) as i32);
        // sqrt(P_tt) 2^-7 mm / L rad -> LSB: isqrt 2^-7 / 256 * 2^32 / (2 pi) = isqrt * 2^17 / (2 pi)
        let t = isqrt(self.p.tt.max(0) as u32);
        PoseSigma { x: len(self.p.xx), y: len(self.p.yy), theta: Angle(t.saturating_mul(20_861)) }
    }
}

/// [`Estimator::keep_in_arena`] for one coordinate: into `[low, high]` mm
/// by its high word (`|c| < 2^63`: it fits).
// tick bar
#[inline(always)]
fn clamp_mm(c: &mut Coord, low: i32, high: i32) {
    let mm = (c.0 >> 32) as i32;
    if mm < low {
        *c = Coord(i64::from(low) << 32);
    }
    if mm >= high {
        *c = Coord(i64::from(high) << 32);
    }
}
