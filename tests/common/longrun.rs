//! Shared by the long simulated runs (tests/control/soak.rs, tests/control/faults_long.rs):
//! a random operator typing commands, and a watcher that checks every tick
//! of the firmware against the invariants that must hold however long it
//! runs: every output line well formed, fault counters never going back,
//! the deadman honoured, the estimate inside the arena with a valid
//! covariance.

#![allow(dead_code)] // each test file uses its own part

use paperbot::config;
use paperbot::control::protocol::{classify_line, parse_telemetry_row, FaultCounters, LineKind, OK};
use paperbot::control::{Mode, TICK_US};
use paperbot::sim::noise::Rng;
use paperbot::sim::robot::SimRobot;

/// Uniform integer in `lo..=hi`.
pub fn range(rng: &mut Rng, lo: i64, hi: i64) -> i64 {
    lo + (rng.next_u64() % (hi - lo + 1) as u64) as i64
}

/// `v / 10^decimals` as the protocol writes it.
pub fn fixed(v: i64, decimals: u32) -> String {
    let scale = 10i64.pow(decimals);
    let sign = if v < 0 { "-" } else { "" };
    if decimals == 0 {
        format!("{v}")
    } else {
        format!("{sign}{}.{:0w$}", v.abs() / scale, v.abs() % scale, w = decimals as usize)
    }
}

/// A random operator: mostly driving commands (timed and untimed, any
/// speed the protocol accepts, raw servo commands anywhere in 0..180),
/// sometimes trims, rate changes, status, a short calibration sweep, a
/// re-localisation at the true pose, or a garbage line.
pub fn random_command(rng: &mut Rng, robot: &SimRobot) -> String {
    let dur = |rng: &mut Rng| -> String {
        if rng.next_u64() % 2 == 0 {
            format!(" {}", fixed(range(rng, 1, 4_000), 3))
        } else {
            String::new()
        }
    };
    match rng.next_u64() % 100 {
        0..=24 => {
            let kw = if rng.next_u64() % 3 == 0 { "back" } else { "fwd" };
            format!("{kw} {}{}", fixed(range(rng, 1, config::serial::MAX_SPEED_MM_S as i64), 3), dur(rng))
        }
        25..=49 => {
            let kw = if rng.next_u64() % 2 == 0 { "cw" } else { "ccw" };
            format!("{kw} {}{}", fixed(range(rng, 1, config::serial::MAX_TURN_MRAD_S as i64), 3), dur(rng))
        }
        50..=59 => format!("servo {} {}{}", fixed(range(rng, 0, 18_000), 2), fixed(range(rng, 0, 18_000), 2), dur(rng)),
        60..=69 => "stop".into(),
        // trims the actuator model covers (neutral outside the measured ranges)
        70..=73 => format!("trim {} {}", ["l", "r"][(rng.next_u64() % 2) as usize], fixed(range(rng, -300, 300), 2)),
        74..=77 => format!("rate {}", [0, 1, 10, 50, 100][(rng.next_u64() % 5) as usize]),
        78..=81 => "status".into(),
        82 => "help".into(),
        83 => format!("cal {}", config::serial::MIN_CAL_SAMPLES),
        84..=87 => {
            let t = robot.truth();
            let deg = t.theta.to_degrees().rem_euclid(360.0);
            format!("pose {:.0} {:.0} {}", t.x, t.y, fixed((deg * 1000.0).round() as i64 % 360_000, 3))
        }
        88..=95 => {
            // a malformed line: a refusal, nothing changes
            let junk = ["fwd", "fwd 9", "cw -1", "servo 181 0", "pose 1e3 0 0", "jump", "trim x 1", "fwd 0.1 2 3"];
            junk[(rng.next_u64() % junk.len() as u64) as usize].into()
        }
        _ => {
            // raw bytes, up to a too-long line
            let n = range(rng, 1, 80) as usize;
            (0..n).map(|_| char::from(b' ' + (rng.next_u64() % 95) as u8)).collect()
        }
    }
}

/// What the watcher saw over a run.
#[derive(Default, Debug)]
pub struct Seen {
    pub ticks: u64,
    pub lines: u64,
    pub rows: u64,
    pub commands_ok: u64,
    pub refusals: u64,
    pub deadman_stops: u64,
    pub last_faults: FaultCounters,
    /// Largest distance of the estimate outside the arena, mm.
    pub worst_outside_mm: f64,
    /// Largest estimate-to-truth distance, mm, and heading error, degrees,
    /// at the checkpoints (every `check_error_every` ticks).
    pub worst_error_mm: f64,
    pub worst_error_deg: f64,
    /// Every checkpoint's (distance mm, heading error degrees).
    pub errors: Vec<(f64, f64)>,
}

impl Seen {
    /// The `q`-quantile (0..=1) of the checkpoint errors: (mm, degrees).
    pub fn error_quantile(&self, q: f64) -> (f64, f64) {
        let pick = |mut v: Vec<f64>| -> f64 {
            if v.is_empty() {
                return 0.0;
            }
            v.sort_by(f64::total_cmp);
            v[((v.len() - 1) as f64 * q).round() as usize]
        };
        (pick(self.errors.iter().map(|e| e.0).collect()), pick(self.errors.iter().map(|e| e.1).collect()))
    }
}

/// Checks the firmware after every tick (see the module docs).
#[derive(Default)]
pub struct Watcher {
    pub seen: Seen,
    /// Loop clock (us) of the last accepted command.
    last_ok_us: u64,
}

fn counters(f: &FaultCounters) -> [u32; 6] {
    [f.bus, f.timeout, f.missing, f.bad_sample, f.rejected_outliers, f.overruns]
}

impl Watcher {
    /// Reads the robot's output since the last call and checks the state.
    pub fn after_tick(&mut self, robot: &mut SimRobot) {
        self.seen.ticks += 1;
        let now = robot.controller().clock_us();
        for line in robot.take_output() {
            self.seen.lines += 1;
            assert!(line.len() <= paperbot::control::protocol::MAX_OUT_LINE, "{line}");
            if line.starts_with(OK) {
                self.seen.commands_ok += 1;
                self.last_ok_us = now;
            } else if line.starts_with("# err") {
                self.seen.refusals += 1;
            } else if line.starts_with("# deadman") {
                self.seen.deadman_stops += 1;
            }
            if classify_line(&line) == LineKind::Row {
                let row = parse_telemetry_row(&line).unwrap_or_else(|e| panic!("bad row {line:?}: {e:?}"));
                self.seen.rows += 1;
                // counters never go back (they saturate, never wrap)
                for (new, old) in counters(&row.faults).iter().zip(counters(&self.seen.last_faults)) {
                    assert!(*new >= old, "fault counter went back: {:?} -> {:?}", self.seen.last_faults, row.faults);
                }
                self.seen.last_faults = row.faults;
            }
        }
        // stopped means the servos are at their neutral commands
        let stop = robot.controller().model().stop();
        if robot.controller().mode() == Mode::Idle {
            let servos = *robot.controller_mut().servos();
            assert_eq!((servos.left, servos.right), (stop.left, stop.right), "idle but driving");
        }
        let ctl = robot.controller();
        // the deadman: an untimed motion never outlives DEADMAN_MS without a command
        let untimed = ctl.mode() != Mode::Idle && ctl.status().remaining_ms.is_none();
        let quiet = now.saturating_sub(self.last_ok_us);
        let limit = u64::from(config::timing::DEADMAN_MS) * 1_000 + 2 * u64::from(TICK_US);
        assert!(!untimed || quiet <= limit, "still driving {:?} after {quiet} us without a command", ctl.mode());
        // the estimate stays in (or near) the arena, its covariance valid
        let p = ctl.pose();
        let (x, y) = (p.x.to_mm_f64(), p.y.to_mm_f64());
        let a = robot.cfg.arena;
        let outside = (-x).max(x - a.length_x_mm()).max(-y).max(y - a.width_y_mm()).max(0.0);
        self.seen.worst_outside_mm = self.seen.worst_outside_mm.max(outside);
        for d in ctl.estimator().covariance_diagonal() {
            assert!(d > 0 && d <= 1 << 30, "covariance {:?}", ctl.estimator().covariance());
        }
    }

    /// Estimate-to-truth error now (after the estimator had time to settle).
    pub fn check_error(&mut self, robot: &SimRobot) {
        let s = robot.sample();
        let (mm, deg) = (s.estimate.distance(&s.truth), s.estimate.heading_error(&s.truth).abs().to_degrees());
        self.seen.worst_error_mm = self.seen.worst_error_mm.max(mm);
        self.seen.worst_error_deg = self.seen.worst_error_deg.max(deg);
        self.seen.errors.push((mm, deg));
    }
}
