//! Scripted runs of the estimator and of the control loop, shared word for
//! word by the host generator (`lx106/vectors`, which includes this file and
//! runs it on the core built for the host) and the on-target suite (the same
//! file on the core built for the lx106). The host writes the bits after
//! every call to `lx106/src/host_bits.rs`; the target replays the script and
//! compares exactly. Every input is integer and derived from the script's own
//! xorshift generator and from the core's outputs, so the two runs see the
//! same inputs exactly when the two builds compute the same bits.
//!
//! Also home of the trait doubles the tick benchmarks use (sensors that
//! return a canned reading once or `WouldBlock`, servos that keep the last
//! command, sinks that hash or discard the lines).

use paperbot::config;
use paperbot::control::log::RingLog;
use paperbot::control::settings::{FlashSettings, NoFlash};
use paperbot::control::{Controller, Hardware, LineSink};
use paperbot::driver::{CompassSample, HeadingSensor, LidarSample, MagCalibrate, RangeSensor, SensorError, Servos};
use paperbot::math::{Angle, Dt, Length, Speed, TurnRate};
use paperbot::model::compass::{MagCalibration, MagCounts, MagField};
use paperbot::model::estimator::{Estimator, Seed, Update, N};
use paperbot::model::measurement::{expected_heading, expected_lidar, Arena, LidarId};
use paperbot::model::{step, Motion, Pose, ServoCmd};

/// xorshift32: the scripts' deterministic "noise".
pub struct Rng(pub u32);

impl Rng {
    pub fn next(&mut self) -> u32 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 17;
        self.0 ^= self.0 << 5;
        self.0
    }
    /// Uniform-ish in `-m..=m` (m < 2^15).
    pub fn pm(&mut self, m: i32) -> i32 {
        (self.next() % (2 * m as u32 + 1)) as i32 - m
    }
}

/// FNV-1a, 32 bit.
pub fn fnv(mut h: u32, bytes: &[u8]) -> u32 {
    for &b in bytes {
        h ^= u32::from(b);
        h = h.wrapping_mul(0x0100_0193);
    }
    h
}
pub const FNV0: u32 = 0x811c_9dc5;

fn fnv_i64(h: u32, v: i64) -> u32 {
    fnv(h, &v.to_le_bytes())
}

/// The estimator's bits beyond the reported pose: the best hypothesis's
/// covariance diagonal, and an FNV-1a hash of its whole covariance, pose,
/// scales and bias, the tracking state, every hypothesis's cost and pose,
/// and the best's id.
pub fn cov_array(est: &Estimator) -> [i32; N + 1] {
    let p = est.covariance();
    let mut h = FNV0;
    for i in 0..N {
        for j in i..N {
            h = fnv_i64(h, i64::from(p.get(i, j)));
        }
    }
    let b = est.best_pose();
    let s = est.scales();
    for v in [b.x.0, b.y.0, i64::from(b.theta.0), i64::from(s.speed), i64::from(s.cw), i64::from(s.ccw)] {
        h = fnv_i64(h, v);
    }
    h = fnv_i64(h, i64::from(est.compass_bias().0));
    h = fnv(h, &[est.tracking() as u8]);
    for (pose, cost) in est.hypotheses() {
        for v in [i64::from(cost), pose.x.0, pose.y.0, i64::from(pose.theta.0)] {
            h = fnv_i64(h, v);
        }
    }
    h = fnv(h, &[est.best_id()]);
    let d = p.diagonal();
    [d[0], d[1], d[2], d[3], d[4], d[5], d[6], h as i32]
}

// ---------------------------------------------------------------- estimator

/// What one scripted estimator call was.
pub const PREDICT: u8 = 0;
pub const FRONT: u8 = 1;
pub const RIGHT: u8 = 2;
pub const HEADING: u8 = 3;

pub fn update_code(u: Option<Update>) -> u8 {
    match u {
        None => 0,
        Some(Update::Accepted) => 1,
        Some(Update::Outlier) => 2,
        Some(Update::Unusable) => 3,
    }
}

/// The state after one estimator call: (kind, update code, the measurement
/// model's expectation for the estimated pose before the call (`expected_lidar`
/// bits, `i32::MIN` for none; `expected_heading` bits for the compass; 0 for
/// predict), x, y, theta, theta_frac of the reported pose, [`cov_array`]).
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub struct EstRec(pub u8, pub u8, pub i32, pub i64, pub i64, pub u32, pub u16, pub [i32; N + 1]);

/// One scripted run: start pose of the truth (mm, mm, deg), the estimator's
/// initial error (mm, mm, deg), more hypotheses seeded beside it (offsets
/// from the truth, mm, mm, deg: none for a typed start), motion segments
/// (motion, ticks) and the seed.
pub struct EstRun {
    pub name: &'static str,
    pub truth: (i32, i32, i32),
    pub error: (i32, i32, i32),
    pub others: &'static [(i32, i32, i32)],
    pub segments: &'static [(Mv, u16)],
    pub seed: u32,
}

/// A motion in the scripts' terms (mm/s, mrad/s).
#[derive(Clone, Copy, Debug)]
pub enum Mv {
    Stop,
    Straight(i32),
    Turn(i32),
}

impl Mv {
    pub fn motion(self) -> Motion {
        match self {
            Mv::Stop => Motion::Stop,
            Mv::Straight(v) => Motion::Straight(Speed::from_mm_s(v)),
            Mv::Turn(w) => Motion::Turn(TurnRate::from_mrad_s(w)),
        }
    }
    /// The truth's motion: 4 % faster than commanded (the estimator has to
    /// be corrected by the sensors).
    fn truth(self) -> Motion {
        match self {
            Mv::Stop => Motion::Stop,
            Mv::Straight(v) => Motion::Straight(Speed::from_mm_s(v * 26 / 25)),
            Mv::Turn(w) => Motion::Turn(TurnRate::from_mrad_s(w * 26 / 25)),
        }
    }
}

pub const EST_RUNS: &[EstRun] = &[
    EstRun {
        name: "drive_turn_drive",
        truth: (380, 250, 0),
        error: (25, -15, 4),
        others: &[],
        segments: &[
            (Mv::Straight(130), 60),
            (Mv::Turn(2500), 40),
            (Mv::Stop, 10),
            (Mv::Straight(-120), 50),
            (Mv::Turn(-2000), 30),
        ],
        seed: 0x1234_5678,
    },
    EstRun {
        name: "corner_and_walls",
        truth: (150, 120, 225),
        error: (-30, 20, -6),
        others: &[],
        segments: &[(Mv::Turn(-3000), 35), (Mv::Straight(140), 45), (Mv::Turn(2800), 25), (Mv::Straight(-100), 40)],
        seed: 0x0bad_cafe,
    },
    // four seeds (a localization's clusters): the leader's whole filter and
    // three lighter ones, weighed in turn, until the truth's dominates
    EstRun {
        name: "four_seeds",
        truth: (380, 250, 30),
        error: (8, -5, 2),
        others: &[(120, -60, 0), (-150, 40, 10), (60, 120, -20)],
        segments: &[(Mv::Straight(130), 50), (Mv::Turn(2500), 30), (Mv::Straight(-100), 40), (Mv::Turn(-2000), 20)],
        seed: 0x5eed_0004,
    },
];

fn deg(d: i32) -> Angle {
    Angle::from_millidegrees(d * 1000)
}

/// Runs one scripted estimator run, calling `rec` after every call.
pub fn run_estimator(run: &EstRun, mut rec: impl FnMut(EstRec)) {
    let arena = Arena::DEFAULT;
    let mut rng = Rng(run.seed);
    let (tx, ty, tt) = run.truth;
    let (ex, ey, et) = run.error;
    let mut truth = Pose::from_mm(tx, ty, deg(tt));
    let start = Pose::from_mm(tx + ex, ty + ey, deg(tt + et));
    let mut est = Estimator::new(start);
    if !run.others.is_empty() {
        let sigma = Length::from_mm(20);
        let seed = |pose| Seed { pose, sigma_x: sigma, sigma_y: sigma, weight: 1 };
        let mut seeds = [seed(start); 4];
        for (s, &(dx, dy, dt)) in seeds.iter_mut().skip(1).zip(run.others) {
            *s = seed(Pose::from_mm(tx + dx, ty + dy, deg(tt + dt)));
        }
        est.seed(seeds.get(..=run.others.len()).unwrap_or(&seeds));
    }
    let record = |kind: u8, u: Option<Update>, exp: i32, est: &Estimator, rec: &mut dyn FnMut(EstRec)| {
        let p = est.pose();
        rec(EstRec(kind, update_code(u), exp, p.x.0, p.y.0, p.theta.0, p.theta_frac, cov_array(est)))
    };
    let mut tick = 0u32;
    for &(mv, ticks) in run.segments {
        for _ in 0..ticks {
            // 10 ms +- 2 ms, sometimes a late tick of 40 ms
            let dt_us = if tick % 29 == 28 { 40_000 } else { (10_000 + rng.pm(2_000)) as u32 };
            let dt = Dt::from_micros_saturating(dt_us);
            truth = step(&truth, mv.truth(), dt);
            est.predict(mv.motion(), dt);
            record(PREDICT, None, 0, &est, &mut rec);
            for (id, kind, phase) in [(LidarId::Front, FRONT, 0), (LidarId::Right, RIGHT, 1)] {
                if tick % 3 != phase {
                    continue;
                }
                let exp = expected_lidar(&arena, &est.pose(), id).map_or(i32::MIN, |l| l.0);
                let Some(z) = expected_lidar(&arena, &truth, id) else {
                    record(kind, None, exp, &est, &mut rec);
                    continue;
                };
                // +-6 mm noise; after the first 30 ticks (the estimate has
                // settled) about every 23rd reading is a 250 mm spike (an outlier)
                let spike = if rng.next().is_multiple_of(23) && tick >= 30 { 250 } else { 0 };
                let z = z.saturating_add(Length::from_mm(rng.pm(6) + spike));
                let u = est.update_lidar(id, z);
                record(kind, Some(u), exp, &est, &mut rec);
            }
            if tick % 5 == 2 {
                let exp = expected_heading(&est.pose()).0 as i32;
                // +-1.5 deg of compass noise
                let h = expected_heading(&truth).wrapping_add(Angle::from_millidegrees(rng.pm(1_500)));
                let u = est.update_heading(h);
                record(HEADING, Some(u), exp, &est, &mut rec);
            }
            tick += 1;
        }
    }
}

// ------------------------------------------------------------ trait doubles

/// A lidar that delivers `next` once (then `WouldBlock`).
pub struct ScriptLidar {
    pub next: Option<nb::Result<LidarSample, SensorError>>,
    pub reinit: Result<(), SensorError>,
}

impl ScriptLidar {
    pub const fn new() -> Self {
        ScriptLidar { next: None, reinit: Ok(()) }
    }
}

impl RangeSensor for ScriptLidar {
    #[inline(always)]
    fn poll(&mut self) -> nb::Result<LidarSample, SensorError> {
        self.next.take().unwrap_or(Err(nb::Error::WouldBlock))
    }
    fn reinit(&mut self) -> Result<(), SensorError> {
        self.reinit
    }
}

/// A compass that delivers `next` once (then `WouldBlock`).
pub struct ScriptCompass {
    pub next: Option<nb::Result<CompassSample, SensorError>>,
    pub reinit: Result<(), SensorError>,
    pub calibration: MagCalibration,
}

impl ScriptCompass {
    pub const fn new() -> Self {
        ScriptCompass { next: None, reinit: Ok(()), calibration: MagCalibration::IDENTITY }
    }
}

impl HeadingSensor for ScriptCompass {
    #[inline(always)]
    fn poll(&mut self) -> nb::Result<CompassSample, SensorError> {
        self.next.take().unwrap_or(Err(nb::Error::WouldBlock))
    }
    fn reinit(&mut self) -> Result<(), SensorError> {
        self.reinit
    }
}

impl MagCalibrate for ScriptCompass {
    fn asa(&self) -> [u8; 3] {
        [176, 177, 165]
    }
    fn calibration(&self) -> MagCalibration {
        self.calibration
    }
    fn set_calibration(&mut self, calibration: MagCalibration) {
        self.calibration = calibration;
    }
    // No declination field: the scripts' store (NoFlash) never restores
    // one, and a field here shifts the controller's layout off the
    // firmware's (its driver keeps the declination in its compass model):
    // 45 more instructions on `bar::tick_without_io`.
    fn declination(&self) -> Angle {
        Angle(0)
    }
    fn set_declination(&mut self, _declination: Angle) {}
}

/// Servos that keep the last command.
pub struct ScriptServos {
    pub left: ServoCmd,
    pub right: ServoCmd,
}

impl Servos for ScriptServos {
    #[inline(always)]
    fn set(&mut self, left: ServoCmd, right: ServoCmd) {
        self.left = left;
        self.right = right;
    }
}

/// A sink that hashes every line (FNV-1a over the bytes and a `\n`).
pub struct HashSink {
    pub hash: u32,
    pub lines: u32,
}

impl LineSink for HashSink {
    fn write_line(&mut self, line: &str) {
        self.hash = fnv(fnv(self.hash, line.as_bytes()), b"\n");
        self.lines = self.lines.wrapping_add(1);
    }
}

/// A sink that discards every line.
pub struct NullSink;

impl LineSink for NullSink {
    #[inline(always)]
    fn write_line(&mut self, _line: &str) {}
}

/// The scripted doubles as the loop's hardware (no on-board log).
pub struct Scripted;

impl Hardware for Scripted {
    type Front = ScriptLidar;
    type Right = ScriptLidar;
    type Compass = ScriptCompass;
    type Servos = ScriptServos;
    type Log = RingLog<0>;
    type Settings = FlashSettings<NoFlash>;
}


pub type ScriptController = Controller<Scripted>;

pub fn controller(pose: Pose) -> ScriptController {
    Controller::new(
        ScriptLidar::new(),
        ScriptLidar::new(),
        ScriptCompass::new(),
        ScriptServos { left: ServoCmd::NEUTRAL, right: ServoCmd::NEUTRAL },
        pose,
    )
}

/// A lidar reading as the chip would give it for a model distance `d`
/// (the lidar model inverted, roughly), plus `noise_mm`.
pub fn lidar_sample(which: LidarId, d: Option<Length>, noise_mm: i32) -> LidarSample {
    let model = match which {
        LidarId::Front => &config::lidar::FRONT,
        LidarId::Right => &config::lidar::RIGHT,
    };
    let raw = match d {
        // raw = (d - intercept) / slope; the slopes are about 0.985
        Some(d) => ((d.to_mm() - model.intercept.to_mm()) * 1015 / 1000 + noise_mm).clamp(0, 8190) as u16,
        None => paperbot::model::lidar::NO_TARGET_READING,
    };
    LidarSample { raw_mm: raw, range: model.range(raw) }
}

/// A compass reading for heading `h` (raw counts and field made up from it).
pub fn compass_sample(h: Angle, rng: &mut Rng) -> CompassSample {
    let raw = MagCounts { x: rng.pm(300) as i16, y: rng.pm(300) as i16, z: -200 };
    let field = MagField { x: i32::from(raw.x) * 2, y: i32::from(raw.y) * 2, z: -400 };
    CompassSample { raw, field, heading: h }
}

// ------------------------------------------------------------ control loop

/// The state after one tick: (x, y, theta, theta_frac, digest of the rest
/// (covariance, servo commands, mode, faults, sensor health, the scripted
/// body's pose), output lines so far, FNV-1a of all output so far).
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub struct TickRec(pub i64, pub i64, pub u32, pub u16, pub u32, pub u32, pub u32);

/// Command lines by tick.
pub const COMMANDS: &[(u32, &[u8])] = &[
    (0, b"rate 20\n"),
    (2, b"fwd 0.13 1.5\n"),
    (160, b"cw 2.5\n"),
    // no command from here: the deadman stops the cw after 500 ms
    (240, b"servo 107 61.5 0.8\n"),
    (250, b"status\n"),
    (255, b"pose 300 200 90\n"),
    (256, b"trim r -1.25\n"),
    (258, b"back 0.1 0.5\n"),
    (262, b"fwd 0.5\n"),
    (263, b"jump\r\n"),
    (264, b"ccw 2 1\n"),
    (330, b"help\n"),
    (331, b"rate 50\n"),
    (340, b"fwd 0.12\n"),
    (360, b"stop\n"),
    (370, b"rate 0\n"),
    (372, b"fwd 0.14 0.2\n"),
];
pub const TICKS: u32 = 400;

/// [`HashSink`] that also shows each line to `echo` (for debugging a run).
struct EchoSink<'a> {
    hash: HashSink,
    echo: &'a mut dyn FnMut(&str),
}

impl LineSink for EchoSink<'_> {
    fn write_line(&mut self, line: &str) {
        self.hash.write_line(line);
        (self.echo)(line);
    }
}

/// Runs the scripted control loop, calling `rec` after every tick and
/// `echo` with every output line.
pub fn run_control(mut rec: impl FnMut(TickRec), echo: &mut dyn FnMut(&str)) {
    let arena = Arena::DEFAULT;
    let mut rng = Rng(0x5eed_1e55);
    let start = Pose::from_mm(380, 250, Angle::ZERO);
    let mut c = controller(start);
    let mut sink = EchoSink { hash: HashSink { hash: FNV0, lines: 0 }, echo };
    // the scripted world's body: driven by the servos' motion over each
    // tick (the state update alone; a `pose` command does not move it)
    let (mut body, mut moving, mut dt) = (start, Motion::Stop, Dt::from_micros_saturating(0));
    // the microsecond counter wraps during the run
    let mut now = 0xffff_0000u32;
    for tick in 0..TICKS {
        body = step(&body, moving, dt);
        for (t, line) in COMMANDS {
            if *t == tick {
                c.feed_bytes(line, &mut sink);
            }
        }
        // sensors: what they would read at the body, noisy
        let front_fault = (40..43).contains(&tick) || tick == 300;
        if front_fault {
            c.front().next = Some(Err(nb::Error::Other(SensorError::Bus)));
        } else if tick % 3 == 0 {
            let d = expected_lidar(&arena, &body, LidarId::Front);
            c.front().next = Some(Ok(lidar_sample(LidarId::Front, d, rng.pm(8))));
        }
        // the right lidar goes silent for a while (timeout, then re-init)
        if tick % 3 == 1 && !(180..260).contains(&tick) {
            let d = expected_lidar(&arena, &body, LidarId::Right);
            c.right().next = Some(Ok(lidar_sample(LidarId::Right, d, rng.pm(8))));
        }
        if tick == 77 {
            c.compass().next = Some(Err(nb::Error::Other(SensorError::BadSample)));
        } else if tick % 5 == 2 {
            let h = expected_heading(&body).wrapping_add(Angle::from_millidegrees(rng.pm(2_000)));
            c.compass().next = Some(Ok(compass_sample(h, &mut rng)));
        }
        c.tick(now, &mut sink);
        // 10 ms +- 0.5 ms; a 20 ms overrun now and then
        let next = now.wrapping_add(if tick % 97 == 50 { 20_000 } else { (10_000 + rng.pm(500)) as u32 });
        (moving, dt, now) = (c.applied().motion, Dt::from_micros_saturating(next.wrapping_sub(now)), next);

        let p = c.pose();
        let mut h = FNV0;
        for v in cov_array(c.estimator()) {
            h = fnv_i64(h, i64::from(v));
        }
        let a = c.applied();
        h = fnv_i64(h, i64::from(a.left.to_q8()));
        h = fnv_i64(h, i64::from(a.right.to_q8()));
        h = fnv(h, c.mode().word().as_bytes());
        let f = c.faults();
        for v in [f.bus, f.timeout, f.missing, f.bad_sample, f.rejected_outliers, f.overruns] {
            h = fnv_i64(h, i64::from(v));
        }
        for s in [c.front_health(), c.right_health(), c.compass_health()] {
            h = fnv_i64(h, i64::from(s.up) | i64::from(s.reinits) << 1);
        }
        let d = body;
        h = fnv_i64(h, d.x.0);
        h = fnv_i64(h, d.y.0);
        h = fnv_i64(h, i64::from(d.theta.0));
        let s = c.servos();
        h = fnv_i64(h, i64::from(s.left.to_q8()) << 16 | i64::from(s.right.to_q8()));
        rec(TickRec(p.x.0, p.y.0, p.theta.0, p.theta_frac, h, sink.hash.lines, sink.hash.hash));
    }
}
