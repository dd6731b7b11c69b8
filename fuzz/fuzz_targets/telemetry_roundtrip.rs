//! The round trips of the protocol's structured values, from arbitrary
//! input: a command built from fuzz data (every field anywhere in its
//! range) formats to its canonical text and parses back to itself; a
//! telemetry report built from fuzz data (any pose, readings, motion,
//! commands, counters) fits `MAX_ROW` and its row reads back to exactly the
//! values it was made from; a status line fits `MAX_STATUS`; and the host's
//! row parser takes any text without panicking (a row it accepts formats
//! back to the same text).
#![no_main]

use arbitrary::{Arbitrary, Result, Unstructured};
use heapless::String;
use libfuzzer_sys::fuzz_target;
use paperbot::config::serial;
use paperbot::control::protocol::{
    format_command, format_row, format_status, format_telemetry, parse, parse_telemetry_row, Command, FaultCounters,
    Side, Status, Telemetry, TelemetryRow, MAX_RESPONSE, MAX_ROW, MAX_STATUS,
};
use paperbot::driver::{CompassSample, LidarSample};
use paperbot::math::{Angle, Coord, Length, Speed, TurnRate};
use paperbot::model::compass::{MagCounts, MagField};
use paperbot::model::estimator::Tracking;
use paperbot::model::{Motion, Pose, Range, ServoCmd, Trim};

fn int(u: &mut Unstructured, lo: i64, hi: i64) -> Result<i64> {
    u.int_in_range(lo..=hi)
}

/// A command the parser can produce, every field anywhere in its range.
fn command(u: &mut Unstructured) -> Result<Command> {
    let duration = |u: &mut Unstructured| -> Result<Option<u32>> {
        Ok(if bool::arbitrary(u)? { Some(int(u, 1, i64::from(serial::MAX_DURATION_MS))? as u32) } else { None })
    };
    // 1/100 steps to the parser's 1/256 steps (as the parser rounds)
    let q8 = |centi: i64| ((centi.abs() * 256 + 50) / 100 * centi.signum()) as i32;
    Ok(match u.int_in_range(0..=9u8)? {
        0 => {
            let v = Speed::from_mm_s(int(u, 1, i64::from(serial::MAX_SPEED_MM_S))? as i32);
            let v = if bool::arbitrary(u)? { v.neg() } else { v };
            Command::Drive { motion: Motion::Straight(v), duration_ms: duration(u)? }
        }
        1 => {
            let w = TurnRate::from_mrad_s(int(u, 1, i64::from(serial::MAX_TURN_MRAD_S))? as i32);
            let w = if bool::arbitrary(u)? { w.neg() } else { w };
            Command::Drive { motion: Motion::Turn(w), duration_ms: duration(u)? }
        }
        2 => Command::Stop,
        3 => Command::Servo {
            left: ServoCmd::from_q8_signed(q8(int(u, 0, 18_000)?)),
            right: ServoCmd::from_q8_signed(q8(int(u, 0, 18_000)?)),
            duration_ms: duration(u)?,
        },
        4 => {
            let max = i64::from(serial::MAX_TRIM_CENTI);
            Command::Trim {
                side: if bool::arbitrary(u)? { Side::Left } else { Side::Right },
                trim: Trim(q8(int(u, -max, max)?) as i16),
            }
        }
        5 => {
            let max = i64::from(serial::MAX_POSE_MM);
            Command::SetPose {
                x_mm: int(u, -max, max)? as i32,
                y_mm: int(u, -max, max)? as i32,
                heading: Angle::from_millidegrees(int(u, -360_000, 360_000)? as i32),
            }
        }
        6 => Command::Calibrate {
            samples: int(u, i64::from(serial::MIN_CAL_SAMPLES), i64::from(serial::MAX_CAL_SAMPLES))? as u16,
        },
        7 => Command::Rate { hz: int(u, 0, i64::from(serial::MAX_TELEMETRY_HZ))? as u16 },
        8 => Command::Status,
        _ => Command::Help,
    })
}

fn motion(u: &mut Unstructured) -> Result<Motion> {
    Ok(match u.int_in_range(0..=2u8)? {
        0 => Motion::Stop,
        1 => Motion::Straight(Speed::from_bits(i32::arbitrary(u)?)),
        _ => Motion::Turn(TurnRate::from_bits(i32::arbitrary(u)?)),
    })
}

fn faults(u: &mut Unstructured) -> Result<FaultCounters> {
    Ok(FaultCounters {
        bus: u32::arbitrary(u)?,
        timeout: u32::arbitrary(u)?,
        missing: u32::arbitrary(u)?,
        bad_sample: u32::arbitrary(u)?,
        rejected_outliers: u32::arbitrary(u)?,
        overruns: u32::arbitrary(u)?,
    })
}

fn pose(u: &mut Unstructured) -> Result<Pose> {
    Ok(Pose::from_parts(
        Coord(i64::arbitrary(u)?),
        Coord(i64::arbitrary(u)?),
        Angle(u32::arbitrary(u)?),
        u16::arbitrary(u)?,
    ))
}

fn lidar(u: &mut Unstructured) -> Result<Option<LidarSample>> {
    if !bool::arbitrary(u)? {
        return Ok(None);
    }
    let range = match u.int_in_range(0..=2u8)? {
        0 => Range::Target(Length(i32::arbitrary(u)?)),
        1 => Range::NoTarget,
        _ => Range::TooClose,
    };
    Ok(Some(LidarSample { raw_mm: u16::arbitrary(u)?, range }))
}

fn compass(u: &mut Unstructured) -> Result<Option<CompassSample>> {
    if !bool::arbitrary(u)? {
        return Ok(None);
    }
    // the compass model clamps the corrected field to +-2^24
    let f = |u: &mut Unstructured| -> Result<i32> { u.int_in_range(-(1 << 24)..=(1 << 24)) };
    Ok(Some(CompassSample {
        raw: MagCounts { x: i16::arbitrary(u)?, y: i16::arbitrary(u)?, z: i16::arbitrary(u)? },
        field: MagField { x: f(u)?, y: f(u)?, z: f(u)? },
        heading: Angle(u32::arbitrary(u)?),
    }))
}

fn telemetry(u: &mut Unstructured) -> Result<Telemetry> {
    Ok(Telemetry {
        t_ms: u32::arbitrary(u)?,
        pose: pose(u)?,
        front: lidar(u)?,
        right: lidar(u)?,
        compass: compass(u)?,
        motion: motion(u)?,
        left_cmd: ServoCmd::from_q8(u32::arbitrary(u)?),
        right_cmd: ServoCmd::from_q8(u32::arbitrary(u)?),
        faults: faults(u)?,
        tracking: *u.choose(&[Tracking::Located, Tracking::Ambiguous, Tracking::Unknown])?,
    })
}

fn status(u: &mut Unstructured) -> Result<Status> {
    Ok(Status {
        t_ms: u32::arbitrary(u)?,
        mode: *u.choose(&["idle", "drive", "servo", "cal"])?,
        motion: motion(u)?,
        remaining_ms: Option::<u32>::arbitrary(u)?,
        pose: pose(u)?,
        tracking: *u.choose(&[Tracking::Located, Tracking::Ambiguous, Tracking::Unknown])?,
        left_cmd: ServoCmd::from_q8(u32::arbitrary(u)?),
        right_cmd: ServoCmd::from_q8(u32::arbitrary(u)?),
        left_trim: Trim(i16::arbitrary(u)?),
        right_trim: Trim(i16::arbitrary(u)?),
        rate_hz: u16::arbitrary(u)?,
        front_ok: bool::arbitrary(u)?,
        right_ok: bool::arbitrary(u)?,
        compass_ok: bool::arbitrary(u)?,
        faults: faults(u)?,
    })
}

fn run(data: &[u8]) -> Result<()> {
    // the host's row parser on the raw input as text
    if let Ok(text) = core::str::from_utf8(data) {
        if let Ok(row) = parse_telemetry_row(text) {
            let mut s: String<1024> = String::new();
            format_row(&row, &mut s).expect("a parsed row fits 1 KiB");
            assert_eq!(parse_telemetry_row(&s), Ok(row), "{text:?} -> {s}");
        }
    }
    let mut u = Unstructured::new(data);

    let cmd = command(&mut u)?;
    let mut text: String<MAX_RESPONSE> = String::new();
    format_command(&cmd, &mut text).expect("canonical form fits");
    assert_eq!(parse(text.as_bytes()), Ok(cmd), "{cmd:?} -> {text}");

    let t = telemetry(&mut u)?;
    let mut row: String<MAX_ROW> = String::new();
    format_telemetry(&t, &mut row).expect("every report fits MAX_ROW");
    let back = parse_telemetry_row(&row).expect("a written row parses");
    assert_eq!(back, TelemetryRow::from(&t), "{row}");

    let st = status(&mut u)?;
    let mut line: String<MAX_STATUS> = String::new();
    format_status(&st, &mut line).expect("every status fits MAX_STATUS");
    Ok(())
}

fuzz_target!(|data: &[u8]| {
    let _ = run(data);
});
