//! The simulator's worlds (`sim::realism`): each of the hard world's
//! effects is there when on, and absent in the lab's and the ideal world;
//! what a run draws is the same for the same seed and another for another.
//! Measured on the true body and the sensor models (f64), not on the
//! firmware's estimate.

use paperbot::config;
use paperbot::config::geometry::{FRONT_LIDAR, RIGHT_LIDAR, ROTATION_TO_REFERENCE};
use paperbot::sim::arena::Arena;
use paperbot::sim::body::PoseF64;
use paperbot::sim::drawn::Drawn;
use paperbot::sim::noise::Rng;
use paperbot::sim::realism::{lidar_range, Realism};
use paperbot::sim::robot::{lidar_truth, Noise, SimConfig, SimRobot};

const WORLDS: [(&str, Realism); 3] = [("ideal", Realism::IDEAL), ("lab", Realism::LAB), ("hard", Realism::HARD)];

/// A robot at the box's centre facing north that knows where it is, motion
/// noise off (so what is left is the world's).
fn robot(realism: Realism, seed: u64) -> SimRobot {
    let start = PoseF64::new(381.0, 247.0, 0.0);
    SimRobot::new(SimConfig {
        start,
        seed,
        realism,
        noise: Noise::OFF,
        locate_at_power_up: false,
        ..SimConfig::default()
    })
}

/// Drives `command` for its duration (and a little), returning the truth
/// every tick.
fn drive(robot: &mut SimRobot, command: &str, ticks: u32) -> Vec<PoseF64> {
    robot.send("rate 0");
    robot.send(command);
    (0..ticks)
        .map(|_| {
            robot.tick();
            robot.truth()
        })
        .collect()
}

/// The heading turned over a path, radians (unwrapped).
fn turned(path: &[PoseF64]) -> f64 {
    path.windows(2).map(|w| w[1].heading_error(&w[0])).sum()
}

/// A turn's rate against the same turn in the ideal world: in the hard
/// world each direction's factor lies in [0.6, 1.8] and is not 1 (most
/// seeds far from it), and is the run's draw (measured with the lab's
/// trial-to-trial spread off); in the lab's world within that spread of
/// 1, in the ideal world exactly 1.
#[test]
fn turn_rates_are_off_the_lab_line_in_the_hard_world_only() {
    let rate = |realism: Realism, seed: u64, command: &str| {
        let ideal = turned(&drive(&mut robot(Realism::IDEAL, seed), command, 60));
        turned(&drive(&mut robot(realism, seed), command, 60)) / ideal
    };
    let no_spread = Realism { speed_spread: [0.0; 4], ..Realism::HARD };
    let mut far = 0;
    for seed in 1..=10 {
        let (cw, ccw) = (rate(Realism::HARD, seed, "cw 2.5 0.5"), rate(Realism::HARD, seed, "ccw 2.5 0.5"));
        let drawn = *robot(no_spread, seed).drawn();
        // the turn starts after the first tick and lasts 0.5 s: its middle
        let want = [true, false].map(|clockwise| drawn.turn_factor(clockwise, 0.26, &no_spread));
        let exact = [rate(no_spread, seed, "cw 2.5 0.5"), rate(no_spread, seed, "ccw 2.5 0.5")];
        println!(
            "seed {seed}: hard world's turn rate over the lab line's: cw {cw:.3}, ccw {ccw:.3}; \
             without the trial spread {:.3}, {:.3}, drawn {:.3}, {:.3}",
            exact[0], exact[1], want[0], want[1]
        );
        for (got, want) in exact.iter().zip(want) {
            assert!((got / want - 1.0).abs() < 0.002, "seed {seed}: {got} vs the draw {want}");
        }
        // the lab's trial spread (a few %) comes on top of the factor
        for r in [cw, ccw] {
            assert!((0.6 * 0.92..=1.8 * 1.08).contains(&r), "seed {seed}: {r}");
            far += usize::from((r - 1.0).abs() > 0.05);
        }
        let lab = rate(Realism::LAB, seed, "cw 2.5 0.5");
        assert!((lab - 1.0).abs() < 0.1, "seed {seed}: lab {lab}");
        assert!((rate(Realism::IDEAL, seed, "cw 2.5 0.5") - 1.0).abs() < 1e-12);
    }
    assert!(far >= 14, "{far} of 20 factors more than 5 % off");
}

/// The factor drifts slowly in the hard world (within its range), not in
/// the others.
#[test]
fn the_turn_factor_drifts_in_the_hard_world_only() {
    for (name, r) in WORLDS {
        let d = Drawn::draw(3, &r, 0.0);
        let f: Vec<f64> = (0..600).map(|s| d.turn_factor(true, f64::from(s), &r)).collect();
        let (lo, hi) = f.iter().fold((f64::MAX, f64::MIN), |(a, b), &x| (a.min(x), b.max(x)));
        println!("{name}: clockwise factor over 10 minutes {lo:.3} to {hi:.3}");
        if name == "hard" {
            assert!(lo >= 0.6 && hi <= 1.8 && hi - lo > 0.05, "{lo} {hi}");
            // slowly: less than a percent of itself per second
            assert!(f.windows(2).all(|w| (w[1] - w[0]).abs() < 0.01 * w[0]));
        } else {
            assert_eq!((lo, hi), (1.0, 1.0));
        }
    }
}

/// Straight speed: within 15 % of the line in the hard world, and not the
/// line for most seeds; the line in the others (the lab's spread aside).
#[test]
fn the_speed_scale_is_drawn_in_the_hard_world_only() {
    let run = |r: Realism, seed: u64| {
        let path = drive(&mut robot(r, seed), "fwd 0.13 1", 110);
        path.last().unwrap().distance(&path[0])
    };
    let mut far = 0;
    for seed in 1..=10 {
        let ideal = run(Realism::IDEAL, seed);
        let (hard, lab) = (run(Realism::HARD, seed) / ideal, run(Realism::LAB, seed) / ideal);
        println!("seed {seed}: straight distance over the line's: hard {hard:.3}, lab {lab:.3}");
        assert!((0.85 * 0.92..=1.15 * 1.08).contains(&hard), "seed {seed}: {hard}");
        assert!((lab - 1.0).abs() < 0.08, "seed {seed}: lab {lab}");
        far += usize::from((hard - 1.0).abs() > 0.03);
    }
    assert!(far >= 6, "{far} of 10 more than 3 % off");
}

/// The pivot, measured from where a quarter turn takes the reference point
/// (a chord of the circle about the pivot, radius D plus the pivot's
/// distance behind the axle): 60 +- 20 mm (and the turn-to-turn spread) in
/// the hard world, about 10 in the lab's, 0 in the ideal world.
#[test]
fn turns_pivot_far_behind_the_axle_in_the_hard_world() {
    let d = ROTATION_TO_REFERENCE.to_mm_f64();
    let pivot = |r: Realism, seed: u64| {
        let path = drive(&mut robot(r, seed), "cw 2.5 0.3", 40);
        let angle = turned(&path).abs();
        let chord = path.last().unwrap().distance(&path[0]);
        chord / (2.0 * (angle / 2.0).sin()) - d
    };
    let mut hard = vec![];
    for seed in 1..=10 {
        let (h, l, i) = (pivot(Realism::HARD, seed), pivot(Realism::LAB, seed), pivot(Realism::IDEAL, seed));
        println!("seed {seed}: pivot behind the axle: hard {h:.1} mm, lab {l:.1} mm, ideal {i:.1} mm");
        assert!((40.0 - 15.0..=80.0 + 15.0).contains(&h), "seed {seed}: {h}");
        assert!((-5.0..=25.0).contains(&l), "seed {seed}: {l}");
        assert!(i.abs() < 1e-6, "seed {seed}: {i}");
        hard.push(h);
    }
    let mean = hard.iter().sum::<f64>() / 10.0;
    assert!((45.0..=75.0).contains(&mean), "{mean}");
}

/// The compass's bias over the floor: up to 12 degrees away from the walls
/// and up to 20 near them in the hard world, the lab's 2 degrees, none in
/// the ideal world; and the fake chip reads it (a standing robot's compass
/// is off by the bias where it stands).
#[test]
fn the_compass_bias_varies_over_the_floor_and_more_near_walls() {
    let a = Arena::default();
    for (name, r) in WORLDS {
        let mut rng = Rng::new(9);
        let (mut inner, mut near) = (0f64, 0f64);
        for seed in 1..=10 {
            let d = Drawn::draw(seed, &r, rng.range_f64(0.0, std::f64::consts::TAU));
            for i in 0..=76 {
                for j in 0..=49 {
                    let (x, y) = (f64::from(i) * 10.0, f64::from(j) * 10.0);
                    let b = d.compass_bias(&a, x, y, &r).to_degrees().abs();
                    if a.clearance(x, y) > 200.0 {
                        inner = inner.max(b);
                    } else if a.clearance(x, y) < 10.0 {
                        near = near.max(b);
                    }
                }
            }
        }
        println!("{name}: largest compass bias {inner:.1} deg away from the walls, {near:.1} deg within 10 mm of one");
        match name {
            // (the wall excursion's tail adds a little even 200 mm from the walls)
            "hard" => assert!(inner > 8.0 && inner <= 12.5 && near > 16.0 && near <= 20.0 + 1e-9, "{inner} {near}"),
            "lab" => assert!(inner <= 2.0 + 1e-9 && near <= 2.0 + 1e-9 && inner > 1.0),
            _ => assert_eq!((inner, near), (0.0, 0.0)),
        }
    }
    // through the chip and the driver: a standing robot near a wall
    let start = PoseF64::new(60.0, 247.0, 0.0);
    let cfg = SimConfig { start, seed: 4, realism: Realism::HARD, locate_at_power_up: false, ..SimConfig::default() };
    let mut robot = SimRobot::new(cfg);
    let bias = robot.drawn().compass_bias(&robot.cfg.arena, start.x, start.y, &Realism::HARD).to_degrees();
    robot.send("rate 0");
    let mut headings = vec![];
    for _ in 0..300 {
        robot.tick();
        if let Some(c) = robot.controller().last_compass() {
            headings.push(c.heading.to_signed_millidegrees() as f64 / 1000.0);
        }
        robot.send("stop");
    }
    let mean = headings.iter().sum::<f64>() / headings.len() as f64;
    println!("standing at {start:?}: compass reads {mean:.1} deg, bias there {bias:.1} deg");
    assert!(bias.abs() > 1.0 && (mean - bias).abs() < 1.0, "{mean} vs {bias}");
}

/// Many draws of one lidar's reading at `p` in world `r`: (mean, sd, share
/// more than 20 mm off `truth`).
fn readings(r: &Realism, p: &PoseF64, front: bool, truth: f64) -> (f64, f64, f64) {
    let mut rng = Rng::new(17);
    let mount = if front { FRONT_LIDAR } else { RIGHT_LIDAR };
    let v: Vec<f64> = (0..20_000).filter_map(|_| lidar_truth(&Arena::default(), r, p, &mount, &mut rng)).collect();
    let n = v.len() as f64;
    let mean = v.iter().sum::<f64>() / n;
    let sd = (v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / n).sqrt();
    (mean, sd, v.iter().filter(|x| (*x - truth).abs() > 20.0).count() as f64 / n)
}

/// The thin ray's length from the mount, plus its setback (the model's
/// distance).
fn thin(p: &PoseF64, front: bool) -> f64 {
    let mount = if front { FRONT_LIDAR } else { RIGHT_LIDAR };
    let (x, y, dir) = p.lidar_ray(&mount);
    let thin = Realism { cone_deg: 0.0, ..Realism::IDEAL };
    lidar_range(&Arena::default(), x, y, dir, &thin).unwrap().0 + PoseF64::along_beam_mm(&mount)
}

/// Square on a wall: the hard world's spurious readings are 5 % of all
/// (counted as those more than 20 mm off: the echoes 0.3 to 1.5 times the
/// range that land that far off), none in the lab's or the
/// ideal world. Oblique (40 degrees): the hard world reads the thin ray
/// (not the cone's nearest point) with noise grown with incidence.
#[test]
fn lidars_are_thin_beams_with_noise_growing_with_incidence_and_spurious_readings() {
    let square = PoseF64::new(381.0, 247.0, 0.0);
    let t = thin(&square, true);
    for (name, r) in WORLDS {
        let (mean, sd, off) = readings(&r, &square, true, t);
        println!(
            "{name}: square on at {t:.0} mm: mean {mean:.1} mm, sd {sd:.1} mm, {:.2} % more than 20 mm off",
            off * 100.0
        );
        if name == "hard" {
            // echoes 0.3 to 1.5 times the range from the mount land more
            // than 20 mm off but for a band of 40 mm about it
            let range = t - PoseF64::along_beam_mm(&FRONT_LIDAR);
            let want = config::sim::HARD_SPURIOUS_RATE * (1.0 - 40.0 / range / 1.2);
            assert!((off / want - 1.0).abs() < 0.15, "{off} want {want}");
        } else {
            assert_eq!(off, 0.0);
        }
    }
    let oblique = PoseF64::new(600.0, 100.0, 40f64.to_radians());
    let t = thin(&oblique, true);
    let (mean, sd, _) = readings(&Realism { spurious_rate: 0.0, ..Realism::HARD }, &oblique, true, t);
    let (lab_mean, lab_sd, _) = readings(&Realism::LAB, &oblique, true, t);
    println!("40 degrees on: thin ray {t:.0} mm; hard mean {mean:.1} sd {sd:.1} mm; lab (cone) {lab_mean:.1} sd {lab_sd:.1} mm");
    assert!((mean - t).abs() < 1.0, "the thin beam: {mean} vs {t}");
    assert!(lab_mean < t - 20.0 && lab_sd < 1e-9, "the lab's cone: nearest wall point, no noise before the sensor's");
    // 5 % of the range times tan(40 deg), about 7 mm at these ranges
    let want = 0.05 * (t - PoseF64::along_beam_mm(&FRONT_LIDAR)) * 40f64.to_radians().tan();
    assert!((sd / want - 1.0).abs() < 0.1, "sd {sd} want {want}");
}

/// A beam into a corner: its footprint spans both walls, and the hard
/// world's readings spread between their ranges; the lab's cone reads one
/// nearest point every time.
#[test]
fn a_beam_into_a_corner_returns_mixed_ranges_in_the_hard_world() {
    let corner = PoseF64::new(650.0, 380.0, 45f64.to_radians());
    let t = thin(&corner, true);
    let quiet = Realism { spurious_rate: 0.0, lidar_incidence_noise: 0.0, ..Realism::HARD };
    let (mean, sd, _) = readings(&quiet, &corner, true, t);
    let (lab_mean, lab_sd, _) = readings(&Realism::LAB, &corner, true, t);
    println!(
        "into the corner: thin ray {t:.0} mm; hard mean {mean:.1} sd {sd:.1} mm; lab {lab_mean:.1} sd {lab_sd:.1}"
    );
    assert!(sd > 5.0, "mixed returns spread: {sd}");
    assert!(lab_sd < 1e-9);
    // away from corners the footprint meets one wall: no mixing
    let square = PoseF64::new(381.0, 247.0, 0.0);
    assert!(readings(&quiet, &square, true, 0.0).1 < 1e-9);
}

/// Same seed, same run (lines and truth); another seed, another; and the
/// lab's world draws what it drew before the hard world existed (its
/// stream untouched: a run's lines are those of a lab run whose draws are
/// neutral).
#[test]
fn the_hard_world_is_the_same_for_the_same_seed() {
    let run = |seed: u64| {
        let cfg = SimConfig { seed, realism: Realism::HARD, locate_at_power_up: false, ..SimConfig::default() };
        let mut robot = SimRobot::new(cfg);
        let script = paperbot::sim::script::Script::parse(&paperbot::sim::script::default_script(10.0)).unwrap();
        let mut lines = vec![];
        let samples = robot.run_script(&script, 10_000_000, 10, |l| lines.push(l.to_string()));
        (lines, samples.last().unwrap().truth, *robot.drawn())
    };
    assert_eq!(run(7), run(7));
    let (a, b) = (run(7), run(8));
    assert_ne!(a.0, b.0);
    assert_ne!(a.2, b.2);
    let lab = Drawn::draw(7, &Realism::LAB, 0.5);
    assert_eq!((lab.turn_scale, lab.speed_scale, lab.pivot_offset_mm), ([1.0; 2], 1.0, 0.0));
}
