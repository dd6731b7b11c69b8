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
//! simulator.

use crate::config;
use crate::config::settings::{SECTORS, VERSION};
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

/// CRC-32 (ISO-HDLC, the zlib/Ethernet one) of the words' little-endian
/// bytes, bitwise: no table in DRAM, about 350 bytes a save or a boot.
fn crc32(words: &[u32]) -> u32 {
    const CRC: crc::Crc<u32, crc::NoTable> = crc::Crc::<u32, crc::NoTable>::new(&crc::CRC_32_ISO_HDLC);
    let mut digest = CRC.digest();
    for w in words {
        digest.update(&w.to_le_bytes());
    }
    digest.finalize()
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

// ---- the flash ----------------------------------------------------------

/// A flash operation failed: the ROM's `SpiFlashOpResult` (ERR, TIMEOUT)
/// or an address the routines refuse.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum FlashError {
    /// SPI_FLASH_RESULT_ERR, or an unaligned or out-of-range address.
    Error,
    /// SPI_FLASH_RESULT_TIMEOUT.
    Timeout,
}

/// The flash as the ESP8266 ROM's routines give it (SPIRead, SPIWrite,
/// SPIEraseSector): addresses and lengths in words, 4-byte aligned; an
/// erase sets a whole sector's bits; a write can only clear bits.
pub trait Flash {
    fn read(&mut self, addr: u32, words: &mut [u32]) -> Result<(), FlashError>;
    /// Erases the sector at `addr` (a multiple of the sector size).
    fn erase_sector(&mut self, addr: u32) -> Result<(), FlashError>;
    fn write(&mut self, addr: u32, words: &[u32]) -> Result<(), FlashError>;
    /// A free-running microsecond clock (wrapping), to measure the pause.
    fn now_us(&self) -> u32;
}

/// What a save did.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub struct Saved {
    /// The sector written.
    pub sector: u32,
    pub sequence: u32,
    /// How long the erase and the write kept the loop waiting, us.
    pub pause_us: u32,
}

/// What the two sectors held at boot.
#[derive(Clone, PartialEq, Eq, Debug)]
pub struct Loaded {
    /// The newer valid record, if any, and its sector.
    pub newest: Option<(Settings, u32)>,
    /// Each sector's refusal (`None`: a valid record), in [`SECTORS`] order.
    pub refused: [Option<Refusal>; 2],
}

/// Where the loop keeps its settings: [`FlashSettings`] over the board's
/// flash, or over [`MemoryFlash`] in tests and the simulator.
pub trait SettingsStore {
    /// Reads both sectors.
    fn load(&mut self) -> Result<Loaded, FlashError>;
    /// Writes `s` as the newest record.
    fn save(&mut self, s: &Settings) -> Result<Saved, FlashError>;
    /// Erases both sectors (back to the config); the pause in us.
    fn forget(&mut self) -> Result<u32, FlashError>;
}

/// The record in two sectors of a [`Flash`], written by turns (see the
/// module docs).
pub struct FlashSettings<F: Flash> {
    pub flash: F,
}

impl<F: Flash + Default> Default for FlashSettings<F> {
    fn default() -> Self {
        FlashSettings::new(F::default())
    }
}

impl<F: Flash> FlashSettings<F> {
    pub const fn new(flash: F) -> Self {
        FlashSettings { flash }
    }

    fn read(&mut self, sector: u32) -> Result<Record, FlashError> {
        let mut r = [0u32; RECORD_WORDS];
        self.flash.read(sector, &mut r)?;
        Ok(r)
    }
}

impl<F: Flash> SettingsStore for FlashSettings<F> {
    fn load(&mut self) -> Result<Loaded, FlashError> {
        let mut loaded = Loaded { newest: None, refused: [None; 2] };
        for (&sector, refused) in SECTORS.iter().zip(loaded.refused.iter_mut()) {
            match decode(&self.read(sector)?) {
                Ok((s, seq)) => {
                    if loaded.newest.as_ref().is_none_or(|(_, best)| newer(seq, *best)) {
                        loaded.newest = Some((s, seq));
                    }
                }
                Err(e) => *refused = Some(e),
            }
        }
        Ok(loaded)
    }

    fn save(&mut self, s: &Settings) -> Result<Saved, FlashError> {
        // the sector without the newest valid record gets the next number
        let [a, b] = SECTORS;
        let (seq_a, seq_b) = (check(&self.read(a)?).ok(), check(&self.read(b)?).ok());
        let (sector, sequence) = match (seq_a, seq_b) {
            (Some(x), Some(y)) if newer(y, x) => (a, y.wrapping_add(1)),
            (Some(x), _) => (b, x.wrapping_add(1)),
            (None, Some(y)) => (a, y.wrapping_add(1)),
            (None, None) => (a, 1),
        };
        let record = encode(s, sequence);
        let start = self.flash.now_us();
        self.flash.erase_sector(sector)?;
        // the magic word last: a write cut short is no record
        let (magic, body) = record.split_first().ok_or(FlashError::Error)?;
        self.flash.write(sector.wrapping_add(4), body)?;
        self.flash.write(sector, &[*magic])?;
        let pause_us = self.flash.now_us().wrapping_sub(start);
        // read back: a write the chip did not take is no save
        if check(&self.read(sector)?) != Ok(sequence) {
            return Err(FlashError::Error);
        }
        Ok(Saved { sector, sequence, pause_us })
    }

    fn forget(&mut self) -> Result<u32, FlashError> {
        let start = self.flash.now_us();
        for sector in SECTORS {
            self.flash.erase_sector(sector)?;
        }
        Ok(self.flash.now_us().wrapping_sub(start))
    }
}

/// A board without settings storage: zero-sized (as the firmware's
/// `board::rom_flash::RomFlash`, so a controller over it has the robot's
/// layout: the lx106 probes), every operation refused.
#[derive(Clone, Copy, Default, Debug)]
pub struct NoFlash;

impl Flash for NoFlash {
    fn read(&mut self, _addr: u32, _words: &mut [u32]) -> Result<(), FlashError> {
        Err(FlashError::Error)
    }
    fn erase_sector(&mut self, _addr: u32) -> Result<(), FlashError> {
        Err(FlashError::Error)
    }
    fn write(&mut self, _addr: u32, _words: &[u32]) -> Result<(), FlashError> {
        Err(FlashError::Error)
    }
    fn now_us(&self) -> u32 {
        0
    }
}

/// Flash in memory with NOR semantics, modelling the two settings sectors
/// up to a record's length (host tests and the simulator). `power_left`
/// counts the word writes and erases the power lasts for (`None`: for
/// ever): after it runs out every operation fails and changes nothing, as
/// on a board switched off mid-save.
#[derive(Clone, PartialEq, Eq, Debug)]
pub struct MemoryFlash {
    pub sectors: [Record; 2],
    pub power_left: Option<u32>,
}

impl Default for MemoryFlash {
    /// Erased flash.
    fn default() -> Self {
        MemoryFlash { sectors: [[u32::MAX; RECORD_WORDS]; 2], power_left: None }
    }
}

impl MemoryFlash {
    /// The modelled sector at `addr` and the word index in it.
    fn locate(&mut self, addr: u32, len: usize) -> Result<(&mut Record, usize), FlashError> {
        let sector_bytes = config::settings::SECTOR_BYTES;
        let base = addr.wrapping_sub(addr % sector_bytes); // <= addr
        let i = SECTORS.iter().position(|&s| s == base).ok_or(FlashError::Error)?;
        let offset = (addr.wrapping_sub(base) / 4) as usize;
        if addr % 4 != 0 || offset.saturating_add(len) > RECORD_WORDS {
            return Err(FlashError::Error);
        }
        Ok((self.sectors.get_mut(i).ok_or(FlashError::Error)?, offset))
    }

    /// One more operation on the power left.
    fn power(&mut self) -> Result<(), FlashError> {
        match &mut self.power_left {
            Some(0) => Err(FlashError::Timeout),
            Some(n) => {
                *n = n.saturating_sub(1);
                Ok(())
            }
            None => Ok(()),
        }
    }
}

impl Flash for MemoryFlash {
    fn read(&mut self, addr: u32, words: &mut [u32]) -> Result<(), FlashError> {
        let (sector, offset) = self.locate(addr, words.len())?;
        for (w, s) in words.iter_mut().zip(sector.iter().skip(offset)) {
            *w = *s;
        }
        Ok(())
    }
    fn erase_sector(&mut self, addr: u32) -> Result<(), FlashError> {
        if addr % config::settings::SECTOR_BYTES != 0 {
            return Err(FlashError::Error);
        }
        self.locate(addr, 0)?;
        self.power()?;
        self.locate(addr, 0)?.0.fill(u32::MAX);
        Ok(())
    }
    fn write(&mut self, addr: u32, words: &[u32]) -> Result<(), FlashError> {
        self.locate(addr, words.len())?;
        for (k, &w) in words.iter().enumerate() {
            self.power()?;
            let (sector, offset) = self.locate(addr, words.len())?;
            if let Some(s) = sector.get_mut(offset.saturating_add(k)) {
                *s &= w; // NOR flash: a write only clears bits
            }
        }
        Ok(())
    }
    fn now_us(&self) -> u32 {
        0
    }
}
