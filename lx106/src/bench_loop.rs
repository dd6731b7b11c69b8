//! Instruction counts of the estimator (predict per motion, the three
//! corrections, the measurement model) and of one control-loop tick
//! (`Controller::tick` over the trait doubles of `crate::scripts`: sensors
//! that return `WouldBlock` or one canned reading, servos that keep the
//! command, a sink that discards the lines), with the tick's bar.

use crate::println;
use crate::rt::count;
use crate::scripts::{compass_sample, controller, lidar_sample, NullSink, Rng, ScriptController};
use core::hint::black_box;
use paperbot::control::TICK_US;
use paperbot::math::{Angle, Dt, Length};
use paperbot::model::estimator::{Estimator, Update};
use paperbot::model::measurement::{expected_heading, expected_lidar, Arena, LidarId};
use paperbot::model::{Motion, Pose};

/// Most instructions one control tick without I/O may take (issue 6): the
/// tick's own work (state update and estimator prediction, sensor servicing
/// with readings already in hand, at most
/// `config::timing::MAX_CORRECTIONS_PER_TICK` corrections, deadman, servo
/// commands), not the formatting of a telemetry row for the UART, which is
/// reported separately. Issue 29 replaced the bar of 3,000 (one 3-state
/// filter) by 15,000: one 7-state hypothesis, the located robot's steady
/// state, and the same tick with [`HYPOTHESES`] hypotheses (while the
/// estimator is ambiguous: the leader's whole filter and the others'
/// lighter ones, one of them corrected with the leader).
pub const TICK_MAX: u32 = 15_000;
/// Hypotheses the worst tick carries (the config's most).
const HYPOTHESES: usize = paperbot::config::estimator::MAX_HYPOTHESES;
/// Corrections one tick applies when all three sensors have a fresh reading.
const CORRECTIONS: u32 = paperbot::config::timing::MAX_CORRECTIONS_PER_TICK as u32;

/// Poses the estimator is counted at: mid-arena, beams square enough on
/// their walls and clear of corners (so the lidar corrections are accepted:
/// their longest path), headings in every quadrant.
const POSES: [(i32, i32, i32); 8] = [
    (380, 250, 0),
    (380, 250, 10),
    (380, 250, 90),
    (380, 250, 170),
    (380, 250, 185),
    (380, 250, 270),
    (300, 200, 355),
    (450, 300, 95),
];

pub fn pose(&(x, y, d): &(i32, i32, i32)) -> Pose {
    Pose::from_mm(x, y, Angle::from_millidegrees(d * 1000))
}

const MOTIONS: [(&str, &[u8]); 3] = [("Stop", b"stop\n"), ("Straight", b"fwd 0.13\n"), ("Turn", b"cw 2.5\n")];

fn motion(name: &str) -> Motion {
    use paperbot::math::{Speed, TurnRate};
    match name {
        "Straight" => Motion::Straight(Speed::from_mm_s(130)),
        "Turn" => Motion::Turn(TurnRate::from_mrad_s(2500)),
        _ => Motion::Stop,
    }
}

/// (name, worst count, note)
pub type Row = (&'static str, u32, &'static str);

pub fn estimator_rows() -> [Row; 9] {
    let dt = Dt::from_micros_saturating(10_000);
    let arena = Arena::DEFAULT;
    let predict = |name: &str, warm: bool| {
        POSES
            .iter()
            .map(|p| {
                let mut e = Estimator::new(pose(p));
                if warm {
                    e.predict(motion(name), dt); // the pose's sin/cos cache is current
                }
                let m = motion(name); // not counted: a command's conversion
                count(|| black_box(&mut e).predict(black_box(m), black_box(dt)))
            })
            .max()
            .unwrap_or(0)
    };
    let mut all_accepted = true;
    let mut lidar = |id: LidarId| {
        POSES
            .iter()
            .map(|p| {
                let mut e = Estimator::new(pose(p));
                let z = expected_lidar(&arena, &e.pose(), id).unwrap_or(Length::from_mm(100));
                let z = z.saturating_add(Length::from_mm(3));
                let mut u = Update::Unusable;
                let n = count(|| u = black_box(&mut e).update_lidar(black_box(id), black_box(z)));
                all_accepted &= u == Update::Accepted;
                n
            })
            .max()
            .unwrap_or(0)
    };
    let front = lidar(LidarId::Front);
    let right = lidar(LidarId::Right);
    let heading = POSES
        .iter()
        .map(|p| {
            let mut e = Estimator::new(pose(p));
            let h = e.pose().theta.wrapping_add(Angle::from_millidegrees(1_000));
            let mut u = Update::Unusable;
            let n = count(|| u = black_box(&mut e).update_heading(black_box(h)));
            all_accepted &= u == Update::Accepted;
            n
        })
        .max()
        .unwrap_or(0);
    let exp_lidar = POSES
        .iter()
        .map(|p| {
            let q = pose(p);
            count(|| {
                black_box(expected_lidar(black_box(&arena), black_box(&q), black_box(LidarId::Front)));
            })
        })
        .max()
        .unwrap_or(0);
    let exp_heading = count(|| {
        black_box(expected_heading(black_box(&pose(&POSES[0]))));
    });
    if !all_accepted {
        println!("      WARNING: a counted correction was not accepted (the count is not its longest path)");
    }
    [
        ("estimator: predict Stop (10 ms)", predict("Stop", true), ""),
        ("estimator: predict Straight, steady state", predict("Straight", true), "pose's sin/cos cache current"),
        ("estimator: predict Turn, steady state", predict("Turn", true), "pose's sin/cos cache current"),
        ("estimator: predict Straight, heading just set from outside", predict("Straight", false), "cold cache"),
        ("estimator: update_lidar front (accepted)", front, "incl. the beam geometry; no division (Newton reciprocal)"),
        ("estimator: update_lidar right (accepted)", right, ""),
        ("estimator: update_heading (accepted)", heading, "no division"),
        ("measurement: expected_lidar front", exp_lidar, "Beam + one math::div_i64 (host-side: not in the firmware)"),
        ("measurement: expected_heading", exp_heading, ""),
    ]
}

/// An estimator with `n` hypotheses seeded 20 mm apart from `at` (30 mm
/// sigma: each accepts a reading).
fn seeded(at: Pose, n: usize) -> Estimator {
    use paperbot::model::estimator::Seed;
    let sigma = Length::from_mm(30);
    let seeds: [Seed; HYPOTHESES] = core::array::from_fn(|i| {
        let d = 20 * i as i32;
        let q = Pose::new(at.x, paperbot::math::Coord(at.y.0 + (i64::from(d) << 32)), at.theta);
        Seed { pose: q, sigma_x: sigma, sigma_y: sigma, weight: 1 }
    });
    let mut e = Estimator::new(at);
    e.seed(seeds.get(..n).unwrap_or(&seeds));
    e
}

/// An estimator's prediction (a turn: the longest) and one lidar correction
/// (accepted by every hypothesis: the longest path), with `n` hypotheses
/// seeded 20 mm apart around each pose (30 mm sigma: each accepts): the
/// worst over the poses.
pub fn predict_and_correct(n: usize) -> u32 {
    let dt = Dt::from_micros_saturating(10_000);
    let arena = Arena::DEFAULT;
    POSES
        .iter()
        .map(|p| {
            let at = pose(p);
            let mut e = seeded(at, n);
            let m = motion("Turn");
            e.predict(m, dt);
            let z = expected_lidar(&arena, &e.pose(), LidarId::Front).unwrap_or(Length::from_mm(100));
            count(|| {
                black_box(&mut e).predict(black_box(m), black_box(dt));
                black_box(black_box(&mut e).update_lidar(black_box(LidarId::Front), black_box(z)));
            })
        })
        .max()
        .unwrap_or(0)
}

/// The standing tick that learns the lidar spot's share from a full batch
/// (`model::estimator`'s spot.rs: its two divisions wait for a tick whose
/// prediction is a stop), with one lidar correction, `n` hypotheses seeded
/// as [`predict_and_correct`]'s: the batch filled by readings met off
/// square (30 degrees), each after 10 mm driven to and fro (counted); the
/// worst over the poses whose beam meets no corner (a reading near one is
/// not used), and how many those were.
pub fn standing_learning_tick(n: usize) -> (u32, usize) {
    let dt = Dt::from_micros_saturating(10_000);
    let arena = Arena::DEFAULT;
    let mut learned = 0;
    let worst = POSES
        .iter()
        .filter_map(|p| {
            let at = pose(p);
            let at = Pose::new(at.x, at.y, at.theta.wrapping_add(Angle::from_millidegrees(30_000)));
            let mut e = seeded(at, n);
            // the batch: a reading after each 10.4 mm driven
            for i in 0..2 * paperbot::config::estimator::SPOT_BATCH {
                let v = if i % 2 == 0 { 130 } else { -130 };
                for _ in 0..8 {
                    e.predict(Motion::Straight(paperbot::math::Speed::from_mm_s(v)), dt);
                }
                if let Some(z) = expected_lidar(&arena, &e.pose(), LidarId::Front) {
                    e.update_lidar(LidarId::Front, z.saturating_add(Length::from_mm(3)));
                }
            }
            let before = e.lidar_spot().1;
            let z = expected_lidar(&arena, &e.pose(), LidarId::Front).unwrap_or(Length::from_mm(100));
            let m = motion("Stop");
            let c = count(|| {
                black_box(&mut e).predict(black_box(m), black_box(dt));
                black_box(black_box(&mut e).update_lidar(black_box(LidarId::Front), black_box(z)));
            });
            let learns = e.lidar_spot().1 == before + 1;
            learned += usize::from(learns);
            learns.then_some(c)
        })
        .max()
        .unwrap_or(0);
    (worst, learned)
}

/// A controller driving `cmd` for a few ticks at `p`, telemetry at `rate`.
fn ready(p: &Pose, cmd: &[u8], rate: &[u8], now: &mut u32) -> ScriptController {
    let mut c = controller(*p);
    let mut sink = NullSink;
    c.feed_bytes(rate, &mut sink);
    c.feed_bytes(cmd, &mut sink);
    for _ in 0..3 {
        c.tick(*now, &mut sink);
        *now = now.wrapping_add(TICK_US);
    }
    c
}

/// Fresh readings for all three sensors, consistent with the estimate.
fn fresh(c: &mut ScriptController, rng: &mut Rng) {
    let arena = Arena::DEFAULT;
    let p = c.pose();
    let f = expected_lidar(&arena, &p, LidarId::Front);
    let r = expected_lidar(&arena, &p, LidarId::Right);
    c.front().next = Some(Ok(lidar_sample(LidarId::Front, f, 0)));
    c.right().next = Some(Ok(lidar_sample(LidarId::Right, r, 0)));
    let h = expected_heading(&p).wrapping_add(Angle::from_millidegrees(500));
    c.compass().next = Some(Ok(compass_sample(h, rng)));
}

/// A controller turning in place with fresh readings from all three
/// sensors (the bar's tick: one correction), with a telemetry row this tick
/// when `row`, and the `now_us` to tick it at (for `src/bin/tick_profile.rs`).
#[allow(dead_code)] // used by src/bin/tick_profile.rs
pub fn worst_tick_setup(p: Pose, row: bool) -> (ScriptController, u32) {
    let mut now = 0x1000u32;
    let rate: &[u8] = if row { b"rate 100\n" } else { b"rate 0\n" };
    let mut c = ready(&p, b"cw 2.5\n", rate, &mut now);
    fresh(&mut c, &mut Rng(0x7ec4_0001));
    (c, now)
}

pub struct TickRow {
    pub name: &'static str,
    /// Worst count per motion (Stop, Straight, Turn).
    pub counts: [u32; 3],
}

impl TickRow {
    pub fn worst(&self) -> u32 {
        self.counts.iter().copied().max().unwrap_or(0)
    }
}

/// One tick, measured: plain; with fresh readings (3 corrections); with a
/// telemetry row; both. Worst over [`POSES`] per motion.
pub fn tick_rows() -> ([TickRow; 4], u32) {
    let mut rng = Rng(0x7ec4_0001);
    let mut not_accepted = 0u32;
    let mut case = |readings: bool, telemetry: bool| -> [u32; 3] {
        MOTIONS.map(|(_, cmd)| {
            POSES
                .iter()
                .map(|p| {
                    let mut now = 0x1000u32;
                    // telemetry at the loop rate: a row every tick; else off
                    let rate: &[u8] = if telemetry { b"rate 100\n" } else { b"rate 0\n" };
                    let mut c = ready(&pose(p), cmd, rate, &mut now);
                    if readings {
                        fresh(&mut c, &mut rng);
                    }
                    let before = c.estimator().stats();
                    let mut sink = NullSink;
                    let n = count(|| black_box(&mut c).tick(black_box(now), &mut sink));
                    let after = c.estimator().stats();
                    if readings {
                        let acc = |s: paperbot::model::estimator::EstimatorStats| {
                            s.front.accepted + s.right.accepted + s.compass.accepted
                        };
                        if acc(after) != acc(before) + CORRECTIONS {
                            not_accepted += 1;
                        }
                    }
                    n
                })
                .max()
                .unwrap_or(0)
        })
    };
    let rows = [
        TickRow { name: "tick: no fresh reading, no telemetry", counts: case(false, false) },
        TickRow {
            name: "tick: fresh lidar x2 + compass (MAX_CORRECTIONS_PER_TICK = 1 correction, the others wait)",
            counts: case(true, false),
        },
        TickRow { name: "tick: telemetry row into a discarding sink", counts: case(false, true) },
        TickRow { name: "tick: fresh readings + telemetry row (worst case)", counts: case(true, true) },
    ];
    (rows, not_accepted)
}

/// What the lx106's missing multiply-high and divide cost: the runtime
/// helpers behind i64 arithmetic and u32 division, as the core uses them.
pub fn helper_rows() -> [Row; 7] {
    let (a, b) = (0x1234_5678_9abc_i64, -0x0fed_cba9_i64);
    let (x, y) = (0x7654_3210_i32, -0x1234_5678_i32);
    let mul = count(|| {
        black_box(black_box(a).wrapping_mul(black_box(b)));
    });
    let widen = count(|| {
        black_box(i64::from(black_box(x)) * i64::from(black_box(y)));
    });
    let sat = count(|| {
        black_box(black_box(a).saturating_mul(black_box(b)));
    });
    let checked = count(|| {
        black_box(black_box(a).checked_mul(black_box(b)));
    });
    let div = [1i64, 0x1234, 0x7fff_ffff, 0x12_3456_789a]
        .iter()
        .map(|&s| {
            count(|| {
                black_box((1i64 << 44) / black_box(s));
            })
        })
        .max()
        .unwrap_or(0);
    let udiv32 = count(|| {
        black_box(black_box(123_456_789u32) / 10);
    });
    let mulhi = count(|| {
        black_box(paperbot::math::mul_hi(black_box(x), black_box(y)));
    });
    [
        ("i64 * i64 (wrapping: `__muldi3`)", mul, ""),
        ("i64::from(i32) * i64::from(i32) (widening)", widen, "still `__muldi3`: no MULSH on the lx106"),
        ("i64 saturating_mul", sat, "overflow test = a 128-bit product"),
        ("i64 checked_mul", checked, ""),
        ("(1 << 44) / i64 (`__divdi3`, worst of 4)", div, ""),
        ("u32 / 10 (`__udivsi3`)", udiv32, "for comparison: the robot's digits are reciprocal multiplies"),
        ("paperbot::math::mul_hi (i32 x i32 -> high 32)", mulhi, "for comparison"),
    ]
}

/// Prints the tables and checks the tick bar; returns (passed, failed).
pub fn run() -> (u32, u32) {
    let est = estimator_rows();
    println!();
    println!("## Estimator (instructions, worst of {} poses in the arena, dt = 10 ms)", POSES.len());
    println!();
    println!("| call | instructions | note |");
    println!("| --- | ---: | --- |");
    for (name, n, note) in &est {
        println!("| {} | {} | {} |", name, n, note);
    }
    let helpers = helper_rows();
    println!();
    println!("## Runtime helpers (instructions per operation, as called)");
    println!();
    println!("| operation | instructions | note |");
    println!("| --- | ---: | --- |");
    for (name, n, note) in &helpers {
        println!("| {} | {} | {} |", name, n, note);
    }
    let (ticks, not_accepted) = tick_rows();
    println!();
    println!(
        "## Control tick, no I/O (instructions, Controller::tick over trait doubles, worst of {} poses)",
        POSES.len()
    );
    println!();
    println!("| tick | Stop | Straight | Turn | worst |");
    println!("| --- | ---: | ---: | ---: | ---: |");
    for r in &ticks {
        println!("| {} | {} | {} | {} | {} |", r.name, r.counts[0], r.counts[1], r.counts[2], r.worst());
    }
    if not_accepted > 0 {
        println!("      WARNING: {} measured ticks did not accept {} reading(s)", not_accepted, CORRECTIONS);
    }
    for (name, n, _) in est.iter().chain(&helpers) {
        println!("BENCH {} {}", name, n);
    }
    for r in &ticks {
        for ((m, _), n) in MOTIONS.iter().zip(r.counts) {
            println!("BENCH {} [{}] {}", r.name, m, n);
        }
    }
    // the first two rows are the tick without I/O; the last two add a telemetry row
    let worst = ticks.iter().take(2).map(TickRow::worst).max().unwrap_or(0);
    let with_row = ticks.iter().map(TickRow::worst).max().unwrap_or(0);
    // the controller's estimator carries one hypothesis here: the others'
    // prediction and correction added as the estimator alone measures them
    let (one, all) = (predict_and_correct(1), predict_and_correct(HYPOTHESES));
    let worst_all = worst + all.saturating_sub(one);
    println!(
        "      estimator predict + correction: {} instructions with one hypothesis, {} with {}",
        one, all, HYPOTHESES
    );
    println!("BENCH estimator: predict Turn + update_lidar, 1 hypothesis {}", one);
    println!("BENCH estimator: predict Turn + update_lidar, {} hypotheses {}", HYPOTHESES, all);
    println!("BENCH tick without I/O, {} hypotheses (ambiguous) {}", HYPOTHESES, worst_all);
    let ok = worst <= TICK_MAX && not_accepted == 0;
    println!(
        "test bar::tick_without_io: {} <= {} instructions (one hypothesis; fresh readings, correction accepted) ... {}",
        worst,
        TICK_MAX,
        if ok { "ok" } else { "FAILED" }
    );
    let ok_all = worst_all <= TICK_MAX && not_accepted == 0;
    println!(
        "test bar::tick_without_io_{}_hypotheses: {} <= {} instructions (ambiguous; the bar's tick plus the others' prediction and correction) ... {}",
        HYPOTHESES,
        worst_all,
        TICK_MAX,
        if ok_all { "ok" } else { "FAILED" }
    );
    // a standing tick that learns the spot's share, the same way
    let (learning, learned) = standing_learning_tick(HYPOTHESES);
    let learned = learned * 2 >= POSES.len();
    let worst_learning = worst + learning.saturating_sub(one);
    println!("BENCH estimator: predict Stop learning the spot + update_lidar, {} hypotheses {}", HYPOTHESES, learning);
    let ok_learning = worst_learning <= TICK_MAX && learned;
    println!(
        "test bar::standing_tick_learning_the_spot_{}_hypotheses: {} <= {} instructions (the bar's tick with the spot's batch learned{}) ... {}",
        HYPOTHESES,
        worst_learning,
        TICK_MAX,
        if learned { "" } else { "; fewer than half the poses learned" },
        if ok_learning { "ok" } else { "FAILED" }
    );
    println!("      a tick that also formats a telemetry row: {} instructions (no bar; rows go out at 10 Hz)", with_row);
    let passed = u32::from(ok) + u32::from(ok_all) + u32::from(ok_learning);
    (passed, 3 - passed)
}
