//! The serial link: bytes to lines, and the line mode.
//!
//! The port is anything `Read + Write` whose reads return after a short
//! timeout when nothing came (`ErrorKind::TimedOut` or `WouldBlock`, as a
//! `serialport` port with a read timeout does): the tools poll it.

use std::io::{self, ErrorKind, Read, Write};
use std::string::String;
use std::time::Instant;
use std::vec::Vec;

use super::dashboard::Dashboard;
use super::plan::PlanLine;
use super::record::Recorder;
use crate::config;
use crate::control::protocol::{parse, Command};

/// Longest line kept, bytes; longer ones (line noise, a wrong baud rate) are
/// cut there. The protocol's longest line is [`crate::control::protocol::MAX_OUT_LINE`].
pub const MAX_LINE: usize = 1024;

/// Splits received bytes into lines (`\n` ends a line, a `\r` before it is
/// dropped; bytes that are not UTF-8 become U+FFFD).
#[derive(Clone, Debug, Default)]
pub struct LineReader {
    buf: Vec<u8>,
}

impl LineReader {
    pub fn new() -> LineReader {
        LineReader::default()
    }

    /// Takes bytes, returns the lines they finish.
    pub fn push(&mut self, bytes: &[u8]) -> Vec<String> {
        let mut lines = Vec::new();
        for &b in bytes {
            if b == b'\n' {
                let mut line = std::mem::take(&mut self.buf);
                if line.last() == Some(&b'\r') {
                    line.pop();
                }
                lines.push(String::from_utf8_lossy(&line).into_owned());
            } else if self.buf.len() < MAX_LINE {
                self.buf.push(b);
            }
        }
        lines
    }

    /// Reads what the port has now (one read; a timeout is no data).
    pub fn poll<R: Read + ?Sized>(&mut self, port: &mut R) -> io::Result<Vec<String>> {
        let mut buf = [0u8; 4096];
        match port.read(&mut buf) {
            Ok(n) => Ok(self.push(buf.get(..n).unwrap_or(&[]))),
            Err(e) if matches!(e.kind(), ErrorKind::TimedOut | ErrorKind::WouldBlock | ErrorKind::Interrupted) => {
                Ok(Vec::new())
            }
            Err(e) => Err(e),
        }
    }
}

/// Sends one command line.
pub fn send<W: Write + ?Sized>(port: &mut W, command: &str) -> io::Result<()> {
    port.write_all(command.as_bytes())?;
    port.write_all(b"\n")?;
    port.flush()
}

/// Asks for telemetry at `hz` rows a second: `rate 0` first, so the robot
/// prints its CSV header again before the first row (it prints one only
/// when telemetry is switched on), which makes the output a complete CSV.
/// `hz` = 0 just switches telemetry off.
pub fn start_telemetry<W: Write + ?Sized>(port: &mut W, hz: u16) -> io::Result<()> {
    send(port, "rate 0")?;
    if hz > 0 {
        send(port, &std::format!("rate {hz}"))?;
    }
    Ok(())
}

/// How the line mode runs.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub struct LineModeOptions {
    /// Keep listening this long after the last command, ms.
    pub linger_ms: u64,
    /// Send an untimed motion command again every `refresh_ms` until the
    /// next motion command (or the end), so it is not cut by the deadman.
    pub keepalive: bool,
    pub refresh_ms: u64,
    /// Telemetry rate to ask for first ([`start_telemetry`]), if any.
    pub rate_hz: Option<u16>,
}

impl Default for LineModeOptions {
    fn default() -> Self {
        LineModeOptions {
            linger_ms: 1_000,
            keepalive: true,
            refresh_ms: u64::from(config::teleop::REFRESH_MS),
            rate_hz: None,
        }
    }
}

/// What a line-mode run did.
#[derive(Clone, Copy, PartialEq, Eq, Debug, Default)]
pub struct LineModeReport {
    /// Lines of the plan sent.
    pub sent: u64,
    /// Keep-alive repeats sent.
    pub refreshes: u64,
    /// Telemetry rows received.
    pub rows: u64,
    /// `# err` lines received.
    pub errors: u64,
    /// Rows written to the log.
    pub recorded: u64,
}

/// Whether a command changes the motion (and so ends a keep-alive), and
/// whether it is one to keep alive (an untimed motion).
fn motion_effect(command: &str) -> (bool, bool) {
    match parse(command.as_bytes()) {
        Ok(Command::Drive { duration_ms, .. }) | Ok(Command::Servo { duration_ms, .. }) => {
            (true, duration_ms.is_none())
        }
        Ok(Command::Stop) | Ok(Command::Calibrate { .. }) => (true, false),
        _ => (false, false),
    }
}

/// Which commands to send at `now_ms` (ms since the start): the plan's
/// due lines and keep-alive repeats. Pure scheduling, tested alone.
#[derive(Clone, Debug)]
pub struct LineSchedule {
    plan: Vec<PlanLine>,
    next: usize,
    refresh_ms: u64,
    keepalive: bool,
    /// The untimed motion being kept alive and when it was last sent.
    held: Option<(String, u64)>,
    /// When the last plan line went out.
    last_plan_ms: u64,
}

impl LineSchedule {
    pub fn new(plan: Vec<PlanLine>, keepalive: bool, refresh_ms: u64) -> LineSchedule {
        LineSchedule { plan, next: 0, refresh_ms: refresh_ms.max(1), keepalive, held: None, last_plan_ms: 0 }
    }

    /// The lines due at `now_ms`, in order, each with `true` for a plan
    /// line and `false` for a keep-alive repeat.
    pub fn poll(&mut self, now_ms: u64) -> Vec<(String, bool)> {
        let mut out = Vec::new();
        while let Some(line) = self.plan.get(self.next).filter(|l| l.at_ms <= now_ms) {
            let (changes, keep) = motion_effect(&line.command);
            if changes {
                self.held = (keep && self.keepalive).then(|| (line.command.clone(), now_ms));
            } else if let Some(h) = self.held.as_mut() {
                h.1 = now_ms; // any valid command refreshes the deadman
            }
            out.push((line.command.clone(), true));
            self.next += 1;
            self.last_plan_ms = now_ms;
        }
        if let Some((cmd, at)) = self.held.as_mut() {
            if now_ms.saturating_sub(*at) >= self.refresh_ms {
                *at = now_ms;
                out.push((cmd.clone(), false));
            }
        }
        out
    }

    /// True when every plan line has been sent.
    pub fn done(&self) -> bool {
        self.next >= self.plan.len()
    }
    /// When the last plan line went out, ms.
    pub fn last_plan_ms(&self) -> u64 {
        self.last_plan_ms
    }
}

/// One read: prints the lines, counts and records the rows.
fn take_lines<P, O, L>(
    port: &mut P,
    reader: &mut LineReader,
    dash: &mut Dashboard,
    out: &mut O,
    recorder: Option<&mut Recorder<L>>,
    report: &mut LineModeReport,
    now_ms: u64,
) -> io::Result<()>
where
    P: Read + ?Sized,
    O: Write + ?Sized,
    L: Write,
{
    let mut recorder = recorder;
    for line in reader.poll(port)? {
        writeln!(out, "{line}")?;
        if let Some(row) = dash.on_line(&line, now_ms) {
            report.rows += 1;
            if let Some(rec) = recorder.as_deref_mut() {
                if rec.record(&row)? {
                    report.recorded += 1;
                }
            }
        }
    }
    Ok(())
}

/// Reads and drops lines until one equal to `answer`, then writes it and
/// whatever came after it in the same read to `out`; gives up after
/// `wait_ms`. True when the answer came.
fn drain_until<P: Read + ?Sized, O: Write + ?Sized>(
    port: &mut P,
    reader: &mut LineReader,
    answer: &str,
    wait_ms: u32,
    out: &mut O,
) -> io::Result<bool> {
    let start = Instant::now();
    while start.elapsed().as_millis() < u128::from(wait_ms) {
        let lines = reader.poll(port)?;
        if let Some(at) = lines.iter().position(|l| l == answer) {
            for line in lines.iter().skip(at) {
                writeln!(out, "{line}")?;
            }
            return Ok(true);
        }
    }
    Ok(false)
}

/// Runs the line mode: asks for telemetry at `rate_hz` if set (`rate 0`
/// first; what the robot sent before its answer is dropped, so the output
/// starts with that answer and the new CSV header), sends each plan line at
/// its time (and keeps untimed motions alive), prints every line the robot
/// sends to `out` as it comes, records telemetry rows into `recorder`,
/// listens `linger_ms` after the last line, then sends `stop`.
pub fn run_line_mode<P, O, L>(
    port: &mut P,
    plan: Vec<PlanLine>,
    opts: LineModeOptions,
    out: &mut O,
    mut recorder: Option<&mut Recorder<L>>,
) -> io::Result<LineModeReport>
where
    P: Read + Write + ?Sized,
    O: Write + ?Sized,
    L: Write,
{
    let start = Instant::now();
    let now_ms = || start.elapsed().as_millis() as u64;
    let mut report = LineModeReport::default();
    let mut reader = LineReader::new();
    let mut dash = Dashboard::new();
    let mut schedule = LineSchedule::new(plan, opts.keepalive, opts.refresh_ms);
    if let Some(hz) = opts.rate_hz {
        send(port, "rate 0")?;
        // rows the robot sent before the run (still in flight or buffered)
        // end at the answer; only what follows it is printed, so the
        // output's first CSV line is the header `rate` brings
        drain_until(port, &mut reader, "# ok rate 0", config::teleop::ANSWER_WAIT_MS, out)?;
        if hz > 0 {
            send(port, &std::format!("rate {hz}"))?;
        }
    }
    let mut stop_at: Option<u64> = None;
    loop {
        let now = now_ms();
        for (cmd, from_plan) in schedule.poll(now) {
            send(port, &cmd)?;
            if from_plan {
                report.sent += 1;
            } else {
                report.refreshes += 1;
            }
        }
        if schedule.done() && stop_at.is_none() {
            stop_at = Some(schedule.last_plan_ms().saturating_add(opts.linger_ms));
        }
        if stop_at.is_some_and(|t| now >= t) {
            break;
        }
        take_lines(port, &mut reader, &mut dash, out, recorder.as_deref_mut(), &mut report, now)?;
    }
    send(port, "stop")?;
    // the stop's answer (and what was in flight), briefly
    let end = now_ms().saturating_add(opts.refresh_ms);
    while now_ms() < end {
        take_lines(port, &mut reader, &mut dash, out, recorder.as_deref_mut(), &mut report, now_ms())?;
    }
    out.flush()?;
    report.errors = dash.errors();
    Ok(report)
}
