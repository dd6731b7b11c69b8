//! Where the robot is: a few extended Kalman filters (hypotheses) over the
//! pose, the actuator lines' scales and the compass's bias, fusing the state
//! update with the two lidars and the compass in a known rectangular arena.
//! Integer only. The longer story, with the figures, is `docs/estimator.md`.
//!
//! # One hypothesis (a filter)
//! - State (7, [`covariance::N`]): the [`Pose`] (x, y as
//!   [`crate::math::Coord`], theta as an [`Angle`]); the straight speed's
//!   scale and the clockwise and counter-clockwise turn rates' scales over
//!   the config's actuator lines (Q29, learned online: real turns run 0.6-1.8
//!   times the lines); the compass's bias (an [`Angle`], a slow random walk
//!   over the floor). The covariance is over the errors times a lever `L` =
//!   256 mm for all but the position, so every entry is in mm^2 and one Q
//!   format fits ([`Covariance`]: the upper triangle, Q12 mm^2, cap 2^28).
//! - Predict: the pose moves by [`advance`](crate::model::state::advance)
//!   of the motion scaled by the hypothesis's scales; the covariance by `F P
//!   F^T + Q` with `F` as shears (state `i` moves by `f` times state `j`):
//!   position by heading and speed scale, heading by the turn's scale. `Q`:
//!   the lab's speed spread per distance (or angle), the wheels' drift, the
//!   pivot's slop across the car, the scales' and the bias's random walks,
//!   small floors per second.
//! - Lidar correction: see [`crate::model::measurement`]. The innovation is
//!   `z |cos incidence| - A` with `H` its Jacobian; the noise grows with
//!   the incidence, `R = sigma^2 cos^2 + sigma_inc^2 sin^2` (the variance
//!   `sigma^2 + (sigma_inc tan)^2` scaled by `cos^2` as the innovation is:
//!   no division, no hard cut but the linearisation's limit,
//!   [`cfg::MAX_INCIDENCE_DEG`]). Beams passing within the corner margin of
//!   a corner are not used ([`Update::Unusable`]).
//! - Compass correction: it reads heading plus bias, `H = (0, 0, 1, 0, 0,
//!   0, 1)`; the lidars tell the two apart.
//! - Gating: a reading whose innovation `nu` has `nu^2 > gate^2 S` is an
//!   outlier for that hypothesis: not used ([`Update::Outlier`]).
//!
//! # No teleports: several hypotheses, a reported pose that never jumps
//! Re-acquisition (ten disagreeing readings in a row: take the sensor's
//! side) moved a standing robot's estimate by up to 157 mm on what were ten
//! readings of one view. It is gone (issue 29). Instead:
//! - Up to [`cfg::MAX_HYPOTHESES`] filters: the best (the leader) the whole
//!   filter above, the others lighter (`light`: the pose block, the
//!   leader's scales and bias). [`Estimator::seed`] starts them
//!   from a localization's clusters (pose, sigma, weight each; never their
//!   mean). Every reading corrects the leader and one other in turn, and
//!   moves that one's cost by its normalised squared innovation
//!   ([`cfg::OUTLIER_COST`] when gated out) minus the leader's: the costs
//!   are differences from the leader, and a hypothesis that did not see a
//!   reading keeps its own - but only readings that are new evidence: a sensor's reading
//!   counts once the robot has moved [`cfg::EVIDENCE_TRAVEL_MM`] since that
//!   sensor's last counted one, or [`cfg::EVIDENCE_PERIOD_S`] has passed.
//!   Ten readings of a standing robot are one.
//! - A sensor whose counted readings disagree with the best hypothesis
//!   [`cfg::RESEARCH_AFTER`] times in a row (so: while the robot moves)
//!   triggers a local re-search: a new hypothesis takes the sensor's side
//!   (a lidar: the best's copy with the position uncertain by
//!   [`cfg::RESEARCH_SIGMA_MM`], moved along the wall's normal if need be;
//!   the compass: one copy with the heading lost, one with the bias moved),
//!   starting [`cfg::SPAWN_COST`] behind. Hypotheses [`cfg::PRUNE_COST`]
//!   behind the best are dropped, near twins merged.
//! - [`Tracking`]: `Located` when one hypothesis leads all others by
//!   [`cfg::DOMINATE_COST`]; `Ambiguous` while none does; `Unknown` from a
//!   typed start ([`Estimator::new`], [`Estimator::reset`]) until the
//!   position is known within [`cfg::LOCATED_SIGMA_MM`].
//! - The reported pose ([`Estimator::pose`]) dead-reckons with the best's
//!   scales; while `Located` it moves toward the best hypothesis by at most
//!   a slack saved up while moving ([`cfg::CATCH_UP_PER_MM`] per mm and
//!   [`cfg::CATCH_UP_MM_PER_S`] per second, at most [`cfg::CATCH_UP_MAX_MM`]
//!   per axis, cut to [`cfg::CATCH_UP_STANDING_MM`] when the servos stop);
//!   while `Ambiguous` it holds (dead reckoning only). So a standing robot's
//!   reported position moves at most 8.5 mm, and between two rows at most
//!   what the wheels drove plus 17 mm (the invariants of issue 29, asserted
//!   in `tests/estimator/invariants.rs`).
//! - The position is kept within [`cfg::ARENA_MARGIN`] of the arena.
//!
//! Why not a particle filter: each particle needs the beam geometry
//! ([`Beam`](crate::model::measurement::Beam), a few hundred lx106
//! instructions) per lidar reading; the tick's budget of 15,000 instructions
//! holds about 40, far too few to cover the box's 0.4 m^2 by 360 degrees
//! with a useful density, and the DRAM left holds fewer than that at 7 states.
//! Four Kalman hypotheses cost two corrections a reading and carry what a
//! particle cloud of thousands would (a Gaussian each).
//!
//! # Numerical safety
//! - Covariance update `P - K b^T` with `b = P H^T`, `K = b / S`: symmetric
//!   by storage. The diagonal's products are rounded down.
//! - After every step the covariance's diagonal is kept between the floor
//!   and the cap (a variance past the cap scales its row and column by 1/2,
//!   `D P D`); after a correction (the step whose rounding can break it) a
//!   correlation past 1 is clamped and counted in
//!   [`EstimatorStats::repairs`]. A prediction is a congruence plus
//!   positive noise: `tests/estimator/longrun.rs` checks `P` positive
//!   definite (f64 Cholesky) after every tick for hours.
//! - No division: `1/S` by Newton's method, kept just below the exact value.
//!   A gain of 2^9 or more (impossible for a valid `P`) is not applied.
//!
//! # Arithmetic of a correction (32-bit but the state's products)
//! - Scale: the covariance entries the row reads are shifted right by `k` so
//!   that they are below 2^23 (`k = 0` below 2,048 mm^2). `b = P H^T`
//!   (`|b| < 2^27`) and `S = H b + R` (`< 2^30 + 2^28`: every `R` is at most
//!   `P_MAX`, asserted) are i32 in Q(12 - k).
//! - Gate: `nu^2` against `gate^2 S`, 64-bit products ([`mul_wide`](crate::math::mul_wide)).
//! - `S` normalised, its reciprocal from a seed table and two Newton steps;
//!   `t_i = beta_i / S` gives the gain and the update `b_i b_j / S`.
//! - The state update `K nu` is exact (Q37 -> Coord; -> angle LSB; -> Q29 scale).
//!
//! # Cost (lx106: no 32x32->64 multiply, no divide)
//! Per call figures in `lx106/BENCHMARKS.md`, measured by `lx106/run.sh`:
//! a control tick with one hypothesis about 10,300 instructions, with four
//! about 14,900 (the bar for both: 15,000; the three others' predictions
//! and one's correction, about 4,600).

// host only (std): replays CSV rows whose width is checked first
#[cfg(feature = "std")]
#[allow(clippy::indexing_slicing)]
pub mod replay;

mod constants;
mod covariance;
mod lag;
mod light;
mod outcome;
mod pivot;
mod predict;
mod report;
mod research;
mod seed;
mod spot;
mod tracker;
mod update;

use crate::config::estimator as cfg;
use crate::math::{isqrt, Angle, Dt, Length};
use crate::model::actuator::Motion;
use crate::model::measurement::Arena;
use crate::model::state::Pose;
use predict::{Bounds, Filter};

pub use crate::model::measurement::LidarId;
pub use covariance::{Covariance, BIAS, CCW, CW, N, SPEED, T, X, Y};
pub use outcome::{EstimatorStats, PoseSigma, SensorStats, Tracking, Update};
pub use predict::Scales;

/// The lever that turns a heading (or scale, or bias) error into mm:
/// `L dtheta`, L = 256 mm.
pub const HEADING_LEVER_MM: i32 = 256;

/// A hypothesis to start from (a localization's cluster): its pose, its
/// position's one-sigma per axis, and its weight (relative: only ratios
/// between the seeds matter; 0 counts as 1).
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub struct Seed {
    pub pose: Pose,
    pub sigma_x: Length,
    pub sigma_y: Length,
    pub weight: u32,
}

#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
enum Sensor {
    Front,
    Right,
    Compass,
}

impl Sensor {
    fn of(which: LidarId) -> Sensor {
        match which {
            LidarId::Front => Sensor::Front,
            LidarId::Right => Sensor::Right,
        }
    }
}

#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug, Default)]
struct EvidenceSet {
    front: tracker::Evidence,
    right: tracker::Evidence,
    compass: tracker::Evidence,
}

impl EvidenceSet {
    const FRESH: EvidenceSet = {
        let e = tracker::Evidence { counted_at: 0, counted_us: 0, fresh: true, disagreements: 0 };
        EvidenceSet { front: e, right: e, compass: e }
    };
}

/// The pose estimator. See the module docs.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub struct Estimator {
    hyps: [Filter; cfg::MAX_HYPOTHESES],
    /// Each hypothesis's cost, Q8 (the best's is 0 after every correction).
    costs: [i32; cfg::MAX_HYPOTHESES],
    /// Each hypothesis's id: a number given when it is seeded or spawned
    /// (counting up, wrapping), kept while it lives (for a replay's picture).
    ids: [u8; cfg::MAX_HYPOTHESES],
    next_id: u8,
    /// `hyps[..live]` are live (at least one).
    live: usize,
    /// The leader: the whole filter; the others are lighter (`light`).
    best: usize,
    /// The secondary that weighed the last reading (they take turns).
    turn: u8,
    /// One hypothesis leads all others by [`cfg::DOMINATE_COST`].
    dominant: bool,
    tracking: Tracking,
    /// What [`Estimator::pose`] reports (see the module docs).
    reported: Pose,
    /// How far (Q16 mm, per axis) the reported pose may still move toward
    /// the best hypothesis.
    slack: i32,
    standing: bool,
    /// Travel so far, Q16 mm (wrapping): straight distance plus turns' arcs.
    odometer: i32,
    /// Time predicted so far, us (wrapping).
    clock_us: u32,
    evidence: EvidenceSet,
    /// Where turns in place pivot, learned (`pivot`).
    pivot: pivot::Pivot,
    /// The body's move over a lidar reading's age at the last step's
    /// motion (`lag`).
    lag: lag::Lag,
    /// Where in the lidars' spot their ranges come from, learned (`spot`).
    spot: spot::Spot,
    arena: Arena,
    /// Where the hypotheses' positions are kept (the arena and its margin).
    bounds: Bounds,
    /// Where the reported position is kept: the arena itself (the reference
    /// point is on the car, inside the box).
    inside: Bounds,
    stats: EstimatorStats,
}

impl Estimator {
    /// Starts at `initial` in the config's arena, with the config's initial
    /// uncertainty (`Unknown`).
    pub fn new(initial: Pose) -> Estimator {
        Estimator::with_arena(initial, Arena::DEFAULT)
    }

    /// Starts at `initial` in `arena`.
    pub fn with_arena(initial: Pose, arena: Arena) -> Estimator {
        let m = cfg::ARENA_MARGIN;
        // Length is Q16 mm: >> 16 is the floor in whole mm (rounds each
        // bound inward: -floor(m) >= -m)
        let whole = |l: Length| l.0 >> 16;
        let bounds = Bounds {
            low_mm: -whole(m),
            high_x_mm: whole(arena.length_x.saturating_add(m)),
            high_y_mm: whole(arena.width_y.saturating_add(m)),
        };
        let filter = Filter::new(initial);
        let mut est = Estimator {
            hyps: [filter; cfg::MAX_HYPOTHESES],
            costs: [0; cfg::MAX_HYPOTHESES],
            ids: [0; cfg::MAX_HYPOTHESES],
            next_id: 0,
            live: 1,
            best: 0,
            turn: 0,
            dominant: true,
            tracking: Tracking::Unknown,
            reported: initial,
            slack: 0,
            standing: true,
            odometer: 0,
            clock_us: 0,
            evidence: EvidenceSet::FRESH,
            pivot: pivot::Pivot::START,
            lag: lag::Lag::NONE,
            spot: spot::Spot::START,
            arena,
            bounds,
            inside: Bounds { low_mm: 0, high_x_mm: whole(arena.length_x), high_y_mm: whole(arena.width_y) },
            stats: EstimatorStats::default(),
        };
        est.reset(initial);
        est
    }

    /// The reported pose (see the module docs: it never jumps).
    pub fn pose(&self) -> Pose {
        self.reported
    }

    /// Located, ambiguous or unknown.
    pub fn tracking(&self) -> Tracking {
        self.tracking
    }

    /// Ambiguous because hypotheses compete (none leads by
    /// [`cfg::DOMINATE_COST`]): the sensors' next readings weigh them,
    /// standing too (once each [`cfg::EVIDENCE_PERIOD_S`]). Not while the
    /// reported pose only lags a dominant hypothesis, which a standing
    /// robot's never closes.
    pub fn contested(&self) -> bool {
        self.tracking == Tracking::Ambiguous && !self.dominant
    }

    pub fn arena(&self) -> Arena {
        self.arena
    }

    /// Moves every hypothesis by `motion` held for `dt` (scaled by its
    /// scales) and grows the uncertainty; the reported pose dead-reckons.
    pub fn predict(&mut self, motion: Motion, dt: Dt) {
        self.predict_all(motion, dt);
    }

    /// Corrects with a lidar's model output (distance from the reference
    /// point along the beam, see [`crate::model::lidar`]), of the body a
    /// reading's age ago (`lag`).
    pub fn update_lidar(&mut self, which: LidarId, distance: Length) -> Update {
        let u = self.lidar_all(which, distance);
        self.stats_of(Sensor::of(which)).count(u);
        u
    }

    /// Corrects with a compass reading (clockwise from north).
    pub fn update_heading(&mut self, heading: Angle) -> Update {
        let u = self.heading_all(heading);
        self.stats.compass.count(u);
        u
    }

    fn stats_of(&mut self, sensor: Sensor) -> &mut SensorStats {
        match sensor {
            Sensor::Front => &mut self.stats.front,
            Sensor::Right => &mut self.stats.right,
            Sensor::Compass => &mut self.stats.compass,
        }
    }

    /// Counts of accepted and rejected readings per sensor.
    pub fn stats(&self) -> EstimatorStats {
        self.stats
    }

    /// The best hypothesis's covariance (Q12 mm^2, see [`Covariance`]).
    pub fn covariance(&self) -> Covariance {
        self.best_filter().p
    }

    /// The best hypothesis's covariance diagonal, Q12 mm^2 (see [`N`]).
    pub fn covariance_diagonal(&self) -> [i32; N] {
        self.best_filter().p.diagonal()
    }

    /// The best hypothesis's pose (the reported pose follows it; see the
    /// module docs).
    pub fn best_pose(&self) -> Pose {
        self.best_filter().pose
    }

    /// The best hypothesis's learned scales and compass bias.
    pub fn scales(&self) -> Scales {
        self.best_filter().scales
    }
    pub fn compass_bias(&self) -> Angle {
        self.best_filter().bias
    }

    /// The learned pivot of turns in place behind the axle, and the turns
    /// it was learned from (see `pivot`).
    pub fn pivot(&self) -> (Length, u32) {
        (Length(self.pivot.behind), self.pivot.samples)
    }

    /// Where in their spot the lidars' ranges come from, learned: the share
    /// of the way from the cone's nearest wall point to the beam's axis
    /// (Q30: 0 to 2^30), and the batches of readings it was learned from
    /// (see `spot`).
    pub fn lidar_spot(&self) -> (i32, u16) {
        (self.spot.share, self.spot.samples)
    }

    /// How far behind the reference point turns in place pivot (`D` plus
    /// the learned pivot), once a turn has taught it.
    pub fn learned_turn_centre(&self) -> Option<Length> {
        let p = &self.pivot;
        (p.samples > 0).then(|| crate::config::geometry::ROTATION_TO_REFERENCE.saturating_add(Length(p.behind)))
    }

    /// The live hypotheses: pose and cost (Q8, the best's 0).
    pub fn hypotheses(&self) -> impl Iterator<Item = (Pose, i32)> + '_ {
        self.hyps.iter().zip(self.costs.iter()).take(self.live).map(|(h, &c)| (h.pose, c))
    }

    /// The id of the hypothesis the reported pose follows (the best; see
    /// [`Estimator::hypotheses`]): given when it was seeded or spawned,
    /// kept while it lives.
    pub fn best_id(&self) -> u8 {
        self.ids.get(self.best).copied().unwrap_or(0)
    }

    /// One-sigma uncertainties of the best hypothesis in mm and as an angle
    /// (integer square roots, no division; for telemetry).
    pub fn sigma(&self) -> PoseSigma {
        let p = &self.best_filter().p;
        // sqrt(P Q12 mm^2) = isqrt(P) 2^-6 mm -> Q16: << 10. P <= 2^28 (2^31 at
        // most before conditioning): isqrt < 2^16, saturated.
        let len = |v: i32| Length((isqrt(v.max(0) as u32) << 10).min(i32::MAX as u32) as i32);
        // sqrt(P_tt) 2^-6 mm / L rad -> LSB: isqrt 2^-6 / 256 * 2^32 / (2 pi) = isqrt * 2^18 / (2 pi)
        let t = isqrt(p.get(T, T).max(0) as u32);
        PoseSigma { x: len(p.get(X, X)), y: len(p.get(Y, Y)), theta: Angle(t.saturating_mul(41_722)) }
    }
}
