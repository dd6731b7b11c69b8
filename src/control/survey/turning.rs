//! How far the turn under way between two views has gone, as the compass
//! shows it (issue #29). A turn ends when the compass shows its steps of
//! [`config::locate::TURN_DEG`], not after the ticks the turn line takes
//! for them: on real floors each direction turns off that line (the hard
//! world: 0.6 to 1.8 times it), and a turn timed by ticks overshoots the
//! ground its view's room check vouched for, or a reversed turn swings
//! past the ground the body has swept, into the unseen left.
//!
//! A turn ends early when it stalls: each stretch of a step's ticks on
//! the turn line must show [`config::locate::BLOCKED_TURN_DEG`] on the
//! compass (the slowest direction, 0.6 of the line, shows 26), else the
//! body is against a wall and pushing on only presses it there. A turn
//! that has not shown its angle after
//! [`config::locate::TURN_LIMIT_PERCENT`] of those ticks ends there too.
//! The readings of a turn that ended before the compass showed its angle
//! say little (the body stood for part of it): the survey forgets them
//! (`Survey::turned`).

use super::TURN_TICKS;
use crate::config;
use crate::math::Angle;

/// The turn under way, from the heading of the view it started at.
#[derive(Clone, Copy, Debug)]
pub struct Turning {
    /// The angle still to turn, its way positive, angle LSB (2^32 a whole
    /// turn; a turn of several steps passes half a turn: i64).
    left: i64,
    /// `left` when the last stretch of the line's step ticks began.
    stretch_left: i64,
    /// The compass's last heading (at the start, the view's).
    last: Angle,
    /// The ticks it may take.
    limit: u16,
    clockwise: bool,
}

/// [`config::locate::TURN_DEG`] in angle LSB.
const STEP: i64 = (config::locate::TURN_DEG as i64) * (1 << 32) / 360;
/// [`config::locate::BLOCKED_TURN_DEG`] in angle LSB.
const BLOCKED: i64 = (config::locate::BLOCKED_TURN_DEG as i64) * (1 << 32) / 360;

impl Turning {
    /// No turn under way.
    pub const NONE: Turning = Turning { left: 0, stretch_left: 0, last: Angle::ZERO, limit: 0, clockwise: true };

    /// A turn that way of `steps` steps, from a view at `from`.
    pub fn start(from: Angle, clockwise: bool, steps: u8) -> Turning {
        let line_ticks = TURN_TICKS.saturating_mul(u32::from(steps));
        let limit = line_ticks.saturating_mul(config::locate::TURN_LIMIT_PERCENT) / 100;
        let left = STEP.saturating_mul(i64::from(steps));
        Turning { left, stretch_left: left, last: from, limit: u16::try_from(limit).unwrap_or(u16::MAX), clockwise }
    }

    /// A compass heading taken while turning.
    pub fn heading(&mut self, h: Angle) {
        let moved = i64::from(h.diff(self.last));
        let toward = if self.clockwise { moved } else { moved.saturating_neg() };
        self.left = self.left.saturating_sub(toward);
        self.last = h;
    }

    /// The compass has shown the whole turn.
    pub fn reached(&self) -> bool {
        self.left <= 0
    }

    /// The turn after `ticks` ticks: whether it is over (reached, stalled
    /// or out of time). Stalled: each stretch of a step's ticks on the
    /// turn line must show [`config::locate::BLOCKED_TURN_DEG`] on the
    /// compass.
    pub fn over(&mut self, ticks: u32) -> bool {
        if ticks > 0 && ticks % TURN_TICKS == 0 {
            if self.stretch_left.saturating_sub(self.left) < BLOCKED {
                self.limit = 0;
            }
            self.stretch_left = self.left;
        }
        self.reached() || ticks > u32::from(self.limit)
    }
}
