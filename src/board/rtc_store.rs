//! The mission's copy in the ESP8266's RTC memory ([`RtcMissionStore`]).
//!
//! What survives what: RTC memory stays powered through a watchdog reset,
//! a software reset and deep sleep, so a mission uploaded before a crash
//! or a watchdog reset is there at the next boot; the reset button (EXT_RST)
//! resets the digital core and is expected to keep it too (the RTC domain
//! stays powered; not yet checked on the robot). Power-off loses it: at
//! power-on the memory holds garbage, which `Mission::decode`'s magic word
//! and checksum refuse, so the robot boots with no mission. Flash would keep
//! it through power-off, but writing flash needs the SDK's flash routines
//! and stopping the flash cache the loop's code runs from: not done here.
//!
//! The words go at 0x60001200, the start of the 512 bytes of user RTC
//! memory (0x60001200..0x60001400). Espressif's NONOS SDK addresses RTC
//! memory in 4-byte blocks from 0x60001100 and leaves blocks 64..191 to the
//! user (`system_rtc_mem_write`: "des_addr >= 64"; the 256 bytes below are
//! the SDK's system area); the ESP8266 Arduino core's
//! `ESP.rtcUserMemoryWrite` writes block 64 + offset with a 512-byte bound,
//! its eboot keeps its command at 0x60001200. Nothing is linked into
//! `memory.x`'s `rtc_seg`. RTC memory is on the peripheral bus: only 32-bit
//! accesses, hence words and volatile reads and writes.

use crate::control::mission::{MissionStore, WORDS};

/// First word of the user part of RTC memory (SDK block 64).
const RTC_USER_MEMORY: usize = 0x6000_1200;
/// Bytes of it: to 0x60001400 (SDK block 191), the end of RTC memory.
const RTC_USER_BYTES: usize = 512;
const _: () = assert!(WORDS * 4 <= RTC_USER_BYTES);
const _: () = assert!(RTC_USER_MEMORY + RTC_USER_BYTES == 0x6000_1400);

/// The mission store in RTC memory (see the module docs).
pub struct RtcMissionStore;

impl RtcMissionStore {
    fn word(i: usize) -> *mut u32 {
        // i < WORDS: inside the user part (asserted above)
        (RTC_USER_MEMORY as *mut u32).wrapping_add(i)
    }
}

impl MissionStore for RtcMissionStore {
    fn load(&mut self) -> [u32; WORDS] {
        let mut words = [0u32; WORDS];
        for (i, w) in words.iter_mut().enumerate() {
            // SAFETY: a word of RTC user memory, which nothing else uses
            *w = unsafe { core::ptr::read_volatile(Self::word(i)) };
        }
        words
    }

    fn save(&mut self, words: &[u32; WORDS]) {
        for (i, &w) in words.iter().enumerate() {
            // SAFETY: as in `load`
            unsafe { core::ptr::write_volatile(Self::word(i), w) };
        }
    }
}
