//! Soak: a million control-loop ticks (2.8 hours of robot time at 100 Hz)
//! on the simulated robot, with a random operator typing commands at random
//! intervals (sometimes falling silent so the deadman has to act). The
//! test build has overflow checks on, so any overflow in the fixed-point
//! paths (state update, estimator, models, protocol) fails it. Every tick:
//! the output is well formed, fault counters never go back, no untimed
//! motion outlives the deadman, the estimate stays in the arena (within the
//! estimator's margin) with a valid covariance; at checkpoints the estimate
//! is near the truth.
//!
//! `SOAK_TICKS=n` changes the length (CI runs the default million).

use crate::common;
use common::longrun::{random_command, range, Watcher};
use paperbot::sim::noise::Rng;
use paperbot::sim::realism::Realism;
use paperbot::sim::robot::{SimConfig, SimRobot};

fn ticks() -> u64 {
    std::env::var("SOAK_TICKS").ok().and_then(|s| s.parse().ok()).unwrap_or(1_000_000)
}

#[test]
fn a_million_ticks_of_random_commands() {
    let n = ticks();
    let start = std::time::Instant::now();
    let mut robot = SimRobot::new(SimConfig {
        seed: 11,
        realism: Realism::IDEAL,
        locate_at_power_up: false,
        ..SimConfig::default()
    });
    let mut rng = Rng::new(0x50A4);
    let mut w = Watcher::default();
    let mut next_command = 0u64;
    let (mut collisions_at_last_checkpoint, mut stuck_checkpoints) = (0, 0);
    for i in 0..n {
        if i == next_command {
            let line = random_command(&mut rng, &robot);
            robot.send(&line);
            // usually within the deadman, sometimes well past it
            next_command +=
                if rng.next_u64() % 10 == 0 { range(&mut rng, 60, 300) } else { range(&mut rng, 1, 45) } as u64;
        }
        robot.tick();
        w.after_tick(&mut robot);
        // checkpoints: a second after a command, the estimate has settled
        // (only those with no wall contact for the last 10 s: a body
        // stuck at a wall while the loop drives on is a different story)
        if i % 1000 == 999 {
            if robot.collisions() == collisions_at_last_checkpoint {
                w.check_error(&robot);
            } else {
                stuck_checkpoints += 1;
            }
            collisions_at_last_checkpoint = robot.collisions();
        }
    }
    let s = &w.seen;
    let c = robot.controller();
    println!(
        "soak: {} ticks ({:.1} h simulated) in {:.1} s; {} commands ok, {} refused, {} deadman stops, {} rows; \
         faults {:?}; wall contacts {}; estimate worst {:.1} mm outside the arena, worst error {:.0} mm / {:.1} deg; \
         estimator {:?}",
        s.ticks,
        c.clock_us() as f64 / 3.6e9,
        start.elapsed().as_secs_f64(),
        s.commands_ok,
        s.refusals,
        s.deadman_stops,
        s.rows,
        c.faults(),
        robot.collisions(),
        s.worst_outside_mm,
        s.worst_error_mm,
        s.worst_error_deg,
        c.estimator().stats(),
    );
    assert_eq!(s.ticks, n);
    assert_eq!(c.ticks(), n);
    // the run did what it says: many commands, refusals, deadman stops, telemetry
    let counts = (s.commands_ok, s.refusals, s.deadman_stops, s.rows);
    assert!(counts.0 > n / 50 && counts.1 > n / 1000 && counts.2 > n / 5000 && counts.3 > n / 100, "{counts:?}");
    // a clean bus: no sensor faults at all
    let f = c.faults();
    assert_eq!((f.bus, f.timeout, f.missing, f.bad_sample), (0, 0, 0, 0), "{f:?}");
    let (q50, q90) = (s.error_quantile(0.5), s.error_quantile(0.9));
    println!("soak: {} checkpoints free of walls for 10 s, {stuck_checkpoints} not", s.errors.len());
    println!("soak: their error median {:.1} mm / {:.1} deg, 90 % {:.0} mm / {:.0} deg", q50.0, q50.1, q90.0, q90.1);
    // A body held at a wall while the loop drives on leaves the estimate
    // off; disagreeing readings seed hypotheses on the sensors' side
    // (`lost_heading_is_recovered` below) and the position is kept within
    // `ARENA_MARGIN` of the box. Measured on main (478d967): the body
    // touches walls in 50,018 ticks, 744 of 1000 checkpoints are free of
    // walls for 10 s; their error median 3.4 mm / 1.5 deg, 90 % 24 mm /
    // 7 deg; worst 146 mm / 24 deg, at most 50.0 mm outside (the margin).
    // The bounds below are regression bounds, about 1.5 to 4 times that.
    let margin = paperbot::config::estimator::ARENA_MARGIN.to_mm_f64();
    assert!(s.worst_outside_mm <= margin + 0.01, "{}", s.worst_outside_mm);
    assert!(q50.0 < 5.0 && q50.1 < 2.5, "{q50:?}");
    assert!(q90.0 < 40.0 && q90.1 < 12.0, "{q90:?}");
    assert!(s.worst_error_mm < 600.0 && s.worst_error_deg < 35.0, "{} {}", s.worst_error_mm, s.worst_error_deg);
    let st = c.estimator().stats();
    assert!(st.spawned > 0, "{st:?}");
}

/// A body held still while the loop drives on (a wheel against a wall)
/// leaves the state update alone far off: 41 degrees after 0.3 s of a
/// commanded turn, 172 after 1 s, 140 mm after 1 s of a straight. Every
/// true reading is then further from the estimate than the gate; a
/// one-hypothesis filter rejected all of them for ever (60 s of compass
/// readings did not correct 41 degrees). Now readings that keep
/// disagreeing seed hypotheses on the sensors' side, and the estimate
/// follows them back. Measured (seed 3): at release the estimate is 2-26
/// degrees and 1-5 mm off; it is back within 5 degrees and 20 mm for good
/// 0-3.4 s after (the test allows 7 s).
#[test]
fn lost_heading_is_recovered() {
    // (command, ticks held still, the error it leaves: degrees, mm)
    let cases: [(&str, usize, f64, f64); 4] = [
        ("cw 1.0 0.3", 32, 20.0, 0.0),
        ("cw 1.0 0.6", 62, 60.0, 0.0),
        ("ccw 3.0 1.0", 102, 120.0, 0.0),
        ("fwd 0.14 1.0", 102, 0.0, 100.0),
    ];
    for (cmd, held, min_deg, min_mm) in cases {
        // held mid-box: at the default start (130 mm from the west wall) the
        // front lidar's cone meets that wall first, grazing, and x is not
        // observable until the robot moves
        let start = paperbot::sim::body::PoseF64::new(380.0, 250.0, 0.0);
        let mut robot = SimRobot::new(SimConfig {
            seed: 3,
            start,
            realism: Realism::IDEAL,
            locate_at_power_up: false,
            ..SimConfig::default()
        });
        for _ in 0..100 {
            robot.tick();
        }
        let truth = robot.truth();
        robot.send(cmd);
        for _ in 0..held {
            robot.tick();
            robot.set_truth(truth); // stuck: the body does not move
        }
        // the state update alone (what the estimate was left with before
        // re-acquisition) is that far off; the estimate already less
        let lost = robot.sample();
        let (deg, mm) = (
            lost.dead_reckoned.heading_error(&lost.truth).to_degrees().abs(),
            lost.dead_reckoned.distance(&lost.truth),
        );
        assert!(deg >= min_deg && mm >= min_mm, "{cmd}: the body was not held: {deg:.0} deg, {mm:.0} mm");
        let (e_deg, e_mm) =
            (lost.estimate.heading_error(&lost.truth).to_degrees().abs(), lost.estimate.distance(&lost.truth));
        println!("{cmd}: estimate at release {e_deg:.0} deg / {e_mm:.0} mm");
        // back within 5 degrees and 20 mm, and staying there to the end of
        // 10 s. The robot turns back and forth once free (six turns of 0.8
        // rad): standing, the lidars square on to their walls do not see
        // the heading, and the compass reads the heading plus a bias it
        // does not know (issue 29); and the held turn taught the filter that
        // the car turns slowly (the turn-rate scale, as a slow real turn
        // would), which the next turns unlearn.
        let mut back_at = None;
        for i in 0..1_000 {
            match i {
                10 | 210 | 410 => robot.send("ccw 1.0 0.8"),
                110 | 310 | 510 => robot.send("cw 1.0 0.8"),
                _ => {}
            }
            robot.tick();
            let s = robot.sample();
            let ok =
                s.estimate.heading_error(&s.truth).to_degrees().abs() < 5.0 && s.estimate.distance(&s.truth) < 20.0;
            match (ok, back_at) {
                (true, None) => back_at = Some(i),
                (false, Some(_)) => back_at = None,
                _ => {}
            }
        }
        let st = robot.controller().estimator().stats();
        println!("{cmd} held {held} ticks: lost {deg:.0} deg / {mm:.0} mm, back after {back_at:?} ticks; {st:?}");
        let back_at = back_at.unwrap_or_else(|| panic!("{cmd}: not recovered in 10 s"));
        assert!(back_at < 700, "{cmd}: recovered only after {back_at} ticks");
    }
}
