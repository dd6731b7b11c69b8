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

/// `teleop --web`: the address the page is served on when none is given
/// (loopback: only this laptop; `0.0.0.0:8080` lets a phone in).
pub const WEB_ADDR: &str = "127.0.0.1:8080";
/// A motion held on the page lasts this long after the page last asked
/// for it, ms: the page repeats a held motion every [`REFRESH_MS`], so one
/// late or lost repeat is forgiven, and a page that stops asking (a tab
/// closed without a goodbye, a phone gone to sleep, a dropped network)
/// gets `stop` sent this long after its last word, before the robot's
/// own deadman would fire.
pub const WEB_HOLD_MS: u32 = 2 * REFRESH_MS;
const _: () = assert!(WEB_HOLD_MS > REFRESH_MS && WEB_HOLD_MS < DEADMAN_MS);
/// The driver's and link's state goes to every page this often, ms (rows
/// go as they come).
pub const WEB_STATE_MS: u32 = 200;
/// Longest message a page may send, bytes: its commands are a few dozen
/// bytes; anything longer is malformed and closes that page's connection.
pub const WEB_MAX_MESSAGE: usize = 256;
/// Messages queued for one page, at most: a page that cannot keep up
/// (a slow phone) loses the newest rows, not the laptop's memory.
pub const WEB_QUEUE: usize = 512;
/// Points of the trail the page keeps (at 10 rows a second, 5 minutes).
pub const WEB_TRAIL_POINTS: usize = 3_000;
