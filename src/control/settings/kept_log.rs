//! The on-board log kept in flash at a mission's end, so that a power-off
//! after the mission keeps it (`dump` then reads it).
//!
//! A kept log is a header of [`HEAD_WORDS`] words (the magic word, the
//! format version [`config::settings::LOG_VERSION`], a sequence number,
//! the rows, the rows dropped, the log's rate and a CRC-32 of the header's
//! other words and the rows), then the rows oldest first,
//! [`ROW_WORDS`] words each (`LogRow::to_words`). Two slots of three
//! sectors ([`config::settings::LOG_SLOTS`]) take it by turns as the
//! settings' two sectors do: the slot without the newest valid log is
//! erased and written, rows first and the magic word last, so a power cut
//! keeps the older log.
//!
//! Nothing here holds the log twice: the rows go from the RAM ring to the
//! flash through a stack buffer of `ROWS_PER_WRITE` rows (240 bytes,
//! within one 256-byte flash page program), and are read back one at a
//! time.

use super::{newer, Crc32, Flash, FlashError, Refusal, Saved};
use crate::config;
use crate::config::settings::{LOG_SLOTS, LOG_SLOT_SECTORS, LOG_VERSION, SECTOR_BYTES};
use crate::control::log::{LogRow, RowLog, ROW_WORDS};
use crate::control::protocol::TelemetryRow;

/// "PBLG": paperbot log.
const MAGIC: u32 = 0x5042_4C47;
/// Words before the rows: magic, version, sequence, rows, dropped, rate, CRC.
pub const HEAD_WORDS: usize = 7;
/// Words a kept log of `config::log::ROWS` rows takes at most.
pub const LOG_WORDS: usize = HEAD_WORDS + config::log::ROWS * ROW_WORDS;
const _: () = assert!(LOG_WORDS * 4 <= (LOG_SLOT_SECTORS * SECTOR_BYTES) as usize);
/// Rows a flash write takes (the stack buffer).
const ROWS_PER_WRITE: usize = 4;

/// A valid kept log's header.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub struct KeptLog {
    /// Where its slot begins.
    pub slot: u32,
    pub sequence: u32,
    pub rows: u32,
    /// Rows the ring dropped (full) during its mission.
    pub dropped: u32,
    /// The log's rate, rows per second.
    pub hz: u16,
}

/// What the two slots hold.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub struct LogsFound {
    /// The newer valid log, if any.
    pub newest: Option<KeptLog>,
    /// Each slot's refusal (`None`: a valid log), in [`LOG_SLOTS`] order.
    pub refused: [Option<Refusal>; 2],
}

/// The address of row `i` of the log in `slot`.
fn row_addr(slot: u32, i: usize) -> u32 {
    let word = HEAD_WORDS.saturating_add(i.saturating_mul(ROW_WORDS)); // <= LOG_WORDS
    slot.wrapping_add((word as u32).wrapping_mul(4))
}

/// The log in `slot` if valid (magic, version, row count, CRC), or why not.
pub fn check<F: Flash>(flash: &mut F, slot: u32) -> Result<Result<KeptLog, Refusal>, FlashError> {
    let mut head = [0u32; HEAD_WORDS];
    flash.read(slot, &mut head)?;
    let [magic, version, sequence, rows, dropped, hz, crc] = head;
    let refusal = if head.iter().all(|&w| w == u32::MAX) {
        Some(Refusal::Blank)
    } else if magic == u32::MAX {
        Some(Refusal::Unfinished)
    } else if magic != MAGIC {
        Some(Refusal::NotARecord)
    } else if version != LOG_VERSION {
        Some(Refusal::OtherVersion(version))
    } else if rows as usize > config::log::ROWS || hz > u32::from(u16::MAX) {
        Some(Refusal::OutOfRange)
    } else {
        None
    };
    if let Some(r) = refusal {
        return Ok(Err(r));
    }
    let mut digest = Crc32::new();
    digest.update(&[version, sequence, rows, dropped, hz]);
    let mut row = [0u32; ROW_WORDS];
    for i in 0..rows as usize {
        flash.read(row_addr(slot, i), &mut row)?;
        digest.update(&row);
    }
    if digest.finish() != crc {
        return Ok(Err(Refusal::Damaged));
    }
    let hz = hz as u16; // <= u16::MAX, checked above
    Ok(Ok(KeptLog { slot, sequence, rows, dropped, hz }))
}

/// Both slots, checked.
pub fn find<F: Flash>(flash: &mut F) -> Result<LogsFound, FlashError> {
    let mut found = LogsFound { newest: None, refused: [None; 2] };
    for (&slot, refused) in LOG_SLOTS.iter().zip(found.refused.iter_mut()) {
        match check(flash, slot)? {
            Ok(log) => {
                if found.newest.is_none_or(|best| newer(log.sequence, best.sequence)) {
                    found.newest = Some(log);
                }
            }
            Err(r) => *refused = Some(r),
        }
    }
    Ok(found)
}

/// Row `i` of a kept log (`None` past its end).
pub fn row<F: Flash>(flash: &mut F, log: &KeptLog, i: usize) -> Result<Option<TelemetryRow>, FlashError> {
    if i >= log.rows as usize {
        return Ok(None);
    }
    let mut words = [0u32; ROW_WORDS];
    flash.read(row_addr(log.slot, i), &mut words)?;
    Ok(Some(LogRow::from_words(&words).unpack()))
}

/// Keeps `log` (its rows at `hz`) in the slot without the newest valid
/// log: erase, rows, header, magic word last; then checks it back.
pub fn keep<F: Flash>(flash: &mut F, log: &impl RowLog, hz: u16) -> Result<Saved, FlashError> {
    let found = find(flash)?;
    let [a, b] = LOG_SLOTS;
    let (slot, sequence) = match found.newest {
        Some(n) if n.slot == a => (b, n.sequence.wrapping_add(1)),
        Some(n) => (a, n.sequence.wrapping_add(1)),
        None => (a, 1),
    };
    let rows = log.len().min(config::log::ROWS);
    let start = flash.now_us();
    for k in 0..LOG_SLOT_SECTORS {
        flash.erase_sector(slot.wrapping_add(k.wrapping_mul(SECTOR_BYTES)))?;
    }
    let head = [LOG_VERSION, sequence, rows as u32, log.dropped(), u32::from(hz)];
    let mut digest = Crc32::new();
    digest.update(&head);
    let mut buf = [0u32; ROWS_PER_WRITE * ROW_WORDS];
    let mut first = 0;
    while first < rows {
        let n = rows.saturating_sub(first).min(ROWS_PER_WRITE);
        for (k, chunk) in buf.chunks_exact_mut(ROW_WORDS).take(n).enumerate() {
            let words = log.row(first.saturating_add(k)).map(|r| LogRow::pack(&r).to_words());
            chunk.copy_from_slice(&words.ok_or(FlashError::Error)?);
        }
        let filled = buf.get(..n.saturating_mul(ROW_WORDS)).ok_or(FlashError::Error)?;
        digest.update(filled);
        flash.write(row_addr(slot, first), filled)?;
        first = first.saturating_add(n);
    }
    let [version, seq, count, dropped, rate] = head;
    flash.write(slot.wrapping_add(4), &[version, seq, count, dropped, rate, digest.finish()])?;
    flash.write(slot, &[MAGIC])?;
    let pause_us = flash.now_us().wrapping_sub(start);
    match check(flash, slot)? {
        Ok(kept) if kept.sequence == sequence => Ok(Saved { sector: slot, sequence, pause_us }),
        _ => Err(FlashError::Error), // a write the chip did not take
    }
}
