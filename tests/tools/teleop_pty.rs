//! End to end: the simulated robot served on a pseudo-terminal in real time
//! (`sim::serve`, as `examples/sim_pty.rs` does), driven through the teleop
//! tool's line mode over a real serial port handle (`serialport`, as
//! `examples/teleop.rs` does), recording the replay log; then the log is
//! checked against what the robot did and replayed through the estimator.
//! Also the server alone on an in-memory port: line endings, and output
//! nobody reads is bounded and dropped whole lines at a time.

use std::collections::VecDeque;
use std::io::{self, Read, Write};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Duration;

use paperbot::config;
use paperbot::control::protocol::{classify_line, parse_telemetry_row, LineKind};
use paperbot::host::teleop::{parse_plan, run_line_mode, LineModeOptions, LineModeReport, Recorder};
use paperbot::math::{Angle, Coord, Speed, TurnRate};
use paperbot::model::estimator::replay::{self, Sample};
use paperbot::model::measurement::Arena;
use paperbot::model::{Motion, Pose};
use paperbot::sim::body::{advance, Kinematics, MotionF64, PoseF64};
use paperbot::sim::robot::{Noise, SimConfig, SimRobot};
use paperbot::sim::serve::{Server, MAX_PENDING};
use serialport::{SerialPort, TTYPort};

/// Sets the flag when dropped: the server stops even if the client panics.
struct StopOnDrop(Arc<AtomicBool>);

impl Drop for StopOnDrop {
    fn drop(&mut self) {
        self.0.store(true, Ordering::Relaxed);
    }
}

/// Runs a plan through the line mode against a fresh simulated robot: the
/// robot served on a PTY on this thread (the simulator is single-threaded),
/// the tool in another, opening the PTY's path as it opens the robot's port.
/// With `streaming_hz` the robot already streams telemetry at that rate,
/// and the tool starts 300 ms into it without clearing its input.
fn drive(
    plan: &str,
    opts: LineModeOptions,
    streaming_hz: Option<u16>,
) -> (LineModeReport, String, Vec<Sample>, Option<String>, Server) {
    let cfg = SimConfig { noise: Noise::OFF, locate_at_power_up: false, ..SimConfig::default() };
    let (mut master, slave) = TTYPort::pair().expect("a pseudo-terminal");
    master.set_timeout(Duration::ZERO).expect("non-blocking master");
    let path = slave.name().expect("the PTY's path");
    let plan = parse_plan(plan).expect("plan");
    let stop = Arc::new(AtomicBool::new(false));
    let guard = StopOnDrop(Arc::clone(&stop));
    let client = std::thread::spawn(move || {
        let _guard = guard;
        if streaming_hz.is_some() {
            std::thread::sleep(Duration::from_millis(300));
        }
        let mut port = serialport::new(&path, config::serial::BAUD)
            .timeout(Duration::from_millis(5))
            .open()
            .unwrap_or_else(|e| panic!("{path}: {e}"));
        // a USB serial chip still holds rows after the OS's buffer is
        // cleared (as the tool does); a streaming robot's rows are all kept
        if streaming_hz.is_none() {
            port.clear(serialport::ClearBuffer::Input).expect("flush stale output");
        }
        let mut out = Vec::new();
        let mut rec = Recorder::new(Vec::new()).unwrap();
        let report = run_line_mode(&mut *port, plan, opts, &mut out, Some(&mut rec)).expect("line mode");
        (report, out, rec.replay_start(), rec.into_inner())
    });
    let mut robot = SimRobot::new(cfg);
    if let Some(hz) = streaming_hz {
        robot.send(&format!("rate {hz}"));
    }
    let mut server = Server::new(robot);
    server.run(&mut master, &stop).expect("the server runs");
    let (report, out, start, log) = client.join().expect("the line mode ran");
    drop(slave);
    let log = String::from_utf8(log).unwrap();
    let samples = replay::parse(&log).unwrap_or_else(|e| panic!("the replay tool refuses the log: {e}\n{log}"));
    (report, String::from_utf8(out).unwrap(), samples, start, server)
}

/// The servo commands (centi-steps) the robot drives `motion` with.
fn commands(motion: Motion) -> (u32, u32) {
    let d = config::actuators::MODEL.drive(motion);
    (d.left.to_centi(), d.right.to_centi())
}

/// First and last time of the one contiguous stretch of rows driving `cmds`.
fn stretch(samples: &[Sample], cmds: (u32, u32)) -> (u32, u32) {
    let hits: Vec<usize> = samples
        .iter()
        .enumerate()
        .filter(|(_, s)| (s.left.to_centi(), s.right.to_centi()) == cmds)
        .map(|(i, _)| i)
        .collect();
    assert!(!hits.is_empty(), "no row drives {cmds:?}");
    let (first, last) = (hits[0], hits[hits.len() - 1]);
    assert_eq!(hits.len(), last - first + 1, "{cmds:?} is not driven in one stretch");
    (samples[first].t_ms, samples[last].t_ms)
}

#[test]
fn line_mode_drives_the_simulated_robot_over_a_pty_and_records_a_replayable_log() {
    let rate = config::teleop::RECORD_TELEMETRY_HZ;
    let opts = LineModeOptions { linger_ms: 300, rate_hz: Some(rate), ..LineModeOptions::default() };
    // untimed motions: only the keep-alive holds them past the deadman
    let plan = "@200ms fwd 0.137\n@1700ms cw 2.839\n@2300ms stop\n";
    let (report, out, samples, start, server) = drive(plan, opts, None);

    assert_eq!((report.sent, report.errors), (3, 0), "{out}");
    // 1.5 s of fwd and 0.6 s of cw at one repeat per REFRESH_MS (125 ms)
    assert!(report.refreshes >= 12, "{report:?}");
    let oks = ["# ok rate 0".into(), format!("# ok rate {rate}"), "# ok fwd 0.137".into(), "# ok cw 2.839".into()];
    for want in oks.iter().chain(&["# ok stop".into()]) {
        assert!(out.lines().any(|l| l == want), "no `{want}` in the output");
    }
    assert!(out.lines().any(|l| classify_line(l) == LineKind::Header), "the telemetry header is printed");
    assert_eq!(report.recorded, samples.len() as u64);
    assert!(samples.len() >= 100, "{} rows in 2.6 s at {rate} Hz", samples.len());

    // a row per 1000/rate ms of robot time
    let mut gaps: Vec<u32> = samples.windows(2).map(|w| w[1].t_ms - w[0].t_ms).collect();
    gaps.sort_unstable();
    assert!(gaps[0] > 0, "time stands still");
    assert_eq!(gaps[gaps.len() / 2], 1000 / u32::from(rate), "median row spacing");

    // what was driven, and for how long (robot time): well past the deadman
    let model = config::actuators::MODEL;
    let fwd = Motion::Straight(Speed::from_mm_s(137));
    let cw = Motion::Turn(TurnRate::from_mrad_s(2839));
    let (f0, f1) = stretch(&samples, commands(fwd));
    let (c0, c1) = stretch(&samples, commands(cw));
    let deadman = config::timing::DEADMAN_MS;
    assert!(f1 - f0 >= 2 * deadman, "fwd held {} ms", f1 - f0);
    assert!(c0 > f1 && c1 - c0 >= deadman / 2, "cw {c0}..{c1} after fwd to {f1}");
    let last = samples.last().unwrap();
    assert_eq!((last.left.to_centi(), last.right.to_centi()), commands(Motion::Stop), "stopped at the end");

    // readings: raw lidar readings (30 Hz) in most rows, a heading in nearly every one
    let share = |n: usize| n as f64 / samples.len() as f64;
    let front = share(samples.iter().filter(|s| s.front_mm.is_some()).count());
    let right = share(samples.iter().filter(|s| s.right_mm.is_some()).count());
    let heading = share(samples.iter().filter(|s| s.heading.is_some()).count());
    assert!(front > 0.4 && right > 0.4 && heading > 0.8, "front {front:.2} right {right:.2} heading {heading:.2}");
    // the log is the printed telemetry, column for column (raw readings, not distances)
    let rows: std::collections::HashMap<u32, _> =
        out.lines().filter_map(|l| parse_telemetry_row(l).ok()).map(|r| (r.t_ms, r)).collect();
    assert_eq!(rows.len(), samples.len());
    for s in &samples {
        let r = &rows[&s.t_ms];
        assert_eq!((s.left.to_centi(), s.right.to_centi()), (r.left_cmd_centi, r.right_cmd_centi), "t {}", s.t_ms);
        assert_eq!((s.front_mm, s.right_mm), (r.front_raw_mm, r.right_raw_mm), "t {}", s.t_ms);
        assert_eq!(s.heading.map(|h| h.to_millidegrees()), r.compass_mdeg, "t {}", s.t_ms);
    }
    let truth = server.robot().truth();

    // the truth moved as the log says it was driven (noise off: the sim
    // moves by the actuator model's forward lines)
    let d = config::geometry::ROTATION_TO_REFERENCE.to_mm_f64();
    let mf = |m: Motion| MotionF64::from_motion(model.motion_from_commands(model.drive(m).left, model.drive(m).right));
    let s0 = SimConfig::default().start;
    let row_s = 1.0 / f64::from(rate);
    let expected = advance(&s0, mf(fwd), f64::from(f1 - f0) / 1000.0 + row_s, Kinematics::Rigid, d);
    let expected = advance(&expected, mf(cw), f64::from(c1 - c0) / 1000.0 + row_s, Kinematics::Rigid, d);
    assert!(truth.distance(&expected) < 15.0, "truth {truth:?} vs log {expected:?}");
    assert!(truth.heading_error(&expected).to_degrees().abs() < 5.0, "truth {truth:?} vs log {expected:?}");

    // the replay of the log ends where the robot's own estimate ended
    let start = start.expect("a start pose");
    let v: Vec<f64> = start.split(',').map(|x| x.parse().unwrap()).collect();
    let pose = Pose::new(Coord::from_mm_f64(v[0]), Coord::from_mm_f64(v[1]), Angle::from_degrees_f64(v[2]));
    let (est, _) = replay::replay(&samples, replay::Start::Pose(pose), Arena::DEFAULT);
    let replayed = PoseF64::from_pose(&est.last().unwrap().pose);
    let reported = out
        .lines()
        .filter_map(|l| parse_telemetry_row(l).ok())
        .filter(|r| r.t_ms == last.t_ms)
        .map(|r| {
            PoseF64::new(
                f64::from(r.x_dmm) / 10.0,
                f64::from(r.y_dmm) / 10.0,
                (f64::from(r.heading_mdeg) / 1000.0).to_radians(),
            )
        })
        .next()
        .expect("the last row in the output");
    assert!(replayed.distance(&reported) < 10.0, "replay {replayed:?} vs robot {reported:?}");
    assert!(replayed.heading_error(&reported).to_degrees().abs() < 3.0, "replay {replayed:?} vs robot {reported:?}");
    assert!(replayed.distance(&truth) < 20.0, "replay {replayed:?} vs truth {truth:?}");
    let stats = server.stats();
    assert_eq!(stats.dropped_lines, 0, "{stats:?}");
    eprintln!(
        "rows {} refreshes {} fwd {} ms cw {} ms; truth vs log {:.1} mm {:.2} deg; replay vs robot {:.2} mm {:.3} deg; \
         replay vs truth {:.1} mm; {stats:?}",
        samples.len(),
        report.refreshes,
        f1 - f0,
        c1 - c0,
        truth.distance(&expected),
        truth.heading_error(&expected).to_degrees(),
        replayed.distance(&reported),
        replayed.heading_error(&reported).to_degrees(),
        replayed.distance(&truth)
    );
}

#[test]
fn rows_streamed_before_the_run_are_dropped_so_the_output_is_one_csv() {
    let opts = LineModeOptions { linger_ms: 200, rate_hz: Some(20), ..LineModeOptions::default() };
    let (report, out, samples, _, _) = drive("@100ms fwd 0.137 0.5\n", opts, Some(50));
    assert_eq!((report.sent, report.errors), (1, 0), "{out}");
    // what pandas.read_csv(log, comment='#') reads: the header first, then rows of its width
    let csv: Vec<&str> = out.lines().filter(|l| !l.starts_with('#')).collect();
    assert_eq!(classify_line(csv[0]), LineKind::Header, "the first CSV line:\n{out}");
    let width = csv[0].split(',').count();
    assert!(csv[1..].iter().all(|l| l.split(',').count() == width && classify_line(l) != LineKind::Header), "{out}");
    assert_eq!(out.lines().next(), Some("# ok rate 0"), "{out}");
    // only rows at 20 Hz (50 ms apart after the first), none of the 50 Hz stream before
    assert!(samples.len() >= 5, "{} rows", samples.len());
    assert!(samples[1..].windows(2).all(|w| w[1].t_ms - w[0].t_ms == 50), "{samples:?}");
}

#[test]
fn without_keepalive_the_robots_deadman_cuts_an_untimed_drive() {
    let opts = LineModeOptions { linger_ms: 200, keepalive: false, rate_hz: Some(50), ..LineModeOptions::default() };
    let (report, out, samples, _, _) = drive("@100ms fwd 0.137\n@1500ms status\n", opts, None);
    assert_eq!((report.sent, report.refreshes, report.errors), (2, 0, 0), "{out}");
    let (f0, f1) = stretch(&samples, commands(Motion::Straight(Speed::from_mm_s(137))));
    // the deadman stops it DEADMAN_MS after the command (rows every 20 ms)
    let held = f1 - f0;
    let deadman = config::timing::DEADMAN_MS;
    assert!(held + 40 >= deadman && held <= deadman + 20, "fwd held {held} ms");
    assert!(out.contains("mode=idle"), "the status after the deadman says idle");
}

// ---- the server on an in-memory port ------------------------------------------------

/// A port: queued input, output accepted up to `room` bytes.
struct FakePort {
    input: VecDeque<u8>,
    output: Vec<u8>,
    room: usize,
}

impl Read for FakePort {
    fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        if self.input.is_empty() {
            return Err(io::ErrorKind::WouldBlock.into());
        }
        let n = buf.len().min(self.input.len());
        for (b, x) in buf.iter_mut().zip(self.input.drain(..n)) {
            *b = x;
        }
        Ok(n)
    }
}

impl Write for FakePort {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        let n = buf.len().min(self.room.saturating_sub(self.output.len()));
        if n == 0 {
            return Err(io::ErrorKind::TimedOut.into());
        }
        self.output.extend_from_slice(&buf[..n]);
        Ok(n)
    }
    fn flush(&mut self) -> io::Result<()> {
        Ok(())
    }
}

/// Every line ends in `\r\n` and is a header, a `#` line or a telemetry row.
fn check_lines(bytes: &[u8]) -> usize {
    let text = std::str::from_utf8(bytes).unwrap();
    assert!(text.ends_with("\r\n"), "ends mid-line");
    let lines: Vec<&str> = text.strip_suffix("\r\n").unwrap().split("\r\n").collect();
    for l in &lines {
        assert!(!l.contains('\n') && !l.contains('\r'), "{l:?}");
        match classify_line(l) {
            LineKind::Row => assert!(parse_telemetry_row(l).is_ok(), "{l:?}"),
            LineKind::Comment | LineKind::Header => {}
        }
    }
    lines.len()
}

#[test]
fn server_answers_with_crlf_lines_like_the_firmware() {
    let mut server =
        Server::new(SimRobot::new(SimConfig { noise: Noise::OFF, locate_at_power_up: false, ..SimConfig::default() }));
    let mut port =
        FakePort { input: b"status\nfwd 0.5\n".iter().copied().collect(), output: Vec::new(), room: 1 << 20 };
    server.step(&mut port).unwrap();
    let text = String::from_utf8(port.output.clone()).unwrap();
    // the input is handled before the first tick (and its telemetry header)
    assert!(text.starts_with("# ok status\r\n# status t_ms=0 mode=idle"), "{text}");
    assert!(text.contains("# err speed out of range 0.001..0.300 m/s\r\n"), "{text}");
    check_lines(&port.output);
    let s = server.stats();
    assert_eq!((s.ticks, s.bytes_in, s.bytes_out), (1, 15, port.output.len() as u64));
}

#[test]
fn server_output_nobody_reads_is_bounded_and_dropped_in_whole_lines() {
    let mut server =
        Server::new(SimRobot::new(SimConfig { noise: Noise::OFF, locate_at_power_up: false, ..SimConfig::default() }));
    let mut port = FakePort { input: b"rate 100\n".iter().copied().collect(), output: Vec::new(), room: 0 };
    // a row per tick, about 100 bytes: MAX_PENDING fills in well under 1000 ticks
    for _ in 0..1000 {
        server.step(&mut port).unwrap();
    }
    let dropped = server.stats().dropped_lines;
    assert!(dropped > 100, "dropped {dropped}");
    // a reader arrives: what was kept comes out as whole lines, then the new ones
    port.room = usize::MAX;
    server.step(&mut port).unwrap();
    assert!(port.output.len() <= MAX_PENDING + 1024, "{} bytes queued", port.output.len());
    assert!(port.output.len() > MAX_PENDING / 2);
    let kept = check_lines(&port.output);
    assert!(kept as u64 + dropped >= 1000, "kept {kept} dropped {dropped}");
    assert_eq!(server.stats().ticks, 1001);
}
