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

/// What a wheel's line should give at a command (see `WheelLine::speed_at`).
#[derive(Clone, Copy, Debug)]
enum Expect {
    /// at or behind the stop: 0
    Zero,
    /// short of the range: the ramp, this fraction of the way from the stop
    /// to the range's near end, times the line's value there
    Ramp(f64),
    /// inside the range: the line itself
    Line,
    /// past the range: held at the far end's value
    Far,
}

/// One row: a line, its report slope and intercept, the trim in steps,
/// and commands with what the line should give there.
type Row<'a> = (&'a str, &'a WheelLine, f64, f64, f64, [(f64, Expect); 4]);

/// Every wheel line with a trim of +10 and -10 steps (the protocol's
/// largest, `MAX_TRIM_CENTI`): +10 puts the stop at 100, inside the
/// backward-right range (99..111) and at the clockwise-left range's start
/// (100..111), where the ramp once ran from neutral to a near end a step
/// away (or past the range) and extrapolated the line 7-fold.
#[test]
fn trims_of_10_steps_never_extrapolate_a_line() {
    let f = ServoCmd::from_f64;
    // (line, report slope and intercept, trim in steps, [(command, expected)])
    #[rustfmt::skip]
    let table: [Row; 16] = [
        // above 90, trim +10 (stop 100): the ramp runs 100..near
        ("forward left +10", &actuators::FORWARD.left, 0.14, -8.205, 10.0,
            [(99.0, Expect::Zero), (101.5, Expect::Ramp(0.5)), (110.0, Expect::Line), (180.0, Expect::Far)]),
        ("backward right +10", &actuators::BACKWARD.right, 0.195, -13.95, 10.0,
            [(99.5, Expect::Zero), (100.5, Expect::Line), (111.0, Expect::Line), (180.0, Expect::Far)]),
        ("cw left +10", &actuators::CW.left, 0.0862, -6.2423, 10.0,
            [(100.0, Expect::Zero), (100.25, Expect::Line), (105.0, Expect::Line), (180.0, Expect::Far)]),
        ("cw right +10", &actuators::CW.right, 0.1431, -13.442, 10.0,
            [(90.0, Expect::Zero), (105.0, Expect::Ramp(0.5)), (117.0, Expect::Line), (150.0, Expect::Far)]),
        // above 90, trim -10 (stop 80): long ramps
        ("forward left -10", &actuators::FORWARD.left, 0.14, -8.205, -10.0,
            [(70.0, Expect::Zero), (91.5, Expect::Ramp(0.5)), (103.0, Expect::Line), (113.0, Expect::Far)]),
        ("backward right -10", &actuators::BACKWARD.right, 0.195, -13.95, -10.0,
            [(80.0, Expect::Zero), (89.5, Expect::Ramp(0.5)), (105.0, Expect::Line), (180.0, Expect::Far)]),
        ("cw left -10", &actuators::CW.left, 0.0862, -6.2423, -10.0,
            [(0.0, Expect::Zero), (85.0, Expect::Ramp(0.25)), (111.0, Expect::Line), (180.0, Expect::Far)]),
        ("cw right -10", &actuators::CW.right, 0.1431, -13.442, -10.0,
            [(79.0, Expect::Zero), (95.0, Expect::Ramp(0.5)), (112.0, Expect::Line), (180.0, Expect::Far)]),
        // below 90, trim +10 (stop 100): long ramps
        ("forward right +10", &actuators::FORWARD.right, -0.146, 15.85, 10.0,
            [(101.0, Expect::Zero), (83.0, Expect::Ramp(0.5)), (60.0, Expect::Line), (0.0, Expect::Far)]),
        ("backward left +10", &actuators::BACKWARD.left, -0.205, 19.77, 10.0,
            [(180.0, Expect::Zero), (85.0, Expect::Ramp(0.5)), (58.0, Expect::Line), (57.0, Expect::Far)]),
        ("ccw left +10", &actuators::CCW.left, -0.0908, 8.6171, 10.0,
            [(100.0, Expect::Zero), (92.75, Expect::Ramp(0.25)), (65.0, Expect::Line), (0.0, Expect::Far)]),
        ("ccw right +10", &actuators::CCW.right, -0.0344, 4.7604, 10.0,
            [(120.0, Expect::Zero), (85.0, Expect::Ramp(0.5)), (43.0, Expect::Line), (10.0, Expect::Far)]),
        // below 90, trim -10 (stop 80): the ramp runs 80..near
        ("forward right -10", &actuators::FORWARD.right, -0.146, 15.85, -10.0,
            [(80.0, Expect::Zero), (73.0, Expect::Ramp(0.5)), (66.0, Expect::Line), (0.0, Expect::Far)]),
        ("backward left -10", &actuators::BACKWARD.left, -0.205, 19.77, -10.0,
            [(90.0, Expect::Zero), (75.0, Expect::Ramp(0.5)), (64.0, Expect::Line), (0.0, Expect::Far)]),
        ("ccw left -10", &actuators::CCW.left, -0.0908, 8.6171, -10.0,
            [(81.0, Expect::Zero), (75.5, Expect::Ramp(0.5)), (71.0, Expect::Line), (59.0, Expect::Far)]),
        ("ccw right -10", &actuators::CCW.right, -0.0344, 4.7604, -10.0,
            [(85.0, Expect::Zero), (77.5, Expect::Ramp(0.25)), (50.0, Expect::Line), (0.0, Expect::Far)]),
    ];
    for (name, w, m, b, trim, cases) in table {
        let neutral = ServoCmd::NEUTRAL.trimmed(Trim::from_f64(trim));
        let y = |c: f64| m * c + b;
        let up = w.min.to_f64() > 90.0;
        let (near, far) = if up { (w.min.to_f64(), w.max.to_f64()) } else { (w.max.to_f64(), w.min.to_f64()) };
        let fastest = y(far);
        for (cmd, expect) in cases {
            let want = match expect {
                Expect::Zero => 0.0,
                Expect::Ramp(frac) => {
                    // the table's command is that fraction of the way from the stop
                    let stop = neutral.to_f64();
                    assert!(((cmd - stop) / (near - stop) - frac).abs() < 1e-9, "{name}: bad row {cmd}");
                    frac * y(near)
                }
                Expect::Line => y(cmd),
                Expect::Far => fastest,
            };
            let (got, flagged) = w.speed_at(f(cmd), neutral);
            let got = rad_s(got);
            assert!((got - want).abs() < 2e-3, "{name} at {cmd} ({expect:?}): {got} rad/s, want {want}");
            assert_eq!(flagged, !matches!(expect, Expect::Line), "{name} at {cmd}");
            assert!(got <= fastest + 1e-3, "{name} at {cmd}: {got} past the far end's {fastest}");
        }
    }
}

/// The forward model of command pairs with trims of +-10 steps, for every
/// motion: the pairs that were modelled far past the lab's speeds, and a
/// sweep of every whole-step pair that stays within the mean of the two
/// lines' far-end values.
#[test]
fn forward_model_with_trims_of_10_steps() {
    let c = ServoCmd::from_int;
    let with = |l: f64, r: f64| {
        let mut m = MODEL;
        m.left_trim = Trim::from_f64(l);
        m.right_trim = Trim::from_f64(r);
        m
    };
    // (left trim, right trim, left, right, kind, m/s for straight or rad/s for turns)
    #[rustfmt::skip]
    let table: [(f64, f64, ServoCmd, ServoCmd, MotionKind, f64); 14] = [
        // right stop at 100, inside its backward range: was 0.64 m/s
        (0.0, 10.0, c(0), c(180), MotionKind::Backward, (7.88 + 7.695) / 2.0 * 0.02),
        (0.0, 0.0, c(0), c(180), MotionKind::Backward, (7.88 + 7.695) / 2.0 * 0.02),
        // left stop at 100, at its clockwise range's start: was 13.7 rad/s
        (10.0, 0.0, c(180), c(180), MotionKind::Cw, (3.3259 + 3.3007) / 2.0),
        (10.0, 10.0, c(180), c(180), MotionKind::Cw, (3.3259 + 3.3007) / 2.0),
        (-10.0, -10.0, c(180), c(180), MotionKind::Cw, (3.3259 + 3.3007) / 2.0),
        (10.0, -10.0, c(180), c(0), MotionKind::Forward, (7.475 + 7.528) / 2.0 * 0.02),
        (-10.0, 10.0, c(180), c(0), MotionKind::Forward, (7.475 + 7.528) / 2.0 * 0.02),
        (10.0, 10.0, c(0), c(0), MotionKind::Ccw, -(3.1691 + 3.2812) / 2.0),
        (-10.0, -10.0, c(0), c(0), MotionKind::Ccw, -(3.1691 + 3.2812) / 2.0),
        // inside the ranges, past the stops: the lines themselves
        (10.0, 10.0, c(60), ServoCmd::from_f64(100.5), MotionKind::Backward, (-0.205 * 60.0 + 19.77 + 0.195 * 100.5 - 13.95) / 2.0 * 0.02),
        (0.0, 10.0, c(64), c(105), MotionKind::Backward, -(-0.205 * 64.0 + 19.77 + 0.195 * 105.0 - 13.95) / 2.0 * 0.02),
        (10.0, 0.0, c(105), c(113), MotionKind::Cw, (0.0862 * 105.0 - 6.2423 + 0.1431 * 113.0 - 13.442) / 2.0),
        // one wheel at its stop: not a modelled motion
        (10.0, 0.0, c(100), c(0), MotionKind::Stop, 0.0),
        (0.0, -10.0, c(0), c(80), MotionKind::Stop, 0.0),
    ];
    for (lt, rt, l, r, kind, want) in table {
        let motion = with(lt, rt).motion_from_commands(l, r);
        assert_eq!(motion.kind(), kind, "trims {lt} {rt}, servo {} {}", l.to_f64(), r.to_f64());
        let got = match motion {
            Motion::Straight(v) => v.to_mps_f64(),
            Motion::Turn(w) => w.to_rad_s_f64(),
            Motion::Stop => 0.0,
        };
        let want = if kind == MotionKind::Backward { -want.abs() } else { want };
        assert!((got - want).abs() < 1e-3, "trims {lt} {rt}, servo {} {}: {got}, want {want}", l.to_f64(), r.to_f64());
    }
    // every whole-step pair, every trim combination of +-10 and 0
    for (lt, rt) in [(10.0, 10.0), (10.0, -10.0), (-10.0, 10.0), (-10.0, -10.0), (10.0, 0.0), (0.0, 10.0)] {
        let m = with(lt, rt);
        for l in 0..=180 {
            for r in 0..=180 {
                let motion = m.motion_from_commands(c(l), c(r));
                let Some(lines) = m.lines(motion.kind()) else { continue };
                let far = |w: &WheelLine| rad_s(w.speed_range_q16().1);
                let fastest = (far(&lines.left) + far(&lines.right)) / 2.0;
                let got = match motion {
                    Motion::Straight(v) => v.to_mps_f64().abs() / 0.02,
                    Motion::Turn(w) => w.to_rad_s_f64().abs(),
                    Motion::Stop => 0.0,
                };
                assert!(got <= fastest + 1e-3, "trims {lt} {rt}, servo {l} {r}: {motion:?} past {fastest}");
            }
        }
    }
}

/// `drive` picks commands past each stop: with the right stop at 100 inside
/// the backward-right range (99..111), the slowest backward speed is the
/// line's just past 100, not at 99 (which would be on the stop's other side
/// and make a different motion).
#[test]
fn drive_keeps_commands_past_a_stop_inside_a_range() {
    let mut m = MODEL;
    m.right_trim = Trim::from_f64(10.0);
    let d = m.drive(Motion::Straight(Speed::from_mps_f64(-0.05)));
    assert!(d.saturated && d.right > m.right_neutral(), "{d:?}");
    assert_eq!(m.motion_from_commands(d.left, d.right), d.motion);
    assert_eq!(d.motion.kind(), MotionKind::Backward);
    let usable = m.usable_lines(MotionKind::Backward).unwrap();
    assert_eq!(usable.right.min, ServoCmd::from_q8((100 << 8) + 1));
    let (lo, _) = usable.common_range_q16().unwrap();
    // the right line just past 100: 0.195 * 100 - 13.95 = 5.55 rad/s (the left reaches it at 69.3)
    assert!((rad_s(lo) - 5.55).abs() < 2e-3, "{}", rad_s(lo));
}
