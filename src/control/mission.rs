//! Missions: a list of steps stored on the robot and run without the
//! cable (`mission add|list|clear|start`, see the protocol's docs).
//!
//! A [`Step`] is one command a mission may hold: a timed motion, a wait,
//! `goto`, `face` or `pose`. A [`Mission`] keeps up to
//! [`crate::config::mission::MAX_STEPS`] of them. So that a reset does not lose
//! it, the firmware copies it into a [`MissionStore`] whenever it changes
//! ([`Mission::encode`]: a magic word, the count, three words a step and a
//! checksum) and reads it back at boot ([`Mission::decode`], which refuses
//! anything that is not a mission it wrote, e.g. power-on garbage). The
//! store is the board's (`board::esp8266::RtcMissionStore`: RTC memory,
//! kept across resets, lost at power-off); [`MemoryStore`] stands in for it
//! on the host.

use heapless::Vec;

use crate::config::mission::MAX_STEPS;
use crate::control::protocol::Command;
use crate::math::{Angle, Speed, TurnRate};
use crate::model::Motion;

/// One step of a mission.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum Step {
    /// A motion for its duration (a mission has no untimed motions: nobody
    /// is there to stop them).
    Drive {
        motion: Motion,
        duration_ms: u32,
    },
    /// Stand still.
    Wait {
        duration_ms: u32,
    },
    Goto {
        x_mm: i32,
        y_mm: i32,
    },
    Face {
        heading: Angle,
    },
    /// Sets the estimate (where the robot is put down).
    Pose {
        x_mm: i32,
        y_mm: i32,
        heading: Angle,
    },
}

impl Step {
    /// The step a command is, if it may be one.
    pub fn from_command(cmd: &Command) -> Option<Step> {
        Some(match *cmd {
            Command::Drive { motion, duration_ms: Some(duration_ms) } => Step::Drive { motion, duration_ms },
            Command::Wait { duration_ms } => Step::Wait { duration_ms },
            Command::Goto { x_mm, y_mm } => Step::Goto { x_mm, y_mm },
            Command::Face { heading } => Step::Face { heading },
            Command::SetPose { x_mm, y_mm, heading } => Step::Pose { x_mm, y_mm, heading },
            _ => return None,
        })
    }

    /// The command that runs the step.
    pub fn command(&self) -> Command {
        match *self {
            Step::Drive { motion, duration_ms } => Command::Drive { motion, duration_ms: Some(duration_ms) },
            Step::Wait { duration_ms } => Command::Wait { duration_ms },
            Step::Goto { x_mm, y_mm } => Command::Goto { x_mm, y_mm },
            Step::Face { heading } => Command::Face { heading },
            Step::Pose { x_mm, y_mm, heading } => Command::SetPose { x_mm, y_mm, heading },
        }
    }

    /// Three words: a tag and two values (their bits).
    fn encode(&self) -> [u32; 3] {
        match *self {
            Step::Drive { motion: Motion::Straight(v), duration_ms } => [1, v.to_bits() as u32, duration_ms],
            Step::Drive { motion: Motion::Turn(w), duration_ms } => [2, w.to_bits() as u32, duration_ms],
            Step::Drive { motion: Motion::Stop, duration_ms } | Step::Wait { duration_ms } => [3, 0, duration_ms],
            Step::Goto { x_mm, y_mm } => [4, x_mm as u32, y_mm as u32],
            Step::Face { heading } => [5, heading.0, 0],
            // pose: x and y (|v| <= 30000 mm) as 16 bits each, the heading
            Step::Pose { x_mm, y_mm, heading } => [6 | (x_mm as u32) << 16, y_mm as u32, heading.0],
        }
    }

    fn decode([tag, a, b]: [u32; 3]) -> Option<Step> {
        Some(match tag & 0xFFFF {
            1 => Step::Drive { motion: Motion::Straight(Speed::from_bits(a as i32)), duration_ms: b },
            2 => Step::Drive { motion: Motion::Turn(TurnRate::from_bits(a as i32)), duration_ms: b },
            3 => Step::Wait { duration_ms: b },
            4 => Step::Goto { x_mm: a as i32, y_mm: b as i32 },
            5 => Step::Face { heading: Angle(a) },
            6 => Step::Pose { x_mm: i32::from((tag >> 16) as u16 as i16), y_mm: a as i32, heading: Angle(b) },
            _ => return None,
        })
    }
}

/// Words of an encoded mission: magic, count, three a step, checksum.
pub const WORDS: usize = 3 + 3 * MAX_STEPS;
/// "PBM1": a paperbot mission, encoding 1.
const MAGIC: u32 = 0x5042_4D31;

/// A mission's steps.
#[derive(Clone, PartialEq, Eq, Debug, Default)]
pub struct Mission {
    steps: Vec<Step, MAX_STEPS>,
}

/// The mission already has [`MAX_STEPS`] steps.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub struct Full;

impl Mission {
    pub const fn new() -> Mission {
        Mission { steps: Vec::new() }
    }
    pub fn push(&mut self, step: Step) -> Result<(), Full> {
        self.steps.push(step).map_err(|_| Full)
    }
    pub fn clear(&mut self) {
        self.steps.clear();
    }
    pub fn steps(&self) -> &[Step] {
        &self.steps
    }
    pub fn get(&self, i: usize) -> Option<Step> {
        self.steps.get(i).copied()
    }
    pub fn len(&self) -> usize {
        self.steps.len()
    }
    pub fn is_empty(&self) -> bool {
        self.steps.is_empty()
    }

    /// The mission as words for a [`MissionStore`] (unused words are 0).
    pub fn encode(&self) -> [u32; WORDS] {
        let mut words = [0u32; WORDS];
        let mut it = words.iter_mut();
        let mut put = |w: u32| {
            if let Some(slot) = it.next() {
                *slot = w;
            }
        };
        put(MAGIC);
        put(self.steps.len() as u32); // <= MAX_STEPS
        for s in &self.steps {
            s.encode().into_iter().for_each(&mut put);
        }
        let sum = checksum(&words);
        if let Some(last) = words.last_mut() {
            *last = sum;
        }
        words
    }

    /// The mission [`Mission::encode`] wrote, or `None` for anything else.
    pub fn decode(words: &[u32; WORDS]) -> Option<Mission> {
        let (&sum, _) = words.split_last()?;
        if words.first() != Some(&MAGIC) || sum != checksum(words) {
            return None;
        }
        let n = *words.get(1)? as usize;
        let mut mission = Mission::new();
        for chunk in words.get(2..)?.chunks_exact(3).take(n) {
            let step = Step::decode([*chunk.first()?, *chunk.get(1)?, *chunk.get(2)?])?;
            mission.push(step).ok()?;
        }
        (mission.len() == n).then_some(mission)
    }
}

/// A rotate-and-add sum of every word but the last (which holds it).
fn checksum(words: &[u32; WORDS]) -> u32 {
    let body = words.split_last().map_or(&[][..], |(_, b)| b);
    body.iter().fold(0x9E37_79B9u32, |acc, &w| acc.rotate_left(5).wrapping_add(w) ^ 0xA5A5_0000)
}

/// Where the board keeps a mission across resets.
pub trait MissionStore {
    fn load(&mut self) -> [u32; WORDS];
    fn save(&mut self, words: &[u32; WORDS]);
}

/// A [`MissionStore`] in plain memory (host tests and the simulator: it
/// survives what the test says it survives).
#[derive(Clone, PartialEq, Eq, Debug)]
pub struct MemoryStore(pub [u32; WORDS]);

impl Default for MemoryStore {
    fn default() -> Self {
        MemoryStore([0; WORDS])
    }
}

impl MissionStore for MemoryStore {
    fn load(&mut self) -> [u32; WORDS] {
        self.0
    }
    fn save(&mut self, words: &[u32; WORDS]) {
        self.0 = *words;
    }
}

#[cfg(test)]
#[allow(clippy::restriction)] // test code: a panic fails the test
mod tests {
    use super::*;

    fn all_kinds() -> Mission {
        let mut m = Mission::new();
        for s in [
            Step::Pose { x_mm: -30_000, y_mm: 30_000, heading: Angle::from_millidegrees(359_999) },
            Step::Drive { motion: Motion::Straight(Speed::from_mm_s(-130)), duration_ms: 2_500 },
            Step::Drive { motion: Motion::Turn(TurnRate::from_mrad_s(2_400)), duration_ms: 60_000 },
            Step::Wait { duration_ms: 1 },
            Step::Goto { x_mm: 300, y_mm: -200 },
            Step::Face { heading: Angle::QUARTER_TURN },
        ] {
            m.push(s).unwrap();
        }
        m
    }

    #[test]
    fn a_mission_survives_its_encoding() {
        let m = all_kinds();
        assert_eq!(Mission::decode(&m.encode()), Some(m));
        let mut full = Mission::new();
        while full.push(Step::Goto { x_mm: 100, y_mm: 100 }).is_ok() {}
        assert_eq!(full.len(), MAX_STEPS);
        assert_eq!(Mission::decode(&full.encode()), Some(full));
        assert_eq!(Mission::decode(&Mission::new().encode()), Some(Mission::new()));
    }

    #[test]
    fn garbage_and_damage_are_no_mission() {
        assert_eq!(Mission::decode(&[0; WORDS]), None);
        assert_eq!(Mission::decode(&[u32::MAX; WORDS]), None);
        let good = all_kinds().encode();
        for i in 0..WORDS {
            for bit in [0, 7, 31] {
                let mut w = good;
                w[i] ^= 1 << bit;
                assert_eq!(Mission::decode(&w), None, "word {i} bit {bit}");
            }
        }
    }
}
