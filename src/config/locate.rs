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
/// point by up to 18 mm, and a turn's own spread (the lab's 5 mm,
/// `sim::PIVOT_SPREAD_MM`).
pub const TURN_TOLERANCE_MM: f64 = 12.0;
/// The turn's pivot behind the axle, tried by the search at every grid
/// point that explains the first view (`model::locate`'s view.rs), mm:
/// the lab's 10 (`sim::PIVOT_BEHIND_AXLE_MM`) and the hard world's
/// 60 +- 20 (`sim::HARD_PIVOT_BEHIND_AXLE_MM`, issue #29), each within
/// 12.5 of one tried.
pub const PIVOTS_BEHIND_AXLE_MM: [i32; 5] = [10, 30, 50, 70, 90];
/// Each pivot further down `PIVOTS_BEHIND_AXLE_MM` adds this to a
/// point's summed misses, mm: readings that fit about as well with the
/// lab's pivot take it.
pub const PIVOT_PRIOR_MM: f64 = 3.0;
/// With more readings than this over all views, the search lets one of
/// them go unexplained when nothing explains them all (a glancing
/// reading's spurious echo, `sim::SPURIOUS_SHARE`): the rest still pin
/// the pose.
pub const MIN_READINGS_FOR_OUTLIER: u32 = 3;
/// Readings that may go unexplained: one for each this many over all
/// views (a pass each, only when fewer leave nothing that fits) ...
pub const READINGS_PER_UNEXPLAINED: u32 = 4;
/// ... up to this many (four views, 8 readings: issue #29's hard world
/// has 5 % spurious readings and mixed returns near corners; a fix that
/// needs two is reported uncertain, `model::locate::Fix::untrusted`).
pub const MAX_UNEXPLAINED: u32 = 2;
/// A fix that leaves a reading unexplained resting on fewer grid points
/// than this is reported uncertain (`model::locate::Fix::untrusted`): in
/// the lab's world 1 right fix of 1,000 is such, in issue #29's hard
/// world 79 wrong ones and 29 right (`tests/localization/locate.rs`,
/// three views).
pub const MIN_POINTS_WITH_OUTLIER: u32 = 10;
/// When nothing fits at the compass's heading, the search tries headings
/// this far apart, degrees (the compass's 2.5-degree spread, `estimator::
/// COMPASS_SIGMA_DEG`) ...
pub const HEADING_STEP_DEG: f64 = 2.5;
/// ... up to this many each way (30 degrees: the real drive's compass,
/// `tests/data/lab2/drive1.csv`, is fitted by no pose within 10 degrees
/// of its first reading; the box is only roughly aligned with north).
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
/// wrong pose far off (`tests/localization/locate.rs`: 75 % right from
/// two, 99.2 % from three with the pivot at the axle), and the turn's
/// pivot is one more unknown (the lab's world: 989 right and 2 wrong and
/// not flagged of 1,000 from three, 991 and none from four; issue #29's
/// hard world: 272 right and 392 wrong unflagged from three, 316 and
/// 277 from four).
pub const MIN_VIEWS: usize = 4;
/// The turn in place between views, degrees: two views at 45 degrees
/// put the beams on walls of both axes from most of the box.
pub const TURN_DEG: i32 = 45;
/// Its rate, mrad/s: `goto`'s turn rate (`goto::TURN_MRAD_S`).
pub const TURN_MRAD_S: i32 = super::goto::TURN_MRAD_S;
/// A turn between views ends when the compass shows its angle
/// (`control::survey`'s turning.rs), or after this share of the ticks
/// `TURN_MRAD_S` takes for it, %: then it was blocked, and the
/// refinement does not use its readings. A floor's slowest turn
/// direction (issue #29's hard world: 0.6 of the lab's turn line) takes
/// 167 %.
pub const TURN_LIMIT_PERCENT: u32 = 200;
/// Pairs of lidar readings kept from each turn between views, for
/// refining the search's fix (`model::locate::turns`): a one-step turn
/// (327 ms at `TURN_MRAD_S`, 32 whole ticks) brings ten, a lidar's
/// reading every 3.3 ticks (`tests/localization/localize.rs`); a longer
/// one keeps every second, third, ... pair. 8 bytes each (each lidar's
/// tick and distance), 116 B a turn on the robot, up to seven turns
/// (`model::locate::MAX_VIEWS` views) kept by the survey: 812 B, in the
/// controller, which lives on the ROM's stack (`firmware::robot::run`'s
/// frame), not in the image's DRAM budget (`cargo fw-image`: the stack's
/// worst case 14,192 of 14,272 B).
pub const TURN_SAMPLES: usize = 12;
/// The body stands this long after a turn before its view is taken,
/// ms: the servos stop within a tick (data `servo_runs.csv`), and a
/// lidar reading begun while turning (33 ms each) is over.
pub const SETTLE_MS: u32 = 100;
/// A counterclockwise turn swings the nose to the left, which no lidar
/// sees from the view it starts at; the survey's earlier views may have
/// (its turns in place keep the turning centre): a reading of theirs in a
/// direction within this of the left, degrees, must show the room a turn
/// wants (`control::survey::room`). 45: the views are a turn step apart,
/// so a view's right or front falls within it when one was taken there
/// (issue #29's hard world: the surveys' wall contacts were turns toward
/// an unseen wall on the left).
pub const LEFT_SEEN_DEG: i32 = 45;
/// A turn the compass says moved less than this, degrees, was blocked
/// (the body against a wall): the next turns go the other way.
pub const BLOCKED_TURN_DEG: i32 = 20;
/// View scores (a view's two lidar models at a grid point and a pivot)
/// searched per loop tick: 200 took up to 315,565 lx106 instructions
/// (39 % of the 10 ms tick at 80 MHz, one instruction a cycle), so 170
/// take about 268,000, a third of the tick (half at 1.5 cycles), which
/// leaves the tick's own work room (lx106/BENCHMARKS.md; a search at a
/// learned lidar spot share 295,000, 37 %); a pass over the box takes
/// about 90 ticks (0.9 s). Counted in scores, not grid
/// columns: a column where many points explain the first view scores
/// each of them once per pivot and later view.
pub const SCORES_PER_TICK: u32 = 170;
/// Each look's time limit, ms (the procedure's, and a second look's
/// from its start, `config::refine::SECOND_LOOK_FIT`): eight views (5 s)
/// and two searches that try every heading (50 passes, 39 s each): a
/// search that finds nothing takes another view and searches again. (60
/// s, room for one such search, left 18 of 1,000 hard power-ups out of
/// time, 9 at this limit: `tests/localization/localize.rs`. One limit
/// for both looks cut short the second looks that began late: set A of
/// docs/simulator.md 8 out of time, 973 right against 980.)
pub const TIME_LIMIT_MS: u32 = 120_000;
/// The longest a localization takes, ms: a first look and a second
/// (`config::refine::SECOND_LOOK_FIT`), each within its limit.
pub const LONGEST_MS: u32 = 2 * TIME_LIMIT_MS;
/// The survey's turns in place are planned to pivot this far behind the
/// reference point, mm: `goto`'s planned centre (`goto::TURN_CENTRE_
/// BEHIND_REFERENCE`, at the skid), the conservative end for the walls;
/// the pivot is not learned before the first turn.
pub const TURN_CENTRE_BEHIND_REFERENCE: super::Length = super::goto::TURN_CENTRE_BEHIND_REFERENCE;
/// The survey turns where its readings show the body's swept circle about
/// that centre clears the walls seen by this, mm: `goto`'s margin for the
/// pivot's error (`goto::TURN_WALL_MARGIN_MM`).
pub const ROOM_MARGIN_MM: i32 = super::goto::TURN_WALL_MARGIN_MM;
/// Before its first view, the survey drives until the wall ahead reads
/// this much more than a turn wants (`FRONT_REACH_HALVES`), mm: a view's
/// median reading is within about 1 mm, but the wheels' speed (up to 15 %
/// off in the hard world, `sim::realism`) makes a planned 130 mm drive up
/// to 20 mm longer.
pub const POSITION_SLACK_MM: i32 = 20;
/// ... backing up at most this far from a wall seen ahead, mm: behind is
/// unseen (a corner behind). Of 1,000 surveys from random starts in each
/// of the three worlds (`tests/sim/survey_room.rs`), 36 touch a wall
/// backing up; 30 mm (200 starts each, an earlier survey) took 1 such
/// collision fewer in the lab's world and cost 4 right fixes (more turns
/// with room only for a wall square ahead).
pub const MAX_BACK_UP_MM: i32 = 60;
/// ... and drives forward or back at this speed, mm/s: `goto`'s
/// (`goto::SPEED_MM_S`).
pub const POSITION_MM_S: i32 = super::goto::SPEED_MM_S;
/// Before each turn the newest view must show the wall ahead at least
/// this many times the reach (the swept radius and margin) from the
/// turning centre, in halves: a wall met at a slant of up to 48 degrees
/// (cos = 2/3) then clears the swept circle (with the centre 126 mm
/// behind the nose, a front reading of 108 mm). (The reach itself, the first
/// try, cut half the lab's surveys short at their first view: the drive
/// before it leaves the wall ahead at about the reach, give or take the
/// reading's noise.)
pub const FRONT_REACH_HALVES: i32 = 3;
