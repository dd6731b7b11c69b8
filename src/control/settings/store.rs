//! The flash behind the settings: the [`Flash`] the ROM's routines give,
//! the store that takes the record by turns in two sectors and keeps the
//! on-board log ([`FlashSettings`]), and the stand-ins ([`NoFlash`],
//! [`MemoryFlash`]).

use super::kept_log::{self, KeptLog, LogsFound, LOG_WORDS};
use super::{check, decode, encode, newer, Record, Refusal, Settings, RECORD_WORDS};
use crate::config;
use crate::config::settings::{LOG_SLOTS, SECTORS};
use crate::control::log::RowLog;
use crate::control::protocol::TelemetryRow;

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

/// What a save did (of the settings, or of the log: `sector` is then the
/// log's slot).
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

/// Where the loop keeps what survives power-off, its settings and the
/// on-board log at a mission's end: [`FlashSettings`] over the board's
/// flash, or over [`MemoryFlash`] in tests and the simulator.
pub trait SettingsStore {
    /// Reads both sectors.
    fn load(&mut self) -> Result<Loaded, FlashError>;
    /// Writes `s` as the newest record.
    fn save(&mut self, s: &Settings) -> Result<Saved, FlashError>;
    /// Erases both sectors (back to the config); the pause in us.
    fn forget(&mut self) -> Result<u32, FlashError>;
    /// Keeps `log` (its rows at `hz`) as the newest kept log.
    fn keep_log(&mut self, log: &impl RowLog, hz: u16) -> Result<Saved, FlashError>;
    /// The kept logs' two slots, checked.
    fn kept_logs(&mut self) -> Result<LogsFound, FlashError>;
    /// Row `i` of a kept log (`None` past its end).
    fn kept_row(&mut self, log: &KeptLog, i: usize) -> Result<Option<TelemetryRow>, FlashError>;
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

    fn keep_log(&mut self, log: &impl RowLog, hz: u16) -> Result<Saved, FlashError> {
        kept_log::keep(&mut self.flash, log, hz)
    }

    fn kept_logs(&mut self) -> Result<LogsFound, FlashError> {
        kept_log::find(&mut self.flash)
    }

    fn kept_row(&mut self, log: &KeptLog, i: usize) -> Result<Option<TelemetryRow>, FlashError> {
        kept_log::row(&mut self.flash, log, i)
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
/// up to a record's length and the two log slots up to a full log's (host
/// tests and the simulator); any other address is refused. `power_left`
/// counts the word writes and erases the power lasts for (`None`: for
/// ever): after it runs out every operation fails and changes nothing, as
/// on a board switched off mid-save.
#[derive(Clone, PartialEq, Eq, Debug)]
pub struct MemoryFlash {
    pub sectors: [Record; 2],
    /// The log slots' first [`LOG_WORDS`] words.
    pub logs: [[u32; LOG_WORDS]; 2],
    pub power_left: Option<u32>,
}

impl Default for MemoryFlash {
    /// Erased flash.
    fn default() -> Self {
        MemoryFlash { sectors: [[u32::MAX; RECORD_WORDS]; 2], logs: [[u32::MAX; LOG_WORDS]; 2], power_left: None }
    }
}

impl MemoryFlash {
    /// The modelled words from `addr` to the end of its region (a settings
    /// sector's record, a log slot's log).
    fn words_from(&mut self, addr: u32) -> Result<&mut [u32], FlashError> {
        if addr % 4 != 0 {
            return Err(FlashError::Error);
        }
        let regions = SECTORS
            .iter()
            .zip(self.sectors.iter_mut().map(|r| r.as_mut_slice()))
            .chain(LOG_SLOTS.iter().zip(self.logs.iter_mut().map(|l| l.as_mut_slice())));
        for (&base, words) in regions {
            let offset = (addr.wrapping_sub(base) / 4) as usize;
            if addr >= base && offset < words.len() {
                return words.get_mut(offset..).ok_or(FlashError::Error);
            }
        }
        Err(FlashError::Error)
    }

    /// The `len` modelled words at `addr`.
    fn locate(&mut self, addr: u32, len: usize) -> Result<&mut [u32], FlashError> {
        self.words_from(addr)?.get_mut(..len).ok_or(FlashError::Error)
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
        words.copy_from_slice(self.locate(addr, words.len())?);
        Ok(())
    }
    fn erase_sector(&mut self, addr: u32) -> Result<(), FlashError> {
        let sector_words = (config::settings::SECTOR_BYTES / 4) as usize;
        if addr % config::settings::SECTOR_BYTES != 0 {
            return Err(FlashError::Error);
        }
        self.words_from(addr)?;
        self.power()?;
        self.words_from(addr)?.iter_mut().take(sector_words).for_each(|w| *w = u32::MAX);
        Ok(())
    }
    fn write(&mut self, addr: u32, words: &[u32]) -> Result<(), FlashError> {
        self.locate(addr, words.len())?;
        for (k, &w) in words.iter().enumerate() {
            self.power()?;
            if let Some(s) = self.locate(addr, words.len())?.get_mut(k) {
                *s &= w; // NOR flash: a write only clears bits
            }
        }
        Ok(())
    }
    fn now_us(&self) -> u32 {
        0
    }
}
