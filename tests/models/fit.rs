//! Fitting the lab's data reproduces the report's coefficients (and the
//! config's): within 1 % for every actuator line (with the data's sign for
//! forward-right), the lidar lines to 5e-5 in slope and 0.003 mm in intercept.
use crate::common;
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
    // the report's method (reading on distance, inverted) gives its lines to
    // the fourth decimal of the slope and within 0.003 mm of the intercept;
    // the config keeps the report's printed values
    for (file, model, m, b) in [
        ("lidar_front.csv", config::lidar::FRONT, 0.9849, -56.2563),
        ("lidar_right.csv", config::lidar::RIGHT, 0.9867, -70.4578),
    ] {
        let rows = fit::parse_lidar(&common::lab1(file)).unwrap();
        assert!(rows.len() > 1200, "{file}: {} rows", rows.len());
        let f = fit::fit_lidar(&rows).unwrap();
        println!("{file}: distance = {:.4} reading + {:.4}", f.slope, f.intercept);
        assert!((f.slope - m).abs() < 5e-5, "{file}: slope {}", f.slope);
        assert!((f.intercept - b).abs() < 0.003, "{file}: intercept {}", f.intercept);
        // the config holds the same line
        assert!(within_pct(f64::from(model.slope_q16) / 65536.0, m, 0.01));
        assert!((model.intercept.to_mm_f64() - b).abs() < 1e-3);
    }
    // distance on reading (the noisy reading as regressor) flattens the slope
    let rows = fit::parse_lidar(&common::lab1("lidar_front.csv")).unwrap();
    let direct = fit_line(rows.iter().map(|&(a, r)| (r, a))).unwrap();
    assert!(direct.slope < 0.9840, "{}", direct.slope);
    assert!(fit::fit_lidar(&[(100.0, 50.0), (100.0, 52.0)]).is_none(), "one distance");
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
    assert!(e.to_string().contains("not a finite number"), "{e}");
    assert!(fit::parse_lidar("a,b\n").unwrap_err().to_string().contains("expected header"));
    assert!(fit::parse_servo_runs("motion,left_cmd,right_cmd,trial,seconds,what_was_timed\nspin,1,2,3,4,x\n")
        .unwrap_err()
        .to_string()
        .contains("unknown motion"));
}

#[test]
fn fit_tool_prints_pasteable_constants() {
    let s = fit::config_constants(&common::lab1("servo_runs.csv"), "servo_runs.csv").unwrap();
    assert!(s.contains("pub const FORWARD: MotionLines"), "{s}");
    assert!(s.contains("right: WheelLine::new(-0.1460, 15.8477, 57, 66)"), "{s}");
    assert!(s.contains("left: WheelLine::new(-0.0908, 8.6171, 60, 71)"), "{s}");
    let s = fit::config_constants(&common::lab1("lidar_front.csv"), "lidar_front.csv").unwrap();
    assert!(s.contains("pub const FRONT: LidarModel = LidarModel::new(0.9849, -56.2555,"), "{s}");
    let s = fit::config_constants(&common::lab1("lidar_right.csv"), "lidar_right.csv").unwrap();
    assert!(s.contains("pub const RIGHT: LidarModel = LidarModel::new(0.9867, -70.4605,"), "{s}");
    assert!(fit::config_constants("x,y\n", "f.csv").unwrap_err().contains("unrecognised header"));
}

#[test]
fn fit_refuses_what_it_cannot_fit() {
    let head = "motion,left_cmd,right_cmd,trial,seconds,what_was_timed\n";
    for bad in ["nan", "inf", "-inf", "0", "-3.2"] {
        let text = format!("{head}forward,100,80,1,{bad},x\nforward,110,70,1,3.1,x\n");
        let e = fit::config_constants(&text, "servo_runs.csv").unwrap_err();
        assert!(e.contains("line 2") && (e.contains("finite") || e.contains("not positive")), "{bad}: {e}");
    }
    let e = fit::config_constants(&format!("{head}forward,100,80,1,3,x\n"), "s.csv").unwrap_err();
    assert!(e.contains("forward: fewer than two distinct commands"), "{e}");
    let e = fit::config_constants(&format!("{head}forward,100,80,1,3,x\nforward,100,80,2,3.1,x\n"), "s.csv");
    assert!(e.unwrap_err().contains("fewer than two"));
    assert_eq!(fit::config_constants(head, "s.csv").unwrap_err(), "no trials to fit");
    let e = fit::config_constants(&format!("{head}forward,200,80,1,3,x\n"), "s.csv").unwrap_err();
    assert!(e.contains("outside 0..180"), "{e}");
    let e = fit::config_constants("actual_mm,reading_mm\n25.4,NaN\n", "lidar_front.csv").unwrap_err();
    assert!(e.contains("not a finite number"), "{e}");
    let e = fit::config_constants("actual_mm,reading_mm\n25.4,80\n25.4,81\n", "lidar_front.csv").unwrap_err();
    assert!(e.contains("fewer than two distinct distances"), "{e}");
}
