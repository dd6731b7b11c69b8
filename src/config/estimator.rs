//! The pose estimator (`model::estimator`): noise levels, gates and limits.
//! Units: lengths in mm, angles in degrees, converted at compile time.

use super::Length;

/// Spread of a lidar's model output, mm: the readings' spread about their
/// mean at a fixed distance is 1.6 mm and the fitted line misses the
/// per-distance means by up to 1.4 mm (data `lidar_*.csv`: rms residual
/// of the report's lines over all readings 1.86 mm front, 1.70 mm right).
pub const LIDAR_SIGMA: Length = Length::from_mm_f64(2.0);
/// Spread of the calibrated compass heading, degrees (data
/// `magnetometer_heading.csv`, fact sheet: about 2.5 degrees).
pub const COMPASS_SIGMA_DEG: f64 = 2.5;
/// Relative spread of the car's speed going straight (std/mean of the
/// timed runs of one command pair; data `servo_runs.csv`: rms over the
/// pairs 1.9 % forward, 2.5 % backward; the larger is used).
pub const SPEED_SPREAD: f64 = 0.025;
/// Relative spread of the turn rate (data `servo_runs.csv`: rms over the
/// pairs 2.6 % clockwise, 1.1 % counter-clockwise; the larger is used).
pub const TURN_SPREAD: f64 = 0.026;
/// A speed error holds for a whole run, not a tick: the estimator models
/// it as a random walk whose variance over this distance equals the
/// spread squared (the lab's timed run was 450 mm, data `servo_runs.csv`).
pub const SPEED_CORRELATION_MM: f64 = 450.0;
/// The same for turns, degrees of turning (one 90-degree turn: the
/// drives the estimator is tested on turn by quarter turns).
pub const TURN_CORRELATION_DEG: f64 = 90.0;
/// A turn in place does not pivot exactly about the axle: the paper skid
/// drags (fact sheet) and moves the pivot by this much, one sigma, mm. The
/// estimator adds it as position noise across the car per angle turned
/// (a random walk over `TURN_CORRELATION_DEG`), so after a turn it
/// follows the lidars instead of gating them out. The simulator's pivot
/// (`sim::PIVOT_BEHIND_AXLE_MM` and its spread) lies within it.
pub const PIVOT_SIGMA_MM: f64 = 12.0;
/// Where a turn in place pivots is learned too (issue 29,
/// `model::estimator::pivot`): its distance behind the axle starts at 0
/// (about the axle, the lab's model) with this uncertainty, one sigma, mm.
/// Real skids drag the pivot tens of mm behind the axle (the hard
/// simulator's 60 +- 20 mm per run).
pub const PIVOT_STATE_SIGMA_MM: f64 = 40.0;
/// The learned pivot's bounds, mm behind the axle (ahead: negative): the
/// hard simulator's 60 +- 20 mm and its turn-to-turn spread inside. With
/// `geometry::ROTATION_TO_REFERENCE` their sum stays below 256 mm, which
/// the turn's Jacobian is sized for.
pub const PIVOT_MIN_MM: f64 = -20.0;
pub const PIVOT_MAX_MM: f64 = 110.0;
/// The learned pivot's random walk, mm^2 per second (it changes with the
/// floor and the battery, slowly): 1 mm after 100 s.
pub const PIVOT_WALK_MM2_PER_S: f64 = 0.01;
/// A turn teaches the pivot once this long has passed since its last
/// turning step, ms: the lidars' first readings after it (30 Hz, two
/// lidars) have corrected where it left the robot.
pub const PIVOT_SETTLE_MS: u32 = 300;
/// A turn teaches the pivot only if the lidars corrected the leading
/// hypothesis at least this often while it turned and settled (two lidars
/// at 30 Hz: a fifth of a second of readings); a turn the lidars did not
/// see (a localization's: its readings go to the search) teaches nothing.
pub const PIVOT_MIN_CORRECTIONS: u32 = 12;
/// Turns smaller than this teach nothing, degrees: their chord is short
/// against the corrections' noise.
pub const PIVOT_MIN_TURN_DEG: f64 = 30.0;
/// One sigma of what a turn's corrections along its chord carry besides
/// the pivot's error (the lidars' noise over the turn's readings, the
/// heading's share), mm: over the chord (1.4 for a quarter turn) the
/// sample's sigma.
pub const PIVOT_SAMPLE_SIGMA_MM: f64 = 6.0;
/// Where in its spot a lidar's range comes from, as a share of the way from
/// the cone's nearest wall point (0) to the beam's axis (1), learned
/// (`model::estimator`'s spot.rs). It starts at the nearest point: the lab
/// 2 README's "a beam 25 degrees wide that sees the nearest thing in its
/// cone" (`tests/data/lab2/README.md`) ...
pub const SPOT_SHARE_START: f64 = 0.0;
/// ... with this one-sigma uncertainty: a thin beam (issue 29's hard
/// world, a share of 1) is two sigmas away.
pub const SPOT_SHARE_SIGMA: f64 = 0.5;
/// Counted readings of the leader per sample of the share (learned at the
/// next standing tick): 16 readings met off square (a spread of 10-40 mm
/// each at the box's ranges) sample it within about 0.1-0.2. The hard
/// world's power-up laps (`tests/sim/hard_world.rs`) measured 17.7 mm
/// median RMS and 26.3 mm the worst located run with 16, 17.0 and 71.0
/// with 32 (its runs spread by several mm from small changes).
pub const SPOT_BATCH: u16 = 16;
/// Readings whose spot spreads less than this along the wall's normal
/// teach nothing about the share, mm: met nearly square on, the cone's
/// nearest point and the axis's meet (the lidar's 2 mm sigma).
pub const SPOT_MIN_SPREAD_MM: f64 = 2.0;
/// ... nor do readings whose spot spreads more than this, mm: the batch is
/// a least-squares fit, and one glancing reading at a long range (a
/// spread of 100 mm and more, where the lab's world returns spurious
/// echoes) outweighs the rest: one echo 130 mm long with a spread of 126
/// took the share from 0 to 0.46 in the lab's world
/// (`tests/control/untethered.rs`, seed 2). A reading's innovation counts
/// as at most twice its spread (a share of 2).
pub const SPOT_MAX_SPREAD_MM: f64 = 100.0;
/// The least sigma of what a reading's innovation carries besides the
/// share's error (the lidar's noise off square, `LIDAR_INCIDENCE_SIGMA_MM`,
/// and the pose's), mm: a batch's own scatter about its line counts when
/// larger; over the batch's `sqrt(sum g^2)` the sample's sigma.
pub const SPOT_SAMPLE_SIGMA_MM: f64 = 15.0;
/// The share's random walk per sample, one sigma: it never stops
/// learning (another wall's surface, a battery that changes the
/// sensor's timing).
pub const SPOT_WALK_PER_SAMPLE: f64 = 0.02;
/// Extra position noise always added, mm^2 per second: keeps the
/// covariance a margin away from singular (a turn's noise is rank one)
/// and from collapsing while the robot stands still; 0.7 mm after a
/// second, small against the lidars' 2 mm at 30 Hz.
pub const POSITION_FLOOR_MM2_PER_S: f64 = 0.5;
/// Extra heading noise always added, deg^2 per second (same reason;
/// 0.2 degrees after a second).
pub const HEADING_FLOOR_DEG2_PER_S: f64 = 0.05;
/// Innovation gate, standard deviations: a reading further than this
/// from its prediction is counted as an outlier and not used (3.5 sigma
/// passes 99.95 % of good readings).
pub const GATE_SIGMAS: f64 = 3.5;
/// Lidar readings hitting their wall further than this from square on
/// are not used: past it the linearisation of the range in the heading
/// breaks down (the range grows as 1 / cos), degrees. Below it a reading's
/// noise grows with the incidence (`LIDAR_INCIDENCE_SIGMA_MM`) instead of a
/// hard accept/refuse cut (issue 29).
pub const MAX_INCIDENCE_DEG: f64 = 75.0;
/// How much a lidar reading's spread grows with the incidence of its cone
/// on the wall, mm per unit of `tan(incidence)`: a beam meeting its wall
/// off square returns a range from somewhere in its spot, which spreads
/// along the wall by about the range times the cone's width (issue 29:
/// glancing beams return ranges a hard cone does not predict). The
/// reading's variance is `LIDAR_SIGMA^2 + (this tan(incidence))^2`: 15 mm
/// at 45 degrees, 26 mm at 60, 56 mm at 75.
pub const LIDAR_INCIDENCE_SIGMA_MM: f64 = 15.0;
/// Lidar readings whose cone meets two walls at ranges closer than this,
/// mm, are not used: the sensor mixes the two walls' returns, which no
/// one wall explains (without the cut the real drive's estimate,
/// tests/estimator/lab2_drive.rs, is lost and the hard world's laps run
/// into walls). Beyond it the heading decides (`CORNER_SIGMAS`): with that,
/// 30 mm passes every test 40 does, 50 all but the count of drive1's
/// hypotheses in its replay (tests/tools/basics.rs); alone, as the only
/// corner test, 35 failed the realistic hours and 45 the real drive.
pub const CORNER_MARGIN: Length = Length::from_mm_f64(40.0);
/// A lidar reading whose cone meets two walls at nearly the same range
/// may have come from either: a side wall met at the cone's edge moves its
/// nearest point by 30 mm and more per degree of heading at the box's
/// distances, so which wall is nearest turns on the heading's error
/// (`model::measurement::Beam::corner_reading` has the geometry). Such a
/// reading's variance grows by this floor squared, mm (the wall's pick
/// with the heading known: the position's and the reading's noise), plus
/// the square of what one sigma of the hypothesis's heading moves the two
/// walls' ranges apart ...
pub const CORNER_SIGMA_FLOOR_MM: f64 = 5.0;
/// ... when the two walls' ranges are within this many of those sigmas
/// (farther apart, no heading error the hypothesis allows picks the other
/// wall). Before, a reading beyond `CORNER_MARGIN` counted in full: the
/// realistic hours with the refined power-up met a turn at a corner, the
/// heading 2 sigma off, that took the other wall's reading for its own
/// and lagged 32 mm (tests/sim/realistic_hour.rs; 16 mm now), and the real
/// drive started at a wrong pose stayed 116 mm off (5 mm now).
pub const CORNER_SIGMAS: f64 = 3.0;
/// The largest corner margin, mm: beyond it the cone's nearest points on
/// the two walls are told apart by any heading (a heading sigma of 2
/// degrees at 700 mm asks 160 mm).
pub const CORNER_MARGIN_MAX: Length = Length::from_mm_f64(160.0);
/// Initial position uncertainty (one sigma), mm: the robot is put down by
/// hand near its start pose.
pub const INITIAL_SIGMA_MM: f64 = 100.0;
/// Initial heading uncertainty (one sigma), degrees.
pub const INITIAL_SIGMA_DEG: f64 = 20.0;
/// Largest position or heading variance kept, mm^2 (heading as (256 mm
/// x rad)^2, see the estimator): 256 mm (57 degrees) one sigma. Past it
/// the row and column are scaled down, which keeps the covariance valid.
pub const MAX_VARIANCE_MM2: f64 = 65536.0;
/// Smallest variance kept, mm^2 (same units): 0.1 mm, 0.02 degrees.
pub const MIN_VARIANCE_MM2: f64 = 0.01;
/// The estimate is kept within this distance outside the arena's walls,
/// mm: the reference point is on the car, always inside the box, so a
/// position further out is known wrong (dead reckoning while the body is
/// held at a wall). 50 mm is more than three times the estimator's
/// tracking error (15 mm rms), so a tracking estimate never meets it.
pub const ARENA_MARGIN: Length = Length::from_mm_f64(50.0);

/// The honest models' states (issue 29): what the filter starts believing
/// about the speed and turn-rate scales (1 = the config's actuator lines)
/// and the compass's bias, one sigma, and how fast each drifts.
/// Speed scale: the car's straight speed over the lines' (battery, floor):
/// +-15 % between runs (issue 29), learned from the lidars.
pub const SPEED_SCALE_SIGMA: f64 = 0.15;
/// Turn-rate scale, per direction (clockwise, counter-clockwise): in-place
/// turns run 0.6-1.8 times the free-running fits on real paper robots
/// (battery, floor, the dragging skid; issue 29), learned from the compass
/// and the lidars. One sigma about 1: 0.6 and 1.8 are within two.
pub const TURN_SCALE_SIGMA: f64 = 0.4;
/// The scales drift slowly during a run: a random walk of this much per
/// square root of a second of the motion it scales (one sigma).
pub const SCALE_WALK_PER_SQRT_S: f64 = 0.01;
/// The scales are kept within these bounds (a projection after every
/// correction; the covariance is left alone): issue 29's 0.6-1.8 with a
/// margin. Below half its line a turn is a wheel held (against a wall),
/// not a scale: the compass's disagreement then starts a re-search instead
/// of teaching the filter a turn rate it will not see again.
pub const SCALE_MIN: f64 = 0.5;
pub const SCALE_MAX: f64 = 2.5;
/// The compass's bias (a heading offset from desks, walls, the floor's
/// iron): unknown at the start within this, degrees one sigma.
pub const COMPASS_BIAS_SIGMA_DEG: f64 = 10.0;
/// The bias varies over the floor: a random walk of this variance per mm
/// driven, deg^2 (5 degrees after 100 mm; issue 29: up to +-12 degrees
/// over the floor, excursions of 20 near walls).
pub const COMPASS_BIAS_WALK_DEG2_PER_MM: f64 = 0.25;
/// The bias is kept within this, degrees (a projection after every
/// correction): issue 29's worst is 20 near walls; a larger offset is a
/// lost heading, not a bias.
pub const COMPASS_BIAS_MAX_DEG: f64 = 25.0;
/// And a little while standing or turning, deg^2 per second.
pub const COMPASS_BIAS_WALK_DEG2_PER_S: f64 = 0.05;

/// The multi-hypothesis tracker (issue 29, "no teleports").
/// Hypotheses kept at most: each is a whole filter (pose, scales, bias,
/// 7 x 7 covariance), and every reading corrects each; the tick's budget
/// (15,000 lx106 instructions a correction tick) holds four.
pub const MAX_HYPOTHESES: usize = 4;
/// A reading counts toward a hypothesis's weight only after the robot has
/// moved this far (mm, a turn counted by its arc at 100 mm) since that
/// sensor's last counted reading: ten readings of a standing robot are one
/// piece of evidence, not ten.
pub const EVIDENCE_TRAVEL_MM: f64 = 10.0;
/// And once this long has passed since that sensor's last counted reading,
/// seconds, moving or not: a body can move while its servos stand (a
/// trimmed neutral creeps, a hand turns it; `tests/control/soak.rs` does both), and
/// the sensors must win then too, slowly.
pub const EVIDENCE_PERIOD_S: f64 = 1.0;
/// Cost (a sum of normalised squared innovations) a reading the gate
/// rejects adds to a hypothesis: more than the gate's square, so a
/// hypothesis that explains a reading always beats one that does not.
pub const OUTLIER_COST: f64 = 16.0;
/// A hypothesis dominates when every other costs this much more (a
/// likelihood ratio of e^(cost/2): 9.2 is 100 to 1). While none dominates
/// the estimator is `Ambiguous`.
pub const DOMINATE_COST: f64 = 9.2;
/// A hypothesis costing this much more than the best is dropped (e^-20).
pub const PRUNE_COST: f64 = 40.0;
/// What a new hypothesis from a local re-search starts behind the best
/// (it must explain readings the best does not to win).
pub const SPAWN_COST: f64 = 4.0;
/// A start from a typed pose (the config's initial uncertainty) is
/// `Unknown`, its reported pose the filter's, until both position sigmas
/// are below this, mm; from then on it is `Located` and the reported pose
/// follows at the catch-up's pace.
pub const LOCATED_SIGMA_MM: f64 = 30.0;
/// Counted disagreements (outliers of one sensor, each after the robot
/// moved `EVIDENCE_TRAVEL_MM` or `EVIDENCE_PERIOD_S` passed) after which the
/// best hypothesis is re-searched locally: a new hypothesis takes the
/// sensor's side. While the servos stand still one is enough (it is all
/// the evidence a standing robot gets for a second).
pub const RESEARCH_AFTER: u8 = 3;
/// A lidar's re-search: the new hypothesis's position uncertainty, one
/// sigma per axis, mm, before it takes the reading.
pub const RESEARCH_SIGMA_MM: f64 = 60.0;
/// Two hypotheses closer than this (mm on each axis, and
/// `MERGE_DEG` in heading) are one: the costlier is dropped.
pub const MERGE_MM: f64 = 15.0;
pub const MERGE_DEG: f64 = 8.0;
/// The reported pose follows the best hypothesis's corrections at most
/// this fast (no teleports): mm per mm the robot moves, plus mm per
/// second of motion; the slack saved up is at most `CATCH_UP_MAX_MM`
/// (per axis) moving and `CATCH_UP_STANDING_MM` once the servos stand
/// still (so a standing robot's reported position moves at most that
/// much times sqrt 2: the invariant's 10 mm).
pub const CATCH_UP_PER_MM: f64 = 0.5;
pub const CATCH_UP_MM_PER_S: f64 = 20.0;
pub const CATCH_UP_MAX_MM: f64 = 12.0;
pub const CATCH_UP_STANDING_MM: f64 = 6.0;
/// While the reported position is farther than this from the dominant
/// hypothesis (per axis), mm, the estimator is still `Ambiguous` (the robot
/// is not where it says): a fix's first corrections (10-20 mm) stay below.
pub const AMBIGUOUS_GAP_MM: f64 = 50.0;
