//! What the loop reports and when: telemetry rows at their rate (after
//! the header), rows into the on-board log at theirs while a mission
//! runs, and `dump`, which sends the log in place of telemetry.

use super::clock::{reached, Stamp};
use super::{Controller, Hardware, LineSink};
use crate::config;
use crate::control::log::RowLog;
use crate::control::protocol::number::{push_str, push_u32};
use crate::control::protocol::{format_row, format_telemetry, telemetry_header, Telemetry, TelemetryRow};
use crate::math::div_u64;

/// Rows at a rate: telemetry's, or the on-board log's.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub(super) struct Schedule {
    /// Rows per second (0: off).
    pub hz: u16,
    /// 1 s / `hz` (0 when off), at most 1 s.
    period_us: u32,
    /// When the next row is due.
    pub next_us: Stamp,
}

impl Schedule {
    const fn new(hz: u16) -> Schedule {
        Schedule { hz, period_us: period_us(hz), next_us: 0 }
    }

    /// A new rate, the schedule kept.
    pub fn set_rate(&mut self, hz: u16) {
        self.hz = hz;
        self.period_us = period_us(hz);
    }

    /// True when a row is due at `now`; the schedule moves on by a period
    /// (after a stall, from now).
    pub fn due(&mut self, now: Stamp) -> bool {
        if self.hz == 0 || !reached(now, self.next_us) {
            return false;
        }
        self.next_us = self.next_us.wrapping_add(self.period_us);
        if reached(now, self.next_us) {
            self.next_us = now.wrapping_add(self.period_us);
        }
        true
    }
}

/// The reporting state: the two schedules and a dump under way.
pub(super) struct Reports {
    pub telemetry: Schedule,
    /// The telemetry header goes before the next row.
    pub header_due: bool,
    pub logging: Schedule,
    /// The next log row `dump` sends (while it is sending).
    pub dump_next: Option<usize>,
}

impl Reports {
    pub const fn new() -> Reports {
        Reports {
            // the config's rate, as `set_rate` would set it: the first row
            // (after the header) at the first tick
            telemetry: Schedule::new(INITIAL_HZ),
            header_due: INITIAL_HZ != 0,
            logging: Schedule::new(config::log::HZ),
            dump_next: None,
        }
    }
}

impl<H: Hardware> Controller<H> {
    /// The on-board log (what `dump` sends).
    pub fn log(&self) -> &H::Log {
        &self.log
    }

    /// `rate`: telemetry at `hz` (0: off), its first row at the next tick
    /// (after the header if telemetry was off).
    pub(super) fn set_rate(&mut self, hz: u16) {
        let r = &mut self.reports;
        if hz != 0 && r.telemetry.hz == 0 {
            r.header_due = true;
        }
        r.telemetry.set_rate(hz);
        r.telemetry.next_us = self.clock.now();
    }

    /// A telemetry row when one is due (or, during a `dump`, the log's
    /// rows instead: telemetry would mix with them).
    pub(super) fn telemetry(&mut self, now: Stamp, sink: &mut impl LineSink) {
        if self.reports.dump_next.is_some() {
            return self.dump_rows(sink);
        }
        if !self.reports.telemetry.due(now) {
            return;
        }
        if core::mem::take(&mut self.reports.header_due) {
            sink.write_line(telemetry_header());
        }
        let fresh = [
            core::mem::take(&mut self.front.unreported),
            core::mem::take(&mut self.right.unreported),
            core::mem::take(&mut self.compass.unreported),
        ];
        let t = self.snapshot(fresh);
        self.out.clear();
        if format_telemetry(&t, &mut self.out).is_ok() {
            sink.write_line(&self.out);
        }
    }

    /// A row into the on-board log at its rate (while a mission runs).
    pub(super) fn log_row(&mut self, now: Stamp) {
        if !self.missions.running() || !self.reports.logging.due(now) {
            return;
        }
        let fresh = [
            core::mem::take(&mut self.front.unlogged),
            core::mem::take(&mut self.right.unlogged),
            core::mem::take(&mut self.compass.unlogged),
        ];
        let t = self.snapshot(fresh);
        self.log.push(&TelemetryRow::from(&t));
    }

    /// `log`: the on-board log's rate (0: off).
    pub(super) fn set_log_rate(&mut self, hz: u16) {
        self.reports.logging.set_rate(hz);
    }

    /// `dump`: a summary line and the header now, a row a tick after.
    pub(super) fn start_dump(&mut self, sink: &mut impl LineSink) {
        self.out.clear();
        let line = push_str(&mut self.out, "# log ")
            .and_then(|()| push_u32(&mut self.out, self.log.len() as u32)) // <= config::log::ROWS
            .and_then(|()| push_str(&mut self.out, " rows at "))
            .and_then(|()| push_u32(&mut self.out, u32::from(self.reports.logging.hz)))
            .and_then(|()| push_str(&mut self.out, " Hz, "))
            .and_then(|()| push_u32(&mut self.out, self.log.dropped()))
            .and_then(|()| push_str(&mut self.out, " dropped (oldest first)"));
        if line.is_ok() {
            sink.write_line(&self.out);
        }
        sink.write_line(telemetry_header());
        self.reports.dump_next = Some(0);
    }

    /// The next rows of a dump (in place of telemetry), then `# log end`.
    pub(super) fn dump_rows(&mut self, sink: &mut impl LineSink) {
        for _ in 0..config::log::DUMP_ROWS_PER_TICK {
            let Some(i) = self.reports.dump_next else { return };
            let Some(row) = self.log.row(i) else {
                self.reports.dump_next = None;
                sink.write_line("# log end");
                return;
            };
            self.out.clear();
            if format_row(&row, &mut self.out).is_ok() {
                sink.write_line(&self.out);
            }
            self.reports.dump_next = Some(i.saturating_add(1));
        }
    }

    /// A telemetry row's values now, with the readings flagged fresh
    /// (front, right, compass).
    pub(super) fn snapshot(&self, [front, right, compass]: [bool; 3]) -> Telemetry {
        Telemetry {
            t_ms: self.t_ms(),
            pose: self.estimator.pose(),
            front: self.front.latest.filter(|_| front),
            right: self.right.latest.filter(|_| right),
            compass: self.compass.latest.filter(|_| compass),
            motion: self.applied.motion,
            left_cmd: self.applied.left,
            right_cmd: self.applied.right,
            faults: self.faults,
            tracking: self.estimator.tracking(),
        }
    }
}

const _: () = assert!(config::timing::TELEMETRY_HZ <= config::serial::MAX_TELEMETRY_HZ as u32);
/// The telemetry rate a new loop starts at (`config::timing::TELEMETRY_HZ`,
/// asserted above to fit the protocol's range).
const INITIAL_HZ: u16 = config::timing::TELEMETRY_HZ as u16;

/// The period of a rate, us: 0 for 0 Hz (off), else at most 1 s (fits).
/// [`div_u64`] stays a call: a division the compiler sees as 32-bit would
/// link compiler_builtins' `__udivsi3`, which the ROM file leaves out.
const fn period_us(hz: u16) -> u32 {
    match div_u64(1_000_000, hz as u64) {
        Some(q) => q as u32,
        None => 0,
    }
}
