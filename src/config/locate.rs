//! Localization (`model::locate`): where in the box the robot is, searched
//! at power-up and on `locate` from the compass and the two lidars.

/// Grid step of the search, mm: 15,000 points in the team's box, each
/// two lidar models (about 0.2 s on the lx106, lx106/BENCHMARKS.md).
pub const GRID_MM: i32 = 5;
/// A grid point explains a reading within this, mm: three lidar sigmas
/// (`estimator::LIDAR_SIGMA`: 6 mm), half the grid's diagonal (3.5 mm),
/// and what the compass's spread (2.5 degrees, `estimator::
/// COMPASS_SIGMA_DEG`) moves an oblique beam's reading at typical
/// ranges (a few mm).
pub const TOLERANCE_MM: f64 = 12.0;
/// Points that explain the readings spread over more than this on an
/// axis: the fix is ambiguous (reported as such), mm. Two tolerances
/// and a grid step over the span of one point's neighbourhood.
pub const AMBIGUOUS_SPAN_MM: i32 = 60;
/// A consistent point within this of a cluster's bounding box joins it,
/// mm (`model::locate::clusters`): a place's points lie on the grid's
/// step, and a hole of a point or two (a reading at the edge of the
/// tolerance) must not split one place in two. Clusters that together
/// span no more than `AMBIGUOUS_SPAN_MM` are one place anyway.
pub const CLUSTER_GAP_MM: i32 = 3 * GRID_MM;
/// A view taken after turns in place explains its readings within
/// this more, mm: the turn's pivot is one of `PIVOTS_BEHIND_AXLE_MM`
/// give or take 12.5 mm, which after a quarter turn moves the reference
/// point by up to 18 mm, and a turn's own spread (the lab's 5 mm).
pub const TURN_TOLERANCE_MM: f64 = 20.0;
/// With more readings than this over all views, the search lets one of
/// them go unexplained (a glancing reading's spurious echo,
/// `sim::SPURIOUS_SHARE`; the hard world's 5 % spurious readings and mixed
/// returns near corners): the rest still pin the pose.
pub const MIN_READINGS_FOR_OUTLIER: u32 = 3;
/// The compass offsets the search tries are this far apart, degrees (the
/// compass's 2.5-degree spread, `estimator::COMPASS_SIGMA_DEG`) ...
pub const HEADING_STEP_DEG: f64 = 2.5;
/// ... up to this many each way when nothing fits within `BIAS_STEPS`
/// (30 degrees: the real drive's compass, `tests/data/lab2/drive1.csv`,
/// is fitted by no pose within 10 degrees of its first reading; the box
/// is only roughly aligned with north).
pub const HEADING_STEPS: u8 = 12;
/// A reading whose beam would meet its wall past this incidence, at a
/// point the search tries, says nothing about that point, degrees:
/// glancing readings fail or come back as spurious echoes (the lab 2
/// README; the simulator's `sim::GLANCING_DEG` onset, where half fail).
pub const GLANCING_DEG: f64 = 75.0;
/// Readings per lidar in a view, whose median the search takes: five
/// lidar periods (0.17 s); the median takes the lidar's 1.6 mm spread
/// to about 1 mm and drops a spurious echo or two.
pub const LIDAR_READINGS: u8 = 5;
/// Compass readings averaged: 0.2 s at 100 Hz; the compass's spread
/// against the truth is mostly per heading, not per reading, so more
/// would not help (data `magnetometer_heading.csv`).
pub const COMPASS_READINGS: u8 = 20;
/// A view's readings are taken for at most this long, ms; a lidar that
/// gave fewer than `LIDAR_READINGS` by then gives the median of what it
/// gave (none: no distance in that view). Five lidar periods and a
/// half: room for a dropped reading or two.
pub const VIEW_LIMIT_MS: u32 = 300;
/// The robot localizes at power-up (the firmware and the simulator),
/// turning in place: set false to start at the box's centre, unknown
/// (`pose` or `locate` then).
pub const AT_POWER_UP: bool = true;
/// Views taken before the first search: two views can agree on a
/// wrong pose far off (`tests/localization/locate.rs`: 75 % right from two, 99.2 %
/// from three).
pub const MIN_VIEWS: usize = 3;
/// The turn in place between views, degrees: two views at 45 degrees
/// put the beams on walls of both axes from most of the box.
pub const TURN_DEG: i32 = 45;
/// Its rate, mrad/s: `goto`'s turn rate (`goto::TURN_MRAD_S`).
pub const TURN_MRAD_S: i32 = super::goto::TURN_MRAD_S;
/// The body stands this long after a turn before its view is taken,
/// ms: the servos stop within a tick (data `servo_runs.csv`), and a
/// lidar reading begun while turning (33 ms each) is over.
pub const SETTLE_MS: u32 = 100;
/// A turn the compass says moved less than this, degrees, was blocked
/// (the body against a wall): the next turns go the other way.
pub const BLOCKED_TURN_DEG: i32 = 20;
/// Grid columns searched per loop tick (a column is 99 points of the
/// team's box): two take up to 275,000 lx106 instructions (the worst
/// slice of the search in lx106/BENCHMARKS.md), a third of the 10 ms
/// tick at 80 MHz and one instruction a cycle (half at 1.5 cycles),
/// which leaves the tick's own work room; a pass over the box takes 77
/// ticks (0.8 s).
pub const COLUMNS_PER_TICK: u32 = 2;
/// The whole procedure's time limit, ms: eight views (5 s) and, after
/// each from the third on, a search of up to 17 passes (the compass's
/// bias range, `BIAS_STEPS`: 13 s each).
pub const TIME_LIMIT_MS: u32 = 120_000;
/// The compass's bias is the same at the views of one standing robot
/// (taken at one place) but unknown: the search tries every offset
/// `HEADING_STEP_DEG` apart up to this many steps each way and keeps the
/// one that explains the views best (20 degrees: issue #29's +-12 over
/// the floor and 20 near walls, `sim::HARD_COMPASS_WALL_DEG`); further,
/// up to `HEADING_STEPS`, only while nothing fits.
pub const BIAS_STEPS: u8 = 8;
/// Each step of compass offset from the compass's own heading adds this
/// to a pass's cost, mm (summed misses along the walls' normals): a prior
/// that the compass is more often near right than far off (the lab's
/// 2.5-degree spread, `estimator::COMPASS_SIGMA_DEG`), so views that fit
/// nearly as well at several offsets take the compass's. A third of a
/// reading's tolerance a step.
pub const BIAS_PRIOR_MM_PER_STEP: f64 = 4.0;
/// The turn's pivot behind the axle, tried by the search, mm: the lab's
/// 10 (`sim::PIVOT_BEHIND_AXLE_MM`) and the hard world's 60 +- 20
/// (`sim::HARD_PIVOT_BEHIND_AXLE_MM`, issue #29), each within 12.5 of
/// one tried, which after a quarter turn moves the reference point by
/// under `TURN_TOLERANCE_MM`.
pub const PIVOTS_BEHIND_AXLE_MM: [i32; 4] = [10, 35, 60, 85];
/// Another compass offset's best point, far from the best one's, fitting
/// within this much of its cost makes the fix ambiguous, mm: one
/// reading's tolerance.
pub const RIVAL_MARGIN_MM: f64 = TOLERANCE_MM;
/// So does another offset's this many heading steps or more from the
/// best one's, fitting within that margin: the readings do not say which
/// heading (two steps: 5 degrees, a right fix's limit).
pub const RIVAL_STEPS: u32 = 2;
