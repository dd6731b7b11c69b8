//! Settings kept in flash (`control::settings`): where the record lives
//! and what it holds. `src/config/` stays the defaults; the record holds
//! what the robot learned since (`save`, `forget`, `settings`).
//!
//! The flash map of a 4 MB module (ESP-12F, NodeMCU), 4 KiB sectors:
//! - 0x000000..0x010000: the boot image (IRAM/DRAM segments, `cargo fw-image`);
//! - 0x010000..0x110000: the flash-mapped code and constants (memory.x's
//!   `irom_seg`, the cache's 1 MiB window);
//! - 0x3F9000, 0x3FA000: the two settings sectors (here);
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
//! [`FIRST_SECTOR`].

/// The flash chip's size, bytes (the module's 4 MB; `cargo fw-flash`
/// writes 4MB into the image header).
pub const FLASH_BYTES: u32 = 0x40_0000;
/// A flash sector, the unit of erase, bytes (SPIEraseSector).
pub const SECTOR_BYTES: u32 = 0x1000;
/// Where the SDK's data sectors begin (RF_CAL: sector total - 5).
pub const SDK_DATA_START: u32 = FLASH_BYTES - 5 * SECTOR_BYTES;
/// The two sectors the record is written to by turns, just below the SDK's.
pub const SECTORS: [u32; 2] = [SDK_DATA_START - 2 * SECTOR_BYTES, SDK_DATA_START - SECTOR_BYTES];
/// The lower of the two (the image must end before it).
pub const FIRST_SECTOR: u32 = SECTORS[0];
/// The record's format version: a record of another version is ignored
/// (with a line saying so) and the config used. Raise it whenever the
/// layout in `control::settings` changes.
pub const VERSION: u32 = 1;

const _: () = assert!(SECTORS[0] == 0x3F_9000 && SECTORS[1] == 0x3F_A000 && SDK_DATA_START == 0x3F_B000);
