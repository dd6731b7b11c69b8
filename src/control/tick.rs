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
//! No allocation, no panics: every buffer is a bounded `heapless` one, every
//! clock difference is wrapping or saturating, every index is checked.

use crate::config;
use crate::control::protocol::number::{div_rem_1000, push_str, put_template, TextOut};
use crate::control::protocol::Overflow;
use crate::control::protocol::{
    format_response, format_status, format_telemetry, telemetry_header, Command, FaultCounters, LineBuffer, OutLine,
    ParseError, Response, Side, Status, Telemetry, HELP, MAX_OUT_LINE,
};
use crate::driver::calibration::{CalStatus, CalibrationError, MagCalibrator};
use crate::driver::{CompassSample, HeadingSensor, LidarSample, MagCalibrate, SensorError, Servos};
use crate::math::{div_u64, Angle, Coord, Dt, Length, TurnRate};
use crate::model::compass::MagCalibration;
use crate::model::estimator::{Estimator, Update};
use crate::model::measurement::{Arena, LidarId};
use crate::model::{advance, ActuatorModel, Drive, Motion, Pose, Range, ServoCmd};

/// Where the loop writes its output lines (without terminators): the UART
/// on the robot, a `Vec<String>` in tests, a channel in the simulator.
pub trait LineSink {
    fn write_line(&mut self, line: &str);
}

/// Loop period, us.
pub const TICK_US: u32 = 1_000_000 / config::timing::LOOP_HZ;
/// A tick later than this after the previous one counts as an overrun, us.
const OVERRUN_US: u32 = TICK_US + TICK_US / 2;
const _: () = assert!(config::timing::LOOP_HZ >= 1 && config::timing::LOOP_HZ <= 1_000);

/// A moment on the loop clock, us: its low 32 bits, which wrap every 71.6
/// minutes. Timestamps and deadlines are compared by their wrapping
/// difference ([`reached`], `now.wrapping_sub(since)`), which is right for
/// any two moments less than [`MAX_SPAN_US`] apart: every span the loop
/// keeps is far shorter (asserted below), and every stored moment is
/// renewed or done with well within it (a deadline is checked every tick).
/// On the lx106 a 64-bit compare or saturating add is several instructions
/// and a 64-bit field two loads and stores, for each of the loop's
/// deadlines; the 64-bit clock itself stays for `t_ms` and
/// [`Controller::clock_us`].
type Stamp = u32;

/// Longest span between two [`Stamp`]s that compare correctly, us (35.8 min).
const MAX_SPAN_US: u32 = i32::MAX as u32;
/// [`MAX_SPAN_US`] in whole ms.
const MAX_SPAN_MS: u32 = MAX_SPAN_US / 1_000;

/// ms to us, at most [`MAX_SPAN_US`].
const fn ms_to_us(ms: u32) -> u32 {
    if ms > MAX_SPAN_MS {
        MAX_SPAN_US
    } else {
        ms.wrapping_mul(1_000) // <= MAX_SPAN_US
    }
}

/// `now` is at or past `deadline` (the two less than [`MAX_SPAN_US`] apart).
fn reached(now: Stamp, deadline: Stamp) -> bool {
    now.wrapping_sub(deadline) <= MAX_SPAN_US
}

// Every span the loop keeps, ms, well under MAX_SPAN_MS: a timed command, a
// calibration sweep of any u16 sample count, the deadman, the sensor
// timings; a telemetry period is at most 1 s.
const _: () = {
    use config::{compass, serial, timing};
    assert!(serial::MAX_DURATION_MS <= MAX_SPAN_MS);
    assert!((u16::MAX as u64) * (compass::CALIBRATION_MS_PER_SAMPLE as u64) <= MAX_SPAN_MS as u64);
    assert!(timing::DEADMAN_MS <= MAX_SPAN_MS);
    assert!(timing::SENSOR_RETRY_MS <= MAX_SPAN_MS && timing::SENSOR_SILENT_MS <= MAX_SPAN_MS);
};

/// One sensor's health.
#[derive(Clone, Copy, PartialEq, Eq, Debug, Default)]
pub struct SensorHealth {
    /// False while the sensor is failed and waiting to be re-initialised.
    pub up: bool,
    /// The last error seen (cleared by nothing: for `status`).
    pub last_error: Option<SensorError>,
    /// Successful re-initialisations since boot.
    pub reinits: u32,
    /// Bus errors in a row (a single glitch does not take a sensor down).
    consecutive_bus_errors: u8,
    /// When a failed sensor is tried again.
    retry_at_us: Stamp,
    /// When the sensor last delivered.
    last_sample_us: Stamp,
}

impl SensorHealth {
    fn new() -> SensorHealth {
        SensorHealth { up: true, ..SensorHealth::default() }
    }
}

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
    /// Turning in place while the magnetometer calibration collects samples.
    Calibrate { drive: Drive, timer: Timer },
}

impl Mode {
    /// The mode's word in `status`.
    pub fn word(&self) -> &'static str {
        match self {
            Mode::Idle => "idle",
            Mode::Drive { .. } => "drive",
            Mode::Servo { .. } => "servo",
            Mode::Calibrate { .. } => "cal",
        }
    }
    fn timer(&self) -> Option<&Timer> {
        match self {
            Mode::Idle => None,
            Mode::Drive { timer, .. } | Mode::Servo { timer, .. } | Mode::Calibrate { timer, .. } => Some(timer),
        }
    }
    #[inline(never)]
    fn timer_mut(&mut self) -> Option<&mut Timer> {
        match self {
            Mode::Idle => None,
            Mode::Drive { timer, .. } | Mode::Servo { timer, .. } | Mode::Calibrate { timer, .. } => Some(timer),
        }
    }
}

/// How long a mode runs: for `duration_us` from the first tick that drives
/// it (so a command runs for its whole duration whenever it arrives between
/// ticks), or, without a duration, until the deadman. A duration is at most
/// `MAX_SPAN_US`, 35.8 min (a longer one, only possible through [`Controller::handle`]
/// with a hand-made command, runs for that long).
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub struct Timer {
    duration_us: Option<u32>,
    started_us: Option<Stamp>,
}

impl Timer {
    fn new(duration_ms: Option<u32>) -> Timer {
        Timer { duration_us: duration_ms.map(ms_to_us), started_us: None }
    }
    /// Time left at `now`, us (`None` for an untimed mode).
    fn remaining_us(&self, now: Stamp) -> Option<u32> {
        let d = self.duration_us?;
        Some(match self.started_us {
            None => d,
            Some(s) => d.saturating_sub(now.wrapping_sub(s)),
        })
    }
}

/// The control loop, generic over the drivers (see the module docs).
#[repr(C)]
pub struct Controller<F, R, C, S> {
    // Declared order (repr(C)), small and hot fields first: the lx106's
    // loads and stores take an offset of at most 255 bytes for a u8, 510
    // for a u16 and 1020 for a u32, and a field further out costs an
    // address computation at every access. The drivers and the line
    // buffers go last. (-188 B of code and -21 instructions per tick.)
    /// A valid command arrived since the last tick.
    command_seen: bool,
    header_due: bool,
    /// A reading came since the last telemetry row (it is in `last_*`).
    fresh_front: bool,
    fresh_right: bool,
    fresh_compass: bool,
    /// The lidar corrected last, so the two take turns.
    front_went_last: bool,
    /// The sweep has all its samples (finished in the same tick).
    calibration_done: bool,
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
    /// Readings waiting for their estimator correction (see
    /// `config::timing::MAX_CORRECTIONS_PER_TICK`).
    pending_front: Option<Length>,
    pending_right: Option<Length>,
    pending_heading: Option<Angle>,
    /// Newest readings (for the estimator and tests).
    last_front: Option<LidarSample>,
    last_right: Option<LidarSample>,
    last_compass: Option<CompassSample>,
    health_front: SensorHealth,
    health_right: SensorHealth,
    health_compass: SensorHealth,
    faults: FaultCounters,
    ticks: u64,
    /// The running magnetometer calibration sweep (in [`Mode::Calibrate`]).
    calibrator: Option<MagCalibrator>,
    front: F,
    right: R,
    compass: C,
    servos: S,
    /// The actuator model with the run-time trims.
    model: ActuatorModel,
    input: LineBuffer,
    out: OutLine<MAX_OUT_LINE>,
}

/// Which sensor (for the shared fault handling).
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
enum Which {
    Front,
    Right,
    Compass,
}

impl<F, R, C, S> Controller<F, R, C, S>
where
    F: crate::driver::RangeSensor,
    R: crate::driver::RangeSensor,
    C: HeadingSensor + MagCalibrate,
    S: Servos,
{
    /// A loop over sensors the caller has brought up (a sensor that fails
    /// later is re-initialised by the loop), starting at `pose` in the
    /// config's arena, stopped.
    pub fn new(front: F, right: R, compass: C, servos: S, pose: Pose) -> Self {
        Self::new_in(front, right, compass, servos, pose, Arena::DEFAULT)
    }

    /// [`Controller::new`] in another arena (the simulator's).
    pub fn new_in(front: F, right: R, compass: C, servos: S, pose: Pose, arena: Arena) -> Self {
        let model = config::actuators::MODEL;
        Controller {
            front,
            right,
            compass,
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
            fresh_front: false,
            fresh_right: false,
            fresh_compass: false,
            pending_front: None,
            pending_right: None,
            pending_heading: None,
            front_went_last: false,
            last_front: None,
            last_right: None,
            last_compass: None,
            health_front: SensorHealth::new(),
            health_right: SensorHealth::new(),
            health_compass: SensorHealth::new(),
            faults: FaultCounters::default(),
            ticks: 0,
            calibrator: None,
            calibration_done: false,
            reinit_ran: false,
        }
    }

    // ---- inputs ------------------------------------------------------

    /// Takes one received serial byte; a finished line is parsed and
    /// handled at once (its answer goes to `sink`).
    // Out of line, as `tick` and `handle`: the firmware's main loop calls
    // each once, and inlined into its frame every field access paid a long
    // stack offset (BENCHMARKS.md, "Fourth pass").
    #[inline(never)]
    pub fn feed(&mut self, byte: u8, sink: &mut impl LineSink) {
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
    #[inline(never)]
    pub fn handle(&mut self, cmd: Command, sink: &mut impl LineSink) {
        self.command_seen = true;
        if matches!(self.mode, Mode::Calibrate { .. })
            && !matches!(cmd, Command::Status | Command::Help | Command::Rate { .. })
        {
            self.end_calibration(None, sink);
        }
        if !matches!(cmd, Command::Drive { .. }) {
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
            Command::SetPose { x_mm, y_mm, heading } => {
                let pose = Pose::new(
                    Coord::from_length(Length::from_mm(x_mm)),
                    Coord::from_length(Length::from_mm(y_mm)),
                    heading,
                );
                self.estimator.reset(pose);
                self.dead = pose;
            }
            Command::Calibrate { samples } => {
                let calibrator = MagCalibrator::new(
                    self.compass.asa(),
                    config::compass::AXES,
                    samples,
                    config::compass::CALIBRATION_MIN_SECTORS,
                    config::compass::CALIBRATION_MIN_RADIUS,
                );
                self.calibrator = Some(calibrator);
                let turn = Motion::Turn(TurnRate::from_mrad_s(config::compass::CALIBRATION_TURN_MRAD_S));
                // max_samples <= u16::MAX: the product fits in u32 (asserted at MAX_SPAN_MS)
                let limit_ms = u32::from(calibrator.max_samples()) * config::compass::CALIBRATION_MS_PER_SAMPLE;
                self.mode = Mode::Calibrate { drive: self.model.drive(turn), timer: Timer::new(Some(limit_ms)) };
            }
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
        }
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
        self.sense(now);
        for _ in 0..config::timing::MAX_CORRECTIONS_PER_TICK {
            if !self.correct_one() {
                break;
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

        // 6. telemetry
        self.telemetry(now, sink);
    }

    /// Integrates `motion` over `dt_us` in steps of at most [`Dt::MAX`]
    /// (a late tick of up to a second is integrated in full; beyond that
    /// the robot has stopped by the deadman anyway).
    #[inline(never)]
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
        // Each sample is stored once, where it is kept (`last_*`; `fresh_*`
        // flag it for the next row): at opt-level "z" a copy of a
        // `CompassSample` is a `memcpy` call.
        if self.ready(Which::Front, now) {
            let polled = self.front.poll();
            self.lidar_polled(Which::Front, polled, now);
        }
        if self.ready(Which::Right, now) {
            let polled = self.right.poll();
            self.lidar_polled(Which::Right, polled, now);
        }
        if self.ready(Which::Compass, now) {
            match self.compass.poll() {
                Ok(s) => {
                    self.sampled(Which::Compass, now);
                    self.fresh_compass = true;
                    self.pending_heading = Some(s.heading);
                    if let Some(cal) = self.calibrator.as_mut() {
                        self.calibration_done = cal.feed(s.raw) == CalStatus::Done;
                    }
                    // the field member by member: at opt-level "z" a copy of
                    // the 12-byte `MagField` is a `memcpy` call (~80
                    // instructions on the lx106; BENCHMARKS.md, "Fifth pass")
                    let f = s.field;
                    let kept = self.last_compass.insert(CompassSample {
                        raw: s.raw,
                        field: Default::default(),
                        heading: s.heading,
                    });
                    kept.field.x = f.x;
                    kept.field.y = f.y;
                    kept.field.z = f.z;
                }
                Err(e) => self.missed(Which::Compass, e, now),
            }
        }
    }

    /// Applies one waiting reading to the estimator: a lidar first (the two
    /// take turns), else the compass. False when nothing waits.
    fn correct_one(&mut self) -> bool {
        let front_first = !self.front_went_last || self.pending_right.is_none();
        let lidar = if front_first && self.pending_front.is_some() {
            self.pending_front.take().map(|d| (LidarId::Front, d))
        } else {
            self.pending_right.take().map(|d| (LidarId::Right, d))
        };
        let u = if let Some((id, d)) = lidar {
            self.front_went_last = id == LidarId::Front;
            self.estimator.update_lidar(id, d)
        } else if let Some(h) = self.pending_heading.take() {
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

    /// True when a sensor is up, to be polled. A sensor that is down is
    /// re-initialised when its back-off is over and no other sensor was
    /// re-initialised in this tick (a bring-up blocks the loop, so one per
    /// tick keeps a tick's cost to one bring-up); it is polled from the
    /// next tick on.
    fn ready(&mut self, which: Which, now: Stamp) -> bool {
        let health = self.health(which);
        if health.up {
            return true;
        }
        if !reached(now, health.retry_at_us) || self.reinit_ran {
            return false;
        }
        self.reinit_ran = true;
        let result = match which {
            Which::Front => self.front.reinit(),
            Which::Right => self.right.reinit(),
            Which::Compass => self.compass.reinit(),
        };
        match result {
            Ok(()) => {
                let h = self.health_mut(which);
                h.up = true;
                h.reinits = h.reinits.saturating_add(1);
                h.consecutive_bus_errors = 0;
                h.last_sample_us = now;
            }
            Err(e) => self.fail(which, e, now),
        }
        false
    }

    /// Keeps what a lidar's poll gave (`which` is `Front` or `Right`).
    /// Inlined: a call costs the tick bar ~100 instructions at opt-level "z".
    #[inline(always)]
    fn lidar_polled(&mut self, which: Which, polled: nb::Result<LidarSample, SensorError>, now: Stamp) {
        let s = match polled {
            Ok(s) => s,
            Err(e) => return self.missed(which, e, now),
        };
        self.sampled(which, now);
        let (fresh, last, pending) = if which == Which::Front {
            (&mut self.fresh_front, &mut self.last_front, &mut self.pending_front)
        } else {
            (&mut self.fresh_right, &mut self.last_right, &mut self.pending_right)
        };
        *fresh = true;
        *last = Some(s);
        if let Range::Target(d) = s.range {
            *pending = Some(d);
        }
    }

    /// A sensor delivered a sample at `now`.
    fn sampled(&mut self, which: Which, now: Stamp) {
        let h = self.health_mut(which);
        h.last_sample_us = now;
        h.consecutive_bus_errors = 0;
    }

    /// A poll gave no sample: nothing new yet (a timeout once the sensor
    /// has been silent too long), or an error.
    fn missed(&mut self, which: Which, e: nb::Error<SensorError>, now: Stamp) {
        match e {
            nb::Error::WouldBlock => {
                let silent = now.wrapping_sub(self.health(which).last_sample_us);
                if silent >= ms_to_us(config::timing::SENSOR_SILENT_MS) {
                    self.fail(which, SensorError::Timeout, now);
                }
            }
            nb::Error::Other(e) => self.fail(which, e, now),
        }
    }

    /// Counts a fault; takes the sensor down unless it was a dropped sample
    /// or one of too few bus errors in a row. A NACK of its address
    /// (`Missing`) from a sensor that is up, i.e. while polling a chip that
    /// was working, counts like a bus error: on a noisy bus a corrupted
    /// address byte is NACKed too, and a chip that is really gone is found
    /// after `SENSOR_MAX_BUS_ERRORS` polls (30 ms) anyway. At a
    /// re-initialisation a NACK means what it says: the sensor stays down.
    fn fail(&mut self, which: Which, e: SensorError, now: Stamp) {
        let f = &mut self.faults;
        let counter = match e {
            SensorError::Bus => &mut f.bus,
            SensorError::Timeout => &mut f.timeout,
            SensorError::Missing | SensorError::NotReady => &mut f.missing,
            SensorError::BadSample => &mut f.bad_sample,
        };
        *counter = counter.saturating_add(1);
        let h = self.health_mut(which);
        h.last_error = Some(e);
        let down = match e {
            SensorError::BadSample => false,
            SensorError::Bus | SensorError::Missing if h.up => {
                h.consecutive_bus_errors = h.consecutive_bus_errors.saturating_add(1);
                h.consecutive_bus_errors >= config::timing::SENSOR_MAX_BUS_ERRORS
            }
            _ => true,
        };
        if down || !h.up {
            h.up = false;
            h.retry_at_us = now.wrapping_add(ms_to_us(config::timing::SENSOR_RETRY_MS));
        }
    }

    fn health(&self, which: Which) -> &SensorHealth {
        match which {
            Which::Front => &self.health_front,
            Which::Right => &self.health_right,
            Which::Compass => &self.health_compass,
        }
    }
    fn health_mut(&mut self, which: Which) -> &mut SensorHealth {
        match which {
            Which::Front => &mut self.health_front,
            Which::Right => &mut self.health_right,
            Which::Compass => &mut self.health_compass,
        }
    }

    fn decide(&mut self, now: Stamp, sink: &mut impl LineSink) {
        if core::mem::take(&mut self.calibration_done) {
            self.finish_sweep(sink);
            return;
        }
        let Some(timer) = self.mode.timer().copied() else { return };
        match timer.remaining_us(now) {
            Some(0) if matches!(self.mode, Mode::Calibrate { .. }) => {
                self.finish_sweep(sink);
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

    /// Ends the running sweep with its result (its samples are in, or its
    /// time is up).
    #[inline(always)]
    fn finish_sweep(&mut self, sink: &mut impl LineSink) {
        let result = self.calibrator.as_ref().map(MagCalibrator::result);
        self.end_calibration(result, sink);
    }

    /// Ends a calibration sweep: applies and prints a good result, reports
    /// a bad one (`None`: abandoned for another command). The robot stops.
    fn end_calibration(&mut self, result: Option<Result<MagCalibration, CalibrationError>>, sink: &mut impl LineSink) {
        let (samples, sectors) = self.calibrator.map(|c| (c.samples(), c.sectors())).unwrap_or((0, 0));
        self.calibrator = None;
        self.calibration_done = false;
        if matches!(self.mode, Mode::Calibrate { .. }) {
            self.mode = Mode::Idle;
        }
        if let Some(Ok(cal)) = result {
            self.compass.set_calibration(cal);
        }
        // Integer formatting (no core::fmt on the robot), straight into the
        // output line: every text here is printable ASCII, as `Response::Note`
        // and `Fail` would leave it. A line that does not fit is cut short,
        // which MAX_OUT_LINE makes impossible here.
        self.out.clear();
        if calibration_report(&mut self.out, result, samples, sectors).is_ok() {
            sink.write_line(&self.out);
        }
        if let Some(Ok(cal)) = result {
            self.out.clear();
            if push_str(&mut self.out, "# ").and_then(|()| push_config_line(&mut self.out, &cal)).is_ok() {
                sink.write_line(&self.out);
            }
        }
    }

    /// The servo commands and motion of the current mode.
    // (out of line, as `Mode::timer_mut`: one copy is 176 B less code than
    // the inlined ones, at no cost to the bar's tick)
    #[inline(never)]
    fn current_drive(&self) -> Drive {
        match self.mode {
            Mode::Idle => self.model.stop(),
            Mode::Drive { drive, .. } | Mode::Calibrate { drive, .. } => drive,
            Mode::Servo { left, right, motion, .. } => Drive { left, right, motion, saturated: false },
        }
    }

    fn telemetry(&mut self, now: Stamp, sink: &mut impl LineSink) {
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
        let t = Telemetry {
            t_ms: self.t_ms(),
            pose: self.estimator.pose(),
            front: self.last_front.filter(|_| core::mem::take(&mut self.fresh_front)),
            right: self.last_right.filter(|_| core::mem::take(&mut self.fresh_right)),
            compass: self.last_compass.filter(|_| core::mem::take(&mut self.fresh_compass)),
            motion: self.applied.motion,
            left_cmd: self.applied.left,
            right_cmd: self.applied.right,
            faults: self.faults,
        };
        self.out.clear();
        if format_telemetry(&t, &mut self.out).is_ok() {
            sink.write_line(&self.out);
        }
    }

    // ---- views -------------------------------------------------------

    /// Loop clock in ms (wraps after 49 days: the truncation is intended).
    pub fn t_ms(&self) -> u32 {
        whole_ms(self.clock_us)
    }
    /// Loop clock, us since the first tick.
    pub fn clock_us(&self) -> u64 {
        self.clock_us
    }
    /// The pose the telemetry reports: the estimator's.
    pub fn pose(&self) -> Pose {
        self.estimator.pose()
    }
    /// The dead-reckoned pose (the state update alone, from the last `pose`).
    pub fn dead_reckoned(&self) -> Pose {
        self.dead
    }
    pub fn estimator(&self) -> &Estimator {
        &self.estimator
    }
    pub fn mode(&self) -> Mode {
        self.mode
    }
    /// The servo commands and motion set at the last tick.
    pub fn applied(&self) -> Drive {
        self.applied
    }
    pub fn model(&self) -> &ActuatorModel {
        &self.model
    }
    pub fn faults(&self) -> FaultCounters {
        self.faults
    }
    pub fn telemetry_hz(&self) -> u16 {
        self.telemetry_hz
    }
    pub fn ticks(&self) -> u64 {
        self.ticks
    }
    pub fn front_health(&self) -> SensorHealth {
        self.health_front
    }
    pub fn right_health(&self) -> SensorHealth {
        self.health_right
    }
    pub fn compass_health(&self) -> SensorHealth {
        self.health_compass
    }
    pub fn last_front(&self) -> Option<LidarSample> {
        self.last_front
    }
    pub fn last_right(&self) -> Option<LidarSample> {
        self.last_right
    }
    pub fn last_compass(&self) -> Option<CompassSample> {
        self.last_compass
    }
    /// The drivers, e.g. for a simulator that reads the servo commands or
    /// sets a fake chip's truth.
    pub fn front(&mut self) -> &mut F {
        &mut self.front
    }
    pub fn right(&mut self) -> &mut R {
        &mut self.right
    }
    pub fn compass(&mut self) -> &mut C {
        &mut self.compass
    }
    pub fn servos(&mut self) -> &mut S {
        &mut self.servos
    }

    /// What `status` reports.
    pub fn status(&self) -> Status {
        let now = self.clock_us as Stamp;
        let remaining_ms = self.mode.timer().and_then(|t| t.remaining_us(now)).map(|us| div_rem_1000(us).0);
        Status {
            t_ms: self.t_ms(),
            mode: self.mode.word(),
            motion: self.applied.motion,
            remaining_ms,
            pose: self.estimator.pose(),
            left_cmd: self.applied.left,
            right_cmd: self.applied.right,
            left_trim: self.model.left_trim,
            right_trim: self.model.right_trim,
            rate_hz: self.telemetry_hz,
            front_ok: self.health_front.up,
            right_ok: self.health_right.up,
            compass_ok: self.health_compass.up,
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

/// `(us / 1000) as u32` (mod 2^32) without a 64-bit division (a ~430
/// instruction call on the lx106): with `us = hi 2^32 + lo`, `lo = 1000 q +
/// r` and `2^32 = 1000 * 4_294_967 + 296`, `us / 1000 = 4_294_967 hi + q +
/// (296 hi + r) / 1000`.
fn whole_ms(us: u64) -> u32 {
    const HI_MAX: u32 = (u32::MAX - 999) / 296; // const-evaluated: 296 hi + r fits
    let hi = (us >> 32) as u32; // < 2^32
    let (q, r) = div_rem_1000(us as u32); // the low 32 bits
    if hi == 0 {
        return q; // the first 71 minutes
    }
    if hi > HI_MAX {
        return div_u64(us, 1_000).map_or(0, |q| q as u32); // after 1,900 years
    }
    let (q2, _) = div_rem_1000(hi.wrapping_mul(296).wrapping_add(r)); // no wrap: hi <= HI_MAX
    hi.wrapping_mul(4_294_967).wrapping_add(q).wrapping_add(q2) // mod 2^32, as the cast
}

/// `|q16| * 10^6 / 2^16` rounded half up, saturating at `u32::MAX`, in 32
/// bits: `10^6 / 2^16 = 15625 / 2^10`, and with `a = h 2^10 + l` that is
/// `15625 h + ((15625 l + 2^9) >> 10)` (`15625 l + 2^9 < 2^24`).
fn q16_to_micro(a: u32) -> u32 {
    const H_MAX: u32 = u32::MAX / 15_625; // const-evaluated
    let (h, l) = (a >> 10, a & 0x3FF);
    if h > H_MAX {
        return u32::MAX;
    }
    // h <= H_MAX: 15625 h fits
    h.wrapping_mul(15_625).saturating_add(l.wrapping_mul(15_625).wrapping_add(1 << 9) >> 10)
}

// The report names z as the axis kept from the config.
const _: () = assert!(crate::driver::calibration::VERTICAL == 2);

/// The answer line to a calibration sweep's end: `# ...` for a result (or
/// an abandoned sweep), `# err ...` (the protocol's `ERR`) for a failure.
/// Each literal carries its prefix: one string per line is 92 bytes less
/// flash than a separate prefix; `tests/control.rs` pins four of the five.
fn calibration_report(
    t: &mut dyn TextOut,
    result: Option<Result<MagCalibration, CalibrationError>>,
    samples: u16,
    sectors: u8,
) -> Result<(), Overflow> {
    let samples = u32::from(samples);
    match result {
        None => put_template(t, "# calibration abandoned after %0 samples", &[samples], &[]),
        Some(Ok(_)) => put_template(
            t,
            "# calibration ok: %0 samples, %0 of 12 sectors; x and y measured, z kept from config; applied. For config::compass:",
            &[samples, u32::from(sectors)],
            &[],
        ),
        Some(Err(CalibrationError::NotEnoughSamples { have, need })) => {
            put_template(t, "# err calibration timed out: %0 of %0 samples", &[u32::from(have), u32::from(need)], &[])
        }
        Some(Err(CalibrationError::SweepIncomplete { sectors, need })) => put_template(
            t,
            "# err calibration failed: the turn covered %0 of 12 sectors, need %0",
            &[u32::from(sectors), u32::from(need)],
            &[],
        ),
        Some(Err(CalibrationError::Degenerate { axis })) => {
            put_template(t, "# err calibration failed: magnetometer axis %0 never changed", &[u32::from(axis)], &[])
        }
    }
}

/// The `CALIBRATION` line of `config::compass` for `cal`, ready to paste
/// (the same text as `driver::calibration::ConfigLine`, written without
/// `core::fmt`): biases as integers, scales with six decimals.
fn push_config_line(out: &mut dyn TextOut, cal: &MagCalibration) -> Result<(), Overflow> {
    let [b0, b1, b2] = cal.bias;
    // q16 * 10^6 / 2^16 rounded half away from zero (as math::div_round):
    // the sign as text, as a magnitude may pass i32::MAX (and |q16| >= 1
    // gives at least 15 millionths: no "-0")
    let [m0, m1, m2] = cal.scale_q16.map(|q16| q16_to_micro(q16.unsigned_abs()));
    let [n0, n1, n2] = cal.scale_q16.map(|q16| if q16 < 0 { "-" } else { "" });
    put_template(
        out,
        "pub const CALIBRATION: MagCalibration = MagCalibration::from_f64([%a.0, %a.0, %a.0], [%s%6, %s%6, %s%6]);",
        &[b0 as u32, b1 as u32, b2 as u32, m0, m1, m2],
        &[n0, n1, n2],
    )
}

#[cfg(test)]
mod tests {
    use super::{q16_to_micro, whole_ms};

    #[test]
    fn whole_ms_is_the_truncated_quotient() {
        let check = |us: u64| {
            assert_eq!(whole_ms(us), (us / 1000) as u32, "{us}");
        };
        let big = (u64::from(u32::MAX) + 1) * 1000; // the first us whose quotient does not fit u32
        for us in [0, 1, 999, 1000, u64::from(u32::MAX), 1 << 32, big - 1, big, u64::MAX, u64::MAX - 1] {
            check(us);
        }
        // around HI_MAX = (2^32 - 1000) / 296 = 14_510_021 and both ends of lo
        for hi in [1u64, 2, 295, 296, 1000, 14_510_020, 14_510_021, 14_510_022, u64::from(u32::MAX)] {
            for lo in [0u64, 1, 703, 704, 999, 1000, 123_456_789, u64::from(u32::MAX) - 1, u64::from(u32::MAX)] {
                check(hi << 32 | lo);
            }
        }
        let mut x: u64 = 0x9E37_79B9_7F4A_7C15;
        for _ in 0..200_000 {
            // xorshift64, shifted to cover every magnitude
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            check(x >> (x % 64));
        }
    }

    #[test]
    fn q16_to_micro_rounds_half_up_and_saturates() {
        let mut a: u32 = 0;
        loop {
            let want = ((u64::from(a) * 1_000_000 + (1 << 15)) >> 16).min(u64::from(u32::MAX)) as u32;
            assert_eq!(q16_to_micro(a), want, "{a}");
            match a.checked_add(a / 1024 + 1) {
                Some(n) => a = n,
                None => break,
            }
        }
        for a in (0..1 << 20).chain([u32::MAX, u32::MAX - 1, 1 << 31, 274_877, 274_878, 281_474_976]) {
            let want = ((u64::from(a) * 1_000_000 + (1 << 15)) >> 16).min(u64::from(u32::MAX)) as u32;
            assert_eq!(q16_to_micro(a), want, "{a}");
        }
    }
}
