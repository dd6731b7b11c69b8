//! An f64 truth simulation for the estimator tests: the report's state
//! update with noisy speeds, f64 ray casting for the lidars (mapped to raw
//! readings through the inverse of the lidar models), a noisy compass, and
//! a scripted drive that stays inside the arena.
#![allow(dead_code)]

use paperbot::config;
use paperbot::math::{Angle, Dt, Length};
use paperbot::model::estimator::{Estimator, Update};
use paperbot::model::lidar::LidarMount;
use paperbot::model::lidar::{LidarModel, Range};
use paperbot::model::measurement::LidarId;
use paperbot::model::{step, Motion, Pose, ServoCmd};
use std::f64::consts::{PI, TAU};

pub use paperbot::sim::noise::Rng;

/// Relative spread of the timed runs, per motion (rms over the command
/// pairs of std/mean of the ten trials), from `tests/data/lab1/servo_runs.csv`.
#[derive(Clone, Copy, Debug)]
pub struct Spread {
    pub forward: f64,
    pub backward: f64,
    pub cw: f64,
    pub ccw: f64,
}

pub fn lab_spread() -> Spread {
    let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/lab1/servo_runs.csv"))
        .expect("servo_runs.csv");
    let mut groups: std::collections::BTreeMap<(String, String, String), Vec<f64>> = Default::default();
    for line in text.lines().skip(1) {
        let f: Vec<&str> = line.split(',').collect();
        groups.entry((f[0].into(), f[1].into(), f[2].into())).or_default().push(f[4].parse().unwrap());
    }
    let rms_cv = |motion: &str| {
        let cvs: Vec<f64> = groups
            .iter()
            .filter(|(k, _)| k.0 == motion)
            .map(|(_, v)| {
                let n = v.len() as f64;
                let m = v.iter().sum::<f64>() / n;
                let var = v.iter().map(|t| (t - m).powi(2)).sum::<f64>() / (n - 1.0);
                var.sqrt() / m
            })
            .collect();
        (cvs.iter().map(|c| c * c).sum::<f64>() / cvs.len() as f64).sqrt()
    };
    Spread { forward: rms_cv("forward"), backward: rms_cv("backward"), cw: rms_cv("cw"), ccw: rms_cv("ccw") }
}

/// Command pairs the lab measured (one per motion).
pub const FORWARD_CMD: (u8, u8) = (110, 61);
pub const CW_CMD: (u8, u8) = (105, 113);
pub const CCW_CMD: (u8, u8) = (65, 60);
pub const STOP_CMD: (u8, u8) = (90, 90);

pub fn motion_of(cmd: (u8, u8)) -> Motion {
    config::actuators::MODEL.motion_from_commands(ServoCmd::from_int(cmd.0), ServoCmd::from_int(cmd.1))
}

/// The true pose: the one host pose type (f64 mm, radians clockwise from
/// north).
pub use paperbot::sim::body::PoseF64;

pub fn d_mm() -> f64 {
    config::geometry::ROTATION_TO_REFERENCE.to_mm_f64()
}

/// The report's equations in f64 (straight with an extra heading drift
/// rate `drift` rad/s: the noise N_w while driving straight).
pub fn truth_step(p: PoseF64, motion_kind: i8, v: f64, w: f64, drift: f64, dt: f64) -> PoseF64 {
    match motion_kind {
        0 => p,
        1 => PoseF64 { x: p.x + v * dt * p.theta.cos(), y: p.y + v * dt * p.theta.sin(), theta: p.theta + drift * dt },
        _ => {
            let th1 = p.theta + w * dt;
            let d = d_mm();
            PoseF64 { x: p.x - d * (p.theta.cos() - th1.cos()), y: p.y - d * (p.theta.sin() - th1.sin()), theta: th1 }
        }
    }
}

/// What a lidar at `mount` reads at `p` in an `lx` x `wy` box, as the
/// model output (distance from the reference point along the beam): the
/// nearest wall point in the sensor's cone (`config::lidar::CONE_DEG`, f64,
/// `sim::realism`) less the mount's setback.
pub fn true_range(p: PoseF64, mount: &LidarMount, lx: f64, wy: f64) -> f64 {
    let (f, r) = (mount.forward.to_mm_f64(), mount.right.to_mm_f64());
    let dir = mount.direction.to_radians_f64();
    let (s, c) = p.theta.sin_cos();
    let mx = p.x + f * c - r * s;
    let my = p.y + f * s + r * c;
    let cone = paperbot::sim::realism::Realism {
        cone_deg: paperbot::config::lidar::CONE_DEG,
        ..paperbot::sim::realism::Realism::IDEAL
    };
    let arena = paperbot::sim::arena::Arena::from_mm_f64(lx, wy);
    let t = paperbot::sim::realism::lidar_range(&arena, mx, my, p.theta + dir, &cone).map_or(f64::INFINITY, |(t, _)| t);
    t + f * dir.cos() + r * dir.sin()
}

/// The raw reading (integer mm) a lidar with `model` gives for a true model output `z`.
pub fn raw_reading(model: &LidarModel, z: f64) -> f64 {
    let slope = model.slope_q16 as f64 / 65536.0;
    (z - model.intercept.to_mm_f64()) / slope
}

pub fn wrap(a: f64) -> f64 {
    (a + PI).rem_euclid(TAU) - PI
}

/// Scenario knobs.
#[derive(Clone, Debug)]
pub struct Scenario {
    pub seed: u64,
    pub seconds: f64,
    /// The estimator's start pose error: (dx, dy mm, dtheta deg).
    pub start_error: (f64, f64, f64),
    /// Lidar dropouts: (which, from s, to s).
    pub dropouts: Vec<(LidarId, f64, f64)>,
    /// Probability of a spurious lidar reading / a disturbed compass reading.
    pub lidar_outlier_p: f64,
    pub compass_outlier_p: f64,
    pub lidar_sigma: f64,
    pub compass_sigma_deg: f64,
    /// Relative speed spread per segment (None: the lab's).
    pub spread: Option<Spread>,
    /// Stop for this long every few waypoints, s.
    pub pause_s: f64,
}

impl Scenario {
    pub fn new(seed: u64) -> Scenario {
        Scenario {
            seed,
            seconds: 60.0,
            start_error: (0.0, 0.0, 0.0),
            dropouts: Vec::new(),
            lidar_outlier_p: 0.01,
            compass_outlier_p: 0.01,
            lidar_sigma: 1.6,
            compass_sigma_deg: 2.5,
            spread: None,
            pause_s: 0.5,
        }
    }
}

/// What a run produced.
#[derive(Clone, Debug, Default)]
pub struct RunResult {
    /// Per tick: time s, position error mm, heading error deg (estimate).
    pub est: Vec<(f64, f64, f64)>,
    /// The same for dead reckoning.
    pub dr: Vec<(f64, f64, f64)>,
    /// The same for the best hypothesis (the reported pose follows it).
    pub best: Vec<(f64, f64, f64)>,
    pub injected_lidar_outliers: u32,
    pub injected_compass_outliers: u32,
    /// Per tick: (t, truth, commands, front reading, right reading, compass deg) for logs.
    pub log: Vec<LogRow>,
    pub truth: Vec<(f64, PoseF64)>,
    /// Per tick: the estimate after the tick.
    pub poses: Vec<Pose>,
    /// The estimator's start pose.
    pub start: Pose,
    pub stats: Option<paperbot::model::estimator::EstimatorStats>,
    pub min_wall_clearance: f64,
    pub max_sigma_pos_mm: f64,
}

#[derive(Clone, Debug)]
pub struct LogRow {
    pub t_ms: u32,
    pub cmd: (u8, u8),
    pub front: Option<u16>,
    pub right: Option<u16>,
    pub heading_deg: Option<f64>,
}

pub fn rms(v: &[(f64, f64, f64)], from_s: f64) -> (f64, f64) {
    let sel: Vec<_> = v.iter().filter(|e| e.0 >= from_s).collect();
    let n = sel.len().max(1) as f64;
    ((sel.iter().map(|e| e.1 * e.1).sum::<f64>() / n).sqrt(), (sel.iter().map(|e| e.2 * e.2).sum::<f64>() / n).sqrt())
}

pub fn max_err(v: &[(f64, f64, f64)], from_s: f64, to_s: f64) -> (f64, f64) {
    v.iter().filter(|e| e.0 >= from_s && e.0 < to_s).fold((0.0, 0.0), |a, e| (a.0.max(e.1), a.1.max(e.2.abs())))
}

/// The waypoint loop: inside the box with at least 130 mm to every wall.
fn waypoints(rng: &mut Rng) -> Vec<(f64, f64)> {
    let base = [(150.0, 150.0), (600.0, 160.0), (610.0, 340.0), (380.0, 250.0), (160.0, 340.0), (600.0, 330.0)];
    base.iter().map(|&(x, y)| (x + 20.0 * (rng.uniform() - 0.5), y + 20.0 * (rng.uniform() - 0.5))).collect()
}

/// Runs the scripted drive with the estimator (and dead reckoning beside
/// it) at the loop rate. `observe` sees the estimator after every tick.
pub fn run(sc: &Scenario, mut observe: impl FnMut(f64, &Estimator, PoseF64)) -> RunResult {
    let mut rng = Rng::new(sc.seed);
    let spread = sc.spread.unwrap_or_else(lab_spread);
    let (lx, wy) = (config::arena::LENGTH_X.to_mm_f64(), config::arena::WIDTH_Y.to_mm_f64());
    let wps = waypoints(&mut rng);
    let mut truth = PoseF64 { x: wps[0].0, y: wps[0].1, theta: 0.3 * (rng.uniform() - 0.5) };
    let start = PoseF64 {
        x: truth.x + sc.start_error.0,
        y: truth.y + sc.start_error.1,
        theta: truth.theta + sc.start_error.2.to_radians(),
    };
    let mut est = Estimator::new(start.to_pose());
    let mut dr = start.to_pose();
    let tick_us = 1_000_000 / config::timing::LOOP_HZ;
    let dt = Dt::from_micros(tick_us).unwrap();
    let dt_s = f64::from(tick_us) / 1e6;
    let lidar_period_ms = config::lidar::TIMING_BUDGET_US / 1000;
    let axle = config::geometry::AXLE_LENGTH.to_mm_f64();

    let mut res = RunResult { min_wall_clearance: f64::INFINITY, start: start.to_pose(), ..Default::default() };
    let mut wp = 1usize;
    let mut cmd = STOP_CMD;
    let mut seg_factor = 1.0;
    let mut seg_drift = 0.0;
    let mut pause_until = 0.0;
    let mut next_front_ms = 0u32;
    let mut next_right_ms = lidar_period_ms / 2;
    // the truth a lidar reading describes
    let mut back = super::reading_age::Lagged::new(truth);
    let ticks = (sc.seconds / dt_s).round() as u32;
    for tick in 0..ticks {
        let t_ms = tick * (tick_us / 1000);
        let t = f64::from(t_ms) / 1000.0;
        // --- the oracle driver decides from the truth ---
        let (tx, ty) = wps[wp % wps.len()];
        let (ex, ey) = (tx - truth.x, ty - truth.y);
        let dist = (ex * ex + ey * ey).sqrt();
        let bearing_err = wrap(ey.atan2(ex) - truth.theta);
        let new_cmd = if t < pause_until {
            STOP_CMD
        } else if dist < 15.0 {
            wp += 1;
            if wp % 3 == 0 {
                pause_until = t + sc.pause_s;
            }
            STOP_CMD
        } else if bearing_err.abs() > 6f64.to_radians()
            && !(cmd == FORWARD_CMD && bearing_err.abs() < 15f64.to_radians())
        {
            if bearing_err > 0.0 {
                CW_CMD
            } else {
                CCW_CMD
            }
        } else {
            FORWARD_CMD
        };
        if new_cmd != cmd {
            cmd = new_cmd;
            let k = match cmd {
                FORWARD_CMD => spread.forward,
                CW_CMD => spread.cw,
                CCW_CMD => spread.ccw,
                _ => 0.0,
            };
            seg_factor = 1.0 + k * rng.normal();
            let v = match motion_of(cmd) {
                Motion::Straight(v) => v.to_mps_f64() * 1000.0,
                _ => 0.0,
            };
            seg_drift = spread.forward * v / axle * rng.normal();
        }
        let motion = motion_of(cmd);
        // --- truth moves ---
        let (kind, v, w) = match motion {
            Motion::Stop => (0, 0.0, 0.0),
            Motion::Straight(v) => (1, v.to_mps_f64() * 1000.0 * seg_factor, 0.0),
            Motion::Turn(w) => (2, 0.0, w.to_rad_s_f64() * seg_factor),
        };
        truth = truth_step(truth, kind, v, w, seg_drift, dt_s);
        back.push(truth);
        res.min_wall_clearance = res.min_wall_clearance.min(truth.x).min(truth.y).min(lx - truth.x).min(wy - truth.y);
        // --- estimator and dead reckoning ---
        est.predict(motion, dt);
        dr = step(&dr, motion, dt);
        let mut row = LogRow { t_ms, cmd, front: None, right: None, heading_deg: None };
        let dropped = |which: LidarId| sc.dropouts.iter().any(|&(w, a, b)| w == which && t >= a && t < b);
        for (which, next, model, mount) in [
            (LidarId::Front, &mut next_front_ms, &config::lidar::FRONT, &config::geometry::FRONT_LIDAR),
            (LidarId::Right, &mut next_right_ms, &config::lidar::RIGHT, &config::geometry::RIGHT_LIDAR),
        ] {
            if t_ms < *next || dropped(which) {
                continue;
            }
            *next = t_ms + lidar_period_ms;
            let z = true_range(back.read(), mount, lx, wy);
            let mut reading = raw_reading(model, z) + sc.lidar_sigma * rng.normal();
            if rng.chance(sc.lidar_outlier_p) {
                reading = 20.0 + 1100.0 * rng.uniform();
                res.injected_lidar_outliers += 1;
            }
            let reading = reading.round().clamp(0.0, 8191.0) as u16;
            match which {
                LidarId::Front => row.front = Some(reading),
                LidarId::Right => row.right = Some(reading),
            }
            if let Range::Target(d) = model.range(reading) {
                let _: Update = est.update_lidar(which, d);
            }
        }
        let mut heading = truth.theta + sc.compass_sigma_deg.to_radians() * rng.normal();
        if rng.chance(sc.compass_outlier_p) {
            let sign = if rng.chance(0.5) { 1.0 } else { -1.0 };
            heading += sign * (30.0 + 60.0 * rng.uniform()).to_radians();
            res.injected_compass_outliers += 1;
        }
        // logged (and used) to 0.01 degree, as the replay tool reads it
        let heading_deg = (heading.to_degrees().rem_euclid(360.0) * 100.0).round() / 100.0;
        row.heading_deg = Some(heading_deg);
        est.update_heading(Angle::from_degrees_f64(heading_deg));
        res.log.push(row);
        res.truth.push((t, truth));
        observe(t, &est, truth);
        let err = |p: &Pose| {
            let (x, y) = (p.x.to_mm_f64(), p.y.to_mm_f64());
            let dth = wrap(p.theta.to_radians_f64() - truth.theta).to_degrees();
            (t, ((x - truth.x).powi(2) + (y - truth.y).powi(2)).sqrt(), dth)
        };
        res.est.push(err(&est.pose()));
        res.best.push(err(&est.best_pose()));
        res.poses.push(est.pose());
        res.dr.push(err(&dr));
        let sig = est.sigma();
        res.max_sigma_pos_mm = res.max_sigma_pos_mm.max(sig.x.to_mm_f64()).max(sig.y.to_mm_f64());
    }
    res.stats = Some(est.stats());
    res
}

/// The test arena's size as Lengths.
pub fn arena_mm() -> (Length, Length) {
    (config::arena::LENGTH_X, config::arena::WIDTH_Y)
}

/// The run as a replay log (`t_ms,left_cmd,right_cmd,front_mm,right_mm,heading_deg`):
/// row k holds the commands decided at tick k and the readings taken at the
/// end of tick k - 1 (time 10 k ms), the order the replay tool applies them.
pub fn replay_log(res: &RunResult) -> String {
    use std::fmt::Write as _;
    let mut s = String::from("t_ms,left_cmd,right_cmd,front_mm,right_mm,heading_deg\n");
    let opt = |v: Option<u16>| v.map(|r| r.to_string()).unwrap_or_default();
    for (k, row) in res.log.iter().enumerate() {
        let prev = if k > 0 { res.log.get(k - 1) } else { None };
        let _ = writeln!(
            s,
            "{},{},{},{},{},{}",
            row.t_ms,
            row.cmd.0,
            row.cmd.1,
            opt(prev.and_then(|p| p.front)),
            opt(prev.and_then(|p| p.right)),
            prev.and_then(|p| p.heading_deg).map(|h| format!("{h:.2}")).unwrap_or_default()
        );
    }
    s
}

/// An estimator sure of itself at `at`: started there and fed 2 s of the
/// exact readings its own arena model gives there (both lidars and the
/// compass every 10 ms tick), standing still.
pub fn settled(at: Pose) -> Estimator {
    let tick = Dt::from_micros_saturating(10_000);
    let arena = paperbot::model::measurement::Arena::DEFAULT;
    let mut est = Estimator::new(at);
    for _ in 0..200 {
        est.predict(Motion::Stop, tick);
        for id in [LidarId::Front, LidarId::Right] {
            if let Some(z) = paperbot::model::measurement::expected_lidar(&arena, &at, id) {
                est.update_lidar(id, z);
            }
        }
        est.update_heading(at.theta);
    }
    est
}
