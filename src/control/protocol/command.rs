//! Commands: the parser and the canonical form that `ok` responses echo
//! (the grammar is in `docs/protocol.md`).

pub(super) use super::field::q8_to_centi;
use super::field::{centi_to_q8, number, value};
pub use super::field::{Field, ParseError};
use super::number::{push_fixed, push_fixed_parts, push_str, push_u32, TextOut};
use super::{Overflow, MAX_LINE};
use crate::config::compass;
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
    /// Writes the trims, the compass calibration and declination and the
    /// mission to flash (`save`; refused while the robot moves).
    Save,
    /// Lists each setting and where its value comes from (`settings`).
    Settings,
    /// Erases the settings in flash, back to the config (`forget`).
    Forget,
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

fn is_space(b: &u8) -> bool {
    matches!(*b, b' ' | b'\t' | b'\r' | b'\n')
}

/// Printable ASCII or whitespace.
fn is_allowed(b: u8) -> bool {
    (0x20..0x7F).contains(&b) || is_space(&b)
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
    ("save", Keyword::Save),
    ("settings", Keyword::Settings),
    ("forget", Keyword::Forget),
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
    Save,
    Settings,
    Forget,
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
            Keyword::Stop
            | Keyword::Locate
            | Keyword::Status
            | Keyword::Help
            | Keyword::Dump
            | Keyword::Save
            | Keyword::Settings
            | Keyword::Forget => (&[], None),
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
        Keyword::Save => Command::Save,
        Keyword::Settings => Command::Settings,
        Keyword::Forget => Command::Forget,
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
        Command::Save => push_str(out, "save"),
        Command::Settings => push_str(out, "settings"),
        Command::Forget => push_str(out, "forget"),
    }
}
