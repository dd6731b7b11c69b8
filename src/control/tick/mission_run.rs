//! The mission runner: the stored mission, and the one under way (its
//! countdown, its steps, its time limit, and its abort on any received
//! byte).

use super::clock::{ms_to_us, Stamp, Timer};
use super::settings::Source;
use super::{Controller, Hardware, LineSink, Mode};
use crate::config;
use crate::control::log::RowLog;
use crate::control::mission::{Mission, Step};
use crate::control::protocol::number::{div_rem_1000, push_fixed_parts, push_str, push_u32};
use crate::control::protocol::{format_command, Command, MissionOp, Response};

/// Where a mission is.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum MissionPhase {
    /// Waiting [`config::mission::COUNTDOWN_MS`] for the cable to go.
    Countdown,
    /// Running its steps.
    Running,
}

/// A mission under way.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub struct MissionRun {
    pub phase: MissionPhase,
    /// When the phase began (set at the first tick that sees it).
    since_us: Option<Stamp>,
    /// The step that runs now (from 1; 0 before the first).
    pub step: usize,
}

/// The mission and its run.
pub(super) struct Missions {
    /// The mission under way, if any.
    pub run: Option<MissionRun>,
    /// The mission changed since [`Controller::take_mission_changed`].
    pub changed: bool,
    /// The stored mission's steps.
    pub mission: Mission,
    /// The on-board log holds a mission's rows not yet kept in flash.
    pub log_unkept: bool,
}

impl Missions {
    pub const fn new() -> Missions {
        Missions { run: None, changed: false, mission: Mission::new(), log_unkept: false }
    }
    /// A mission runs its steps (its countdown is over).
    pub fn running(&self) -> bool {
        matches!(self.run, Some(MissionRun { phase: MissionPhase::Running, .. }))
    }
}

impl<H: Hardware> Controller<H> {
    /// The mission's steps.
    pub fn mission(&self) -> &Mission {
        &self.missions.mission
    }

    /// Restores a stored mission (at boot, from RTC memory: kept across a
    /// reset, newer than the flash's when it differs).
    pub fn set_mission(&mut self, mission: Mission) {
        if mission != self.missions.mission {
            self.sources.mission = Source::Changed;
        }
        self.missions.mission = mission;
    }

    /// True once after each change of the mission (the firmware then
    /// stores it).
    pub fn take_mission_changed(&mut self) -> bool {
        core::mem::take(&mut self.missions.changed)
    }

    /// The mission under way, if any.
    pub fn mission_run(&self) -> Option<MissionRun> {
        self.missions.run
    }

    /// Any byte aborts a running mission (after its countdown: pulling
    /// the cable may make line noise).
    pub(super) fn byte_received(&mut self, sink: &mut impl LineSink) {
        if self.missions.running() {
            self.abort("aborted: a byte came on the serial line", sink);
        }
    }

    /// A command during the countdown cancels the mission.
    pub(super) fn command_received(&mut self, sink: &mut impl LineSink) {
        if self.missions.run.is_some() {
            self.abort("cancelled by a command", sink);
        }
    }

    pub(super) fn mission_op(&mut self, op: MissionOp, cmd: &Command, sink: &mut impl LineSink) {
        match op {
            MissionOp::Add(step) => {
                if self.missions.mission.push(step).is_err() {
                    return self.respond(&Response::Fail("mission full: clear it or start it"), sink);
                }
                self.missions.changed = true;
                self.sources.mission = Source::Changed;
                self.respond(&Response::Ok(cmd), sink);
            }
            MissionOp::Clear => {
                self.missions.mission.clear();
                self.missions.changed = true;
                self.sources.mission = Source::Changed;
                self.respond(&Response::Ok(cmd), sink);
            }
            MissionOp::List => {
                self.respond(&Response::Ok(cmd), sink);
                for i in 0..self.missions.mission.len() {
                    self.write_step(i, sink);
                }
                self.out.clear();
                let line = push_str(&mut self.out, "# mission: ")
                    .and_then(|()| push_u32(&mut self.out, self.missions.mission.len() as u32)) // <= MAX_STEPS
                    .and_then(|()| push_str(&mut self.out, " steps"));
                if line.is_ok() {
                    sink.write_line(&self.out);
                }
            }
            MissionOp::Start => {
                if self.missions.mission.is_empty() {
                    return self.respond(&Response::Fail("mission is empty: add steps first"), sink);
                }
                self.respond(&Response::Ok(cmd), sink);
                self.mode = Mode::Idle;
                self.reports.dump = None;
                self.missions.run = Some(MissionRun { phase: MissionPhase::Countdown, since_us: None, step: 0 });
                self.out.clear();
                let line = push_str(&mut self.out, "# mission starts in ")
                    .and_then(|()| push_u32(&mut self.out, config::mission::COUNTDOWN_MS / 1_000))
                    .and_then(|()| {
                        push_str(&mut self.out, " s: unplug the cable now; a byte received after that aborts it")
                    });
                if line.is_ok() {
                    sink.write_line(&self.out);
                }
            }
        }
    }

    /// `# mission <n>: <command>` for step `i`.
    pub(super) fn write_step(&mut self, i: usize, sink: &mut impl LineSink) {
        let Some(step) = self.missions.mission.get(i) else { return };
        self.out.clear();
        let line = push_str(&mut self.out, "# mission ")
            .and_then(|()| push_u32(&mut self.out, i.saturating_add(1) as u32)) // <= MAX_STEPS
            .and_then(|()| push_str(&mut self.out, ": "))
            .and_then(|()| format_command(&step.command(), &mut self.out));
        if line.is_ok() {
            sink.write_line(&self.out);
        }
    }

    /// A mission's countdown, its time limit and its next step.
    pub(super) fn supervise(&mut self, now: Stamp, sink: &mut impl LineSink) {
        let Some(run) = self.missions.run.as_mut() else { return };
        let since = *run.since_us.get_or_insert(now);
        let elapsed = now.wrapping_sub(since);
        match run.phase {
            MissionPhase::Countdown => {
                if elapsed >= ms_to_us(config::mission::COUNTDOWN_MS) {
                    run.phase = MissionPhase::Running;
                    run.since_us = Some(now);
                    self.log.clear();
                    self.missions.log_unkept = true;
                    self.reports.logging.next_us = now;
                    self.front.unlogged = false;
                    self.right.unlogged = false;
                    self.compass.unlogged = false;
                    self.respond(&Response::Note("mission: go"), sink);
                }
                return;
            }
            MissionPhase::Running => {}
        }
        if elapsed >= ms_to_us(config::mission::TIME_LIMIT_MS) {
            return self.abort("stopped: its time limit", sink);
        }
        if !matches!(self.mode, Mode::Idle) {
            return;
        }
        let i = run.step;
        let Some(step) = self.missions.mission.get(i) else {
            self.missions.run = None;
            self.out.clear();
            let line = push_str(&mut self.out, "# mission done in ")
                .and_then(|()| push_fixed_parts(&mut self.out, false, div_rem_1000(elapsed).0, 3))
                .and_then(|()| push_str(&mut self.out, " s; dump sends its log"));
            if line.is_ok() {
                sink.write_line(&self.out);
            }
            return;
        };
        run.step = i.saturating_add(1);
        self.write_step(i, sink);
        let cmd = step.command();
        match step {
            Step::Drive { motion, duration_ms } => {
                let drive = self.model.drive(motion);
                self.mode = Mode::Drive { drive, timer: Timer::new(Some(duration_ms)) };
            }
            Step::Pose { x_mm, y_mm, heading } => self.set_pose(crate::model::Pose::from_mm(x_mm, y_mm, heading)),
            Step::Wait { .. } | Step::Goto { .. } | Step::Face { .. } => self.begin(&cmd, true, sink),
        }
    }

    /// Ends a mission under way (if any): the robot stops.
    pub(super) fn abort(&mut self, why: &str, sink: &mut impl LineSink) {
        let Some(run) = self.missions.run.take() else { return };
        self.mode = Mode::Idle;
        self.out.clear();
        let line = push_str(&mut self.out, "# err mission ")
            .and_then(|()| push_str(&mut self.out, why))
            .and_then(|()| push_str(&mut self.out, " (step "))
            .and_then(|()| push_u32(&mut self.out, run.step as u32)) // <= MAX_STEPS
            .and_then(|()| push_str(&mut self.out, " of "))
            .and_then(|()| push_u32(&mut self.out, self.missions.mission.len() as u32))
            .and_then(|()| push_str(&mut self.out, ")"));
        if line.is_ok() {
            sink.write_line(&self.out);
        }
    }
}
