//! `goto` and `face` on the estimate (the plan is `control::goto`'s), the
//! wall stop, and the stop with its reason.

use super::clock::{ms_to_us, Stamp, Timer};
use super::{Controller, Hardware, LineSink, Mode};
use crate::config;
use crate::control::goto::{check_target, heading_steerable, position_steerable, Nav, NavStep, Refusal, Target};
use crate::control::protocol::number::{push_fixed_parts, push_i32, push_str};
use crate::control::protocol::{format_command, Command, Response};
use crate::math::Length;
use crate::model::estimator::Tracking;
use crate::model::Motion;

/// [`config::goto::SETTLE_MS`] in loop ticks.
const SETTLE_TICKS: u32 = config::goto::SETTLE_MS * config::timing::LOOP_HZ / 1000;

impl<H: Hardware> Controller<H> {
    /// Starts a `goto`, `face` or `wait` (from a command or a mission
    /// step); a refused one answers why and aborts a running mission. On an
    /// estimate too uncertain to steer by a `goto` or `face` first stands
    /// while standing may settle it (`unsettled`), else it finds the pose
    /// (`locate`), then starts (`may_locate` false: it is refused).
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
        let answered = match check_target(target, &self.estimator.arena()).and_then(|()| self.certain_enough(1)) {
            Ok(()) => true,
            Err(Refusal::Uncertain) if self.settles_standing(1) => false,
            Err(Refusal::Uncertain) if may_locate => {
                self.respond(&Response::Note("estimate too uncertain to steer by: locating first"), sink);
                self.locate_then(*cmd);
                return;
            }
            Err(why) => {
                self.mode = Mode::Idle;
                self.refuse(cmd, why.text(), sink);
                return;
            }
        };
        if answered {
            self.respond(&Response::Ok(cmd), sink);
        }
        let timer = Timer::new(Some(config::goto::TIME_LIMIT_MS));
        let nav = Nav { after_fix: !may_locate, answered, ..Nav::new(target) };
        self.mode = Mode::Goto { nav, drive: self.model.stop(), timer };
    }

    /// Localizes, then begins `cmd`.
    fn locate_then(&mut self, cmd: Command) {
        self.begin_locate();
        self.localizing.then = Some(cmd);
    }

    /// The estimate is good enough to steer by: not ambiguous, and within
    /// `slack` times the config's limits (1 to start, 2 on the way, as the
    /// uncertainty breathes between corrections).
    pub(super) fn certain_enough(&self, slack: i32) -> Result<(), Refusal> {
        // several hypotheses, none dominating: the pose holds, no steering by it
        if self.estimator.tracking() == Tracking::Ambiguous {
            return Err(Refusal::Uncertain);
        }
        let sigma = self.estimator.sigma();
        if !position_steerable(sigma.x, sigma.y, slack) || !heading_steerable(sigma.theta, slack) {
            Err(Refusal::Uncertain)
        } else {
            Ok(())
        }
    }

    /// What is too uncertain to steer by may settle while the robot
    /// stands: hypotheses that compete (the sensors weigh them) or a
    /// position too uncertain (the lidars shrink it), not a heading (the
    /// compass's bias hides it while the robot stands) nor an unknown pose.
    fn settles_standing(&self, slack: i32) -> bool {
        let sigma = self.estimator.sigma();
        self.estimator.contested()
            || (self.estimator.tracking() != Tracking::Unknown
                && !position_steerable(sigma.x, sigma.y, slack)
                && heading_steerable(sigma.theta, slack))
    }

    /// `# err <command>: <why>`.
    pub(super) fn refuse(&mut self, cmd: &Command, why: &str, sink: &mut impl LineSink) {
        self.say_refused(cmd, why, sink);
        self.abort("stopped: a step was refused", sink);
    }

    /// `# err <cmd>: <why>`.
    pub(super) fn say_refused(&mut self, cmd: &Command, why: &str, sink: &mut impl LineSink) {
        self.out.clear();
        let line = push_str(&mut self.out, "# err ")
            .and_then(|()| format_command(cmd, &mut self.out))
            .and_then(|()| push_str(&mut self.out, ": "))
            .and_then(|()| push_str(&mut self.out, why));
        if line.is_ok() {
            sink.write_line(&self.out);
        }
    }

    /// One `goto`/`face` tick: plan from the estimate, or arrive.
    pub(super) fn navigate(&mut self, now: Stamp, sink: &mut impl LineSink) {
        let Mode::Goto { mut nav, timer, .. } = self.mode else { return };
        if self.certain_enough(nav.slack()).is_err() {
            return self.unsettled(nav, timer, now, sink);
        }
        nav.settling = 0;
        if !nav.answered {
            nav.answered = true;
            let cmd = command_of(nav.target);
            self.respond(&Response::Ok(&cmd), sink);
        }
        // turns pivot where the estimator learned, or config says until then
        let centre = self.estimator.learned_turn_centre().unwrap_or(config::goto::TURN_CENTRE_BEHIND_REFERENCE);
        match nav.step(&self.estimator.pose(), centre, &self.estimator.arena()) {
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

    /// A `goto` or `face` on an estimate too uncertain to steer by: while
    /// standing may settle it (`settles_standing`) it stands, for at most
    /// [`config::goto::SETTLE_MS`]; then (or at once) it finds the pose and
    /// goes on to the same target. One that started from a fix is stopped
    /// (refused if it had not started) instead of localizing again.
    fn unsettled(&mut self, mut nav: Nav, timer: Timer, now: Stamp, sink: &mut impl LineSink) {
        if u32::from(nav.settling) < SETTLE_TICKS && self.settles_standing(nav.slack()) {
            nav.settling = nav.settling.saturating_add(1);
            self.mode = Mode::Goto { nav, drive: self.model.stop(), timer };
            return;
        }
        let cmd = command_of(nav.target);
        match (nav.after_fix, nav.answered) {
            (true, true) => self.halt("estimate too uncertain on the way", now, sink),
            (true, false) => {
                self.mode = Mode::Idle;
                self.refuse(&cmd, Refusal::Uncertain.text(), sink);
            }
            (false, answered) => {
                let note = if answered {
                    "estimate too uncertain on the way: locating first"
                } else {
                    "estimate too uncertain to steer by: locating first"
                };
                self.respond(&Response::Note(note), sink);
                self.locate_then(cmd);
            }
        }
    }

    /// The front lidar's distance if it read a target lately (too close
    /// to measure is 0).
    pub(super) fn front_distance(&self, now: Stamp) -> Option<Length> {
        self.front.distance(now)
    }

    /// A forward motion: stops it near a wall (and, untethered, without a
    /// fresh front reading).
    pub(super) fn wall_stop(&mut self, now: Stamp, sink: &mut impl LineSink) {
        let untethered = self.missions.run.is_some() || matches!(self.mode, Mode::Goto { .. });
        match self.front_distance(now) {
            Some(d) if d < Length::from_mm(config::goto::WALL_STOP_MM) => self.halt("wall ahead", now, sink),
            None if untethered && !self.front.is_fresh(now) => self.halt("front lidar silent", now, sink),
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
}

/// The command that set `target`.
fn command_of(target: Target) -> Command {
    match target {
        Target::Point { x_mm, y_mm } => Command::Goto { x_mm, y_mm },
        Target::Heading(heading) => Command::Face { heading },
    }
}
