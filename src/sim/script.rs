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

/// The default lap's corners, mm (x north, y east), clockwise from the
/// default start (config::sim): each at least 170 mm from every wall, so
/// neither lidar's 25-degree cone grazes a side wall before the wall it
/// faces (at 130 mm from a side wall the front cone meets it first).
const LAP_CORNERS: [(i32, i32); 4] = [(590, 170), (590, 325), (170, 325), (170, 170)];
/// Time given to each corner's `goto`, ms: a quarter turn (0.65 s at
/// `config::goto::TURN_MRAD_S`) and the leg at 0.13 m/s (420 mm: 3.2 s;
/// 155 mm: 1.2 s), with time to spare.
const LEG_MS: [u64; 4] = [6_000, 4_000, 6_000, 4_000];
/// Time before the first `goto`, ms: the power-up localization (3.0 s from
/// the default start, four views) and the estimate's settling on the
/// lidars and the compass (`goto` refuses an uncertain estimate); a
/// command during the localization would end it.
const SETTLE_MS: u64 = 5_000;

/// The built-in script: from the default start (config::sim, heading
/// north), once the power-up localization has found the robot, laps
/// clockwise around the default box by `goto` (steered by the
/// estimate, so the realistic robot's speed spread and pivots do not drive
/// it into a wall), 420 x 155 mm, for `duration_s` seconds. Telemetry at
/// 10 Hz.
pub fn default_script(duration_s: f64) -> String {
    let end_ms = (duration_s.max(0.0) * 1000.0) as u64;
    let mut s = String::new();
    let _ = writeln!(s, "# built-in: laps clockwise around the default box by goto (x north, y east)");
    let _ = writeln!(s, "@0ms rate 10");
    let mut t = SETTLE_MS;
    'laps: loop {
        for ((x, y), ms) in LAP_CORNERS.iter().zip(LEG_MS) {
            if t + ms > end_ms {
                break 'laps;
            }
            let _ = writeln!(s, "@{t}ms goto {x} {y}");
            t += ms;
        }
    }
    s
}
