//! Where the robot is: an extended Kalman filter over (x, y, theta) that
//! fuses the state update with the two lidars and the compass in a known
//! rectangular arena. Integer only.
//!
//! # The filter
//! - State: the [`Pose`] itself (x, y as [`crate::math::Coord`], theta as an
//!   [`Angle`]); the covariance is over the error `(dx, dy, L dtheta)` with
//!   `L` = 256 mm, so all three components are in mm and one Q format fits
//!   them all ([`Covariance`]: six `i32`, Q14 mm^2, symmetric by storage).
//! - Predict: the pose moves by [`advance`] (the report's equations, including
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
//!   variance to the cap and zeroes its correlations; a lidar does the same
//!   to both position variances (the beam may be meeting another wall than
//!   the estimate thinks, so the other axis is in doubt too: the other
//!   lidar's next reading then passes the wide gate). The reading that ends
//!   the run is then used without the gate (counted as accepted and in
//!   [`SensorStats::reacquired`]). Single outliers and shorter runs stay
//!   rejected; a persistent disagreement wins. A lidar reading whose
//!   distance to its wall along the normal (`z |cos incidence|`) lies
//!   outside `[0, arena extent]` cannot come from any position in the
//!   arena (a lidar against an obstacle or pressed to a wall): an outlier
//!   that does not count toward a run.
//! - The position is kept within [`cfg::ARENA_MARGIN`] of the arena after
//!   every predict and correction (`max`/`min` on the 64-bit coordinates):
//!   the reference point is on the car, inside the box, so a position
//!   further out is known wrong (dead reckoning of a body held at a wall
//!   drove the estimate about 1 m outside in the soak).
//!
//! Measured: the held turn of 0.3-1 s and the held 1 s straight are back
//! within 5 degrees and 20 mm 0.06-0.36 s after the body is free
//! (`tests/soak.rs`); over the soak's million ticks the estimate stays
//! within the margin (was up to 1 m out) and the error at checkpoints clear
//! of walls has a 90th percentile of 19 mm / 6 degrees (was 164 mm / 64).
//! Cost on the robot: the accepted paths end a run (a store) and keep the
//! position in bounds (two 32-bit compares per axis on the coordinates'
//! high words; predict skips it standing still); everything about a run of
//! outliers is out of line (`#[cold]`), so 11-41 lx106 instructions per
//! call (table below).
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
//! - Gate: `nu^2` against `gate^2 S` as exact 64-bit products ([`mul_wide`]).
//! - `S` is normalised to `[2^31, 2^32)` (a 5-step binary search: the lx106
//!   has no NSAU) and its reciprocal `y` comes from a 64-entry seed table and
//!   two Newton steps (error below 2^-26); `b` is normalised to `beta` with
//!   a common shift.
//! - `t_i = mul_hi(|beta_i|, y)` (signed, rounded toward zero) gives both the
//!   gain `K = b / S` (Q21, by a shift) and the covariance update
//!   `b_i b_j / S = mul_hi(t_i, beta_j)` shifted back: relative precision
//!   about 2^-24 of the largest term, where the former `2^44 / S` gain lost
//!   precision as `S` grew.
//! - The state update `K nu` is exact ([`mul_wide`], Q37 -> Coord); the
//!   heading's goes through one `mul_hi` to angle LSB (modulo a turn).
//!
//! # Cost (lx106: no 32x32->64 multiply, no divide)
//! Measured by `lx106/run.sh` (ICOUNT under QEMU, worst of 8 poses, 10 ms
//! step) at opt-level "z" (`lx106/BENCHMARKS.md`); in parentheses, at
//! opt-level 3 in earlier versions: without re-acquisition and the arena
//! limit first, before this arithmetic second:
//!
//! | call | instructions |
//! | --- | ---: |
//! | predict Stop | 181 (169; 626) |
//! | predict Straight | 658 (689; 1221) |
//! | predict Turn | 738 (720; 1284) |
//! | update_lidar (accepted, incl. its [`Beam`]) | 1572 (1362; 5368) |
//! | update_heading (accepted) | 1037 (837; 4527) |
//!
//! Predict: [`advance`] on the pose in place (no `sin_cos` going straight,
//! one turning, both from the pose's cache), the Jacobian and noise from
//! the cached sin/cos of the old and new heading, about 17 [`mul_hi`] (~11
//! instructions each, the Q30 products unsaturated where `|f| < 1/2` bounds
//! them); no 64-bit multiply, no division. A correction: about 20 `mul_hi`,
//! 5 calls of [`mul_wide`] (~23 instructions each, out of line), no
//! runtime helper call; a lidar adds its [`Beam`] (the cached sin/cos
//! turned by the mount's quarter turn, 6 `mul_hi` with the corner test). Every step ends with the
//! conditioning (~80 instructions; an exact `P_ij^2 <= P_ii P_jj` test from
//! 15-bit partial products only when `|P_ij| > min(P_ii, P_jj)`).

// host only (std): replays CSV rows whose width is checked first
#[cfg(feature = "std")]
#[allow(clippy::indexing_slicing)]
pub mod replay;

use crate::config::estimator as cfg;
use crate::config::geometry;
use crate::math::{mul_hi, mul_wide, Angle, Coord, Dt};
use crate::model::actuator::Motion;
use crate::model::measurement::{mul_q30, Arena, Beam, Wall};
use crate::model::state::{advance, Pose};

pub use crate::model::measurement::LidarId;

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

/// The error covariance, symmetric, over `(dx, dy, L dtheta)` with
/// `L` = [`HEADING_LEVER_MM`]: every entry in Q14 mm^2 (2^-14 mm^2).
/// Invariants after every step: `MIN <= P_ii <= MAX` and
/// `P_ij^2 <= P_ii P_jj`, so every entry is at most 2^30 in magnitude.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug, Default)]
pub struct Covariance {
    pub xx: i32,
    pub xy: i32,
    pub xt: i32,
    pub yy: i32,
    pub yt: i32,
    pub tt: i32,
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

// ---- Constants, evaluated by the compiler from the config ----

const Q14: f64 = 16384.0;
const TAU: f64 = core::f64::consts::TAU;
const L: f64 = HEADING_LEVER_MM as f64;

const fn to_i32(x: f64) -> i32 {
    crate::math::round_f64(x) as i32
}
/// cos(x) for |x| <= pi, by its series (const: for the config's angles).
const fn cos_f64(x: f64) -> f64 {
    let (mut term, mut sum, mut k) = (1.0, 1.0, 1);
    while k < 20 {
        term = -term * x * x / ((2 * k - 1) as f64 * (2 * k) as f64);
        sum += term;
        k += 1;
    }
    sum
}

/// Lidar variance, Q14 mm^2.
const R_LIDAR: i32 = to_i32(cfg::LIDAR_SIGMA.0 as f64 / 65536.0 * (cfg::LIDAR_SIGMA.0 as f64 / 65536.0) * Q14);
/// Compass variance in (L rad)^2, Q14 mm^2.
const R_COMPASS: i32 =
    to_i32((cfg::COMPASS_SIGMA_DEG * TAU / 360.0 * L) * (cfg::COMPASS_SIGMA_DEG * TAU / 360.0 * L) * Q14);
/// gate^2 in Q8.
const GATE_SQ_Q8: i32 = to_i32(cfg::GATE_SIGMAS * cfg::GATE_SIGMAS * 256.0);
/// cos(max incidence), Q30.
const MIN_NORMAL: i32 = to_i32(cos_f64(cfg::MAX_INCIDENCE_DEG * TAU / 360.0) * 1_073_741_824.0);
/// Straight: distance variance per mm driven (k^2 Lc), as a factor for
/// `mul_hi(|d| in Q24 mm, .)` giving Q14 mm^2: k^2 Lc 2^14 2^32 / 2^24.
const K_DIST: i32 = to_i32(cfg::SPEED_SPREAD * cfg::SPEED_SPREAD * cfg::SPEED_CORRELATION_MM * Q14 * 256.0);
/// Straight: heading variance per mm driven, (k L / axle)^2 Lc, same scaling.
const K_DRIFT: i32 = {
    let axle = geometry::AXLE_LENGTH.0 as f64 / 65536.0;
    let r = cfg::SPEED_SPREAD * L / axle;
    to_i32(r * r * cfg::SPEED_CORRELATION_MM * Q14 * 256.0)
};
/// Turn: heading variance (L rad)^2 Q14 per angle LSB turned, times 2^32
/// (for `mul_hi(|turn| in LSB, .)`): k^2 Lc_rad L^2 2^14 (2 pi / 2^32) 2^32.
const K_TURN: i32 = {
    let lc = cfg::TURN_CORRELATION_DEG * TAU / 360.0;
    to_i32(cfg::TURN_SPREAD * cfg::TURN_SPREAD * lc * L * L * Q14 * TAU)
};
/// Floors per microsecond, Q14 mm^2 times 2^16.
const FLOOR_POS: u32 = crate::math::round_f64(cfg::POSITION_FLOOR_MM2_PER_S * Q14 / 1e6 * 65_536.0) as u32;
const FLOOR_HEADING: u32 = {
    let rad = TAU / 360.0;
    crate::math::round_f64(cfg::HEADING_FLOOR_DEG2_PER_S * rad * rad * L * L * Q14 / 1e6 * 65_536.0) as u32
};
/// D / L in Q31 (D < 128 mm by the config's assert, so D / L < 1/2).
const D_OVER_L_Q31: i32 = to_i32(geometry::ROTATION_TO_REFERENCE.0 as f64 / 65536.0 / L * 2_147_483_648.0);
const P_MAX: i32 = to_i32(cfg::MAX_VARIANCE_MM2 * Q14);
const P_MIN: i32 = to_i32(cfg::MIN_VARIANCE_MM2 * Q14);
const P0_POS: i32 = to_i32(cfg::INITIAL_SIGMA_MM * cfg::INITIAL_SIGMA_MM * Q14);
const P0_HEADING: i32 = {
    let s = cfg::INITIAL_SIGMA_DEG * TAU / 360.0 * L;
    to_i32(s * s * Q14)
};
/// Angle LSB per (L rad) mm, 2^32 / (2 pi L), times 2^9: `mul_hi(K Q21, .)`
/// then times `nu` (Q16) and `>> 14` gives angle LSB (see `correct`).
const LSB_PER_TILDE_MM_Q9: i32 = to_i32(4_294_967_296.0 / (TAU * L) * 512.0);
/// (L rad) mm in Q16 per angle LSB, times 2^32 (for `mul_hi`): 2 pi L 2^16 / 2^32 * 2^32.
const TILDE_Q16_PER_LSB: i32 = to_i32(TAU * L * 65536.0);

const _: () = {
    assert!(R_LIDAR > 0 && R_COMPASS > 0 && R_COMPASS < (1 << 22));
    assert!(GATE_SQ_Q8 > 0 && GATE_SQ_Q8 < (1 << 12));
    // lidar R = R_LIDAR cos^2(incidence) >= R_LIDAR MIN_NORMAL^2 >= 2^12 (Q14 mm^2):
    // S >= R stays positive after `correct`'s scaling by 2^-9
    assert!((R_LIDAR as i64) * (MIN_NORMAL as i64) / (1 << 30) * (MIN_NORMAL as i64) / (1 << 30) >= (1 << 12));
    assert!(LSB_PER_TILDE_MM_Q9 > (1 << 30));
    // D / L < 1/4 (D < 64 mm): a turn's Jacobian entries stay below 1/2,
    // which `propagate`'s unsaturated products rely on
    assert!(D_OVER_L_Q31 >= 0 && D_OVER_L_Q31 < (1 << 29));
    assert!(MIN_NORMAL > (1 << 28) && MIN_NORMAL <= (1 << 30));
    assert!(P_MIN > 0 && P_MIN < P_MAX && P_MAX <= (1 << 30));
    assert!(P0_POS <= P_MAX && P0_HEADING <= P_MAX);
    assert!(K_DIST > 0 && K_DRIFT > 0 && K_TURN > 0);
    // floor * dt must fit u32 for dt <= 65535 us
    assert!((FLOOR_POS as u64) * 65_535 < (1 << 32) && (FLOOR_HEADING as u64) * 65_535 < (1 << 32));
};

/// Outliers in a row per sensor (see [`cfg::REACQUIRE_AFTER`]).
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug, Default)]
struct Streaks {
    front: u8,
    right: u8,
    compass: u8,
}

/// Whether [`Estimator::correct`] applies the innovation gate.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Gate {
    On,
    /// Re-acquiring: the covariance has just been re-inflated and the
    /// reading is used whatever its innovation.
    Off,
}

/// One row of `H` for a scalar measurement: `sign` times a unit on x or y
/// (or nothing), plus `theta` (Q16, per mm of `L dtheta`) on the heading.
#[derive(Clone, Copy)]
struct Row {
    /// 0 = x, 1 = y, with the sign of the unit entry; `None` for the compass.
    pos: Option<(u8, bool)>,
    /// Q16; |theta| <= THETA_MAX < 2^19 ((|z| + |lateral|) / L with |z| <= 2^11 mm, clamped).
    theta: i32,
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

    /// Keeps the position within [`cfg::ARENA_MARGIN`] of the arena, to the
    /// whole mm (the heading and the covariance are left alone): a
    /// projection onto what the position can be. The tests look at a
    /// coordinate's high word only (its floor in mm, Coord being Q32): two
    /// 32-bit compares per axis, the 64-bit stores only when out of bounds.
    /// (For an arena of negative size the upper bound wins: no panic.)
    #[inline(never)]
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

    /// Moves the pose by `motion` held for `dt` and grows the uncertainty.
    pub fn predict(&mut self, motion: Motion, dt: Dt) {
        let p = &mut self.p;
        match motion {
            Motion::Stop => {}
            Motion::Straight(v) => {
                // the heading does not change: the pose's cached sin/cos are
                // those of the step's heading, before and after
                let (s, c) = self.pose.sin_cos();
                advance(&mut self.pose, motion, dt);
                // |d| <= 65.5 mm in Q24 < 2^31 (Speed::MAX over Dt::MAX)
                let d = v.distance_q24(dt);
                // F: dx/d(L theta) = -d s / L, dy/d(L theta) = d c / L; in Q30
                // that is exactly mul_hi(d Q24, s Q30) (2^30 / (2^22 * 256) = 1):
                // |f| <= 65.5 / 256 < 2^-2 (Q30: < 2^28).
                let f1 = -mul_hi(d, s);
                let f2 = mul_hi(d, c);
                propagate(p, f1, f2);
                // Q: distance noise along (c, s), heading drift. |d| < 2^31,
                // K_DIST < 2^21: var_d < 2^20, so every Q30 product below is
                // far inside i32.
                let ad = d.wrapping_abs(); // |d| < 2^31 (above): no wrap
                add_noise(p, mul_hi(ad, K_DIST), c, s);
                p.tt = p.tt.saturating_add(mul_hi(ad, K_DRIFT));
            }
            Motion::Turn(_) => {
                let before = self.pose.theta;
                // both cached: the last step's new heading, and this one's
                // (`advance` stores it)
                let (s0, c0) = self.pose.sin_cos();
                advance(&mut self.pose, motion, dt);
                let (s1, c1) = self.pose.sin_cos();
                // The turn (model::state): x' = x - D (c0 - c1), y' = y - D (s0 - s1):
                // dx'/dtheta = D (s0 - s1), dy'/dtheta = D (c1 - c0). Halves
                // of Q30 values keep the differences in i32 (Q29); D/L Q31
                // times Q29 gives Q28 from mul_hi, hence the << 2:
                // |f| <= 2 D / L < 7/16 (D < 64 mm, asserted): < 2^29 in Q30.
                let f1 = mul_hi(D_OVER_L_Q31, (s0 >> 1) - (s1 >> 1)) << 2;
                let f2 = mul_hi(D_OVER_L_Q31, (c1 >> 1) - (c0 >> 1)) << 2;
                propagate(p, f1, f2);
                // Q: the turned angle's noise enters through G = (-D s1 / L, D c1 / L, 1)
                // (|g| < 2^28 in Q30); |turned| <= 2^31, K_TURN < 2^23: vt < 2^22.
                let turned = self.pose.theta.diff(before).saturating_abs();
                let vt = mul_hi(turned, K_TURN);
                let g1 = -(mul_hi(D_OVER_L_Q31, s1) << 1);
                let g2 = mul_hi(D_OVER_L_Q31, c1) << 1;
                let (v1, v2) = add_noise(p, vt, g1, g2);
                p.xt = p.xt.saturating_add(v1);
                p.yt = p.yt.saturating_add(v2);
                p.tt = p.tt.saturating_add(vt);
            }
        }
        // Floors: dt <= 65535 us, so the products fit u32 (asserted above).
        let dt = dt.as_micros();
        let fp = (FLOOR_POS.wrapping_mul(dt) >> 16) as i32;
        let fh = (FLOOR_HEADING.wrapping_mul(dt) >> 16) as i32;
        p.xx = p.xx.saturating_add(fp);
        p.yy = p.yy.saturating_add(fp);
        p.tt = p.tt.saturating_add(fh);
        self.condition();
        if motion != Motion::Stop {
            self.keep_in_arena();
        }
    }

    /// Corrects the pose with a lidar's model output (distance from the
    /// reference point along the beam, see [`crate::model::lidar`]).
    // out of line: inlined into the tick it was 256 B more code for no
    // fewer instructions
    #[inline(never)]
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
            let (s, c) = (beam.sin, beam.cos);
            // d(normal_miss)/d(state), see the module docs of `measurement`:
            // x-walls: sign(c) (-1, 0, z s + lat c); y-walls: sign(s) (0, -1, lat s - z c).
            let lat = |t: i32| if beam.lateral.0 == 0 { 0 } else { mul_q30(beam.lateral.0, t) };
            let (axis, lever, sign_pos) = if beam.wall.is_x_wall() {
                (0u8, mul_q30(z.0, s).saturating_add(lat(c)), beam.wall == Wall::North)
            } else {
                (1u8, lat(s).saturating_sub(mul_q30(z.0, c)), beam.wall == Wall::East)
            };
            // lever is mm Q16; / L -> Q16 per (L rad) mm; |z| <= 2^27 and a
            // mount's lateral offset of a few mm keep it near 2^19: clamped
            // to the bound `correct` relies on.
            let theta = (lever >> 8).clamp(-THETA_MAX, THETA_MAX);
            // North and East: H = (-1 on the axis, +lever); South and West: (+1, -lever).
            let row = if sign_pos {
                Row { pos: Some((axis, false)), theta }
            } else {
                Row { pos: Some((axis, true)), theta: -theta }
            };
            // R = sigma^2 cos^2(incidence): normal^2 in Q30 via mul_hi (Q28) * 4.
            let n2 = mul_hi(beam.normal, beam.normal).saturating_mul(4);
            let r = mul_q30(R_LIDAR, n2).max(1);
            match self.correct(row, nu.0, r, Gate::On) {
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
    /// lost (see the module docs). Out of line: the accepted path stays as
    /// it was.
    #[cold]
    #[inline(never)]
    fn lidar_outlier(&mut self, which: LidarId, row: Row, nu: crate::math::Length, r: i32, beam: &Beam) -> Update {
        // The distance to the wall along its normal that the reading implies:
        // one that puts the reference point outside the arena (a lidar
        // against an obstacle or pressed to a wall) is no evidence the
        // position is lost, and does not count.
        let implied = nu.saturating_add(beam.to_wall);
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
        // on both axes: the beam may meet another wall than the estimate thinks.
        let q = &mut self.p;
        (q.xx, q.yy, q.xy, q.xt, q.yt) = (P_MAX, P_MAX, 0, 0, 0);
        let st = self.stats_of(which);
        st.reacquired = st.reacquired.saturating_add(1);
        self.correct_ungated(row, nu.0, r)
    }

    /// [`Estimator::correct`] without the gate, out of line (re-acquisition only).
    #[cold]
    #[inline(never)]
    fn correct_ungated(&mut self, row: Row, nu: i32, r: i32) -> Update {
        self.correct(row, nu, r, Gate::Off)
    }

    /// A compass reading failed the gate: counted into the compass's run of
    /// outliers, and at [`cfg::REACQUIRE_AFTER`] the heading is taken as
    /// lost: its variance to the cap, uncorrelated, and the reading used.
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
        self.correct_ungated(row, nu, R_COMPASS)
    }

    /// Corrects the heading with a compass reading (clockwise from north).
    pub fn update_heading(&mut self, heading: Angle) -> Update {
        let diff = heading.diff(self.pose.theta);
        // angle LSB -> (L rad) mm Q16: |result| < 2^31 * 0.025
        let nu = mul_hi(diff, TILDE_Q16_PER_LSB);
        let row = Row { pos: None, theta: 1 << 16 };
        let result = match self.correct(row, nu, R_COMPASS, Gate::On) {
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
    /// noise `r` (Q14 mm^2, > 0), gated unless re-acquiring. All 32-bit but
    /// the state update's three products (see the module docs, "Arithmetic
    /// of a correction"). One copy for the three callers (gated lidar and
    /// compass, ungated re-acquisition): the call costs a few instructions,
    /// three inlined copies cost kilobytes of flash.
    #[inline(never)]
    fn correct(&mut self, h: Row, nu: i32, r: i32, gate: Gate) -> Update {
        // b = P H^T and H P H^T, scaled by 2^-k (Q(14 - k) mm^2).
        let (b, hph, k) = project(&self.p, h);
        // S = H P H^T + R > 0: |hph| < 2^30, r >> k < 2^22, so S < 2^31;
        // H P H^T >= 0 for a valid P, and r >> k >= 1 keeps S positive.
        let s = hph.max(0) + (r >> k).max(1);
        // Gate: nu^2 (Q32) against gate^2 S (S 2^k in Q14 = S 2^(18 + k) in
        // Q32, gate^2 in Q8): nu^2 <= 2^62; gate^2 < 2^12 (asserted) shifted
        // by 10 + k <= 19 stays below 2^31, and its product with S below 2^62.
        if gate == Gate::On && mul_wide(nu, nu) > mul_wide(s, GATE_SQ_Q8 << (10 + k)) {
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
        // (element by element, not `map`: at opt-level "z" a closure per
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

    /// Keeps the covariance valid (see the module docs).
    fn condition(&mut self) {
        let p = &mut self.p;
        // Cap: scale row and column i by 1/2 (D P D, still PSD).
        if p.xx > P_MAX {
            p.xx >>= 2;
            p.xy >>= 1;
            p.xt >>= 1;
        }
        if p.yy > P_MAX {
            p.yy >>= 2;
            p.xy >>= 1;
            p.yt >>= 1;
        }
        if p.tt > P_MAX {
            p.tt >>= 2;
            p.xt >>= 1;
            p.yt >>= 1;
        }
        // Floor: adding to the diagonal keeps P PSD.
        p.xx = p.xx.max(P_MIN);
        p.yy = p.yy.max(P_MIN);
        p.tt = p.tt.max(P_MIN);
        // (three calls, not a loop over an array: at opt-level "z" the
        // array's iterator is a call per element)
        let repairs = bound_correlation(&mut p.xy, p.xx, p.yy)
            + bound_correlation(&mut p.xt, p.xx, p.tt)
            + bound_correlation(&mut p.yt, p.yy, p.tt);
        self.stats.repairs = self.stats.repairs.saturating_add(repairs);
    }
}

/// Keeps `|P_ij| <= sqrt(P_ii P_jj)` (`0 < P_ii, P_jj <= 2^30`, capped and
/// floored by [`Estimator::condition`]); 1 if it had to change `P_ij`.
#[inline(always)]
fn bound_correlation(pij: &mut i32, pii: i32, pjj: i32) -> u32 {
    // |P_ij| <= min(P_ii, P_jj) implies P_ij^2 <= P_ii P_jj: the exact test
    // (two 64-bit products) only past that.
    if pij.unsigned_abs() <= pii.min(pjj).unsigned_abs() {
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

/// One covariance entry's part of a correction, `P_ij -= mul_hi(t_i,
/// beta_j) 2^e` (saturating, [`shift_inline`]; see [`Estimator::correct`]).
/// Out of line: one copy for the six entries is 220 B less code for ~3
/// instructions each.
#[inline(never)]
fn remove(pij: &mut i32, ti: i32, bj: i32, e: i32) {
    *pij = pij.saturating_sub(shift_inline(mul_hi(ti, bj), e));
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

/// [`Estimator::keep_in_arena`] for one coordinate: into `[low, high]` mm
/// by its high word (`|c| < 2^63`: it fits).
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

/// The exact product of `a, b < 2^31`, from 15-bit halves: `a = ah 2^15 + al`
/// (`ah < 2^16`, `al < 2^15`), so `ah bh < 2^32`, `ah bl + al bh < 2^32` and
/// `al bl < 2^30` fit u32. (A split at 16 bits is the textbook pattern LLVM
/// turns back into a `__muldi3` call when it can prove the operands
/// non-negative.) About 25 lx106 instructions.
#[inline(always)]
fn mul_u31(a: u32, b: u32) -> u64 {
    let (ah, al) = (a >> 15, a & 0x7FFF);
    let (bh, bl) = (b >> 15, b & 0x7FFF);
    let mid = ah * bl + al * bh;
    (u64::from(ah * bh) << 30) + (u64::from(mid) << 15) + u64::from(al * bl)
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
            // |b| < 2^26 + 2^23 < 2^27 (element by element: at opt-level "z"
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

/// `(x << n, n)` with `x << n` in `[2^31, 2^32)`, for `x > 0` (the lx106 has
/// no NSAU: a five-step binary search, ~15 instructions). Out of line: one
/// copy for its three sites in a correction is 160 B less code for ~10
/// instructions a call.
#[inline(never)]
fn normalize(x: u32) -> (u32, u32) {
    let (mut x, mut n) = (x, 0u32);
    if x < 1 << 16 {
        x <<= 16;
        n += 16;
    }
    if x < 1 << 24 {
        x <<= 8;
        n += 8;
    }
    if x < 1 << 28 {
        x <<= 4;
        n += 4;
    }
    if x < 1 << 30 {
        x <<= 2;
        n += 2;
    }
    if x < 1 << 31 {
        x <<= 1;
        n += 1;
    }
    (x, n)
}

/// Unsigned [`mul_hi`]: `(a * b) >> 32` within 3 LSB below the exact floor
/// (three 16x16 products; the dropped low product and the two floors only
/// ever lower it). Never overflows: the sum is at most the exact high word.
#[inline(always)]
fn mul_hi_u(a: u32, b: u32) -> u32 {
    let (ah, al) = (a >> 16, a & 0xFFFF);
    let (bh, bl) = (b >> 16, b & 0xFFFF);
    ah * bh + ((ah * bl) >> 16) + ((al * bh) >> 16)
}

/// Seeds for [`reciprocal`]: `2^23 / (129 + 2 i)`, 2^15 / the middle of
/// interval `i` of 64 over `[1/2, 1)`; 65028 at most. (Evaluated by the
/// compiler: an index out of range would be a build error, not a panic.)
#[allow(clippy::indexing_slicing)]
const RECIP_SEED: [u16; 64] = {
    let mut t = [0u16; 64];
    let mut i = 0;
    while i < 64 {
        t[i] = ((1u32 << 23) / (129 + 2 * i as u32)) as u16;
        i += 1;
    }
    t
};

/// `2^62 / x` for `x` in `[2^31, 2^32)` (a result in `(2^30, 2^31]`), at most
/// a few 2^-28 below the exact value and never above it: a 64-entry seed
/// (relative error below 2^-7) and two Newton steps `y += y (1 - x y)`
/// (2^-14, then 2^-28) in [`mul_hi`] arithmetic. About 50 instructions,
/// where a 64-bit division is ~430.
#[inline(always)]
fn reciprocal(x: u32) -> u32 {
    // x >> 25 is 64..127: the index is below 64
    let seed = RECIP_SEED.get(((x >> 25) & 63) as usize).copied().unwrap_or(1 << 15);
    let mut y = u32::from(seed) << 15; // Q30, (2^30, 2^31)
    for _ in 0..2 {
        // x y / 2^32 in Q30 (~2^30); d = (1 - x y) 2^30, |d| < 2^23 after the seed
        let d = (1u32 << 30).wrapping_sub(mul_hi_u(x, y)) as i32;
        // y d / 2^30 = mul_hi(y / 2, 8 d): y / 2 < 2^30, |8 d| < 2^26
        y = y.wrapping_add_signed(mul_hi((y >> 1) as i32, d << 3));
    }
    // mul_hi's floors can leave y a few LSB above 1/x: step below it
    y.saturating_sub(16)
}

/// `v 2^e`: an arithmetic right shift for `e <= 0`, a saturating left shift
/// for `e > 0`. Out of line: one copy for the gain's three entries (and
/// [`remove`]'s own for the covariance's six) is less code for a few
/// instructions in all.
#[inline(never)]
fn shift(v: i32, e: i32) -> i32 {
    shift_inline(v, e)
}

/// [`shift`]'s body, for [`remove`] to inline (a call from there costs the
/// tick ~100 instructions).
#[inline(always)]
fn shift_inline(v: i32, e: i32) -> i32 {
    if e <= 0 {
        v >> (-e).min(31)
    } else {
        shift_left(v, e)
    }
}

/// `v 2^e` for `e > 0`, saturating: [`shift`]'s rare side (a correction's
/// gain and covariance terms shift left only while the covariance is large,
/// S at least 2^9 times the entries' scale).
#[inline(always)]
fn shift_left(v: i32, e: i32) -> i32 {
    let e = e.clamp(0, 31) as u32;
    // fits when |v| < 2^(31 - e)
    if v.unsigned_abs() < 1u32 << (31 - e) {
        v << e
    } else if v < 0 {
        i32::MIN
    } else {
        i32::MAX
    }
}

/// Defines an integer square root (floor) over one unsigned type, without
/// division: bit by bit, one round per result bit.
macro_rules! isqrt_of {
    ($(#[$doc:meta])* $name:ident, $t:ty) => {
        $(#[$doc])*
        pub fn $name(v: $t) -> u32 {
            let (mut rem, mut root): ($t, $t) = (v, 0);
            let mut bit: $t = 1 << (<$t>::BITS - 2);
            while bit > rem {
                bit >>= 2;
            }
            while bit != 0 {
                if rem >= root + bit {
                    rem -= root + bit;
                    root = (root >> 1) + bit;
                } else {
                    root >>= 1;
                }
                bit >>= 2;
            }
            root as u32 // the root of a u64 is below 2^32
        }
    };
}

isqrt_of!(
    /// Integer square root (floor) of a `u32`, no division: 16 rounds.
    isqrt,
    u32
);
isqrt_of!(
    /// Integer square root (floor) of a `u64`, no division: 32 rounds.
    isqrt64,
    u64
);

/// `a f` for `f` in Q30, where `|a f| < 2^61` (`|f| <= 2^29` for any `a`,
/// or small operands): `mul_hi` gives Q-2 within 3 LSB below the exact
/// product, and the `<< 2` cannot overflow under that bound (where
/// [`mul_q30`] pays for a saturating multiply).
#[inline(always)]
fn q30(a: i32, f: i32) -> i32 {
    mul_hi(a, f) << 2
}

/// Adds `v g g^T` to the position block of `P` (`g = (g1, g2)` in Q30,
/// `|g| <= 1`, `v` small: see [`Estimator::predict`]) and returns
/// `(v g1, v g2)`, the heading column's share of a turn's noise. Both
/// motions' noise has this shape (a straight step's `g` is the heading's
/// `(cos, sin)`): one out-of-line copy for the two.
#[inline(never)]
fn add_noise(p: &mut Covariance, v: i32, g1: i32, g2: i32) -> (i32, i32) {
    let (v1, v2) = (q30(v, g1), q30(v, g2));
    p.xx = p.xx.saturating_add(q30(v1, g1));
    p.xy = p.xy.saturating_add(q30(v1, g2));
    p.yy = p.yy.saturating_add(q30(v2, g2));
    (v1, v2)
}

/// `F P F^T` for `F = I + f1 e_x e_t^T + f2 e_y e_t^T` (f in Q30, |f| < 2^29,
/// i.e. below 1/2). With `|P_ij| <= 2^30` (conditioned): `u` below 1.5 2^30
/// fits i32; the other sums can pass 2^31 only for a P near its cap, and
/// saturate.
#[inline(never)]
fn propagate(p: &mut Covariance, f1: i32, f2: i32) {
    // new P_xt = P_xt + f1 P_tt, new P_yt = P_yt + f2 P_tt
    let u1 = p.xt + q30(p.tt, f1);
    let u2 = p.yt + q30(p.tt, f2);
    // P_xx + 2 f1 P_xt + f1^2 P_tt = P_xx + f1 (P_xt + u1)
    p.xx = p.xx.saturating_add(q30(p.xt, f1)).saturating_add(q30(u1, f1));
    p.yy = p.yy.saturating_add(q30(p.yt, f2)).saturating_add(q30(u2, f2));
    // P_xy + f1 P_yt + f2 P_xt + f1 f2 P_tt = P_xy + f1 P_yt + f2 u1
    p.xy = p.xy.saturating_add(q30(p.yt, f1)).saturating_add(q30(u1, f2));
    p.xt = u1;
    p.yt = u2;
}
