//! The simulator: arena ray casting, scripts, and the control loop driving
//! the simulated robot through the register-level fake chips: exact runs
//! against an f64 reference, sensor truth, faults, determinism.

use crate::common;
use paperbot::config;
use paperbot::config::geometry::ROTATION_TO_REFERENCE;
use paperbot::math::{Speed, TurnRate};
use paperbot::model::{Motion, Range};
use paperbot::sim::arena::Arena;
use paperbot::sim::body::{Kinematics, PoseF64};
use paperbot::sim::realism::Realism;
use paperbot::sim::robot::{Noise, SimConfig, SimRobot};
use paperbot::sim::script::{default_script, Script};
use std::f64::consts::{FRAC_PI_2, PI};

// ---- arena -------------------------------------------------------------

#[test]
fn ray_cast_hits_the_expected_wall() {
    let a = Arena::from_mm_f64(762.5, 495.0);
    let d = |deg: f64| deg.to_radians();
    // (x, y, heading deg) -> distance
    let table = [
        (100.0, 100.0, 0.0, 662.5),                // north wall
        (100.0, 100.0, 90.0, 395.0),               // east wall
        (100.0, 100.0, 180.0, 100.0),              // south wall
        (100.0, 100.0, 270.0, 100.0),              // west wall
        (100.0, 100.0, 45.0, 395.0 * 2f64.sqrt()), // east wall first at 45 deg
        (700.0, 100.0, 45.0, 62.5 * 2f64.sqrt()),  // north wall first
        (0.0, 0.0, 45.0, 495.0 * 2f64.sqrt()),     // from the corner
        (381.25, 247.5, -90.0, 247.5),             // negative heading
        (381.25, 247.5, 360.0 + 180.0, 381.25),    // past a full turn
    ];
    for (x, y, h, want) in table {
        let got = a.ray_cast(x, y, d(h)).expect("a ray from inside hits");
        assert!((got - want).abs() < 1e-9, "({x}, {y}, {h}): {got} want {want}");
    }
    assert_eq!(a.ray_cast(-10.0, 100.0, PI), None, "from outside, pointing away");
    assert!((a.ray_cast(-10.0, 100.0, 0.0).unwrap() - 10.0).abs() < 1e-9, "from outside, pointing in");
    assert!(a.contains(0.0, 495.0) && !a.contains(-0.1, 10.0));
}

// ---- scripts -----------------------------------------------------------

#[test]
fn scripts_parse_times_in_seconds_or_ms_and_refuse_bad_lines() {
    let s = Script::parse("# c\n\n@0 rate 5\n0.5s fwd 0.13 2 # go\n@1500ms   stop\n2 cw 2.5\n").unwrap();
    let got: Vec<(u64, &str, usize)> = s.lines.iter().map(|l| (l.at_us, l.command.as_str(), l.line_no)).collect();
    assert_eq!(got, [(0, "rate 5", 3), (500_000, "fwd 0.13 2", 4), (1_500_000, "stop", 5), (2_000_000, "cw 2.5", 6)]);
    assert_eq!(s.end_us(), 2_000_000);
    for (bad, line) in [("@x fwd 1", 1), ("1 stop\n0.5 stop", 2), ("@1", 1), ("-1 stop", 1), ("1h stop", 1)] {
        let e = Script::parse(bad).unwrap_err();
        assert_eq!(e.line_no, line, "{bad}: {e}");
    }
}

#[test]
fn the_default_script_is_valid_and_lasts_the_duration() {
    let s = Script::parse(&default_script(60.0)).unwrap();
    // the last goto has its leg's time (4 or 6 s) before the end
    assert!(s.end_us() <= 56_000_000 && s.end_us() > 50_000_000, "{}", s.end_us());
    assert!(s.lines.iter().all(|l| paperbot::control::protocol::parse(l.command.as_bytes()).is_ok()));
}

// ---- exact runs against the f64 reference ----------------------------

fn exact(kinematics: Kinematics, start: PoseF64) -> SimRobot {
    SimRobot::new(SimConfig {
        noise: Noise::OFF,
        kinematics,
        start,
        realism: Realism::IDEAL,
        locate_at_power_up: false,
        ..SimConfig::default()
    })
}

/// The model's motion for a `fwd`/`cw` request (what the loop drives).
fn driven(request: Motion) -> Motion {
    config::actuators::MODEL.drive(request).motion
}

/// The report's equations in f64, closed form for a motion held `t` seconds.
fn reference(p: PoseF64, motion: Motion, t: f64) -> PoseF64 {
    let d = ROTATION_TO_REFERENCE.to_mm_f64();
    match motion {
        Motion::Stop => p,
        Motion::Straight(v) => {
            let s = v.to_mps_f64() * 1000.0 * t;
            PoseF64::new(p.x + s * p.theta.cos(), p.y + s * p.theta.sin(), p.theta)
        }
        Motion::Turn(w) => {
            let th = p.theta + w.to_rad_s_f64() * t;
            PoseF64::new(p.x - d * (p.theta.cos() - th.cos()), p.y - d * (p.theta.sin() - th.sin()), th)
        }
    }
}

fn assert_close(what: &str, a: &PoseF64, b: &PoseF64, mm: f64, deg: f64) {
    let (e, h) = (a.distance(b), a.heading_error(b).to_degrees().abs());
    assert!(e <= mm && h <= deg, "{what}: {a:?} vs {b:?}: {e:.6} mm, {h:.6} deg");
}

#[test]
fn a_scripted_drive_without_noise_ends_where_the_f64_reference_does() {
    // a rigid body turning about its axle: the geometry the firmware's state update uses
    let start = PoseF64::new(150.0, 120.0, 0.0);
    let mut robot = exact(Kinematics::Rigid, start);
    let script = Script::parse(
        "@0 rate 0\n@0 fwd 0.13 2.5\n@3 cw 2.5 0.7\n@4 fwd 0.14 1.2\n@6 ccw 3 0.45\n@7 back 0.13 0.8\n@8 servo 105 105 0.3\n",
    )
    .unwrap();
    let samples = robot.run_script(&script, 9_000_000, 10, |l| assert!(!l.starts_with("# err"), "{l}"));
    // f64 reference of the same motions, each for its whole duration
    let servo_turn = config::actuators::MODEL
        .motion_from_commands(paperbot::model::ServoCmd::from_int(105), paperbot::model::ServoCmd::from_int(105));
    let legs = [
        (driven(Motion::Straight(Speed::from_mm_s(130))), 2.5),
        (driven(Motion::Turn(TurnRate::from_mrad_s(2500))), 0.7),
        (driven(Motion::Straight(Speed::from_mm_s(140))), 1.2),
        (driven(Motion::Turn(TurnRate::from_mrad_s(-3000))), 0.45),
        (driven(Motion::Straight(Speed::from_mm_s(-130))), 0.8),
        (servo_turn, 0.3),
    ];
    let want = legs.iter().fold(start, |p, &(m, t)| reference(p, m, t));
    let end = samples.last().unwrap();
    assert_close("truth", &end.truth, &want, 1e-6, 1e-6);
    // the firmware's fixed-point dead reckoning of the same run
    assert_close("dead reckoning", &end.dead_reckoned, &want, 0.01, 0.001);
    assert!(want.distance(&start) > 150.0, "the run went somewhere: {want:?}");
    assert_eq!(robot.collisions(), 0);
    assert_eq!(robot.controller().faults(), Default::default());
}

#[test]
fn the_state_update_follows_a_rigid_turn_not_the_reports_printed_form() {
    let start = PoseF64::new(200.0, 200.0, 0.0);
    let script = Script::parse("@0 fwd 0.13 2\n@2.5 back 0.13 1\n").unwrap();
    let mut rigid = exact(Kinematics::Rigid, start);
    let end = *rigid.run_script(&script, 4_000_000, 100, |_| {}).last().unwrap();
    assert_close("straight", &end.truth, &end.dead_reckoned, 0.01, 0.001);

    // a quarter turn clockwise from north: a rigid car's reference point
    // (D ahead of the axle) swings back and to the east, and so does the
    // firmware's state update; the report's printed equations move it back
    // and to the west
    let quarter = Script::parse("@0 cw 2.493 0.63\n").unwrap();
    let d = ROTATION_TO_REFERENCE.to_mm_f64();
    let mut rigid = exact(Kinematics::Rigid, start);
    let r = *rigid.run_script(&quarter, 1_000_000, 100, |_| {}).last().unwrap();
    let turned = r.truth.theta;
    assert!((turned - FRAC_PI_2).abs() < 0.01, "{turned}");
    let axle = (start.x - d, start.y);
    assert!((r.truth.x - (axle.0 + d * turned.cos())).abs() < 1e-6);
    assert!((r.truth.y - (axle.1 + d * turned.sin())).abs() < 1e-6);
    assert!(r.truth.y > start.y + 50.0, "{r:?}");
    assert_close("rigid turn", &r.truth, &r.dead_reckoned, 0.01, 0.001);
    let mut printed = exact(Kinematics::Report, start);
    let p = *printed.run_script(&quarter, 1_000_000, 100, |_| {}).last().unwrap();
    assert!(p.truth.y < start.y - 50.0 && p.dead_reckoned.y > start.y + 50.0, "{p:?}");
}

// ---- the fake chips see the truth ----------------------------------

#[test]
fn lidars_and_compass_read_the_true_pose_through_the_fake_chips() {
    let start = PoseF64::new(300.0, 150.0, 30f64.to_radians());
    // thin rays, no disturbance: the readings are the ray's (the cone's are
    // tested in sim::realism's tests)
    let mut robot =
        SimRobot::new(SimConfig { start, realism: Realism::IDEAL, locate_at_power_up: false, ..SimConfig::default() });
    robot.send("rate 0");
    let a = robot.cfg.arena;
    let (mut fronts, mut rights, mut headings) = (vec![], vec![], vec![]);
    for _ in 0..300 {
        robot.tick();
        let ctl = robot.controller();
        if let Some(Range::Target(d)) = ctl.last_front().map(|s| s.range) {
            fronts.push(d.to_mm_f64());
        }
        if let Some(Range::Target(d)) = ctl.last_right().map(|s| s.range) {
            rights.push(d.to_mm_f64());
        }
        if let Some(c) = ctl.last_compass() {
            headings.push(c.heading.to_signed_millidegrees() as f64 / 1000.0);
        }
        robot.send("stop"); // keep the deadman happy (nothing moves anyway)
    }
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    let sd = |v: &[f64]| (v.iter().map(|x| (x - mean(v)).powi(2)).sum::<f64>() / v.len() as f64).sqrt();
    // truth: the nearest wall in each lidar's cone, less the mount's setback
    // (both mounts sit on their beams' lines through the reference point)
    let truth = |mount: &paperbot::model::LidarMount, setback: f64| {
        let (x, y, dir) = start.lidar_ray(mount);
        paperbot::sim::realism::lidar_range(&a, x, y, dir, &Realism::IDEAL).unwrap().0 - setback
    };
    let front_truth = truth(&config::geometry::FRONT_LIDAR, 50.0);
    let right_truth = truth(&config::geometry::RIGHT_LIDAR, 53.0);
    assert!((mean(&fronts) - front_truth).abs() < 1.5, "front {} vs {front_truth}", mean(&fronts));
    assert!((mean(&rights) - right_truth).abs() < 1.5, "right {} vs {right_truth}", mean(&rights));
    // the fake chip reports whole mm of reading, so a little more than the 1.6 mm noise
    assert!((1.0..2.5).contains(&sd(&fronts)), "front sd {}", sd(&fronts));
    // the compass: distortion undone by the driver's calibration, ~2.5 deg noise
    assert!((mean(&headings) - 30.0).abs() < 1.0, "compass {}", mean(&headings));
    assert!((1.8..3.5).contains(&sd(&headings)), "compass sd {}", sd(&headings));
    assert_eq!(robot.controller().faults(), Default::default());
}

// ---- runs with noise --------------------------------------------------

/// The main job: power-up localization, then laps by `goto`.
#[test]
fn the_default_minute_locates_then_drives_laps_without_touching_a_wall() {
    let mut robot = SimRobot::new(SimConfig::default());
    assert_eq!(robot.take_output(), ["# ok locate"]);
    let script = Script::parse(&default_script(60.0)).unwrap();
    let mut rows = 0;
    let mut errors = vec![];
    let mut located = vec![];
    let samples = robot.run_script(&script, 60_000_000, 10, |l| {
        if l.starts_with("# locate") {
            located.push(l.to_string());
        }
        if l.starts_with("# err") || l.starts_with("# locate failed") {
            errors.push(l.to_string());
        } else if !l.starts_with('#') && !l.starts_with("t_ms") {
            rows += 1;
        }
    });
    assert!(errors.is_empty(), "{errors:?}");
    assert_eq!(located.len(), 1, "{located:?}");
    assert_eq!(rows, 600, "10 Hz telemetry for 60 s");
    assert_eq!(robot.collisions(), 0);
    let a = robot.cfg.arena;
    let min_clearance = samples.iter().map(|s| a.clearance(s.truth.x, s.truth.y)).fold(f64::MAX, f64::min);
    // the laps are gotos steered by the estimate: the realistic robot's
    // speed spread and pivots do not take it near a wall
    assert!(min_clearance > 15.0, "{min_clearance}");
    // it went around: both ends of the box visited
    let xs: Vec<f64> = samples.iter().map(|s| s.truth.x).collect();
    assert!(xs.iter().cloned().fold(f64::MAX, f64::min) < 200.0 && xs.iter().cloned().fold(0.0, f64::max) > 550.0);
    let f = robot.controller().faults();
    assert_eq!((f.bus, f.timeout, f.missing, f.bad_sample, f.overruns), (0, 0, 0, 0, 0));
}

#[test]
fn the_same_seed_gives_the_same_run_and_another_seed_another() {
    let run = |seed: u64| {
        let mut robot = SimRobot::new(SimConfig { seed, locate_at_power_up: false, ..SimConfig::default() });
        let script = Script::parse(&default_script(5.0)).unwrap();
        let mut lines = vec![];
        robot.run_script(&script, 5_000_000, 10, |l| lines.push(l.to_string()));
        lines
    };
    assert_eq!(run(7), run(7));
    assert_ne!(run(7), run(8));
}

#[test]
fn a_lidar_pulled_out_is_counted_and_brought_back_after_the_back_off() {
    let mut robot = SimRobot::new(SimConfig { locate_at_power_up: false, ..SimConfig::default() });
    robot.send("rate 0");
    for _ in 0..20 {
        robot.tick();
    }
    robot.sensors.front.borrow_mut().set_present(false);
    for _ in 0..100 {
        robot.tick();
    }
    let ctl = robot.controller();
    assert!(!ctl.front_health().up);
    let f = ctl.faults();
    assert!(f.bus + f.timeout + f.missing >= 1, "{f:?}");
    assert!(ctl.right_health().up && ctl.compass_health().up, "the others keep working");
    robot.sensors.front.borrow_mut().set_present(true);
    for _ in 0..150 {
        robot.tick();
    }
    let ctl = robot.controller();
    assert!(ctl.front_health().up, "{:?}", ctl.front_health());
    assert!(ctl.front_health().reinits >= 1);
    let reading = ctl.last_front().unwrap();
    assert!(matches!(reading.range, Range::Target(_)), "{reading:?}");
}

#[test]
fn bytes_in_lines_out_one_tick_at_a_time() {
    let mut robot = SimRobot::new(SimConfig { locate_at_power_up: false, ..SimConfig::default() });
    for b in b"rate 0\nfwd 0.13\n" {
        robot.feed(*b);
    }
    assert_eq!(robot.take_output(), ["# ok rate 0", "# ok fwd 0.130"]);
    let x0 = robot.truth().x;
    for _ in 0..10 {
        robot.tick();
    }
    assert!(robot.truth().x > x0 + 10.0, "it drove: {:?}", robot.truth());
    assert_eq!(robot.now_us() % 10_000, robot.now_us() % 10_000);
    for _ in 0..60 {
        robot.tick();
    }
    assert_eq!(robot.take_output(), ["# deadman: no command, stopped"]);
}

// ---- calibration -------------------------------------------------------

/// Runs `cal` (with `args`) on a simulated robot until it answers; returns
/// the lines after the `# ok`.
fn calibrate(seed: u64, noise: Noise, command: &str) -> Vec<String> {
    let mut robot = SimRobot::new(SimConfig { seed, noise, locate_at_power_up: false, ..SimConfig::default() });
    robot.send("rate 0");
    robot.send(command);
    let samples = command.strip_prefix("cal").unwrap().trim().parse().unwrap_or(config::compass::CALIBRATION_SAMPLES);
    let out = robot.take_output();
    assert_eq!(out.last().cloned(), Some(format!("# ok cal {samples}")), "{out:?}");
    // the longest a sweep may take: all its samples at their time limit
    let cap = u64::from(samples + config::compass::CALIBRATION_EXTRA_SAMPLES);
    let limit_us = cap * u64::from(config::compass::CALIBRATION_MS_PER_SAMPLE) * 1000;
    let mut lines = Vec::new();
    while robot.now_us() < limit_us + 100_000 && !lines.iter().any(|l: &String| l.starts_with("# calibration ok")) {
        robot.tick();
        lines.extend(robot.take_output().into_iter().filter(|l| !l.starts_with("# deadman")));
        if lines.iter().any(|l| l.starts_with("# err")) {
            break;
        }
    }
    robot.tick();
    lines.extend(robot.take_output());
    lines
}

/// On the simulated floor a turn sweeps the field through x and y only
/// (z is the vertical field, whatever the heading), as on a real floor. A
/// `cal` recovers the simulated distortion (the config's calibration,
/// which the simulator's compass inverts): biases within 3 counts, scales
/// within 3 %, z kept from the config; with and without noise, for the
/// default sweep and for one turn's samples (`cal 250`).
#[test]
fn cal_in_the_simulator_recovers_the_simulated_distortion() {
    let cfg = config::compass::CALIBRATION;
    for (seed, noise, command) in [
        (1, Noise::default(), "cal"),
        (7, Noise::default(), "cal"),
        (3, Noise::OFF, "cal"),
        (5, Noise::default(), "cal 250"),
        (9, Noise::OFF, "cal 250"),
    ] {
        let lines = calibrate(seed, noise, command);
        let ok = lines.iter().position(|l| l.starts_with("# calibration ok")).unwrap_or_else(|| panic!("{lines:?}"));
        assert!(lines[ok].contains("z kept from config"), "{lines:?}");
        let line = lines[ok + 1].strip_prefix("# ").unwrap();
        assert!(line.starts_with("pub const CALIBRATION: MagCalibration = MagCalibration::from_f64(["), "{line}");
        assert!(line.ends_with("]);"), "{line}");
        let (bias, scale) = common::parse_calibration_line(line);
        for i in 0..3 {
            let want_scale = f64::from(cfg.scale_q16[i]) / 65536.0;
            assert!((bias[i] - f64::from(cfg.bias[i])).abs() <= 3.0, "{command} seed {seed}: bias {i}: {line}");
            assert!((scale[i] / want_scale - 1.0).abs() <= 0.03, "{command} seed {seed}: scale {i}: {line}");
        }
        assert_eq!(bias[2], f64::from(cfg.bias[2]), "z kept: {line}");
    }
}

#[test]
fn a_turn_in_the_simulator_leaves_z_alone() {
    let mut robot = SimRobot::new(SimConfig { locate_at_power_up: false, ..SimConfig::default() });
    robot.send("rate 0");
    let mut fields = Vec::new();
    for k in 0..300 {
        if k % 25 == 0 {
            robot.send("cw 2.5"); // within the deadman
        }
        robot.tick();
        fields.push(robot.sensors.mpu.borrow().ak.field());
    }
    let spread = |i: usize| {
        let v = fields.iter().map(|f| f[i]);
        v.clone().max().unwrap() - v.min().unwrap()
    };
    assert!(spread(0) > 200 && spread(1) > 200, "x and y sweep: {} {}", spread(0), spread(1));
    assert_eq!(spread(2), 0, "z moved while turning");
}

// ---- the realistic effects ----------------------------------------------

/// The cone's reading is the nearest wall point in the cone: against a
/// brute-force minimum over 2,001 thin rays across it, from random points
/// and directions in the box; and the thin ray's length with the cone off.
#[test]
fn the_lidar_cone_reads_the_nearest_wall_in_it() {
    use paperbot::sim::realism::lidar_range;
    let a = Arena::default();
    let lab = Realism::LAB;
    let half = lab.cone_deg.to_radians() / 2.0;
    let mut rng = paperbot::sim::noise::Rng::new(5);
    let mut worst: f64 = 0.0;
    let mut shorter = 0;
    for _ in 0..2_000 {
        let (x, y) = (rng.range_f64(1.0, a.length_x_mm() - 1.0), rng.range_f64(1.0, a.width_y_mm() - 1.0));
        let dir = rng.range_f64(0.0, 2.0 * PI);
        let (t, _) = lidar_range(&a, x, y, dir, &lab).unwrap();
        let brute = (0..=2000)
            .map(|i| a.ray_cast(x, y, dir - half + 2.0 * half * f64::from(i) / 2000.0).unwrap())
            .fold(f64::MAX, f64::min);
        // the brute force samples the cone: at most a little above the true minimum
        assert!(t <= brute + 1e-6 && brute - t < 0.05 + 1e-4 * brute, "{x} {y} {dir}: cone {t}, rays {brute}");
        worst = worst.max(brute - t);
        let thin = lidar_range(&a, x, y, dir, &Realism { cone_deg: 0.0, ..Realism::IDEAL }).unwrap().0;
        assert!((thin - a.ray_cast(x, y, dir).unwrap()).abs() < 1e-9);
        if t < thin - 1.0 {
            shorter += 1;
        }
    }
    println!("cone vs 2,001 rays: worst {worst:.4} mm; shorter than the thin ray by > 1 mm in {shorter} of 2,000");
    assert!(shorter > 1_000, "the cone matters at most angles");
}
