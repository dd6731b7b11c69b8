//! Settings that survive power-off: the trims, the compass calibration and
//! declination, and the mission, kept as one record in flash (`save`,
//! `settings`, `forget` in the protocol's docs).
//!
//! The record ([`encode`], [`decode`]) is [`RECORD_WORDS`] little-endian
//! words: a magic word, the format version
//! ([`config::settings::VERSION`]), a sequence number, the two trims, the
//! calibration's biases and scales, the declination, the mission's words
//! ([`Mission::encode`], with their own check) and a CRC-32 of all that.
//! [`decode`] refuses anything else with a [`Refusal`] that says why: an
//! erased sector, another version, a damaged record, a value out of range.
//! Nothing is half-applied: a record is taken whole or not at all.
//!
//! Two sectors ([`config::settings::SECTORS`]) take the record by turns
//! ([`FlashSettings`]): a save erases and writes the sector that does not
//! hold the newest valid record, with the next sequence number and its
//! magic word last, so a power cut during the erase or the write leaves
//! the older record valid (and the torn one reads as a save cut short); at
//! boot the newer valid record wins. The flash itself is behind [`Flash`]: the
//! ESP8266 ROM's routines on the robot, [`MemoryFlash`] (NOR semantics: an
//! erase sets every bit, a write only clears bits) on the host and in the
//! simulator. The same flash keeps the on-board log at a mission's end
//! ([`kept_log`]).

use crate::config;
use crate::config::settings::VERSION;
use crate::control::mission::{self, Mission};
use crate::math::Angle;
use crate::model::compass::MagCalibration;
use crate::model::Trim;

/// The values a record holds.
#[derive(Clone, PartialEq, Eq, Debug)]
pub struct Settings {
    pub left_trim: Trim,
    pub right_trim: Trim,
    pub calibration: MagCalibration,
    pub declination: Angle,
    pub mission: Mission,
}

impl Settings {
    /// The config's values (`src/config/`), with no mission.
    pub fn from_config() -> Settings {
        Settings {
            left_trim: config::actuators::LEFT_TRIM,
            right_trim: config::actuators::RIGHT_TRIM,
            calibration: config::compass::CALIBRATION,
            declination: config::compass::DECLINATION,
            mission: Mission::new(),
        }
    }
}

/// "PBST": paperbot settings.
const MAGIC: u32 = 0x5042_5354;
/// Words before the mission: magic, version, sequence, trims, 3 biases,
/// 3 scales, declination.
const HEAD_WORDS: usize = 11;
/// Words of a record: the head, the mission, the CRC.
pub const RECORD_WORDS: usize = HEAD_WORDS + mission::WORDS + 1;
/// Bytes of a record (348: one flash page write, a stack buffer).
pub const RECORD_BYTES: usize = RECORD_WORDS * 4;
const _: () = assert!(RECORD_BYTES <= config::settings::SECTOR_BYTES as usize);

/// An encoded record.
pub type Record = [u32; RECORD_WORDS];

/// Why a sector's contents are not a record this firmware takes.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum Refusal {
    /// Erased (every bit set): never written, or erased by `forget` or by a
    /// save the power cut.
    Blank,
    /// A save cut short: written but for its magic word, which a save
    /// writes last.
    Unfinished,
    /// Not a settings record (no magic word).
    NotARecord,
    /// A record of another format version (written by another firmware).
    OtherVersion(u32),
    /// The CRC does not match: damaged, or a write the power cut.
    Damaged,
    /// A value out of the range the protocol accepts.
    OutOfRange,
}

impl Refusal {
    /// The reason, for the boot line (short: every byte of text is DRAM
    /// on the robot).
    pub fn reason(self) -> &'static str {
        match self {
            Refusal::Blank => "erased",
            Refusal::Unfinished => "save cut short",
            Refusal::NotARecord => "not a record",
            Refusal::OtherVersion(_) => "version",
            Refusal::Damaged => "CRC mismatch",
            Refusal::OutOfRange => "value out of range",
        }
    }
}

/// CRC-32 (ISO-HDLC, the zlib/Ethernet one) of words' little-endian
/// bytes as they stream by, bitwise: no table in DRAM, about 350 bytes a
/// save or a boot (12 KB for a kept log: `kept_log`).
struct Crc32(crc::Digest<'static, u32, crc::NoTable>);

static CRC32: crc::Crc<u32, crc::NoTable> = crc::Crc::<u32, crc::NoTable>::new(&crc::CRC_32_ISO_HDLC);

impl Crc32 {
    fn new() -> Crc32 {
        Crc32(CRC32.digest())
    }
    fn update(&mut self, words: &[u32]) {
        for w in words {
            self.0.update(&w.to_le_bytes());
        }
    }
    fn finish(self) -> u32 {
        self.0.finalize()
    }
}

/// The CRC-32 of `words` (see [`Crc32`]).
fn crc32(words: &[u32]) -> u32 {
    let mut c = Crc32::new();
    c.update(words);
    c.finish()
}

/// The record of `s` with sequence number `sequence`.
pub fn encode(s: &Settings, sequence: u32) -> Record {
    let mut r = [0u32; RECORD_WORDS];
    let [b0, b1, b2] = s.calibration.bias;
    let [s0, s1, s2] = s.calibration.scale_q16;
    let trims = u32::from(s.left_trim.0 as u16) | u32::from(s.right_trim.0 as u16) << 16;
    let decl = s.declination.0;
    let head =
        [MAGIC, VERSION, sequence, trims, b0 as u32, b1 as u32, b2 as u32, s0 as u32, s1 as u32, s2 as u32, decl];
    let mission = s.mission.encode();
    for (slot, w) in r.iter_mut().zip(head.iter().chain(mission.iter())) {
        *slot = *w;
    }
    if let Some((last, body)) = r.split_last_mut() {
        *last = crc32(body);
    }
    r
}

/// The record's sequence number if it is a valid record of this version
/// (magic, version, CRC; the values are checked by [`decode`]).
pub fn check(r: &Record) -> Result<u32, Refusal> {
    if r.iter().all(|&w| w == u32::MAX) {
        return Err(Refusal::Blank);
    }
    let word = |i: usize| r.get(i).copied().unwrap_or(0);
    if word(0) == u32::MAX {
        return Err(Refusal::Unfinished);
    }
    if word(0) != MAGIC {
        return Err(Refusal::NotARecord);
    }
    if word(1) != VERSION {
        return Err(Refusal::OtherVersion(word(1)));
    }
    let (&crc, body) = r.split_last().ok_or(Refusal::Damaged)?;
    if crc != crc32(body) {
        return Err(Refusal::Damaged);
    }
    Ok(word(2))
}

/// The settings and sequence number of a record [`encode`] wrote, or why not.
pub fn decode(r: &Record) -> Result<(Settings, u32), Refusal> {
    let sequence = check(r)?;
    let word = |i: usize| r.get(i).copied().unwrap_or(0);
    let trim = |bits: u32| Trim(bits as u16 as i16);
    let (left_trim, right_trim) = (trim(word(3)), trim(word(3) >> 16));
    let max_trim = config::serial::MAX_TRIM_CENTI * 256 / 100; // 1/256 steps, as the parser's
    if left_trim.0.unsigned_abs() as u32 > max_trim || right_trim.0.unsigned_abs() as u32 > max_trim {
        return Err(Refusal::OutOfRange);
    }
    let i = |k: usize| word(k) as i32;
    let calibration = MagCalibration { bias: [i(4), i(5), i(6)], scale_q16: [i(7), i(8), i(9)] };
    if calibration.scale_q16.iter().any(|&s| s <= 0) {
        return Err(Refusal::OutOfRange);
    }
    let declination = Angle(word(10));
    let mut words = [0u32; mission::WORDS];
    for (slot, w) in words.iter_mut().zip(r.iter().skip(HEAD_WORDS)) {
        *slot = *w;
    }
    let mission = Mission::decode(&words).ok_or(Refusal::OutOfRange)?;
    Ok((Settings { left_trim, right_trim, calibration, declination, mission }, sequence))
}

/// `a` was written after `b` (sequence numbers wrap).
fn newer(a: u32, b: u32) -> bool {
    (a.wrapping_sub(b) as i32) > 0
}

pub mod kept_log;
mod store;
pub use store::*;
