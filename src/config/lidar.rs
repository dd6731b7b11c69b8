//! The two lidar lines (report 3.3, data `lidar_*.csv`), mapping a reading
//! (mm) to the distance from the car's reference point (mm).

use crate::model::lidar::LidarModel;

/// The closest distance from the reference point a reading may mean,
/// mm; a reading below it is "too close", not a measurement. The
/// reference point is on the car, inside the box, and both lidars look
/// across it (front: from 50 mm behind it, right: from 53 mm to its
/// left; `geometry`), so a wall cannot be nearer than 0 mm along the
/// beam; -6 mm leaves three lidar sigmas (`estimator::LIDAR_SIGMA`) for
/// noise: the lab's readings of a target at 0 mm go down to -5.3 mm
/// (data `lidar_*.csv`). This takes readings below 52 (front) and 66
/// (right) as too close; the right lidar pushed past a wall read 43-55,
/// which the former bound (20) turned into -16..-28 mm and the
/// estimator accepted.
pub const MIN_DISTANCE_MM: f64 = -6.0;
/// Readings past this are beyond the VL53L0X's reliable range in its
/// default mode (1.2 m, datasheet): reported as no target.
pub const MAX_READING_MM: u16 = 1200;
/// Front: `distance = 0.9849 reading - 56.2563` (report 3.3: the reading
/// fitted on the true distance, inverted; `cargo run --example fit --
/// tests/data/lab1/lidar_front.csv` gives 0.9849 / -56.2555 from the data).
pub const FRONT: LidarModel = LidarModel::new(0.9849, -56.2563, MIN_DISTANCE_MM, MAX_READING_MM);
/// Right: `distance = 0.9867 reading - 70.4578` (report 3.3; the fit
/// gives 0.9867 / -70.4605).
pub const RIGHT: LidarModel = LidarModel::new(0.9867, -70.4578, MIN_DISTANCE_MM, MAX_READING_MM);

/// The VL53L0X's field of view, full cone angle, degrees (ST's
/// datasheet: 25 degrees): it reads the nearest surface in the cone, so
/// the estimator's measurement model takes the cone's direction nearest
/// a wall's normal (`model::measurement`).
pub const CONE_DEG: f64 = 25.0;
/// Measurement timing budget, us (VL53L0X default 33 ms; at most one
/// reading per 33 ms per lidar).
pub const TIMING_BUDGET_US: u32 = 33_000;
/// A reading describes the body this long before the loop tick it is
/// read at, us: the chip measures over its whole timing budget (ST's
/// datasheet, continuous back-to-back ranging; UM2039: the budget is
/// one measurement's time), so its middle is half a budget before the
/// result is ready, and the loop polls for it once a tick (half a tick's
/// wait on average). Turning at the survey's 2.4 rad/s, the body turns
/// 3 degrees in that time; the refinement reads a turn's readings there
/// (`model::locate::refine`).
pub const READING_AGE_US: u32 = TIMING_BUDGET_US / 2 + 1_000_000 / super::timing::LOOP_HZ / 2;
/// Wait after releasing XSHUT before talking to the chip, us (datasheet
/// boot time 1.2 ms, with margin).
pub const BOOT_TIME_US: u32 = 2_000;
/// How long XSHUT is held low to reset a lidar, us (the datasheet gives
/// no minimum; Adafruit's two-sensor example holds it 10 ms).
pub const RESET_TIME_US: u32 = 10_000;
/// Consecutive reads of one status register the bring-up may make while
/// it waits for the chip (SPAD info, reference calibrations) before it
/// gives up with a timeout: about 0.2 s at 100 us a read (three bytes at
/// 400 kHz). The vl53l0x crate's own limits (10000 and 65535 reads)
/// would block the robot for seconds.
pub const INIT_POLL_LIMIT: u16 = 2_000;
