//! The control loop: one [`Controller::tick`] per loop period
//! ([`config::timing::LOOP_HZ`]).
//!
//! Each tick, in this order:
//! 1. time: the elapsed time since the previous tick (`now_us` is a free-running,
//!    wrapping microsecond counter; the loop keeps its own 64-bit clock, and
//!    its deadlines on that clock's low 32 bits, see `Stamp`);
//! 2. state update: the estimator predicts with the motion the servos were
//!    driving since the previous tick (the fixed-point [`crate::model::step`]
//!    plus its uncertainty); a dead-reckoned pose (`step` alone) is kept
//!    beside it for comparison;
//! 3. sensing: each sensor is polled once, never waited for; a fresh reading
//!    corrects the estimator (an outlier is counted in the telemetry's
//!    `f_outliers`); a failed sensor is counted, marked down and
//!    re-initialised after [`config::timing::SENSOR_RETRY_MS`] (a bus
//!    error, or a NACK of a chip that was working, takes it down only after
//!    [`config::timing::SENSOR_MAX_BUS_ERRORS`] in a row; at most one
//!    re-initialisation per tick, as each blocks the loop for its waits and
//!    its ~110 (lidar) or 13 (compass) transactions);
//! 4. deciding: a timed command that has run out, or the deadman
//!    ([`config::timing::DEADMAN_MS`] without a command), stops the robot;
//! 5. acting: the servo commands of the current mode go to the servos
//!    (computed once per command by the inverse actuator model, so the tick
//!    does no division);
//! 6. telemetry, at its own rate.
//!
//! Command bytes arrive between ticks through [`Controller::feed`]; every
//! output line (telemetry, responses) goes to a [`LineSink`]. The loop owns
//! no hardware type: it runs the same on the robot, in tests and in the
//! simulator (`sim::robot`).
//!
//! Deadman: an untimed `fwd`/`back`/`cw`/`ccw`/`servo` runs until the next
//! command or until no valid command came for `DEADMAN_MS`. A timed one runs
//! for its duration (at most `config::serial::MAX_DURATION_MS`) and is its
//! own deadman. A calibration sweep (`cal`) turns in place clockwise while
//! the magnetometer samples feed a [`MagCalibrator`](crate::model::compass::MagCalibrator); it stops when it has
//! its samples (the new calibration is applied and printed as the config
//! line to paste) or after [`config::compass::CALIBRATION_MS_PER_SAMPLE`]
//! per sample. Any valid command refreshes the deadman (and ends a sweep);
//! a malformed line gets one `# err` line and changes nothing.
//!
//! Untethered: `goto` and `face` drive on the estimate (`navigate.rs`,
//! planned by `control::goto`); a mission (`mission_run.rs`, steps from
//! `control::mission`) runs its steps after a countdown, with its own time
//! limit instead of the deadman, and any byte received while it runs
//! aborts it; during a mission telemetry rows also go into the on-board
//! log (`report.rs`, `control::log`), which `dump` sends. The wall stop: a
//! forward motion, whatever started it, stops when the front lidar sees
//! something nearer than [`config::goto::WALL_STOP_MM`].
//!
//! Localization (`localizing.rs`): `locate`, `reset` and the power-up run
//! a `control::survey`; while it runs, the readings go to its views instead
//! of the estimator, it turns the body between views, and its fix starts
//! the estimator. The calibration sweep is in `sweep.rs`; the settings in
//! flash (restored at boot, `save`, `settings`, `forget`) in `settings.rs`,
//! over the [`Hardware`]'s `Settings` store (`control::settings`).
//!
//! The parts: the [`Hardware`] the loop drives; a `SensorSlot` per sensor
//! (`sensor.rs`: driver, health, newest sample, waiting reading); the
//! [`Mode`] with the state of the mode that runs (`mode.rs`: a goto's
//! `Nav`, a sweep's `Sweep`; the localization's `Localizing` beside it);
//! `Missions` (the mission runner) and `Reports` (telemetry and log
//! schedules). Commands come in through `commands.rs`; `readout.rs` has
//! the accessors and `status`.
//!
//! No allocation, no panics: every buffer is a bounded `heapless` one, every
//! clock difference is wrapping or saturating, every index is checked.

mod clock;
mod commands;
mod localizing;
mod mission_run;
mod mode;
mod navigate;
mod readout;
mod report;
mod sensor;
mod settings;
mod sweep;

use crate::config;
use clock::{ms_to_us, LoopClock, Stamp, Timer, OVERRUN_US};
use sensor::{CompassSlot, LidarSlot, SensorSlot};

use crate::control::protocol::{FaultCounters, LineBuffer, OutLine, Response, MAX_OUT_LINE};
use crate::driver::{HeadingSensor, RangeSensor, Servos};
use crate::math::Dt;
use crate::model::estimator::{Estimator, Update};
use crate::model::measurement::{Arena, LidarId};
use crate::model::{ActuatorModel, Drive, Motion, Pose};
pub use clock::TICK_US;
use localizing::Localizing;
use mission_run::Missions;
pub use mission_run::{MissionPhase, MissionRun};
pub use mode::{Mode, Sweep};
use report::Reports;
pub use sensor::SensorHealth;
pub use settings::{Source, Sources};

pub use crate::control::hardware::Hardware;

/// Where the loop writes its output lines (without terminators): the UART
/// on the robot, a `Vec<String>` in tests, a channel in the simulator.
pub trait LineSink {
    fn write_line(&mut self, line: &str);
}

/// The control loop over the robot's [`Hardware`] (see the module docs).
/// [`Controller::new`] starts with a new log (`RingLog<0>` keeps none:
/// every row is dropped and counted); [`Controller::with_log`] takes one.
pub struct Controller<H: Hardware> {
    /// A valid command arrived since the last tick.
    command_seen: bool,
    /// The lidar corrected last, so the two take turns.
    front_went_last: bool,
    /// A sensor was re-initialised in this tick (the others wait a tick).
    reinit_ran: bool,
    clock: LoopClock,
    /// When the last valid command was seen.
    last_command_us: Stamp,
    mode: Mode,
    /// Servo commands and motion applied at the last tick.
    applied: Drive,
    /// The pose estimate (state update corrected by the sensors).
    estimator: Estimator,
    /// Dead-reckoned pose (the state update alone): a host instrument
    /// (the simulator's summary and tests compare the estimate with it);
    /// nothing on the robot reads it, so the robot's tick does not keep it
    /// (156 lx106 instructions a tick, lx106/BENCHMARKS.md).
    #[cfg(feature = "std")]
    dead: Pose,
    faults: FaultCounters,
    /// Telemetry, the on-board log's rows and `dump`: when they are due.
    reports: Reports,
    front: LidarSlot<H::Front>,
    right: LidarSlot<H::Right>,
    compass: CompassSlot<H::Compass>,
    servos: H::Servos,
    /// The actuator model with the run-time trims.
    model: ActuatorModel,
    input: LineBuffer,
    out: OutLine<MAX_OUT_LINE>,
    /// The mission and its run.
    missions: Missions,
    /// The localization (the state of [`Mode::Locate`]).
    localizing: Localizing,
    log: H::Log,
    /// The settings in flash, and where each value in use comes from.
    settings: H::Settings,
    sources: Sources,
}

impl<H: Hardware> Controller<H>
where
    H::Log: Default,
    H::Settings: Default,
{
    /// A loop over sensors the caller has brought up (a sensor that fails
    /// later is re-initialised by the loop), starting at `pose` in the
    /// config's arena, stopped, with a new log and settings store (the
    /// config's values in use: [`Controller::restore_settings`] reads it).
    pub fn new(front: H::Front, right: H::Right, compass: H::Compass, servos: H::Servos, pose: Pose) -> Self {
        let log = H::Log::default();
        Controller::with_log(front, right, compass, servos, pose, Arena::DEFAULT, log, H::Settings::default())
    }
}

impl<H: Hardware> Controller<H> {
    /// A loop in `arena` (the simulator's may differ from the config's)
    /// with an on-board log (the firmware's is a static, in the DRAM
    /// budget) and a settings store (the config's values are in use until
    /// [`Controller::restore_settings`]).
    #[allow(clippy::too_many_arguments)] // one per part the loop owns
    pub fn with_log(
        front: H::Front,
        right: H::Right,
        compass: H::Compass,
        servos: H::Servos,
        pose: Pose,
        arena: Arena,
        log: H::Log,
        settings: H::Settings,
    ) -> Self {
        let model = config::actuators::MODEL;
        Controller {
            front: SensorSlot::new(front),
            right: SensorSlot::new(right),
            compass: SensorSlot::new(compass),
            servos,
            model,
            input: LineBuffer::new(),
            out: OutLine::new(),
            clock: LoopClock::default(),
            command_seen: false,
            last_command_us: 0,
            mode: Mode::Idle,
            applied: model.stop(),
            estimator: Estimator::with_arena(pose, arena),
            #[cfg(feature = "std")]
            dead: pose,
            reports: Reports::new(),
            front_went_last: false,
            faults: FaultCounters::default(),
            reinit_ran: false,
            missions: Missions::new(),
            localizing: Localizing::new(),
            log,
            settings,
            sources: Sources::CONFIG,
        }
    }

    // ---- the tick ----------------------------------------------------

    /// Runs one loop iteration at `now_us` (a free-running microsecond
    /// counter that may wrap; call it every [`TICK_US`]).
    // flash: out of line; inlined into the firmware's loop it makes the
    // image's code much larger (`cargo fw-image`'s flash figure)
    #[inline(never)]
    pub fn tick(&mut self, now_us: u32, sink: &mut impl LineSink) {
        // 1. time
        let dt_us = self.clock.tick(now_us);
        if dt_us > OVERRUN_US {
            self.faults.overruns = self.faults.overruns.saturating_add(1);
        }
        let now = self.clock.now();
        if core::mem::take(&mut self.command_seen) {
            self.last_command_us = now;
        }

        // 2. state update with what the servos drove since the last tick
        self.advance(self.applied.motion, dt_us);

        // 3. sensing, then at most MAX_CORRECTIONS_PER_TICK corrections
        // (while locating, the readings go to the views instead)
        self.sense(now);
        if matches!(self.mode, Mode::Locate { .. }) {
            self.take_view_readings();
        } else {
            for _ in 0..config::timing::MAX_CORRECTIONS_PER_TICK {
                if !self.correct_one() {
                    break;
                }
            }
        }

        // 4. deciding
        self.decide(now, sink);

        // 5. acting
        self.applied = self.current_drive();
        self.servos.set(self.applied.left, self.applied.right);
        if let Some(t) = self.mode.timer_mut() {
            if t.started_us.is_none() {
                t.started_us = Some(now);
            }
        }

        // 6. telemetry (and in a mission the on-board log; after it, the
        // log kept in flash once the robot stands)
        self.telemetry(now, sink);
        if self.missions.run.is_some() {
            self.log_row(now);
        }
        if self.missions.log_unkept {
            self.keep_log(sink);
        }
    }

    /// Integrates `motion` over `dt_us` in steps of at most [`Dt::MAX`]
    /// (a late tick of up to a second is integrated in full; beyond that
    /// the robot has stopped by the deadman anyway).
    pub(super) fn advance(&mut self, motion: Motion, dt_us: u32) {
        const MAX_STEPS: u32 = 16; // 16 * 65.5 ms > 1 s
        let mut left = dt_us;
        let mut n = 0;
        while left > 0 && n < MAX_STEPS {
            let dt = Dt::from_micros_saturating(left);
            self.estimator.predict(motion, dt);
            #[cfg(feature = "std")]
            crate::model::advance(&mut self.dead, motion, dt); // in place: no copy of the pose
            left = left.saturating_sub(dt.as_micros()); // dt <= left
            n = n.saturating_add(1); // n < MAX_STEPS
        }
    }

    pub(super) fn sense(&mut self, now: Stamp) {
        self.reinit_ran = false;
        let (ran, faults) = (&mut self.reinit_ran, &mut self.faults);
        if self.front.ready(now, ran, faults, RangeSensor::reinit) {
            let polled = self.front.driver.poll();
            self.front.polled(polled, now, faults);
        }
        if self.right.ready(now, ran, faults, RangeSensor::reinit) {
            let polled = self.right.driver.poll();
            self.right.polled(polled, now, faults);
        }
        if self.compass.ready(now, ran, faults, HeadingSensor::reinit) {
            let polled = self.compass.driver.poll();
            if let (Some(s), Mode::Calibrate { sweep, .. }) = (self.compass.polled(polled, now, faults), &mut self.mode)
            {
                sweep.feed(s.raw);
            }
        }
    }

    /// Applies one waiting reading to the estimator: a lidar first (the two
    /// take turns), else the compass. False when nothing waits.
    pub(super) fn correct_one(&mut self) -> bool {
        let front_first = !self.front_went_last || self.right.pending.is_none();
        let lidar = if front_first && self.front.pending.is_some() {
            self.front.pending.take().map(|d| (LidarId::Front, d))
        } else {
            self.right.pending.take().map(|d| (LidarId::Right, d))
        };
        let u = if let Some((id, d)) = lidar {
            self.front_went_last = id == LidarId::Front;
            self.estimator.update_lidar(id, d)
        } else if let Some(h) = self.compass.pending.take() {
            self.estimator.update_heading(h)
        } else {
            return false;
        };
        self.count_update(u);
        true
    }

    pub(super) fn count_update(&mut self, u: Update) {
        if u == Update::Outlier {
            self.faults.rejected_outliers = self.faults.rejected_outliers.saturating_add(1);
        }
    }

    pub(super) fn decide(&mut self, now: Stamp, sink: &mut impl LineSink) {
        if let Mode::Calibrate { sweep, .. } = &mut self.mode {
            if sweep.take_done() {
                self.finish_sweep(sink);
                return;
            }
        }
        if let Some(timer) = self.mode.timer().copied() {
            self.timeout(timer, now, sink);
        }
        // a mission supervises the modes its steps start
        if self.missions.run.is_some() {
            self.supervise(now, sink);
        }
        match self.mode {
            Mode::Goto { .. } => self.navigate(now, sink),
            Mode::Locate { .. } => self.locate_tick(sink),
            _ => {}
        }
        match self.mode {
            Mode::Drive { drive: Drive { motion: Motion::Straight(v), .. }, .. }
            | Mode::Goto { drive: Drive { motion: Motion::Straight(v), .. }, .. }
            | Mode::Servo { motion: Motion::Straight(v), .. }
                if v.to_bits() > 0 =>
            {
                self.wall_stop(now, sink)
            }
            _ => {}
        }
    }

    /// A mode's timer: its end, or the deadman for an untimed one.
    pub(super) fn timeout(&mut self, timer: Timer, now: Stamp, sink: &mut impl LineSink) {
        match timer.remaining_us(now) {
            Some(0) if matches!(self.mode, Mode::Calibrate { .. }) => {
                self.finish_sweep(sink);
            }
            Some(0) if matches!(self.mode, Mode::Goto { .. }) => {
                self.halt("did not get there in time", now, sink);
            }
            Some(0) if matches!(self.mode, Mode::Locate { .. }) => {
                let result = self.localizing.survey.out_of_time();
                self.end_locate(result, sink);
            }
            Some(0) => {
                self.mode = Mode::Idle;
                self.respond(&Response::Note("done"), sink);
            }
            Some(_) => {}
            None => {
                if now.wrapping_sub(self.last_command_us) >= ms_to_us(config::timing::DEADMAN_MS) {
                    self.mode = Mode::Idle;
                    self.respond(&Response::Note("deadman: no command, stopped"), sink);
                }
            }
        }
    }

    /// The servo commands and motion of the current mode.
    pub(super) fn current_drive(&self) -> Drive {
        match self.mode {
            Mode::Idle | Mode::Wait { .. } => self.model.stop(),
            Mode::Drive { drive, .. }
            | Mode::Calibrate { drive, .. }
            | Mode::Goto { drive, .. }
            | Mode::Locate { drive, .. } => drive,
            Mode::Servo { left, right, motion, .. } => Drive { left, right, motion, saturated: false },
        }
    }
}
