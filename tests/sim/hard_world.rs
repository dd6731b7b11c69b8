//! Issue #29's "done when" for the estimator, measured: 20 seeds x 10
//! simulated minutes of `goto` laps (the built-in script) from the
//! power-up localization, in the lab's and in the hard world
//! (`sim::realism`). Per run: the RMS of the position error, the worst
//! error, wall collisions, and the invariants: while the servos stand
//! still the reported position moves at most 10 mm; between consecutive
//! telemetry rows (10 Hz) it never moves more than the wheels can drive
//! (the reference point swinging about the run's pivot at the fastest
//! turn) plus 25 mm; every reported pose lies in the box. Samples taken while
//! the robot localizes do not count (it claims no pose then), nor, for the
//! invariants, while the estimate is `unknown` (the known start's typed
//! pose before the sensors place it: its first ticks broke them in 3 of
//! 20 hard runs, a 121 mm move and poses 50 mm outside the box, all while
//! `unknown`).
//!
//! Both worlds are asserted: the lab's figures must not get worse, and the
//! hard world's power-up laps meet the issue's bars (median of the runs'
//! RMS <= 15 mm, worst run's RMS <= 50 mm, no collision, the invariants),
//! as does its tracking from a known start. Each run prints its figures,
//! its learned lidar spot and how many `goto`s localized first
//! (`-- --nocapture`); `PAPERBOT_FIRST_SEED` and `PAPERBOT_SEEDS` run other
//! seeds (the bars are the issue's 20 from seed 1).
//!
//! Measured (lab world): see `lab_world_laps_keep_their_figures`; the hard
//! world, the power-up fix refined (the default): median rms 13.1 mm, the
//! worst run 17.4 (12.2 and 14.8 before each turn's pivot move in the
//! refinement and the survey's drive that ends at a wall ahead,
//! `config::refine::PIVOT_MOVE_SIGMA_MM`, `control::survey::room::drive_ends`;
//! 12.9 and 16.4 before the compass's bend and the
//! survey's search-on limit, `config::refine::FIELD_SIGMA_DEG` and
//! `SEARCH_ON_LIMIT`; 14.2 and 44.2 unrefined; seeds 21-220: 12.5 and 65.6, 2
//! runs touching a wall); docs/simulator.md. Before the refinement and the
//! corner's variance: median rms 13.3 mm, the worst run 33.9 mm,
//! every run located, no collision, the invariants kept, since a `goto`
//! waits for competing hypotheses to settle before it localizes; other
//! blocks of 20 seeds measure 13.4, 16.4 and 16.6 mm, 80 seeds 14.1 mm:
//! the median's margin is within the seeds' spread. Before the wait: 15.4
//! mm, 29.1, 1 with collisions (6 ticks); 14.9 mm with 1 run never located
//! before the search's axis guess; 17.7 mm and 3 with collisions before
//! the search read the learned spot; 28.0 mm and 2 with collisions before
//! the learned spot; 19 with collisions before the survey made room to
//! turn; 36.3 mm and 18 with collisions before the learned pivot; 125.7
//! mm, 2 never located and 16 before the lighter secondary hypotheses and
//! the search's pivot and fourth view). The hard effects one at a time are
//! the ignored test at the end: docs/simulator.md has their table.

use paperbot::config;
use paperbot::control::TICK_US;
use paperbot::model::estimator::Tracking;
use paperbot::sim::body::PoseF64;
use paperbot::sim::realism::Realism;
use paperbot::sim::robot::{SimConfig, SimRobot};
use paperbot::sim::script::{default_script, Script};

const MINUTES: u64 = 10;
const SEEDS: u64 = 20;
/// Standing still, the reported position moves at most this, mm.
const STANDSTILL_MM: f64 = 10.0;
/// Between rows it moves at most what the wheels can drive plus this, mm.
const STEP_SLACK_MM: f64 = 25.0;
/// Telemetry rows every this many ticks (10 Hz).
const ROW_TICKS: u64 = 10;

/// One run's figures.
#[derive(Debug, Default)]
struct Run {
    /// The power-up localization gave a fix (else nothing below counts).
    located: bool,
    rms_mm: f64,
    worst_mm: f64,
    collisions: u32,
    /// Largest move of the reported position while the servos stood
    /// still, mm.
    standstill_mm: f64,
    /// Largest move between rows beyond what the wheels can drive, mm
    /// (negative: within).
    step_excess_mm: f64,
    /// Largest distance of a reported pose outside the box, mm.
    outside_mm: f64,
    /// The lidar spot's learned share at the end (0 the cone's nearest
    /// point, 1 the axis) and the batches it learned from.
    spot: (f64, u16),
    /// `goto`s that found the estimate too uncertain and localized first.
    localized_again: u32,
}

impl Run {
    fn invariants_hold(&self) -> bool {
        self.located
            && self.standstill_mm <= STANDSTILL_MM
            && self.step_excess_mm <= STEP_SLACK_MM
            && self.outside_mm == 0.0
    }
}

/// What the wheels can drive in `dt_s`, mm: the protocol's fastest straight
/// speed, or the reference point's swing at the fastest turn rate about a
/// pivot `pivot_mm` behind the axle (the run's: the reference point is D +
/// pivot from it).
fn wheels_can_drive_mm(dt_s: f64, pivot_mm: f64) -> f64 {
    let d = config::geometry::ROTATION_TO_REFERENCE.to_mm_f64() + pivot_mm.max(0.0);
    let straight = f64::from(config::serial::MAX_SPEED_MM_S);
    let swing = d * f64::from(config::serial::MAX_TURN_MRAD_S) / 1000.0;
    straight.max(swing) * dt_s
}

/// Where a run's estimate starts.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
enum Start {
    /// From the power-up localization (the issue's bar).
    Localized,
    /// Told the true start pose: the tracking alone.
    Known,
}

fn laps(realism: Realism, seed: u64, start: Start) -> Run {
    let locate_at_power_up = start == Start::Localized;
    let mut robot = SimRobot::new(SimConfig { seed, realism, locate_at_power_up, ..SimConfig::default() });
    robot.send("rate 0");
    let limit = (config::locate::LONGEST_MS + 1_000) / 10;
    let located = !locate_at_power_up
        || (0..limit).any(|_| {
            robot.tick();
            robot.take_output().iter().any(|l| l.starts_with("# located "))
        });
    if !located {
        return Run::default();
    }
    let duration_us = MINUTES * 60_000_000;
    let script = Script::parse(&default_script(duration_us as f64 / 1e6)).unwrap();
    let stop = robot.controller().model().stop();
    let (lx, wy) = (robot.cfg.arena.length_x_mm(), robot.cfg.arena.width_y_mm());
    // the run's pivot, with its turn-to-turn spread (two sigma)
    let pivot = realism.pivot_behind_mm + robot.drawn().pivot_offset_mm + 2.0 * realism.pivot_spread_mm;
    let allowed = wheels_can_drive_mm(ROW_TICKS as f64 * f64::from(TICK_US) * 1e-6, pivot);
    let mut run = Run { located: true, step_excess_mm: f64::MIN, ..Run::default() };
    let (mut sum_sq, mut n) = (0.0, 0u64);
    let mut standing_since: Option<PoseF64> = None;
    let mut last_row: Option<PoseF64> = None;
    let start = robot.now_us();
    let mut lines = script.lines.iter().peekable();
    for tick in 0..duration_us / u64::from(TICK_US) {
        let t = robot.now_us() - start;
        while let Some(l) = lines.next_if(|l| l.at_us <= t) {
            robot.send(&l.command);
        }
        robot.tick();
        let lines = robot.take_output();
        run.localized_again += lines.iter().filter(|l| l.ends_with(": locating first")).count() as u32;
        let s = robot.sample();
        let servos = *robot.controller_mut().servos();
        if s.locating {
            (standing_since, last_row) = (None, None);
            continue;
        }
        let e = s.estimate;
        let err = e.distance(&s.truth);
        (sum_sq, n) = (sum_sq + err * err, n + 1);
        run.worst_mm = run.worst_mm.max(err);
        if robot.controller().estimator().tracking() == Tracking::Unknown {
            // a pose reported `unknown` (a typed start converging) claims
            // nothing either: counted in the error, not the invariants
            (standing_since, last_row) = (None, None);
            continue;
        }
        run.outside_mm = run.outside_mm.max((-e.x).max(e.x - lx).max(-e.y).max(e.y - wy).max(0.0));
        if (servos.left, servos.right) == (stop.left, stop.right) {
            let anchor = *standing_since.get_or_insert(e);
            run.standstill_mm = run.standstill_mm.max(anchor.distance(&e));
        } else {
            standing_since = None;
        }
        if tick % ROW_TICKS == 0 {
            if let Some(prev) = last_row {
                run.step_excess_mm = run.step_excess_mm.max(prev.distance(&e) - allowed);
            }
            last_row = Some(e);
        }
    }
    run.rms_mm = (sum_sq / n.max(1) as f64).sqrt();
    run.collisions = robot.collisions();
    let (share, batches) = robot.controller().estimator().lidar_spot();
    run.spot = (f64::from(share) / f64::from(1 << 30), batches);
    run
}

/// Runs the seeds, prints each and the summary; returns (median RMS,
/// worst RMS, runs).
fn world(name: &str, realism: Realism, start: Start) -> (f64, f64, Vec<Run>) {
    let env = |name: &str, default: u64| std::env::var(name).ok().and_then(|s| s.parse().ok()).unwrap_or(default);
    let (first, seeds) = (env("PAPERBOT_FIRST_SEED", 1), env("PAPERBOT_SEEDS", SEEDS));
    let runs: Vec<Run> = (first..first + seeds).map(|seed| laps(realism, seed, start)).collect();
    for (seed, r) in (first..).zip(&runs) {
        println!(
            "{name} seed {seed:2}: {} rms {:6.1} mm, worst {:6.1} mm; {} collision ticks; standing still moved {:5.1} mm, \
             row step beyond the wheels' {:6.1} mm, outside the box {:5.1} mm; spot share {:.2} ({} batches); \
             localized again {}{}",
            if r.located { "located;" } else { "NEVER LOCATED;" },
            r.rms_mm,
            r.worst_mm,
            r.collisions,
            r.standstill_mm,
            r.step_excess_mm,
            r.outside_mm,
            r.spot.0,
            r.spot.1,
            r.localized_again,
            if r.invariants_hold() { "" } else { "  (invariants broken)" }
        );
    }
    let mut rms: Vec<f64> = runs.iter().map(|r| if r.located { r.rms_mm } else { f64::INFINITY }).collect();
    rms.sort_by(f64::total_cmp);
    let (median, worst) = (rms[rms.len() / 2], rms[rms.len() - 1]);
    println!(
        "{name} world, {seeds} seeds x {MINUTES} min of goto laps: median rms {median:.1} mm, worst run's rms {worst:.1} mm; \
         {} runs never located; {} runs with collisions ({} ticks); {} runs break the invariants \
         (standing still <= {STANDSTILL_MM} mm, row steps <= wheels + {STEP_SLACK_MM} mm, in the box); \
         {} gotos localized first",
        runs.iter().filter(|r| !r.located).count(),
        runs.iter().filter(|r| r.collisions > 0).count(),
        runs.iter().map(|r| r.collisions).sum::<u32>(),
        runs.iter().filter(|r| !r.invariants_hold()).count(),
        runs.iter().map(|r| r.localized_again).sum::<u32>(),
    );
    (median, worst, runs)
}

/// The issue's bars in the hard world, from the power-up localization
/// (see the module docs).
#[test]
fn hard_world_laps_meet_the_issues_bars() {
    let (median, worst, runs) = world("hard", Realism::HARD, Start::Localized);
    assert!(median <= 15.0, "median rms {median:.1} mm");
    assert!(worst <= 50.0, "worst rms {worst:.1} mm");
    assert!(runs.iter().all(|r| r.collisions == 0), "collisions");
    assert!(runs.iter().all(Run::invariants_hold), "invariants");
}

/// The lab's world: what holds today, every invariant included. Measured
/// figures are printed (`-- --nocapture`). (The one-hypothesis estimator
/// with re-acquisition broke the standstill invariant in 18 of the 20
/// runs, up to 22 mm while the servos stood still.)
#[test]
fn lab_world_laps_keep_their_figures() {
    let (median, worst, runs) = world("lab", Realism::LAB, Start::Localized);
    assert!(median <= 5.0, "median rms {median:.1} mm");
    assert!(worst <= 10.0, "worst rms {worst:.1} mm");
    assert!(runs.iter().all(|r| r.located && r.collisions == 0), "never located, or collisions");
    assert!(runs.iter().all(Run::invariants_hold), "invariants");
}

/// The hard world's tracking alone: each run told its true start pose (no
/// localization; its first `goto` still locates, the heading too
/// uncertain). The issue's bars hold here too (median 14.0 mm, worst 21.8;
/// 12.9 and 19.0 before each turn's pivot move and the drive that ends at
/// a wall ahead, whose seed 1 touched a wall without it).
#[test]
fn hard_world_tracking_from_a_known_start() {
    let (median, worst, runs) = world("hard, known start", Realism::HARD, Start::Known);
    assert!(median <= 15.0, "median rms {median:.1} mm");
    assert!(worst <= 50.0, "worst rms {worst:.1} mm");
    assert!(runs.iter().all(|r| r.collisions == 0), "collisions");
    assert!(runs.iter().all(Run::invariants_hold), "invariants");
}

/// The hard world's effects one at a time, tracking from a known start:
/// the hard world with one effect put back to the lab's, and the lab's
/// with one effect of the hard world's. Prints the median and worst RMS of
/// each (docs/simulator.md has the table); asserts nothing but that the
/// two worlds' ends differ.
#[test]
#[ignore = "issue #29: prints which of the hard world's effects the tracking fails on"]
fn hard_world_effects_one_at_a_time() {
    let (lab, hard) = (Realism::LAB, Realism::HARD);
    let variants: [(&str, Realism, Realism); 6] = [
        ("thin beam", Realism { cone_deg: lab.cone_deg, ..hard }, Realism { cone_deg: hard.cone_deg, ..lab }),
        (
            "pivot",
            Realism { pivot_behind_mm: lab.pivot_behind_mm, pivot_run_mm: lab.pivot_run_mm, ..hard },
            Realism { pivot_behind_mm: hard.pivot_behind_mm, pivot_run_mm: hard.pivot_run_mm, ..lab },
        ),
        (
            "compass bias",
            Realism {
                compass_disturbance_deg: lab.compass_disturbance_deg,
                compass_wall_deg: lab.compass_wall_deg,
                ..hard
            },
            Realism {
                compass_disturbance_deg: hard.compass_disturbance_deg,
                compass_wall_deg: hard.compass_wall_deg,
                compass_wall_decay_mm: hard.compass_wall_decay_mm,
                compass_wall_wavelength_mm: hard.compass_wall_wavelength_mm,
                ..lab
            },
        ),
        (
            "turn rates",
            Realism { turn_scale: lab.turn_scale, turn_drift: lab.turn_drift, ..hard },
            Realism {
                turn_scale: hard.turn_scale,
                turn_drift: hard.turn_drift,
                turn_drift_period_s: hard.turn_drift_period_s,
                ..lab
            },
        ),
        ("speed", Realism { speed_scale: lab.speed_scale, ..hard }, Realism { speed_scale: hard.speed_scale, ..lab }),
        (
            "lidar noise, spurious, corners",
            Realism {
                lidar_incidence_noise: lab.lidar_incidence_noise,
                spurious_rate: lab.spurious_rate,
                corner_mix_half_deg: lab.corner_mix_half_deg,
                ..hard
            },
            Realism {
                lidar_incidence_noise: hard.lidar_incidence_noise,
                spurious_rate: hard.spurious_rate,
                corner_mix_half_deg: hard.corner_mix_half_deg,
                ..lab
            },
        ),
    ];
    let mut table = Vec::new();
    for (effect, hard_without, lab_with) in variants {
        let (m1, w1, r1) = world(&format!("hard without {effect}"), hard_without, Start::Known);
        let (m2, w2, r2) = world(&format!("lab with {effect}"), lab_with, Start::Known);
        let collided = |runs: &[Run]| runs.iter().filter(|r| r.collisions > 0).count();
        table.push(format!(
            "| {effect} | {m1:.1} / {w1:.1} mm, {} collided | {m2:.1} / {w2:.1} mm, {} collided |",
            collided(&r1),
            collided(&r2)
        ));
    }
    let (m_lab, ..) = world("lab", lab, Start::Known);
    let (m_hard, ..) = world("hard", hard, Start::Known);
    println!("| effect | hard without it (median / worst rms) | lab with it |");
    println!("| --- | --- | --- |");
    for row in &table {
        println!("{row}");
    }
    println!("(known start: lab median {m_lab:.1} mm, hard {m_hard:.1} mm)");
    assert!(m_hard > m_lab, "the hard world is harder");
}
