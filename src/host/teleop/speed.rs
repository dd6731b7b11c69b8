//! Speed levels for the drive keys: each motion (forward, backward, cw,
//! ccw) gets [`config::teleop::SPEED_LEVELS`] speeds spread evenly over the
//! range the actuator model can drive it exactly (both wheels inside their
//! measured command ranges, [`MotionLines::common_range_q16`]); level 0 is
//! the slowest. Each speed is rounded inward to the protocol's resolution
//! (1 mm/s, 1 mrad/s), so no level asks for more than the lab measured.

use std::format;
use std::string::String;

use crate::config;
use crate::model::actuator::{ActuatorModel, MotionLines};
use crate::model::MotionKind;

/// Speed level and the per-motion ranges.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub struct Speeds {
    level: usize,
    count: usize,
    /// (lo, hi) per motion in forward, backward, cw, ccw order: mm/s for
    /// straight motions, mrad/s for turns; `None` if the lines miss.
    ranges: [Option<(u32, u32)>; 4],
}

fn slot(kind: MotionKind) -> Option<usize> {
    match kind {
        MotionKind::Forward => Some(0),
        MotionKind::Backward => Some(1),
        MotionKind::Cw => Some(2),
        MotionKind::Ccw => Some(3),
        MotionKind::Stop => None,
    }
}

/// The exactly drivable range of one motion in protocol units, rounded inward.
fn range(model: &ActuatorModel, lines: &MotionLines, straight: bool) -> Option<(u32, u32)> {
    let (lo, hi) = lines.common_range_q16()?;
    // wheel rad/s (Q16) -> car mm/s for straight motions; car rad/s -> mrad/s for turns
    let scale = if straight { model.wheel_radius.to_mm_f64() } else { 1000.0 };
    let to = |q16: i32| f64::from(q16) / 65536.0 * scale;
    let (lo, hi) = (to(lo).ceil(), to(hi).floor());
    (lo >= 1.0 && hi >= lo).then_some((lo as u32, hi as u32))
}

impl Speeds {
    /// `count` levels (at least 2) over the model's ranges, starting at `level`.
    pub fn new(model: &ActuatorModel, count: usize, level: usize) -> Speeds {
        let count = count.max(2);
        Speeds {
            level: level.min(count - 1),
            count,
            ranges: [
                range(model, &model.forward, true),
                range(model, &model.backward, true),
                range(model, &model.cw, false),
                range(model, &model.ccw, false),
            ],
        }
    }

    /// The tool's default: the config's model, levels and start level.
    pub fn from_config() -> Speeds {
        Speeds::new(&config::actuators::MODEL, config::teleop::SPEED_LEVELS, config::teleop::START_LEVEL)
    }

    pub fn level(&self) -> usize {
        self.level
    }
    pub fn count(&self) -> usize {
        self.count
    }
    /// One level up; false at the top.
    pub fn faster(&mut self) -> bool {
        let up = self.level + 1 < self.count;
        if up {
            self.level += 1;
        }
        up
    }
    /// One level down; false at the bottom.
    pub fn slower(&mut self) -> bool {
        let down = self.level > 0;
        if down {
            self.level -= 1;
        }
        down
    }

    /// The drivable range of a motion, mm/s or mrad/s.
    pub fn range(&self, kind: MotionKind) -> Option<(u32, u32)> {
        slot(kind).and_then(|i| self.ranges.get(i).copied().flatten())
    }

    /// The speed of a motion at the current level, mm/s (straight) or
    /// mrad/s (turns); `None` for stop or a motion the model cannot drive.
    pub fn value(&self, kind: MotionKind) -> Option<u32> {
        let (lo, hi) = self.range(kind)?;
        // (hi - lo) * level / (count - 1), rounded: small numbers, no overflow
        let span = u64::from(hi - lo) * self.level as u64;
        let steps = (self.count - 1) as u64;
        Some(lo + ((2 * span + steps) / (2 * steps)) as u32)
    }

    /// The protocol command that drives `kind` at the current level (untimed:
    /// the deadman stops it unless it is sent again), `stop` for
    /// [`MotionKind::Stop`] or a motion the model cannot drive.
    pub fn command(&self, kind: MotionKind) -> String {
        let word = match kind {
            MotionKind::Forward => "fwd",
            MotionKind::Backward => "back",
            MotionKind::Cw => "cw",
            MotionKind::Ccw => "ccw",
            MotionKind::Stop => return String::from("stop"),
        };
        match self.value(kind) {
            Some(v) => format!("{word} {}.{:03}", v / 1000, v % 1000),
            None => String::from("stop"),
        }
    }

    /// The level as shown on screen, e.g. `3/5: fwd 0.136 m/s, turn 2.690 rad/s`.
    pub fn describe(&self) -> String {
        let f = |v: Option<u32>| v.map_or(String::from("-"), |v| format!("{}.{:03}", v / 1000, v % 1000));
        format!(
            "{}/{}: fwd {} back {} m/s, cw {} ccw {} rad/s",
            self.level + 1,
            self.count,
            f(self.value(MotionKind::Forward)),
            f(self.value(MotionKind::Backward)),
            f(self.value(MotionKind::Cw)),
            f(self.value(MotionKind::Ccw)),
        )
    }
}
