//! Telemetry rows, status lines and the integer-only formatting: golden
//! lines, the widest row, and the host-side row parser and its round trip.

use crate::common;
use common::rng::Rng;
use heapless::String;
use paperbot::control::protocol::number::{
    div_rem_1000, div_rem_10k, parse_fixed, push_fixed, push_fixed_parts, push_i32, push_str, push_text, push_u32,
    NumError, TextOut,
};
use paperbot::control::protocol::{
    classify_line, format_row, format_status, format_telemetry, parse_telemetry_row, telemetry_header, FaultCounters,
    LineKind, RowError, Status, Telemetry, TelemetryRow, COLUMNS, HEADER, MAX_OUT_LINE, MAX_ROW, MAX_STATUS,
};
use paperbot::control::protocol::{OutLine, Overflow};
use paperbot::driver::{CompassSample, LidarSample};
use paperbot::math::{Angle, Coord, Length, Speed, TurnRate};
use paperbot::model::compass::{MagCounts, MagField};
use paperbot::model::estimator::Tracking;
use paperbot::model::{Motion, MotionKind, Pose, Range, ServoCmd, Trim};

fn row_text(t: &Telemetry) -> std::string::String {
    let mut out: String<MAX_ROW> = String::new();
    format_telemetry(t, &mut out).expect("fits MAX_ROW");
    out.as_str().to_owned()
}

fn quiet(t_ms: u32) -> Telemetry {
    Telemetry {
        t_ms,
        pose: Pose::default(),
        front: None,
        right: None,
        compass: None,
        motion: Motion::Stop,
        left_cmd: ServoCmd::NEUTRAL,
        right_cmd: ServoCmd::NEUTRAL,
        faults: FaultCounters::default(),
        tracking: Tracking::Located,
    }
}

#[test]
fn header() {
    assert_eq!(telemetry_header(), HEADER);
    let names: Vec<&str> = HEADER.split(',').collect();
    assert_eq!(names.len(), COLUMNS);
    assert_eq!(
        &names[..17],
        &[
            "t_ms",
            "x_mm",
            "y_mm",
            "heading_deg",
            "motion",
            "v_mps",
            "w_radps",
            "left_cmd",
            "right_cmd",
            "front_raw_mm",
            "front_mm",
            "right_raw_mm",
            "right_mm",
            "mag_x",
            "mag_y",
            "mag_z",
            "field_x"
        ]
    );
    assert!(!HEADER.starts_with('#') && HEADER.is_ascii() && !HEADER.contains(' '));
    assert_eq!(classify_line(HEADER), LineKind::Header);
    assert_eq!(classify_line("# ok stop\r"), LineKind::Comment);
    assert_eq!(classify_line("0,0.0"), LineKind::Row);
}

#[test]
fn golden_rows() {
    assert_eq!(row_text(&quiet(0)), "0,0.0,0.0,0.000,stop,0.000,0.000,90.00,90.00,,,,,,,,,,,,0,0,0,0,0,0,located");

    let t = Telemetry {
        t_ms: 1200,
        pose: Pose::new(Coord::from_mm_f64(153.24), Coord::from_mm_f64(-4.06), Angle::from_millidegrees(11_933)),
        front: Some(LidarSample { raw_mm: 412, range: Range::Target(Length::from_mm_f64(349.52)) }),
        right: Some(LidarSample { raw_mm: 8190, range: Range::NoTarget }),
        compass: Some(CompassSample {
            raw: MagCounts { x: -12, y: 40, z: -3 },
            field: MagField { x: -66, y: 4, z: -3 },
            heading: Angle::from_millidegrees(353_117),
        }),
        motion: Motion::Straight(Speed::from_mm_s(130)),
        left_cmd: ServoCmd::from_int(107),
        right_cmd: ServoCmd::from_int(61),
        faults: FaultCounters { bus: 1, timeout: 2, missing: 3, bad_sample: 4, rejected_outliers: 5, overruns: 6 },
        tracking: Tracking::Ambiguous,
    };
    assert_eq!(
        row_text(&t),
        "1200,153.2,-4.1,11.933,fwd,0.130,0.000,107.00,61.00,412,349.5,8190,,-12,40,-3,-66,4,-3,353.117,1,2,3,4,5,6,ambiguous"
    );

    let t = Telemetry {
        t_ms: 4_294_967_295,
        pose: Pose::new(Coord::from_mm_f64(-0.04), Coord::from_mm_f64(0.05), Angle::from_millidegrees(-90_000)),
        front: Some(LidarSample { raw_mm: 10, range: Range::TooClose }),
        right: Some(LidarSample { raw_mm: 120, range: Range::Target(Length::from_mm_f64(-0.35)) }),
        compass: None,
        motion: Motion::Turn(TurnRate::from_mrad_s(2500).neg()),
        left_cmd: ServoCmd::from_q8(15_744),
        right_cmd: ServoCmd::MAX,
        faults: FaultCounters { bus: u32::MAX, ..FaultCounters::default() },
        tracking: Tracking::Unknown,
    };
    assert_eq!(
        row_text(&t),
        "4294967295,0.0,0.1,270.000,ccw,0.000,-2.500,61.50,180.00,10,,120,-0.4,,,,,,,,4294967295,0,0,0,0,0,unknown"
    );
    let back = Telemetry { motion: Motion::Straight(Speed::from_mm_s(100).neg()), ..quiet(5) };
    assert!(row_text(&back).starts_with("5,0.0,0.0,0.000,back,-0.100,0.000,"));
}

/// A row with every column at its widest is exactly MAX_ROW bytes.
#[test]
fn widest_row_is_max_row() {
    let row = TelemetryRow {
        t_ms: u32::MAX,
        x_dmm: -327_680,
        y_dmm: -327_680,
        heading_mdeg: 359_999,
        motion: MotionKind::Backward,
        v_mm_s: -1000,
        w_mrad_s: -20_000,
        left_cmd_centi: 18_000,
        right_cmd_centi: 18_000,
        front_raw_mm: Some(u16::MAX),
        front_dmm: Some(-327_680),
        right_raw_mm: Some(u16::MAX),
        right_dmm: Some(-327_680),
        mag_raw: Some([i16::MIN; 3]),
        mag_field: Some([-(1 << 24); 3]),
        compass_mdeg: Some(359_999),
        faults: max_faults(),
        tracking: Tracking::Ambiguous,
    };
    let mut out: String<MAX_ROW> = String::new();
    format_row(&row, &mut out).expect("fits");
    assert_eq!(out.len(), MAX_ROW);
    assert_eq!(parse_telemetry_row(&out), Ok(row));
    // one byte less does not fit, and says so
    let mut short: String<{ MAX_ROW - 1 }> = String::new();
    assert!(format_row(&row, &mut short).is_err());

    // the extremes a real Telemetry can reach fit as well
    let t = Telemetry {
        pose: Pose::new(Coord(i64::MIN), Coord(i64::MAX), Angle(u32::MAX)),
        motion: Motion::Turn(TurnRate::from_mrad_s(-20_000)),
        front: Some(LidarSample { raw_mm: u16::MAX, range: Range::Target(Length(i32::MIN)) }),
        compass: Some(CompassSample {
            raw: MagCounts { x: i16::MIN, y: i16::MIN, z: i16::MIN },
            field: MagField { x: -(1 << 24), y: -(1 << 24), z: -(1 << 24) },
            heading: Angle(u32::MAX - (1 << 20)),
        }),
        ..quiet(u32::MAX)
    };
    let text = row_text(&t);
    assert!(text.len() <= MAX_ROW);
    assert_eq!(parse_telemetry_row(&text), Ok(TelemetryRow::from(&t)));
}

fn random_sample(rng: &mut Rng, model: &paperbot::model::LidarModel) -> Option<LidarSample> {
    match rng.range_u32(0, 3) {
        0 => None,
        1 => Some(LidarSample { raw_mm: 8190 + rng.range_u32(0, 1) as u16, range: Range::NoTarget }),
        _ => {
            let raw_mm = rng.range_u32(0, 1300) as u16;
            Some(LidarSample { raw_mm, range: model.range(raw_mm) })
        }
    }
}

fn random_telemetry(rng: &mut Rng) -> Telemetry {
    let coord = |rng: &mut Rng| Coord((rng.next_u64() as i64) >> rng.range_u32(16, 40));
    let motion = match rng.range_u32(0, 2) {
        0 => Motion::Stop,
        1 => Motion::Straight(Speed::from_bits(rng.next_u32() as i32 >> rng.range_u32(8, 31))),
        _ => Motion::Turn(TurnRate::from_bits(rng.next_u32() as i32 >> rng.range_u32(4, 31))),
    };
    let i16r = |rng: &mut Rng| rng.next_u32() as i16;
    let i32r = |rng: &mut Rng| (rng.next_u32() as i32) >> 7; // |.| < 2^24
    let count = |rng: &mut Rng| if rng.next_u32() % 4 == 0 { rng.next_u32() } else { rng.range_u32(0, 9) };
    Telemetry {
        t_ms: rng.next_u32(),
        pose: Pose::new(coord(rng), coord(rng), Angle(rng.next_u32())),
        front: random_sample(rng, &paperbot::config::lidar::FRONT),
        right: random_sample(rng, &paperbot::config::lidar::RIGHT),
        compass: (rng.next_u32() % 3 != 0).then(|| CompassSample {
            raw: MagCounts { x: i16r(rng), y: i16r(rng), z: i16r(rng) },
            field: MagField { x: i32r(rng), y: i32r(rng), z: i32r(rng) },
            heading: Angle(rng.next_u32()),
        }),
        motion,
        left_cmd: ServoCmd::from_q8(rng.range_u32(0, 180 << 8)),
        right_cmd: ServoCmd::from_q8(rng.range_u32(0, 180 << 8)),
        faults: FaultCounters {
            bus: count(rng),
            timeout: count(rng),
            missing: count(rng),
            bad_sample: count(rng),
            rejected_outliers: count(rng),
            overruns: count(rng),
        },
        tracking: [Tracking::Located, Tracking::Ambiguous, Tracking::Unknown][rng.range_u32(0, 2) as usize],
    }
}

/// format -> parse gives the row's values, and those are the telemetry's
/// values at the written resolution (checked against f64).
#[test]
fn random_rows_round_trip() {
    let mut rng = Rng::new(2024);
    for _ in 0..50_000 {
        let t = random_telemetry(&mut rng);
        let text = row_text(&t);
        assert!(text.is_ascii() && !text.contains(['\r', '\n', '#', ' ']), "{text}");
        let row = parse_telemetry_row(&text).unwrap_or_else(|e| panic!("{text}: {e:?}"));
        assert_eq!(row, TelemetryRow::from(&t), "{text}");
        // and the numbers mean what they should
        let x_mm = t.pose.x.to_mm_f64().clamp(-32768.0, 32767.99);
        assert!((f64::from(row.x_dmm) / 10.0 - x_mm).abs() <= 0.05 + 1e-4, "{text}");
        let deg = t.pose.theta.to_radians_f64().to_degrees();
        let err = (f64::from(row.heading_mdeg) / 1000.0 - deg).rem_euclid(360.0);
        assert!(err.min(360.0 - err) <= 0.0005 + 1e-6, "{text}");
        match t.motion {
            Motion::Straight(v) => assert!((f64::from(row.v_mm_s) - v.to_mps_f64() * 1000.0).abs() <= 0.5 + 1e-6),
            Motion::Turn(w) => assert!((f64::from(row.w_mrad_s) - w.to_rad_s_f64() * 1000.0).abs() <= 0.5 + 1e-6),
            Motion::Stop => assert_eq!((row.v_mm_s, row.w_mrad_s), (0, 0)),
        }
        assert_eq!(row.front_dmm.is_some(), matches!(t.front, Some(LidarSample { range: Range::Target(_), .. })));
        assert_eq!(row.mag_raw.is_some(), t.compass.is_some());
    }
}

/// Rows made of arbitrary numbers in each column's type round-trip too.
#[test]
fn arbitrary_rows_round_trip() {
    let mut rng = Rng::new(5);
    let opt = |rng: &mut Rng| rng.next_u32() % 3 != 0;
    for _ in 0..50_000 {
        let row = TelemetryRow {
            t_ms: rng.next_u32(),
            x_dmm: rng.next_u32() as i32,
            y_dmm: rng.next_u32() as i32,
            heading_mdeg: rng.next_u32(),
            motion: [MotionKind::Stop, MotionKind::Forward, MotionKind::Backward, MotionKind::Cw, MotionKind::Ccw]
                [rng.range_u32(0, 4) as usize],
            v_mm_s: rng.next_u32() as i32,
            w_mrad_s: rng.next_u32() as i32,
            left_cmd_centi: rng.next_u32(),
            right_cmd_centi: rng.next_u32(),
            front_raw_mm: opt(&mut rng).then(|| rng.next_u32() as u16),
            front_dmm: opt(&mut rng).then(|| rng.next_u32() as i32),
            right_raw_mm: opt(&mut rng).then(|| rng.next_u32() as u16),
            right_dmm: opt(&mut rng).then(|| rng.next_u32() as i32),
            mag_raw: opt(&mut rng).then(|| [rng.next_u32() as i16, rng.next_u32() as i16, rng.next_u32() as i16]),
            mag_field: opt(&mut rng).then(|| [rng.next_u32() as i32, rng.next_u32() as i32, i32::MIN]),
            compass_mdeg: opt(&mut rng).then(|| rng.next_u32()),
            faults: FaultCounters { bus: rng.next_u32(), overruns: u32::MAX, ..FaultCounters::default() },
            tracking: [Tracking::Located, Tracking::Ambiguous, Tracking::Unknown][rng.range_u32(0, 2) as usize],
        };
        let mut out: String<400> = String::new();
        format_row(&row, &mut out).expect("fits");
        assert_eq!(parse_telemetry_row(&out), Ok(row), "{out}");
    }
}

#[test]
fn bad_rows_are_refused() {
    let good =
        "1200,153.2,-4.1,11.933,fwd,0.130,0.000,107.00,61.00,412,349.5,8190,,-12,40,-3,-66,4,-3,353.117,1,2,3,4,5,6,located";
    assert!(parse_telemetry_row(good).is_ok());
    assert!(parse_telemetry_row(&format!("{good}\r\n")).is_ok());
    let col = |name: &'static str| Err(RowError::Field { column: name });
    let cases: &[(std::string::String, Result<TelemetryRow, RowError>)] = &[
        (HEADER.to_string(), col("t_ms")),
        ("# ok stop".to_string(), Err(RowError::Columns { found: 1 })),
        (format!("{good},7"), Err(RowError::Columns { found: 28 })),
        (good.replacen("1200", "-1200", 1), col("t_ms")),
        (good.replacen("1200", "4294967296", 1), col("t_ms")),
        (good.replacen("153.2", "153.25", 1), col("x_mm")),
        (good.replacen("fwd", "jump", 1), col("motion")),
        (good.replacen("107.00", "", 1), col("left_cmd")),
        (good.replacen(",412,", ",70000,", 1), col("front_raw_mm")),
        (good.replacen(",-12,", ",,", 1), col("mag_x")),
        (good.replacen(",40,", ",40000,", 1), col("mag_y")),
        (good.replacen("353.117", "-353.117", 1), col("compass_deg")),
        (good.replacen(",6,located", ",x,located", 1), col("f_overruns")),
        (good.replacen("located", "lost", 1), col("pose")),
    ];
    for (line, want) in cases {
        assert_eq!(&parse_telemetry_row(line), want, "{line}");
    }
}

#[test]
fn status_line() {
    let s = Status {
        t_ms: 1200,
        mode: "drive",
        motion: Motion::Straight(Speed::from_mm_s(130)),
        remaining_ms: Some(800),
        pose: Pose::from_mm(12, -3, Angle::QUARTER_TURN),
        tracking: Tracking::Located,
        left_cmd: ServoCmd::from_int(107),
        right_cmd: ServoCmd::from_int(61),
        left_trim: Trim(0),
        right_trim: Trim(-384),
        rate_hz: 10,
        front_ok: true,
        right_ok: true,
        compass_ok: false,
        faults: FaultCounters { bus: 3, ..FaultCounters::default() },
    };
    let mut out: String<MAX_STATUS> = String::new();
    format_status(&s, &mut out).expect("fits");
    assert_eq!(
        out.as_str(),
        "# status t_ms=1200 mode=drive motion=fwd v_mps=0.130 w_radps=0.000 left_ms=800 x_mm=12 y_mm=-3 \
         heading_deg=90.000 pose=located left_cmd=107.00 right_cmd=61.00 trim_left=0.00 trim_right=-1.50 rate_hz=10 \
         front=ok right=ok compass=down f_bus=3 f_timeout=0 f_missing=0 f_bad_sample=0 f_outliers=0 f_overruns=0"
    );

    // the widest status fits MAX_STATUS, stays one printable line
    let wide = Status {
        t_ms: u32::MAX,
        mode: "calibrating-with-a-very-long-name\n",
        motion: Motion::Turn(TurnRate::from_mrad_s(-20_000)),
        remaining_ms: Some(u32::MAX),
        pose: Pose::new(Coord(i64::MIN), Coord(i64::MIN), Angle(u32::MAX >> 1)),
        tracking: Tracking::Ambiguous,
        left_cmd: ServoCmd::MAX,
        right_cmd: ServoCmd::MAX,
        left_trim: Trim(i16::MIN),
        right_trim: Trim(i16::MIN),
        rate_hz: u16::MAX,
        front_ok: false,
        right_ok: false,
        compass_ok: false,
        faults: max_faults(),
    };
    let mut out: String<MAX_STATUS> = String::new();
    format_status(&wide, &mut out).expect("fits");
    assert!(out.bytes().all(|b| (0x20..0x7F).contains(&b)), "{out}");
    assert!(out.contains("mode=calibrating-with motion="), "{out}");
    const { assert!(MAX_STATUS <= MAX_OUT_LINE && MAX_ROW <= MAX_OUT_LINE) };
}

/// The integer formatter and parser against Rust's own (std) formatting.
#[test]
fn integer_decimal_formatting() {
    let mut rng = Rng::new(11);
    for i in 0..200_000u32 {
        let v = match i {
            0 => i32::MIN,
            1 => i32::MAX,
            2 => 0,
            3 => -1,
            _ => (rng.next_u32() as i32) >> rng.range_u32(0, 31),
        };
        let decimals = rng.range_u32(0, 9);
        let mut out: String<16> = String::new();
        push_fixed(&mut out, v, decimals).expect("fits");
        let p = 10i64.pow(decimals);
        let want = if decimals == 0 {
            format!("{v}")
        } else {
            let a = i64::from(v).abs();
            let sign = if v < 0 { "-" } else { "" };
            format!("{sign}{}.{:0w$}", a / p, a % p, w = decimals as usize)
        };
        assert_eq!(out.as_str(), want);
        assert_eq!(parse_fixed(out.as_bytes(), decimals), Ok(v), "{out}");
    }
    let mut out: String<32> = String::new();
    push_fixed_parts(&mut out, false, u32::MAX, 0).unwrap();
    push_fixed(&mut out, i32::MIN, 0).unwrap();
    assert_eq!(out.as_str(), "4294967295-2147483648");
    assert_eq!(parse_fixed(b"2147483648", 0), Err(NumError::Range));
    assert_eq!(parse_fixed(b"-2147483649", 0), Err(NumError::Range));
    assert_eq!(parse_fixed(b"1.5", 0), Err(NumError::Bad));
    assert_eq!(parse_fixed(b"1.50", 1), Ok(15));
    assert_eq!(parse_fixed(b"-.5", 1), Ok(-5));
    let mut tiny: String<3> = String::new();
    assert!(push_fixed(&mut tiny, -1234, 1).is_err());
}

/// The plain writers into both buffer kinds: integers at both ends of
/// their range, text with anything but printable ASCII as `?`, and an
/// overflow that keeps what fitted.
#[test]
fn plain_writers() {
    fn write(out: &mut dyn TextOut) -> Result<(), Overflow> {
        push_u32(out, u32::MAX)?;
        push_str(out, " ")?;
        push_i32(out, i32::MIN)?;
        push_str(out, " ")?;
        push_i32(out, 0)?;
        push_str(out, " ")?;
        push_text(out, "tab\there\u{e9}\n")
    }
    let want = "4294967295 -2147483648 0 tab?here???";
    let mut out: String<64> = String::new();
    write(&mut out).expect("fits");
    assert_eq!(out.as_str(), want);
    let mut line: OutLine<64> = OutLine::new();
    write(&mut line).expect("fits");
    assert_eq!(&*line, want);
    // too long: an error, with what fitted kept
    let mut tiny: String<8> = String::new();
    assert_eq!(write(&mut tiny), Err(Overflow));
    assert_eq!(tiny.as_str(), "42949672");
}

/// What `push_fixed_parts` must write, by std formatting.
fn std_fixed(negative: bool, magnitude: u32, decimals: u32) -> std::string::String {
    let p = 10u64.pow(decimals);
    let m = u64::from(magnitude);
    let sign = if negative && magnitude != 0 { "-" } else { "" };
    if decimals == 0 {
        format!("{sign}{m}")
    } else {
        format!("{sign}{}.{:0w$}", m / p, m % p, w = decimals as usize)
    }
}

/// The division-free digit routine against std formatting, for every
/// number of decimals: every value below 2^18, every value within 3 of a
/// power of ten, of a multiple of 10^4 up to 10^8 and of every multiple of
/// 10^8, 10^4 multiples across the whole range, and random values.
#[test]
fn digits_without_division_match_std() {
    let mut values: std::vec::Vec<u32> = (0..1 << 18).collect();
    let mut near = |c: u64| {
        for d in 0..=6u64 {
            if let Some(v) = (c + d).checked_sub(3).and_then(|v| u32::try_from(v).ok()) {
                values.push(v);
            }
        }
    };
    for k in 0..=9 {
        near(10u64.pow(k));
    }
    for k in (0..=10_000u64).step_by(7) {
        near(k * 10_000);
    }
    for k in 0..=42u64 {
        near(k * 100_000_000);
    }
    near(u64::from(u32::MAX));
    values.extend((0..=u32::MAX / 10_000).filter_map(|k| (k * 10_000).checked_add(k % 10_000)));
    let mut rng = Rng::new(23);
    values.extend((0..100_000).map(|_| rng.next_u32() >> rng.range_u32(0, 31)));
    let mut out: String<16> = String::new();
    for (i, &v) in values.iter().enumerate() {
        // every value with a decimals count that changes along the list, the
        // small ones with all of them
        let all = v < 1 << 12;
        for decimals in 0..=9u32 {
            if !all && decimals as usize != i % 10 {
                continue;
            }
            for negative in [false, true] {
                out.clear();
                push_fixed_parts(&mut out, negative, v, decimals).expect("fits");
                assert_eq!(out.as_str(), std_fixed(negative, v, decimals), "{v} {decimals}");
            }
        }
    }
    // more than 9 decimals is 9
    out.clear();
    push_fixed_parts(&mut out, false, 1, 12).expect("fits");
    assert_eq!(out.as_str(), "0.000000001");
}

/// The reciprocal divisions are exact for every u32: the multiply-high
/// overshoots `v / d` by less than `1 / d`, so the only values it could get
/// wrong are those just below a multiple of `d`; all of them are checked,
/// with the multiples themselves.
#[test]
fn reciprocal_divisions_are_exact() {
    for k in 0..=u32::MAX / 10_000 {
        for v in [k * 10_000, k * 10_000 + 1, (k * 10_000).wrapping_sub(1)] {
            assert_eq!(div_rem_10k(v), (v / 10_000, v % 10_000), "{v}");
        }
    }
    for k in 0..=u32::MAX / 1000 {
        for v in [k * 1000, (k * 1000).wrapping_sub(1)] {
            assert_eq!(div_rem_1000(v), (v / 1000, v % 1000), "{v}");
        }
    }
    let mut rng = Rng::new(29);
    for v in (0..1_000_000).map(|_| rng.next_u32()).chain([u32::MAX, u32::MAX - 1]) {
        assert_eq!(div_rem_10k(v), (v / 10_000, v % 10_000), "{v}");
        assert_eq!(div_rem_1000(v), (v / 1000, v % 1000), "{v}");
    }
}

/// OutLine (the control loop's line buffer) writes what a heapless String
/// does for ASCII, stores anything else as `?`, and on overflow keeps what
/// fitted and says so.
#[test]
fn out_line_buffer() {
    let mut line: OutLine<12> = OutLine::new();
    assert!(line.is_empty());
    line.put_str("ab").unwrap();
    line.put_byte(b'c').unwrap();
    line.put_ascii(b"12").unwrap();
    push_fixed(&mut line, -5, 2).unwrap();
    assert_eq!(line.as_str(), "abc12-0.05");
    assert_eq!(line.len(), 10);
    line.clear();
    line.put_str("h\u{e9}!").unwrap(); // two UTF-8 bytes, two `?`
    line.put_byte(0xFF).unwrap();
    line.put_ascii(&[b'x', 0x80]).unwrap();
    assert_eq!(line.as_str(), "h??!?x?");
    assert_eq!(line.put_ascii(b"123456"), Err(Overflow));
    assert_eq!(line.as_str(), "h??!?x?12345");
    assert_eq!(line.put_byte(b'z'), Err(Overflow));
    assert_eq!(line.put_str(""), Ok(()));
    assert_eq!(line.as_bytes().len(), 12);

    // a telemetry row: the same text as in a String, and no room to spare
    let row = TelemetryRow::from(&Telemetry { motion: Motion::Straight(Speed::from_mm_s(130)), ..quiet(1200) });
    let mut a: OutLine<MAX_ROW> = OutLine::new();
    let mut b: String<MAX_ROW> = String::new();
    format_row(&row, &mut a).unwrap();
    format_row(&row, &mut b).unwrap();
    assert_eq!(a.as_str(), b.as_str());
    let mut tiny: OutLine<20> = OutLine::new();
    assert_eq!(format_row(&row, &mut tiny), Err(Overflow));
    assert_eq!(tiny.as_str(), &b.as_str()[..20]);
}

/// Every fault counter at its largest value (the widest row and status).
fn max_faults() -> FaultCounters {
    FaultCounters {
        bus: u32::MAX,
        timeout: u32::MAX,
        missing: u32::MAX,
        bad_sample: u32::MAX,
        rejected_outliers: u32::MAX,
        overruns: u32::MAX,
    }
}
