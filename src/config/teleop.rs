//! The teleop tool (`examples/teleop.rs`, `host::teleop`; host only).

use super::timing::DEADMAN_MS;

/// How often a held motion command is sent again, ms: a quarter of the
/// deadman, so three refreshes in a row may be lost or late (USB serial
/// adds a few ms) before the robot stops.
pub const REFRESH_MS: u32 = DEADMAN_MS / 4;
const _: () = assert!(REFRESH_MS > 0 && REFRESH_MS * 2 < DEADMAN_MS);
/// Speed levels of the drive keys, spread evenly over each motion's
/// measured range (`config::actuators`: both wheels' lines hold there).
pub const SPEED_LEVELS: usize = 5;
/// The level at start (0 = slowest): the middle of the measured range.
pub const START_LEVEL: usize = SPEED_LEVELS / 2;
const _: () = assert!(SPEED_LEVELS >= 2 && START_LEVEL < SPEED_LEVELS);
/// Telemetry rate the tool asks for while recording, Hz: a row every
/// 20 ms catches every lidar reading (one per 33 ms timing budget; a
/// row carries only the newest reading) and half the compass's 100 Hz;
/// about 5.5 kB/s of rows (110 bytes each), half the UART's 11.5 kB/s.
pub const RECORD_TELEMETRY_HZ: u16 = 50;
const _: () = assert!(RECORD_TELEMETRY_HZ <= super::serial::MAX_TELEMETRY_HZ);
/// No telemetry row for this long marks the link stale on the screen, ms.
pub const STALE_LINK_MS: u32 = 1_000;
/// Screen refresh period of the terminal UI, ms (20 frames a second).
pub const FRAME_MS: u32 = 50;
/// Messages (`#` lines) kept on the screen.
pub const MESSAGES_SHOWN: usize = 8;
/// How long the line mode waits for the answer to its first `rate 0`,
/// dropping the rows the robot streamed before, ms: the answer comes
/// within a tick or two; a robot still booting may take longer, and the
/// run then goes on without it.
pub const ANSWER_WAIT_MS: u32 = 1_000;
