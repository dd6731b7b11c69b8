//! The replay tool's core (`model::estimator::replay`) on the shipped sample
//! log, which the truth simulation made: the replay must reproduce the
//! estimator's run bit for bit, and track the truth.

use crate::common;
use common::estimator::*;
use paperbot::model::estimator::replay::{self, ReplayError};
use paperbot::model::measurement::Arena;

const SAMPLE: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/estimator/replay_sample.csv");
const SAMPLE_TRUTH: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/estimator/replay_sample_truth.csv");
const SAMPLE_SEED: u64 = 42;
const SAMPLE_SECONDS: f64 = 20.0;

fn sample_scenario() -> Scenario {
    let mut sc = Scenario::new(SAMPLE_SEED);
    sc.seconds = SAMPLE_SECONDS;
    sc
}

fn truth_csv(res: &RunResult) -> String {
    let mut s = String::from("t_ms,x_mm,y_mm,theta_deg\n");
    for (row, (_, t)) in res.log.iter().zip(&res.truth) {
        // the truth at the end of the tick, i.e. at the next row's time
        s += &format!("{},{:.3},{:.3},{:.4}\n", row.t_ms + 10, t.x, t.y, t.theta.to_degrees().rem_euclid(360.0));
    }
    s
}

/// Writes the sample files: `cargo test --test estimator replay:: -- --ignored`.
#[test]
#[ignore]
fn regenerate_sample() {
    let res = run(&sample_scenario(), |_, _, _| {});
    std::fs::create_dir_all(std::path::Path::new(SAMPLE).parent().unwrap()).unwrap();
    std::fs::write(SAMPLE, replay_log(&res)).unwrap();
    std::fs::write(SAMPLE_TRUTH, truth_csv(&res)).unwrap();
}

#[test]
fn sample_log_is_what_the_simulation_makes() {
    let res = run(&sample_scenario(), |_, _, _| {});
    let text = std::fs::read_to_string(SAMPLE).unwrap();
    assert_eq!(text, replay_log(&res), "regenerate with `cargo test --test estimator replay:: -- --ignored`");
    assert_eq!(std::fs::read_to_string(SAMPLE_TRUTH).unwrap(), truth_csv(&res));
}

#[test]
fn replay_reproduces_the_estimator_bit_for_bit_and_tracks_the_truth() {
    let res = run(&sample_scenario(), |_, _, _| {});
    let samples = replay::parse(&std::fs::read_to_string(SAMPLE).unwrap()).unwrap();
    assert_eq!(samples.len(), res.log.len());
    let (est, stats) = replay::replay(&samples, replay::Start::Pose(res.start), Arena::DEFAULT);
    // row k + 1 of the replay is the estimate after tick k of the run
    for (k, pose) in res.poses.iter().enumerate().take(res.poses.len() - 1) {
        assert_eq!(est[k + 1].pose, *pose, "row {}", k + 1);
    }
    assert!(stats.front.accepted > 300 && stats.compass.accepted > 1900, "{stats:?}");
    // and against the truth file
    let truth: Vec<(u32, f64, f64, f64)> = std::fs::read_to_string(SAMPLE_TRUTH)
        .unwrap()
        .lines()
        .skip(1)
        .map(|l| {
            let f: Vec<f64> = l.split(',').map(|v| v.parse().unwrap()).collect();
            (f[0] as u32, f[1], f[2], f[3])
        })
        .collect();
    let out = replay::to_csv(&est);
    let rows: Vec<Vec<f64>> = out.lines().skip(1).map(|l| l.split(',').map(|v| v.parse().unwrap()).collect()).collect();
    let (mut se_pos, mut se_deg, mut n) = (0.0, 0.0, 0.0);
    for (t, x, y, th) in &truth {
        let r = rows.iter().find(|r| r[0] as u32 == *t);
        let Some(r) = r else { continue };
        se_pos += (r[1] - x).powi(2) + (r[2] - y).powi(2);
        se_deg += wrap((r[3] - th).to_radians()).to_degrees().powi(2);
        n += 1.0;
    }
    let (rms_pos, rms_deg) = ((se_pos / n).sqrt(), (se_deg / n).sqrt());
    println!("replay of the sample: {rms_pos:.2} mm / {rms_deg:.2} deg rms against the truth over {n} rows");
    assert!(n > 1900.0 && rms_pos < 15.0 && rms_deg < 2.0);
}

#[test]
fn parse_rejects_bad_logs_with_the_line() {
    let h = replay::HEADER;
    let cases: &[(String, ReplayError)] = &[
        ("t,l,r\n0,90,90,,,\n".into(), ReplayError::Header),
        (format!("{h}\n0,90,90,,\n"), ReplayError::Fields { line: 2 }),
        (format!("{h}\n0,90,90,,,\nx,90,90,,,\n"), ReplayError::Field { line: 3, column: "t_ms" }),
        (format!("{h}\n0,190,90,,,\n"), ReplayError::Field { line: 2, column: "left_cmd" }),
        (format!("{h}\n0,90,90,-5,,\n"), ReplayError::Field { line: 2, column: "front_mm" }),
        (format!("{h}\n0,90,90,,70000,\n"), ReplayError::Field { line: 2, column: "right_mm" }),
        (format!("{h}\n0,90,90,,,NaN\n"), ReplayError::Field { line: 2, column: "heading_deg" }),
        (format!("{h}\n10,90,90,,,\n5,90,90,,,\n"), ReplayError::TimeBackwards { line: 3 }),
    ];
    for (text, want) in cases {
        assert_eq!(replay::parse(text).unwrap_err(), *want, "{text}");
    }
    let ok = replay::parse(&format!("{h}\n0,110,61,400,300,12.5\n10,90.5,90,,,\n")).unwrap();
    assert_eq!(ok.len(), 2);
    assert_eq!(ok[0].front_mm, Some(400));
    assert_eq!(ok[1].front_mm, None);
    assert_eq!(ok[1].heading, None);
    assert_eq!(ok[1].left.to_q8(), 90 * 256 + 128);
}

#[test]
fn stopped_robot_stays_put_and_readings_pull_it_to_the_truth() {
    // 2 s standing still at (200, 150) facing north, perfect readings; the
    // start guess is 30 mm and 5 degrees off.
    let (lx, wy) = (762.5, 495.0);
    let truth = PoseF64 { x: 200.0, y: 150.0, theta: 0.0 };
    let f = true_range(truth, &paperbot::config::geometry::FRONT_LIDAR, lx, wy);
    let r = true_range(truth, &paperbot::config::geometry::RIGHT_LIDAR, lx, wy);
    let fr = raw_reading(&paperbot::config::lidar::FRONT, f).round();
    let rr = raw_reading(&paperbot::config::lidar::RIGHT, r).round();
    let mut log = String::from(replay::HEADER);
    log.push('\n');
    for k in 0..200 {
        log += &format!("{},90,90,{fr},{rr},0\n", k * 10);
    }
    let start = PoseF64 { x: 220.0, y: 130.0, theta: 5f64.to_radians() }.to_pose();
    let (est, _) = replay::replay(&replay::parse(&log).unwrap(), replay::Start::Pose(start), Arena::DEFAULT);
    let last = est.last().unwrap().pose;
    // the readings are rounded to whole mm: the model maps them within ~1 mm
    assert!((last.x.to_mm_f64() - 200.0).abs() < 1.5, "{}", last.x.to_mm_f64());
    assert!((last.y.to_mm_f64() - 150.0).abs() < 1.5, "{}", last.y.to_mm_f64());
    // the compass reads heading plus a bias the filter does not know (10
    // degrees one sigma) and square-on lidars do not see the heading: it
    // splits the 5 degrees between them
    let th = wrap(last.theta.to_radians_f64()).to_degrees();
    assert!(th.abs() < 2.0, "{th}");
}
