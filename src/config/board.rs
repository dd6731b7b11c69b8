//! The ESP8266 itself: clocks, the servo timer and the watchdog (used by
//! `board`; the numbers are the chip's, from the ESP8266 Technical Reference).

/// CPU clock, Hz: the ESP8266 runs at 80 MHz after the HAL's PLL setup;
/// CCOUNT counts CPU cycles.
pub const CPU_HZ: u32 = 80_000_000;
/// APB clock that feeds UART0 and FRC1, Hz (80 MHz, Technical Reference 11.3).
pub const APB_HZ: u32 = 80_000_000;
/// FRC1 prescaler for the servo pulses: 16, so one tick is 0.2 us
/// (5 ticks per us) and the 23-bit counter spans 1.67 s.
pub const FRC1_PRESCALER: u32 = 16;
/// The FRC1 interrupt is raised this long before each servo edge; the
/// handler then spins on CCOUNT to the exact cycle, so any interrupt latency below
/// this does not move the edge, us. 20 us covers the vector entry and a
/// flash-cache miss in another interrupt (a few us) with margin.
pub const SERVO_EDGE_GUARD_US: u32 = 20;
/// The right servo's pulse starts this long after the left one's, us:
/// the pulses never overlap (max pulse 2300 us) and the two servos'
/// current surges are apart.
pub const SERVO_STAGGER_US: u32 = 2_600;
/// Hardware watchdog timeout, ms: the loop (100 Hz) feeds it every tick.
pub const WATCHDOG_MS: u32 = 1_680;
/// LED heartbeat: half period while running normally, ms.
pub const LED_BLINK_OK_MS: u32 = 500;
/// LED half period while a sensor is down (`src/bin/firmware.rs`), ms.
pub const LED_BLINK_FAULT_MS: u32 = 100;
/// At start, a servo pulse frame (20 ms, after a 1 ms start delay) must
/// have completed this long after the servo timer started, or the FRC1
/// interrupt is reported not running, ms (issue 28).
pub const SERVO_TIMER_CHECK_MS: u32 = 50;
/// Room the firmware's worst-case stack depth must leave above the ROM's
/// flash parameters, bytes: `cargo fw-image` bounds the depth from the
/// image (xtask/src/stack.rs) and fails the build when it comes closer to
/// them than this.
pub const STACK_MARGIN_BYTES: u32 = 256;
