//! Fitting the lab's data reproduces the report's coefficients (and the
//! config's): within 1 % for every actuator line (with the data's sign for
//! forward-right), 1 % for the lidar slopes, 1 mm for the lidar intercepts.
mod common;
use paperbot::config;
use paperbot::model::actuator::WheelLine;
use paperbot::model::fit::{self, fit_line};

fn within_pct(got: f64, want: f64, pct: f64) -> bool {
    ((got - want) / want).abs() * 100.0 <= pct
}

#[test]
fn least_squares_recovers_an_exact_line() {
    let f = fit_line((0..10).map(|x| (x as f64, 3.0 * x as f64 - 2.0))).unwrap();
    assert!((f.slope - 3.0).abs() < 1e-12 && (f.intercept + 2.0).abs() < 1e-12 && (f.r2 - 1.0).abs() < 1e-12);
    assert!(fit_line([(1.0, 1.0)]).is_none());
    assert!(fit_line([(1.0, 1.0), (1.0, 2.0)]).is_none(), "no spread in x");
}

#[test]
fn servo_runs_reproduce_the_reports_eight_lines() {
    let runs = fit::parse_servo_runs(&common::lab1("servo_runs.csv")).unwrap();
    assert_eq!(runs.len(), 200);
    let r = config::geometry::WHEEL_RADIUS.to_mm_f64() / 1000.0;
    // (motion, report left (m, b), report right (m, b) with the data's sign for forward right)
    let table = [
        ("forward", (0.14, -8.205), (-0.146, 15.85)),
        ("backward", (-0.205, 19.77), (0.195, -13.95)),
        ("cw", (0.0862, -6.2423), (0.1431, -13.442)),
        ("ccw", (-0.0908, 8.6171), (-0.0344, 4.7604)),
    ];
    for (motion, (lm, lb), (rm, rb)) in table {
        let f = fit::fit_motion(&runs, motion, r).unwrap();
        for (side, got, m, b) in [("left", f.left, lm, lb), ("right", f.right, rm, rb)] {
            println!("{motion} {side}: y = {:.4} x + {:.4} (report {m} x + {b})", got.slope, got.intercept);
            assert!(within_pct(got.slope, m, 1.0), "{motion} {side} slope {} vs {m}", got.slope);
            assert!(within_pct(got.intercept, b, 1.0), "{motion} {side} intercept {} vs {b}", got.intercept);
        }
    }
    // the report's printed forward-right line has the wrong sign: the data rejects it
    let f = fit::fit_motion(&runs, "forward", r).unwrap();
    assert!(!within_pct(f.right.slope, 0.145, 100.0));
}

#[test]
fn config_lines_are_the_fitted_lines_and_ranges() {
    let runs = fit::parse_servo_runs(&common::lab1("servo_runs.csv")).unwrap();
    let r = config::geometry::WHEEL_RADIUS.to_mm_f64() / 1000.0;
    let a = config::actuators::MODEL;
    for (motion, lines) in [("forward", a.forward), ("backward", a.backward), ("cw", a.cw), ("ccw", a.ccw)] {
        let f = fit::fit_motion(&runs, motion, r).unwrap();
        let check = |w: &WheelLine, got: fit::LineFit, range: (f64, f64), side: &str| {
            let m = f64::from(w.line.slope_q16) / 65536.0;
            let b = f64::from(w.line.intercept_q16) / 65536.0;
            assert!(within_pct(got.slope, m, 1.0) && within_pct(got.intercept, b, 1.0), "{motion} {side}");
            assert_eq!((w.min.to_f64(), w.max.to_f64()), range, "{motion} {side} measured range");
        };
        check(&lines.left, f.left, f.left_range, "left");
        check(&lines.right, f.right, f.right_range, "right");
    }
}

#[test]
fn lidar_data_reproduces_the_reports_lines() {
    for (file, model, m, b) in [
        ("lidar_front.csv", config::lidar::FRONT, 0.9849, -56.2563),
        ("lidar_right.csv", config::lidar::RIGHT, 0.9867, -70.4578),
    ] {
        let rows = fit::parse_lidar(&common::lab1(file)).unwrap();
        assert!(rows.len() > 1200, "{file}: {} rows", rows.len());
        for means in [false, true] {
            let f = fit::fit_lidar(&rows, means).unwrap();
            println!("{file} (means: {means}): distance = {:.4} reading + {:.4}", f.slope, f.intercept);
            assert!(within_pct(f.slope, m, 1.0), "{file}: slope {}", f.slope);
            assert!((f.intercept - b).abs() <= 1.0, "{file}: intercept {}", f.intercept);
        }
        // the config holds the same line
        assert!(within_pct(f64::from(model.slope_q16) / 65536.0, m, 0.01));
        assert!((model.intercept.to_mm_f64() - b).abs() < 1e-3);
    }
}

#[test]
fn compass_check_data_has_the_reported_spread() {
    let rows = fit::parse_magnetometer(&common::lab1("magnetometer_heading.csv")).unwrap();
    let n = rows.len() as f64;
    let errs: Vec<f64> = rows.iter().map(|&(c, r)| fit::heading_error_deg(r, c)).collect();
    let mean = errs.iter().sum::<f64>() / n;
    let sd = (errs.iter().map(|e| (e - mean) * (e - mean)).sum::<f64>() / n).sqrt();
    println!("compass error: mean {mean:.2} deg, sd {sd:.2} deg over {n} readings");
    assert!(mean.abs() < 2.0 && sd > 1.0 && sd < 4.0, "mean {mean} sd {sd}");
}

#[test]
fn malformed_csv_is_a_clear_error() {
    let e = fit::parse_lidar("actual_mm,reading_mm\n1,2\n3,x\n").unwrap_err();
    assert_eq!(e.line, 3);
    assert!(e.to_string().contains("not a number"), "{e}");
    assert!(fit::parse_lidar("a,b\n").unwrap_err().to_string().contains("expected header"));
    assert!(fit::parse_servo_runs("motion,left_cmd,right_cmd,trial,seconds,what_was_timed\nspin,1,2,3,4,x\n")
        .unwrap_err()
        .to_string()
        .contains("unknown motion"));
}

#[test]
fn fit_tool_prints_pasteable_constants() {
    let s = fit::config_constants(&common::lab1("servo_runs.csv"), "servo_runs.csv", false).unwrap();
    assert!(s.contains("pub const FORWARD: MotionLines"), "{s}");
    assert!(s.contains("right: WheelLine::new(-0.1460, 15.8477, 57, 66)"), "{s}");
    assert!(s.contains("left: WheelLine::new(-0.0908, 8.6171, 60, 71)"), "{s}");
    let s = fit::config_constants(&common::lab1("lidar_front.csv"), "lidar_front.csv", false).unwrap();
    assert!(s.contains("pub const FRONT: LidarModel = LidarModel::new(0.9846, -56.2074,"), "{s}");
    let s = fit::config_constants(&common::lab1("lidar_right.csv"), "lidar_right.csv", true).unwrap();
    assert!(s.contains("pub const RIGHT: LidarModel = LidarModel::new(0.9856, -70.2957,"), "{s}");
    assert!(fit::config_constants("x,y\n", "f.csv", false).unwrap_err().contains("unrecognised header"));
}
