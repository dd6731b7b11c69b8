//! Lines that are not telemetry: responses, status and help. Every one
//! starts with `#`, so a plotting script that skips `#` lines reads the
//! telemetry directly.

use super::command::{format_command, q8_to_centi, Command, ParseError};
use super::number::{push_str, push_text, put_template, TextOut};
use super::telemetry::{motion_word, FaultCounters};
use super::Overflow;
use crate::model::{Motion, Pose, ServoCmd, Trim};

/// Prefix of an accepted command's echo.
pub const OK: &str = "# ok ";
/// Prefix of a refusal or failure.
pub const ERR: &str = "# err ";

/// A one-line answer.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum Response<'a> {
    /// A command was accepted: `# ok <canonical command>`, e.g. `# ok fwd 0.130 2.000`.
    Ok(&'a Command),
    /// A line was refused: `# err <problem>`, e.g. `# err speed out of range 0.001..0.300 m/s`.
    Err(ParseError),
    /// The control loop refused or aborted something: `# err <text>`.
    Fail(&'a str),
    /// Anything else worth saying: `# <text>`.
    Note(&'a str),
}

/// Appends a response line (no terminator). On [`Overflow`] the string
/// holds a partial line: clear it. A `String<`[`super::MAX_RESPONSE`]`>` fits
/// every `Ok` and `Err` response.
pub fn format_response(response: &Response, out: &mut dyn TextOut) -> Result<(), Overflow> {
    match *response {
        Response::Ok(cmd) => {
            push_str(out, OK)?;
            format_command(cmd, out)
        }
        Response::Err(e) => {
            push_str(out, ERR)?;
            e.write(out)
        }
        Response::Fail(text) => {
            push_str(out, ERR)?;
            push_text(out, text)
        }
        Response::Note(text) => {
            push_str(out, "# ")?;
            push_text(out, text)
        }
    }
}

/// Longest mode word written by [`format_status`], bytes.
pub const MODE_MAX: usize = 16;

/// What the `status` command reports (the control loop fills it in).
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub struct Status {
    /// Time since boot, ms.
    pub t_ms: u32,
    /// The loop's mode in one word, e.g. `idle`, `drive`, `servo`, `cal`.
    pub mode: &'static str,
    pub motion: Motion,
    /// Time left of a timed command, ms.
    pub remaining_ms: Option<u32>,
    pub pose: Pose,
    pub left_cmd: ServoCmd,
    pub right_cmd: ServoCmd,
    pub left_trim: Trim,
    pub right_trim: Trim,
    /// Telemetry rate, Hz (0 = off).
    pub rate_hz: u16,
    /// Whether each sensor is up.
    pub front_ok: bool,
    pub right_ok: bool,
    pub compass_ok: bool,
    pub faults: FaultCounters,
}

/// Appends the status line (no terminator), `key=value` pairs:
/// `# status t_ms=1200 mode=drive motion=fwd v_mps=0.130 w_radps=0.000 left_ms=800 x_mm=12 y_mm=-3
/// heading_deg=90.000 left_cmd=107.00 right_cmd=61.00 trim_left=0.00 trim_right=-1.50 rate_hz=10
/// front=ok right=ok compass=down f_bus=0 f_timeout=0 f_missing=0 f_bad_sample=0 f_outliers=0
/// f_overruns=0` (one line; `left_ms` only for timed commands; the fault
/// counters named as the telemetry columns). Fits in [`super::MAX_OUT_LINE`].
#[inline(never)]
pub fn format_status(s: &Status, out: &mut dyn TextOut) -> Result<(), Overflow> {
    let (v, w) = match s.motion {
        Motion::Stop => (0, 0),
        Motion::Straight(v) => (v.to_mm_s(), 0),
        Motion::Turn(w) => (0, w.to_mrad_s()),
    };
    // at most MODE_MAX bytes of the mode word (it may be any &str)
    let mode = s.mode.get(..s.mode.len().min(MODE_MAX)).unwrap_or("?");
    let motion = motion_word(s.motion.kind());
    // signed values as their i32's bits (codes a..d)
    put_template(
        out,
        "# status t_ms=%0 mode=%s motion=%s v_mps=%d w_radps=%d",
        &[s.t_ms, v as u32, w as u32],
        &[mode, motion],
    )?;
    if let Some(ms) = s.remaining_ms {
        put_template(out, " left_ms=%0", &[ms], &[])?;
    }
    let up = |ok: bool| if ok { "ok" } else { "down" };
    let f = &s.faults;
    put_template(
        out,
        " x_mm=%a y_mm=%a heading_deg=%3 left_cmd=%2 right_cmd=%2 trim_left=%c trim_right=%c rate_hz=%0 \
front=%s right=%s compass=%s f_bus=%0 f_timeout=%0 f_missing=%0 f_bad_sample=%0 f_outliers=%0 f_overruns=%0",
        &[
            s.pose.x.to_length().to_mm() as u32,
            s.pose.y.to_length().to_mm() as u32,
            s.pose.theta.to_millidegrees(),
            s.left_cmd.to_centi(),
            s.right_cmd.to_centi(),
            q8_to_centi(i32::from(s.left_trim.0)) as u32,
            q8_to_centi(i32::from(s.right_trim.0)) as u32,
            u32::from(s.rate_hz),
            f.bus,
            f.timeout,
            f.missing,
            f.bad_sample,
            f.rejected_outliers,
            f.overruns,
        ],
        &[up(s.front_ok), up(s.right_ok), up(s.compass_ok)],
    )
}

/// The `help` answer, one line each (ranges as in `config::serial`; a test
/// checks they match).
pub const HELP: &[&str] = &[
    "# commands (one per line, words separated by spaces, case-insensitive):",
    "#  fwd|back <m/s> [<s>]   drive straight, speed 0.001..0.300, optional duration 0.001..60.000 s",
    "#  cw|ccw <rad/s> [<s>]   turn in place, rate 0.001..6.000",
    "#  stop (or s)            both servos to neutral",
    "#  servo <l> <r> [<s>]    raw servo commands 0.00..180.00 (90 = stop), no trim",
    "#  trim left|right <steps> servo neutral offset -10.00..10.00",
    "#  pose <x mm> <y mm> <deg> set the pose, |x|,|y| <= 30000, heading -360.000..360.000",
    "#  reset                  pose 0 0 0",
    "#  cal [<samples>]        magnetometer calibration sweep, 250..10000 samples (default 1000)",
    "#  rate <Hz>              telemetry rows per second 0..100 (0 = off)",
    "#  status | help",
    "# telemetry: CSV rows after a header line; lines starting with # are not telemetry",
];
