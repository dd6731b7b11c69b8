//! Lines that are not telemetry: responses, status and help. Every one
//! starts with `#`, so a plotting script that skips `#` lines reads the
//! telemetry directly.

use super::command::{format_command, q8_to_centi, Command, ParseError};
use super::number::{push_fixed, push_fixed_parts, push_i32, push_str, push_text, push_u32, TextOut};
use super::telemetry::{motion_word, FaultCounters};
use super::Overflow;
use crate::model::compass::{CalibrationError, MagCalibration};
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
    /// How sure the estimator is of the pose (issue 29).
    pub tracking: crate::model::estimator::Tracking,
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
/// heading_deg=90.000 pose=located left_cmd=107.00 right_cmd=61.00 trim_left=0.00 trim_right=-1.50 rate_hz=10
/// front=ok right=ok compass=down f_bus=0 f_timeout=0 f_missing=0 f_bad_sample=0 f_outliers=0
/// f_overruns=0` (one line; `left_ms` only for timed commands; the fault
/// counters named as the telemetry columns). Fits in [`super::MAX_OUT_LINE`].
pub fn format_status(s: &Status, out: &mut dyn TextOut) -> Result<(), Overflow> {
    let (v, w) = match s.motion {
        Motion::Stop => (0, 0),
        Motion::Straight(v) => (v.to_mm_s(), 0),
        Motion::Turn(w) => (0, w.to_mrad_s()),
    };
    // at most MODE_MAX bytes of the mode word (it may be any &str)
    let mode = s.mode.get(..s.mode.len().min(MODE_MAX)).unwrap_or("?");
    let motion = motion_word(s.motion.kind());
    push_str(out, "# status t_ms=")?;
    push_u32(out, s.t_ms)?;
    push_str(out, " mode=")?;
    push_text(out, mode)?;
    push_str(out, " motion=")?;
    push_str(out, motion)?;
    push_str(out, " v_mps=")?;
    push_fixed(out, v, 3)?;
    push_str(out, " w_radps=")?;
    push_fixed(out, w, 3)?;
    if let Some(ms) = s.remaining_ms {
        push_str(out, " left_ms=")?;
        push_u32(out, ms)?;
    }
    push_str(out, " x_mm=")?;
    push_i32(out, s.pose.x.to_length().to_mm())?;
    push_str(out, " y_mm=")?;
    push_i32(out, s.pose.y.to_length().to_mm())?;
    push_str(out, " heading_deg=")?;
    push_fixed_parts(out, false, s.pose.theta.to_millidegrees(), 3)?;
    push_str(out, " pose=")?;
    push_str(out, s.tracking.word())?;
    push_str(out, " left_cmd=")?;
    push_fixed_parts(out, false, s.left_cmd.to_centi(), 2)?;
    push_str(out, " right_cmd=")?;
    push_fixed_parts(out, false, s.right_cmd.to_centi(), 2)?;
    push_str(out, " trim_left=")?;
    push_fixed(out, q8_to_centi(i32::from(s.left_trim.0)), 2)?;
    push_str(out, " trim_right=")?;
    push_fixed(out, q8_to_centi(i32::from(s.right_trim.0)), 2)?;
    push_str(out, " rate_hz=")?;
    push_u32(out, u32::from(s.rate_hz))?;
    let up = |ok: bool| if ok { "ok" } else { "down" };
    push_str(out, " front=")?;
    push_str(out, up(s.front_ok))?;
    push_str(out, " right=")?;
    push_str(out, up(s.right_ok))?;
    push_str(out, " compass=")?;
    push_str(out, up(s.compass_ok))?;
    let f = &s.faults;
    for (name, n) in [
        (" f_bus=", f.bus),
        (" f_timeout=", f.timeout),
        (" f_missing=", f.missing),
        (" f_bad_sample=", f.bad_sample),
        (" f_outliers=", f.rejected_outliers),
        (" f_overruns=", f.overruns),
    ] {
        push_str(out, name)?;
        push_u32(out, n)?;
    }
    Ok(())
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
    "#  locate (or reset)      find the pose: views of the walls, turning in place",
    "#  cal [<samples>]        magnetometer calibration sweep, 250..10000 samples (default 1000)",
    "#  rate <Hz>              telemetry rows per second 0..100 (0 = off)",
    "#  status | help",
    "#  goto <x mm> <y mm>     drive there on the estimate (turn, then straight)",
    "#  face <deg>             turn in place to a heading on the estimate",
    "#  wait <s>               stand still 0.001..60.000 s",
    "#  mission add <step>     append a timed fwd/back/cw/ccw, wait, goto, face or pose",
    "#  mission list|clear|start  show, forget, run (after a countdown; any byte aborts)",
    "#  log <Hz>               on-board log rows per second in a mission 0..100; dump sends it",
    "#  save|settings|forget   settings in flash: keep (when stopped), show, erase",
    "# telemetry: CSV rows after a header line; lines starting with # are not telemetry",
];

/// `|q16| * 10^6 / 2^16` rounded half up, saturating at `u32::MAX`, in 32
/// bits: `10^6 / 2^16 = 15625 / 2^10`, and with `a = h 2^10 + l` that is
/// `15625 h + ((15625 l + 2^9) >> 10)` (`15625 l + 2^9 < 2^24`).
fn q16_to_micro(a: u32) -> u32 {
    const H_MAX: u32 = u32::MAX / 15_625; // const-evaluated
    let (h, l) = (a >> 10, a & 0x3FF);
    if h > H_MAX {
        return u32::MAX;
    }
    // h <= H_MAX: 15625 h fits
    h.wrapping_mul(15_625).saturating_add(l.wrapping_mul(15_625).wrapping_add(1 << 9) >> 10)
}

/// `bias <x> <y> <z> scale <x> <y> <z>`: a calibration's values (biases in
/// counts, scales to six decimals, as the config line).
pub fn format_calibration_values(out: &mut dyn TextOut, cal: &MagCalibration) -> Result<(), Overflow> {
    push_str(out, "bias")?;
    for b in cal.bias {
        push_str(out, " ")?;
        push_i32(out, b)?;
    }
    push_str(out, " scale")?;
    for q16 in cal.scale_q16 {
        push_str(out, " ")?;
        push_fixed_parts(out, q16 < 0, q16_to_micro(q16.unsigned_abs()), 6)?;
    }
    Ok(())
}

/// The answer line to a calibration sweep's end: `# ...` for a result (or
/// an abandoned sweep), `# err ...` (the protocol's `ERR`) for a failure.
/// `tests/control/basics.rs` pins the lines.
pub fn format_calibration_report(
    t: &mut dyn TextOut,
    result: Option<Result<MagCalibration, CalibrationError>>,
    samples: u16,
    sectors: u8,
) -> Result<(), Overflow> {
    match result {
        None => {
            push_str(t, "# calibration abandoned after ")?;
            push_u32(t, u32::from(samples))?;
            push_str(t, " samples")
        }
        Some(Ok(_)) => {
            push_str(t, "# calibration ok: ")?;
            push_u32(t, u32::from(samples))?;
            push_str(t, " samples, ")?;
            push_u32(t, u32::from(sectors))?;
            push_str(t, " of 12 sectors; x and y measured, z kept from config; applied. For config::compass:")
        }
        Some(Err(CalibrationError::NotEnoughSamples { have, need })) => {
            push_str(t, "# err calibration timed out: ")?;
            push_u32(t, u32::from(have))?;
            push_str(t, " of ")?;
            push_u32(t, u32::from(need))?;
            push_str(t, " samples")
        }
        Some(Err(CalibrationError::SweepIncomplete { sectors, need })) => {
            push_str(t, "# err calibration failed: the turn covered ")?;
            push_u32(t, u32::from(sectors))?;
            push_str(t, " of 12 sectors, need ")?;
            push_u32(t, u32::from(need))
        }
        Some(Err(CalibrationError::Degenerate { axis })) => {
            push_str(t, "# err calibration failed: magnetometer axis ")?;
            push_u32(t, u32::from(axis))?;
            push_str(t, " never changed")
        }
    }
}

// The calibration report names z as the axis kept from the config.
const _: () = assert!(crate::model::compass::calibration::VERTICAL == 2);

/// The `CALIBRATION` line of `config::compass` for `cal`, ready to paste
/// (the same text as `model::compass::ConfigLine`, written without
/// `core::fmt`): biases as integers, scales with six decimals.
pub fn format_config_line(out: &mut dyn TextOut, cal: &MagCalibration) -> Result<(), Overflow> {
    push_str(out, "pub const CALIBRATION: MagCalibration = MagCalibration::from_f64([")?;
    for (i, b) in cal.bias.into_iter().enumerate() {
        if i > 0 {
            push_str(out, ", ")?;
        }
        push_i32(out, b)?;
        push_str(out, ".0")?;
    }
    push_str(out, "], [")?;
    for (i, q16) in cal.scale_q16.into_iter().enumerate() {
        if i > 0 {
            push_str(out, ", ")?;
        }
        // q16 * 10^6 / 2^16 rounded half away from zero (as math::div_round):
        // the sign as text, as a magnitude may pass i32::MAX (and |q16| >= 1
        // gives at least 15 millionths: no "-0")
        push_fixed_parts(out, q16 < 0, q16_to_micro(q16.unsigned_abs()), 6)?;
    }
    push_str(out, "]);")
}

#[cfg(test)]
#[allow(clippy::restriction)] // test code: a panic fails the test
mod tests {
    use super::q16_to_micro;

    #[test]
    fn q16_to_micro_rounds_half_up_and_saturates() {
        let mut a: u32 = 0;
        loop {
            let want = ((u64::from(a) * 1_000_000 + (1 << 15)) >> 16).min(u64::from(u32::MAX)) as u32;
            assert_eq!(q16_to_micro(a), want, "{a}");
            match a.checked_add(a / 1024 + 1) {
                Some(n) => a = n,
                None => break,
            }
        }
        for a in (0..1 << 20).chain([u32::MAX, u32::MAX - 1, 1 << 31, 274_877, 274_878, 281_474_976]) {
            let want = ((u64::from(a) * 1_000_000 + (1 << 15)) >> 16).min(u64::from(u32::MAX)) as u32;
            assert_eq!(q16_to_micro(a), want, "{a}");
        }
    }
}
