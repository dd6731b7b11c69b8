//! The ESP8266 board layer: what turns the control loop into firmware.
//!
//! Everything that can be reasoned about without the chip is here, compiled
//! and tested on every target:
//! - [`bitbang_i2c`]: the I2C master (embedded-hal 1.0 `I2c`) over two
//!   open-drain GPIOs, fast mode, clock stretching, bus recovery;
//! - [`servo_pulse`]: the FRC1 servo-pulse schedule (latency-independent
//!   edges) and the CAS-free loop-to-interrupt handoff of pulse widths;
//! - [`uart`]: the UART0 baud divider.
//!
//! The board holds no simulator code: `tests/drivers/bitbang_i2c.rs` runs the
//! master cycle by cycle on the simulator's wire (`sim::wire`, the one wire
//! model, which the emulated board drives too).
//!
//! The chip glue, [`esp8266`](self) (`esp8266.rs`), exists only for
//! `target_arch = "xtensa"` with the `board` feature: esp8266-hal pins as
//! [`bitbang_i2c::I2cPins`], the FRC1 interrupt, UART0, watchdog and LED;
//! [`halt`](self) (`halt.rs`) stops for good, the panic handler too; [`rtc_store`](self) (`rtc_store.rs`) keeps a mission in
//! RTC memory across resets; [`rom_flash`](self) (`rom_flash.rs`) reaches
//! the settings sectors through the ROM's flash routines. The firmware
//! binary is `src/bin/firmware.rs`.

pub mod bitbang_i2c;
pub mod servo_pulse;
pub mod uart;

#[cfg(all(target_arch = "xtensa", feature = "board"))]
pub mod esp8266;
/// Halt and the panic handler (see the file).
#[cfg(all(target_arch = "xtensa", feature = "board"))]
pub mod halt;
/// The settings sectors through the ROM's flash routines (see the file).
#[cfg(all(target_arch = "xtensa", feature = "board"))]
pub mod rom_flash;
/// The mission store in RTC memory (see the file).
#[cfg(all(target_arch = "xtensa", feature = "board"))]
pub mod rtc_store;
