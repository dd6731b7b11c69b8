//! The serial protocol: text lines over UART0 (115200 8N1). Commands come
//! in one per line; telemetry goes out as CSV rows, and every other line
//! the robot sends starts with `#`.
//!
//! Bounded buffers only (`heapless`), no allocation, and integer code only:
//! numbers are parsed into fixed point and written back as decimals by
//! [`number`], so the standard formatting machinery and its float code never
//! reach the robot (`lx106/run.sh` checks that no soft-float routine is
//! linked).
//!
//! The grammar, every command's answers, the status line and the telemetry
//! columns are described once, in `docs/protocol.md`, whose examples
//! `tests/protocol/docs.rs` runs on the control loop. In short: one command
//! per line, at most [`MAX_LINE`] bytes; every line gets one answer, `# ok
//! <canonical command>` ([`format_command`]: parsing it gives the same
//! command) or `# err <problem>` ([`ParseError`]), and a refused line
//! changes nothing; telemetry is a CSV header ([`telemetry_header`]) and
//! rows ([`format_row`]), and every other line starts with `#`
//! ([`classify_line`]).

pub mod command;
pub mod field;
pub mod line;
pub mod number;
pub mod out_line;
pub mod response;
pub mod telemetry;

pub use command::{format_command, parse, Command, Field, MissionOp, ParseError, Side};
pub use line::{Line, LineBuffer};
pub use number::TextOut;
pub use out_line::OutLine;
pub use response::{format_response, format_status, Response, Status, ERR, HELP, OK};
pub use telemetry::{
    classify_line, format_row, format_telemetry, telemetry_header, FaultCounters, LineKind, Telemetry, TelemetryRow,
    COLUMNS, HEADER, MAX_ROW,
};
#[cfg(feature = "std")]
pub use telemetry::{parse_telemetry_row, RowError};

/// Longest command line, bytes, without the terminator.
pub const MAX_LINE: usize = crate::config::serial::MAX_LINE;

/// Longest `ok`/`err` response line from [`format_response`] with `Ok` or
/// `Err` (the longest is a `missing`/`bad` message, about 90 bytes).
pub const MAX_RESPONSE: usize = 128;

/// Longest status line from [`format_status`] (every field at its widest:
/// 409 bytes).
pub const MAX_STATUS: usize = 416;

/// A buffer of this size holds any line the protocol writes (telemetry row,
/// response, status, help line).
pub const MAX_OUT_LINE: usize = MAX_STATUS;

const _: () = assert!(MAX_ROW <= MAX_OUT_LINE && MAX_RESPONSE <= MAX_OUT_LINE);

/// An output line did not fit its buffer (the buffer then holds a partial
/// line: clear it before reuse).
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
pub struct Overflow;
