//! Command scripts for the simulator: protocol lines with the time at which
//! they are sent.
//!
//! Format, one command per line:
//! ```text
//! # a comment; blank lines are ignored
//! @0     rate 10
//! @0.5s  fwd 0.13 3      # times in seconds ("s" optional) ...
//! @3750ms cw 2.493 0.63  # ... or in milliseconds
//! ```
//! The `@` is optional. Times must not decrease. The rest of the line, up
//! to a `#` comment, is sent to the robot as typed (a malformed command is
//! the firmware's business: it answers with `# err`).

use std::fmt::Write;
use std::format;
use std::string::{String, ToString};
use std::vec::Vec;

/// One timed command.
#[derive(Clone, PartialEq, Eq, Debug)]
pub struct ScriptLine {
    /// When it is sent, us from the start of the run.
    pub at_us: u64,
    /// The command line, without terminator.
    pub command: String,
    /// Line number in the script text (from 1).
    pub line_no: usize,
}

/// A parsed script.
#[derive(Clone, PartialEq, Eq, Debug, Default)]
pub struct Script {
    pub lines: Vec<ScriptLine>,
}

/// A script line that could not be read.
#[derive(Clone, PartialEq, Eq, Debug)]
pub struct ScriptError {
    pub line_no: usize,
    pub message: String,
}

impl core::fmt::Display for ScriptError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(f, "script line {}: {}", self.line_no, self.message)
    }
}

impl std::error::Error for ScriptError {}

/// Reads a time like `1.5`, `1.5s`, `@1500ms` into us.
fn parse_time(token: &str) -> Option<u64> {
    let t = token.strip_prefix('@').unwrap_or(token);
    let (num, scale) = if let Some(ms) = t.strip_suffix("ms") {
        (ms, 1e3)
    } else if let Some(s) = t.strip_suffix('s') {
        (s, 1e6)
    } else {
        (t, 1e6)
    };
    let v: f64 = num.parse().ok()?;
    let us = (v * scale).round();
    (v.is_finite() && v >= 0.0 && us < 1e15).then_some(us as u64)
}

impl Script {
    /// Parses a script (see the module docs).
    pub fn parse(text: &str) -> Result<Script, ScriptError> {
        let mut lines = Vec::new();
        let mut last = 0u64;
        for (i, raw) in text.lines().enumerate() {
            let line_no = i + 1;
            let content = raw.split('#').next().unwrap_or("").trim();
            if content.is_empty() {
                continue;
            }
            let (time, command) = content.split_once(char::is_whitespace).unwrap_or((content, ""));
            let err = |message: String| ScriptError { line_no, message };
            let at_us =
                parse_time(time).ok_or_else(|| err(format!("bad time {time:?}, want e.g. 1.5, 1.5s or 1500ms")))?;
            if at_us < last {
                return Err(err(format!("time {time} is before the previous line's")));
            }
            let command = command.trim();
            if command.is_empty() {
                return Err(err("no command after the time".to_string()));
            }
            last = at_us;
            lines.push(ScriptLine { at_us, command: command.to_string(), line_no });
        }
        Ok(Script { lines })
    }

    /// The time of the last command, us.
    pub fn end_us(&self) -> u64 {
        self.lines.last().map_or(0, |l| l.at_us)
    }
}

/// Forward speed of the default lap, m/s (inside the forward lines'
/// measured range, 0.123..0.149 m/s).
const LAP_SPEED: &str = "0.13";
/// Clockwise quarter turn of the default lap: pi/2 / 0.63 s = 2.493 rad/s
/// for 0.63 s, a whole number of 10 ms loop ticks.
const QUARTER_TURN: (&str, u64) = ("cw 2.493 0.63", 630);
/// The lap's legs, ms of driving north-south and east-west.
const LONG_LEG_MS: u64 = 3000;
const SHORT_LEG_MS: u64 = 1500;
/// Stop between moves, ms.
const PAUSE_MS: u64 = 250;

/// The built-in script: from the default start (config::sim, heading
/// north), laps clockwise around the default box, each 390 x 195 mm of
/// driving with a quarter turn in place at each corner and a short stop
/// after each move, for `duration_s` seconds. Telemetry at 10 Hz.
pub fn default_script(duration_s: f64) -> String {
    let end_ms = (duration_s.max(0.0) * 1000.0) as u64;
    let mut s = String::new();
    let _ = writeln!(s, "# built-in: laps clockwise around the default box (x north, y east)");
    let _ = writeln!(s, "@0ms rate 10");
    let mut t = 0u64;
    'laps: loop {
        for leg in [LONG_LEG_MS, SHORT_LEG_MS, LONG_LEG_MS, SHORT_LEG_MS] {
            for (cmd, ms) in [
                (format!("fwd {LAP_SPEED} {:.3}", leg as f64 / 1000.0), leg),
                (QUARTER_TURN.0.to_string(), QUARTER_TURN.1),
            ] {
                if t >= end_ms {
                    break 'laps;
                }
                let _ = writeln!(s, "@{t}ms {cmd}");
                t += ms + PAUSE_MS;
            }
        }
    }
    s
}
