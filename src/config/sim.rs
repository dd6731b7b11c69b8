//! The simulated robot (`sim`, host only; f64 is fine: nothing here reaches
//! the robot). Noise levels from the lab's data where it has them.

/// Lidar noise (one sigma), mm: the spread of the lab's repeated
/// readings at fixed distances (data `lidar_*.csv`, about 1.6 mm).
pub const LIDAR_NOISE_MM: f64 = 1.6;
/// Compass heading noise (one sigma), degrees: the spread of the lab's
/// check against a printed compass (data `magnetometer_heading.csv`,
/// fact sheet: about 2.5 degrees).
pub const COMPASS_NOISE_DEG: f64 = 2.5;
/// Straight speed noise per loop tick (one sigma), fraction of the
/// speed: white noise on top of the fitted lines (averages to about 1%
/// over a one-second run; the lab's runs spread by a few percent, data
/// `servo_runs.csv`, most of which the lines absorb).
pub const SPEED_NOISE: f64 = 0.10;
/// Turn rate noise per loop tick (one sigma), fraction of the rate.
pub const TURN_NOISE: f64 = 0.10;
/// Horizontal earth field after calibration, ASA-adjusted counts:
/// about 24 uT at UCLA (NOAA WMM) at 0.15 uT per count.
pub const FIELD_HORIZONTAL_COUNTS: f64 = 160.0;
/// Vertical (down) earth field, counts: about 38 uT at UCLA (NOAA WMM).
pub const FIELD_DOWN_COUNTS: f64 = 253.0;
/// Where the default run starts, mm and degrees: the first corner of
/// the built-in laps (`sim::script::default_script`), 170 mm from the
/// south and west walls, where the front lidar's cone meets the wall
/// ahead before the side wall.
pub const START_X_MM: f64 = 170.0;
pub const START_Y_MM: f64 = 170.0;
pub const START_HEADING_DEG: f64 = 0.0;
/// Half the car's width at the wheels, mm (the 85 mm axle): a wheel
/// that would pass a wall is a collision.
pub const HALF_TRACK_MM: f64 = 42.5;

// The realistic simulator's effects (`sim::realism`; each an option of
// `simulate`).

/// Trial-to-trial spread of the speed, one sigma, fraction, per motion
/// (forward, backward, clockwise, counter-clockwise): each motion runs at
/// its line's speed times one factor drawn for it. Data `servo_runs.csv`:
/// the rms over the five command pairs of the ten timed runs' relative
/// spread, 1.9 %, 2.5 %, 2.6 %, 1.1 %.
pub const SPEED_SPREAD: [f64; 4] = [0.019, 0.025, 0.026, 0.011];
/// A turn in place pivots about a point this far behind the axle's
/// midpoint on average, mm: the paper skid drags ~70 mm behind the axle
/// (fact sheet) and holds the tail back. Not measured (the lab timed turns
/// only); 10 mm, a seventh of the way to the skid, is an assumption.
pub const PIVOT_BEHIND_AXLE_MM: f64 = 10.0;
/// Spread of that point from turn to turn, one sigma, mm (assumed, as
/// the mean: the skid's grip changes with the paper and the floor).
pub const PIVOT_SPREAD_MM: f64 = 5.0;
/// The lidar's cone, full angle, degrees: the sensor's (`lidar::CONE_DEG`).
pub const LIDAR_CONE_DEG: f64 = super::lidar::CONE_DEG;
/// Readings start failing past this incidence of the beam's axis on the
/// wall, degrees, all fail at 90 (the lab 2 README: glancing readings
/// fail; the lab measured square on only, so the onset is assumed).
pub const GLANCING_DEG: f64 = 60.0;
/// Of the failed readings, the share that is a spurious echo (0.3 to 1.5
/// times the true distance) rather than "no target" (assumed).
pub const SPURIOUS_SHARE: f64 = 0.3;
/// Compass disturbance: amplitude of the heading error that varies over
/// the floor, degrees (assumed: within the lab's 2.5-degree spread
/// against a printed compass, data `magnetometer_heading.csv`).
pub const COMPASS_DISTURBANCE_DEG: f64 = 2.0;
/// Wavelength of that pattern over the floor, mm (about the box's length).
pub const COMPASS_DISTURBANCE_WAVELENGTH_MM: f64 = 800.0;

// The hard world (`sim::realism::Realism::HARD`, `simulate --realism
// hard`): what real paper robots do that the lab's data does not show.
// The lab measured free-running servos and square-on lidar readings; these
// widen each belief to what a drive off the bench meets (issue #29), so a
// test passing here does not rest on the lab's lines being right. Each
// run draws its values once from its seed (`sim::drawn`).

/// Each turn direction's rate is its line's times a factor drawn per run
/// uniformly in this range (per direction): in-place turns of paper robots
/// run far off free-running fits (battery, floor, the dragging skid;
/// issue #29). Fraction.
pub const HARD_TURN_SCALE: (f64, f64) = (0.6, 1.8);
/// That factor drifts during the run by this fraction of itself, one
/// slow sine per direction (the battery sagging, the skid's paper
/// wearing; assumed), and stays within `HARD_TURN_SCALE`.
pub const HARD_TURN_DRIFT: f64 = 0.10;
/// The drift's period, s (a few laps; assumed).
pub const HARD_TURN_DRIFT_PERIOD_S: f64 = 240.0;
/// Straight speed is its line's times a factor drawn per run uniformly
/// within this of 1 (the same servos on another floor and battery;
/// issue #29: +-15 %). Fraction.
pub const HARD_SPEED_SCALE: f64 = 0.15;
/// The turn's pivot sits this far behind the axle on average, mm: the
/// skid's drag pulls the turn's centre most of the way to the skid
/// (about 70 mm behind, PAPERBOT; issue #29: 60 +- 20 mm) ...
pub const HARD_PIVOT_BEHIND_AXLE_MM: f64 = 60.0;
/// ... offset per run uniformly within this, mm (the lab's turn-to-turn
/// spread, `PIVOT_SPREAD_MM`, comes on top).
pub const HARD_PIVOT_RUN_MM: f64 = 20.0;
/// Compass bias over the floor, degrees: the lab's smooth pattern at this
/// amplitude (desks, steel under the floor; issue #29: +-12 degrees) ...
pub const HARD_COMPASS_FLOOR_DEG: f64 = 12.0;
/// ... reaching this near the walls, degrees (the box's fixings, a radiator
/// or a laptop behind a wall; issue #29: excursions of 20).
pub const HARD_COMPASS_WALL_DEG: f64 = 20.0;
/// The wall excursion falls off by e over this distance from the wall, mm
/// (a magnetized object's field falls off fast; assumed).
pub const HARD_COMPASS_WALL_DECAY_MM: f64 = 60.0;
/// Wavelength of the wall excursion's pattern along the walls, mm (about
/// the box's short side; assumed).
pub const HARD_COMPASS_WALL_WAVELENGTH_MM: f64 = 500.0;
/// Lidar noise grows with incidence: one sigma of this fraction of the
/// range times tan(incidence) on top of `LIDAR_NOISE_MM` (the beam's
/// footprint spans ranges that spread with the slope of the wall; the
/// VL53L0X's 25-degree emitter cone, datasheet, gives 0.2 at the edge; a
/// quarter of that, assumed). tan is capped at 80 degrees.
pub const HARD_LIDAR_INCIDENCE_NOISE: f64 = 0.05;
/// Share of all lidar readings that are spurious (0.3 to 1.5 times the
/// true range), whatever the incidence (issue #29: 5 %; multipath,
/// cross-talk, a hand in the box).
pub const HARD_SPURIOUS_RATE: f64 = 0.05;
/// A beam whose footprint (this half-angle about its axis, degrees: the
/// emitter's 25-degree cone, datasheet) spans two walls near a corner
/// returns a mix of their ranges: a weight drawn uniformly between them
/// (mixed returns; issue #29).
pub const HARD_CORNER_MIX_HALF_DEG: f64 = 12.5;
