//! The command grammar: every command, every error, boundaries, spelling,
//! whitespace, the canonical echo and its round trip, and the messages.

use crate::common;
use common::rng::Rng;
use heapless::String;
use paperbot::config;
use paperbot::control::protocol::{
    format_command, format_response, parse, Command, Field, ParseError, Response, Side, HELP, MAX_LINE, MAX_RESPONSE,
};
use paperbot::math::{Angle, Speed, TurnRate};
use paperbot::model::{Motion, ServoCmd, Trim};

fn fwd(mm_s: i32, duration_ms: Option<u32>) -> Command {
    Command::Drive { motion: Motion::Straight(Speed::from_mm_s(mm_s)), duration_ms }
}
/// Backward is forward negated: the same magnitude both ways.
fn back(mm_s: i32, duration_ms: Option<u32>) -> Command {
    Command::Drive { motion: Motion::Straight(Speed::from_mm_s(mm_s).neg()), duration_ms }
}
/// Positive clockwise; counter-clockwise is clockwise negated.
fn turn(mrad_s: i32, duration_ms: Option<u32>) -> Command {
    let w = TurnRate::from_mrad_s(mrad_s.abs());
    Command::Drive { motion: Motion::Turn(if mrad_s < 0 { w.neg() } else { w }), duration_ms }
}
fn servo(l_q8: u32, r_q8: u32, duration_ms: Option<u32>) -> Command {
    Command::Servo { left: ServoCmd::from_q8(l_q8), right: ServoCmd::from_q8(r_q8), duration_ms }
}
fn pose(x_mm: i32, y_mm: i32, mdeg: i32) -> Command {
    Command::SetPose { x_mm, y_mm, heading: Angle::from_millidegrees(mdeg) }
}

#[test]
fn accepted_lines() {
    use Command::*;
    let table: &[(&str, Command)] = &[
        // drive straight: speed in m/s, 3 decimals, exact
        ("fwd 0.13", fwd(130, None)),
        ("forward 0.13 2.5", fwd(130, Some(2500))),
        ("FWD 0.130 2.5s", fwd(130, Some(2500))),
        ("Fwd 0.13 2.5S", fwd(130, Some(2500))),
        ("  fwd\t0.13   ", fwd(130, None)),
        ("fwd 0.13\r", fwd(130, None)),
        ("fwd .13", fwd(130, None)),
        ("fwd +0.13", fwd(130, None)),
        ("fwd 0.1300000", fwd(130, None)),
        ("fwd 00.13", fwd(130, None)),
        ("fwd 0.001", fwd(1, None)),
        ("fwd 0.3", fwd(300, None)),
        ("fwd 0.13 60", fwd(130, Some(60_000))),
        ("fwd 0.13 0.001", fwd(130, Some(1))),
        ("fwd 0.13 .5", fwd(130, Some(500))),
        ("back 0.1", back(100, None)),
        ("backward 0.149 1", back(149, Some(1000))),
        // turns: rad/s, 3 decimals
        ("cw 2.5", turn(2500, None)),
        ("cw 0.001", turn(1, None)),
        ("ccw 6", turn(-6000, None)),
        ("CCW 3.2 0.25s", turn(-3200, Some(250))),
        // stop
        ("stop", Stop),
        ("s", Stop),
        ("STOP", Stop),
        // raw servo commands: 2 decimals, to 1/256 step
        ("servo 90 90", servo(90 << 8, 90 << 8, None)),
        ("servo 107 61.5 0.8", servo(107 << 8, 15_744, Some(800))),
        ("servo 0 180", servo(0, 180 << 8, None)),
        ("servo 0.01 179.99", servo(3, 46_077, None)), // 2.56 -> 3, 46077.44 -> 46077
        ("servo 90.5 89.50 1s", servo(23_168, 22_912, Some(1000))),
        // trim: side word, steps with 2 decimals
        ("trim left 1.5", Trim { side: Side::Left, trim: paperbot::model::Trim(384) }),
        ("trim l -1.25", Trim { side: Side::Left, trim: paperbot::model::Trim(-320) }),
        ("trim R 10", Trim { side: Side::Right, trim: paperbot::model::Trim(2560) }),
        ("trim right -10.00", Trim { side: Side::Right, trim: paperbot::model::Trim(-2560) }),
        ("trim r 0.01", Trim { side: Side::Right, trim: paperbot::model::Trim(3) }),
        ("trim r -0", Trim { side: Side::Right, trim: paperbot::model::Trim(0) }),
        // pose: whole mm, degrees with 3 decimals
        ("pose 100 -50 90", pose(100, -50, 90_000)),
        ("pose 30000 -30000 -360", pose(30_000, -30_000, -360_000)),
        ("pose -30000 30000 360", pose(-30_000, 30_000, 0)),
        ("pose 0 0 359.999", pose(0, 0, 359_999)),
        ("pose 1.0 2.00 0.5", pose(1, 2, 500)),
        ("reset", Command::Locate),
        ("locate", Command::Locate),
        // calibration
        ("cal", Calibrate { samples: config::compass::CALIBRATION_SAMPLES }),
        ("calibrate 250", Calibrate { samples: 250 }),
        ("cal 10000", Calibrate { samples: 10_000 }),
        // telemetry rate
        ("rate 0", Rate { hz: 0 }),
        ("rate 100", Rate { hz: 100 }),
        ("RATE 10", Rate { hz: 10 }),
        ("status", Status),
        ("help", Help),
        ("?", Help),
        ("Help", Help),
    ];
    for (line, want) in table {
        assert_eq!(parse(line.as_bytes()), Ok(*want), "{line:?}");
    }
}

#[test]
fn fixed_point_values_are_exact() {
    // the guidance's examples, checked against the math types directly
    assert_eq!(parse(b"fwd 0.13"), Ok(fwd(130, None)));
    let Ok(Command::Drive { motion: Motion::Straight(v), .. }) = parse(b"fwd 0.13") else { panic!() };
    assert_eq!(v.to_mm_s(), 130);
    let Ok(Command::Drive { motion: Motion::Turn(w), .. }) = parse(b"cw 2.5") else { panic!() };
    assert_eq!(w, TurnRate::from_mrad_s(2500));
    assert!((w.to_rad_s_f64() - 2.5).abs() < 1e-6);
    let Ok(Command::SetPose { heading, .. }) = parse(b"pose 0 0 90") else { panic!() };
    assert_eq!(heading, Angle::QUARTER_TURN);
    let Ok(Command::SetPose { heading, .. }) = parse(b"pose 0 0 -90") else { panic!() };
    assert_eq!(heading, Angle(3 << 30));
    let Ok(Command::Servo { right, .. }) = parse(b"servo 90 61.5") else { panic!() };
    assert_eq!(right.to_f64(), 61.5);
}

#[test]
fn refused_lines() {
    use Field::*;
    use ParseError::*;
    let long = "stop".to_string() + &" ".repeat(MAX_LINE - 3); // 65 bytes
    let table: &[(&[u8], ParseError)] = &[
        (b"", Empty),
        (b"   ", Empty),
        (b"\t\r", Empty),
        (b"jump", UnknownCommand),
        (b"fwd0.13", UnknownCommand),
        (b"forwards 0.1", UnknownCommand),
        (b"0.13 fwd", UnknownCommand),
        (b"#fwd 0.1", UnknownCommand),
        // missing arguments
        (b"fwd", MissingArgument(Speed)),
        (b"back  ", MissingArgument(Speed)),
        (b"cw", MissingArgument(TurnRate)),
        (b"servo", MissingArgument(LeftCommand)),
        (b"servo 90", MissingArgument(RightCommand)),
        (b"trim", MissingArgument(Side)),
        (b"trim left", MissingArgument(Trim)),
        (b"pose", MissingArgument(X)),
        (b"pose 1", MissingArgument(Y)),
        (b"pose 1 2", MissingArgument(Heading)),
        (b"rate", MissingArgument(Rate)),
        // not numbers, or finer than the field's resolution
        (b"fwd abc", BadNumber(Speed)),
        (b"fwd 0.1305", BadNumber(Speed)),
        (b"fwd 0.0001", BadNumber(Speed)),
        (b"fwd 1.", BadNumber(Speed)),
        (b"fwd .", BadNumber(Speed)),
        (b"fwd -", BadNumber(Speed)),
        (b"fwd +", BadNumber(Speed)),
        (b"fwd --1", BadNumber(Speed)),
        (b"fwd 0..1", BadNumber(Speed)),
        (b"fwd 0.1.2", BadNumber(Speed)),
        (b"fwd 0,13", BadNumber(Speed)),
        (b"fwd 1e-1", BadNumber(Speed)),
        (b"fwd 0x1", BadNumber(Speed)),
        (b"fwd 0.1 2ms", BadNumber(Duration)),
        (b"fwd 0.1 s", BadNumber(Duration)),
        (b"fwd 0.1 2ss", BadNumber(Duration)),
        (b"fwd 0.1 1e3", BadNumber(Duration)),
        (b"fwd 0.1 0.0005", BadNumber(Duration)),
        (b"cw fast", BadNumber(TurnRate)),
        (b"servo 90.001 90", BadNumber(LeftCommand)),
        (b"servo 90 ninety", BadNumber(RightCommand)),
        (b"trim l 0.005", BadNumber(Trim)),
        (b"pose 1.5 0 0", BadNumber(X)),
        (b"pose 0 y 0", BadNumber(Y)),
        (b"pose 0 0 0.0001", BadNumber(Heading)),
        (b"rate 1.5", BadNumber(Rate)),
        (b"cal 300.5", BadNumber(Samples)),
        // out of range
        (b"fwd 0", OutOfRange(Speed)),
        (b"fwd 0.000", OutOfRange(Speed)),
        (b"fwd -0.1", OutOfRange(Speed)),
        (b"fwd 0.301", OutOfRange(Speed)),
        (b"fwd 1", OutOfRange(Speed)),
        (b"fwd 99999999999999999999", OutOfRange(Speed)),
        (b"cw 6.001", OutOfRange(TurnRate)),
        (b"ccw -1", OutOfRange(TurnRate)),
        (b"fwd 0.1 0", OutOfRange(Duration)),
        (b"fwd 0.1 60.001", OutOfRange(Duration)),
        (b"fwd 0.1 -1", OutOfRange(Duration)),
        (b"servo 180.01 90", OutOfRange(LeftCommand)),
        (b"servo 90 -0.01", OutOfRange(RightCommand)),
        (b"servo 90 90 0", OutOfRange(Duration)),
        (b"trim l 10.01", OutOfRange(Trim)),
        (b"trim r -10.01", OutOfRange(Trim)),
        (b"pose 30001 0 0", OutOfRange(X)),
        (b"pose 0 -30001 0", OutOfRange(Y)),
        (b"pose 0 0 360.001", OutOfRange(Heading)),
        (b"pose 0 0 -360.001", OutOfRange(Heading)),
        (b"cal 249", OutOfRange(Samples)),
        (b"cal 10001", OutOfRange(Samples)),
        (b"cal -1000", OutOfRange(Samples)),
        (b"rate 101", OutOfRange(Rate)),
        (b"rate -1", OutOfRange(Rate)),
        (b"rate 4294967296", OutOfRange(Rate)),
        // word choices
        (b"trim up 1", BadChoice(Side)),
        (b"trim 1 left", BadChoice(Side)),
        // extra words
        (b"stop now", TrailingInput),
        (b"s 1", TrailingInput),
        (b"fwd 0.1 2 3", TrailingInput),
        (b"servo 90 90 1 1", TrailingInput),
        (b"status 1", TrailingInput),
        (b"help me", TrailingInput),
        (b"reset 0", TrailingInput),
        (b"cal 1000 1", TrailingInput),
        (b"trim l 1 2", TrailingInput),
        (b"pose 0 0 0 0", TrailingInput),
        (b"rate 10 20", TrailingInput),
        // bytes that are not printable ASCII
        ("fwd 0.1\u{e9}".as_bytes(), NotAscii),
        (b"fwd 0.1\xff", NotAscii),
        (b"\x00", NotAscii),
        (b"stop\x7f", NotAscii),
        (b"stop\x08", NotAscii),
        (b"\x1b[Astop", NotAscii),
        (b"fwd\x0b0.1", NotAscii),
        // too long
        (long.as_bytes(), TooLong),
    ];
    for (line, want) in table {
        assert_eq!(parse(line), Err(*want), "{:?}", std::string::String::from_utf8_lossy(line));
    }
}

#[test]
fn line_length_boundary() {
    let exact = "stop".to_string() + &" ".repeat(MAX_LINE - 4);
    assert_eq!(exact.len(), MAX_LINE);
    assert_eq!(parse(exact.as_bytes()), Ok(Command::Stop));
    let over = exact.clone() + " ";
    assert_eq!(parse(over.as_bytes()), Err(ParseError::TooLong));
    // a too-long line is refused even when it starts with a good command
    assert_eq!(parse(format!("fwd 0.1{}", "0".repeat(MAX_LINE)).as_bytes()), Err(ParseError::TooLong));
    // a long but legal number: many trailing zeros
    let zeros = format!("fwd 0.1{}", "0".repeat(MAX_LINE - 7));
    assert_eq!(zeros.len(), MAX_LINE);
    assert_eq!(parse(zeros.as_bytes()), Ok(fwd(100, None)));
}

fn render(r: &Response) -> std::string::String {
    let mut out: String<MAX_RESPONSE> = String::new();
    format_response(r, &mut out).expect("fits MAX_RESPONSE");
    out.as_str().to_owned()
}

#[test]
fn error_messages() {
    use Field::*;
    use ParseError::*;
    let table: &[(ParseError, &str)] = &[
        (Empty, "# err empty line"),
        (TooLong, "# err line too long, max 64 bytes"),
        (NotAscii, "# err line has a byte that is not printable ASCII"),
        (UnknownCommand, "# err unknown command, try help"),
        (OutOfRange(Speed), "# err speed out of range 0.001..0.300 m/s"),
        (OutOfRange(TurnRate), "# err turn rate out of range 0.001..6.000 rad/s"),
        (OutOfRange(Duration), "# err duration out of range 0.001..60.000 s"),
        (OutOfRange(LeftCommand), "# err left command out of range 0.00..180.00"),
        (OutOfRange(Trim), "# err trim out of range -10.00..10.00 steps"),
        (OutOfRange(X), "# err x out of range -30000..30000 mm"),
        (OutOfRange(Heading), "# err heading out of range -360.000..360.000 deg"),
        (OutOfRange(Samples), "# err samples out of range 250..10000"),
        (OutOfRange(Rate), "# err rate out of range 0..100 Hz"),
        (MissingArgument(Speed), "# err missing speed, want a number 0.001..0.300 m/s with up to 3 decimals"),
        (MissingArgument(Rate), "# err missing rate, want an integer 0..100 Hz"),
        (MissingArgument(Side), "# err missing side, want left or right"),
        (BadNumber(RightCommand), "# err bad right command, want a number 0.00..180.00 with up to 2 decimals"),
        (BadNumber(Y), "# err bad y, want an integer -30000..30000 mm"),
        (BadChoice(Side), "# err bad side, want left or right"),
        (TrailingInput, "# err unexpected input after the arguments"),
    ];
    for (e, want) in table {
        assert_eq!(render(&Response::Err(*e)), *want);
    }
    // the range in each message is the config's
    let speed = render(&Response::Err(OutOfRange(Speed)));
    assert!(speed.contains(&format!("{:.3}", f64::from(config::serial::MAX_SPEED_MM_S) / 1000.0)));
}

const FIELDS: [Field; 12] = [
    Field::Speed,
    Field::TurnRate,
    Field::Duration,
    Field::LeftCommand,
    Field::RightCommand,
    Field::Side,
    Field::Trim,
    Field::X,
    Field::Y,
    Field::Heading,
    Field::Samples,
    Field::Rate,
];

#[test]
fn every_error_is_one_short_line() {
    let mut all = vec![
        ParseError::Empty,
        ParseError::TooLong,
        ParseError::NotAscii,
        ParseError::UnknownCommand,
        ParseError::TrailingInput,
    ];
    for f in FIELDS {
        all.extend([
            ParseError::MissingArgument(f),
            ParseError::BadNumber(f),
            ParseError::OutOfRange(f),
            ParseError::BadChoice(f),
        ]);
    }
    for e in all {
        let line = render(&Response::Err(e));
        assert!(line.starts_with("# err "), "{line}");
        assert!(line.bytes().all(|b| (0x20..0x7F).contains(&b)), "{line:?}");
        assert!(line.len() <= MAX_RESPONSE, "{line}");
        assert!(!line.ends_with(' '), "{line:?}");
    }
}

#[test]
fn responses() {
    assert_eq!(render(&Response::Ok(&fwd(130, Some(2500)))), "# ok fwd 0.130 2.500");
    assert_eq!(render(&Response::Ok(&turn(-2500, None))), "# ok ccw 2.500");
    assert_eq!(
        render(&Response::Fail("calibration failed:\nonly 9 sectors")),
        "# err calibration failed:?only 9 sectors"
    );
    assert_eq!(render(&Response::Note("booted")), "# booted");
    // a buffer too small gives Overflow, not a panic
    let mut small: String<8> = String::new();
    assert!(format_response(&Response::Err(ParseError::OutOfRange(Field::Speed)), &mut small).is_err());
}

fn canonical(cmd: &Command) -> std::string::String {
    let mut out: String<MAX_RESPONSE> = String::new();
    format_command(cmd, &mut out).expect("fits");
    out.as_str().to_owned()
}

#[test]
fn canonical_forms() {
    let table: &[(&str, &str)] = &[
        ("fwd .13 2.5s", "fwd 0.130 2.500"),
        ("BACKWARD 0.1", "back 0.100"),
        ("cw 2.5", "cw 2.500"),
        ("ccw 3.2 0.25", "ccw 3.200 0.250"),
        ("s", "stop"),
        ("servo 107 61.5 0.8", "servo 107.00 61.50 0.800"),
        ("servo 0.01 179.99", "servo 0.01 179.99"),
        ("trim r -1.25", "trim right -1.25"),
        ("trim l 0.01", "trim left 0.01"),
        ("pose 100 -50 90", "pose 100 -50 90.000"),
        ("pose 0 0 -90", "pose 0 0 270.000"),
        ("pose 0 0 360", "pose 0 0 0.000"),
        ("reset", "locate"),
        ("LOCATE", "locate"),
        ("calibrate", "cal 1000"),
        ("rate 0", "rate 0"),
        ("?", "help"),
        ("status", "status"),
    ];
    for (line, want) in table {
        let cmd = parse(line.as_bytes()).expect(line);
        assert_eq!(canonical(&cmd), *want, "{line}");
        assert_eq!(parse(want.as_bytes()), Ok(cmd), "{want}");
    }
}

/// Every servo value and trim of the grammar survives 1/100 -> 1/256 -> 1/100.
#[test]
fn exhaustive_resolution_round_trips() {
    for centi in 0..=18_000u32 {
        let line = format!("servo {}.{:02} 90", centi / 100, centi % 100);
        let Ok(Command::Servo { left, .. }) = parse(line.as_bytes()) else { panic!("{line}") };
        assert_eq!(left.to_centi(), centi, "{line}");
    }
    for centi in -1000..=1000i32 {
        let sign = if centi < 0 { "-" } else { "" };
        let line = format!("trim l {sign}{}.{:02}", centi.abs() / 100, centi.abs() % 100);
        let cmd = parse(line.as_bytes()).expect(&line);
        let back = canonical(&cmd);
        assert_eq!(parse(back.as_bytes()), Ok(cmd), "{line} -> {back}");
        let Command::Trim { trim, .. } = cmd else { panic!() };
        assert!((f64::from(trim.0) / 256.0 - f64::from(centi) / 100.0).abs() <= 0.5 / 256.0 + 1e-12, "{line}");
    }
    for mm_s in 1..=config::serial::MAX_SPEED_MM_S as i32 {
        assert_eq!(Speed::from_mm_s(mm_s).to_mm_s(), mm_s);
    }
    for mrad_s in 1..=config::serial::MAX_TURN_MRAD_S as i32 {
        assert_eq!(TurnRate::from_mrad_s(mrad_s).to_mrad_s(), mrad_s);
    }
    for mdeg in (0..360_000).step_by(7) {
        assert_eq!(Angle::from_millidegrees(mdeg).to_millidegrees(), mdeg as u32);
    }
}

fn dec(v: i64, decimals: u32) -> std::string::String {
    let p = 10i64.pow(decimals);
    let sign = if v < 0 { "-" } else { "" };
    if decimals == 0 {
        format!("{v}")
    } else {
        format!("{sign}{}.{:0width$}", v.abs() / p, v.abs() % p, width = decimals as usize)
    }
}

/// Random commands in every field's range: text -> parse -> canonical ->
/// parse gives the same command, and the values are the ones written.
#[test]
fn random_commands_round_trip() {
    let mut rng = Rng::new(4);
    let pick = |rng: &mut Rng, f: Field| -> i64 {
        let (lo, hi) = f.range().expect("numeric");
        i64::from(lo) + (rng.next_u64() % (i64::from(hi) - i64::from(lo) + 1) as u64) as i64
    };
    for _ in 0..20_000 {
        let dur = |rng: &mut Rng| {
            if rng.next_u32() % 2 == 0 {
                (std::string::String::new(), None)
            } else {
                let ms = pick(rng, Field::Duration);
                (format!(" {}", dec(ms, 3)), Some(ms as u32))
            }
        };
        let (line, want) = match rng.next_u32() % 7 {
            0 => {
                let v = pick(&mut rng, Field::Speed);
                let (d, ms) = dur(&mut rng);
                (format!("fwd {}{d}", dec(v, 3)), fwd(v as i32, ms))
            }
            1 => {
                let v = pick(&mut rng, Field::Speed);
                let (d, ms) = dur(&mut rng);
                (format!("back {}{d}", dec(v, 3)), back(v as i32, ms))
            }
            2 => {
                let w = pick(&mut rng, Field::TurnRate);
                let (d, ms) = dur(&mut rng);
                let cw = rng.next_u32() % 2 == 0;
                let word = if cw { "cw" } else { "ccw" };
                (format!("{word} {}{d}", dec(w, 3)), turn(if cw { w as i32 } else { -(w as i32) }, ms))
            }
            3 => {
                let (l, r) = (pick(&mut rng, Field::LeftCommand), pick(&mut rng, Field::RightCommand));
                let (d, ms) = dur(&mut rng);
                let q8 = |c: i64| ((c * 256 + 50) / 100) as u32;
                (format!("servo {} {}{d}", dec(l, 2), dec(r, 2)), servo(q8(l), q8(r), ms))
            }
            4 => {
                let t = pick(&mut rng, Field::Trim);
                let q8 = (t.abs() * 256 + 50) / 100 * t.signum();
                let side = if rng.next_u32() % 2 == 0 { Side::Left } else { Side::Right };
                let word = if side == Side::Left { "left" } else { "right" };
                (format!("trim {word} {}", dec(t, 2)), Command::Trim { side, trim: Trim(q8 as i16) })
            }
            5 => {
                let (x, y, h) = (pick(&mut rng, Field::X), pick(&mut rng, Field::Y), pick(&mut rng, Field::Heading));
                (format!("pose {x} {y} {}", dec(h, 3)), pose(x as i32, y as i32, h as i32))
            }
            _ => {
                let hz = pick(&mut rng, Field::Rate);
                (format!("rate {hz}"), Command::Rate { hz: hz as u16 })
            }
        };
        let cmd = parse(line.as_bytes()).unwrap_or_else(|e| panic!("{line}: {e:?}"));
        assert_eq!(cmd, want, "{line}");
        let text = canonical(&cmd);
        assert_eq!(parse(text.as_bytes()), Ok(cmd), "{line} -> {text}");
    }
}

/// Random byte soup from the grammar's alphabet: never a panic, and
/// whatever parses round-trips through its canonical form.
#[test]
fn random_lines_never_panic() {
    let alphabet: &[&[u8]] = &[
        b"fwd", b"back", b"cw", b"ccw", b"stop", b"servo", b"trim", b"pose", b"reset", b"locate", b"cal", b"rate",
        b"status", b"help", b"l", b"right", b" ", b" ", b"\t", b"0", b"1", b"9", b".", b"-", b"+", b"s", b"\r",
        b"\xff", b"e", b"180", b"60", b"0.5", b"00000",
    ];
    let mut rng = Rng::new(99);
    let mut accepted = 0;
    for _ in 0..100_000 {
        let mut line = Vec::new();
        for _ in 0..rng.range_u32(0, 12) {
            line.extend_from_slice(alphabet[rng.range_u32(0, alphabet.len() as u32 - 1) as usize]);
        }
        match parse(&line) {
            Ok(cmd) => {
                accepted += 1;
                let text = canonical(&cmd);
                assert_eq!(
                    parse(text.as_bytes()),
                    Ok(cmd),
                    "{:?} -> {text}",
                    std::string::String::from_utf8_lossy(&line)
                );
            }
            Err(e) => {
                let msg = render(&Response::Err(e));
                assert!(msg.starts_with("# err "));
            }
        }
    }
    assert!(accepted > 100, "the soup should hit some valid commands ({accepted})");
}

/// The help text states the ranges the parser enforces.
#[test]
fn help_matches_config() {
    let help = HELP.join("\n");
    for line in HELP {
        assert!(line.starts_with("# "), "{line}");
        assert!(line.len() <= MAX_RESPONSE, "{line}");
    }
    for f in FIELDS {
        let Some((lo, hi)) = f.range() else { continue };
        let range = format!("{}..{}", dec(lo.into(), f.decimals()), dec(hi.into(), f.decimals()));
        match f {
            Field::X | Field::Y => assert!(help.contains(&format!("<= {hi}")), "{f:?}"),
            _ => assert!(help.contains(&range), "help lacks {range} for {f:?}"),
        }
    }
    assert!(help.contains(&format!("default {}", config::compass::CALIBRATION_SAMPLES)));
    // every keyword of the grammar appears in the help
    for word in [
        "fwd", "back", "cw", "ccw", "stop", "servo", "trim", "pose", "reset", "locate", "cal", "rate", "status", "help",
    ] {
        assert!(help.contains(word), "{word}");
        assert_ne!(parse(word.as_bytes()), Err(ParseError::UnknownCommand), "{word}");
    }
}
