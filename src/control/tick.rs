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
//! the magnetometer samples feed a [`MagCalibrator`]; it stops when it has
//! its samples (the new calibration is applied and printed as the config
//! line to paste) or after [`config::compass::CALIBRATION_MS_PER_SAMPLE`]
//! per sample. Any valid command refreshes the deadman (and ends a sweep);
//! a malformed line gets one `# err` line and changes nothing.
//!
//! Untethered (`untethered.rs`): `goto` and `face` drive on the estimate
//! (`control::goto`); a mission (`control::mission`) runs its steps after
//! a countdown, with its own time limit instead of the deadman, and any
//! byte received while it runs aborts it; during a mission telemetry rows
//! also go into the on-board log (`control::log`), which `dump` sends. The
//! wall stop: a forward motion, whatever started it, stops when the front
//! lidar sees something nearer than [`config::goto::WALL_STOP_MM`].
//!
//! Localization (`locating.rs`): `locate`, `reset` and the power-up run
//! `control::localize`; while it runs, the readings go to its views instead
//! of the estimator, it turns the body between views, and its fix starts
//! the estimator. The calibration sweep is in `sweep.rs`.
//!
//! No allocation, no panics: every buffer is a bounded `heapless` one, every
//! clock difference is wrapping or saturating, every index is checked.

mod clock;
mod locating;
mod mode;
mod sensor;
mod sweep;
mod untethered;
mod views;

use crate::config;
use clock::{ms_to_us, reached, Stamp, Timer, OVERRUN_US};
use sensor::{CompassSlot, LidarSlot, SensorSlot};

use crate::control::protocol::{
    format_response, format_status, format_telemetry, telemetry_header, Command, FaultCounters, LineBuffer, OutLine,
    ParseError, Response, Side, Telemetry, HELP, MAX_OUT_LINE,
};
use crate::driver::{HeadingSensor, RangeSensor, Servos};
use crate::math::{div_u64, Dt};
use crate::model::estimator::{Estimator, Update};
use crate::model::measurement::{Arena, LidarId};
use crate::model::{advance, ActuatorModel, Drive, Motion, Pose};
pub use clock::TICK_US;
pub use mode::Mode;
pub use sensor::SensorHealth;
pub use untethered::{MissionPhase, MissionRun};

pub use crate::control::hardware::Hardware;
use crate::control::localize::{Failure, Procedure};
use crate::control::mission::Mission;

/// Where the loop writes its output lines (without terminators): the UART
/// on the robot, a `Vec<String>` in tests, a channel in the simulator.
pub trait LineSink {
    fn write_line(&mut self, line: &str);
}

/// The control loop over the robot's [`Hardware`] (see the module docs).
/// [`Controller::new`] starts with a new log (`RingLog<0>` keeps none:
/// every row is dropped and counted); [`Controller::with_log`] takes one.
#[repr(C)]
pub struct Controller<H: Hardware> {
    // tick bar: declared order (repr(C)), small and hot fields first: the
    // lx106's loads and stores take an offset of at most 255 bytes for a
    // u8, 510 for a u16 and 1020 for a u32, and a field further out costs
    // an address computation at every access. The drivers and the line
    // buffers go last.
    /// A valid command arrived since the last tick.
    command_seen: bool,
    header_due: bool,
    /// The lidar corrected last, so the two take turns.
    front_went_last: bool,
    /// A sensor was re-initialised in this tick (the others wait a tick).
    reinit_ran: bool,
    /// Loop clock, us since the first tick.
    clock_us: u64,
    /// The `now_us` of the previous tick (`None` before the first).
    last_now_us: Option<u32>,
    /// When the last valid command was seen.
    last_command_us: Stamp,
    mode: Mode,
    /// Servo commands and motion applied at the last tick.
    applied: Drive,
    /// The pose estimate (state update corrected by the sensors).
    estimator: Estimator,
    /// Dead-reckoned pose (the state update alone).
    dead: Pose,
    telemetry_hz: u16,
    /// <= 1 s
    telemetry_period_us: u32,
    next_telemetry_us: Stamp,
    faults: FaultCounters,
    ticks: u64,
    /// The running mission, if any.
    run: Option<MissionRun>,
    /// The on-board log's rate (0 = off) and schedule.
    log_hz: u16,
    log_period_us: u32,
    next_log_us: Stamp,
    /// The next log row `dump` sends (while it is sending).
    dump_next: Option<usize>,
    /// The mission changed since [`Controller::take_mission_changed`].
    mission_changed: bool,
    front: LidarSlot<H::Front>,
    right: LidarSlot<H::Right>,
    compass: CompassSlot<H::Compass>,
    servos: H::Servos,
    /// The actuator model with the run-time trims.
    model: ActuatorModel,
    input: LineBuffer,
    out: OutLine<MAX_OUT_LINE>,
    // tick bar: the mission, the localization procedure and the log are
    // large and off the tick's path: last
    mission: Mission,
    /// The localization procedure (its state while in [`Mode::Locate`]).
    locating: Procedure,
    /// The `goto` or `face` that waits for the localization's fix.
    after_locate: Option<Command>,
    log: H::Log,
}

impl<H: Hardware> Controller<H>
where
    H::Log: Default,
{
    /// A loop over sensors the caller has brought up (a sensor that fails
    /// later is re-initialised by the loop), starting at `pose` in the
    /// config's arena, stopped, with a new log.
    pub fn new(front: H::Front, right: H::Right, compass: H::Compass, servos: H::Servos, pose: Pose) -> Self {
        Self::new_in(front, right, compass, servos, pose, Arena::DEFAULT)
    }

    /// [`Controller::new`] in another arena (the simulator's).
    pub fn new_in(
        front: H::Front,
        right: H::Right,
        compass: H::Compass,
        servos: H::Servos,
        pose: Pose,
        arena: Arena,
    ) -> Self {
        Controller::with_log(front, right, compass, servos, pose, arena, H::Log::default())
    }
}

impl<H: Hardware> Controller<H> {
    /// [`Controller::new_in`] with an on-board log (the firmware's is a
    /// static, in the DRAM budget).
    pub fn with_log(
        front: H::Front,
        right: H::Right,
        compass: H::Compass,
        servos: H::Servos,
        pose: Pose,
        arena: Arena,
        log: H::Log,
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
            clock_us: 0,
            last_now_us: None,
            command_seen: false,
            last_command_us: 0,
            mode: Mode::Idle,
            applied: model.stop(),
            estimator: Estimator::with_arena(pose, arena),
            dead: pose,
            // the config's rate, as `set_rate` would set it: the first row
            // (after the header) at the first tick
            telemetry_hz: INITIAL_HZ,
            telemetry_period_us: INITIAL_PERIOD_US,
            next_telemetry_us: 0,
            header_due: INITIAL_HZ != 0,
            front_went_last: false,
            faults: FaultCounters::default(),
            ticks: 0,
            reinit_ran: false,
            run: None,
            log_hz: config::log::HZ,
            log_period_us: telemetry_period_us(config::log::HZ),
            next_log_us: 0,
            dump_next: None,
            mission_changed: false,
            mission: Mission::new(),
            locating: Procedure::new(),
            after_locate: None,
            log,
        }
    }

    // ---- inputs ------------------------------------------------------

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
        // a command ends a sweep or a localization (it runs instead)
        if !matches!(cmd, Command::Status | Command::Help | Command::Rate { .. }) {
            match self.mode {
                Mode::Calibrate { .. } => self.end_calibration(None, sink),
                Mode::Locate { .. } => self.end_locate(Err(Failure::Interrupted), sink),
                _ => {}
            }
        }
        // a motion, a goto or face (which may be refused) and a mission
        // start answer for themselves
        if !matches!(cmd, Command::Drive { .. } | Command::Goto { .. } | Command::Face { .. } | Command::Mission(_)) {
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
        }
    }

    /// Sets the estimate (and the dead-reckoned pose) to `pose`.
    fn set_pose(&mut self, pose: Pose) {
        self.estimator.reset(pose);
        self.dead = pose;
    }

    fn respond(&mut self, r: &Response, sink: &mut impl LineSink) {
        self.out.clear();
        if format_response(r, &mut self.out).is_ok() {
            sink.write_line(&self.out);
        }
    }

    fn set_rate(&mut self, hz: u16) {
        let was_off = self.telemetry_hz == 0;
        self.telemetry_hz = hz;
        // hz = 0 (off) gives period 0
        // <= 1_000_000: fits
        self.telemetry_period_us = telemetry_period_us(hz);
        // the first row at the next tick (after the header if telemetry was off)
        self.next_telemetry_us = self.clock_us as Stamp;
        if hz != 0 && was_off {
            self.header_due = true;
        }
    }

    // ---- the tick ----------------------------------------------------

    /// Runs one loop iteration at `now_us` (a free-running microsecond
    /// counter that may wrap; call it every [`TICK_US`]).
    // tick bar: in a frame of its own, its field accesses take short offsets
    #[inline(never)]
    pub fn tick(&mut self, now_us: u32, sink: &mut impl LineSink) {
        // 1. time
        let dt_us = match self.last_now_us {
            None => 0,
            Some(last) => now_us.wrapping_sub(last),
        };
        self.last_now_us = Some(now_us);
        self.clock_us = self.clock_us.saturating_add(u64::from(dt_us));
        self.ticks = self.ticks.saturating_add(1);
        if dt_us > OVERRUN_US {
            self.faults.overruns = self.faults.overruns.saturating_add(1);
        }
        let now = self.clock_us as Stamp; // the low 32 bits
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

        // 6. telemetry (and in a mission the on-board log)
        self.telemetry(now, sink);
        if self.run.is_some() {
            self.log_row(now);
        }
    }

    /// Integrates `motion` over `dt_us` in steps of at most [`Dt::MAX`]
    /// (a late tick of up to a second is integrated in full; beyond that
    /// the robot has stopped by the deadman anyway).
    fn advance(&mut self, motion: Motion, dt_us: u32) {
        const MAX_STEPS: u32 = 16; // 16 * 65.5 ms > 1 s
        let mut left = dt_us;
        let mut n = 0;
        while left > 0 && n < MAX_STEPS {
            let dt = Dt::from_micros_saturating(left);
            self.estimator.predict(motion, dt);
            advance(&mut self.dead, motion, dt); // in place: no copy of the pose
            left = left.saturating_sub(dt.as_micros()); // dt <= left
            n = n.saturating_add(1); // n < MAX_STEPS
        }
    }

    fn sense(&mut self, now: Stamp) {
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
    fn correct_one(&mut self) -> bool {
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

    fn count_update(&mut self, u: Update) {
        if u == Update::Outlier {
            self.faults.rejected_outliers = self.faults.rejected_outliers.saturating_add(1);
        }
    }

    fn decide(&mut self, now: Stamp, sink: &mut impl LineSink) {
        if let Mode::Calibrate { sweep, .. } = &mut self.mode {
            if sweep.take_done() {
                self.finish_sweep(sink);
                return;
            }
        }
        if let Some(timer) = self.mode.timer().copied() {
            self.timeout(timer, now, sink);
        }
        // tick bar: the untethered checks cost a few compares when no
        // mission, goto or forward motion runs
        if self.run.is_some() {
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
    fn timeout(&mut self, timer: Timer, now: Stamp, sink: &mut impl LineSink) {
        match timer.remaining_us(now) {
            Some(0) if matches!(self.mode, Mode::Calibrate { .. }) => {
                self.finish_sweep(sink);
            }
            Some(0) if matches!(self.mode, Mode::Goto { .. }) => {
                self.halt("did not get there in time", now, sink);
            }
            Some(0) if matches!(self.mode, Mode::Locate { .. }) => {
                self.end_locate(Err(Failure::OutOfTime), sink);
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
    fn current_drive(&self) -> Drive {
        match self.mode {
            Mode::Idle | Mode::Wait { .. } => self.model.stop(),
            Mode::Drive { drive, .. }
            | Mode::Calibrate { drive, .. }
            | Mode::Goto { drive, .. }
            | Mode::Locate { drive, .. } => drive,
            Mode::Servo { left, right, motion, .. } => Drive { left, right, motion, saturated: false },
        }
    }

    fn telemetry(&mut self, now: Stamp, sink: &mut impl LineSink) {
        if self.dump_next.is_some() {
            // the log's rows go out instead (telemetry would mix with them)
            return self.dump_rows(sink);
        }
        if self.telemetry_hz == 0 || !reached(now, self.next_telemetry_us) {
            return;
        }
        if core::mem::take(&mut self.header_due) {
            sink.write_line(telemetry_header());
        }
        // keep the schedule; after a stall, start again from now
        self.next_telemetry_us = self.next_telemetry_us.wrapping_add(self.telemetry_period_us);
        if reached(now, self.next_telemetry_us) {
            self.next_telemetry_us = now.wrapping_add(self.telemetry_period_us);
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
}

impl<H: Hardware> Controller<H> {
    /// A telemetry row's values now, with the readings flagged fresh
    /// (front, right, compass).
    fn snapshot(&self, [front, right, compass]: [bool; 3]) -> Telemetry {
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
        }
    }
}

const _: () = assert!(config::timing::TELEMETRY_HZ <= config::serial::MAX_TELEMETRY_HZ as u32);
/// The telemetry rate a new loop starts at (`config::timing::TELEMETRY_HZ`,
/// asserted above to fit the protocol's range) and its period, us (0 = off,
/// as [`Controller::set_rate`] gives).
const INITIAL_HZ: u16 = config::timing::TELEMETRY_HZ as u16;
const INITIAL_PERIOD_US: u32 = telemetry_period_us(INITIAL_HZ);

/// The period of a telemetry rate, us: 0 for 0 Hz (off), else at most 1 s
/// (fits). [`div_u64`] stays a call: a division the compiler sees as 32-bit
/// would link compiler_builtins' `__udivsi3`, which the ROM file leaves out.
const fn telemetry_period_us(hz: u16) -> u32 {
    match div_u64(1_000_000, hz as u64) {
        Some(q) => q as u32,
        None => 0,
    }
}
