//! A command's arguments: each field's name, unit, resolution and range,
//! how a token becomes its value, and why a line was refused
//! ([`ParseError`], with its message).

use super::number::{parse_fixed, push_fixed, push_str, push_u32, NumError, TextOut};
use super::{Overflow, MAX_LINE};
use crate::config::{compass, serial};

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

/// `f`'s value in `token`: a number in `f`'s range and resolution, scaled
/// by `10^decimals`, or for [`Field::Side`] 0 (left) or 1 (right).
pub(super) fn value(token: &[u8], f: Field) -> Result<i32, ParseError> {
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

pub(super) fn number(token: &[u8], f: Field) -> Result<i32, ParseError> {
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
pub(super) fn centi_to_q8(centi: i32) -> i32 {
    crate::math::div_round(i64::from(centi) << 8, 100).map_or(0, |q8| q8 as i32)
}

/// 1/256 command steps to 1/100 steps, rounded half away from zero.
pub(crate) fn q8_to_centi(q8: i32) -> i32 {
    let c = (q8.unsigned_abs().min(1 << 22).saturating_mul(100).saturating_add(128) >> 8) as i32; // < 2^29
    if q8 < 0 {
        c.wrapping_neg()
    } else {
        c
    }
}
