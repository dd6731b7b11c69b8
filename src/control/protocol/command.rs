//! Commands: the grammar (see the module docs of [`super`]), the parser and
//! the canonical form that `ok` responses echo.

use super::number::{parse_fixed, push_fixed, push_fixed_parts, push_str, push_u32, NumError, TextOut};
use super::{Overflow, MAX_LINE};
use crate::config::{compass, serial};
use crate::control::mission::Step;
use crate::math::{Angle, Speed, TurnRate};
use crate::model::{Motion, ServoCmd, Trim};

/// Which servo a `trim` command adjusts.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
pub enum Side {
    Left,
    Right,
}

/// One parsed command line.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum Command {
    /// `fwd`/`back` (speed in m/s) or `cw`/`ccw` (turn rate in rad/s),
    /// for `duration_ms` or, without one, until the next command or the
    /// deadman. `motion` is never [`Motion::Stop`] and never zero.
    Drive {
        motion: Motion,
        duration_ms: Option<u32>,
    },
    /// Both servos to neutral (90 plus trim).
    Stop,
    /// Raw servo commands (0..180, 90 = stop, trims not applied).
    Servo {
        left: ServoCmd,
        right: ServoCmd,
        duration_ms: Option<u32>,
    },
    /// Sets one servo's trim (in command steps, moves its neutral).
    Trim {
        side: Side,
        trim: Trim,
    },
    /// Sets the pose estimate.
    SetPose {
        x_mm: i32,
        y_mm: i32,
        heading: Angle,
    },
    /// Starts a magnetometer calibration sweep of `samples` samples.
    Calibrate {
        samples: u16,
    },
    /// Telemetry rows per second, 0 = off.
    Rate {
        hz: u16,
    },
    Status,
    Help,
    /// Drives the reference point to `(x, y)` on the estimate (`goto`).
    Goto {
        x_mm: i32,
        y_mm: i32,
    },
    /// Turns in place to a heading on the estimate (`face`).
    Face {
        heading: Angle,
    },
    /// Stands still for a while (`wait`, a mission's pause).
    Wait {
        duration_ms: u32,
    },
    /// `mission add|list|clear|start`.
    Mission(MissionOp),
    /// Rows per second of the on-board log during a mission, 0 = off (`log`).
    Log {
        hz: u16,
    },
    /// Sends the on-board log (`dump`).
    Dump,
    /// Finds where the robot is, turning in place (`locate`, or `reset`;
    /// see `control::survey`).
    Locate,
}

/// What a `mission` command does.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum MissionOp {
    /// Appends a step.
    Add(Step),
    /// Lists the steps.
    List,
    /// Forgets the steps.
    Clear,
    /// Starts the mission after the countdown.
    Start,
}

/// A command argument: its name, unit, resolution and accepted range, for
/// the parser and for error messages.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
pub enum Field {
    /// `fwd`/`back` speed, m/s.
    Speed,
    /// `cw`/`ccw` turn rate, rad/s.
    TurnRate,
    /// Optional duration of a motion, s.
    Duration,
    /// `servo` left command.
    LeftCommand,
    /// `servo` right command.
    RightCommand,
    /// `trim` side: `left`/`l` or `right`/`r`.
    Side,
    /// `trim` amount, command steps.
    Trim,
    /// `pose` x, mm.
    X,
    /// `pose` y, mm.
    Y,
    /// `pose` heading, degrees clockwise from north.
    Heading,
    /// `cal` sample count.
    Samples,
    /// `rate`, Hz.
    Rate,
    /// `mission`'s first word: `add`, `list`, `clear` or `start`.
    Action,
}

impl Field {
    /// The name used in messages.
    pub fn name(self) -> &'static str {
        match self {
            Field::Speed => "speed",
            Field::TurnRate => "turn rate",
            Field::Duration => "duration",
            Field::LeftCommand => "left command",
            Field::RightCommand => "right command",
            Field::Side => "side",
            Field::Trim => "trim",
            Field::X => "x",
            Field::Y => "y",
            Field::Heading => "heading",
            Field::Samples => "samples",
            Field::Rate => "rate",
            Field::Action => "mission action",
        }
    }

    /// The unit the user writes (empty for plain counts).
    pub fn unit(self) -> &'static str {
        match self {
            Field::Speed => "m/s",
            Field::TurnRate => "rad/s",
            Field::Duration => "s",
            Field::Trim => "steps",
            Field::X | Field::Y => "mm",
            Field::Heading => "deg",
            Field::Rate => "Hz",
            Field::LeftCommand | Field::RightCommand | Field::Side | Field::Samples | Field::Action => "",
        }
    }

    /// Decimal places accepted (the value's resolution).
    pub fn decimals(self) -> u32 {
        match self {
            Field::Speed | Field::TurnRate | Field::Duration | Field::Heading => 3,
            Field::LeftCommand | Field::RightCommand | Field::Trim => 2,
            Field::Side | Field::X | Field::Y | Field::Samples | Field::Rate | Field::Action => 0,
        }
    }

    /// Accepted range, inclusive, in units of `10^-decimals` (speed in mm/s,
    /// turn rate in mrad/s, duration in ms, commands and trim in 1/100 step,
    /// heading in millidegrees). `None` for [`Field::Side`] and
    /// [`Field::Action`] (words, not numbers).
    pub fn range(self) -> Option<(i32, i32)> {
        // every limit is a small config constant (asserted below): the casts are exact
        let symmetric = |max: u32| ((max as i32).wrapping_neg(), max as i32);
        Some(match self {
            Field::Speed => (1, serial::MAX_SPEED_MM_S as i32),
            Field::TurnRate => (1, serial::MAX_TURN_MRAD_S as i32),
            Field::Duration => (1, serial::MAX_DURATION_MS as i32),
            Field::LeftCommand | Field::RightCommand => (0, 18_000),
            Field::Side | Field::Action => return None,
            Field::Trim => symmetric(serial::MAX_TRIM_CENTI),
            Field::X | Field::Y => symmetric(serial::MAX_POSE_MM),
            Field::Heading => (-360_000, 360_000),
            Field::Samples => (i32::from(serial::MIN_CAL_SAMPLES), i32::from(serial::MAX_CAL_SAMPLES)),
            Field::Rate => (0, i32::from(serial::MAX_TELEMETRY_HZ)),
        })
    }
}

const _: () = {
    assert!(serial::MAX_SPEED_MM_S >= 1 && serial::MAX_SPEED_MM_S <= 1_000); // Speed::MAX is 1 m/s
    assert!(serial::MAX_TURN_MRAD_S >= 1 && serial::MAX_TURN_MRAD_S <= 20_000); // TurnRate::MAX is 20 rad/s
    assert!(serial::MAX_DURATION_MS >= 1 && serial::MAX_DURATION_MS <= 3_600_000);
    assert!(serial::MAX_TRIM_CENTI <= 12_700); // Trim is i16 in 1/256 steps
    assert!(serial::MAX_POSE_MM <= 32_000); // Length holds +-32767 mm
    assert!(serial::MIN_CAL_SAMPLES <= compass::CALIBRATION_SAMPLES);
    assert!(compass::CALIBRATION_SAMPLES <= serial::MAX_CAL_SAMPLES);
    assert!(serial::MAX_LINE >= 32 && serial::MAX_LINE <= 255);
};

/// Why a line was refused. Each renders as one line (see
/// [`super::format_response`]); a refused line changes nothing.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
pub enum ParseError {
    /// Nothing but whitespace (the loop may ignore it silently).
    Empty,
    /// Longer than [`MAX_LINE`] bytes.
    TooLong,
    /// A byte that is not printable ASCII (space and tab allowed).
    NotAscii,
    /// The first word is no command.
    UnknownCommand,
    /// A required argument is missing.
    MissingArgument(Field),
    /// An argument is not a number of the field's resolution.
    BadNumber(Field),
    /// A number outside the field's range.
    OutOfRange(Field),
    /// A word argument is not one of its choices (the trim side).
    BadChoice(Field),
    /// More arguments than the command takes.
    TrailingInput,
    /// `mission add` with a command that cannot be a mission step.
    NotAStep,
}

impl ParseError {
    /// Writes the message (without the `# err ` prefix), e.g.
    /// `speed out of range 0.001..0.300 m/s`.
    pub fn write(&self, out: &mut dyn TextOut) -> Result<(), Overflow> {
        match *self {
            ParseError::Empty => push_str(out, "empty line"),
            // MAX_LINE <= 255 (asserted)
            ParseError::TooLong => {
                push_str(out, "line too long, max ")?;
                push_u32(out, MAX_LINE as u32)?;
                push_str(out, " bytes")
            }
            ParseError::NotAscii => push_str(out, "line has a byte that is not printable ASCII"),
            ParseError::UnknownCommand => push_str(out, "unknown command, try help"),
            ParseError::MissingArgument(f) => {
                push_str(out, "missing ")?;
                push_str(out, f.name())?;
                push_str(out, ", want ")?;
                write_want(out, f)
            }
            ParseError::BadNumber(f) | ParseError::BadChoice(f) => {
                push_str(out, "bad ")?;
                push_str(out, f.name())?;
                push_str(out, ", want ")?;
                write_want(out, f)
            }
            ParseError::OutOfRange(f) => {
                push_str(out, f.name())?;
                push_str(out, " out of range ")?;
                write_range(out, f)
            }
            ParseError::TrailingInput => push_str(out, "unexpected input after the arguments"),
            ParseError::NotAStep => {
                push_str(out, "not a mission step, want a timed fwd/back/cw/ccw, wait, goto, face or pose")
            }
        }
    }
}

/// "a number 0.001..0.300 m/s with up to 3 decimals", "an integer 0..100 Hz",
/// "left or right".
fn write_want(out: &mut dyn TextOut, f: Field) -> Result<(), Overflow> {
    if f.range().is_none() {
        return write_range(out, f);
    }
    push_str(out, if f.decimals() == 0 { "an integer " } else { "a number " })?;
    write_range(out, f)?;
    if f.decimals() > 0 {
        push_str(out, " with up to ")?;
        push_u32(out, f.decimals())?;
        push_str(out, " decimals")?;
    }
    Ok(())
}

/// "0.001..0.300 m/s" ("left or right" for the trim side, the choices of
/// a mission action)
fn write_range(out: &mut dyn TextOut, f: Field) -> Result<(), Overflow> {
    let Some((lo, hi)) = f.range() else {
        return push_str(out, if f == Field::Action { "add, list, clear or start" } else { "left or right" });
    };
    push_fixed(out, lo, f.decimals())?;
    push_str(out, "..")?;
    push_fixed(out, hi, f.decimals())?;
    if !f.unit().is_empty() {
        push_str(out, " ")?;
        push_str(out, f.unit())?;
    }
    Ok(())
}

fn is_space(b: &u8) -> bool {
    matches!(*b, b' ' | b'\t' | b'\r' | b'\n')
}

/// Printable ASCII or whitespace.
fn is_allowed(b: u8) -> bool {
    (0x20..0x7F).contains(&b) || is_space(&b)
}

/// `f`'s value in `token`: a number in `f`'s range and resolution, scaled
/// by `10^decimals`, or for [`Field::Side`] 0 (left) or 1 (right).
fn value(token: &[u8], f: Field) -> Result<i32, ParseError> {
    if f != Field::Side {
        return number(token, f);
    }
    if token.eq_ignore_ascii_case(b"left") || token.eq_ignore_ascii_case(b"l") {
        Ok(0)
    } else if token.eq_ignore_ascii_case(b"right") || token.eq_ignore_ascii_case(b"r") {
        Ok(1)
    } else {
        Err(ParseError::BadChoice(Field::Side))
    }
}

fn number(token: &[u8], f: Field) -> Result<i32, ParseError> {
    let v = parse_fixed(token, f.decimals()).map_err(|e| match e {
        NumError::Bad => ParseError::BadNumber(f),
        NumError::Range => ParseError::OutOfRange(f),
    })?;
    match f.range() {
        Some((lo, hi)) if (lo..=hi).contains(&v) => Ok(v),
        _ => Err(ParseError::OutOfRange(f)),
    }
}

/// 1/100 command steps to 1/256 steps, rounded half away from zero (the
/// callers' ranges keep |centi| <= 18_000, so |result| <= 46_080).
fn centi_to_q8(centi: i32) -> i32 {
    crate::math::div_round(i64::from(centi) << 8, 100).map_or(0, |q8| q8 as i32)
}

/// 1/256 command steps to 1/100 steps, rounded half away from zero.
pub(super) fn q8_to_centi(q8: i32) -> i32 {
    let c = (q8.unsigned_abs().min(1 << 22).saturating_mul(100).saturating_add(128) >> 8) as i32; // < 2^29
    if q8 < 0 {
        c.wrapping_neg()
    } else {
        c
    }
}

const KEYWORDS: &[(&str, Keyword)] = &[
    ("fwd", Keyword::Forward),
    ("forward", Keyword::Forward),
    ("back", Keyword::Backward),
    ("backward", Keyword::Backward),
    ("cw", Keyword::Cw),
    ("ccw", Keyword::Ccw),
    ("stop", Keyword::Stop),
    ("s", Keyword::Stop),
    ("servo", Keyword::Servo),
    ("trim", Keyword::Trim),
    ("pose", Keyword::Pose),
    ("locate", Keyword::Locate),
    ("reset", Keyword::Locate),
    ("cal", Keyword::Calibrate),
    ("calibrate", Keyword::Calibrate),
    ("rate", Keyword::Rate),
    ("status", Keyword::Status),
    ("help", Keyword::Help),
    ("?", Keyword::Help),
    ("goto", Keyword::Goto),
    ("face", Keyword::Face),
    ("wait", Keyword::Wait),
    ("log", Keyword::Log),
    ("dump", Keyword::Dump),
];

#[derive(Clone, Copy)]
enum Keyword {
    Forward,
    Backward,
    Cw,
    Ccw,
    Stop,
    Servo,
    Trim,
    Pose,
    Locate,
    Calibrate,
    Rate,
    Status,
    Help,
    Goto,
    Face,
    Wait,
    Log,
    Dump,
}

impl Keyword {
    /// The required arguments, in order, and the optional one that may
    /// follow them ([`Field::Duration`] in seconds, `2.5` or `2.5s`, or
    /// [`Field::Samples`]).
    fn grammar(self) -> (&'static [Field], Option<Field>) {
        const DURATION: Option<Field> = Some(Field::Duration);
        match self {
            Keyword::Forward | Keyword::Backward => (&[Field::Speed], DURATION),
            Keyword::Cw | Keyword::Ccw => (&[Field::TurnRate], DURATION),
            Keyword::Servo => (&[Field::LeftCommand, Field::RightCommand], DURATION),
            Keyword::Trim => (&[Field::Side, Field::Trim], None),
            Keyword::Pose => (&[Field::X, Field::Y, Field::Heading], None),
            Keyword::Calibrate => (&[], Some(Field::Samples)),
            Keyword::Rate | Keyword::Log => (&[Field::Rate], None),
            Keyword::Goto => (&[Field::X, Field::Y], None),
            Keyword::Face => (&[Field::Heading], None),
            Keyword::Wait => (&[], DURATION),
            Keyword::Stop | Keyword::Locate | Keyword::Status | Keyword::Help | Keyword::Dump => (&[], None),
        }
    }
}

/// Parses one command line (without its terminator; trailing `\r`/`\n` are
/// whitespace). Words are separated by spaces or tabs; keywords are
/// case-insensitive. Never panics, allocates nothing.
pub fn parse(line: &[u8]) -> Result<Command, ParseError> {
    if line.len() > MAX_LINE {
        return Err(ParseError::TooLong);
    }
    if !line.iter().all(|&b| is_allowed(b)) {
        return Err(ParseError::NotAscii);
    }
    let (first, rest) = split_word(line);
    if first.eq_ignore_ascii_case(b"mission") {
        return parse_mission(rest);
    }
    let mut words = line.split(is_space).filter(|w| !w.is_empty());
    let word = words.next().ok_or(ParseError::Empty)?;
    let keyword = KEYWORDS
        .iter()
        .find(|(name, _)| name.as_bytes().eq_ignore_ascii_case(word))
        .map(|&(_, k)| k)
        .ok_or(ParseError::UnknownCommand)?;
    // the required arguments (at most three), in the fields' units
    let (fields, optional) = keyword.grammar();
    let mut v = [0; 3];
    for (slot, &f) in v.iter_mut().zip(fields) {
        let token = words.next().ok_or(ParseError::MissingArgument(f))?;
        *slot = value(token, f)?;
    }
    let mut extra = None;
    if let Some(f) = optional {
        if let Some(token) = words.next() {
            let token = match token.split_last() {
                Some((b's' | b'S', rest)) if f == Field::Duration => rest,
                _ => token,
            };
            extra = Some(number(token, f)?);
        }
    }
    if words.next().is_some() {
        return Err(ParseError::TrailingInput);
    }
    // ranges: duration 1..=MAX_DURATION_MS, samples MIN..=MAX_CAL_SAMPLES
    // (<= u16::MAX), rate 0..=MAX_TELEMETRY_HZ: the casts are exact
    let duration_ms = extra.map(i32::unsigned_abs);
    let [a, b, c] = v;
    Ok(match keyword {
        // speed 1..=MAX_SPEED_MM_S, turn rate 1..=MAX_TURN_MRAD_S
        Keyword::Forward => Command::Drive { motion: Motion::Straight(Speed::from_mm_s(a)), duration_ms },
        Keyword::Backward => Command::Drive { motion: Motion::Straight(Speed::from_mm_s(a).neg()), duration_ms },
        Keyword::Cw => Command::Drive { motion: Motion::Turn(TurnRate::from_mrad_s(a)), duration_ms },
        Keyword::Ccw => Command::Drive { motion: Motion::Turn(TurnRate::from_mrad_s(a).neg()), duration_ms },
        Keyword::Stop => Command::Stop,
        // commands 0..=18_000
        Keyword::Servo => Command::Servo {
            left: ServoCmd::from_q8_signed(centi_to_q8(a)),
            right: ServoCmd::from_q8_signed(centi_to_q8(b)),
            duration_ms,
        },
        // |trim| <= MAX_TRIM_CENTI <= 12_700
        Keyword::Trim => {
            Command::Trim { side: if a == 0 { Side::Left } else { Side::Right }, trim: Trim(centi_to_q8(b) as i16) }
        }
        Keyword::Pose => Command::SetPose { x_mm: a, y_mm: b, heading: Angle::from_millidegrees(c) },
        Keyword::Locate => Command::Locate,
        Keyword::Calibrate => Command::Calibrate { samples: extra.map_or(compass::CALIBRATION_SAMPLES, |n| n as u16) },
        Keyword::Rate => Command::Rate { hz: a as u16 },
        Keyword::Status => Command::Status,
        Keyword::Help => Command::Help,
        // |x|, |y| <= MAX_POSE_MM
        Keyword::Goto => Command::Goto { x_mm: a, y_mm: b },
        Keyword::Face => Command::Face { heading: Angle::from_millidegrees(a) },
        Keyword::Wait => {
            Command::Wait { duration_ms: duration_ms.ok_or(ParseError::MissingArgument(Field::Duration))? }
        }
        Keyword::Log => Command::Log { hz: a as u16 },
        Keyword::Dump => Command::Dump,
    })
}

/// The first word of `line` and what follows it.
fn split_word(line: &[u8]) -> (&[u8], &[u8]) {
    let start = line.iter().position(|b| !is_space(b)).unwrap_or(line.len());
    let line = line.get(start..).unwrap_or(&[]);
    let end = line.iter().position(is_space).unwrap_or(line.len());
    (line.get(..end).unwrap_or(&[]), line.get(end..).unwrap_or(&[]))
}

/// `mission` and its action: `add <step>`, `list`, `clear`, `start`.
fn parse_mission(rest: &[u8]) -> Result<Command, ParseError> {
    let (action, rest) = split_word(rest);
    let op = if action.is_empty() {
        return Err(ParseError::MissingArgument(Field::Action));
    } else if action.eq_ignore_ascii_case(b"add") {
        // the step is a command line of its own
        let cmd = parse(rest).map_err(|e| if e == ParseError::Empty { ParseError::NotAStep } else { e })?;
        MissionOp::Add(Step::from_command(&cmd).ok_or(ParseError::NotAStep)?)
    } else if action.eq_ignore_ascii_case(b"list") {
        MissionOp::List
    } else if action.eq_ignore_ascii_case(b"clear") {
        MissionOp::Clear
    } else if action.eq_ignore_ascii_case(b"start") {
        MissionOp::Start
    } else {
        return Err(ParseError::BadChoice(Field::Action));
    };
    if !matches!(op, MissionOp::Add(_)) && !split_word(rest).0.is_empty() {
        return Err(ParseError::TrailingInput);
    }
    Ok(Command::Mission(op))
}

/// ` <seconds>` with three decimals, if there is a duration.
fn push_duration(out: &mut dyn TextOut, duration_ms: Option<u32>) -> Result<(), Overflow> {
    match duration_ms {
        Some(ms) => {
            push_str(out, " ")?;
            push_fixed_parts(out, false, ms, 3)
        }
        None => Ok(()),
    }
}

/// Writes the canonical form of a command: the grammar's short keyword and
/// every number at the field's resolution (`fwd 0.130 2.000`). Parsing the
/// canonical form gives the same command back.
pub fn format_command(cmd: &Command, out: &mut dyn TextOut) -> Result<(), Overflow> {
    match *cmd {
        Command::Drive { motion, duration_ms } => {
            // the word gives the direction, the number is positive
            let (word, value) = match motion {
                Motion::Straight(v) => (if v.to_bits() < 0 { "back" } else { "fwd" }, v.to_mm_s()),
                Motion::Turn(w) => (if w.to_bits() < 0 { "ccw" } else { "cw" }, w.to_mrad_s()),
                Motion::Stop => return push_str(out, "stop"),
            };
            push_str(out, word)?;
            push_str(out, " ")?;
            push_fixed_parts(out, false, value.unsigned_abs(), 3)?;
            push_duration(out, duration_ms)
        }
        Command::Stop => push_str(out, "stop"),
        Command::Servo { left, right, duration_ms } => {
            push_str(out, "servo ")?;
            push_fixed_parts(out, false, left.to_centi(), 2)?;
            push_str(out, " ")?;
            push_fixed_parts(out, false, right.to_centi(), 2)?;
            push_duration(out, duration_ms)
        }
        Command::Trim { side, trim } => {
            let word = if side == Side::Left { "left" } else { "right" };
            push_str(out, "trim ")?;
            push_str(out, word)?;
            push_str(out, " ")?;
            push_fixed(out, q8_to_centi(i32::from(trim.0)), 2)
        }
        Command::SetPose { x_mm, y_mm, heading } => {
            push_str(out, "pose ")?;
            push_fixed(out, x_mm, 0)?;
            push_str(out, " ")?;
            push_fixed(out, y_mm, 0)?;
            push_str(out, " ")?;
            push_fixed_parts(out, false, heading.to_millidegrees(), 3)
        }
        Command::Calibrate { samples } => {
            push_str(out, "cal ")?;
            push_u32(out, u32::from(samples))
        }
        Command::Rate { hz } => {
            push_str(out, "rate ")?;
            push_u32(out, u32::from(hz))
        }
        Command::Status => push_str(out, "status"),
        Command::Help => push_str(out, "help"),
        Command::Goto { x_mm, y_mm } => {
            push_str(out, "goto ")?;
            push_fixed(out, x_mm, 0)?;
            push_str(out, " ")?;
            push_fixed(out, y_mm, 0)
        }
        Command::Face { heading } => {
            push_str(out, "face ")?;
            push_fixed_parts(out, false, heading.to_millidegrees(), 3)
        }
        Command::Wait { duration_ms } => {
            push_str(out, "wait")?;
            push_duration(out, Some(duration_ms))
        }
        Command::Mission(op) => {
            push_str(out, "mission ")?;
            match op {
                MissionOp::Add(step) => {
                    push_str(out, "add ")?;
                    format_command(&step.command(), out)
                }
                MissionOp::List => push_str(out, "list"),
                MissionOp::Clear => push_str(out, "clear"),
                MissionOp::Start => push_str(out, "start"),
            }
        }
        Command::Log { hz } => {
            push_str(out, "log ")?;
            push_u32(out, u32::from(hz))
        }
        Command::Dump => push_str(out, "dump"),
        Command::Locate => push_str(out, "locate"),
    }
}
