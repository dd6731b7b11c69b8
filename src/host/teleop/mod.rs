//! The teleop tool's logic: drive the robot from a laptop over its serial
//! line, watch its telemetry, record the session for the replay tool.
//!
//! `examples/teleop.rs` is the thin shell (serial port, terminal UI); the
//! pieces it uses, each testable alone:
//! - [`keys`]: key presses to actions (arrows / WASD drive, space stops,
//!   `+`/`-` change the speed level, `q` quits);
//! - [`speed`]: the speed levels, spread over each motion's measured range
//!   of the actuator model, as protocol commands;
//! - [`drive`]: the motion the user holds, sent again every
//!   [`config::teleop::REFRESH_MS`](crate::config::teleop::REFRESH_MS) so the
//!   robot's deadman ([`config::timing::DEADMAN_MS`](crate::config::timing::DEADMAN_MS))
//!   never fires while the tool runs, and fires when it dies;
//! - [`record`]: telemetry rows to the replay log
//!   (`t_ms,left_cmd,right_cmd,front_mm,right_mm,heading_deg`);
//! - [`dashboard`]: the screen's content (pose, sensors, motion, faults,
//!   messages) as plain text panels;
//! - [`link`]: serial bytes to lines, and the line mode for scripts
//!   ([`link::run_line_mode`]): send a file of commands, print what comes back;
//! - [`plan`]: the line mode's command file (`@t` / `+t` times, comments);
//! - [`mission`]: a mission file uploaded, started, and the on-board log
//!   downloaded.

pub mod dashboard;
pub mod drive;
pub mod keys;
pub mod link;
pub mod mission;
pub mod plan;
pub mod record;
pub mod speed;

pub use dashboard::{Dashboard, Panel};
pub use drive::Driver;
pub use keys::{action, Action, Key};
pub use link::{run_line_mode, LineModeOptions, LineModeReport, LineReader};
pub use plan::{parse_plan, PlanError, PlanLine};
pub use record::{replay_row, Recorder, REPLAY_HEADER};
pub use speed::Speeds;
