//! The loop's localization, the state of [`Mode::Locate`]: the survey
//! (`control::survey`) gets the readings instead of the estimator, drives
//! the body between views, and its fix starts the estimator; `# located`
//! or `# locate failed` says how it went.

use super::clock::Timer;
use super::{Controller, Hardware, LineSink, Mode};
use crate::config;
use crate::control::protocol::number::{push_fixed_parts, push_i32, push_str, push_u32};
use crate::math::{Speed, TurnRate};
use crate::model::locate::Fix;
use crate::model::measurement::LidarId;
use crate::model::Motion;

use crate::control::protocol::Command;
use crate::control::survey::{Action, Failure, Survey};

/// A localization under way (the state of [`Mode::Locate`]).
pub(super) struct Localizing {
    /// Its views so far, and what it does next.
    pub survey: Survey,
    /// The `goto` or `face` that waits for its fix.
    pub then: Option<Command>,
}

impl Localizing {
    pub const fn new() -> Localizing {
        Localizing { survey: Survey::new(), then: None }
    }

    /// As new, in place (no second survey on the stack,
    /// [`Survey::restart`]); what waited for the fix, handed back.
    fn restart(&mut self) -> Option<Command> {
        self.survey.restart();
        self.then.take()
    }
}

impl<H: Hardware> Controller<H> {
    /// The power-up localization ([`config::locate::AT_POWER_UP`]): `locate` as if
    /// typed (`# ok locate`). The firmware and the simulator call it once
    /// the sensors are up, with the loop started at the arena's centre
    /// ([`crate::model::measurement::Arena::centre`]).
    pub fn power_up(&mut self, sink: &mut impl LineSink) {
        self.handle(Command::Locate, sink);
    }

    /// Whether localizations refine the search's fix with every reading of
    /// their surveys ([`crate::model::locate::refine`]; the default
    /// [`config::refine::ENABLED`]).
    pub fn set_refine(&mut self, on: bool) {
        self.localizing.survey.set_refine(on);
    }

    /// Starts the procedure (`locate`, `reset`, and at power-up): the
    /// robot stands for its first view.
    pub(super) fn begin_locate(&mut self) {
        self.localizing.restart();
        // the search reads the ranges as the estimator has learned to
        self.localizing.survey.set_spot_share(self.estimator.lidar_spot().0);
        self.mode = Mode::Locate { drive: self.model.stop(), timer: look_timer() };
    }

    /// While locating, this tick's readings go to the procedure's view
    /// (the estimator starts afresh from its fix).
    pub(super) fn take_view_readings(&mut self) {
        let p = &mut self.localizing.survey;
        if let Some(d) = self.front.pending.take() {
            p.lidar(LidarId::Front, d);
        }
        if let Some(d) = self.right.pending.take() {
            p.lidar(LidarId::Right, d);
        }
        if let Some(h) = self.compass.pending.take() {
            p.heading(h);
        }
    }

    /// One tick of the procedure: stand, turn, or its answer.
    pub(super) fn locate_tick(&mut self, sink: &mut impl LineSink) {
        let motion = match self.localizing.survey.tick(&self.estimator.arena()) {
            Action::Done(result) => return self.end_locate(result, sink),
            Action::LookAgain => {
                if let Mode::Locate { timer, .. } = &mut self.mode {
                    *timer = look_timer();
                }
                sink.write_line("# looking again from elsewhere: a poor fit");
                Motion::Stop
            }
            Action::Stand => Motion::Stop,
            Action::Turn { clockwise } => {
                let rate = TurnRate::from_mrad_s(config::locate::TURN_MRAD_S);
                Motion::Turn(if clockwise { rate } else { rate.neg() })
            }
            Action::Drive { forward } => {
                let speed = Speed::from_mm_s(config::locate::POSITION_MM_S);
                Motion::Straight(if forward { speed } else { speed.neg() })
            }
        };
        if let Mode::Locate { drive, .. } = &mut self.mode {
            if drive.motion != motion {
                *drive = self.model.drive(motion);
            }
        }
    }

    /// Ends the procedure: a fix starts the estimator there, with its
    /// uncertainty, and a `goto` or `face` that waited for it starts; a
    /// failure leaves the pose with the config's initial uncertainty
    /// (unknown until `pose` or `locate`) and refuses what waited. The
    /// robot stands.
    pub(super) fn end_locate(&mut self, result: Result<Fix, Failure>, sink: &mut impl LineSink) {
        if matches!(self.mode, Mode::Locate { .. }) {
            self.mode = Mode::Idle;
        }
        let views = self.localizing.survey.views().len();
        let then = self.localizing.restart();
        match result {
            Ok(fix) => {
                self.estimator.start_at(&fix);
                #[cfg(feature = "std")]
                {
                    self.dead = fix.pose;
                }
                self.report_fix(&fix, views, sink);
                if let Some(cmd) = then {
                    self.begin(&cmd, false, sink);
                }
            }
            Err(why) => {
                self.estimator.lose_place(self.estimator.pose());
                self.out.clear();
                let line = push_str(&mut self.out, "# locate failed: ")
                    .and_then(|()| push_str(&mut self.out, why.text()))
                    .and_then(|()| push_str(&mut self.out, "; the pose is unknown until `pose` or `locate`"));
                if line.is_ok() {
                    sink.write_line(&self.out);
                }
                if let Some(cmd) = then {
                    self.refuse(&cmd, why.text(), sink);
                }
            }
        }
    }

    /// `# located x y heading sigma sx sy views n [ambiguous|uncertain]`:
    /// mm, degrees.
    pub(super) fn report_fix(&mut self, fix: &Fix, views: usize, sink: &mut impl LineSink) {
        let mm = |l: crate::math::Length| l.0 >> 16;
        let o = &mut self.out;
        o.clear();
        let line = push_str(o, "# located ")
            .and_then(|()| push_i32(o, mm(fix.pose.x.to_length())))
            .and_then(|()| push_str(o, " "))
            .and_then(|()| push_i32(o, mm(fix.pose.y.to_length())))
            .and_then(|()| push_str(o, " "))
            .and_then(|()| push_fixed_parts(o, false, fix.pose.theta.to_millidegrees(), 3))
            .and_then(|()| push_str(o, " sigma "))
            .and_then(|()| push_i32(o, mm(fix.sigma_x)))
            .and_then(|()| push_str(o, " "))
            .and_then(|()| push_i32(o, mm(fix.sigma_y)))
            .and_then(|()| push_str(o, " mm, views "))
            .and_then(|()| push_u32(o, views as u32))
            .and_then(|()| push_str(o, flag_text(fix)));
        if line.is_ok() {
            sink.write_line(o);
        }
    }
}

/// What the `# located` line says of a fix the readings do not settle.
fn flag_text(fix: &Fix) -> &'static str {
    if fix.ambiguous {
        ", ambiguous: more than one place fits"
    } else if fix.untrusted {
        ", uncertain: the compass is disturbed here or the readings fit poorly"
    } else {
        ""
    }
}

/// A look's time limit ([`config::locate::TIME_LIMIT_MS`]): the
/// procedure's, begun again by a second look.
fn look_timer() -> Timer {
    Timer::new(Some(config::locate::TIME_LIMIT_MS))
}
