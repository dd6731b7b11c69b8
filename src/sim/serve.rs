//! Serving a [`SimRobot`] over a serial byte stream in real time, so the
//! host tools (the teleop tool, a terminal program, a script) talk to the
//! simulated robot exactly as to the real one: `examples/sim_pty.rs` puts
//! it on a pseudo-terminal.
//!
//! Each loop period ([`TICK_US`], the firmware's loop rate) of wall time:
//! the bytes that arrived are fed to the robot, the robot ticks once, and
//! its output lines go out with `\r\n` as the firmware's UART writes them.
//! Output nobody reads piles up in the port (a PTY holds a few kB) and then
//! in a bounded queue here; past [`MAX_PENDING`] new lines are dropped and
//! counted, as a real UART's bytes are lost when nobody listens.
//!
//! With [`Server::with_truth`] the output also carries the simulator's true
//! pose as `# truth ...` lines ([`truth_line`]) at a chosen rate, so a tool
//! can draw it beside the estimate (`teleop --web`); a real robot sends
//! none, and tools that do not know them show them as messages.
//!
//! The port is anything `Read + Write` whose reads and writes return at once
//! when they cannot proceed (`TimedOut`/`WouldBlock`), e.g. a `serialport`
//! port with a zero timeout.

use std::format;
use std::io::{self, ErrorKind, Read, Write};
use std::string::String;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};
use std::vec::Vec;

use super::body::PoseF64;
use super::robot::SimRobot;
use crate::control::TICK_US;

/// Most output bytes queued here for a slow or absent reader.
pub const MAX_PENDING: usize = 64 * 1024;

/// A server falling this far behind wall time (a stalled host) starts its
/// schedule anew instead of running the missed ticks in a burst, ms.
pub const RESYNC_MS: u64 = 100;

/// Counts of a serving run.
#[derive(Clone, Copy, PartialEq, Eq, Debug, Default)]
pub struct ServeStats {
    pub ticks: u64,
    pub bytes_in: u64,
    pub bytes_out: u64,
    /// Output lines dropped because nobody read them.
    pub dropped_lines: u64,
    /// Times the schedule was restarted after falling behind.
    pub resyncs: u64,
}

/// The robot and its output queue.
pub struct Server {
    robot: SimRobot,
    pending: Vec<u8>,
    stats: ServeStats,
    /// `# truth` lines: their period and when the next is due, us of simulated time.
    truth: Option<(u64, u64)>,
}

/// The `# truth t_ms=T x_mm=X y_mm=Y heading_deg=H` line for the true pose
/// at `t_ms` of simulated time (the firmware's clock): mm to 0.1, degrees
/// clockwise from north in 0..360 to 0.01.
pub fn truth_line(t_ms: u64, p: &PoseF64) -> String {
    format!(
        "# truth t_ms={t_ms} x_mm={:.1} y_mm={:.1} heading_deg={:.2}",
        p.x,
        p.y,
        p.theta.to_degrees().rem_euclid(360.0)
    )
}

fn idle(e: &io::Error) -> bool {
    matches!(e.kind(), ErrorKind::TimedOut | ErrorKind::WouldBlock | ErrorKind::Interrupted)
}

impl Server {
    pub fn new(robot: SimRobot) -> Server {
        Server { robot, pending: Vec::new(), stats: ServeStats::default(), truth: None }
    }

    /// Also sends the true pose `hz` times a second of simulated time (0:
    /// never; at most once a loop period), as [`truth_line`]s among the
    /// robot's lines.
    pub fn with_truth(mut self, hz: u32) -> Server {
        self.truth = (hz > 0).then(|| (1_000_000 / u64::from(hz), 0));
        self
    }

    /// One loop period without waiting: input, one tick, output.
    pub fn step<P: Read + Write + ?Sized>(&mut self, port: &mut P) -> io::Result<()> {
        let mut buf = [0u8; 1024];
        loop {
            match port.read(&mut buf) {
                Ok(0) => break,
                Ok(n) => {
                    self.stats.bytes_in += n as u64;
                    for &b in buf.get(..n).unwrap_or(&[]) {
                        self.robot.feed(b);
                    }
                    if n < buf.len() {
                        break;
                    }
                }
                Err(e) if idle(&e) => break,
                Err(e) => return Err(e),
            }
        }
        self.robot.tick();
        self.stats.ticks += 1;
        let mut lines = self.robot.take_output();
        if let Some((period, next)) = self.truth.as_mut() {
            let now = self.robot.now_us();
            if now >= *next {
                *next = now + *period;
                lines.push(truth_line(now / 1000, &self.robot.truth()));
            }
        }
        for line in lines {
            if self.pending.len() + line.len() + 2 > MAX_PENDING {
                self.stats.dropped_lines += 1;
                continue;
            }
            self.pending.extend_from_slice(line.as_bytes());
            self.pending.extend_from_slice(b"\r\n");
        }
        while !self.pending.is_empty() {
            match port.write(&self.pending) {
                Ok(0) => break,
                Ok(n) => {
                    self.stats.bytes_out += n as u64;
                    self.pending.drain(..n.min(self.pending.len()));
                }
                Err(e) if idle(&e) => break,
                Err(e) => return Err(e),
            }
        }
        let _ = port.flush();
        Ok(())
    }

    /// Runs [`Server::step`] once per loop period of wall time until `stop`
    /// is set (or the port fails).
    pub fn run<P: Read + Write + ?Sized>(&mut self, port: &mut P, stop: &AtomicBool) -> io::Result<()> {
        let period = Duration::from_micros(u64::from(TICK_US));
        let mut base = Instant::now();
        let mut k: u32 = 0;
        while !stop.load(Ordering::Relaxed) {
            let due = base + period * k;
            let now = Instant::now();
            if due > now {
                std::thread::sleep(due - now);
            } else if now - due > Duration::from_millis(RESYNC_MS) {
                base = now;
                k = 0;
                self.stats.resyncs += 1;
            }
            self.step(port)?;
            k += 1;
            if k >= 1_000_000 {
                // keep the tick count small: move the base up (no drift)
                base += period * k;
                k = 0;
            }
        }
        Ok(())
    }

    pub fn robot(&self) -> &SimRobot {
        &self.robot
    }
    pub fn robot_mut(&mut self) -> &mut SimRobot {
        &mut self.robot
    }
    pub fn stats(&self) -> ServeStats {
        self.stats
    }
    pub fn into_robot(self) -> SimRobot {
        self.robot
    }
}
