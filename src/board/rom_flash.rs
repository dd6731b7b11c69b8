//! The flash's settings sectors on the robot: [`RomFlash`], the ESP8266
//! ROM's SPI flash routines (`control::settings::Flash`).
//!
//! The routines (SPIRead, SPIWrite, SPIEraseSector; their addresses from
//! Espressif's eagle.rom.addr.v6.ld, in rom-functions.x) talk to the flash
//! chip through SPI0, which the flash cache also uses: while they run the
//! cache must be off, so nothing may be fetched from flash meanwhile, code
//! or constants. Hence each call goes through one `#[ram]` function that
//! turns the cache off, calls the ROM and turns it on again, touching only
//! registers, its arguments and the caller's buffer (on the stack, in
//! DRAM). The cache switch is the one esp8266-hal's `CachePauseGuard`
//! writes (DPORT SPI_CACHE bit 8, SPI0 CTRL's AHB enable, bit 17, after the
//! SPI0 state machine is idle). Interrupts stay on: the FRC1 servo
//! interrupt is in IRAM (the image's checks) and keeps its pulses. The
//! watchdog is fed before and after each operation (a sector erase takes
//! up to 400 ms, W25Q32 datasheet, against `config::board::WATCHDOG_MS`).
//! The pause is measured with CCOUNT.
//!
//! Why not esp8266-hal's `ESPFlash`: its `erase_sectors` steps the address
//! by one byte per sector and enables writes once for all sectors, and its
//! generic helpers (`chunks`, `align_to`) may be placed in flash, where
//! they cannot run with the cache off.

use esp8266_hal::ram;

use crate::config;
use crate::control::settings::{Flash, FlashError};

extern "C" {
    fn SPIRead(addr: u32, dst: *mut u32, size: u32) -> u32;
    fn SPIWrite(addr: u32, src: *const u32, size: u32) -> u32;
    fn SPIEraseSector(sector: u32) -> u32;
}

/// DPORT SPI_CACHE (PAC: `spi_cache`), bit 8: the flash cache.
const DPORT_SPI_CACHE: *mut u32 = 0x3FF0_000C as *mut u32;
const CACHE_ENABLE: u32 = 1 << 8;
/// SPI0 CTRL (`spi_ctrl`), bit 17: AHB (cache) access to the flash.
const SPI0_CTRL: *mut u32 = 0x6000_0208 as *mut u32;
const ENABLE_AHB: u32 = 1 << 17;
/// SPI0 EXT2 (`spi_ext2`): the SPI state machine, 0 when idle.
const SPI0_EXT2: *const u32 = 0x6000_02F8 as *const u32;
/// The hardware watchdog's feed register and value (esp8266-hal's `feed`).
const WDT_RST: *mut u32 = 0x6000_0914 as *mut u32;
const WDT_FEED: u32 = 0x73;

/// Which ROM routine [`with_cache_off`] calls.
#[derive(Clone, Copy)]
enum Op {
    Read,
    Write,
    Erase,
}

/// Calls one ROM flash routine with the flash cache off (see the module
/// docs): in IRAM, and so is everything it calls (ROM routines).
#[ram] // out of line in IRAM (the attribute's section)
fn with_cache_off(op: Op, addr: u32, buf: *mut u32, size: u32) -> u32 {
    // SAFETY: fixed registers of the chip; the caller's buffer is valid
    // for `size` bytes (RomFlash's methods); nothing here is in flash.
    unsafe {
        core::ptr::write_volatile(WDT_RST, WDT_FEED);
        let cache = core::ptr::read_volatile(DPORT_SPI_CACHE);
        core::ptr::write_volatile(DPORT_SPI_CACHE, cache & !CACHE_ENABLE);
        while core::ptr::read_volatile(SPI0_EXT2) != 0 {}
        let ctrl = core::ptr::read_volatile(SPI0_CTRL);
        core::ptr::write_volatile(SPI0_CTRL, ctrl & !ENABLE_AHB);
        let result = match op {
            Op::Read => SPIRead(addr, buf, size),
            Op::Write => SPIWrite(addr, buf, size),
            Op::Erase => SPIEraseSector(addr / config::settings::SECTOR_BYTES),
        };
        let ctrl = core::ptr::read_volatile(SPI0_CTRL);
        core::ptr::write_volatile(SPI0_CTRL, ctrl | ENABLE_AHB);
        let cache = core::ptr::read_volatile(DPORT_SPI_CACHE);
        core::ptr::write_volatile(DPORT_SPI_CACHE, cache | CACHE_ENABLE);
        core::ptr::write_volatile(WDT_RST, WDT_FEED);
        result
    }
}

/// SpiFlashOpResult: 0 OK, 1 ERR, 2 TIMEOUT.
fn result(r: u32) -> Result<(), FlashError> {
    match r {
        0 => Ok(()),
        2 => Err(FlashError::Timeout),
        _ => Err(FlashError::Error),
    }
}

/// The flash through the ROM's routines (see the module docs).
#[derive(Clone, Copy, Default, Debug)]
pub struct RomFlash;

/// Bytes of `words`, if they fit a u32.
fn bytes(words: usize) -> Result<u32, FlashError> {
    u32::try_from(words.saturating_mul(4)).map_err(|_| FlashError::Error)
}

impl Flash for RomFlash {
    fn read(&mut self, addr: u32, words: &mut [u32]) -> Result<(), FlashError> {
        let size = bytes(words.len())?;
        result(with_cache_off(Op::Read, addr, words.as_mut_ptr(), size))
    }
    fn erase_sector(&mut self, addr: u32) -> Result<(), FlashError> {
        if addr % config::settings::SECTOR_BYTES != 0 {
            return Err(FlashError::Error);
        }
        result(with_cache_off(Op::Erase, addr, core::ptr::null_mut(), 0))
    }
    fn write(&mut self, addr: u32, words: &[u32]) -> Result<(), FlashError> {
        let size = bytes(words.len())?;
        // SPIWrite only reads the buffer
        result(with_cache_off(Op::Write, addr, words.as_ptr().cast_mut(), size))
    }
    fn now_us(&self) -> u32 {
        xtensa_lx::timer::get_cycle_count() / (config::board::CPU_HZ / 1_000_000)
    }
}
