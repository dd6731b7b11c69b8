//! Stopping for good (xtensa + `board` feature only): [`halt`] and the
//! panic handler stop the servo pulses, say why on UART0, release the
//! strapping pins and reset through the watchdog.

use core::fmt::Write as _;

use esp8266_hal::prelude::*;
use esp8266_hal::target::{self as pac, Peripherals};
use esp8266_hal::watchdog::StageTimeout;

use super::esp8266::stop_servo_pulses;
use crate::config;

/// The strapping pins the lidars' XSHUT lines share: GPIO0 low at a reset
/// starts the ROM's UART download mode instead of the flash (ESP8266 boot
/// modes: GPIO15, GPIO0, GPIO2 = 0, 1, 1 boots from flash).
const STRAPPING_MASK: u32 = (1 << config::pins::FRONT_XSHUT_GPIO) | (1 << config::pins::RIGHT_XSHUT_GPIO);

/// UART0 written straight through the FIFO register, for [`halt`] (the
/// `UART0Serial` may be borrowed by the interrupted code).
struct HaltUart;

impl core::fmt::Write for HaltUart {
    fn write_str(&mut self, s: &str) -> core::fmt::Result {
        // SAFETY: the code that owned UART0 will never run again; we only
        // append bytes to the TX FIFO.
        let uart = unsafe { &*pac::UART0::ptr() };
        for &b in s.as_bytes() {
            // bounded wait for FIFO room (128 bytes; ~11 ms to drain at 115200)
            let start = xtensa_lx::timer::get_cycle_count();
            while uart.uart_status.read().txfifo_cnt().bits() >= 127 {
                if xtensa_lx::timer::get_cycle_count().wrapping_sub(start) > config::board::CPU_HZ / 10 {
                    return Err(core::fmt::Error);
                }
            }
            #[allow(unused_unsafe)]
            uart.uart_fifo.write(|w| unsafe { w.rxfifo_write_byte().bits(b) });
        }
        Ok(())
    }
}

/// Releases the strapping pins GPIO0 and GPIO2 (the lidars' XSHUT lines):
/// inputs with the internal pull-up on, so that the reset which follows
/// boots from flash (a lidar held in reset keeps its XSHUT low otherwise,
/// and GPIO0 low at a reset means UART download mode: a robot dead until
/// power-cycled). Before any reset the firmware causes.
pub fn release_strapping_pins() {
    // SAFETY: called only on the way to a reset: the XSHUT pins' owners
    // never run again; single writes of the enable strobe and IO_MUX.
    let dp = unsafe { Peripherals::steal() };
    #[allow(unused_unsafe)]
    dp.GPIO.gpio_enable_w1tc.write(|w| unsafe { w.bits(STRAPPING_MASK) });
    dp.IO_MUX.io_mux_gpio0.modify(|_, w| w.pullup().set_bit());
    dp.IO_MUX.io_mux_gpio2.modify(|_, w| w.pullup().set_bit());
}

/// Stops the robot for good, without panicking: servo pulses off first,
/// then `why` on UART0 (`!` line), then the strapping pins released, then
/// a watchdog reset. For what the firmware cannot go on from: the panic
/// handler, a failed bring-up.
pub fn halt(why: core::fmt::Arguments<'_>) -> ! {
    // 1. wheels first
    stop_servo_pulses();
    // 2. say why
    let _ = write!(HaltUart, "\r\n!{}\r\n", why);
    // 3. boot from flash after the reset
    release_strapping_pins();
    // 4. reset: arm the watchdog at its shortest stages and never feed it
    // SAFETY: nothing else runs any more (the servo interrupt is masked and
    // the caller never gets control back).
    let dp = unsafe { Peripherals::steal() };
    let mut wdt = dp.WDT.watchdog();
    wdt.start((StageTimeout::Stage084Sec, StageTimeout::Stage084Sec));
    loop {
        core::hint::spin_loop();
    }
}

#[panic_handler]
fn panic(info: &core::panic::PanicInfo) -> ! {
    halt(format_args!("panic {}", info))
}
