//! Settings kept in flash (`control::settings`): where the record lives
//! and what it holds. `src/config/` stays the defaults; the record holds
//! what the robot learned since (`save`, `forget`, `settings`).
//!
//! The flash map of a 4 MB module (ESP-12F, NodeMCU), 4 KiB sectors:
//! - 0x000000..0x010000: the boot image (IRAM/DRAM segments, `cargo fw-image`);
//! - 0x010000..0x110000: the flash-mapped code and constants (memory.x's
//!   `irom_seg`, the cache's 1 MiB window);
//! - 0x3F3000..0x3F9000: the on-board log kept at a mission's end, two
//!   slots of three sectors taken by turns ([`LOG_SLOTS`]);
//! - 0x3F9000, 0x3FA000: the two settings sectors ([`SECTORS`]);
//! - 0x3FB000..0x400000: the NONOS SDK's data sectors, kept free so that an
//!   SDK-built program flashed later finds them as it expects: RF_CAL at
//!   sector total - 5 (`user_rf_cal_sector_set` in Espressif's examples,
//!   0x3FB000), esp_init_data_default at 0x3FC000, the system parameters
//!   at 0x3FD000..0x3FFFFF (Espressif, "ESP8266 Flash RW Operation" and the
//!   SDK's download addresses: blank.bin at 0x3FE000). The esp8266 Arduino
//!   core's map for 4 MB puts rf_cal/phy_data/system_parameter at the same
//!   places (`user_pre_init`).
//!
//! `cargo fw-image` checks that the image's flash-mapped code ends before
//! [`FIRST_SECTOR`], the log's first slot.

/// The flash chip's size, bytes (the module's 4 MB; `cargo fw-flash`
/// writes 4MB into the image header).
pub const FLASH_BYTES: u32 = 0x40_0000;
/// A flash sector, the unit of erase, bytes (SPIEraseSector).
pub const SECTOR_BYTES: u32 = 0x1000;
/// Where the SDK's data sectors begin (RF_CAL: sector total - 5).
pub const SDK_DATA_START: u32 = FLASH_BYTES - 5 * SECTOR_BYTES;
/// The two sectors the record is written to by turns, just below the SDK's.
pub const SECTORS: [u32; 2] = [SDK_DATA_START - 2 * SECTOR_BYTES, SDK_DATA_START - SECTOR_BYTES];
/// Sectors of one log slot: a header and `config::log::ROWS` rows of 60
/// bytes (12,032 bytes of 12,288; asserted in `control::settings`).
pub const LOG_SLOT_SECTORS: u32 = 3;
/// The two slots the on-board log is kept in by turns at a mission's end,
/// just below the settings sectors.
pub const LOG_SLOTS: [u32; 2] =
    [SECTORS[0] - 2 * LOG_SLOT_SECTORS * SECTOR_BYTES, SECTORS[0] - LOG_SLOT_SECTORS * SECTOR_BYTES];
/// The lowest sector this firmware writes (the image must end before it).
pub const FIRST_SECTOR: u32 = LOG_SLOTS[0];
/// The record's format version: a record of another version is ignored
/// (with a line saying so) and the config used. Raise it whenever the
/// layout in `control::settings` changes.
pub const VERSION: u32 = 1;
/// The kept log's format version (its header and `control::log::LogRow`'s
/// words): a log of another version is ignored by `dump`, with a line.
pub const LOG_VERSION: u32 = 1;

const _: () = assert!(SECTORS[0] == 0x3F_9000 && SECTORS[1] == 0x3F_A000 && SDK_DATA_START == 0x3F_B000);
const _: () = assert!(LOG_SLOTS[0] == 0x3F_3000 && LOG_SLOTS[1] == 0x3F_6000);
