//! The turn's pivot, learned (issue 29, `model::estimator::pivot`): in a
//! world whose turns pivot 40 to 80 mm behind the axle (the hard
//! simulator's pivot, the rest the lab's), two minutes of `goto` laps from
//! a known start teach the estimator where the robot pivots, and the
//! estimate stays within the lab's figures; a localization keeps what was
//! learned, a typed `pose` forgets it.

use paperbot::sim::realism::Realism;
use paperbot::sim::robot::{SimConfig, SimRobot};
use paperbot::sim::script::{default_script, Script};

/// The lab's world with the hard world's pivot.
fn pivoting() -> Realism {
    let hard = Realism::HARD;
    Realism { pivot_behind_mm: hard.pivot_behind_mm, pivot_run_mm: hard.pivot_run_mm, ..Realism::LAB }
}

/// `seconds` of the built-in laps from the true start; the RMS error over
/// the second half, mm.
fn laps(robot: &mut SimRobot, seconds: f64) -> f64 {
    robot.send("rate 0");
    let script = Script::parse(&default_script(seconds)).unwrap();
    let start = robot.now_us();
    let mut lines = script.lines.iter().peekable();
    let (mut sum_sq, mut n) = (0.0, 0u32);
    for tick in 0..(seconds * 100.0) as u64 {
        let t = robot.now_us() - start;
        while let Some(l) = lines.next_if(|l| l.at_us <= t) {
            robot.send(&l.command);
        }
        robot.tick();
        robot.take_output();
        if tick as f64 >= seconds * 50.0 {
            let s = robot.sample();
            let e = s.estimate.distance(&s.truth);
            (sum_sq, n) = (sum_sq + e * e, n + 1);
        }
    }
    (sum_sq / f64::from(n.max(1))).sqrt()
}

#[test]
fn where_turns_pivot_is_learned_from_the_lidars() {
    let realism = pivoting();
    for seed in 1..=5 {
        let mut robot = SimRobot::new(SimConfig { seed, realism, locate_at_power_up: false, ..SimConfig::default() });
        let rms = laps(&mut robot, 120.0);
        let truth = realism.pivot_behind_mm + robot.drawn().pivot_offset_mm;
        let (learned, turns) = robot.controller().estimator().pivot();
        let learned = learned.to_mm_f64();
        println!("seed {seed}: pivot {truth:.1} mm behind the axle, learned {learned:.1} from {turns} turns; rms {rms:.1} mm");
        assert!((learned - truth).abs() <= 5.0, "seed {seed}: learned {learned:.1} mm, true {truth:.1}");
        assert!(rms <= 8.0, "seed {seed}: rms {rms:.1} mm");
    }
}

#[test]
fn a_localization_keeps_what_was_learned_and_a_typed_pose_forgets_it() {
    let mut robot =
        SimRobot::new(SimConfig { seed: 3, realism: pivoting(), locate_at_power_up: false, ..SimConfig::default() });
    assert_eq!(robot.controller().estimator().learned_turn_centre(), None, "nothing learned before a turn");
    laps(&mut robot, 60.0);
    let learned = robot.controller().estimator().pivot();
    assert!(learned.0.to_mm_f64() > 30.0, "{learned:?}");
    // what goto plans its turns about: D (56 mm) plus the learned pivot
    let centre = robot.controller().estimator().learned_turn_centre().unwrap();
    assert!((centre.to_mm_f64() - 56.0 - learned.0.to_mm_f64()).abs() < 1e-3, "{centre:?}");
    robot.send("locate");
    for _ in 0..(paperbot::config::locate::LONGEST_MS / 10) {
        robot.tick();
        if robot.take_output().iter().any(|l| l.starts_with("# located ")) {
            break;
        }
    }
    let e = robot.controller().estimator();
    assert_eq!(e.pivot(), learned, "kept through the localization");
    robot.send("pose 380 250 0");
    robot.tick();
    let e = robot.controller().estimator();
    assert_eq!(e.pivot(), (paperbot::math::Length::ZERO, 0), "a typed pose starts over");
    assert_eq!(e.learned_turn_centre(), None);
}
