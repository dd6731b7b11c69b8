//! Long fault-injection runs on the simulated bus: the control loop of the
//! simulated robot for an hour of robot time, with a few percent of the
//! bus transactions failing at random (NACK, clock-stretch timeout, SDA
//! stuck for one transaction, corrupted bytes), and every half minute or so
//! an outage: a chip unplugged for seconds and plugged back in (a power
//! cycle), SDA held low for a while, or an address that stops answering.
//! A random operator keeps typing, sometimes going silent mid-drive.
//!
//! Checked (overflow checks are on): no panic; every tick, the deadman
//! stops an untimed motion and the output stays well formed with
//! monotonic fault counters (`common::longrun::Watcher`); the faults show
//! in the telemetry's counters; after each outage every sensor is back up
//! and delivering; the estimate stays bounded with a valid covariance.

use crate::common;
use common::longrun::{random_command, range, Watcher};
use paperbot::config;
use paperbot::control::TICK_US;
use paperbot::sim::bus::Fault;
use paperbot::sim::noise::Rng;
use paperbot::sim::robot::{SimConfig, SimRobot};

/// One outage of the sensor bus.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Outage {
    /// A chip unplugged (0 front, 1 right, 2 MPU9250) and plugged back in.
    Unplugged(u8),
    /// SDA held low by a stuck slave.
    SdaStuck,
    /// An address nobody answers (front, right or the compass).
    Nack(u8),
}

impl Outage {
    /// True if the outage takes sensor `k` (front, right, compass) off the bus.
    fn affects(self, k: usize) -> bool {
        match self {
            Outage::Unplugged(n) => usize::from(n) == k,
            Outage::SdaStuck => true,
            Outage::Nack(a) => {
                [config::i2c::FRONT_LIDAR_ADDR, config::i2c::RIGHT_LIDAR_ADDR, config::i2c::AK8963_ADDR].get(k)
                    == Some(&a)
            }
        }
    }
    fn set(self, robot: &SimRobot, on: bool) {
        let s = &robot.sensors;
        match self {
            Outage::Unplugged(0) => s.front.borrow_mut().set_present(!on),
            Outage::Unplugged(1) => s.right.borrow_mut().set_present(!on),
            Outage::Unplugged(_) => s.mpu.borrow_mut().set_present(!on),
            Outage::SdaStuck => s.bus.set_sda_stuck(on),
            Outage::Nack(a) => s.bus.set_nack_address(a, on),
        }
    }
}

/// Counts of what was injected.
#[derive(Default, Debug)]
struct Injected {
    /// One-shot faults that reached a transaction, by kind.
    failing: u64,
    corrupt: u64,
    outages: u64,
    transactions: u64,
    /// Failing one-shots injected while no outage ran.
    quiet_failing: u64,
}

fn random_fault(rng: &mut Rng) -> Fault {
    match rng.next_u64() % 4 {
        0 => Fault::Nack,
        1 => Fault::Timeout,
        2 => Fault::SdaStuck,
        _ => Fault::Corrupt(1 << (rng.next_u64() % 8) | (rng.next_u64() as u8 & 0x81)),
    }
}

struct Run {
    ticks: u64,
    /// Probability that a transaction gets a one-shot fault.
    fault_rate: f64,
    seed: u64,
    /// Every outage must be recovered from within this long (s), and the
    /// next one waits for the recovery; `None`: outages come regardless.
    recovery_limit_s: Option<f64>,
}

struct Report {
    recovery_limit_s: Option<f64>,
    watcher: Watcher,
    injected: Injected,
    /// Longest time from the end of an outage to all three sensors up and
    /// delivering again, s.
    worst_recovery_s: f64,
    recoveries: u64,
    /// Fraction of the ticks each sensor was up (front, right, compass).
    up: [f64; 3],
    /// The same over the ticks when no outage took that sensor off the bus
    /// (what the noisy bus alone costs, plus the way back after an outage).
    up_outside_outages: [f64; 3],
    /// Transactions that failed on the bus (injected and outages).
    bus_failures: u64,
    /// Faults the loop saw (bus, timeout, missing) in ticks with no outage
    /// running: what got through the transaction retries.
    quiet_faults: u64,
    robot: SimRobot,
    secs: f64,
}

/// When each sensor (front, right, compass) last delivered a sample, loop
/// clock us: any sample, "too close" and "no target" included (a lidar
/// against a wall delivers samples the estimator does not take).
fn last_samples(robot: &SimRobot) -> [u32; 3] {
    let c = robot.controller();
    [c.front_health(), c.right_health(), c.compass_health()].map(|h| h.last_sample_us())
}

fn run(r: Run) -> Report {
    let start = std::time::Instant::now();
    // `PAPERBOT_REALISM=hard` runs it in the hard world (issue #29)
    let realism = paperbot::sim::realism::Realism::from_env_or(paperbot::sim::realism::Realism::LAB).unwrap();
    let mut robot = SimRobot::new(SimConfig { seed: r.seed, realism, ..SimConfig::default() });
    let mut rng = Rng::new(r.seed ^ 0xFA17);
    let mut w = Watcher::default();
    let mut inj = Injected::default();
    let mut next_command = 0u64;
    let mut outage: Option<(Outage, u64)> = None; // and the tick it ends
    let mut next_outage = range(&mut rng, 1_000, 5_000) as u64;
    // (end of the last outage in ticks, the sensors' last sample times
    // then, which sensors have been back up and delivered since)
    let mut recovering: Option<(u64, [u32; 3], [bool; 3])> = None;
    let (mut worst_recovery, mut recoveries) = (0u64, 0u64);
    let mut up_ticks = [0u64; 3];
    // (ticks without an outage on the sensor, of them up)
    let mut outside = [(0u64, 0u64); 3];
    let failures0 = robot.sensors.bus.failures();
    let mut quiet_faults = 0u64;
    let loud = |robot: &SimRobot| {
        let f = robot.controller().faults();
        u64::from(f.bus) + u64::from(f.timeout) + u64::from(f.missing)
    };
    let per_s = i64::from(1_000_000 / TICK_US);
    for i in 0..r.ticks {
        if i == next_command {
            let line = random_command(&mut rng, &robot);
            robot.send(&line);
            next_command +=
                if rng.next_u64() % 10 == 0 { range(&mut rng, 60, 300) } else { range(&mut rng, 1, 45) } as u64;
        }
        // outages: one at a time, 0.2..5 s long, every 10..50 s
        if outage.is_none() && i >= next_outage {
            let o = match rng.next_u64() % 5 {
                0 => Outage::Unplugged((rng.next_u64() % 3) as u8),
                1 => Outage::SdaStuck,
                2 => Outage::Nack(config::i2c::FRONT_LIDAR_ADDR),
                3 => Outage::Nack(config::i2c::RIGHT_LIDAR_ADDR),
                _ => Outage::Nack(config::i2c::AK8963_ADDR),
            };
            o.set(&robot, true);
            inj.outages += 1;
            outage = Some((o, i + range(&mut rng, per_s / 5, 5 * per_s) as u64));
            recovering = None;
        }
        if let Some((o, end)) = outage {
            if i >= end {
                o.set(&robot, false);
                outage = None;
                next_outage = i + range(&mut rng, 10 * per_s, 50 * per_s) as u64;
                recovering = Some((i, last_samples(&robot), [false; 3]));
                if r.recovery_limit_s.is_some() {
                    next_outage = u64::MAX; // scheduled once recovered
                }
            }
        }
        // one-shot faults: each transaction of this tick faulty with the
        // given probability (the bus matches them by transaction number)
        let t0 = robot.sensors.bus.transactions();
        robot.sensors.bus.clear_faults();
        let mut planned = Vec::new();
        for k in 0..512 {
            if rng.uniform() < r.fault_rate {
                let f = random_fault(&mut rng);
                robot.sensors.bus.inject(t0 + k, f);
                planned.push((t0 + k, f));
            }
        }
        let loud0 = loud(&robot);
        robot.tick();
        let t1 = robot.sensors.bus.transactions();
        inj.transactions += u64::from(t1 - t0);
        for (at, f) in planned {
            if at < t1 {
                match f {
                    Fault::Corrupt(_) => inj.corrupt += 1,
                    _ => {
                        inj.failing += 1;
                        inj.quiet_failing += u64::from(outage.is_none());
                    }
                }
            }
        }
        if outage.is_none() {
            quiet_faults += loud(&robot) - loud0;
        }
        w.after_tick(&mut robot);
        let c = robot.controller();
        for (k, h) in [c.front_health(), c.right_health(), c.compass_health()].iter().enumerate() {
            up_ticks[k] += u64::from(h.up);
            if !outage.is_some_and(|(o, _)| o.affects(k)) {
                outside[k].0 += 1;
                outside[k].1 += u64::from(h.up);
            }
        }
        // recovery: each sensor is up again and has delivered a reading
        // since the outage ended (not necessarily all at the same moment:
        // on a faulty bus a sensor can go down again at the next glitch)
        if let Some((since, before, mut back)) = recovering {
            let now = last_samples(&robot);
            let c = robot.controller();
            let up = [c.front_health().up, c.right_health().up, c.compass_health().up];
            for k in 0..3 {
                back[k] |= up[k] && now[k] != before[k];
            }
            recovering = Some((since, before, back));
            if back.iter().all(|b| *b) {
                worst_recovery = worst_recovery.max(i - since);
                recoveries += 1;
                recovering = None;
                if next_outage == u64::MAX {
                    next_outage = i + range(&mut rng, 10 * per_s, 50 * per_s) as u64;
                }
            } else if let Some(limit) = r.recovery_limit_s {
                assert!(
                    ((i - since) as f64) < limit * per_s as f64,
                    "sensors {back:?} (front, right, compass) not back {limit} s after an outage: {:?} {:?} {:?}",
                    c.front_health(),
                    c.right_health(),
                    c.compass_health()
                );
            }
        }
    }
    let secs = start.elapsed().as_secs_f64();
    Report {
        recovery_limit_s: r.recovery_limit_s,
        watcher: w,
        injected: inj,
        worst_recovery_s: worst_recovery as f64 / per_s as f64,
        recoveries,
        up: up_ticks.map(|u| u as f64 / r.ticks.max(1) as f64),
        up_outside_outages: outside.map(|(n, u)| u as f64 / n.max(1) as f64),
        bus_failures: u64::from(robot.sensors.bus.failures().wrapping_sub(failures0)),
        quiet_faults,
        robot,
        secs,
    }
}

fn print(name: &str, r: &Report) {
    let c = r.robot.controller();
    let s = &r.watcher.seen;
    println!(
        "{name}: {} ticks ({:.2} h simulated) in {:.1} s; {:?} ({:.2} % of transactions faulty); {} recoveries, worst {:.1} s; \
         up {:.1} / {:.1} / {:.1} % of the time ({:.2} / {:.2} / {:.2} % outside its outages); {} bus failures, {} faults seen outside outages; \
         telemetry counters {:?}; health {:?} {:?} {:?}; {} deadman stops; estimate worst {:.0} mm outside",
        s.ticks,
        c.clock_us() as f64 / 3.6e9,
        r.secs,
        r.injected,
        100.0 * (r.injected.failing + r.injected.corrupt) as f64 / r.injected.transactions.max(1) as f64,
        r.recoveries,
        r.worst_recovery_s,
        100.0 * r.up[0],
        100.0 * r.up[1],
        100.0 * r.up[2],
        100.0 * r.up_outside_outages[0],
        100.0 * r.up_outside_outages[1],
        100.0 * r.up_outside_outages[2],
        r.bus_failures,
        r.quiet_faults,
        s.last_faults,
        c.front_health(),
        c.right_health(),
        c.compass_health(),
        s.deadman_stops,
        s.worst_outside_mm,
    );
}

fn check(r: &Report) {
    let s = &r.watcher.seen;
    let f = r.robot.controller().faults();
    // the faults are counted, and the telemetry says so
    let counted = u64::from(f.bus) + u64::from(f.timeout) + u64::from(f.missing) + u64::from(f.bad_sample);
    assert!(counted > 0 && s.last_faults.bus > 0, "{f:?}");
    // every failing one-shot failed its transaction on the bus (outages
    // fail more)...
    assert!(r.bus_failures >= r.injected.failing, "{} bus failures, {:?}", r.bus_failures, r.injected);
    // ...but the transaction retries (config::i2c::TRANSACTION_RETRIES) let
    // through only the runs of failures longer than the retries: the loop
    // sees at most one fault per 100 failing one-shots outside outages
    // (measured: see each test)
    assert!(
        r.quiet_faults * 100 <= r.injected.quiet_failing,
        "{} faults seen of {} failing one-shots outside outages",
        r.quiet_faults,
        r.injected.quiet_failing
    );
    // the last row is at most a telemetry period old
    let t = s.last_faults;
    assert!(t.bus <= f.bus && t.timeout <= f.timeout && t.missing <= f.missing, "{t:?} {f:?}");
    // with a recovery limit, every outage was recovered from (the last one
    // may still be running or recovering)
    if r.recovery_limit_s.is_some() {
        assert!(
            // (more than one a minute: over 50 in an hour)
            r.recoveries + 1 >= r.injected.outages && r.recoveries * 7_200 > s.ticks,
            "{} of {}",
            r.recoveries,
            r.injected.outages
        );
    }
    assert!(s.deadman_stops > 0);
    // The estimate stays bounded, its covariance valid every tick (the
    // watcher). A regression bound, not accuracy: with sensors down the
    // loop dead-reckons while the body may sit at a wall, and nothing
    // holds the estimate inside the arena (tests/control/soak.rs). Measured: 1538 mm.
    assert!(s.worst_outside_mm < 2_500.0, "{}", s.worst_outside_mm);
}

/// Checks each sensor's up-time (front, right, compass) and the overruns
/// per hour of robot time against the given bounds.
fn check_up(r: &Report, min_up: [f64; 3], min_up_outside: f64, max_overruns_per_h: f64) {
    let c = r.robot.controller();
    for (k, (up, min)) in r.up.iter().zip(min_up).enumerate() {
        assert!(*up > min, "sensor {k} (front, right, compass) up {:.1} % of the time", 100.0 * up);
        let outside = r.up_outside_outages[k];
        assert!(outside > min_up_outside, "sensor {k} up {:.2} % outside its outages", 100.0 * outside);
    }
    let hours = c.clock_us() as f64 / 3.6e9;
    let per_h = f64::from(c.faults().overruns) / hours;
    assert!(per_h < max_overruns_per_h, "{per_h:.0} overruns per hour");
}

/// An hour of robot time with outages every 10..50 s on a bus where 1 %
/// of the transactions fail or corrupt at random: after every outage each
/// sensor is back up and delivering within 5 s. Measured over seeds 21 and
/// 30..40 (`cargo test --test control faults_long:: -- --ignored` for 30..40): worst
/// recovery 1.0 to 1.9 s; each sensor up 94.7 to 96.5 % of the time, the
/// rest being the outages themselves (one takes a sensor off the bus for
/// 0.2..5 s, all three for a stuck SDA: about 3.5 % of the time) and the
/// back-off after them; up 99.11 to 99.51 % of the ticks when no outage
/// has it off the bus; 67 to 124 overruns per hour (one per
/// re-initialisation that waits for a chip's reset). Before the
/// transaction retries (seed 21): recovery 15 to 26 s (over 30 s for seed
/// 30), up 39 / 39 / 62 %, 1,336 overruns per hour.
#[test]
fn an_hour_of_outages_on_a_one_percent_bus() {
    for seed in ONE_PERCENT_SEEDS {
        let r = run(Run { ticks: 360_000, fault_rate: 0.01, seed, recovery_limit_s: Some(5.0) });
        print(&format!("outages, 1 % faulty, seed {seed}"), &r);
        check(&r);
        check_up(&r, [0.93; 3], 0.985, 200.0);
    }
}

/// The seeds of [`an_hour_of_outages_on_a_one_percent_bus`] (21: the
/// original; 30: failed a 30 s recovery limit before the retries).
const ONE_PERCENT_SEEDS: [u64; 3] = [21, 30, 34];

/// The 1 % run over more seeds (about 2 s each), for the figures above.
#[test]
#[ignore]
fn an_hour_of_outages_on_a_one_percent_bus_more_seeds() {
    for seed in 30..=40 {
        let r = run(Run { ticks: 360_000, fault_rate: 0.01, seed, recovery_limit_s: Some(5.0) });
        print(&format!("outages, 1 % faulty, seed {seed}"), &r);
        check(&r);
        check_up(&r, [0.93; 3], 0.985, 200.0);
    }
}

/// An hour with 3 % of the transactions faulty and outages regardless of
/// recovery: with the transaction retries, a poll or a bring-up fails
/// only when three attempts in a row do, so the sensors are down about as
/// long as the outages take them (measured: up 95.4 / 96.3 / 95.0 % of the
/// time, 99.30 / 99.36 / 99.11 % outside its outages, 119 overruns per
/// hour, worst recovery 1.8 s; before the retries: 1 / 2 / 32 %, a single
/// NACKed poll took a sensor down for a second and a re-init that got
/// through one try in ten).
#[test]
fn an_hour_with_three_percent_faulty_transactions() {
    let r = run(Run { ticks: 360_000, fault_rate: 0.03, seed: 22, recovery_limit_s: None });
    print("3 % faulty", &r);
    check(&r);
    check_up(&r, [0.93; 3], 0.985, 200.0);
}

/// Ten minutes with 10 % of the transactions faulty: every sensor comes
/// back within 5 s after every outage (measured: worst 3.6 s, up 93.5 to
/// 96.5 % of the time, 98.2 to 99.3 % outside its outages, 22 to 25
/// overruns; before the retries the lidars never came back).
#[test]
fn ten_minutes_with_ten_percent_faulty_transactions() {
    let r = run(Run { ticks: 60_000, fault_rate: 0.10, seed: 23, recovery_limit_s: Some(5.0) });
    print("10 % faulty", &r);
    check(&r);
    check_up(&r, [0.90; 3], 0.97, 250.0);
}
