//! The two FS90R wheel servos: command (0..180, 1/256 steps) to pulse width.
//!
//! The mapping is the ESP8266 Arduino core's `Servo.write()` of the lab's
//! time, a straight line from [`config::servo::PULSE_AT_0_US`] (command 0)
//! to [`config::servo::PULSE_AT_180_US`] (command 180), computed exactly in
//! nanoseconds (one 1/256 command step is 40 ns), then clamped to the
//! FS90R's safe window [`config::servo::SAFE_MIN_US`]..=`SAFE_MAX_US`.
//!
//! The pulses leave through a [`PulseOutput`], which the board implements
//! (`board::servo_pulse`, the FRC1 interrupt's mailbox; a recording fake in
//! tests and the simulator), which takes whole microseconds: the width is
//! rounded to the nearest microsecond there (0.1 command step, about
//! 0.3 mm/s of wheel speed on the report's lines).
//!
//! Trims: [`Servos::set`] takes commands the actuator model has already
//! trimmed (see `model::actuator`); [`ServoPair::stop`] sends each servo its
//! own neutral, 90 plus its trim, so "stop" means standing still.

use crate::config;
use crate::model::{ServoCmd, Trim};

use super::Servos;

/// A servo pulse width in microseconds; 0 means no pulses on that pin.
#[derive(Clone, Copy, PartialEq, Eq, Debug, Default)]
pub struct PulseWidthUs(pub u16);

impl PulseWidthUs {
    /// No pulses: the pin stays low.
    pub const OFF: Self = Self(0);

    /// `us` clamped to the servo's safe window ([`config::servo::SAFE_MIN_US`]
    /// ..= [`config::servo::SAFE_MAX_US`]); 0 stays [`Self::OFF`].
    pub const fn safe(us: u32) -> Self {
        if us == 0 {
            return Self::OFF;
        }
        let c = if us < config::servo::SAFE_MIN_US {
            config::servo::SAFE_MIN_US
        } else if us > config::servo::SAFE_MAX_US {
            config::servo::SAFE_MAX_US
        } else {
            us
        };
        // c <= SAFE_MAX_US <= u16::MAX (asserted below)
        Self(c as u16)
    }

    pub const fn is_off(self) -> bool {
        self.0 == 0
    }
}

/// Where the servo driver sends pulse widths.
pub trait PulseOutput {
    /// Both widths, applied together from the next frame on.
    fn set_widths(&mut self, left: PulseWidthUs, right: PulseWidthUs);
}

const _: () =
    assert!(config::servo::SAFE_MIN_US <= config::servo::SAFE_MAX_US && config::servo::SAFE_MAX_US <= u16::MAX as u32);

#[allow(clippy::arithmetic_side_effects)] // compile time only; `%` by b != 0 (the loop's condition)
const fn gcd(mut a: u64, mut b: u64) -> u64 {
    while b != 0 {
        let t = a % b;
        a = b;
        b = t;
    }
    a
}

/// Pulse span over the command range, ns.
const SPAN_NS: u64 = (config::servo::PULSE_AT_180_US as u64 - config::servo::PULSE_AT_0_US as u64) * 1000;
/// Command range in 1/256 steps.
const CMD_SPAN_Q8: u64 = ServoCmd::MAX.to_q8() as u64;
const G: u64 = gcd(SPAN_NS, CMD_SPAN_Q8);
/// `ns per q8 step = NUM / DEN` (1_856_000 / 46_080 = 725 / 18).
const NUM: u32 = (SPAN_NS / G) as u32;
const DEN: u32 = (CMD_SPAN_Q8 / G) as u32;

const _: () = {
    assert!(config::servo::PULSE_AT_180_US > config::servo::PULSE_AT_0_US);
    assert!(config::servo::SAFE_MIN_US <= config::servo::SAFE_MAX_US);
    // cmd_q8 * NUM + DEN / 2 fits in u32 for every command.
    assert!(CMD_SPAN_Q8 * (NUM as u64) + (DEN as u64) < u32::MAX as u64);
    assert!((config::servo::PULSE_AT_180_US as u64) * 1000 < u32::MAX as u64);
};

/// The unclamped pulse width for `cmd`, ns (rounded to the nearest ns).
pub const fn pulse_ns(cmd: ServoCmd) -> u32 {
    // cmd <= MAX, so the product fits (asserted above); DEN > 0.
    let frac = (cmd.to_q8() as u32).saturating_mul(NUM).saturating_add(DEN / 2) / DEN;
    (config::servo::PULSE_AT_0_US * 1000).saturating_add(frac)
}

/// The pulse width sent for `cmd`: [`pulse_ns`] rounded to whole
/// microseconds and clamped to the safe window.
pub const fn pulse_width(cmd: ServoCmd) -> PulseWidthUs {
    PulseWidthUs::safe(pulse_ns(cmd).saturating_add(500) / 1000)
}

/// Both wheel servos on one pulse output.
pub struct ServoPair<P> {
    out: P,
    left_trim: Trim,
    right_trim: Trim,
    last: (ServoCmd, ServoCmd),
}

impl<P: PulseOutput> ServoPair<P> {
    /// Servos with the given trims (used by [`stop`](Self::stop)). Sends
    /// nothing until the first command.
    pub fn new(out: P, left_trim: Trim, right_trim: Trim) -> Self {
        ServoPair { out, left_trim, right_trim, last: (ServoCmd::NEUTRAL, ServoCmd::NEUTRAL) }
    }

    /// Servos with the configured trims ([`config::actuators`]).
    pub fn with_config(out: P) -> Self {
        Self::new(out, config::actuators::LEFT_TRIM, config::actuators::RIGHT_TRIM)
    }

    /// Each servo's stop command: 90 plus its trim.
    pub fn neutral(&self) -> (ServoCmd, ServoCmd) {
        (ServoCmd::NEUTRAL.trimmed(self.left_trim), ServoCmd::NEUTRAL.trimmed(self.right_trim))
    }

    /// Both servos to their neutral (standing still).
    pub fn stop(&mut self) {
        let (l, r) = self.neutral();
        self.set(l, r);
    }

    /// Replaces the trims (e.g. from the `trim` command); takes effect at
    /// the next [`stop`](Self::stop).
    pub fn set_trims(&mut self, left: Trim, right: Trim) {
        self.left_trim = left;
        self.right_trim = right;
    }

    /// The last commands sent.
    pub fn commands(&self) -> (ServoCmd, ServoCmd) {
        self.last
    }

    /// Gives the output back.
    pub fn release(self) -> P {
        self.out
    }
}

impl<P: PulseOutput> Servos for ServoPair<P> {
    fn set(&mut self, left: ServoCmd, right: ServoCmd) {
        self.last = (left, right);
        self.out.set_widths(pulse_width(left), pulse_width(right));
    }
}
