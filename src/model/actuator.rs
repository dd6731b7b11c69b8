//! The servo actuator model (report section 3.2): per motion and wheel, a
//! line from servo command to speed, its inverse, and the neutral stop.
//!
//! Sign conventions (made explicit; the report's lines are magnitudes):
//! - Every line's `y` is a non-negative magnitude in rad/s over its measured
//!   command range: for forward and backward it is the *wheel* speed (car
//!   speed `v = y r`), for cw and ccw it is the *car's* turn rate.
//! - [`Motion::Straight`] speed is positive forward, negative backward;
//!   [`Motion::Turn`] rate is positive clockwise (heading grows), negative
//!   counter-clockwise.
//! - The left servo drives forward above neutral, the right one below it
//!   (it is mounted mirrored): forward is left > 90, right < 90 (the data's
//!   forward-right line `y = -0.146 x + 15.85` falls as the command rises).

use crate::math::{div_i64, div_round, round_f64, sat_i32, Length, Speed, TurnRate};

/// A servo command in the Arduino `Servo.write()` scale (0..=180, 90 = stop),
/// with 8 fractional bits, so the inverse model is not rounded to whole steps.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug, Default, PartialOrd, Ord)]
pub struct ServoCmd(u16);

impl ServoCmd {
    pub const MIN: ServoCmd = ServoCmd(0);
    pub const MAX: ServoCmd = ServoCmd(180 << 8);
    pub const NEUTRAL: ServoCmd = ServoCmd(90 << 8);

    /// Whole command (clamped to 0..=180).
    pub const fn from_int(cmd: u8) -> ServoCmd {
        ServoCmd::from_q8((cmd as u32) << 8)
    }
    /// Command in 1/256 steps (clamped to 0..=180).
    pub const fn from_q8(q8: u32) -> ServoCmd {
        if q8 > Self::MAX.0 as u32 {
            Self::MAX
        } else {
            ServoCmd(q8 as u16)
        }
    }
    /// Signed command in 1/256 steps (clamped to 0..=180).
    pub const fn from_q8_signed(q8: i32) -> ServoCmd {
        if q8 < 0 {
            Self::MIN
        } else {
            ServoCmd::from_q8(q8 as u32)
        }
    }
    pub const fn from_f64(cmd: f64) -> ServoCmd {
        ServoCmd::from_q8_signed(sat_i32(round_f64(cmd * 256.0)))
    }
    pub const fn to_q8(self) -> u16 {
        self.0
    }
    /// Whole command, rounded.
    pub const fn round(self) -> u8 {
        ((self.0 + 128) >> 8) as u8
    }
    /// Hundredths of a command step (for telemetry): 9000 = 90.00.
    pub const fn to_centi(self) -> u32 {
        (self.0 as u32 * 100 + 128) >> 8
    }
    pub fn to_f64(self) -> f64 {
        f64::from(self.0) / 256.0
    }
    /// The command shifted by `trim` (in 1/256 steps), clamped to 0..=180.
    pub const fn trimmed(self, trim: Trim) -> ServoCmd {
        ServoCmd::from_q8_signed(self.0 as i32 + trim.0 as i32)
    }
}

/// A per-servo trim in 1/256 command steps: moves that servo's neutral
/// (stop) command away from 90.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug, Default)]
pub struct Trim(pub i16);

impl Trim {
    pub const ZERO: Trim = Trim(0);
    pub const fn from_f64(steps: f64) -> Trim {
        Trim(sat_i32(round_f64(steps * 256.0)) as i16)
    }
}

/// `y = slope * cmd + intercept`, y in rad/s, both in Q16.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub struct Line {
    pub slope_q16: i32,
    pub intercept_q16: i32,
}

impl Line {
    /// From the report's numbers (y in rad/s, x in commands).
    pub const fn from_f64(slope: f64, intercept: f64) -> Line {
        Line { slope_q16: sat_i32(round_f64(slope * 65536.0)), intercept_q16: sat_i32(round_f64(intercept * 65536.0)) }
    }
    /// `y` in rad/s Q16 at `cmd`. 32-bit: |slope| < 2^15 (0.5 rad/s per
    /// step), cmd < 2^16.
    pub fn eval_q16(&self, cmd: ServoCmd) -> i32 {
        let prod = i64::from(self.slope_q16) * i64::from(cmd.to_q8());
        let y = (prod >> 8) + i64::from(self.intercept_q16);
        y.clamp(i64::from(i32::MIN), i64::from(i32::MAX)) as i32
    }
    /// The command at which the line gives `y` (rad/s Q16); `None` for a
    /// flat line. Not on the per-step path (one division).
    pub fn inverse(&self, y_q16: i32) -> Option<ServoCmd> {
        if self.slope_q16 == 0 {
            return None;
        }
        let num = (i64::from(y_q16) - i64::from(self.intercept_q16)) << 8;
        let q = div_round(num, i64::from(self.slope_q16))?;
        Some(ServoCmd::from_q8_signed(q.clamp(i64::from(i32::MIN), i64::from(i32::MAX)) as i32))
    }
}

/// One wheel's line for one motion and the command range it was measured on.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub struct WheelLine {
    pub line: Line,
    /// Lowest and highest command of the lab's measurements.
    pub min: ServoCmd,
    pub max: ServoCmd,
}

impl WheelLine {
    pub const fn new(slope: f64, intercept: f64, min: u8, max: u8) -> WheelLine {
        WheelLine { line: Line::from_f64(slope, intercept), min: ServoCmd::from_int(min), max: ServoCmd::from_int(max) }
    }
    /// The speeds (rad/s Q16) at the two ends of the measured range, low first.
    pub fn speed_range_q16(&self) -> (i32, i32) {
        let (a, b) = (self.line.eval_q16(self.min), self.line.eval_q16(self.max));
        (a.min(b), a.max(b))
    }
    /// True when the measured range lies above the untrimmed stop (90): the
    /// side of neutral this wheel turns the line's way on. The lab measured
    /// every range at trim 0, each wholly on one side of 90.
    pub fn above_neutral(&self) -> bool {
        u32::from(self.min.to_q8()) + u32::from(self.max.to_q8()) >= 2 * u32::from(ServoCmd::NEUTRAL.to_q8())
    }
    /// The part of the measured range past `neutral` (on the range's side of
    /// it), where [`WheelLine::speed_at`] is the line: all of it unless a
    /// trim moves the stop into the range; `None` when the stop is at or
    /// past the range's far end.
    pub fn past_neutral(&self, neutral: ServoCmd) -> Option<WheelLine> {
        let (lo, hi) = (self.min.min(self.max), self.min.max(self.max));
        let n = neutral.to_q8();
        // one 1/256 step past neutral: n < hi <= MAX, or n > lo >= 0, so no clamp
        let (lo, hi) = if self.above_neutral() {
            if n >= hi.to_q8() {
                return None;
            }
            (lo.max(ServoCmd::from_q8(u32::from(n) + 1)), hi)
        } else {
            if n <= lo.to_q8() {
                return None;
            }
            (lo, hi.min(ServoCmd::from_q8(u32::from(n) - 1)))
        };
        Some(WheelLine { line: self.line, min: lo, max: hi })
    }
    /// Speed magnitude (rad/s Q16) at `cmd`, for a wheel whose stop command
    /// is `neutral`. Going from neutral toward the measured range (the side
    /// [`WheelLine::above_neutral`] says): 0 at or behind neutral; a straight
    /// ramp from 0 at neutral to the line's value at the range's near end
    /// while short of the range; the line inside it; held at the far end's
    /// value past it. Never above the far end's value (the fastest the lab
    /// measured), whatever the trim: a neutral next to the near end does not
    /// steepen the ramp (it only runs from neutral to the near end), and
    /// with a neutral inside the range the part of it behind neutral gives 0.
    /// The flag is true where the value is not the line's own (outside the
    /// measured range, or behind neutral).
    pub fn speed_at(&self, cmd: ServoCmd, neutral: ServoCmd) -> (i32, bool) {
        let (lo, hi) = (self.min.min(self.max), self.min.max(self.max));
        let up = self.above_neutral();
        // how far past neutral a command is, toward the range (1/256 steps,
        // |.| <= 180 * 256)
        let past = |c: ServoCmd| {
            let d = i32::from(c.to_q8()) - i32::from(neutral.to_q8());
            if up {
                d
            } else {
                -d
            }
        };
        let (near, far) = if up { (lo, hi) } else { (hi, lo) };
        let (off, to_near, to_far) = (past(cmd), past(near), past(far));
        let y_far = self.line.eval_q16(far).max(0);
        let (y, outside) = if off <= 0 {
            (0, true) // at or behind neutral: this line says nothing
        } else if off > to_far {
            (y_far, true)
        } else if off >= to_near {
            (self.line.eval_q16(cmd).max(0), false)
        } else {
            // 0 < off < to_near: the ramp, below the near end's value
            let y_near = i64::from(self.line.eval_q16(near).max(0));
            (div_i64(y_near * i64::from(off), i64::from(to_near)).unwrap_or(0) as i32, true)
        };
        (y.min(y_far), outside)
    }
}

/// Both wheels' lines for one motion.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub struct MotionLines {
    pub left: WheelLine,
    pub right: WheelLine,
}

impl MotionLines {
    /// The magnitudes (rad/s Q16) both wheels can reach inside their
    /// measured ranges: the intersection of the two, `None` if they miss.
    pub fn common_range_q16(&self) -> Option<(i32, i32)> {
        let (l0, l1) = self.left.speed_range_q16();
        let (r0, r1) = self.right.speed_range_q16();
        let (lo, hi) = (l0.max(r0), l1.min(r1));
        (lo <= hi).then_some((lo, hi))
    }
}

/// The kinds of motion the report models.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
pub enum MotionKind {
    Stop,
    Forward,
    Backward,
    Cw,
    Ccw,
}

/// A motion with its speed: what the state update integrates.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
pub enum Motion {
    Stop,
    /// Straight, positive forward.
    Straight(Speed),
    /// Turn in place about the axle, positive clockwise.
    Turn(TurnRate),
}

impl Motion {
    pub fn kind(&self) -> MotionKind {
        match *self {
            Motion::Stop => MotionKind::Stop,
            Motion::Straight(v) if v.to_bits() > 0 => MotionKind::Forward,
            Motion::Straight(v) if v.to_bits() < 0 => MotionKind::Backward,
            Motion::Turn(w) if w.to_bits() > 0 => MotionKind::Cw,
            Motion::Turn(w) if w.to_bits() < 0 => MotionKind::Ccw,
            _ => MotionKind::Stop,
        }
    }
}

/// The two servo commands for a motion, and what the model says they do.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub struct Drive {
    pub left: ServoCmd,
    pub right: ServoCmd,
    /// The motion the commands give by the model (the request, clamped).
    pub motion: Motion,
    /// True when the request was outside the measured range and was clamped.
    pub saturated: bool,
}

/// The actuator model: the eight fitted lines, the wheel radius and the
/// servos' stop commands.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub struct ActuatorModel {
    pub forward: MotionLines,
    pub backward: MotionLines,
    pub cw: MotionLines,
    pub ccw: MotionLines,
    pub wheel_radius: Length,
    pub left_trim: Trim,
    pub right_trim: Trim,
}

impl ActuatorModel {
    pub fn lines(&self, kind: MotionKind) -> Option<&MotionLines> {
        match kind {
            MotionKind::Forward => Some(&self.forward),
            MotionKind::Backward => Some(&self.backward),
            MotionKind::Cw => Some(&self.cw),
            MotionKind::Ccw => Some(&self.ccw),
            MotionKind::Stop => None,
        }
    }

    /// The lines of `kind` restricted to the commands past each servo's
    /// neutral ([`WheelLine::past_neutral`]): what [`ActuatorModel::drive`]
    /// picks commands from. `None` for `Stop`, or when a trim puts a stop
    /// at or past the far end of its range.
    pub fn usable_lines(&self, kind: MotionKind) -> Option<MotionLines> {
        let lines = self.lines(kind)?;
        Some(MotionLines {
            left: lines.left.past_neutral(self.left_neutral())?,
            right: lines.right.past_neutral(self.right_neutral())?,
        })
    }

    pub fn left_neutral(&self) -> ServoCmd {
        ServoCmd::NEUTRAL.trimmed(self.left_trim)
    }
    pub fn right_neutral(&self) -> ServoCmd {
        ServoCmd::NEUTRAL.trimmed(self.right_trim)
    }

    /// Both servos at neutral (90 plus trim).
    pub fn stop(&self) -> Drive {
        Drive { left: self.left_neutral(), right: self.right_neutral(), motion: Motion::Stop, saturated: false }
    }

    /// Wheel speed (rad/s Q16) for a car speed.
    fn wheel_rate_q16(&self, v: Speed) -> i32 {
        let r = i64::from(self.wheel_radius.0.max(1));
        let mm_s_q16 = (i64::from(v.to_bits()) * 1_000_000) >> 16;
        div_i64(mm_s_q16 << 16, r).unwrap_or(0).clamp(0, i64::from(i32::MAX)) as i32
    }
    /// Car speed for a wheel speed (rad/s Q16).
    fn car_speed(&self, wheel_q16: i32) -> Speed {
        let mm_s_q16 = (i64::from(wheel_q16) * i64::from(self.wheel_radius.0)) >> 16;
        Speed::from_mm_s_q16(mm_s_q16.clamp(0, i64::from(i32::MAX)) as i32)
    }

    /// The inverse model: the two servo commands for a requested motion.
    /// A speed outside what both wheels reach in their measured ranges
    /// (past their neutrals, [`ActuatorModel::usable_lines`]) is clamped
    /// into it and `saturated` is set: never extrapolated.
    pub fn drive(&self, request: Motion) -> Drive {
        let kind = request.kind();
        let Some(lines) = self.usable_lines(kind) else { return self.stop() };
        let Some((lo, hi)) = lines.common_range_q16() else { return self.stop() };
        let want = match request {
            Motion::Straight(v) => self.wheel_rate_q16(v.abs()),
            Motion::Turn(w) => w.abs().to_rad_s_q16(),
            Motion::Stop => 0,
        };
        // max then min, not `clamp`: lo <= hi and min <= max hold by
        // construction, but `clamp` would link a panic for the other case
        let y = want.max(lo).min(hi);
        let saturated = y != want;
        let cmd = |w: &WheelLine| w.line.inverse(y).unwrap_or(w.min).max(w.min).min(w.max);
        let (left, right) = (cmd(&lines.left), cmd(&lines.right));
        let motion = self.motion_of(kind, left, right);
        Drive { left, right, motion, saturated }
    }

    /// The forward model for a pair of commands: which motion they make
    /// (from which side of neutral each servo is) and how fast (the mean of
    /// the two wheels' lines, see [`WheelLine::speed_at`]). A pair the report
    /// did not model (one wheel stopped, both the same way...) is `Stop`.
    pub fn motion_from_commands(&self, left: ServoCmd, right: ServoCmd) -> Motion {
        use core::cmp::Ordering::*;
        let kind = match (left.cmp(&self.left_neutral()), right.cmp(&self.right_neutral())) {
            (Greater, Less) => MotionKind::Forward,
            (Less, Greater) => MotionKind::Backward,
            (Greater, Greater) => MotionKind::Cw,
            (Less, Less) => MotionKind::Ccw,
            _ => MotionKind::Stop,
        };
        self.motion_of(kind, left, right)
    }

    fn motion_of(&self, kind: MotionKind, left: ServoCmd, right: ServoCmd) -> Motion {
        let Some(lines) = self.lines(kind) else { return Motion::Stop };
        let (yl, _) = lines.left.speed_at(left, self.left_neutral());
        let (yr, _) = lines.right.speed_at(right, self.right_neutral());
        let y = ((i64::from(yl) + i64::from(yr)) / 2) as i32;
        match kind {
            MotionKind::Forward => Motion::Straight(self.car_speed(y)),
            MotionKind::Backward => Motion::Straight(self.car_speed(y).neg()),
            MotionKind::Cw => Motion::Turn(TurnRate::from_rad_s_q16(y)),
            MotionKind::Ccw => Motion::Turn(TurnRate::from_rad_s_q16(y).neg()),
            MotionKind::Stop => Motion::Stop,
        }
    }
}
