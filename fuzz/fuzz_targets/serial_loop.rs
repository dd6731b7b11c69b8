//! The control loop of the simulated robot fed arbitrary serial bytes
//! between ticks (on a sensor bus with arbitrary one-shot faults): never a
//! panic, every output line is a `#` line, the CSV header or a telemetry row
//! that parses; and once the bytes stop, the deadman (or a timed command's
//! own end) stops the robot: after `DEADMAN_MS` without input, an
//! untimed motion is never still driving.
#![no_main]

use libfuzzer_sys::fuzz_target;
use paperbot::config;
use paperbot::control::protocol::{classify_line, parse_telemetry_row, LineKind};
use paperbot::control::{Mode, TICK_US};
use paperbot::sim::bus::Fault;
use paperbot::sim::robot::{SimConfig, SimRobot};

fn check_output(robot: &mut SimRobot) {
    for line in robot.take_output() {
        assert!(line.len() <= paperbot::control::protocol::MAX_OUT_LINE, "{line}");
        if classify_line(&line) == LineKind::Row {
            assert!(parse_telemetry_row(&line).is_ok(), "not a row: {line:?}");
        }
    }
}

fuzz_target!(|data: &[u8]| {
    if data.len() > 4096 {
        return;
    }
    let mut robot = SimRobot::new(SimConfig::default());
    // Input: bytes go to the serial line; 0xFF ticks the loop once, 0xFE
    // ticks it 16 times, 0xFD injects a fault into the next bus
    // transaction (the following byte picks which).
    let mut bytes = data.iter().copied();
    while let Some(b) = bytes.next() {
        match b {
            0xFF => robot.tick(),
            0xFE => (0..16).for_each(|_| robot.tick()),
            0xFD => {
                let f = match bytes.next().unwrap_or(0) % 4 {
                    0 => Fault::Nack,
                    1 => Fault::Timeout,
                    2 => Fault::SdaStuck,
                    m => Fault::Corrupt(m.wrapping_mul(37) | 1),
                };
                robot.sensors.bus.inject_next(f);
            }
            _ => robot.feed(b),
        }
        check_output(&mut robot);
    }
    // silence: past the deadman, an untimed motion has stopped
    let ticks = config::timing::DEADMAN_MS * 1_000 / TICK_US + 2;
    for _ in 0..ticks {
        robot.tick();
    }
    check_output(&mut robot);
    let ctl = robot.controller();
    match ctl.mode() {
        Mode::Idle => {}
        // a timed command (and a calibration sweep) is its own deadman
        _ => assert!(ctl.status().remaining_ms.is_some(), "still driving untimed: {:?}", ctl.mode()),
    }
});
