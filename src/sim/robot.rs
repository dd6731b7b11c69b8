//! [`SimRobot`]: the firmware's control loop driving a simulated paperbot.
//!
//! Each [`SimRobot::tick`] (one loop period of simulated time):
//! 1. the fake chips get the truth at this instant: each lidar reads the
//!    nearest wall in its cone from its mount (a thin ray with the cone
//!    off), readings at glancing incidence may fail
//!    ([`super::realism`]); the distance from the reference point along
//!    the beam gets Gaussian noise and becomes the chip's reading through
//!    the inverse lidar model ([`LidarModel::reading_for`]); the compass's
//!    earth field is turned into the car's frame at the true magnetic
//!    heading (plus noise and the floor's disturbance), then distorted by
//!    the inverse of the configured hard/soft-iron calibration, so the
//!    driver's correction undoes it;
//! 2. the control loop ticks: its drivers talk to the fake chips over the
//!    simulated bus (register level), it reads, steps, acts, reports;
//! 3. the body moves for one period by what its servo commands make by the
//!    actuator model ([`ActuatorModel::motion_from_commands`](crate::model::actuator::ActuatorModel::motion_from_commands)), times
//!    the motion's trial factor, with per-tick noise on the speed and turn
//!    rate; a turn pivots about the trial's point behind the axle; a
//!    motion that would take the body through a wall is refused.
//!
//! Commands go in byte by byte ([`SimRobot::feed`]) and the loop's output
//! lines come out of [`SimRobot::take_output`], so the same robot serves a
//! scripted run ([`SimRobot::run_script`]) and a real-time pseudo-terminal.

use std::string::String;
use std::vec::Vec;

use super::arena::Arena;
use super::body::{advance, Kinematics, MotionF64, PoseF64};
use super::drawn::Drawn;
use super::noise::Rng;
use super::realism::{beam_effects, glancing_failure, lidar_range, spurious, Realism, Trial};
use super::script::Script;
use super::sensors::{SimCompass, SimLidar, SimSensors};
use crate::config;
use crate::control::log::RingLog;
use crate::control::settings::{FlashSettings, MemoryFlash};
use crate::control::{Controller, Hardware, LineSink, TICK_US};
use crate::driver::{HeadingSensor, Servos};
use crate::math::Length;
use crate::model::lidar::LidarMount;
use crate::model::{LidarModel, ServoCmd};

/// The servos as the simulator sees them: the last commands set.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub struct SimServos {
    pub left: ServoCmd,
    pub right: ServoCmd,
}

impl Default for SimServos {
    fn default() -> Self {
        let m = config::actuators::MODEL;
        SimServos { left: m.left_neutral(), right: m.right_neutral() }
    }
}

impl Servos for SimServos {
    fn set(&mut self, left: ServoCmd, right: ServoCmd) {
        self.left = left;
        self.right = right;
    }
}

/// The simulated robot's parts: its drivers on the simulated bus, and the
/// robot's on-board log.
pub struct SimHardware;

impl Hardware for SimHardware {
    type Front = SimLidar;
    type Right = SimLidar;
    type Compass = SimCompass;
    type Servos = SimServos;
    type Log = RingLog<{ config::log::ROWS }>;
    /// The settings sectors in memory (kept by the [`SimRobot`]).
    type Settings = FlashSettings<MemoryFlash>;
}

/// The control loop on the simulated drivers, with the robot's on-board log.
pub type SimController = Controller<SimHardware>;

/// Noise levels (one sigma); [`Noise::OFF`] for exact runs.
#[derive(Clone, Copy, PartialEq, Debug)]
pub struct Noise {
    /// Straight speed, fraction per tick.
    pub speed: f64,
    /// Turn rate, fraction per tick.
    pub turn: f64,
    /// Lidar distance, mm.
    pub lidar_mm: f64,
    /// Compass heading, degrees.
    pub compass_deg: f64,
}

impl Noise {
    pub const OFF: Noise = Noise { speed: 0.0, turn: 0.0, lidar_mm: 0.0, compass_deg: 0.0 };
}

impl Default for Noise {
    /// The config's levels ([`config::sim`]).
    fn default() -> Self {
        Noise {
            speed: config::sim::SPEED_NOISE,
            turn: config::sim::TURN_NOISE,
            lidar_mm: config::sim::LIDAR_NOISE_MM,
            compass_deg: config::sim::COMPASS_NOISE_DEG,
        }
    }
}

/// How to set up a simulated robot.
#[derive(Clone, Copy, PartialEq, Debug)]
pub struct SimConfig {
    pub arena: Arena,
    /// The true start pose.
    pub start: PoseF64,
    /// The firmware powers up as on the robot: at the box's centre, not
    /// knowing where it is, and localizes
    /// ([`crate::config::locate::AT_POWER_UP`]). False: it starts
    /// believing `start` (a test that needs a known start).
    pub locate_at_power_up: bool,
    /// Localizations refine the search's fix with every reading
    /// (`Controller::set_refine`; default `config::refine::ENABLED`).
    pub refine: bool,
    pub seed: u64,
    pub noise: Noise,
    pub kinematics: Kinematics,
    /// The effects that make it as hard as the real robot (default: the
    /// lab's, [`Realism::LAB`]).
    pub realism: Realism,
}

impl Default for SimConfig {
    fn default() -> Self {
        SimConfig {
            arena: Arena::default(),
            start: PoseF64::new(
                config::sim::START_X_MM,
                config::sim::START_Y_MM,
                config::sim::START_HEADING_DEG.to_radians(),
            ),
            locate_at_power_up: config::locate::AT_POWER_UP,
            refine: config::refine::ENABLED,
            seed: 1,
            noise: Noise::default(),
            kinematics: Kinematics::default(),
            realism: Realism::default(),
        }
    }
}

/// Output lines collected from the loop.
#[derive(Default)]
struct Collect(Vec<String>);

impl LineSink for Collect {
    fn write_line(&mut self, line: &str) {
        self.0.push(line.into());
    }
}

/// One recorded instant of a run.
#[derive(Clone, Copy, PartialEq, Debug)]
pub struct Sample {
    pub t_us: u64,
    pub truth: PoseF64,
    /// What the firmware reports (its telemetry pose: the estimator's).
    pub estimate: PoseF64,
    /// The firmware's dead-reckoned pose (state update alone).
    pub dead_reckoned: PoseF64,
    /// The firmware is localizing (its pose is not an estimate yet).
    pub locating: bool,
}

/// The simulated robot (see the module docs).
pub struct SimRobot {
    pub cfg: SimConfig,
    /// The bus, the clock and the fake chips (inject faults here).
    pub sensors: SimSensors,
    ctl: SimController,
    truth: PoseF64,
    rng: Rng,
    out: Collect,
    /// Loop clock of the next tick, ns on the simulated clock.
    next_tick_ns: u64,
    /// Ticks whose motion was refused because a wheel or the nose would
    /// have passed a wall.
    collisions: u32,
    /// The running motion's draw of speed factor and pivot.
    trial: Trial,
    /// What the run drew once: the hard world's robot, the compass's
    /// pattern over the floor.
    drawn: Drawn,
    /// A hand held this far in front of the front lidar, mm: it reads the
    /// nearer of the hand and the wall (`None`: no hand).
    pub hand_mm: Option<f64>,
}

impl SimRobot {
    /// A robot powered up with erased settings sectors (the config's
    /// values, no boot line about them).
    pub fn new(cfg: SimConfig) -> SimRobot {
        SimRobot::start(cfg, None)
    }

    /// A robot powered up with `flash` in its settings sectors (e.g. the
    /// [`SimRobot::flash`] of a robot before a power-cycle): it restores
    /// them as the firmware does, with the boot lines.
    pub fn with_flash(cfg: SimConfig, flash: MemoryFlash) -> SimRobot {
        SimRobot::start(cfg, Some(flash))
    }

    /// The settings sectors as they are now (to power-cycle into).
    pub fn flash(&mut self) -> MemoryFlash {
        self.ctl.settings_store().flash.clone()
    }

    fn start(cfg: SimConfig, flash: Option<MemoryFlash>) -> SimRobot {
        let sensors = SimSensors::new();
        let (mut front, mut right, mut compass) = sensors.drivers();
        let mut rng = Rng::new(cfg.seed);
        let disturbance_phase = rng.range_f64(0.0, core::f64::consts::TAU);
        let drawn = Drawn::draw(cfg.seed, &cfg.realism, disturbance_phase);
        // the chips see the start pose during bring-up
        set_truth(&sensors, &cfg, &cfg.start, &mut rng, &drawn);
        // bring-up results show in the loop's health: a chip that failed
        // here fails its first poll and is re-initialised by the loop
        let _ = crate::driver::lidar::bring_up(&mut front, &mut right);
        let _ = compass.reinit();
        // the firmware knows the arena it is in (its estimator uses the walls)
        let arena = cfg.arena;
        let believed = if cfg.locate_at_power_up { arena.centre() } else { cfg.start.to_pose() };
        let store = FlashSettings::new(flash.clone().unwrap_or_default());
        let servos = SimServos::default();
        let mut ctl = Controller::with_log(front, right, compass, servos, believed, arena, RingLog::new(), store);
        let mut out = Collect::default();
        if flash.is_some() {
            ctl.restore_settings(&mut out);
        }
        ctl.set_refine(cfg.refine);
        if cfg.locate_at_power_up {
            ctl.power_up(&mut out);
        }
        let next_tick_ns = sensors.clock.now_ns();
        SimRobot {
            cfg,
            sensors,
            ctl,
            truth: cfg.start,
            rng,
            out,
            next_tick_ns,
            collisions: 0,
            trial: Trial::NONE,
            drawn,
            hand_mm: None,
        }
    }

    /// One received serial byte.
    pub fn feed(&mut self, byte: u8) {
        self.ctl.feed(byte, &mut self.out);
    }

    /// A command line (the terminator is added).
    pub fn send(&mut self, line: &str) {
        for b in line.bytes() {
            self.feed(b);
        }
        self.feed(b'\n');
    }

    /// Output lines since the last call.
    pub fn take_output(&mut self) -> Vec<String> {
        std::mem::take(&mut self.out.0)
    }

    /// Simulated time, us since the simulator was created.
    pub fn now_us(&self) -> u64 {
        self.sensors.clock.now_ns() / 1_000
    }

    /// Runs one loop period (see the module docs).
    pub fn tick(&mut self) {
        let clock = &self.sensors.clock;
        // a driver that waited (a re-init's delays) may have pushed the
        // clock past the schedule: then this tick is late, as on the robot
        let now_ns = clock.now_ns().max(self.next_tick_ns);
        clock.advance_ns(now_ns - clock.now_ns());
        set_truth(&self.sensors, &self.cfg, &self.truth, &mut self.rng, &self.drawn);
        if let Some(hand) = self.hand_mm.and_then(|mm| config::lidar::FRONT.reading_for(Length::from_mm_f64(mm))) {
            let mut front = self.sensors.front.borrow_mut();
            let wall = front.distance_mm();
            front.set_distance_mm(wall.min(hand));
        }
        // the loop's wrapping microsecond counter
        self.ctl.tick((now_ns / 1_000) as u32, &mut self.out);
        self.next_tick_ns = now_ns + u64::from(TICK_US) * 1_000;
        // the body moves for one period by what the servos do now
        let servos = *self.ctl.servos();
        let motion = config::actuators::MODEL.motion_from_commands(servos.left, servos.right);
        let dt_s = f64::from(TICK_US) * 1e-6;
        let motion = MotionF64::from_motion(motion);
        self.trial = self.trial.for_motion(motion, &self.cfg.realism, &mut self.rng);
        let k = self.trial.speed_factor;
        let t_s = now_ns as f64 * 1e-9;
        let (drawn, realism) = (&self.drawn, &self.cfg.realism);
        let noisy = match motion {
            MotionF64::Stop => MotionF64::Stop,
            MotionF64::Straight(v) => {
                MotionF64::Straight(v * k * drawn.speed_scale * (1.0 + self.rng.gauss(self.cfg.noise.speed)))
            }
            MotionF64::Turn(w) => {
                let scale = drawn.turn_factor(w >= 0.0, t_s, realism);
                MotionF64::Turn(w * k * scale * (1.0 + self.rng.gauss(self.cfg.noise.turn)))
            }
        };
        // a turn pivots `pivot_behind_mm` behind the axle: the reference
        // point circles it at D plus that
        let d =
            config::geometry::ROTATION_TO_REFERENCE.to_mm_f64() + self.trial.pivot_behind_mm + drawn.pivot_offset_mm;
        let next = advance(&self.truth, noisy, dt_s, self.cfg.kinematics, d);
        if self.fits(&next) {
            self.truth = next;
        } else {
            self.collisions = self.collisions.saturating_add(1);
        }
        let clock = &self.sensors.clock;
        clock.advance_ns(self.next_tick_ns.saturating_sub(clock.now_ns()));
    }

    fn fits(&self, p: &PoseF64) -> bool {
        body_fits(&self.cfg.arena, &self.cfg.realism, p)
    }

    /// Runs `script` (times from now) for `duration_us` of simulated time,
    /// recording a [`Sample`] every `record_every` ticks and handing every
    /// output line to `on_line`.
    pub fn run_script(
        &mut self,
        script: &Script,
        duration_us: u64,
        record_every: u32,
        mut on_line: impl FnMut(&str),
    ) -> Vec<Sample> {
        let start = self.now_us();
        let ticks = duration_us / u64::from(TICK_US);
        let mut next_line = script.lines.iter().peekable();
        let mut samples = Vec::new();
        for i in 0..=ticks {
            let t = self.now_us().saturating_sub(start);
            while let Some(l) = next_line.next_if(|l| l.at_us <= t) {
                self.send(&l.command);
            }
            if i % u64::from(record_every.max(1)) == 0 || i == ticks {
                samples.push(self.sample());
            }
            if i < ticks {
                self.tick();
            }
            for line in self.take_output() {
                on_line(&line);
            }
        }
        samples
    }

    /// The truth and the firmware's estimate now.
    pub fn sample(&self) -> Sample {
        Sample {
            t_us: self.now_us(),
            truth: self.truth,
            estimate: PoseF64::from_pose(&self.ctl.pose()),
            dead_reckoned: PoseF64::from_pose(&self.ctl.dead_reckoned()),
            locating: matches!(self.ctl.mode(), crate::control::Mode::Locate { .. }),
        }
    }

    /// The true pose.
    pub fn truth(&self) -> PoseF64 {
        self.truth
    }
    /// Moves the robot (e.g. a test's start), without telling the firmware.
    pub fn set_truth(&mut self, p: PoseF64) {
        self.truth = p;
    }
    pub fn controller(&self) -> &SimController {
        &self.ctl
    }
    pub fn controller_mut(&mut self) -> &mut SimController {
        &mut self.ctl
    }
    /// Ticks whose motion a wall stopped.
    pub fn collisions(&self) -> u32 {
        self.collisions
    }
    /// What the run drew once from its seed (the hard world's robot).
    pub fn drawn(&self) -> &Drawn {
        &self.drawn
    }
}

/// True when the nose (reference point) and both wheels are inside the
/// arena, and with [`Realism::whole_body`] the skid and both lidars too.
pub fn body_fits(a: &Arena, realism: &Realism, p: &PoseF64) -> bool {
    let d = config::geometry::ROTATION_TO_REFERENCE.to_mm_f64();
    let (s, c) = p.theta.sin_cos();
    let (ax, ay) = (p.x - d * c, p.y - d * s);
    let h = config::sim::HALF_TRACK_MM;
    let wheels = a.contains(p.x, p.y) && a.contains(ax - h * s, ay + h * c) && a.contains(ax + h * s, ay - h * c);
    if !realism.whole_body {
        return wheels;
    }
    let skid = config::geometry::SKID_BEHIND_AXLE.to_mm_f64();
    let lidar_in = |m: &LidarMount| {
        let (x, y, _) = p.lidar_ray(m);
        a.contains(x, y)
    };
    wheels
        && a.contains(ax - skid * c, ay - skid * s)
        && lidar_in(&config::geometry::FRONT_LIDAR)
        && lidar_in(&config::geometry::RIGHT_LIDAR)
}

/// What a lidar at `mount` on the body at `p` measures before the
/// sensor's own noise: the distance from the reference point along the
/// beam (the lidar model's output) to the nearest wall in its cone (a thin
/// ray with the cone off), with the hard world's mixed returns and
/// incidence noise ([`beam_effects`]), a glancing reading's failure and a
/// spurious echo drawn from `rng`; `None` for "no target".
pub fn lidar_truth(arena: &Arena, realism: &Realism, p: &PoseF64, mount: &LidarMount, rng: &mut Rng) -> Option<f64> {
    let (x, y, dir) = p.lidar_ray(mount);
    let (t, incidence) = lidar_range(arena, x, y, dir, realism)?;
    let t = beam_effects(arena, (x, y, dir), t, incidence, realism, rng);
    let t = match glancing_failure(incidence, realism, rng) {
        None => t,
        Some(None) => return None,
        Some(Some(factor)) => t * factor,
    };
    let t = spurious(realism, rng).map_or(t, |factor| t * factor);
    Some(t + PoseF64::along_beam_mm(mount))
}

/// Sets the fake chips' truth for the body at `p`.
pub fn set_truth(sensors: &SimSensors, cfg: &SimConfig, p: &PoseF64, rng: &mut Rng, drawn: &Drawn) {
    let no_target = crate::model::lidar::NO_TARGET_READING;
    let lidar = |mount: &LidarMount, model: &LidarModel, rng: &mut Rng| -> u16 {
        let Some(d) = lidar_truth(&cfg.arena, &cfg.realism, p, mount, rng) else { return no_target };
        let distance = d + rng.gauss(cfg.noise.lidar_mm);
        model.reading_for(Length::from_mm_f64(distance)).unwrap_or(0).min(no_target)
    };
    let front = lidar(&config::geometry::FRONT_LIDAR, &config::lidar::FRONT, rng);
    let right = lidar(&config::geometry::RIGHT_LIDAR, &config::lidar::RIGHT, rng);
    sensors.front.borrow_mut().set_distance_mm(front);
    sensors.right.borrow_mut().set_distance_mm(right);
    let disturbed = p.theta + drawn.compass_bias(&cfg.arena, p.x, p.y, &cfg.realism);
    sensors.mpu.borrow_mut().ak.set_field_adjusted(field_for(disturbed, cfg.noise.compass_deg, rng));
}

/// The ASA-adjusted counts (chip axes) the AK8963 reads at true heading
/// `theta` (radians clockwise from north), with heading noise: the earth
/// field in the car's frame, mapped to the chip's axes, then distorted by
/// the inverse of the configured calibration (`adj = corrected / scale + bias`).
/// The car stays flat on the floor: a turn sweeps the horizontal field through
/// the forward and right axes, the vertical axis reads the same at every heading.
pub fn field_for(theta: f64, noise_deg: f64, rng: &mut Rng) -> [i32; 3] {
    let m = &config::compass::MODEL;
    // magnetic heading: true heading minus the (east) declination
    let psi = theta - m.declination.to_radians_f64() + rng.gauss(noise_deg).to_radians();
    let b = config::sim::FIELD_HORIZONTAL_COUNTS;
    // north seen from the car: (forward, right) = (cos psi, -sin psi)
    let (forward, right) = (b * psi.cos(), -b * psi.sin());
    let mut chip = [0.0f64; 3];
    chip[2] = config::sim::FIELD_DOWN_COUNTS;
    for (axis, v) in [(m.axes.forward, forward), (m.axes.right, right)] {
        if let Some(c) = chip.get_mut(usize::from(axis.index)) {
            *c = if axis.negate { -v } else { v };
        }
    }
    let cal = &m.calibration;
    let mut adj = [0i32; 3];
    for i in 0..3 {
        let scale = f64::from(cal.scale_q16[i]) / 65536.0;
        adj[i] = (chip[i] / scale + f64::from(cal.bias[i])).round() as i32;
    }
    adj
}
