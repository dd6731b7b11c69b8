//! The teleop tool's logic, without a terminal or a serial port: key
//! mapping, speed levels (against the report's lines), the deadman refresh
//! schedule, the replay-log recorder (against the replay tool's parser),
//! the screen model, the line mode's command files and schedule, and the
//! line splitter. The end-to-end run over a PTY is tests/tools/teleop_pty.rs.

use paperbot::config;
use paperbot::control::protocol::{parse, parse_telemetry_row, Command, TelemetryRow, HEADER};
use paperbot::host::teleop::link::LineSchedule;
use paperbot::host::teleop::{
    action, parse_plan, replay_row, Action, Dashboard, Driver, Key, LineReader, PlanLine, Recorder, Speeds,
    REPLAY_HEADER,
};
use paperbot::model::estimator::replay;
use paperbot::model::{Motion, MotionKind};

/// The protocol docs' example row: fwd, front lidar on a target, right
/// lidar without one (8190), compass at 353.117 degrees.
const ROW: &str =
    "1200,153.2,-4.1,11.933,fwd,0.130,0.000,107.00,61.00,412,349.5,8190,,-12,40,-3,-66,4,-3,353.117,0,0,0,0,0,0,located";
/// A row with no fresh reading at all.
const EMPTY_ROW: &str = "1220,153.9,-4.1,11.933,stop,0.000,0.000,90.00,90.00,,,,,,,,,,,,2,1,0,0,3,1,ambiguous";

fn row(line: &str) -> TelemetryRow {
    parse_telemetry_row(line).expect("test row parses")
}

// ---- keys ----------------------------------------------------------------

#[test]
fn keys_map_to_actions() {
    use Action::*;
    use MotionKind::*;
    let table: &[(Key, Option<Action>)] = &[
        (Key::Up, Some(Drive(Forward))),
        (Key::Down, Some(Drive(Backward))),
        (Key::Left, Some(Drive(Ccw))),
        (Key::Right, Some(Drive(Cw))),
        (Key::Char('w'), Some(Drive(Forward))),
        (Key::Char('W'), Some(Drive(Forward))),
        (Key::Char('s'), Some(Drive(Backward))),
        (Key::Char('a'), Some(Drive(Ccw))),
        (Key::Char('D'), Some(Drive(Cw))),
        (Key::Char(' '), Some(Drive(Stop))),
        (Key::Char('x'), Some(Drive(Stop))),
        (Key::Char('+'), Some(Faster)),
        (Key::Char('='), Some(Faster)),
        (Key::Char('e'), Some(Faster)),
        (Key::Char('-'), Some(Slower)),
        (Key::Char('_'), Some(Slower)),
        (Key::Char('z'), Some(Slower)),
        (Key::Char('r'), Some(Locate)),
        (Key::Char('p'), Some(Status)),
        (Key::Char('h'), Some(ToggleHelp)),
        (Key::Char('?'), Some(ToggleHelp)),
        (Key::Char('q'), Some(Quit)),
        (Key::Char('Q'), Some(Quit)),
        (Key::Esc, Some(Quit)),
        (Key::CtrlC, Some(Quit)),
        (Key::Char('k'), Some(Save)),
        (Key::Char('K'), Some(Save)),
        (Key::Char('1'), None),
        (Key::Char('\n'), None),
    ];
    for &(key, want) in table {
        assert_eq!(action(key), want, "{key:?}");
    }
}

#[test]
fn r_asks_the_robot_to_find_its_pose() {
    let cmd = paperbot::host::teleop::keys::LOCATE_COMMAND;
    assert_eq!(parse(cmd.as_bytes()), Ok(Command::Locate));
}

#[test]
fn k_asks_the_robot_to_save_its_settings() {
    let cmd = paperbot::host::teleop::mission::SAVE_COMMAND;
    assert_eq!(parse(cmd.as_bytes()), Ok(Command::Save));
}

// ---- speed levels ----------------------------------------------------------

/// The drivable range of a motion straight from the report's lines (f64):
/// the intersection of both wheels' speeds over their measured commands.
fn report_range(left: (f64, f64, f64, f64), right: (f64, f64, f64, f64), scale: f64) -> (f64, f64) {
    let ends = |(a, b, lo, hi): (f64, f64, f64, f64)| {
        let (y0, y1) = (a * lo + b, a * hi + b);
        (y0.min(y1), y0.max(y1))
    };
    let (l0, l1) = ends(left);
    let (r0, r1) = ends(right);
    (l0.max(r0) * scale, l1.min(r1) * scale)
}

#[test]
fn speed_ranges_are_the_measured_ranges_of_the_report() {
    let s = Speeds::from_config();
    let r = 20.0; // wheel radius, mm
                  // (kind, left line + commands, right line + commands, scale to mm/s or mrad/s): the fact sheet's table (docs/paperbot.md)
    let table = [
        (MotionKind::Forward, (0.14, -8.205, 103.0, 112.0), (-0.146, 15.85, 57.0, 66.0), r),
        (MotionKind::Backward, (-0.205, 19.77, 58.0, 70.0), (0.195, -13.95, 99.0, 111.0), r),
        (MotionKind::Cw, (0.0862, -6.2423, 100.0, 111.0), (0.1431, -13.442, 110.0, 117.0), 1000.0),
        (MotionKind::Ccw, (-0.0908, 8.6171, 60.0, 71.0), (-0.0344, 4.7604, 43.0, 70.0), 1000.0),
    ];
    for (kind, left, right, scale) in table {
        let (lo, hi) = report_range(left, right, scale);
        let (got_lo, got_hi) = s.range(kind).unwrap_or_else(|| panic!("{kind:?} has no range"));
        // rounded inward to 1 mm/s or 1 mrad/s, plus the Q16 lines' rounding
        // (slope and intercept to 2^-16 rad/s: under 1 mrad/s at x <= 180)
        let q16 = 1.0;
        assert!(f64::from(got_lo) >= lo - q16 && f64::from(got_lo) <= lo + 1.0 + q16, "{kind:?} lo {got_lo} vs {lo}");
        assert!(f64::from(got_hi) <= hi + q16 && f64::from(got_hi) >= hi - 1.0 - q16, "{kind:?} hi {got_hi} vs {hi}");
    }
    assert_eq!(s.range(MotionKind::Stop), None);
}

#[test]
fn every_speed_level_is_a_valid_command_the_model_drives_exactly() {
    let model = config::actuators::MODEL;
    let count = config::teleop::SPEED_LEVELS;
    for kind in [MotionKind::Forward, MotionKind::Backward, MotionKind::Cw, MotionKind::Ccw] {
        let mut prev = 0;
        for level in 0..count {
            let s = Speeds::new(&model, count, level);
            let v = s.value(kind).expect("a speed");
            assert!(v > prev, "{kind:?} level {level}: {v} not above {prev}");
            prev = v;
            let (lo, hi) = s.range(kind).expect("a range");
            assert_eq!(level == 0, v == lo, "{kind:?} level {level}");
            assert_eq!(level == count - 1, v == hi, "{kind:?} level {level}");
            let text = s.command(kind);
            let cmd = parse(text.as_bytes()).unwrap_or_else(|e| panic!("`{text}` refused: {e:?}"));
            let Command::Drive { motion, duration_ms: None } = cmd else { panic!("`{text}` is {cmd:?}") };
            assert_eq!(motion.kind(), kind, "`{text}`");
            let magnitude = match motion {
                Motion::Straight(speed) => speed.to_mm_s().unsigned_abs(),
                Motion::Turn(rate) => rate.to_mrad_s().unsigned_abs(),
                Motion::Stop => 0,
            };
            assert_eq!(magnitude, v, "`{text}`");
            // inside the measured range: the robot will not clamp it
            assert!(!model.drive(motion).saturated, "`{text}` would be clamped");
        }
    }
    assert_eq!(Speeds::from_config().command(MotionKind::Stop), "stop");
}

#[test]
fn speed_level_steps_stop_at_the_ends() {
    let mut s = Speeds::new(&config::actuators::MODEL, 3, 1);
    assert!(s.faster());
    assert_eq!(s.level(), 2);
    assert!(!s.faster(), "past the top");
    assert_eq!(s.level(), 2);
    assert!(s.slower() && s.slower());
    assert!(!s.slower(), "past the bottom");
    assert_eq!(s.level(), 0);
    // a start level past the top is clamped, fewer than two levels become two
    assert_eq!(Speeds::new(&config::actuators::MODEL, 3, 9).level(), 2);
    assert_eq!(Speeds::new(&config::actuators::MODEL, 1, 0).count(), 2);
    assert!(Speeds::from_config().describe().starts_with(&format!(
        "{}/{}: fwd ",
        config::teleop::START_LEVEL + 1,
        config::teleop::SPEED_LEVELS
    )));
}

// ---- the deadman refresh -------------------------------------------------------

#[test]
fn driver_sends_changes_at_once_and_refreshes_a_held_motion() {
    let refresh = config::teleop::REFRESH_MS as u64;
    let mut d = Driver::from_config();
    let fwd = d.speeds().command(MotionKind::Forward);
    assert_eq!(d.poll(0).as_deref(), None, "connecting interrupts nothing (a localization in progress)");
    assert_eq!(d.poll(10_000).as_deref(), None, "nor does standing");
    d.set(MotionKind::Forward);
    assert_eq!(d.poll(10_005), Some(fwd.clone()), "a new motion goes out at once");
    assert_eq!(d.poll(10_005 + refresh - 1), None);
    assert_eq!(d.poll(10_005 + refresh), Some(fwd.clone()), "refreshed after REFRESH_MS");
    d.faster();
    let faster = d.speeds().command(MotionKind::Forward);
    assert_ne!(faster, fwd);
    assert_eq!(d.poll(10_005 + refresh + 3), Some(faster), "a new speed goes out at once");
    d.set(MotionKind::Forward); // the same key again changes nothing
    assert_eq!(d.poll(10_005 + refresh + 4), None);
    d.set(MotionKind::Stop);
    assert_eq!(d.poll(10_005 + refresh + 5).as_deref(), Some("stop"));
    assert_eq!(d.poll(20_000), None, "stop is not refreshed");
    assert_eq!(d.sent(), 4);
    assert_eq!(d.last_sent(), Some("stop"));
}

#[test]
fn a_held_motion_never_goes_a_deadman_period_without_a_command() {
    // the UI loop polls every few ms; with any poll spacing up to 20 ms the
    // gaps between sends stay under REFRESH_MS + 20 ms, well below the deadman
    for step_ms in [1u64, 5, 7, 20] {
        let mut d = Driver::from_config();
        d.set(MotionKind::Cw);
        let mut sends = Vec::new();
        let mut t = 0;
        while t < 5_000 {
            if d.poll(t).is_some() {
                sends.push(t);
            }
            t += step_ms;
        }
        let max_gap = sends.windows(2).map(|w| w[1] - w[0]).max().unwrap_or(u64::MAX);
        assert!(max_gap >= config::teleop::REFRESH_MS as u64, "step {step_ms}: refreshed too often ({max_gap})");
        assert!(max_gap < config::teleop::REFRESH_MS as u64 + step_ms, "step {step_ms}: gap {max_gap}");
        assert!(max_gap * 2 < config::timing::DEADMAN_MS as u64, "step {step_ms}: gap {max_gap}");
    }
}

// ---- the replay log ----------------------------------------------------------

#[test]
fn replay_rows_carry_commands_raw_readings_and_the_compass_heading() {
    let table = [
        (ROW, "1200,107.00,61.00,412,8190,353.117"),
        (EMPTY_ROW, "1220,90.00,90.00,,,"),
        (
            "0,0.0,0.0,0.000,ccw,0.000,-2.500,63.50,43.00,20,,8191,,1,2,3,4,5,6,0.000,0,0,0,0,0,0,ambiguous",
            "0,63.50,43.00,20,8191,0.000",
        ),
        (
            "4294967295,0.0,0.0,359.999,stop,0.000,0.000,180.00,0.00,,,65535,,,,,,,,359.999,0,0,0,0,0,0,unknown",
            "4294967295,180.00,0.00,,65535,359.999",
        ),
    ];
    for (telemetry, want) in table {
        assert_eq!(replay_row(&row(telemetry)), want, "{telemetry}");
    }
    assert_eq!(REPLAY_HEADER, replay::HEADER, "the replay tool's header");
}

#[test]
fn the_recorded_log_reads_back_in_the_replay_tool() {
    let mut rec = Recorder::new(Vec::new()).unwrap();
    assert!(rec.record(&row(ROW)).unwrap());
    assert!(rec.record(&row(EMPTY_ROW)).unwrap());
    // the robot rebooted: its clock went back
    let rebooted = ROW.replacen("1200,", "40,", 1);
    assert!(!rec.record(&row(&rebooted)).unwrap());
    assert_eq!((rec.rows(), rec.skipped()), (2, 1));
    assert_eq!(rec.replay_start().as_deref(), Some("153.2,-4.1,11.933"));
    let text = String::from_utf8(rec.into_inner()).unwrap();
    assert_eq!(text, format!("{REPLAY_HEADER}\n1200,107.00,61.00,412,8190,353.117\n1220,90.00,90.00,,,\n"));
    let samples = replay::parse(&text).expect("the replay tool reads the log");
    assert_eq!(samples.len(), 2);
    let (a, b) = (samples[0], samples[1]);
    assert_eq!((a.t_ms, a.left.to_centi(), a.right.to_centi()), (1200, 10_700, 6_100));
    assert_eq!((a.front_mm, a.right_mm), (Some(412), Some(8190)));
    assert_eq!(a.heading.map(|h| h.to_millidegrees()), Some(353_117));
    assert_eq!((b.t_ms, b.front_mm, b.right_mm, b.heading), (1220, None, None, None));
}

// ---- the screen ---------------------------------------------------------------

fn panel(panels: &[paperbot::host::teleop::Panel], title: &str) -> String {
    panels.iter().find(|p| p.title == title).unwrap_or_else(|| panic!("no panel {title}")).lines.join("\n")
}

#[test]
fn dashboard_shows_the_newest_row_and_counts_the_link() {
    let mut d = Dashboard::new();
    let driver = Driver::from_config();
    assert!(d.stale(0));
    assert!(panel(&d.panels(0, &driver, None), "link").contains("waiting for telemetry"));
    assert_eq!(d.on_line(HEADER, 0), None);
    assert_eq!(d.on_line(&format!("{ROW}\r"), 10), Some(row(ROW)));
    assert_eq!(d.on_line("# ok fwd 0.137", 11), None);
    assert_eq!(d.on_line("# ok fwd 0.137", 12), None); // a refresh's ack: counted, not shown
    assert_eq!(d.on_line("# err speed out of range 0.001..0.300 m/s", 13), None);
    assert_eq!(d.on_line("paperbot 0.1.0 up", 14), None); // boot text
    assert_eq!(d.on_line("", 15), None);
    assert_eq!((d.rows(), d.errors(), d.bad_lines()), (1, 1, 1));
    let msgs: Vec<&str> = d.messages().collect();
    assert_eq!(msgs, ["# ok fwd 0.137", "# err speed out of range 0.001..0.300 m/s", "? paperbot 0.1.0 up"]);

    let p = d.panels(20, &driver, Some("drive.csv: 1 rows"));
    let pose = panel(&p, "pose and motion");
    for want in [
        "t 1200 ms",
        "x 153.2 mm  y -4.1 mm",
        "heading 11.933 deg",
        "estimate located",
        "motion fwd  v 0.130 m/s",
        "L 107.00  R 61.00",
    ] {
        assert!(pose.contains(want), "{want:?} in\n{pose}");
    }
    let sensors = panel(&p, "sensors");
    for want in [
        "front raw 412 mm  dist 349.5 mm  (0 ms ago)",
        "right raw 8190 mm  dist - mm",
        "compass 353.117 deg",
        "mag raw -12 40 -3",
    ] {
        assert!(sensors.contains(want), "{want:?} in\n{sensors}");
    }
    let link = panel(&p, "link");
    for want in ["telemetry ok", "rows 1  ok 2  err 1  bad 1", "record drive.csv: 1 rows"] {
        assert!(link.contains(want), "{want:?} in\n{link}");
    }
    assert!(panel(&p, "drive").contains("stopped"));
    let mut moving = Driver::from_config();
    moving.set(MotionKind::Ccw);
    let text = panel(&d.panels(20, &moving, None), "drive");
    assert!(text.contains(&format!("holding `{}`, sent again every 125 ms", moving.command())), "{text}");
    assert_eq!(panel(&p, "messages").lines().count(), 3);

    d.on_line(EMPTY_ROW, 30);
    let p = d.panels(40, &driver, None);
    assert!(panel(&p, "faults").contains("bus 2  timeout 1  missing 0"), "{}", panel(&p, "faults"));
    assert!(panel(&p, "faults").contains("outliers 3  overruns 1"));
    // the estimator's state, as the row says it
    assert!(panel(&p, "pose and motion").contains("estimate AMBIGUOUS: several places fit, the pose holds"));
    // an empty row keeps the newest readings on screen, with their age
    let sensors = panel(&p, "sensors");
    assert!(sensors.contains("front raw 412 mm  dist 349.5 mm  (20 ms ago)"), "{sensors}");
    assert!(sensors.contains("compass 353.117 deg  (20 ms ago)"), "{sensors}");
    let stale_at = 30 + config::teleop::STALE_LINK_MS as u64 + 1;
    assert!(!d.stale(stale_at - 1) && d.stale(stale_at));
    assert!(panel(&d.panels(stale_at, &driver, None), "link").contains("STALE"));
}

#[test]
fn dashboard_keeps_the_newest_messages() {
    let mut d = Dashboard::new();
    let n = config::teleop::MESSAGES_SHOWN;
    for i in 0..n + 5 {
        d.on_line(&format!("# note {i}"), 0);
    }
    let msgs: Vec<&str> = d.messages().collect();
    assert_eq!(msgs.len(), n);
    assert_eq!(msgs[0], "# note 5");
    assert_eq!(msgs[n - 1], format!("# note {}", n + 4));
}

// ---- the line mode ------------------------------------------------------------

fn at(lines: &[PlanLine]) -> Vec<(u64, &str)> {
    lines.iter().map(|l| (l.at_ms, l.command.as_str())).collect()
}

#[test]
fn plan_files_give_times_and_commands() {
    let text = "# a drive\n\nrate 20\n@0.5 fwd 0.13   # go\n+2s stop\n@3000ms ccw 2.5 0.5\nstatus\n+250ms reset\n";
    let plan = parse_plan(text).unwrap();
    assert_eq!(
        at(&plan),
        [(0, "rate 20"), (500, "fwd 0.13"), (2500, "stop"), (3000, "ccw 2.5 0.5"), (3000, "status"), (3250, "reset")]
    );
    assert_eq!(plan.iter().map(|l| l.line_no).collect::<Vec<_>>(), [3, 4, 5, 6, 7, 8]);
    assert!(parse_plan("").unwrap().is_empty());
}

#[test]
fn plan_files_with_mistakes_are_refused_before_anything_is_sent() {
    let table: &[(&str, usize, &str)] = &[
        ("@1 stop\n@0.5 stop\n", 2, "before the previous line"),
        ("@x stop\n", 1, "bad time"),
        ("@-1 stop\n", 1, "bad time"),
        ("+1h stop\n", 1, "bad time"),
        ("@1\n", 1, "no command"),
        ("stop\nfwd 0.5\n", 2, "speed out of range"),
        ("jump\n", 1, "unknown command"),
        ("fwd\n", 1, "missing speed"),
    ];
    for &(text, line_no, want) in table {
        let e = parse_plan(text).expect_err(text);
        assert_eq!(e.line_no, line_no, "{text:?}: {e}");
        assert!(e.to_string().contains(want), "{text:?}: {e}");
    }
}

#[test]
fn line_schedule_sends_on_time_and_keeps_untimed_motions_alive() {
    let refresh = 100;
    let plan = parse_plan("@0 fwd 0.13\n@250ms status\n@400ms cw 2.5 1\n@500ms back 0.13\n@600ms stop\n").unwrap();
    let mut s = LineSchedule::new(plan, true, refresh);
    let mut log = Vec::new();
    for t in (0..=800).step_by(10) {
        for (cmd, from_plan) in s.poll(t) {
            log.push((t, cmd, from_plan));
        }
    }
    let got: Vec<(u64, &str, bool)> = log.iter().map(|(t, c, p)| (*t, c.as_str(), *p)).collect();
    assert_eq!(
        got,
        [
            (0, "fwd 0.13", true),
            (100, "fwd 0.13", false),
            (200, "fwd 0.13", false),
            (250, "status", true), // any valid command refreshes the deadman: the clock restarts
            (350, "fwd 0.13", false),
            (400, "cw 2.5 1", true), // timed: its own deadman, not repeated
            (500, "back 0.13", true),
            (600, "stop", true),
        ]
    );
    assert!(s.done());
    assert_eq!(s.last_plan_ms(), 600);

    // without keep-alive only the plan goes out
    let plan = parse_plan("fwd 0.13\n@0.3 stop\n").unwrap();
    let mut s = LineSchedule::new(plan, false, refresh);
    let sent: Vec<u64> = (0..=400).step_by(10).filter(|&t| !s.poll(t).is_empty()).collect();
    assert_eq!(sent, [0, 300]);
}

#[test]
fn line_reader_splits_crlf_lines_across_reads() {
    let mut r = LineReader::new();
    assert!(r.push(b"# ok st").is_empty());
    assert_eq!(r.push(b"op\r\n12,3\n\n"), ["# ok stop", "12,3", ""]);
    assert_eq!(r.push(b"bad \xff byte\r\n"), ["bad \u{fffd} byte"]);
    // line noise without a newline is cut at MAX_LINE
    let long = vec![b'x'; paperbot::host::teleop::link::MAX_LINE + 100];
    assert!(r.push(&long).is_empty());
    let lines = r.push(b"\n");
    assert_eq!(lines.len(), 1);
    assert_eq!(lines[0].len(), paperbot::host::teleop::link::MAX_LINE);
}
