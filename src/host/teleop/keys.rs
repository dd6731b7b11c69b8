//! Key presses to teleop actions. The terminal layer turns its events into
//! [`Key`]s (so this mapping is tested without a terminal).
//!
//! | keys                   | action                                   |
//! | ---------------------- | ---------------------------------------- |
//! | Up, `w`                | drive forward (held until another key)   |
//! | Down, `s`              | drive backward                           |
//! | Left, `a`              | turn counter-clockwise (left) in place   |
//! | Right, `d`             | turn clockwise (right) in place          |
//! | Space, `x`             | stop                                     |
//! | `+`, `=`, `e`          | next speed level                         |
//! | `-`, `_`, `z`          | previous speed level                     |
//! | `r`                    | find the pose again (`locate`)           |
//! | `p`                    | ask for the robot's `status` line        |
//! | `k`                    | keep trims, calibration, mission (`save`) |
//! | `h`, `?`               | show or hide the key help                |
//! | `q`, Esc, Ctrl-C       | stop the robot and quit                  |
//!
//! `r` is for a robot that was carried or got lost: it turns in place and
//! finds where it is from the walls (`control::survey`). Letters work in
//! either case. A terminal reports no key releases, so a
//! motion is latched: it runs until space or another motion key, and the
//! tool keeps refreshing it (see [`super::drive`]).

use crate::model::MotionKind;

/// A key press, as far as the tool cares.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum Key {
    Up,
    Down,
    Left,
    Right,
    Esc,
    /// Ctrl-C (raw mode delivers it as a key, not a signal).
    CtrlC,
    Char(char),
}

/// What a key asks for.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum Action {
    /// Drive this motion (or stop) until told otherwise.
    Drive(MotionKind),
    Faster,
    Slower,
    Locate,
    Status,
    /// Keep the robot's settings in flash (`save`; refused while it moves).
    Save,
    ToggleHelp,
    Quit,
}

/// The action of a key, `None` for keys without one.
pub fn action(key: Key) -> Option<Action> {
    let a = match key {
        Key::Up => Action::Drive(MotionKind::Forward),
        Key::Down => Action::Drive(MotionKind::Backward),
        Key::Left => Action::Drive(MotionKind::Ccw),
        Key::Right => Action::Drive(MotionKind::Cw),
        Key::Esc | Key::CtrlC => Action::Quit,
        Key::Char(c) => match c.to_ascii_lowercase() {
            'w' => Action::Drive(MotionKind::Forward),
            's' => Action::Drive(MotionKind::Backward),
            'a' => Action::Drive(MotionKind::Ccw),
            'd' => Action::Drive(MotionKind::Cw),
            ' ' | 'x' => Action::Drive(MotionKind::Stop),
            '+' | '=' | 'e' => Action::Faster,
            '-' | '_' | 'z' => Action::Slower,
            'r' => Action::Locate,
            'p' => Action::Status,
            'k' => Action::Save,
            'h' | '?' => Action::ToggleHelp,
            'q' => Action::Quit,
            _ => return None,
        },
    };
    Some(a)
}

/// The key help, one line per group (for the screen).
pub const HELP: &[&str] = &[
    "arrows / WASD: drive (held until space or another key)",
    "space or x: stop      + / -  (or e / z): speed level",
    "r: find the pose (turns in place)   p: status   k: save settings (stopped)",
    "h: hide help   q / Esc: stop and quit",
];

/// The command `r` sends.
pub const LOCATE_COMMAND: &str = "locate";
