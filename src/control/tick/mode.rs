//! What the loop is doing: idle, driving, raw servo commands, a
//! calibration sweep, going somewhere on the estimate, waiting, or finding
//! where it is, each with its timer.

use super::clock::Timer;
use crate::control::goto::{Nav, Target};
use crate::model::compass::{CalStatus, MagCalibrator, MagCounts};
use crate::model::{Drive, Motion, ServoCmd};

/// What the loop is doing.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum Mode {
    /// Stopped: servos at neutral.
    Idle,
    /// Driving a motion through the inverse actuator model (`drive` holds
    /// the servo commands and the motion they make by the model).
    Drive { drive: Drive, timer: Timer },
    /// Raw servo commands; `motion` is what the forward model says they do.
    Servo { left: ServoCmd, right: ServoCmd, motion: Motion, timer: Timer },
    /// Turning in place while the magnetometer calibration sweep collects
    /// samples.
    Calibrate { drive: Drive, timer: Timer, sweep: Sweep },
    /// `goto` or `face`: `drive` is this tick's leg (see `control::goto`),
    /// the timer its time limit.
    Goto { nav: Nav, drive: Drive, timer: Timer },
    /// Standing still for a while (`wait`).
    Wait { timer: Timer },
    /// Finding where it is (`locate`, `control::survey`): `drive` stands
    /// or turns between views, the timer is the procedure's time limit.
    Locate { drive: Drive, timer: Timer },
}

impl Mode {
    /// The mode's word in `status`.
    pub fn word(&self) -> &'static str {
        match self {
            Mode::Idle => "idle",
            Mode::Drive { .. } => "drive",
            Mode::Servo { .. } => "servo",
            Mode::Calibrate { .. } => "cal",
            Mode::Goto { nav: Nav { target: Target::Point { .. }, .. }, .. } => "goto",
            Mode::Goto { .. } => "face",
            Mode::Wait { .. } => "wait",
            Mode::Locate { .. } => "locate",
        }
    }
    pub(super) fn timer(&self) -> Option<&Timer> {
        match self {
            Mode::Idle => None,
            Mode::Drive { timer, .. }
            | Mode::Servo { timer, .. }
            | Mode::Calibrate { timer, .. }
            | Mode::Goto { timer, .. }
            | Mode::Locate { timer, .. }
            | Mode::Wait { timer } => Some(timer),
        }
    }
    pub(super) fn timer_mut(&mut self) -> Option<&mut Timer> {
        match self {
            Mode::Idle => None,
            Mode::Drive { timer, .. }
            | Mode::Servo { timer, .. }
            | Mode::Calibrate { timer, .. }
            | Mode::Goto { timer, .. }
            | Mode::Locate { timer, .. }
            | Mode::Wait { timer } => Some(timer),
        }
    }
}

/// A calibration sweep under way (`sweep.rs`).
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub struct Sweep {
    calibrator: MagCalibrator,
    /// It has all its samples (it ends in the tick that got the last).
    done: bool,
}

impl Sweep {
    pub(super) fn new(calibrator: MagCalibrator) -> Sweep {
        Sweep { calibrator, done: false }
    }
    pub(super) fn calibrator(&self) -> &MagCalibrator {
        &self.calibrator
    }
    /// Feeds one raw compass sample.
    pub(super) fn feed(&mut self, raw: MagCounts) {
        self.done = self.calibrator.feed(raw) == CalStatus::Done;
    }
    /// True once, in the tick the sweep got its last sample.
    pub(super) fn take_done(&mut self) -> bool {
        core::mem::take(&mut self.done)
    }
}
