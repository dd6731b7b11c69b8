//! Timing of the control loop. Design choices unless a source is named;
//! the reason is given with each.

/// Control loop rate, Hz: a 10 ms tick, the AK8963's sample period in
/// continuous mode 2 (100 Hz, AK8963 datasheet), so every compass
/// sample is used.
pub const LOOP_HZ: u32 = 100;
/// Telemetry rows per second at boot, Hz (0 = off; `rate` changes it):
/// about 1.1 kB/s of the UART's 11.5 kB/s (`serial::MAX_TELEMETRY_HZ`).
pub const TELEMETRY_HZ: u32 = 10;
/// Stop when no command arrived for this long, ms: the teleop tool resends
/// a held motion every quarter of it (`teleop::REFRESH_MS`), so a dead
/// link stops the robot within half a second.
pub const DEADMAN_MS: u32 = 500;
/// Wait before re-initialising a failed sensor, ms: each re-initialisation
/// blocks the loop for its waits and its ~110 (lidar) or 13 (compass)
/// transactions, so a chip that stays away costs that once a second.
pub const SENSOR_RETRY_MS: u32 = 1_000;
/// A lidar reading older than this is stale, ms: six timing budgets
/// (`lidar::TIMING_BUDGET_US`, 33 ms).
pub const LIDAR_STALE_MS: u32 = 200;
/// A sensor that delivers nothing for this long is taken as failed
/// (counted as a timeout, re-initialised after `SENSOR_RETRY_MS`), ms:
/// 15 lidar periods (33 ms) or 50 compass periods (10 ms at 100 Hz).
pub const SENSOR_SILENT_MS: u32 = 500;
/// Bus errors in a row before a sensor is taken down: one glitch (e.g.
/// a servo's current surge on the bus) only costs that sample.
pub const SENSOR_MAX_BUS_ERRORS: u8 = 3;
/// Estimator corrections per tick at most (what one costs:
/// lx106/BENCHMARKS.md). Readings that arrive together wait a tick, lidars
/// first (a 10 ms wait at 0.15 m/s is 1.5 mm, within the lidar's 1.6 mm
/// spread), the compass when no lidar reading waits; this keeps a tick
/// within its instruction bar (15,000, lx106's `bar::tick_without_io`). 3
/// applies every reading in the tick it arrives.
pub const MAX_CORRECTIONS_PER_TICK: u8 = 1;
