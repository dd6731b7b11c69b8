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
//! # Command grammar
//!
//! ```text
//! line     = ws* [ command ws* ] ( "\n" | "\r\n" )      at most 64 bytes before the terminator
//! ws       = " " | "\t"                                  words are separated by one or more ws
//! command  = ( "fwd" | "forward" | "back" | "backward" ) ws speed [ ws duration ]
//!          | ( "cw" | "ccw" ) ws rate [ ws duration ]
//!          | "stop" | "s"
//!          | "servo" ws cmd ws cmd [ ws duration ]
//!          | "trim" ws ( "left" | "l" | "right" | "r" ) ws trim
//!          | "pose" ws x ws y ws heading
//!          | "reset"                                     same as "pose 0 0 0"
//!          | ( "cal" | "calibrate" ) [ ws samples ]      default 1000 samples
//!          | "rate" ws hz
//!          | "status"
//!          | "help" | "?"
//!          | "goto" ws x ws y                            on the estimate, see control::goto
//!          | "face" ws heading
//!          | "wait" ws duration
//!          | "mission" ws ( "add" ws step | "list" | "clear" | "start" )
//!          | "log" ws hz                                 on-board log rate in missions (0 = off)
//!          | "dump"                                      sends the on-board log
//! step     = a timed fwd/back/cw/ccw, wait, goto, face or pose command
//! number   = [ "+" | "-" ] ( digits [ "." digits ] | "." digits )
//!
//! field     unit        decimals  range (config::serial)        fixed point
//! speed     m/s         3         0.001 ..= 0.300               Speed::from_mm_s
//! rate      rad/s       3         0.001 ..= 6.000               TurnRate::from_mrad_s
//! duration  s           3         0.001 ..= 60.000, may end in "s"   ms
//! cmd       steps       2         0.00 ..= 180.00 (90 = stop)   ServoCmd, 1/256 step
//! trim      steps       2         -10.00 ..= 10.00              Trim, 1/256 step
//! x, y      mm          0         -30000 ..= 30000              i32
//! heading   deg (cw from north)  3  -360.000 ..= 360.000        Angle::from_millidegrees
//! samples   count       0         250 ..= 10000                 u16
//! hz        Hz          0         0 ..= 100 (0 = off)           u16
//! ```
//!
//! Keywords are case-insensitive. A number may carry more decimals than its
//! field's resolution only if they are zeros (`0.1300` is fine, `0.1305` is
//! a bad number): values are exact or refused, never rounded. `fwd` and
//! `back` take a positive speed (the word gives the direction), as `cw` and
//! `ccw` take a positive rate. Without a duration a motion lasts until the
//! next command (or the control loop's deadman). Bytes outside printable
//! ASCII (space and tab allowed) refuse the line.
//!
//! Every line gets one answer line: `# ok <canonical command>` (the command
//! as understood, every number at its resolution; parsing it gives the same
//! command) or `# err <problem>`. A refused line changes nothing. The speed
//! and rate limits guard against typos; a motion the servos cannot drive as
//! asked is answered by the control loop with the motion they drive
//! ([`crate::control::Controller::handle`]).
//!
//! ```text
//! > fwd 0.13 2.5            # ok fwd 0.130 2.500
//! > BACK .12                # ok back 0.120
//! > ccw 2.5 1s              # ok ccw 2.500 1.000
//! > servo 107 61.5 0.8      # ok servo 107.00 61.50 0.800
//! > trim r -1.25            # ok trim right -1.25
//! > pose 100 -50 90         # ok pose 100 -50 90.000
//! > cal                     # ok cal 1000
//! > rate 20                 # ok rate 20
//! > fwd 0.5                 # err speed out of range 0.001..0.300 m/s
//! > fwd                     # err missing speed, want a number 0.001..0.300 m/s with up to 3 decimals
//! > fwd 0.1305              # err bad speed, want a number 0.001..0.300 m/s with up to 3 decimals
//! > fwd 0.1 2 3             # err unexpected input after the arguments
//! > jump                    # err unknown command, try help
//! > (65+ bytes)             # err line too long, max 64 bytes
//! ```
//!
//! # Telemetry
//!
//! A header line ([`telemetry_header`], no `#`), then one row per report:
//!
//! ```text
//! t_ms,x_mm,y_mm,heading_deg,motion,v_mps,w_radps,left_cmd,right_cmd,front_raw_mm,front_mm,right_raw_mm,right_mm,mag_x,mag_y,mag_z,field_x,field_y,field_z,compass_deg,f_bus,f_timeout,f_missing,f_bad_sample,f_outliers,f_overruns
//! 1200,153.2,-4.1,11.933,fwd,0.130,0.000,107.00,61.00,412,349.5,8190,,-12,40,-3,-66,4,-3,353.117,0,0,0,0,0,0
//! ```
//!
//! x/y in mm (0.1), headings in degrees (0.001, 0..360, clockwise from
//! north), `v_mps` signed m/s, `w_radps` signed rad/s (clockwise positive),
//! servo commands in steps (0.01), lidar raw readings and distances from the
//! reference point in mm (distance empty without a target), raw
//! magnetometer counts and the corrected field (chip axes), the compass
//! heading, then the fault counters ([`FaultCounters`]). A field is empty
//! when there was no fresh reading. `pandas.read_csv(f, comment='#')` reads
//! a log directly; `parse_telemetry_row` (feature `std`) reads a row back
//! into exactly the numbers written.

pub mod command;
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
