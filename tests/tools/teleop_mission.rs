//! The teleop tool's mission side against the simulated robot: a mission
//! file checked, uploaded and started over a port, the cable pulled (the
//! robot runs on with no byte), then the log downloaded as telemetry CSV
//! and as a replay log that the replay tool reads.

use std::collections::VecDeque;
use std::io::{self, Read, Write};

use paperbot::config;
use paperbot::control::log::RowLog;
use paperbot::control::protocol::{parse_telemetry_row, telemetry_header};
use paperbot::host::teleop::mission::{download, parse_mission_file, save, start, upload};
use paperbot::host::teleop::Recorder;
use paperbot::model::estimator::replay;
use paperbot::sim::body::PoseF64;
use paperbot::sim::robot::{SimConfig, SimRobot};

/// The robot on an in-memory serial port: a read runs one loop tick and
/// returns what the robot sent; a write feeds the robot.
struct SimPort {
    robot: SimRobot,
    pending: VecDeque<u8>,
}

impl Read for SimPort {
    fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        if self.pending.is_empty() {
            self.robot.tick();
            for line in self.robot.take_output() {
                self.pending.extend(line.bytes().chain(*b"\r\n"));
            }
        }
        if self.pending.is_empty() {
            return Err(io::ErrorKind::TimedOut.into());
        }
        let n = buf.len().min(self.pending.len());
        for (d, s) in buf.iter_mut().zip(self.pending.drain(..n)) {
            *d = s;
        }
        Ok(n)
    }
}

impl Write for SimPort {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        for &b in buf {
            self.robot.feed(b);
        }
        Ok(buf.len())
    }
    fn flush(&mut self) -> io::Result<()> {
        Ok(())
    }
}

const FILE: &str = "\
# a square's three sides
pose 170 170 0      # put down here
wait 1.5            # the estimate settles
goto 500 170
face 90
goto 500 330
back 0.13 0.5
goto 220 330
";

#[test]
fn a_mission_file_is_uploaded_started_run_unplugged_and_its_log_downloaded() {
    let steps = parse_mission_file(FILE).unwrap();
    assert_eq!(steps[0], "mission add pose 170 170 0.000");
    assert_eq!(steps[5], "mission add back 0.130 0.500");
    let cfg = SimConfig { start: PoseF64::new(170.0, 170.0, 0.0), seed: 9, ..SimConfig::default() };
    let mut port = SimPort { robot: SimRobot::new(cfg), pending: VecDeque::new() };
    let mut shown = Vec::new();
    upload(&mut port, &steps, &mut shown).unwrap().unwrap();
    assert_eq!(port.robot.controller().mission().len(), 7);
    let countdown = start(&mut port, Some(10), &mut shown).unwrap().unwrap();
    assert!(countdown.starts_with("# mission starts in 10 s"), "{countdown}");

    // the cable is pulled: the robot runs on its own, nobody sends a byte
    let mut lines = Vec::new();
    for _ in 0..90 * 100 {
        port.robot.tick();
        lines.extend(port.robot.take_output());
        if lines.iter().any(|l| l.starts_with("# mission done") || l.starts_with("# err")) {
            break;
        }
    }
    assert!(lines.iter().any(|l| l.starts_with("# mission done")), "{lines:?}");
    let t = port.robot.truth();
    assert!((t.x - 220.0).hypot(t.y - 330.0) <= 20.0, "ended at {t:?}");

    // plugged in again: the log comes down
    let mut csv = Vec::new();
    let mut replay_log = Vec::new();
    let mut rec = Recorder::new(&mut replay_log).unwrap();
    let got = download(&mut port, &mut csv, Some(&mut rec)).unwrap().unwrap();
    let held = port.robot.controller().log().len();
    assert_eq!(got.rows, held);
    assert_eq!(got.summary, format!("# log {held} rows at 10 Hz, 0 dropped (oldest first)"));
    let csv = String::from_utf8(csv).unwrap();
    let mut it = csv.lines();
    assert_eq!(it.next(), Some(telemetry_header()));
    assert!(it.all(|l| parse_telemetry_row(l).is_ok()));
    let samples = replay::parse(&String::from_utf8(replay_log).unwrap()).unwrap();
    assert_eq!(samples.len(), held);
    assert!(samples.iter().any(|s| s.front_mm.is_some()) && samples.iter().any(|s| s.heading.is_some()));
    println!("mission log: {held} rows, downloaded and replayable");
}

#[test]
fn a_mission_uploaded_and_saved_is_back_after_a_power_cycle() {
    // teleop --mission FILE --save
    let steps = parse_mission_file(FILE).unwrap();
    let cfg = SimConfig { locate_at_power_up: false, ..SimConfig::default() };
    let mut port = SimPort { robot: SimRobot::new(cfg), pending: VecDeque::new() };
    let mut shown = Vec::new();
    upload(&mut port, &steps, &mut shown).unwrap().unwrap();
    let saved = save(&mut port, &mut shown).unwrap().unwrap();
    assert!(saved.starts_with("# saved: record 1 at 0x3f9000, paused "), "{saved}");
    let flash = port.robot.flash();
    let mut again = SimRobot::with_flash(cfg, flash);
    assert_eq!(
        again.take_output(),
        ["# settings from flash, record 1: trims, compass, declination, mission of 7 steps"]
    );
    assert_eq!(again.controller().mission(), port.robot.controller().mission());

    // refused while the robot moves: the reason comes back
    let mut port = SimPort { robot: again, pending: VecDeque::new() };
    port.robot.send("fwd 0.13");
    let refused = save(&mut port, &mut shown).unwrap().unwrap_err();
    assert!(refused.ends_with("# err moving: stop first (flash pauses the loop)"), "{refused}");
}

#[test]
fn mission_files_with_mistakes_are_refused_before_anything_is_sent() {
    for (text, line, says) in [
        ("goto 100 100\nfwd 0.13\n", 2, "not a mission step"),
        ("# c\n\nstatus\n", 3, "not a mission step"),
        ("goto 100\n", 1, "missing y"),
        ("jump 3\n", 1, "unknown command"),
        ("wait 99\n", 1, "duration out of range"),
    ] {
        let e = parse_mission_file(text).unwrap_err();
        assert_eq!(e.line_no, line, "{text:?}: {e}");
        assert!(e.message.contains(says), "{text:?}: {e}");
    }
    let many = "wait 1\n".repeat(config::mission::MAX_STEPS + 1);
    assert!(parse_mission_file(&many).unwrap_err().message.contains("steps, the robot holds"));
    assert_eq!(parse_mission_file("wait 1\n".repeat(config::mission::MAX_STEPS).as_str()).unwrap().len(), 24);
}
