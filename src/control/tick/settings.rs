//! The settings in flash as the loop uses them: restored at boot (with a
//! line saying what came from flash, or why a record was ignored), and the
//! `save`, `settings` and `forget` commands. Each value's [`Source`] is
//! kept, so `settings` says whether it is the config's, the record's, or
//! changed since (`trim`, `cal`, `mission add|clear`: not saved).
//!
//! A save or a forget pauses the loop for the flash's erase and write
//! (`board::rom_flash`: 49.8 ms on the emulated board; UART0's 128-byte
//! FIFO fills in 11 ms at 115200 baud), so both are refused while the robot
//! moves, or a mission is under way, with the reason.

use super::{Controller, Hardware, LineSink, Mode};
use crate::config;
use crate::control::log::RowLog;
use crate::control::protocol::field::q8_to_centi;
use crate::control::protocol::number::{push_fixed, push_fixed_parts, push_hex, push_str, push_u32, TextOut};
use crate::control::protocol::response::format_calibration_values;
use crate::control::protocol::{Overflow, Response};
use crate::control::settings::{FlashError, Refusal, Settings, SettingsStore};
use crate::driver::MagCalibrate;

/// Where a setting's value comes from.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum Source {
    /// `src/config/` (nothing in flash, or after `forget`).
    Config,
    /// The record in flash (restored at boot, or saved since).
    Flash,
    /// Changed since (`trim`, `cal`, `mission`): lost at power-off.
    Changed,
}

impl Source {
    fn word(self) -> &'static str {
        match self {
            Source::Config => "config",
            Source::Flash => "flash",
            Source::Changed => "not saved",
        }
    }
}

/// Each setting's [`Source`].
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub struct Sources {
    pub trims: Source,
    pub calibration: Source,
    pub declination: Source,
    pub mission: Source,
}

impl Sources {
    pub const CONFIG: Sources = Sources {
        trims: Source::Config,
        calibration: Source::Config,
        declination: Source::Config,
        mission: Source::Config,
    };
    const FLASH: Sources = Sources {
        trims: Source::Flash,
        calibration: Source::Flash,
        declination: Source::Flash,
        mission: Source::Flash,
    };
}

/// The answer to a changed setting (`trim`, a good `cal`, `mission add|clear`).
pub(super) const NOT_SAVED: &str = "not saved: save to keep it";

pub(super) fn flash_error(e: FlashError) -> &'static str {
    match e {
        FlashError::Error => "flash error",
        FlashError::Timeout => "flash timeout",
    }
}

impl<H: Hardware> Controller<H> {
    /// Where each setting's value comes from.
    pub fn sources(&self) -> Sources {
        self.sources
    }

    /// The settings in use (what `save` writes).
    pub fn settings_now(&self) -> Settings {
        Settings {
            left_trim: self.model.left_trim,
            right_trim: self.model.right_trim,
            calibration: self.compass.driver.calibration(),
            declination: self.compass.driver.declination(),
            mission: self.missions.mission.clone(),
        }
    }

    /// The settings store (tests and the simulator look at its flash).
    pub fn settings_store(&mut self) -> &mut H::Settings {
        &mut self.settings
    }

    fn apply(&mut self, s: Settings) {
        self.model.left_trim = s.left_trim;
        self.model.right_trim = s.right_trim;
        self.compass.driver.set_calibration(s.calibration);
        self.compass.driver.set_declination(s.declination);
        self.missions.mission = s.mission;
    }

    /// Boot: the newer valid record in flash replaces the config's values,
    /// whole; a sector that holds something else than a record (or nothing)
    /// is named with the reason, and the config is used.
    pub fn restore_settings(&mut self, sink: &mut impl LineSink) {
        let loaded = match self.settings.load() {
            Ok(loaded) => loaded,
            Err(e) => {
                self.say(sink, |o| {
                    push_str(o, "# settings: config (")?;
                    push_str(o, flash_error(e))?;
                    push_str(o, ")")
                });
                return;
            }
        };
        for (&sector, refusal) in config::settings::SECTORS.iter().zip(loaded.refused) {
            self.say_ignored(sink, "# settings at ", sector, refusal, config::settings::VERSION);
        }
        match loaded.newest {
            Some((settings, sequence)) => {
                let steps = settings.mission.len() as u32; // <= MAX_STEPS
                self.apply(settings);
                self.sources = Sources::FLASH;
                self.say(sink, |o| {
                    push_str(o, "# settings from flash, record ")?;
                    push_u32(o, sequence)?;
                    push_str(o, ": trims, compass, declination, mission of ")?;
                    push_u32(o, steps)?;
                    push_str(o, " steps")
                });
            }
            None => self.respond(&Response::Note("settings: config (none in flash)"), sink),
        }
    }

    /// A save or a forget pauses the loop: not while the robot moves.
    fn still(&mut self, sink: &mut impl LineSink) -> bool {
        let still = matches!(self.mode, Mode::Idle) && self.missions.run.is_none();
        if !still {
            self.respond(&Response::Fail("moving: stop first (flash pauses the loop)"), sink);
        }
        still
    }

    /// `save`.
    pub(super) fn save_settings(&mut self, sink: &mut impl LineSink) {
        if !self.still(sink) {
            return;
        }
        let settings = self.settings_now();
        match self.settings.save(&settings) {
            Ok(saved) => {
                self.sources = Sources::FLASH;
                self.respond(&Response::Ok(&crate::control::protocol::Command::Save), sink);
                self.say(sink, |o| {
                    push_str(o, "# saved: record ")?;
                    push_u32(o, saved.sequence)?;
                    push_str(o, " at ")?;
                    push_hex(o, saved.sector)?;
                    push_pause(o, saved.pause_us)
                });
            }
            Err(e) => self.say(sink, |o| {
                push_str(o, crate::control::protocol::ERR)?;
                push_str(o, "not saved: ")?;
                push_str(o, flash_error(e))
            }),
        }
    }

    /// `forget`: both sectors erased, the config's values back (the
    /// mission stays in RAM, not saved).
    pub(super) fn forget_settings(&mut self, sink: &mut impl LineSink) {
        if !self.still(sink) {
            return;
        }
        match self.settings.forget() {
            Ok(pause_us) => {
                // the config's values, field by field (the mission stays)
                self.model.left_trim = config::actuators::LEFT_TRIM;
                self.model.right_trim = config::actuators::RIGHT_TRIM;
                self.compass.driver.set_calibration(config::compass::CALIBRATION);
                self.compass.driver.set_declination(config::compass::DECLINATION);
                let mission = if self.missions.mission.is_empty() { Source::Config } else { Source::Changed };
                self.sources = Sources { mission, ..Sources::CONFIG };
                self.respond(&Response::Ok(&crate::control::protocol::Command::Forget), sink);
                self.say(sink, |o| {
                    push_str(o, "# flash erased, config in use")?;
                    push_pause(o, pause_us)
                });
            }
            Err(e) => self.say(sink, |o| {
                push_str(o, crate::control::protocol::ERR)?;
                push_str(o, "not forgotten: ")?;
                push_str(o, flash_error(e))
            }),
        }
    }

    /// At a mission's end, once the robot stands: the on-board log kept in
    /// flash (a power-off then keeps it for `dump`). The erase and write
    /// pause the loop (`push_pause`); the wheels are stopped by then.
    pub(super) fn keep_log(&mut self, sink: &mut impl LineSink) {
        let standing = matches!(self.mode, Mode::Idle)
            && self.missions.run.is_none()
            && self.applied.motion == crate::model::Motion::Stop;
        if !self.missions.log_unkept || !standing {
            return;
        }
        self.missions.log_unkept = false;
        if self.log.is_empty() {
            return; // nothing to keep (the log's rate was 0)
        }
        let rows = self.log.len() as u32; // <= config::log::ROWS
        match self.settings.keep_log(&self.log, self.reports.logging.hz) {
            Ok(kept) => self.say(sink, |o| {
                push_str(o, "# kept the log in flash: ")?;
                push_u32(o, rows)?;
                push_str(o, " rows, log ")?;
                push_u32(o, kept.sequence)?;
                push_str(o, " at ")?;
                push_hex(o, kept.sector)?;
                push_pause(o, kept.pause_us)
            }),
            Err(e) => self.say(sink, |o| {
                push_str(o, crate::control::protocol::ERR)?;
                push_str(o, "log not kept in flash: ")?;
                push_str(o, flash_error(e))
            }),
        }
    }

    /// `settings`: one line per setting with its source.
    pub(super) fn report_settings(&mut self, sink: &mut impl LineSink) {
        let s = self.settings_now();
        let src = self.sources;
        self.say(sink, |o| {
            push_str(o, "# trims (")?;
            push_str(o, src.trims.word())?;
            push_str(o, "): left ")?;
            push_fixed(o, q8_to_centi(i32::from(s.left_trim.0)), 2)?;
            push_str(o, " right ")?;
            push_fixed(o, q8_to_centi(i32::from(s.right_trim.0)), 2)
        });
        self.say(sink, |o| {
            push_str(o, "# compass (")?;
            push_str(o, src.calibration.word())?;
            push_str(o, "): ")?;
            format_calibration_values(o, &s.calibration)
        });
        self.say(sink, |o| {
            push_str(o, "# declination (")?;
            push_str(o, src.declination.word())?;
            push_str(o, "): ")?;
            push_fixed_parts(o, false, s.declination.to_millidegrees(), 3)
        });
        self.say(sink, |o| {
            push_str(o, "# mission (")?;
            push_str(o, src.mission.word())?;
            push_str(o, "): ")?;
            push_u32(o, s.mission.len() as u32)?; // <= MAX_STEPS
            push_str(o, " steps")
        });
    }

    /// `<what><addr> ignored: <reason>` for what a flash sector holds in
    /// place of a record or a log this firmware takes (nothing for an
    /// erased one); another version is named against `version`.
    pub(super) fn say_ignored(
        &mut self,
        sink: &mut impl LineSink,
        what: &str,
        addr: u32,
        refusal: Option<Refusal>,
        version: u32,
    ) {
        let Some(refusal) = refusal.filter(|r| *r != Refusal::Blank) else { return };
        self.say(sink, |o| {
            push_str(o, what)?;
            push_hex(o, addr)?;
            push_str(o, " ignored: ")?;
            push_str(o, refusal.reason())?;
            if let Refusal::OtherVersion(v) = refusal {
                push_str(o, " ")?;
                push_u32(o, v)?;
                push_str(o, " not ")?;
                push_u32(o, version)?;
            }
            Ok(())
        });
    }

    /// One output line built by `f` (a line that does not fit is dropped,
    /// which `MAX_OUT_LINE` makes impossible here).
    pub(super) fn say(&mut self, sink: &mut impl LineSink, f: impl FnOnce(&mut dyn TextOut) -> Result<(), Overflow>) {
        self.out.clear();
        if f(&mut self.out).is_ok() {
            sink.write_line(&self.out);
        }
    }
}

/// `, paused <ms>.<tenths> ms` (the loop's pause).
fn push_pause(o: &mut dyn TextOut, pause_us: u32) -> Result<(), Overflow> {
    push_str(o, ", paused ")?;
    push_fixed_parts(o, false, pause_us / 100, 1)?;
    push_str(o, " ms")
}
