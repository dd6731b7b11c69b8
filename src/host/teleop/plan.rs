//! The line mode's command file: protocol commands, one per line, each
//! sent at its time.
//!
//! ```text
//! # comments and blank lines are ignored; so is anything after a '#'
//! rate 20          # no time: sent right after the previous line
//! @0.5 fwd 0.13    # @T: T seconds after the start ("s" or "ms" suffix allowed)
//! +2s stop         # +T: T after the previous line
//! @3000ms ccw 2.5 0.5
//! ```
//!
//! Times never go back: an `@T` before the previous line's time is an
//! error. Every command is checked with the robot's own parser before
//! anything is sent, so a typo stops the script before the robot moves.

use std::format;
use std::string::{String, ToString};
use std::vec::Vec;

use crate::control::protocol::{parse, ParseError, MAX_RESPONSE};

/// One command and when to send it.
#[derive(Clone, PartialEq, Eq, Debug)]
pub struct PlanLine {
    /// ms after the start.
    pub at_ms: u64,
    /// The command as written (sent with a `\n`).
    pub command: String,
    /// Line number in the file, from 1.
    pub line_no: usize,
}

/// A line of the file that cannot be used.
#[derive(Clone, PartialEq, Eq, Debug)]
pub struct PlanError {
    pub line_no: usize,
    pub message: String,
}

impl core::fmt::Display for PlanError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(f, "line {}: {}", self.line_no, self.message)
    }
}

impl std::error::Error for PlanError {}

/// A time like `1.5`, `1.5s`, `1500ms`, in ms (at most a day).
fn parse_ms(t: &str) -> Option<u64> {
    let (num, scale) = match t.strip_suffix("ms") {
        Some(n) => (n, 1.0),
        None => (t.strip_suffix('s').unwrap_or(t), 1000.0),
    };
    let v: f64 = num.parse().ok()?;
    let ms = (v * scale).round();
    (v.is_finite() && v >= 0.0 && ms <= 86_400_000.0).then_some(ms as u64)
}

/// The protocol's refusal of a line as text.
pub(super) fn refusal(e: ParseError) -> String {
    let mut s: heapless::String<MAX_RESPONSE> = heapless::String::new();
    let _ = e.write(&mut s);
    s.as_str().to_string()
}

/// Reads a command file (see the module docs).
pub fn parse_plan(text: &str) -> Result<Vec<PlanLine>, PlanError> {
    let mut out = Vec::new();
    let mut t = 0u64;
    for (i, raw) in text.lines().enumerate() {
        let line_no = i + 1;
        let content = raw.split('#').next().unwrap_or("").trim();
        if content.is_empty() {
            continue;
        }
        let err = |message: String| PlanError { line_no, message };
        let (at, command) = match content.chars().next() {
            Some(c @ ('@' | '+')) => {
                let (time, rest) = content.split_once(char::is_whitespace).unwrap_or((content, ""));
                let ms = parse_ms(time.get(1..).unwrap_or(""))
                    .ok_or_else(|| err(format!("bad time {time:?}, want e.g. {c}1.5, {c}1.5s or {c}1500ms")))?;
                let at = if c == '@' { ms } else { t.saturating_add(ms) };
                if at < t {
                    return Err(err(format!("time {time} is before the previous line's ({t} ms)")));
                }
                (at, rest.trim())
            }
            _ => (t, content),
        };
        if command.is_empty() {
            return Err(err("no command after the time".to_string()));
        }
        parse(command.as_bytes()).map_err(|e| err(format!("`{command}`: {}", refusal(e))))?;
        t = at;
        out.push(PlanLine { at_ms: at, command: command.to_string(), line_no });
    }
    Ok(out)
}
