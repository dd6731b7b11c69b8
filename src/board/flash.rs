//! The flash's settings sectors on the robot (`control::settings`).
//!
//! Not wired yet (issue 31, layer 3): writing flash on the ESP8266 means
//! calling the ROM's SPIRead / SPIWrite / SPIEraseSector (Espressif's
//! eagle.rom.addr.v6.ld: 0x40004b1c, 0x40004a4c, 0x40004a00) from IRAM with
//! the flash cache off (Cache_Read_Disable 0x400047f0 / Cache_Read_Enable
//! 0x40004678), nothing fetched from flash meanwhile, and the emulated
//! board's ROM implementing those routines. Until then [`NoFlashAccess`]
//! refuses every operation: the firmware says so at boot and `save`
//! answers with the reason; the config's values are used.

use crate::control::settings::{Flash, FlashError};

/// A flash the firmware cannot reach yet (see the module docs).
#[derive(Clone, Copy, Default, Debug)]
pub struct NoFlashAccess;

impl Flash for NoFlashAccess {
    fn read(&mut self, _addr: u32, _words: &mut [u32]) -> Result<(), FlashError> {
        Err(FlashError::NoAccess)
    }
    fn erase_sector(&mut self, _addr: u32) -> Result<(), FlashError> {
        Err(FlashError::NoAccess)
    }
    fn write(&mut self, _addr: u32, _words: &[u32]) -> Result<(), FlashError> {
        Err(FlashError::NoAccess)
    }
    fn now_us(&self) -> u32 {
        0
    }
}
