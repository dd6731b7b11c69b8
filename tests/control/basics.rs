//! The control loop against trait doubles: deadman, timed commands, each
//! command's effect, telemetry format and rate, sensor fault counting and
//! re-initialisation after the back-off, calibration sweeps.

use std::collections::VecDeque;

use paperbot::config;
use paperbot::control::log::RingLog;
use paperbot::control::protocol::{parse_telemetry_row, telemetry_header, FaultCounters, HELP};
use paperbot::control::settings::{FlashSettings, MemoryFlash};
use paperbot::control::{Controller, Hardware, LineSink, Mode, TICK_US};
use paperbot::driver::{CompassSample, HeadingSensor, LidarSample, MagCalibrate, RangeSensor, SensorError, Servos};
use paperbot::math::{Angle, Speed};
use paperbot::model::compass::{MagCalibration, MagCounts, MagField};
use paperbot::model::{Motion, MotionKind, Pose, Range, ServoCmd, Trim};

// ---- doubles ---------------------------------------------------------

#[derive(Default)]
struct Lines(Vec<String>);

impl LineSink for Lines {
    fn write_line(&mut self, line: &str) {
        self.0.push(line.to_string());
    }
}

impl Lines {
    fn take(&mut self) -> Vec<String> {
        std::mem::take(&mut self.0)
    }
}

/// A lidar that answers from a queue, then with `steady` (or WouldBlock),
/// and whose re-inits fail `reinit_failures` times.
#[derive(Default)]
struct FakeLidar {
    queue: VecDeque<nb::Result<LidarSample, SensorError>>,
    steady: Option<LidarSample>,
    reinit_failures: u32,
    reinit_calls: u32,
    polls: u32,
}

impl RangeSensor for FakeLidar {
    fn poll(&mut self) -> nb::Result<LidarSample, SensorError> {
        self.polls += 1;
        self.queue.pop_front().unwrap_or(self.steady.ok_or(nb::Error::WouldBlock))
    }
    fn reinit(&mut self) -> Result<(), SensorError> {
        self.reinit_calls += 1;
        if self.reinit_failures > 0 {
            self.reinit_failures -= 1;
            Err(SensorError::Missing)
        } else {
            Ok(())
        }
    }
}

/// A compass whose samples come from a queue, or from a field turning by
/// `turn_per_poll` each poll around `centre` (raw counts).
struct FakeCompass {
    queue: VecDeque<nb::Result<CompassSample, SensorError>>,
    angle: f64,
    turn_per_poll: f64,
    radius: f64,
    centre: [f64; 3],
    calibration: MagCalibration,
    declination: Angle,
    reinit_calls: u32,
}

impl Default for FakeCompass {
    fn default() -> Self {
        FakeCompass {
            queue: VecDeque::new(),
            angle: 0.0,
            turn_per_poll: 0.0,
            radius: 0.0,
            centre: [0.0; 3],
            calibration: config::compass::CALIBRATION,
            declination: config::compass::DECLINATION,
            reinit_calls: 0,
        }
    }
}

impl HeadingSensor for FakeCompass {
    fn poll(&mut self) -> nb::Result<CompassSample, SensorError> {
        if let Some(r) = self.queue.pop_front() {
            return r;
        }
        if self.radius == 0.0 {
            return Err(nb::Error::WouldBlock);
        }
        self.angle += self.turn_per_poll;
        let raw = MagCounts {
            x: (self.centre[0] + self.radius * self.angle.cos()).round() as i16,
            y: (self.centre[1] + self.radius * self.angle.sin()).round() as i16,
            z: (self.centre[2] + 10.0 * (self.angle * 0.5).sin()).round() as i16,
        };
        Ok(CompassSample { raw, field: MagField::default(), heading: Angle::ZERO })
    }
    fn reinit(&mut self) -> Result<(), SensorError> {
        self.reinit_calls += 1;
        Ok(())
    }
}

impl MagCalibrate for FakeCompass {
    fn asa(&self) -> [u8; 3] {
        [128; 3] // factor 1: raw counts are adjusted counts
    }
    fn calibration(&self) -> MagCalibration {
        self.calibration
    }
    fn set_calibration(&mut self, calibration: MagCalibration) {
        self.calibration = calibration;
    }
    fn declination(&self) -> Angle {
        self.declination
    }
    fn set_declination(&mut self, declination: Angle) {
        self.declination = declination;
    }
}

#[derive(Default)]
struct FakeServos {
    last: Option<(ServoCmd, ServoCmd)>,
    calls: u32,
}

impl Servos for FakeServos {
    fn set(&mut self, left: ServoCmd, right: ServoCmd) {
        self.last = Some((left, right));
        self.calls += 1;
    }
}

/// The doubles as the loop's hardware (no on-board log).
struct Fakes;

impl Hardware for Fakes {
    type Front = FakeLidar;
    type Right = FakeLidar;
    type Compass = FakeCompass;
    type Servos = FakeServos;
    type Log = RingLog<0>;
    type Settings = FlashSettings<MemoryFlash>;
}

type Ctl = Controller<Fakes>;

/// A loop at the origin over working test doubles, as configured.
fn fresh() -> Ctl {
    Controller::new(
        FakeLidar::default(),
        FakeLidar::default(),
        FakeCompass::default(),
        FakeServos::default(),
        Pose::default(),
    )
}

/// A loop at the origin, telemetry off, and its output.
fn setup() -> (Ctl, Lines) {
    let mut ctl = fresh();
    let mut out = Lines::default();
    send(&mut ctl, &mut out, "rate 0");
    out.take();
    (ctl, out)
}

fn send(ctl: &mut Ctl, out: &mut Lines, line: &str) {
    ctl.feed_bytes(line.as_bytes(), out);
    ctl.feed(b'\n', out);
}

/// Ticks at every loop period from `from_ms` (inclusive) to `to_ms` (exclusive).
fn run(ctl: &mut Ctl, out: &mut Lines, from_ms: u32, to_ms: u32) {
    let mut t = from_ms * 1000;
    while t < to_ms * 1000 {
        ctl.tick(t, out);
        t += TICK_US;
    }
}

fn servos(ctl: &mut Ctl) -> (ServoCmd, ServoCmd) {
    ctl.servos().last.expect("servos were set")
}

fn neutral() -> (ServoCmd, ServoCmd) {
    (config::actuators::MODEL.left_neutral(), config::actuators::MODEL.right_neutral())
}

fn fwd_drive() -> (ServoCmd, ServoCmd) {
    let d = config::actuators::MODEL.drive(Motion::Straight(Speed::from_mm_s(130)));
    (d.left, d.right)
}

fn lidar(raw_mm: u16) -> LidarSample {
    LidarSample { raw_mm, range: config::lidar::FRONT.range(raw_mm) }
}

// ---- deadman and timed commands --------------------------------------

#[test]
fn untimed_drive_stops_at_the_deadman() {
    let (mut ctl, mut out) = setup();
    run(&mut ctl, &mut out, 0, 100);
    send(&mut ctl, &mut out, "fwd 0.13");
    assert_eq!(out.take(), ["# ok fwd 0.130"]);
    // the command is seen by the tick at 100 ms: the deadman runs from there
    run(&mut ctl, &mut out, 100, 100 + config::timing::DEADMAN_MS);
    assert_eq!(servos(&mut ctl), fwd_drive());
    assert!(matches!(ctl.mode(), Mode::Drive { .. }));
    assert!(out.take().is_empty());
    ctl.tick((100 + config::timing::DEADMAN_MS) * 1000, &mut out);
    assert_eq!(servos(&mut ctl), neutral());
    assert_eq!(ctl.mode(), Mode::Idle);
    assert_eq!(out.take(), ["# deadman: no command, stopped"]);
}

#[test]
fn every_valid_command_refreshes_the_deadman_and_malformed_lines_do_not() {
    let (mut ctl, mut out) = setup();
    send(&mut ctl, &mut out, "cw 2.5");
    run(&mut ctl, &mut out, 0, 400);
    send(&mut ctl, &mut out, "status"); // seen at 400 ms
    run(&mut ctl, &mut out, 400, 890);
    assert!(matches!(ctl.mode(), Mode::Drive { .. }), "status refreshed the deadman");
    send(&mut ctl, &mut out, "cw 99"); // out of range: refused, no refresh
    out.take();
    ctl.tick(890_000, &mut out);
    assert!(matches!(ctl.mode(), Mode::Drive { .. }));
    ctl.tick(900_000, &mut out);
    assert_eq!(ctl.mode(), Mode::Idle, "stopped 500 ms after the status command");
}

#[test]
fn timed_drive_runs_its_whole_duration_past_the_deadman_then_stops() {
    let (mut ctl, mut out) = setup();
    send(&mut ctl, &mut out, "fwd 0.13 1.5");
    run(&mut ctl, &mut out, 0, 1500);
    assert_eq!(servos(&mut ctl), fwd_drive());
    assert_eq!(ctl.status().remaining_ms, Some(10));
    out.take();
    ctl.tick(1_500_000, &mut out);
    assert_eq!(servos(&mut ctl), neutral());
    assert_eq!(out.take(), ["# done"]);
    // exactly 150 ticks of 10 ms at the model's speed
    let v = config::actuators::MODEL.drive(Motion::Straight(Speed::from_mm_s(130))).motion;
    let Motion::Straight(v) = v else { panic!("{v:?}") };
    let want = v.to_mps_f64() * 1000.0 * 1.5;
    let got = ctl.pose().x.to_mm_f64();
    assert!((got - want).abs() < 1e-3, "x {got} want {want}");
    assert!(ctl.pose().y.to_mm_f64().abs() < 1e-6);
}

#[test]
fn a_new_command_replaces_a_timed_one() {
    let (mut ctl, mut out) = setup();
    send(&mut ctl, &mut out, "fwd 0.13 5");
    run(&mut ctl, &mut out, 0, 200);
    send(&mut ctl, &mut out, "stop");
    ctl.tick(200_000, &mut out);
    assert_eq!(servos(&mut ctl), neutral());
    assert_eq!(ctl.mode(), Mode::Idle);
}

// ---- each command ----------------------------------------------------

#[test]
fn stop_sets_both_neutrals_at_the_next_tick() {
    let (mut ctl, mut out) = setup();
    send(&mut ctl, &mut out, "back 0.13");
    ctl.tick(0, &mut out);
    let back = config::actuators::MODEL.drive(Motion::Straight(Speed::from_mm_s(-130)));
    assert_eq!(servos(&mut ctl), (back.left, back.right));
    send(&mut ctl, &mut out, "s");
    assert_eq!(out.take(), ["# ok back 0.130", "# ok stop"]);
    ctl.tick(10_000, &mut out);
    assert_eq!(servos(&mut ctl), neutral());
    assert_eq!(ctl.applied().motion, Motion::Stop);
}

#[test]
fn servo_sets_raw_commands_and_the_pose_follows_the_forward_model() {
    let (mut ctl, mut out) = setup();
    send(&mut ctl, &mut out, "servo 105 60 0.5");
    assert_eq!(out.take(), ["# ok servo 105.00 60.00 0.500"]);
    run(&mut ctl, &mut out, 0, 510);
    let (l, r) = (ServoCmd::from_int(105), ServoCmd::from_int(60));
    let m = config::actuators::MODEL.motion_from_commands(l, r);
    assert_eq!(m.kind(), MotionKind::Forward);
    let Motion::Straight(v) = m else { panic!() };
    let want = v.to_mps_f64() * 1000.0 * 0.5;
    assert!((ctl.pose().x.to_mm_f64() - want).abs() < 1e-3);
    // raw commands ignore the trims
    send(&mut ctl, &mut out, "trim left 2");
    send(&mut ctl, &mut out, "servo 90 90");
    ctl.tick(520_000, &mut out);
    assert_eq!(servos(&mut ctl), (ServoCmd::from_int(90), ServoCmd::from_int(90)));
}

#[test]
fn trim_moves_the_neutral_of_one_servo() {
    let (mut ctl, mut out) = setup();
    send(&mut ctl, &mut out, "trim left 1.5");
    send(&mut ctl, &mut out, "trim r -2.25");
    assert_eq!(
        out.take(),
        [
            "# ok trim left 1.50",
            "# not saved: save to keep it",
            "# ok trim right -2.25",
            "# not saved: save to keep it"
        ]
    );
    ctl.tick(0, &mut out);
    assert_eq!(servos(&mut ctl), (ServoCmd::from_f64(91.5), ServoCmd::from_f64(87.75)));
    assert_eq!(ctl.model().left_trim, Trim::from_f64(1.5));
    assert_eq!(ctl.status().right_trim, Trim::from_f64(-2.25));
}

#[test]
fn pose_sets_the_pose() {
    let (mut ctl, mut out) = setup();
    send(&mut ctl, &mut out, "pose 120 -45 90");
    assert_eq!(out.take(), ["# ok pose 120 -45 90.000"]);
    assert_eq!(ctl.pose(), Pose::from_mm(120, -45, Angle::QUARTER_TURN));
}

/// `reset` is `locate`: the robot stands for its first view; `status`
/// leaves it at that, any other command ends it and says so (the pose is
/// then unknown: `goto` refuses it). `tests/localization/localize.rs` runs it to the end.
#[test]
fn reset_locates_and_a_command_interrupts_it() {
    let (mut ctl, mut out) = setup();
    send(&mut ctl, &mut out, "pose 120 -45 90");
    send(&mut ctl, &mut out, "reset");
    assert_eq!(out.take()[1], "# ok locate");
    run(&mut ctl, &mut out, 0, 50);
    assert_eq!(ctl.status().mode, "locate");
    assert_eq!(ctl.applied().motion, Motion::Stop, "the first view is taken standing");
    send(&mut ctl, &mut out, "status");
    assert_eq!(ctl.status().mode, "locate");
    out.take();
    send(&mut ctl, &mut out, "stop");
    assert_eq!(
        out.take(),
        ["# locate failed: interrupted by a command; the pose is unknown until `pose` or `locate`", "# ok stop"]
    );
    assert_eq!(ctl.status().mode, "idle");
    // the pose is unknown: a goto finds it first
    send(&mut ctl, &mut out, "goto 300 200");
    assert_eq!(out.take(), ["# estimate too uncertain to steer by: locating first"]);
    assert_eq!(ctl.status().mode, "locate");
}

#[test]
fn status_reports_the_mode_pose_and_sensors() {
    let (mut ctl, mut out) = setup();
    send(&mut ctl, &mut out, "pose 10 20 0");
    send(&mut ctl, &mut out, "fwd 0.13 2");
    run(&mut ctl, &mut out, 0, 500);
    out.take();
    send(&mut ctl, &mut out, "status");
    let lines = out.take();
    assert_eq!(lines.len(), 2, "{lines:?}");
    assert_eq!(lines[0], "# ok status");
    let s = &lines[1];
    for want in ["# status t_ms=490 ", " mode=drive ", " motion=fwd ", " left_ms=1510 ", " x_mm=74 ", " y_mm=20 "] {
        assert!(s.contains(want), "{want:?} not in {s}");
    }
    assert!(
        s.ends_with(
            " front=ok right=ok compass=ok f_bus=0 f_timeout=0 f_missing=0 f_bad_sample=0 f_outliers=0 f_overruns=0"
        ),
        "{s}"
    );
}

#[test]
fn help_prints_the_help_lines() {
    let (mut ctl, mut out) = setup();
    send(&mut ctl, &mut out, "help");
    let lines = out.take();
    assert_eq!(lines[0], "# ok help");
    assert_eq!(&lines[1..], HELP);
}

#[test]
fn malformed_input_gets_one_error_line_and_changes_nothing() {
    let (mut ctl, mut out) = setup();
    send(&mut ctl, &mut out, "fwd 0.13 3");
    ctl.tick(0, &mut out);
    out.take();
    let before = (ctl.mode(), ctl.pose(), *ctl.model());
    for bad in ["fwd", "fwd 0.5", "jump 3", "servo 90", "trim up 1", "rate 1000", "pose 1 2", "fwd 0.1 2 3"] {
        send(&mut ctl, &mut out, bad);
        let lines = out.take();
        assert_eq!(lines.len(), 1, "{bad}: {lines:?}");
        assert!(lines[0].starts_with("# err "), "{bad}: {lines:?}");
        assert_eq!((ctl.mode(), ctl.pose(), *ctl.model()), before, "{bad}");
    }
    // an over-long line, and bytes that are not ASCII
    ctl.feed_bytes(&[b'x'; 200], &mut out);
    ctl.feed(b'\n', &mut out);
    ctl.feed_bytes(b"fwd \xff\n", &mut out);
    let lines = out.take();
    assert_eq!(lines.len(), 2, "{lines:?}");
    assert!(lines.iter().all(|l| l.starts_with("# err ")));
    // an empty line is ignored
    ctl.feed_bytes(b"  \r\n", &mut out);
    assert!(out.take().is_empty());
    assert_eq!((ctl.mode(), ctl.pose(), *ctl.model()), before);
}

// ---- telemetry ---------------------------------------------------------

#[test]
fn telemetry_rows_come_at_the_set_rate_after_one_header() {
    let (mut ctl, mut out) = setup();
    send(&mut ctl, &mut out, "rate 4");
    assert_eq!(out.take(), ["# ok rate 4"]);
    run(&mut ctl, &mut out, 0, 2000);
    let lines = out.take();
    assert_eq!(lines[0], telemetry_header());
    let rows: Vec<_> = lines[1..].iter().map(|l| parse_telemetry_row(l).expect(l)).collect();
    assert_eq!(rows.iter().map(|r| r.t_ms).collect::<Vec<_>>(), [0, 250, 500, 750, 1000, 1250, 1500, 1750]);
    // a new rate takes over at once; no second header while telemetry stays on
    send(&mut ctl, &mut out, "rate 100");
    run(&mut ctl, &mut out, 2000, 2100);
    let lines = out.take();
    assert_eq!(lines.len(), 11, "{lines:?}");
    assert!(lines[1..].iter().all(|l| parse_telemetry_row(l).is_ok()));
    send(&mut ctl, &mut out, "rate 0");
    run(&mut ctl, &mut out, 2100, 3000);
    assert_eq!(out.take(), ["# ok rate 0"]);
}

#[test]
fn default_rate_is_the_config_rate() {
    let mut ctl = fresh();
    let mut out = Lines::default();
    run(&mut ctl, &mut out, 0, 1000);
    let lines = out.take();
    assert_eq!(lines[0], telemetry_header());
    assert_eq!(lines.len() as u32, 1 + config::timing::TELEMETRY_HZ);
}

#[test]
fn telemetry_reports_each_fresh_reading_once() {
    let (mut ctl, mut out) = setup();
    ctl.front().queue.push_back(Ok(lidar(300)));
    ctl.compass().queue.push_back(Ok(CompassSample {
        raw: MagCounts { x: 100, y: -20, z: 3 },
        field: MagField { x: 14, y: -37, z: 3 },
        heading: Angle::from_degrees_f64(45.0),
    }));
    send(&mut ctl, &mut out, "pose 100 200 45");
    send(&mut ctl, &mut out, "rate 50");
    send(&mut ctl, &mut out, "servo 100 100");
    ctl.tick(0, &mut out);
    let pose_at_0 = ctl.pose(); // corrected by the first readings
    run(&mut ctl, &mut out, 10, 40);
    let lines = out.take();
    let rows: Vec<_> = lines.iter().filter_map(|l| parse_telemetry_row(l).ok()).collect();
    assert_eq!(rows.len(), 2, "{lines:?}");
    let (a, b) = (&rows[0], &rows[1]);
    assert_eq!(a.front_raw_mm, Some(300));
    let Range::Target(d) = config::lidar::FRONT.range(300) else { panic!() };
    assert_eq!(a.front_dmm, Some((d.to_mm_f64() * 10.0).round() as i32));
    assert_eq!(a.right_raw_mm, None);
    assert_eq!(a.mag_raw, Some([100, -20, 3]));
    assert_eq!(a.mag_field, Some([14, -37, 3]));
    assert_eq!(a.compass_mdeg, Some(45_000));
    let dmm = |c: paperbot::math::Coord| (c.to_mm_f64() * 10.0).round() as i32;
    assert_eq!(
        (a.x_dmm, a.y_dmm, a.heading_mdeg),
        (dmm(pose_at_0.x), dmm(pose_at_0.y), pose_at_0.theta.to_millidegrees())
    );
    assert_eq!((a.left_cmd_centi, a.right_cmd_centi), (10_000, 10_000));
    assert_eq!(a.motion, MotionKind::Cw);
    assert_eq!((b.front_raw_mm, b.mag_raw), (None, None), "not fresh any more");
    assert_eq!(b.t_ms, 20);
}

// ---- sensor faults ---------------------------------------------------

#[test]
fn bus_errors_take_a_sensor_down_after_a_few_and_it_is_reinitialised_after_the_back_off() {
    let (mut ctl, mut out) = setup();
    ctl.front().steady = Some(lidar(300));
    ctl.right().steady = Some(lidar(200));
    ctl.compass().radius = 200.0;
    // one glitch: counted, the sensor stays up
    ctl.front().queue.push_back(Err(nb::Error::Other(SensorError::Bus)));
    run(&mut ctl, &mut out, 0, 30);
    assert!(ctl.front_health().up);
    assert_eq!(ctl.faults().bus, 1);
    // enough in a row: down
    let n = config::timing::SENSOR_MAX_BUS_ERRORS;
    for _ in 0..n {
        ctl.front().queue.push_back(Err(nb::Error::Other(SensorError::Bus)));
    }
    run(&mut ctl, &mut out, 30, 30 + 10 * u32::from(n));
    let down_at = 30 + 10 * (u32::from(n) - 1);
    assert!(!ctl.front_health().up);
    assert_eq!(ctl.faults().bus, 1 + u32::from(n));
    assert_eq!(ctl.front_health().last_error, Some(SensorError::Bus));
    // the first re-init fails (counted as missing), the second one works
    ctl.front().reinit_failures = 1;
    let polls = ctl.front().polls;
    let retry = config::timing::SENSOR_RETRY_MS;
    run(&mut ctl, &mut out, 30 + 10 * u32::from(n), down_at + retry);
    assert_eq!(ctl.front().reinit_calls, 0, "no re-init before the back-off");
    assert_eq!(ctl.front().polls, polls, "a down sensor is not polled");
    ctl.tick((down_at + retry) * 1000, &mut out);
    assert_eq!(ctl.front().reinit_calls, 1);
    assert_eq!(ctl.faults().missing, 1);
    assert!(!ctl.front_health().up);
    run(&mut ctl, &mut out, down_at + retry + 10, down_at + 2 * retry);
    assert_eq!(ctl.front().reinit_calls, 1);
    ctl.tick((down_at + 2 * retry) * 1000, &mut out);
    assert_eq!(ctl.front().reinit_calls, 2);
    assert!(ctl.front_health().up);
    assert_eq!(ctl.front_health().reinits, 1);
    // and it delivers again
    ctl.tick((down_at + 2 * retry + 10) * 1000, &mut out);
    assert_eq!(ctl.last_front(), Some(lidar(300)));
    // the others were never touched
    assert!(ctl.right_health().up && ctl.compass_health().up);
    // (the doubles' readings do not fit the pose: the estimator rejects them)
    let f = FaultCounters { rejected_outliers: 0, ..ctl.faults() };
    assert_eq!(f, FaultCounters { bus: 1 + u32::from(n), missing: 1, ..FaultCounters::default() });
}

#[test]
fn a_nack_while_polling_counts_like_a_bus_error_and_at_a_reinit_keeps_the_sensor_down() {
    let (mut ctl, mut out) = setup();
    ctl.front().steady = Some(lidar(300));
    let n = u32::from(config::timing::SENSOR_MAX_BUS_ERRORS);
    // fewer than the limit in a row, mixed with bus errors: still up
    for k in 0..n - 1 {
        let e = if k % 2 == 1 { SensorError::Missing } else { SensorError::Bus };
        ctl.front().queue.push_back(Err(nb::Error::Other(e)));
    }
    run(&mut ctl, &mut out, 0, 10 * n);
    assert!(ctl.front_health().up);
    assert_eq!(ctl.faults().missing + ctl.faults().bus, n - 1);
    assert_eq!(ctl.front_health().last_error, Some(SensorError::Missing));
    // a reading resets the count; then the limit of NACKs in a row: down
    for _ in 0..n {
        ctl.front().queue.push_back(Err(nb::Error::Other(SensorError::Missing)));
    }
    let t0 = 10 * n + 10;
    run(&mut ctl, &mut out, t0, t0 + 10 * (n - 1));
    assert!(ctl.front_health().up, "one short of the limit");
    ctl.tick((t0 + 10 * (n - 1)) * 1000, &mut out);
    assert!(!ctl.front_health().up);
    // a re-init that finds no chip: a NACK there means missing, down again
    ctl.front().reinit_failures = 1;
    let retry_at = t0 + 10 * (n - 1) + config::timing::SENSOR_RETRY_MS;
    run(&mut ctl, &mut out, t0 + 10 * n, retry_at + 10);
    assert_eq!(ctl.front().reinit_calls, 1);
    assert!(!ctl.front_health().up);
    assert_eq!(ctl.faults().missing, (n - 1) / 2 + n + 1, "the glitches, the NACKs in a row, the re-init");
}

#[test]
fn a_timeout_takes_a_sensor_down_at_once_a_bad_sample_does_not() {
    let (mut ctl, mut out) = setup();
    ctl.right().steady = Some(lidar(200));
    ctl.right().queue.push_back(Err(nb::Error::Other(SensorError::BadSample)));
    ctl.tick(0, &mut out);
    assert!(ctl.right_health().up);
    assert_eq!(ctl.faults().bad_sample, 1);
    ctl.right().queue.push_back(Err(nb::Error::Other(SensorError::Timeout)));
    ctl.tick(10_000, &mut out);
    assert!(!ctl.right_health().up);
    assert_eq!(ctl.faults().timeout, 1);
    run(&mut ctl, &mut out, 20, 10 + config::timing::SENSOR_RETRY_MS + 10);
    assert!(ctl.right_health().up);
    assert_eq!(ctl.right().reinit_calls, 1);
}

#[test]
fn a_silent_sensor_counts_as_a_timeout_and_the_loop_keeps_running() {
    let (mut ctl, mut out) = setup();
    // the compass never delivers: down after SENSOR_SILENT_MS, retried after the back-off
    send(&mut ctl, &mut out, "fwd 0.13 5");
    let silent = config::timing::SENSOR_SILENT_MS;
    run(&mut ctl, &mut out, 0, silent);
    assert!(ctl.compass_health().up);
    ctl.tick(silent * 1000, &mut out);
    assert!(!ctl.compass_health().up);
    // lidars are silent too (no steady reading): all three are down
    assert_eq!(ctl.faults().timeout, 3);
    // re-inits after the back-off, one per tick (each blocks the loop):
    // front, then right, then the compass
    let first = silent + config::timing::SENSOR_RETRY_MS;
    run(&mut ctl, &mut out, silent + 10, first);
    let calls = |ctl: &mut Ctl| [ctl.front().reinit_calls, ctl.right().reinit_calls, ctl.compass().reinit_calls];
    assert_eq!(calls(&mut ctl), [0, 0, 0]);
    for (k, want) in [[1, 0, 0], [1, 1, 0], [1, 1, 1]].into_iter().enumerate() {
        ctl.tick((first + 10 * k as u32) * 1000, &mut out);
        assert_eq!(calls(&mut ctl), want, "{k}");
    }
    // silent again for SENSOR_SILENT_MS, down, re-init 1 s later
    let second = first + 20 + silent + config::timing::SENSOR_RETRY_MS;
    run(&mut ctl, &mut out, first + 30, second);
    assert_eq!(ctl.compass().reinit_calls, 1);
    ctl.tick(second * 1000, &mut out);
    assert_eq!(ctl.compass().reinit_calls, 2);
    assert_eq!(ctl.faults().timeout, 6);
    // the loop kept driving and updating the pose the whole time
    assert_eq!(servos(&mut ctl), fwd_drive());
    assert!(ctl.pose().x.to_mm_f64() > 300.0);
}

#[test]
fn late_ticks_count_as_overruns_and_the_clock_survives_wrapping() {
    let (mut ctl, mut out) = setup();
    let start = u32::MAX - 15_000; // wraps between the 2nd and 3rd tick
    send(&mut ctl, &mut out, "fwd 0.13 0.1");
    let mut t = start;
    for _ in 0..10 {
        ctl.tick(t, &mut out);
        t = t.wrapping_add(TICK_US);
    }
    assert_eq!(ctl.faults().overruns, 0);
    assert_eq!(ctl.clock_us(), 90_000);
    ctl.tick(t.wrapping_add(20_000), &mut out); // 30 ms after the last
    assert_eq!(ctl.faults().overruns, 1);
    assert_eq!(ctl.clock_us(), 120_000);
    let v = config::actuators::MODEL.drive(Motion::Straight(Speed::from_mm_s(130))).motion;
    let Motion::Straight(v) = v else { panic!() };
    // the late tick ends the 100 ms drive, but the servos drove until it: 120 ms
    assert!((ctl.pose().x.to_mm_f64() - v.to_mps_f64() * 120.0).abs() < 1e-3, "{:?}", ctl.pose());
    assert_eq!(ctl.mode(), Mode::Idle);
}

// ---- calibration -----------------------------------------------------

#[test]
fn calibration_turns_in_place_applies_and_prints_the_result() {
    let (mut ctl, mut out) = setup();
    {
        let c = ctl.compass();
        c.radius = 200.0;
        c.centre = [79.0, 35.0, 2.0];
        c.turn_per_poll = std::f64::consts::TAU / 97.0;
    }
    send(&mut ctl, &mut out, "cal 300");
    assert_eq!(out.take(), ["# ok cal 300"]);
    ctl.tick(0, &mut out);
    let turn = config::actuators::MODEL
        .drive(Motion::Turn(paperbot::math::TurnRate::from_mrad_s(config::compass::CALIBRATION_TURN_MRAD_S)));
    assert_eq!(servos(&mut ctl), (turn.left, turn.right));
    assert_eq!(ctl.mode().word(), "cal");
    // no deadman during the sweep: 300 samples at one per tick
    run(&mut ctl, &mut out, 10, 2990);
    assert_eq!(ctl.mode().word(), "cal");
    assert!(out.take().is_empty());
    ctl.tick(2_990_000, &mut out);
    assert_eq!(ctl.mode(), Mode::Idle);
    let lines = out.take();
    assert_eq!(lines.len(), 3, "{lines:?}");
    assert_eq!(lines[2], "# not saved: save to keep it");
    assert_eq!(
        lines[0],
        "# calibration ok: 300 samples, 12 of 12 sectors; x and y measured, z kept from config; applied. For config::compass:"
    );
    assert!(lines[1].starts_with("# pub const CALIBRATION: MagCalibration = MagCalibration::from_f64([79.0, 35.0, "));
    let cal = ctl.compass().calibration;
    assert_eq!(&cal.bias[..2], &[79, 35]);
    // the line to paste, from the applied calibration: biases as integers,
    // scales (Q16) in millionths rounded half away from zero
    let scale = |q16: i32| {
        let m = (u64::from(q16.unsigned_abs()) * 1_000_000 + (1 << 15)) >> 16;
        format!("{}{}.{:06}", if q16 < 0 { "-" } else { "" }, m / 1_000_000, m % 1_000_000)
    };
    let [b0, b1, b2] = cal.bias;
    let [s0, s1, s2] = cal.scale_q16.map(scale);
    assert_eq!(
        lines[1],
        format!("# pub const CALIBRATION: MagCalibration = MagCalibration::from_f64([{b0}.0, {b1}.0, {b2}.0], [{s0}, {s1}, {s2}]);")
    );
    // the same text as the host-side ConfigLine (core::fmt)
    assert_eq!(lines[1], format!("# {}", paperbot::model::compass::ConfigLine(&cal)));
    ctl.tick(3_000_000, &mut out);
    assert_eq!(servos(&mut ctl), neutral());
}

#[test]
fn calibration_without_a_turning_field_times_out_and_stops() {
    let (mut ctl, mut out) = setup();
    ctl.compass().radius = 200.0; // a field that never turns
    send(&mut ctl, &mut out, "cal 250");
    out.take();
    // short of sectors, the sweep keeps collecting up to its cap
    let cap = u32::from(250 + config::compass::CALIBRATION_EXTRA_SAMPLES);
    run(&mut ctl, &mut out, 0, 10 * cap);
    let lines = out.take();
    assert_eq!(lines, ["# err calibration failed: the turn covered 0 of 12 sectors, need 11"]);
    assert_eq!(ctl.mode(), Mode::Idle);
    assert_eq!(ctl.compass().calibration, config::compass::CALIBRATION, "unchanged");

    // a compass that delivers nothing: the sweep times out
    ctl.compass().radius = 0.0;
    send(&mut ctl, &mut out, "cal 250");
    out.take();
    let limit = cap * config::compass::CALIBRATION_MS_PER_SAMPLE;
    let t0 = 10 * cap;
    run(&mut ctl, &mut out, t0, t0 + limit);
    assert_eq!(ctl.mode().word(), "cal");
    ctl.tick((t0 + limit) * 1000, &mut out);
    assert_eq!(ctl.mode(), Mode::Idle);
    let lines = out.take();
    assert!(lines.contains(&"# err calibration timed out: 0 of 250 samples".to_string()), "{lines:?}");
}

#[test]
fn any_motion_command_abandons_a_calibration() {
    let (mut ctl, mut out) = setup();
    send(&mut ctl, &mut out, "cal");
    run(&mut ctl, &mut out, 0, 100);
    send(&mut ctl, &mut out, "status");
    assert_eq!(ctl.mode().word(), "cal", "status does not end the sweep");
    out.take();
    send(&mut ctl, &mut out, "stop");
    assert_eq!(out.take(), ["# calibration abandoned after 0 samples", "# ok stop"]);
    assert_eq!(ctl.mode(), Mode::Idle);
}

// ---- the estimator -------------------------------------------------------

#[test]
fn the_estimator_corrects_the_pose_with_fresh_readings_dead_reckoning_does_not() {
    let (mut ctl, mut out) = setup();
    // believed at x = 300 facing north; the front lidar sees the north wall
    // as if from x = 320 (762.5 - 320 = 442.5 mm ahead)
    send(&mut ctl, &mut out, "pose 300 200 0");
    let raw = config::lidar::FRONT.reading_for(paperbot::math::Length::from_mm_f64(442.5)).unwrap();
    ctl.front().steady = Some(LidarSample { raw_mm: raw, range: config::lidar::FRONT.range(raw) });
    let mut xs = vec![];
    for i in 0..100 {
        ctl.tick(i * TICK_US, &mut out);
        xs.push(ctl.pose().x.to_mm_f64());
    }
    let last = *xs.last().unwrap();
    assert!((last - 320.0).abs() < 2.0, "estimate x {last}");
    assert!(xs.windows(2).all(|w| w[1] >= w[0] - 1e-9), "moves towards the reading");
    assert_eq!(ctl.dead_reckoned(), Pose::from_mm(300, 200, Angle::ZERO));
    assert!(ctl.estimator().stats().front.accepted > 50);
    // `pose` resets both
    send(&mut ctl, &mut out, "pose 100 100 0");
    assert_eq!(ctl.pose(), ctl.dead_reckoned());
}

/// A motion the servos cannot drive as asked is driven at the nearest they
/// can, and its one answer says what is driven: `fwd 0.05` (below the
/// slowest forward speed) answers `# ok fwd <the slowest>`, not the request
/// and a note. A motion inside the range is answered as asked.
#[test]
fn a_motion_outside_the_servos_range_is_answered_with_what_is_driven() {
    let model = config::actuators::MODEL;
    let number = |line: &str, prefix: &str| -> f64 {
        line.strip_prefix(prefix).unwrap_or_else(|| panic!("{line}")).parse().unwrap()
    };
    for (command, prefix, request) in [
        ("fwd 0.05", "# ok fwd ", Motion::Straight(Speed::from_mm_s(50))),
        ("fwd 0.3", "# ok fwd ", Motion::Straight(Speed::from_mm_s(300))),
        ("back 0.001", "# ok back ", Motion::Straight(Speed::from_mm_s(-1))),
        ("cw 6", "# ok cw ", Motion::Turn(paperbot::math::TurnRate::from_mrad_s(6000))),
        ("ccw 0.5", "# ok ccw ", Motion::Turn(paperbot::math::TurnRate::from_mrad_s(-500))),
    ] {
        let drive = model.drive(request);
        assert!(drive.saturated, "{command} is outside the measured range");
        let (mut ctl, mut out) = setup();
        send(&mut ctl, &mut out, command);
        let lines = out.take();
        assert_eq!(lines.len(), 1, "one answer: {lines:?}");
        let driven = match drive.motion {
            Motion::Straight(v) => v.to_mps_f64().abs(),
            Motion::Turn(w) => f64::from(w.to_mrad_s().abs()) / 1000.0,
            Motion::Stop => panic!("{command}"),
        };
        assert!((number(&lines[0], prefix) - driven).abs() <= 0.0005, "{command}: {lines:?}, driven {driven}");
        ctl.tick(0, &mut out);
        assert_eq!(servos(&mut ctl), (drive.left, drive.right), "{command}");
    }
    let (mut ctl, mut out) = setup();
    send(&mut ctl, &mut out, "fwd 0.13");
    assert_eq!(out.take(), ["# ok fwd 0.130"]);
}

/// The ranges docs/protocol.md and `config::serial` give for what the servos
/// drive with no trim: each end is what a request past it is answered with.
#[test]
fn the_documented_drivable_ranges_are_the_models() {
    for (command, answer) in [
        ("fwd 0.001", "# ok fwd 0.124"),
        ("fwd 0.3", "# ok fwd 0.150"),
        ("back 0.001", "# ok back 0.108"),
        ("back 0.3", "# ok back 0.154"),
        ("cw 0.001", "# ok cw 2.377"),
        ("cw 6", "# ok cw 3.300"),
        ("ccw 0.001", "# ok ccw 2.353"),
        ("ccw 6", "# ok ccw 3.169"),
    ] {
        let (mut ctl, mut out) = setup();
        send(&mut ctl, &mut out, command);
        assert_eq!(out.take(), [answer], "{command}");
    }
}
