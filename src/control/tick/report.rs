//! What the loop reports and when: telemetry rows at their rate (after
//! the header), rows into the on-board log at theirs while a mission
//! runs, and `dump`, which sends the log in place of telemetry: the one
//! in RAM, or when that is empty (after a power-off) the one kept in
//! flash at the last mission's end (`tick/settings.rs`).

use super::clock::{reached, Stamp};
use super::{Controller, Hardware, LineSink};
use crate::config;
use crate::control::log::RowLog;
use crate::control::protocol::number::{push_str, push_u32};
use crate::control::protocol::{format_row, format_telemetry, telemetry_header, Telemetry, TelemetryRow};
use crate::control::settings::kept_log::KeptLog;
use crate::control::settings::SettingsStore;
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

/// A `dump` under way.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub(super) struct Dump {
    /// The next row it sends.
    next: usize,
    /// The log it sends: the kept one in flash, or (`None`) the RAM's.
    kept: Option<KeptLog>,
}

/// The reporting state: the two schedules and a dump under way.
pub(super) struct Reports {
    pub telemetry: Schedule,
    /// The telemetry header goes before the next row.
    pub header_due: bool,
    pub logging: Schedule,
    /// The dump being sent, if any.
    pub dump: Option<Dump>,
}

impl Reports {
    pub const fn new() -> Reports {
        Reports {
            // the config's rate, as `set_rate` would set it: the first row
            // (after the header) at the first tick
            telemetry: Schedule::new(INITIAL_HZ),
            header_due: INITIAL_HZ != 0,
            logging: Schedule::new(config::log::HZ),
            dump: None,
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
        if self.reports.dump.is_some() {
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

    /// `dump`: a summary line and the header now, a row a tick after. The
    /// RAM's log, or when it holds no row the newest kept in flash.
    pub(super) fn start_dump(&mut self, sink: &mut impl LineSink) {
        let kept = if self.log.is_empty() { self.newest_kept_log(sink) } else { None };
        let (rows, hz, dropped) = match kept {
            Some(k) => (k.rows, k.hz, k.dropped),
            None => (self.log.len() as u32, self.reports.logging.hz, self.log.dropped()), // <= config::log::ROWS
        };
        self.say(sink, |o| {
            push_str(o, "# log ")?;
            push_u32(o, rows)?;
            push_str(o, " rows at ")?;
            push_u32(o, u32::from(hz))?;
            push_str(o, " Hz, ")?;
            push_u32(o, dropped)?;
            push_str(o, " dropped (oldest first)")?;
            match kept {
                Some(k) => {
                    push_str(o, ", kept in flash, log ")?;
                    push_u32(o, k.sequence)
                }
                None => Ok(()),
            }
        });
        sink.write_line(telemetry_header());
        self.reports.dump = Some(Dump { next: 0, kept });
    }

    /// The newest valid log in flash; a slot holding something else is
    /// named with the reason.
    fn newest_kept_log(&mut self, sink: &mut impl LineSink) -> Option<KeptLog> {
        let found = match self.settings.kept_logs() {
            Ok(found) => found,
            Err(e) => {
                self.say(sink, |o| {
                    push_str(o, crate::control::protocol::ERR)?;
                    push_str(o, "kept log unread: ")?;
                    push_str(o, super::settings::flash_error(e))
                });
                return None;
            }
        };
        for (&slot, refusal) in config::settings::LOG_SLOTS.iter().zip(found.refused) {
            self.say_ignored(sink, "# kept log at ", slot, refusal, config::settings::LOG_VERSION);
        }
        found.newest
    }

    /// The next rows of a dump (in place of telemetry), then `# log end`.
    pub(super) fn dump_rows(&mut self, sink: &mut impl LineSink) {
        for _ in 0..config::log::DUMP_ROWS_PER_TICK {
            let Some(dump) = self.reports.dump else { return };
            let row = match &dump.kept {
                Some(kept) => self.settings.kept_row(kept, dump.next),
                None => Ok(self.log.row(dump.next)),
            };
            let row = match row {
                Ok(Some(row)) => row,
                Ok(None) => {
                    self.reports.dump = None;
                    sink.write_line("# log end");
                    return;
                }
                Err(e) => {
                    self.reports.dump = None;
                    return self.say(sink, |o| {
                        push_str(o, crate::control::protocol::ERR)?;
                        push_str(o, "log cut short: ")?;
                        push_str(o, super::settings::flash_error(e))
                    });
                }
            };
            self.out.clear();
            if format_row(&row, &mut self.out).is_ok() {
                sink.write_line(&self.out);
            }
            self.reports.dump = Some(Dump { next: dump.next.saturating_add(1), ..dump });
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
