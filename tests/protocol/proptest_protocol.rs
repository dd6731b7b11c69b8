//! Property tests for the serial protocol: any byte string gives a command
//! or a typed error (never a panic); every accepted line's canonical echo
//! parses back to the same command; numbers written in range, in any of the
//! grammar's spellings, parse to exactly their value; values out of range
//! are refused as such; the line buffer keeps lines apart and bounded
//! whatever arrives; telemetry rows read back to exactly the numbers
//! written, and a row of any [`Telemetry`] fits [`MAX_ROW`].

use heapless::String;
use paperbot::config::serial;
use paperbot::control::protocol::{
    format_command, format_response, format_row, format_telemetry, parse, parse_telemetry_row, Command, FaultCounters,
    Field, LineBuffer, ParseError, Response, Side, Telemetry, TelemetryRow, MAX_LINE, MAX_RESPONSE, MAX_ROW,
};
use paperbot::driver::{CompassSample, LidarSample};
use paperbot::math::{Angle, Coord, Length};
use paperbot::model::compass::{MagCounts, MagField};
use paperbot::model::estimator::Tracking;
use paperbot::model::{Motion, MotionKind, Pose, Range, ServoCmd};
use proptest::prelude::*;

/// The canonical text of a command.
fn canonical(cmd: &Command) -> std::string::String {
    let mut s: String<MAX_RESPONSE> = String::new();
    format_command(cmd, &mut s).expect("a canonical command fits a response line");
    s.as_str().into()
}

/// `value / 10^decimals` as a decimal in one of the grammar's spellings:
/// optional `+`, optional leading zeros, `.5` for `0.5`, trailing zeros.
fn spell(value: i64, decimals: u32, plus: bool, lead: usize, trail: usize) -> std::string::String {
    let scale = 10i64.pow(decimals);
    let (int, frac) = (value.abs() / scale, value.abs() % scale);
    let mut s = std::string::String::new();
    if value < 0 {
        s.push('-');
    } else if plus {
        s.push('+');
    }
    s.push_str(&"0".repeat(lead));
    if !(int == 0 && decimals > 0 && lead == 0 && trail % 2 == 1) {
        s.push_str(&int.to_string()); // sometimes ".5" for "0.5"
    }
    if decimals > 0 || trail > 0 {
        s.push('.');
        if decimals > 0 {
            s.push_str(&format!("{frac:0width$}", width = decimals as usize));
        }
        s.push_str(&"0".repeat(trail));
        if decimals == 0 && trail == 0 {
            s.pop();
        }
    }
    s
}

/// A keyword in random letter case.
fn mixed_case(word: &str, mask: u32) -> std::string::String {
    word.chars().enumerate().map(|(i, c)| if mask >> (i % 32) & 1 == 1 { c.to_ascii_uppercase() } else { c }).collect()
}

fn ws() -> impl Strategy<Value = std::string::String> {
    prop::collection::vec(prop_oneof![Just(' '), Just('\t')], 1..3).prop_map(|v| v.into_iter().collect())
}

fn range_of(f: Field) -> (i32, i32) {
    f.range().expect("a numeric field")
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 2000, ..ProptestConfig::default() })]

    /// Arbitrary bytes: a command or a typed error, and an accepted line
    /// echoes a canonical form that parses to the same command.
    #[test]
    fn any_bytes_parse_to_a_command_or_an_error(bytes in prop::collection::vec(any::<u8>(), 0..100)) {
        match parse(&bytes) {
            Ok(cmd) => {
                prop_assert!(bytes.len() <= MAX_LINE);
                let text = canonical(&cmd);
                prop_assert_eq!(parse(text.as_bytes()), Ok(cmd), "{}", text);
                let mut s: String<MAX_RESPONSE> = String::new();
                prop_assert!(format_response(&Response::Ok(&cmd), &mut s).is_ok());
            }
            Err(e) => {
                if bytes.len() > MAX_LINE {
                    prop_assert_eq!(e, ParseError::TooLong);
                }
                let mut s: String<MAX_RESPONSE> = String::new();
                prop_assert!(format_response(&Response::Err(e), &mut s).is_ok(), "{:?}", e);
            }
        }
    }

    /// Lines made of the grammar's words and number-like tokens (far more
    /// of them reach the argument parsers than random bytes do).
    #[test]
    fn word_salad_parses_to_a_command_or_an_error(
        words in prop::collection::vec(
            prop_oneof![
                prop::sample::select(vec![
                    "fwd", "back", "cw", "ccw", "stop", "servo", "trim", "pose", "reset", "locate", "cal", "rate",
                    "status", "help", "?", "l", "r", "left", "right", "s", "-", "+", ".", "-.", "1.", "0x10",
                ]).prop_map(str::to_string),
                "[-+]?[0-9]{0,11}(\\.[0-9]{0,6})?s?",
            ],
            0..7,
        ),
    ) {
        let line = words.join(" ");
        if let Ok(cmd) = parse(line.as_bytes()) {
            let text = canonical(&cmd);
            prop_assert_eq!(parse(text.as_bytes()), Ok(cmd), "{} -> {}", line, text);
        }
    }

    #[test]
    fn speeds_in_range_parse_exactly(
        mm_s in 1..=serial::MAX_SPEED_MM_S as i64, back: bool, dur in prop::option::of(1..=serial::MAX_DURATION_MS as i64),
        plus: bool, lead in 0usize..3, trail in 0usize..3, case in any::<u32>(), sep in ws(), s_suffix: bool,
    ) {
        let kw = if back { "back" } else { "fwd" };
        let mut line = format!("{}{sep}{}", mixed_case(kw, case), spell(mm_s, 3, plus, lead, trail));
        if let Some(d) = dur {
            line += &format!("{sep}{}{}", spell(d, 3, false, lead, trail), if s_suffix { "s" } else { "" });
        }
        let cmd = parse(line.as_bytes());
        let Ok(Command::Drive { motion: Motion::Straight(v), duration_ms }) = cmd else {
            return Err(TestCaseError::fail(format!("{line:?} -> {cmd:?}")));
        };
        prop_assert_eq!(v.to_mm_s(), if back { -mm_s as i32 } else { mm_s as i32 }, "{}", line);
        prop_assert_eq!(duration_ms, dur.map(|d| d as u32));
        prop_assert_eq!(parse(canonical(&cmd.unwrap()).as_bytes()), cmd);
    }

    #[test]
    fn turn_rates_in_range_parse_exactly(mrad in 1..=serial::MAX_TURN_MRAD_S as i64, ccw: bool, case in any::<u32>()) {
        let line = format!("{} {}", mixed_case(if ccw { "ccw" } else { "cw" }, case), spell(mrad, 3, false, 0, 1));
        let cmd = parse(line.as_bytes());
        let Ok(Command::Drive { motion: Motion::Turn(w), duration_ms: None }) = cmd else {
            return Err(TestCaseError::fail(format!("{line:?} -> {cmd:?}")));
        };
        prop_assert_eq!(w.to_mrad_s(), if ccw { -mrad as i32 } else { mrad as i32 });
        prop_assert_eq!(parse(canonical(&cmd.unwrap()).as_bytes()), cmd);
    }

    /// Servo commands and trims are kept in 1/256 step: 1/100 steps round
    /// trip through them exactly.
    #[test]
    fn servo_and_trim_values_parse_exactly(
        l in 0..=18_000i64, r in 0..=18_000i64, trim in -(serial::MAX_TRIM_CENTI as i64)..=serial::MAX_TRIM_CENTI as i64,
        right: bool,
    ) {
        let cmd = parse(format!("servo {} {}", spell(l, 2, false, 0, 0), spell(r, 2, false, 0, 0)).as_bytes());
        let Ok(Command::Servo { left, right: rc, duration_ms: None }) = cmd else {
            return Err(TestCaseError::fail(format!("{cmd:?}")));
        };
        prop_assert_eq!((left.to_centi(), rc.to_centi()), (l as u32, r as u32));
        prop_assert_eq!(parse(canonical(&cmd.unwrap()).as_bytes()), cmd);

        let side = if right { "r" } else { "left" };
        let cmd = parse(format!("trim {side} {}", spell(trim, 2, false, 0, 0)).as_bytes());
        let Ok(Command::Trim { side: s, trim: t }) = cmd else {
            return Err(TestCaseError::fail(format!("{cmd:?}")));
        };
        prop_assert_eq!(s, if right { Side::Right } else { Side::Left });
        let back = ServoCmd::NEUTRAL.trimmed(t).to_centi() as i64 - 9000;
        prop_assert_eq!(back, trim);
        prop_assert_eq!(parse(canonical(&cmd.unwrap()).as_bytes()), cmd);
    }

    #[test]
    fn poses_parse_exactly(
        x in -(serial::MAX_POSE_MM as i64)..=serial::MAX_POSE_MM as i64,
        y in -(serial::MAX_POSE_MM as i64)..=serial::MAX_POSE_MM as i64,
        h in -360_000i64..=360_000,
    ) {
        let line = format!("pose {x} {y} {}", spell(h, 3, false, 0, 0));
        let cmd = parse(line.as_bytes());
        let Ok(Command::SetPose { x_mm, y_mm, heading }) = cmd else {
            return Err(TestCaseError::fail(format!("{line:?} -> {cmd:?}")));
        };
        prop_assert_eq!((i64::from(x_mm), i64::from(y_mm)), (x, y));
        prop_assert_eq!(i64::from(heading.to_millidegrees()), h.rem_euclid(360_000));
        prop_assert_eq!(parse(canonical(&cmd.unwrap()).as_bytes()), cmd);
    }

    /// A number just outside (or far outside) a field's range is refused
    /// as out of range, never wrapped or clamped.
    #[test]
    fn out_of_range_numbers_are_refused(
        which in 0usize..6, above: bool, beyond in 1i64..1_000_000_000,
    ) {
        let (field, template, decimals) = [
            (Field::Speed, "fwd {}", 3),
            (Field::TurnRate, "cw {}", 3),
            (Field::Duration, "fwd 0.1 {}", 3),
            (Field::LeftCommand, "servo {} 90", 2),
            (Field::X, "pose {} 0 0", 0),
            (Field::Rate, "rate {}", 0),
        ][which];
        let (lo, hi) = range_of(field);
        let v = if above { i64::from(hi) + beyond } else { i64::from(lo) - beyond };
        let line = template.replace("{}", &spell(v, decimals, false, 0, 0));
        // too large even for the parser's integer: out of range as well
        prop_assert_eq!(parse(line.as_bytes()), Err(ParseError::OutOfRange(field)), "{}", line);
    }

    /// Any byte stream: lines come out at each `\n`, without `\r`, never
    /// longer than MAX_LINE; an over-long line is reported once as TooLong
    /// and the next line starts clean.
    #[test]
    fn line_buffer_splits_any_stream(
        chunks in prop::collection::vec(
            prop_oneof![
                prop::collection::vec(any::<u8>(), 0..20),
                prop::collection::vec(b'a'..=b'z', 60..140),
                Just(b"\r\n".to_vec()),
                Just(b"\n".to_vec()),
            ],
            0..20,
        ),
    ) {
        let stream: Vec<u8> = chunks.concat();
        let mut lb = LineBuffer::new();
        let mut got = Vec::new();
        for &b in &stream {
            if let Some(r) = lb.push(b) {
                got.push(r.map(|l| l.as_bytes().to_vec()));
            }
            prop_assert!(lb.len() <= MAX_LINE);
        }
        // the reference: split at '\n', drop '\r', too long -> error
        let mut want = Vec::new();
        let mut pieces: Vec<&[u8]> = stream.split(|&b| b == b'\n').collect();
        pieces.pop(); // the unterminated rest
        for p in pieces {
            let line: Vec<u8> = p.iter().copied().filter(|&b| b != b'\r').collect();
            want.push(if line.len() > MAX_LINE { Err(ParseError::TooLong) } else { Ok(line) });
        }
        prop_assert_eq!(got, want);
    }

    /// Any row of numbers reads back from its CSV exactly.
    #[test]
    fn telemetry_rows_round_trip(row in any_row()) {
        let mut s: String<1024> = String::new();
        format_row(&row, &mut s).unwrap();
        prop_assert_eq!(parse_telemetry_row(&s), Ok(row), "{}", s);
    }

    /// Whatever the loop reports (any pose, readings, commands and counters),
    /// the row fits MAX_ROW and reads back as the values it was made from.
    #[test]
    fn any_telemetry_fits_max_row(t in any_telemetry()) {
        let mut s: String<MAX_ROW> = String::new();
        prop_assert!(format_telemetry(&t, &mut s).is_ok(), "did not fit: {:?}", t);
        let row = parse_telemetry_row(&s).unwrap();
        prop_assert_eq!(row, TelemetryRow::from(&t));
    }
}

fn motion_kind() -> impl Strategy<Value = MotionKind> {
    prop::sample::select(vec![
        MotionKind::Stop,
        MotionKind::Forward,
        MotionKind::Backward,
        MotionKind::Cw,
        MotionKind::Ccw,
    ])
}

fn faults() -> impl Strategy<Value = FaultCounters> {
    prop::array::uniform6(any::<u32>()).prop_map(|f| FaultCounters {
        bus: f[0],
        timeout: f[1],
        missing: f[2],
        bad_sample: f[3],
        rejected_outliers: f[4],
        overruns: f[5],
    })
}

fn any_row() -> impl Strategy<Value = TelemetryRow> {
    (
        (any::<u32>(), any::<i32>(), any::<i32>(), any::<u32>(), motion_kind(), any::<i32>(), any::<i32>()),
        (
            any::<u32>(),
            any::<u32>(),
            any::<Option<u16>>(),
            any::<Option<i32>>(),
            any::<Option<u16>>(),
            any::<Option<i32>>(),
        ),
        (any::<Option<[i16; 3]>>(), any::<Option<[i32; 3]>>(), any::<Option<u32>>(), faults(), tracking()),
    )
        .prop_map(|((t_ms, x, y, h, motion, v, w), (lc, rc, fr, fd, rr, rd), (mr, mf, cd, faults, tracking))| {
            TelemetryRow {
                t_ms,
                x_dmm: x,
                y_dmm: y,
                heading_mdeg: h,
                motion,
                v_mm_s: v,
                w_mrad_s: w,
                left_cmd_centi: lc,
                right_cmd_centi: rc,
                front_raw_mm: fr,
                front_dmm: fd,
                right_raw_mm: rr,
                right_dmm: rd,
                mag_raw: mr,
                mag_field: mf,
                compass_mdeg: cd,
                faults,
                tracking,
            }
        })
}

fn tracking() -> impl Strategy<Value = Tracking> {
    prop_oneof![Just(Tracking::Located), Just(Tracking::Ambiguous), Just(Tracking::Unknown)]
}

fn lidar_sample() -> impl Strategy<Value = Option<LidarSample>> {
    prop::option::of(
        (any::<u16>(), any::<Option<i32>>()).prop_map(|(raw_mm, d)| LidarSample {
            raw_mm,
            range: d.map_or(Range::NoTarget, |d| Range::Target(Length(d))),
        }),
    )
}

fn compass_sample() -> impl Strategy<Value = Option<CompassSample>> {
    // the corrected field is clamped to +-2^24 by the compass model
    let field = -(1i32 << 24)..=(1 << 24);
    prop::option::of((any::<[i16; 3]>(), [field.clone(), field.clone(), field], any::<u32>()).prop_map(|(r, f, h)| {
        CompassSample {
            raw: MagCounts { x: r[0], y: r[1], z: r[2] },
            field: MagField { x: f[0], y: f[1], z: f[2] },
            heading: Angle(h),
        }
    }))
}

fn motion() -> impl Strategy<Value = Motion> {
    prop_oneof![
        Just(Motion::Stop),
        any::<i32>().prop_map(|b| Motion::Straight(paperbot::math::Speed::from_bits(b))),
        any::<i32>().prop_map(|b| Motion::Turn(paperbot::math::TurnRate::from_bits(b))),
    ]
}

fn any_telemetry() -> impl Strategy<Value = Telemetry> {
    (
        (any::<u32>(), any::<i64>(), any::<i64>(), any::<u32>()),
        (lidar_sample(), lidar_sample(), compass_sample()),
        (motion(), any::<u32>(), any::<u32>(), faults(), tracking()),
    )
        .prop_map(|((t_ms, x, y, th), (front, right, compass), (motion, l, r, faults, tracking))| Telemetry {
            t_ms,
            pose: Pose::new(Coord(x), Coord(y), Angle(th)),
            front,
            right,
            compass,
            motion,
            left_cmd: ServoCmd::from_q8(l),
            right_cmd: ServoCmd::from_q8(r),
            faults,
            tracking,
        })
}
