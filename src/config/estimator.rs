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
/// are not used (the VL53L0X's 25-degree cone makes oblique readings
/// short; the linearisation also degrades), degrees.
pub const MAX_INCIDENCE_DEG: f64 = 60.0;
/// Lidar readings whose cone meets two walls at ranges closer than this
/// are not used (which wall the reading came from is uncertain), mm. A
/// side wall met at the cone's edge moves its nearest point by about
/// 30 mm per degree of heading at the box's distances (160 mm from the
/// wall, 17 degrees off its line), so a one-degree heading error can pick
/// the wrong wall inside 30 mm, and a turn at a corner sweeps the
/// cone's edge across a glancing wall: at 35 mm the realistic
/// simulator's hours, from the power-up localization, took such a
/// reading as the other wall's and jumped 22 mm (tests/sim/realistic_hour.rs:
/// worst 34.4 mm over 20 seeds; at 40 mm, 24.0 mm). Larger is not
/// better: from 45 mm the real drive (tests/estimator/lab2_drive.rs) loses
/// readings it needs and steps further than the wheels drive.
pub const CORNER_MARGIN: Length = Length::from_mm_f64(40.0);
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
/// Outliers in a row from one sensor after which the estimator takes the
/// sensor's side, readings: it re-inflates the variances that sensor
/// reads (compass: the heading's, to `MAX_VARIANCE_MM2`; a lidar: the
/// position's, to `REACQUIRE_SIGMA_MM`), drops their correlations, and
/// uses the reading with its innovation clipped to the gate (so the step
/// stays within `GATE_SIGMAS` of the re-inflated covariance). Without it
/// a wrong estimate further than the gate from the truth (a wheel held
/// at a wall for 0.3 s of a turn: 41 degrees) rejects every true reading
/// for ever. A good reading fails the 3.5-sigma gate with probability
/// 5e-4, so ten in a row do not happen by chance, nor from the 1-10 % of
/// corrupted transactions the fault tests inject; ten are 0.1 s of
/// compass (100 Hz) and 0.33 s of one lidar (30 Hz). Single outliers
/// stay rejected.
pub const REACQUIRE_AFTER: u8 = 10;
/// Position uncertainty a lidar's re-acquisition starts from (one sigma
/// on each axis, uncorrelated; a larger variance already held is kept),
/// mm. One re-acquisition moves the position at most `GATE_SIGMAS`
/// times this (157 mm), so a lost estimate walks back to the lidars in
/// bounded steps, one per run of `REACQUIRE_AFTER` outliers, instead of
/// jumping across the box. The real robot's turns leave position errors
/// of about 100 mm (issue 23): one step covers them. Measured
/// (tests/estimator/no_teleport.rs, a robot standing 550 mm from where
/// a settled estimate believes it): 4 re-acquisitions, 1.2 s until
/// within 20 mm; at 30 mm, 6 steps of 105 mm and 1.5-1.8 s; at 60 mm,
/// 3 steps of 210 mm and 0.9 s. The realistic simulated hour (worst
/// 24 mm), the soak (90 % of errors below 20 mm) and the real drive's
/// largest step (4.0-4.2 mm) do not change from 30 to 60 mm.
pub const REACQUIRE_SIGMA_MM: f64 = 45.0;
/// The estimate is kept within this distance outside the arena's walls,
/// mm: the reference point is on the car, always inside the box, so a
/// position further out is known wrong (dead reckoning while the body is
/// held at a wall). 50 mm is more than three times the estimator's
/// tracking error (15 mm rms), so a tracking estimate never meets it.
pub const ARENA_MARGIN: Length = Length::from_mm_f64(50.0);
