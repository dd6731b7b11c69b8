//! The actuator model: forward lines, inverse, saturation, stop, and the
//! forward model from a command pair.
use paperbot::config::actuators::{self, MODEL};
use paperbot::math::{Speed, TurnRate};
use paperbot::model::actuator::{MotionLines, WheelLine};
use paperbot::model::{Motion, MotionKind, ServoCmd, Trim};

fn rad_s(q16: i32) -> f64 {
    f64::from(q16) / 65536.0
}

/// The report's (and for forward-right, the data's) lines at both ends of each
/// measured range, straight from the printed equations.
#[test]
fn forward_lines_match_the_report() {
    #[rustfmt::skip]
    let table: [(&str, &WheelLine, f64, f64); 8] = [
        ("forward left", &actuators::FORWARD.left, 0.14, -8.205),
        ("forward right", &actuators::FORWARD.right, -0.146, 15.85),
        ("backward left", &actuators::BACKWARD.left, -0.205, 19.77),
        ("backward right", &actuators::BACKWARD.right, 0.195, -13.95),
        ("cw left", &actuators::CW.left, 0.0862, -6.2423),
        ("cw right", &actuators::CW.right, 0.1431, -13.442),
        ("ccw left", &actuators::CCW.left, -0.0908, 8.6171),
        ("ccw right", &actuators::CCW.right, -0.0344, 4.7604),
    ];
    for (name, w, m, b) in table {
        for cmd in [w.min, w.max, ServoCmd::from_f64(100.5)] {
            let want = m * cmd.to_f64() + b;
            let got = rad_s(w.line.eval_q16(cmd));
            assert!((got - want).abs() < 1e-3, "{name} at {}: {got} vs {want}", cmd.to_f64());
        }
        // every line is a positive magnitude over its measured range
        let (lo, hi) = w.speed_range_q16();
        assert!(lo > 0 && hi > lo, "{name}: {lo}..{hi}");
    }
}

#[test]
fn stop_is_neutral_plus_trim() {
    let d = MODEL.stop();
    assert_eq!((d.left, d.right, d.motion, d.saturated), (ServoCmd::NEUTRAL, ServoCmd::NEUTRAL, Motion::Stop, false));
    let mut m = MODEL;
    m.left_trim = Trim::from_f64(-1.5);
    m.right_trim = Trim::from_f64(2.0);
    let d = m.stop();
    assert_eq!(d.left, ServoCmd::from_f64(88.5));
    assert_eq!(d.right, ServoCmd::from_f64(92.0));
    assert_eq!(m.drive(Motion::Stop), d);
    assert_eq!(m.drive(Motion::Straight(Speed::ZERO)), d);
}

#[test]
fn inverse_inside_the_range_round_trips() {
    // (request, expected kind, which side of 90 each servo goes)
    let cases = [
        (Motion::Straight(Speed::from_mps_f64(0.135)), MotionKind::Forward, true, false),
        (Motion::Straight(Speed::from_mps_f64(-0.13)), MotionKind::Backward, false, true),
        (Motion::Turn(TurnRate::from_rad_s_f64(2.8)), MotionKind::Cw, true, true),
        (Motion::Turn(TurnRate::from_rad_s_f64(-2.6)), MotionKind::Ccw, false, false),
    ];
    for (req, kind, left_up, right_up) in cases {
        let d = MODEL.drive(req);
        assert!(!d.saturated, "{req:?}");
        assert_eq!(d.motion.kind(), kind);
        assert_eq!(d.left > ServoCmd::NEUTRAL, left_up, "{req:?}: left {}", d.left.to_f64());
        assert_eq!(d.right > ServoCmd::NEUTRAL, right_up, "{req:?}: right {}", d.right.to_f64());
        // the achieved motion is the request within the 1/256-step command resolution
        match (req, d.motion) {
            (Motion::Straight(a), Motion::Straight(b)) => {
                assert!((a.to_mps_f64() - b.to_mps_f64()).abs() < 2e-4, "{a:?} {b:?}")
            }
            (Motion::Turn(a), Motion::Turn(b)) => {
                assert!((a.to_rad_s_f64() - b.to_rad_s_f64()).abs() < 2e-3, "{a:?} {b:?}")
            }
            _ => panic!("{req:?} -> {:?}", d.motion),
        }
        // and the forward model of the command pair gives the same motion back
        assert_eq!(MODEL.motion_from_commands(d.left, d.right), d.motion);
    }
}

#[test]
fn inverse_matches_the_report_lines_in_f64() {
    // forward 0.13 m/s: wheel 6.5 rad/s; left (6.5 + 8.205) / 0.14, right (6.5 - 15.85) / -0.146
    let d = MODEL.drive(Motion::Straight(Speed::from_mps_f64(0.13)));
    assert!((d.left.to_f64() - 105.0357).abs() < 0.01, "{}", d.left.to_f64());
    assert!((d.right.to_f64() - 64.0411).abs() < 0.01, "{}", d.right.to_f64());
}

#[test]
fn requests_outside_the_measured_range_saturate() {
    let common = |l: &MotionLines| l.common_range_q16().map(|(a, b)| (rad_s(a), rad_s(b))).unwrap();
    let (lo, hi) = common(&actuators::FORWARD);
    let r = actuators::FORWARD.left.line; // sanity: lo/hi are the slower wheel's ends
    assert!(lo > 6.2 && hi < 7.5 && r.slope_q16 > 0, "{lo} {hi}");
    for (req, want_wheel) in [(0.05, lo), (0.5, hi), (0.2, hi)] {
        let d = MODEL.drive(Motion::Straight(Speed::from_mps_f64(req)));
        assert!(d.saturated, "{req}");
        let v = match d.motion {
            Motion::Straight(v) => v.to_mps_f64(),
            m => panic!("{m:?}"),
        };
        assert!((v - want_wheel * 0.02).abs() < 2e-4, "{req} -> {v}, want {}", want_wheel * 0.02);
        // commands stay inside the measured ranges, never extrapolated
        let f = &actuators::FORWARD;
        assert!(d.left >= f.left.min && d.left <= f.left.max && d.right >= f.right.min && d.right <= f.right.max);
    }
    for w in [0.5, 10.0, -0.5, -10.0] {
        let d = MODEL.drive(Motion::Turn(TurnRate::from_rad_s_f64(w)));
        assert!(d.saturated, "{w}");
        let lines = if w > 0.0 { &actuators::CW } else { &actuators::CCW };
        assert!(d.left >= lines.left.min && d.left <= lines.left.max, "{w}: {}", d.left.to_f64());
        assert!(d.right >= lines.right.min && d.right <= lines.right.max, "{w}: {}", d.right.to_f64());
    }
}

#[test]
fn command_pairs_classify_by_side_of_neutral() {
    let c = ServoCmd::from_int;
    let table = [
        (c(108), c(60), MotionKind::Forward),
        (c(64), c(105), MotionKind::Backward),
        (c(105), c(113), MotionKind::Cw),
        (c(65), c(50), MotionKind::Ccw),
        (c(90), c(90), MotionKind::Stop),
        (c(90), c(60), MotionKind::Stop), // one wheel only: not a modelled motion
    ];
    for (l, r, kind) in table {
        assert_eq!(MODEL.motion_from_commands(l, r).kind(), kind, "{} {}", l.to_f64(), r.to_f64());
    }
}

#[test]
fn speed_ramps_from_neutral_and_holds_past_the_range() {
    let w = &actuators::FORWARD.left; // 103..112 above neutral 90
    let n = ServoCmd::NEUTRAL;
    assert_eq!(w.speed_at(n, n), (0, true));
    let (at_near, _) = w.speed_at(w.min, n);
    let (half, flagged) = w.speed_at(ServoCmd::from_f64(96.5), n); // halfway 90..103
    assert!(flagged && (half - at_near / 2).abs() <= 2, "{half} vs {at_near}");
    let (at_far, _) = w.speed_at(w.max, n);
    assert_eq!(w.speed_at(ServoCmd::from_int(150), n), (at_far, true));
    assert_eq!(w.speed_at(ServoCmd::from_int(60), n), (0, true)); // other side of neutral
}
