//! The loop's untethered side: `goto`/`face` on the estimate, the wall
//! stop, missions (their countdown, steps, time limit and abort on any
//! received byte) and the on-board log with its `dump`.

use super::clock::{ms_to_us, reached, Stamp, Timer};
use super::health::Which;
use super::{telemetry_period_us, Controller, LineSink, Mode};
use crate::config;
use crate::control::goto::{check_target, position_steerable, Nav, NavStep, Refusal, Target};
use crate::control::log::RowLog;
use crate::control::mission::{Mission, Step};
use crate::control::protocol::number::{div_rem_1000, push_fixed_parts, push_i32, push_str, push_u32};
use crate::control::protocol::{
    format_command, format_row, telemetry_header, Command, MissionOp, Response, TelemetryRow,
};
use crate::driver::{HeadingSensor, LidarSample, MagCalibrate, Servos};
use crate::math::{Angle, Length};
use crate::model::{Motion, Range};

/// [`Controller`]'s `log_fresh` bits: a reading came since the last log row.
pub(super) const LOG_FRONT: u8 = 1;
pub(super) const LOG_RIGHT: u8 = 2;
pub(super) const LOG_COMPASS: u8 = 4;

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

impl<F, R, C, S, L> Controller<F, R, C, S, L>
where
    F: crate::driver::RangeSensor,
    R: crate::driver::RangeSensor,
    C: HeadingSensor + MagCalibrate,
    S: Servos,
    L: RowLog,
{
    // ---- the mission and the log, for the board and tests -----------------

    /// The mission's steps.
    pub fn mission(&self) -> &Mission {
        &self.mission
    }
    /// Restores a stored mission (at boot).
    pub fn set_mission(&mut self, mission: Mission) {
        self.mission = mission;
    }
    /// True once after each change of the mission (the firmware then
    /// stores it).
    pub fn take_mission_changed(&mut self) -> bool {
        core::mem::take(&mut self.mission_changed)
    }
    /// The mission under way, if any.
    pub fn mission_run(&self) -> Option<MissionRun> {
        self.run
    }
    pub fn log(&self) -> &L {
        &self.log
    }

    // ---- input ---------------------------------------------------------

    /// Any byte aborts a running mission (after its countdown: pulling
    /// the cable may make line noise).
    pub(super) fn byte_received(&mut self, sink: &mut impl LineSink) {
        if matches!(self.run, Some(MissionRun { phase: MissionPhase::Running, .. })) {
            self.abort("aborted: a byte came on the serial line", sink);
        }
    }

    /// A command during the countdown cancels the mission.
    pub(super) fn command_received(&mut self, sink: &mut impl LineSink) {
        if self.run.is_some() {
            self.abort("cancelled by a command", sink);
        }
    }

    /// Starts a `goto`, `face` or `wait` (from a command or a mission
    /// step); a refused one answers why and aborts a running mission. An
    /// estimate too uncertain to steer by is found first (`locate`), then
    /// the command starts (`may_locate` false: it is refused).
    pub(super) fn begin(&mut self, cmd: &Command, may_locate: bool, sink: &mut impl LineSink) {
        let target = match *cmd {
            Command::Goto { x_mm, y_mm } => Target::Point { x_mm, y_mm },
            Command::Face { heading } => Target::Heading(heading),
            Command::Wait { duration_ms } => {
                self.mode = Mode::Wait { timer: Timer::new(Some(duration_ms)) };
                return;
            }
            _ => return,
        };
        match check_target(target, &self.estimator.arena()).and_then(|()| self.certain_enough(1)) {
            Ok(()) => {}
            Err(Refusal::Uncertain) if may_locate => {
                self.respond(&Response::Note("estimate too uncertain to steer by: locating first"), sink);
                self.begin_locate();
                self.after_locate = Some(*cmd);
                return;
            }
            Err(why) => {
                self.mode = Mode::Idle;
                self.refuse(cmd, why.text(), sink);
                return;
            }
        }
        self.respond(&Response::Ok(cmd), sink);
        let timer = Timer::new(Some(config::goto::TIME_LIMIT_MS));
        let nav = Nav { after_fix: !may_locate, ..Nav::new(target) };
        self.mode = Mode::Goto { nav, drive: self.model.stop(), timer };
    }

    /// The estimate is good enough to steer by: not ambiguous, and within
    /// `slack` times the config's limits (1 to start, 2 on the way, as the
    /// uncertainty breathes between corrections).
    fn certain_enough(&self, slack: i32) -> Result<(), Refusal> {
        // several hypotheses, none dominating: the pose holds, no steering by it
        if self.estimator.tracking() == crate::model::estimator::Tracking::Ambiguous {
            return Err(Refusal::Uncertain);
        }
        let sigma = self.estimator.sigma();
        let heading = Angle::from_millidegrees(config::goto::MAX_SIGMA_MDEG.saturating_mul(slack));
        // a one-sigma heading is small and positive: compare the LSBs
        if !position_steerable(sigma.x, sigma.y, slack) || sigma.theta.0 > heading.0 {
            Err(Refusal::Uncertain)
        } else {
            Ok(())
        }
    }

    /// `# err <command>: <why>`.
    pub(super) fn refuse(&mut self, cmd: &Command, why: &str, sink: &mut impl LineSink) {
        self.out.clear();
        let line = push_str(&mut self.out, "# err ")
            .and_then(|()| format_command(cmd, &mut self.out))
            .and_then(|()| push_str(&mut self.out, ": "))
            .and_then(|()| push_str(&mut self.out, why));
        if line.is_ok() {
            sink.write_line(&self.out);
        }
        self.abort("stopped: a step was refused", sink);
    }

    pub(super) fn mission_op(&mut self, op: MissionOp, cmd: &Command, sink: &mut impl LineSink) {
        match op {
            MissionOp::Add(step) => {
                if self.mission.push(step).is_err() {
                    return self.respond(&Response::Fail("mission full: clear it or start it"), sink);
                }
                self.mission_changed = true;
                self.respond(&Response::Ok(cmd), sink);
            }
            MissionOp::Clear => {
                self.mission.clear();
                self.mission_changed = true;
                self.respond(&Response::Ok(cmd), sink);
            }
            MissionOp::List => {
                self.respond(&Response::Ok(cmd), sink);
                for i in 0..self.mission.len() {
                    self.write_step(i, sink);
                }
                self.out.clear();
                let line = push_str(&mut self.out, "# mission: ")
                    .and_then(|()| push_u32(&mut self.out, self.mission.len() as u32)) // <= MAX_STEPS
                    .and_then(|()| push_str(&mut self.out, " steps"));
                if line.is_ok() {
                    sink.write_line(&self.out);
                }
            }
            MissionOp::Start => {
                if self.mission.is_empty() {
                    return self.respond(&Response::Fail("mission is empty: add steps first"), sink);
                }
                self.respond(&Response::Ok(cmd), sink);
                self.mode = Mode::Idle;
                self.dump_next = None;
                self.run = Some(MissionRun { phase: MissionPhase::Countdown, since_us: None, step: 0 });
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
    fn write_step(&mut self, i: usize, sink: &mut impl LineSink) {
        let Some(step) = self.mission.get(i) else { return };
        self.out.clear();
        let line = push_str(&mut self.out, "# mission ")
            .and_then(|()| push_u32(&mut self.out, i.saturating_add(1) as u32)) // <= MAX_STEPS
            .and_then(|()| push_str(&mut self.out, ": "))
            .and_then(|()| format_command(&step.command(), &mut self.out));
        if line.is_ok() {
            sink.write_line(&self.out);
        }
    }

    pub(super) fn set_log_rate(&mut self, hz: u16) {
        self.log_hz = hz;
        self.log_period_us = telemetry_period_us(hz);
    }

    /// `dump`: a summary line and the header now, a row a tick after.
    pub(super) fn start_dump(&mut self, sink: &mut impl LineSink) {
        self.out.clear();
        let line = push_str(&mut self.out, "# log ")
            .and_then(|()| push_u32(&mut self.out, self.log.len() as u32)) // <= config::log::ROWS
            .and_then(|()| push_str(&mut self.out, " rows at "))
            .and_then(|()| push_u32(&mut self.out, u32::from(self.log_hz)))
            .and_then(|()| push_str(&mut self.out, " Hz, "))
            .and_then(|()| push_u32(&mut self.out, self.log.dropped()))
            .and_then(|()| push_str(&mut self.out, " dropped (oldest first)"));
        if line.is_ok() {
            sink.write_line(&self.out);
        }
        sink.write_line(telemetry_header());
        self.dump_next = Some(0);
    }

    /// The next rows of a dump (in place of telemetry), then `# log end`.
    pub(super) fn dump_rows(&mut self, sink: &mut impl LineSink) {
        for _ in 0..config::log::DUMP_ROWS_PER_TICK {
            let Some(i) = self.dump_next else { return };
            let Some(row) = self.log.row(i) else {
                self.dump_next = None;
                sink.write_line("# log end");
                return;
            };
            self.out.clear();
            if format_row(&row, &mut self.out).is_ok() {
                sink.write_line(&self.out);
            }
            self.dump_next = Some(i.saturating_add(1));
        }
    }

    // ---- the tick --------------------------------------------------------

    /// A mission's countdown, its time limit and its next step.
    pub(super) fn supervise(&mut self, now: Stamp, sink: &mut impl LineSink) {
        let Some(run) = self.run.as_mut() else { return };
        let since = *run.since_us.get_or_insert(now);
        let elapsed = now.wrapping_sub(since);
        match run.phase {
            MissionPhase::Countdown => {
                if elapsed >= ms_to_us(config::mission::COUNTDOWN_MS) {
                    run.phase = MissionPhase::Running;
                    run.since_us = Some(now);
                    self.log.clear();
                    self.next_log_us = now;
                    self.log_fresh = 0;
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
        let Some(step) = self.mission.get(i) else {
            self.run = None;
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

    /// One `goto`/`face` tick: plan from the estimate, or arrive.
    pub(super) fn navigate(&mut self, now: Stamp, sink: &mut impl LineSink) {
        let Mode::Goto { mut nav, timer, .. } = self.mode else { return };
        if self.certain_enough(2).is_err() {
            if nav.after_fix {
                return self.halt("estimate too uncertain on the way", now, sink);
            }
            // find the pose, then go on to the same target
            let cmd = match nav.target {
                Target::Point { x_mm, y_mm } => Command::Goto { x_mm, y_mm },
                Target::Heading(heading) => Command::Face { heading },
            };
            self.respond(&Response::Note("estimate too uncertain on the way: locating first"), sink);
            self.begin_locate();
            self.after_locate = Some(cmd);
            return;
        }
        match nav.step(&self.estimator.pose()) {
            NavStep::Arrived => {
                self.mode = Mode::Idle;
                let p = self.estimator.pose();
                self.out.clear();
                let line = push_str(&mut self.out, "# done at x_mm=")
                    .and_then(|()| push_i32(&mut self.out, p.x.to_length().to_mm()))
                    .and_then(|()| push_str(&mut self.out, " y_mm="))
                    .and_then(|()| push_i32(&mut self.out, p.y.to_length().to_mm()))
                    .and_then(|()| push_str(&mut self.out, " heading_deg="))
                    .and_then(|()| push_fixed_parts(&mut self.out, false, p.theta.to_millidegrees(), 3));
                if line.is_ok() {
                    sink.write_line(&self.out);
                }
            }
            NavStep::Drive { motion, ahead_mm } => {
                let in_the_way = match (motion, self.front_distance(now)) {
                    (Motion::Straight(v), Some(d)) => {
                        let obstacle = d.saturating_add(Length::from_mm(config::goto::OBSTACLE_MARGIN_MM));
                        v.to_bits() > 0 && obstacle < Length::from_mm(ahead_mm)
                    }
                    _ => false,
                };
                nav.obstacle_since = if in_the_way { nav.obstacle_since.or(Some(now)) } else { None };
                if let Some(since) = nav.obstacle_since {
                    if now.wrapping_sub(since) >= ms_to_us(config::goto::OBSTACLE_CONFIRM_MS) {
                        return self.halt("something in the way", now, sink);
                    }
                }
                self.mode = Mode::Goto { nav, drive: self.model.drive(motion), timer };
            }
        }
    }

    /// The front lidar's distance if it read a target lately (too close
    /// to measure is 0).
    fn front_distance(&self, now: Stamp) -> Option<Length> {
        if !self.is_fresh(Which::Front, now) {
            return None;
        }
        match self.last_front {
            Some(LidarSample { range: Range::Target(d), .. }) => Some(d),
            Some(LidarSample { range: Range::TooClose, .. }) => Some(Length::ZERO),
            _ => None,
        }
    }

    /// A forward motion: stops it near a wall (and, untethered, without a
    /// fresh front reading).
    pub(super) fn wall_stop(&mut self, now: Stamp, sink: &mut impl LineSink) {
        let untethered = self.run.is_some() || matches!(self.mode, Mode::Goto { .. });
        match self.front_distance(now) {
            Some(d) if d < Length::from_mm(config::goto::WALL_STOP_MM) => self.halt("wall ahead", now, sink),
            None if untethered && !self.is_fresh(Which::Front, now) => self.halt("front lidar silent", now, sink),
            _ => {}
        }
    }

    /// Stops with `# err stopped: <why> (front <d> mm)` and aborts a
    /// running mission.
    pub(super) fn halt(&mut self, why: &str, now: Stamp, sink: &mut impl LineSink) {
        self.mode = Mode::Idle;
        self.out.clear();
        let mut line = push_str(&mut self.out, "# err stopped: ").and_then(|()| push_str(&mut self.out, why));
        if let Some(d) = self.front_distance(now) {
            line = line
                .and_then(|()| push_str(&mut self.out, " (front "))
                .and_then(|()| push_i32(&mut self.out, d.to_mm()))
                .and_then(|()| push_str(&mut self.out, " mm)"));
        }
        if line.is_ok() {
            sink.write_line(&self.out);
        }
        self.abort("stopped: a step failed", sink);
    }

    /// Ends a mission under way (if any): the robot stops.
    fn abort(&mut self, why: &str, sink: &mut impl LineSink) {
        let Some(run) = self.run.take() else { return };
        self.mode = Mode::Idle;
        self.out.clear();
        let line = push_str(&mut self.out, "# err mission ")
            .and_then(|()| push_str(&mut self.out, why))
            .and_then(|()| push_str(&mut self.out, " (step "))
            .and_then(|()| push_u32(&mut self.out, run.step as u32)) // <= MAX_STEPS
            .and_then(|()| push_str(&mut self.out, " of "))
            .and_then(|()| push_u32(&mut self.out, self.mission.len() as u32))
            .and_then(|()| push_str(&mut self.out, ")"));
        if line.is_ok() {
            sink.write_line(&self.out);
        }
    }

    /// A row into the on-board log at its rate (while a mission runs).
    pub(super) fn log_row(&mut self, now: Stamp) {
        if !matches!(self.run, Some(MissionRun { phase: MissionPhase::Running, .. }))
            || self.log_hz == 0
            || !reached(now, self.next_log_us)
        {
            return;
        }
        self.next_log_us = self.next_log_us.wrapping_add(self.log_period_us);
        if reached(now, self.next_log_us) {
            self.next_log_us = now.wrapping_add(self.log_period_us);
        }
        let fresh = core::mem::take(&mut self.log_fresh);
        let t = self.snapshot([fresh & LOG_FRONT != 0, fresh & LOG_RIGHT != 0, fresh & LOG_COMPASS != 0]);
        self.log.push(&TelemetryRow::from(&t));
    }
}
