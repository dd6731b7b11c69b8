//! What the survey answers each tick ([`Action`]), and why a survey ends
//! without a fix ([`Failure`]).

use crate::model::locate::{Fix, LocateError};

/// Why there is no fix.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum Failure {
    /// The compass gave no heading for a view.
    NoHeading,
    /// Neither lidar gave a distance in any view.
    NoRange,
    /// No pose in the box explains the views (an obstacle, another box).
    NothingFits,
    /// A look's time limit ran out ([`crate::config::locate::TIME_LIMIT_MS`]).
    OutOfTime,
    /// A command came (it runs instead).
    Interrupted,
}

impl Failure {
    /// The reason in words, for the `# locate failed` line.
    pub fn text(self) -> &'static str {
        match self {
            Failure::NoHeading => "no compass heading",
            Failure::NoRange => "no lidar distance",
            Failure::NothingFits => "no pose in the box explains the readings",
            Failure::OutOfTime => "out of time",
            Failure::Interrupted => "interrupted by a command",
        }
    }
}

impl From<LocateError> for Failure {
    fn from(e: LocateError) -> Failure {
        match e {
            LocateError::NoReading => Failure::NoRange,
            LocateError::NothingFits => Failure::NothingFits,
        }
    }
}

/// What the body does this tick, or the procedure's answer.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum Action {
    Stand,
    /// Turn in place at [`crate::config::locate::TURN_MRAD_S`].
    Turn {
        clockwise: bool,
    },
    /// Drive straight at [`crate::config::locate::POSITION_MM_S`] (making room
    /// before the first view).
    Drive {
        forward: bool,
    },
    /// The answer fit poorly: the procedure looks again from elsewhere,
    /// with a time limit of its own (the body stands this tick).
    LookAgain,
    Done(Result<Fix, Failure>),
}
