//! The motion the user holds, and when to send it.
//!
//! A command is sent at once when it changes (a new motion or speed
//! level) and then, while the robot is asked to move, again every
//! `refresh_ms` ([`config::teleop::REFRESH_MS`], a quarter of the robot's
//! deadman): any valid command refreshes the deadman, so the robot keeps
//! moving while the tool runs and stops within
//! [`config::timing::DEADMAN_MS`] when the tool, the cable or the laptop
//! dies. `stop` is sent once (the deadman does not need it refreshed),
//! and not at all until the user has driven: connecting does not
//! interrupt what the robot is doing (its power-up localization, say; a
//! motion left over from before stops at its deadman).

use std::string::String;

use super::speed::Speeds;
use crate::config;
use crate::model::MotionKind;

/// The held motion and the refresh clock (times in ms on any monotonic clock).
#[derive(Clone, PartialEq, Eq, Debug)]
pub struct Driver {
    want: MotionKind,
    speeds: Speeds,
    refresh_ms: u64,
    /// The last command sent and when.
    last: Option<(String, u64)>,
    sent: u64,
}

impl Driver {
    pub fn new(speeds: Speeds, refresh_ms: u32) -> Driver {
        Driver { want: MotionKind::Stop, speeds, refresh_ms: u64::from(refresh_ms.max(1)), last: None, sent: 0 }
    }

    /// The config's speeds and refresh period.
    pub fn from_config() -> Driver {
        Driver::new(Speeds::from_config(), config::teleop::REFRESH_MS)
    }

    /// Holds `kind` from now on (`Stop` stops).
    pub fn set(&mut self, kind: MotionKind) {
        self.want = kind;
    }
    pub fn wanted(&self) -> MotionKind {
        self.want
    }
    pub fn faster(&mut self) -> bool {
        self.speeds.faster()
    }
    pub fn slower(&mut self) -> bool {
        self.speeds.slower()
    }
    pub fn speeds(&self) -> &Speeds {
        &self.speeds
    }

    /// The command for the held motion at the current level.
    pub fn command(&self) -> String {
        self.speeds.command(self.want)
    }

    /// The command to send at `now_ms`, if one is due: the first call always
    /// sends (the robot starts from a known state), a changed command is
    /// sent at once, a moving one again `refresh_ms` after the last send.
    pub fn poll(&mut self, now_ms: u64) -> Option<String> {
        let cmd = self.command();
        let due = match &self.last {
            None => self.want != MotionKind::Stop,
            Some((last, at)) => {
                *last != cmd || (self.want != MotionKind::Stop && now_ms.saturating_sub(*at) >= self.refresh_ms)
            }
        };
        if !due {
            return None;
        }
        self.last = Some((cmd.clone(), now_ms));
        self.sent = self.sent.saturating_add(1);
        Some(cmd)
    }

    /// The refresh period of a held motion, ms.
    pub fn refresh_ms(&self) -> u64 {
        self.refresh_ms
    }

    /// Commands sent so far.
    pub fn sent(&self) -> u64 {
        self.sent
    }

    /// The last command sent, if any.
    pub fn last_sent(&self) -> Option<&str> {
        self.last.as_ref().map(|(c, _)| c.as_str())
    }
}
