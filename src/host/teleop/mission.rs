//! Missions from the laptop: a mission file checked and uploaded line by
//! line (`mission clear`, then `mission add <step>` for each step, each
//! answer awaited), the start, and the on-board log downloaded (`dump`) as
//! telemetry CSV (and, through a [`Recorder`], as a replay log).
//!
//! Mission file, one step per line, as typed after `mission add`:
//!
//! ```text
//! # square.txt: '#' starts a comment, blank lines are ignored
//! pose 170 170 0      # where the robot is put down
//! wait 1              # the estimate settles
//! goto 550 170
//! face 90
//! fwd 0.13 1.5        # motions need a duration in a mission
//! goto 200 170
//! ```
//!
//! Every line is parsed here first (the robot's own parser) and must be a
//! step a mission holds; a file with a mistake is refused before anything
//! is sent.

use std::format;
use std::io::{self, Read, Write};
use std::string::{String, ToString};
use std::time::Instant;
use std::vec::Vec;

use super::link::{send, LineReader};
use super::plan::{refusal, PlanError};
use super::record::Recorder;
use crate::config;
use crate::control::mission::Step;
use crate::control::protocol::{format_command, parse, parse_telemetry_row, telemetry_header, MAX_LINE, MAX_RESPONSE};

/// The steps of a mission file, each as its `mission add` command line
/// (canonical form); a line that cannot be a step is a [`PlanError`].
pub fn parse_mission_file(text: &str) -> Result<Vec<String>, PlanError> {
    let mut steps = Vec::new();
    for (i, raw) in text.lines().enumerate() {
        let line_no = i + 1;
        let err = |message: String| PlanError { line_no, message };
        let content = raw.split('#').next().unwrap_or("").trim();
        if content.is_empty() {
            continue;
        }
        let cmd = parse(content.as_bytes()).map_err(|e| err(refusal(e)))?;
        let step = Step::from_command(&cmd).ok_or_else(|| {
            err(format!("`{content}` is not a mission step: a timed fwd/back/cw/ccw, wait, goto, face or pose"))
        })?;
        let mut canonical: heapless::String<MAX_RESPONSE> = heapless::String::new();
        let _ = format_command(&step.command(), &mut canonical);
        let line = format!("mission add {canonical}");
        if line.len() > MAX_LINE {
            return Err(err(format!("`{line}` is longer than the robot's {MAX_LINE}-byte line")));
        }
        steps.push(line);
    }
    if steps.len() > config::mission::MAX_STEPS {
        let message = format!("{} steps, the robot holds {}", steps.len(), config::mission::MAX_STEPS);
        return Err(PlanError { line_no: text.lines().count(), message });
    }
    Ok(steps)
}

/// Sends `command` and waits for its answer (`# ok ...` or `# err ...`),
/// writing every line that comes to `out`. `Ok(Err)` holds a refusal or
/// "no answer".
fn exchange<P, O>(port: &mut P, reader: &mut LineReader, command: &str, out: &mut O) -> io::Result<Result<(), String>>
where
    P: Read + Write + ?Sized,
    O: Write + ?Sized,
{
    send(port, command)?;
    let start = Instant::now();
    while start.elapsed().as_millis() < u128::from(config::teleop::ANSWER_WAIT_MS) {
        for line in reader.poll(port)? {
            writeln!(out, "{line}")?;
            if line.starts_with("# ok ") {
                return Ok(Ok(()));
            }
            if line.starts_with("# err ") {
                return Ok(Err(format!("`{command}`: {line}")));
            }
        }
    }
    Ok(Err(format!("`{command}`: no answer")))
}

/// Uploads a mission (telemetry off first, so the answers are not buried):
/// the old mission is cleared, each step added; stops at the first refusal.
pub fn upload<P, O>(port: &mut P, steps: &[String], out: &mut O) -> io::Result<Result<(), String>>
where
    P: Read + Write + ?Sized,
    O: Write + ?Sized,
{
    let mut reader = LineReader::new();
    for command in ["rate 0", "mission clear"].iter().map(|s| s.to_string()).chain(steps.iter().cloned()) {
        if let Err(e) = exchange(port, &mut reader, &command, out)? {
            return Ok(Err(e));
        }
    }
    exchange(port, &mut reader, "mission list", out)
}

/// Sets the log's rate (if given) and starts the mission; returns the
/// robot's countdown line. After this nothing may be sent: any byte
/// aborts the mission once its countdown is over.
pub fn start<P, O>(port: &mut P, log_hz: Option<u16>, out: &mut O) -> io::Result<Result<String, String>>
where
    P: Read + Write + ?Sized,
    O: Write + ?Sized,
{
    let mut reader = LineReader::new();
    if let Some(hz) = log_hz {
        if let Err(e) = exchange(port, &mut reader, &format!("log {hz}"), out)? {
            return Ok(Err(e));
        }
    }
    // the answer and the countdown line come together
    send(port, "mission start")?;
    let begin = Instant::now();
    while begin.elapsed().as_millis() < u128::from(config::teleop::ANSWER_WAIT_MS) {
        for line in reader.poll(port)? {
            writeln!(out, "{line}")?;
            if line.starts_with("# mission starts") {
                return Ok(Ok(line));
            }
            if line.starts_with("# err ") {
                return Ok(Err(format!("`mission start`: {line}")));
            }
        }
    }
    Ok(Err("no countdown line after `mission start`".into()))
}

/// Keeps the robot's settings and mission in flash (`save`): returns the
/// robot's `# saved: ...` line, or its refusal (e.g. while it moves).
pub fn save<P, O>(port: &mut P, out: &mut O) -> io::Result<Result<String, String>>
where
    P: Read + Write + ?Sized,
    O: Write + ?Sized,
{
    let mut reader = LineReader::new();
    // the answer and the line with the record and the pause come together
    send(port, SAVE_COMMAND)?;
    let begin = Instant::now();
    while begin.elapsed().as_millis() < u128::from(config::teleop::ANSWER_WAIT_MS) {
        for line in reader.poll(port)? {
            writeln!(out, "{line}")?;
            if line.starts_with("# saved") {
                return Ok(Ok(line));
            }
            if line.starts_with("# err ") {
                return Ok(Err(format!("`{SAVE_COMMAND}`: {line}")));
            }
        }
    }
    Ok(Err(format!("no `# saved` line after `{SAVE_COMMAND}`")))
}

/// The command that keeps the settings in flash (`--save`, the `k` key).
pub const SAVE_COMMAND: &str = "save";

/// What a download got.
#[derive(Clone, PartialEq, Eq, Debug)]
pub struct Download {
    /// The robot's summary: `# log <n> rows at <hz> Hz, <d> dropped ...`.
    pub summary: String,
    pub rows: usize,
}

/// Downloads the on-board log (`dump`): the header and every row go to
/// `csv` (the telemetry CSV format), the rows also to `recorder` (the
/// replay log). Fails when the robot goes quiet for
/// [`config::teleop::STALE_LINK_MS`] before `# log end`.
pub fn download<P, C, L>(
    port: &mut P,
    csv: &mut C,
    mut recorder: Option<&mut Recorder<L>>,
) -> io::Result<Result<Download, String>>
where
    P: Read + Write + ?Sized,
    C: Write + ?Sized,
    L: Write,
{
    let mut reader = LineReader::new();
    if let Err(e) = exchange(port, &mut reader, "rate 0", &mut io::sink())? {
        return Ok(Err(e));
    }
    send(port, "dump")?;
    let mut summary = None;
    let mut rows = 0;
    let mut last = Instant::now();
    while last.elapsed().as_millis() < u128::from(config::teleop::STALE_LINK_MS) {
        for line in reader.poll(port)? {
            last = Instant::now();
            if line.starts_with("# log end") {
                csv.flush()?;
                let summary = summary.unwrap_or_default();
                return Ok(Ok(Download { summary, rows }));
            } else if line.starts_with("# log ") {
                summary = Some(line);
            } else if summary.is_none() {
                // before the dump: an answer, stray rows
            } else if line == telemetry_header() {
                writeln!(csv, "{line}")?;
            } else if let Ok(row) = parse_telemetry_row(&line) {
                writeln!(csv, "{line}")?;
                rows += 1;
                if let Some(rec) = recorder.as_deref_mut() {
                    rec.record(&row)?;
                }
            }
        }
    }
    Ok(Err(format!("the robot went quiet after {rows} rows, before `# log end`")))
}
