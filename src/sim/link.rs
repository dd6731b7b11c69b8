//! The simulated robot behind the emulated board's pins: what the board
//! (emu/esp8266_link.h, `cargo fw-emu --sim`) talks to over its socket.
//!
//! The board sends events stamped with QEMU's virtual clock, in order: the
//! levels the chip drives on its pins (SCL/SDA, XSHUT, servo pulses), each
//! byte UART0 sent, and sync requests, which are answered with what the
//! outside world does at that instant (a slave pulling SDA low, bytes for
//! UART0 RX). [`EmulatedRobot::handle`] first brings the world up to the
//! event's time, so the answers depend on virtual time alone and a run is
//! the same run every time.
//!
//! The world is the host simulator's ([`super::robot`]): the same arena,
//! fake chips, noise and body, stepped every loop period of virtual time
//! (the chips' truth set, then the body moved by what the servos did over
//! the period). What differs is the way in: the chips answer the real
//! image's bit-banged I2C through [`Wire`], each lidar's XSHUT is a pin, and
//! the wheels turn by the pulse widths measured on GPIO5/GPIO4.
//!
//! Wire format, little endian: an event is u64 virtual ns, u32 kind, u32
//! value; an answer is u32 flags (bit 0: SDA pulled low, bit 1: stop the
//! run, bit 2: the firmware's loop runs), u32 rx_len, u64 valid_until_ns, u64 wake_at_ns, then rx_len bytes.

use std::io::{self, Read};
use std::string::String;
use std::vec::Vec;

use super::body::{advance, MotionF64, PoseF64};
use super::drawn::Drawn;
use super::noise::Rng;
use super::robot::{body_fits, set_truth, SimConfig};
use super::script::Script;
use super::sensors::SimSensors;
use super::vl53l0x::DEFAULT_PERIOD_NS;
use super::wire::Wire;
use crate::config;
use crate::control::TICK_US;
use crate::model::ServoCmd;

/// Event kinds (esp8266_link.h).
pub const PINS: u32 = 1;
pub const UART_TX: u32 = 2;
pub const SYNC: u32 = 3;
pub const END: u32 = 4;

/// Most RX bytes in one answer (the board's buffer).
pub const MAX_RX: usize = 256;

const NS_PER_TICK: u64 = TICK_US as u64 * 1_000;
/// A servo pin without a pulse for this long is idle (no pulses: the
/// servo holds still).
const SERVO_IDLE_NS: u64 = 100_000_000;
/// Pulse widths a servo takes as a command (0 to 180 with some margin).
const SERVO_PULSE_NS: core::ops::RangeInclusive<u64> =
    (config::servo::PULSE_AT_0_US as u64 * 900)..=(config::servo::PULSE_AT_180_US as u64 * 1100);
/// A lidar that never gets ready: its next result this far away.
const STALLED_PERIOD_NS: u64 = 1_000_000_000_000;

/// One event from the board.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub struct Event {
    pub t_ns: u64,
    pub kind: u32,
    pub value: u32,
}

/// Reads one event; `None` at the end of the stream.
pub fn read_event(r: &mut impl Read) -> io::Result<Option<Event>> {
    let mut b = [0u8; 16];
    match r.read_exact(&mut b) {
        Ok(()) => {}
        Err(e) if e.kind() == io::ErrorKind::UnexpectedEof => return Ok(None),
        Err(e) => return Err(e),
    }
    let u32_at = |i: usize| u32::from_le_bytes([b[i], b[i + 1], b[i + 2], b[i + 3]]);
    Ok(Some(Event { t_ns: u64::from(u32_at(0)) | u64::from(u32_at(4)) << 32, kind: u32_at(8), value: u32_at(12) }))
}

/// The answer to a sync.
#[derive(Clone, PartialEq, Eq, Debug)]
pub struct Answer {
    pub sda_low: bool,
    /// The run has reached its end: the board stops.
    pub stop: bool,
    /// The firmware has brought its sensors up and runs its loop.
    pub looping: bool,
    /// The answer holds until an edge or this virtual time.
    pub valid_until_ns: u64,
    /// Sync again at this virtual time.
    pub wake_at_ns: u64,
    pub rx: Vec<u8>,
}

impl Answer {
    pub fn encode(&self) -> Vec<u8> {
        let mut v = Vec::with_capacity(24 + self.rx.len());
        let flags = u32::from(self.sda_low) | u32::from(self.stop) << 1 | u32::from(self.looping) << 2;
        v.extend_from_slice(&flags.to_le_bytes());
        v.extend_from_slice(&(self.rx.len() as u32).to_le_bytes());
        v.extend_from_slice(&self.valid_until_ns.to_le_bytes());
        v.extend_from_slice(&self.wake_at_ns.to_le_bytes());
        v.extend_from_slice(&self.rx);
        v
    }
}

/// What a fault does while its window is open.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum WireFault {
    /// The chip at this address does not acknowledge it.
    Nack(u8),
    /// A stuck slave holds SDA low.
    SdaLow,
    /// The front (false) or right (true) lidar never has a result ready.
    LidarStall { right: bool },
}

/// A fault injected at the wire during `[from_ns, to_ns)` of virtual time.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub struct FaultWindow {
    pub fault: WireFault,
    pub from_ns: u64,
    pub to_ns: u64,
}

/// One servo pin's pulses.
#[derive(Clone, Copy, Default, Debug)]
struct ServoPin {
    rise_ns: Option<u64>,
    last_fall_ns: u64,
    width_ns: Option<u64>,
}

/// The command a pulse width drives (the inverse of
/// `driver::servo::pulse_ns`).
pub fn command_for_width(width_ns: u64) -> ServoCmd {
    let (lo, hi) = (config::servo::PULSE_AT_0_US as f64, config::servo::PULSE_AT_180_US as f64);
    ServoCmd::from_f64(((width_ns as f64 / 1000.0 - lo) / (hi - lo) * 180.0).clamp(0.0, 180.0))
}

/// Pin numbers (config::pins).
const SDA: u32 = config::pins::SDA_GPIO as u32;
const SCL: u32 = config::pins::SCL_GPIO as u32;
const FRONT_XSHUT: u32 = config::pins::FRONT_XSHUT_GPIO as u32;
const RIGHT_XSHUT: u32 = config::pins::RIGHT_XSHUT_GPIO as u32;
const SERVO_PINS: [u32; 2] = [config::pins::LEFT_SERVO_GPIO as u32, config::pins::RIGHT_SERVO_GPIO as u32];

/// The world behind the pins (see the module docs).
pub struct EmulatedRobot {
    pub cfg: SimConfig,
    pub sensors: SimSensors,
    pub wire: Wire,
    truth: PoseF64,
    rng: Rng,
    /// What the run drew once (as in the host simulator; the hard world's
    /// motion effects are the host simulator's only, its sensor effects
    /// apply here too).
    drawn: Drawn,
    next_step_ns: u64,
    pins: u32,
    /// Whether `pins` holds levels the board reported.
    pins_known: bool,
    servos: [ServoPin; 2],
    collisions: u32,
    /// The true pose after every loop period of virtual time.
    pub truth_log: Vec<(u64, PoseF64)>,
    line: Vec<u8>,
    line_start_ns: u64,
    /// Lines UART0 sent (without CR LF), with the virtual time their first
    /// byte left.
    pub lines: Vec<(u64, String)>,
    script: Script,
    /// The first command: where the firmware starts believing it is
    /// (`pose`, which ends its power-up localization); empty when it is to
    /// localize ([`SimConfig::locate_at_power_up`]).
    preamble: String,
    /// The script's time zero: when the firmware has brought its sensors up.
    script_start_ns: Option<u64>,
    next_line: usize,
    faults: Vec<(FaultWindow, bool)>,
    /// Script time at which the run ends, ns.
    duration_ns: u64,
    /// When the board ended the run.
    pub ended_ns: Option<u64>,
}

impl EmulatedRobot {
    /// Runs `script` for `duration_ns` of script time once the firmware is
    /// up, with `faults` (virtual time since power-on).
    pub fn new(cfg: SimConfig, script: Script, duration_ns: u64, faults: &[FaultWindow]) -> EmulatedRobot {
        let sensors = SimSensors::new();
        let wire = Wire::new(std::vec![sensors.front.clone(), sensors.right.clone(), sensors.mpu.clone()]);
        // XSHUT is low until the firmware drives it
        sensors.front.borrow_mut().set_xshut(false);
        sensors.right.borrow_mut().set_xshut(false);
        let mut rng = Rng::new(cfg.seed);
        let disturbance_phase = rng.range_f64(0.0, core::f64::consts::TAU);
        let drawn = Drawn::draw(cfg.seed, &cfg.realism, disturbance_phase);
        set_truth(&sensors, &cfg, &cfg.start, &mut rng, &drawn);
        let s = cfg.start;
        let preamble = if cfg.locate_at_power_up {
            String::new()
        } else {
            std::format!("pose {:.0} {:.0} {:.1}\n", s.x, s.y, s.theta.to_degrees().rem_euclid(360.0))
        };
        EmulatedRobot {
            cfg,
            sensors,
            wire,
            truth: cfg.start,
            rng,
            drawn,
            next_step_ns: NS_PER_TICK,
            pins: 0,
            pins_known: false,
            servos: [ServoPin::default(); 2],
            collisions: 0,
            truth_log: std::vec![(0, cfg.start)],
            line: Vec::new(),
            line_start_ns: 0,
            lines: Vec::new(),
            script,
            preamble,
            script_start_ns: None,
            next_line: 0,
            faults: faults.iter().map(|f| (*f, false)).collect(),
            duration_ns,
            ended_ns: None,
        }
    }

    /// Handles one event; a sync gets an answer.
    pub fn handle(&mut self, ev: Event) -> Option<Answer> {
        self.advance_to(ev.t_ns);
        match ev.kind {
            PINS => self.pins_changed(ev.t_ns, ev.value),
            UART_TX => self.uart_byte(ev.t_ns, ev.value as u8),
            SYNC => return Some(self.answer(ev.t_ns)),
            END => self.ended_ns = Some(ev.t_ns),
            _ => {}
        }
        None
    }

    pub fn truth(&self) -> PoseF64 {
        self.truth
    }

    /// The true pose at virtual time `t_ns` (the last step at or before it).
    pub fn truth_at(&self, t_ns: u64) -> PoseF64 {
        let i = self.truth_log.partition_point(|(t, _)| *t <= t_ns);
        self.truth_log[i.saturating_sub(1)].1
    }

    /// Loop periods whose motion a wall stopped.
    pub fn collisions(&self) -> u32 {
        self.collisions
    }

    /// The script's time zero, if the firmware got that far.
    pub fn script_start_ns(&self) -> Option<u64> {
        self.script_start_ns
    }

    fn advance_to(&mut self, t_ns: u64) {
        while self.next_step_ns <= t_ns {
            let t = self.next_step_ns;
            self.set_clock(t);
            self.step(t);
            self.next_step_ns += NS_PER_TICK;
        }
        self.set_clock(t_ns);
        self.apply_faults(t_ns);
    }

    fn set_clock(&self, t_ns: u64) {
        let clock = &self.sensors.clock;
        clock.advance_ns(t_ns.saturating_sub(clock.now_ns()));
    }

    /// One loop period ends at `t`: the body moves by what the servos did,
    /// then the chips see the new pose.
    fn step(&mut self, t: u64) {
        let [left, right] = [0, 1].map(|i| {
            let p = &self.servos[i];
            match p.width_ns {
                Some(w) if t.saturating_sub(p.last_fall_ns) < SERVO_IDLE_NS => Some(command_for_width(w)),
                _ => None,
            }
        });
        let motion = match (left, right) {
            (Some(l), Some(r)) => MotionF64::from_motion(config::actuators::MODEL.motion_from_commands(l, r)),
            _ => MotionF64::Stop,
        };
        let noisy = match motion {
            MotionF64::Stop => MotionF64::Stop,
            MotionF64::Straight(v) => MotionF64::Straight(v * (1.0 + self.rng.gauss(self.cfg.noise.speed))),
            MotionF64::Turn(w) => MotionF64::Turn(w * (1.0 + self.rng.gauss(self.cfg.noise.turn))),
        };
        let d = config::geometry::ROTATION_TO_REFERENCE.to_mm_f64();
        let next = advance(&self.truth, noisy, NS_PER_TICK as f64 * 1e-9, self.cfg.kinematics, d);
        if body_fits(&self.cfg.arena, &self.cfg.realism, &next) {
            self.truth = next;
        } else {
            self.collisions += 1;
        }
        self.truth_log.push((t, self.truth));
        set_truth(&self.sensors, &self.cfg, &self.truth, &mut self.rng, &self.drawn);
    }

    fn pins_changed(&mut self, t: u64, levels: u32) {
        let changed = levels ^ self.pins;
        self.pins = levels;
        // The first report gives the levels at reset, not edges.
        let first_report = !std::mem::replace(&mut self.pins_known, true);
        let high = |pin: u32| levels >> pin & 1 == 1;
        if changed >> FRONT_XSHUT & 1 == 1 {
            self.sensors.front.borrow_mut().set_xshut(high(FRONT_XSHUT));
        }
        if changed >> RIGHT_XSHUT & 1 == 1 {
            self.sensors.right.borrow_mut().set_xshut(high(RIGHT_XSHUT));
        }
        for (pin, servo) in SERVO_PINS.iter().zip(self.servos.iter_mut()) {
            if changed >> pin & 1 == 1 {
                if first_report {
                    servo.rise_ns = None;
                } else if high(*pin) {
                    servo.rise_ns = Some(t);
                } else if let Some(r) = servo.rise_ns.take() {
                    // a servo ignores what is no pulse (a pin settling at reset)
                    if SERVO_PULSE_NS.contains(&(t - r)) {
                        servo.width_ns = Some(t - r);
                        servo.last_fall_ns = t;
                    }
                }
            }
        }
        if changed & (1 << SDA | 1 << SCL) != 0 {
            self.wire.set_master(high(SCL), high(SDA));
        }
    }

    fn uart_byte(&mut self, t: u64, b: u8) {
        if self.line.is_empty() {
            self.line_start_ns = t;
        }
        if b != b'\n' {
            self.line.push(b);
            return;
        }
        let line: String = String::from_utf8_lossy(&self.line).trim_end_matches('\r').into();
        self.line.clear();
        // the firmware's bring-up report: its loop starts now
        if self.script_start_ns.is_none() && line.starts_with("lidars ") {
            self.script_start_ns = Some(t);
        }
        self.lines.push((self.line_start_ns, line));
    }

    fn answer(&mut self, t: u64) -> Answer {
        let mut rx = Vec::new();
        // before the firmware is up, look again every loop period
        let Some(start) = self.script_start_ns else {
            return self.answer_with(t, rx, false, t + NS_PER_TICK);
        };
        let end = start + self.duration_ns;
        let mut wake = end;
        rx.extend_from_slice(std::mem::take(&mut self.preamble).as_bytes());
        while let Some(l) = self.script.lines.get(self.next_line) {
            let at = start + l.at_us * 1_000;
            if at > t {
                wake = wake.min(at);
                break;
            }
            if rx.len() + l.command.len() + 1 > MAX_RX {
                wake = wake.min(t + 1_000_000);
                break;
            }
            rx.extend_from_slice(l.command.as_bytes());
            rx.push(b'\n');
            self.next_line += 1;
        }
        self.answer_with(t, rx, t >= end, wake)
    }

    /// The answer, its validity and wake-up bounded by the next fault edge.
    fn answer_with(&self, t: u64, rx: Vec<u8>, stop: bool, mut wake: u64) -> Answer {
        let mut valid_until = u64::MAX;
        for (w, _) in &self.faults {
            for edge in [w.from_ns, w.to_ns] {
                if edge > t {
                    valid_until = valid_until.min(edge);
                    wake = wake.min(edge);
                }
            }
        }
        let looping = self.script_start_ns.is_some();
        Answer { sda_low: self.wire.sda_pulled_low(), stop, looping, valid_until_ns: valid_until, wake_at_ns: wake, rx }
    }

    fn apply_faults(&mut self, t: u64) {
        for i in 0..self.faults.len() {
            let (w, was) = self.faults[i];
            let now = w.from_ns <= t && t < w.to_ns;
            if now == was {
                continue;
            }
            self.faults[i].1 = now;
            match w.fault {
                WireFault::Nack(addr) => self.wire.set_nack(addr, now),
                WireFault::SdaLow => self.wire.set_sda_held(now),
                WireFault::LidarStall { right } => {
                    let chip = if right { &self.sensors.right } else { &self.sensors.front };
                    chip.borrow_mut().set_period_ns(if now { STALLED_PERIOD_NS } else { DEFAULT_PERIOD_NS });
                }
            }
        }
    }
}
