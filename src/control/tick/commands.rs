//! Commands: bytes in, parsed lines carried out, answers out.

use super::clock::Timer;
use super::settings::{Source, NOT_SAVED};
use super::{Controller, Hardware, LineSink, Mode};
use crate::control::protocol::{format_response, format_status, Command, ParseError, Response, Side, HELP};
use crate::control::survey::Failure;
use crate::model::Pose;

impl<H: Hardware> Controller<H> {
    /// Takes one received serial byte; a finished line is parsed and
    /// handled at once (its answer goes to `sink`).
    pub fn feed(&mut self, byte: u8, sink: &mut impl LineSink) {
        self.byte_received(sink);
        match self.input.push(byte) {
            None => {}
            Some(Err(e)) => self.respond(&Response::Err(e), sink),
            Some(Ok(line)) => match line.parse() {
                Ok(cmd) => self.handle(cmd, sink),
                Err(ParseError::Empty) => {}
                Err(e) => self.respond(&Response::Err(e), sink),
            },
        }
    }

    /// [`Controller::feed`] for each byte.
    pub fn feed_bytes(&mut self, bytes: &[u8], sink: &mut impl LineSink) {
        for &b in bytes {
            self.feed(b, sink);
        }
    }

    /// Carries out one parsed command and answers `# ok <command>` (for a
    /// motion the servos cannot drive as asked, the motion they drive).
    pub fn handle(&mut self, cmd: Command, sink: &mut impl LineSink) {
        self.command_seen = true;
        self.command_received(sink);
        // a goto or face while locating waits for the fix it needs: the
        // localization goes on (only other commands end it), the newest
        // target after it; one that waited already is answered
        let needs_fix = matches!(cmd, Command::Goto { .. } | Command::Face { .. });
        if needs_fix && matches!(self.mode, Mode::Locate { .. }) && self.missions.run.is_none() {
            if let Some(old) = self.localizing.then.replace(cmd) {
                self.say_refused(&old, "replaced by a later command", sink);
            }
            self.respond(&Response::Note("locating: it goes when located"), sink);
            return;
        }
        // a command ends a sweep or a localization (it runs instead)
        if !matches!(cmd, Command::Status | Command::Help | Command::Rate { .. } | Command::Settings) {
            match self.mode {
                Mode::Calibrate { .. } => self.end_calibration(None, sink),
                Mode::Locate { .. } => self.end_locate(Err(Failure::Interrupted), sink),
                _ => {}
            }
        }
        // a motion, a goto or face, a mission start, a save or forget (which
        // may be refused) answer for themselves
        if !matches!(
            cmd,
            Command::Drive { .. }
                | Command::Goto { .. }
                | Command::Face { .. }
                | Command::Mission(_)
                | Command::Save
                | Command::Forget
        ) {
            self.respond(&Response::Ok(&cmd), sink);
        }
        match cmd {
            Command::Drive { motion, duration_ms } => {
                let drive = self.model.drive(motion);
                self.mode = Mode::Drive { drive, timer: Timer::new(duration_ms) };
                // a motion outside what the servos drive is driven at the
                // nearest they can, and the answer says so: `fwd 0.05` -> `# ok fwd 0.124`
                let driven = if drive.saturated { Command::Drive { motion: drive.motion, duration_ms } } else { cmd };
                self.respond(&Response::Ok(&driven), sink);
            }
            Command::Stop => {
                self.mode = Mode::Idle;
            }
            Command::Servo { left, right, duration_ms } => {
                let motion = self.model.motion_from_commands(left, right);
                self.mode = Mode::Servo { left, right, motion, timer: Timer::new(duration_ms) };
            }
            Command::Trim { side, trim } => {
                match side {
                    Side::Left => self.model.left_trim = trim,
                    Side::Right => self.model.right_trim = trim,
                }
                // the neutral moved: recompute a running drive's commands
                if let Mode::Drive { drive, .. } = &mut self.mode {
                    *drive = self.model.drive(drive.motion);
                }
                self.sources.trims = Source::Changed;
                self.respond(&Response::Note(NOT_SAVED), sink);
            }
            Command::SetPose { x_mm, y_mm, heading } => self.set_pose(Pose::from_mm(x_mm, y_mm, heading)),
            Command::Calibrate { samples } => self.begin_sweep(samples),
            Command::Rate { hz } => {
                self.set_rate(hz);
            }
            Command::Status => {
                let status = self.status();
                self.out.clear();
                if format_status(&status, &mut self.out).is_ok() {
                    sink.write_line(&self.out);
                }
            }
            Command::Help => {
                for line in HELP {
                    sink.write_line(line);
                }
            }
            Command::Goto { .. } | Command::Face { .. } | Command::Wait { .. } => self.begin(&cmd, true, sink),
            Command::Mission(op) => self.mission_op(op, &cmd, sink),
            Command::Log { hz } => self.set_log_rate(hz),
            Command::Dump => self.start_dump(sink),
            Command::Locate => self.begin_locate(),
            Command::Save => self.save_settings(sink),
            Command::Settings => self.report_settings(sink),
            Command::Forget => self.forget_settings(sink),
        }
    }

    /// Sets the estimate (and the dead-reckoned pose) to `pose`.
    pub(super) fn set_pose(&mut self, pose: Pose) {
        self.estimator.reset(pose);
        #[cfg(feature = "std")]
        {
            self.dead = pose;
        }
    }

    pub(super) fn respond(&mut self, r: &Response, sink: &mut impl LineSink) {
        self.out.clear();
        if format_response(r, &mut self.out).is_ok() {
            sink.write_line(&self.out);
        }
    }
}
