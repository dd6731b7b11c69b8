//! The ESP8266 glue (xtensa + `board` feature only): esp8266-hal 0.5 pins
//! and peripherals behind the chip-independent parts of [`crate::board`].
//!
//! - I2C: GPIO14 (SDA) / GPIO12 (SCL) open-drain with the internal pull-ups
//!   on, driven by single writes to `GPIO_OUT_W1TS/W1TC` and read from
//!   `GPIO_IN` ([`I2cGpio`]), paced by CCOUNT ([`Ccount`]).
//! - Servos: FRC1 at 80 MHz / 16, edge interrupt; the handler is in IRAM
//!   (`#[ram]`) with the whole scheduler inlined into it, so no flash-cache
//!   miss can delay an edge; widths arrive through [`SERVO_MAILBOX`].
//! - UART0 at [`config::serial::BAUD`]: the divider written through the PAC
//!   (esp8266-hal has no baud API); frame format is the ROM's 8N1.
//! - Watchdog: the hardware WDT, [`config::board::WATCHDOG_MS`].
//! - LED on GPIO16 (active low on the NodeMCU), XSHUT on GPIO0 / GPIO2.
//! - [`take_over_interrupts`]: PS and INTENABLE set by the firmware at start,
//!   whatever the ROM left (it hands over with interrupts masked).
//! - [`halt`] and the panic handler (`halt.rs`): servo pulses off first, then the
//!   message on UART0, then the strapping pins released, then a watchdog
//!   reset.

use core::cell::UnsafeCell;
use core::convert::Infallible;
use core::sync::atomic::{AtomicU32, Ordering};

use embedded_hal_02::digital::v2::OutputPin as OutputPin02;
use esp8266_hal::gpio::{Gpio0, Gpio12, Gpio14, Gpio16, Gpio2, Gpio4, Gpio5, OpenDrain, Output, PushPull};
use esp8266_hal::prelude::*;
use esp8266_hal::target::{self as pac, Peripherals};
use esp8266_hal::time::Milliseconds;
use esp8266_hal::uart::UART0Serial;
use esp8266_hal::watchdog::Watchdog;

use super::bitbang_i2c::{ns_to_cycles, BitBangI2c, CycleClock, I2cPins, Timing};
use super::servo_pulse::{Channel, PulseMailbox, PulseScheduler, PulseTimer, ServoPulses};
use super::uart::UART0_DIVIDER;
use crate::config;

// The pin types below are fixed by the HAL; the config must agree.
const _: () = {
    assert!(config::pins::SDA_GPIO == 14 && config::pins::SCL_GPIO == 12);
    assert!(config::pins::LEFT_SERVO_GPIO == 5 && config::pins::RIGHT_SERVO_GPIO == 4);
    assert!(config::pins::FRONT_XSHUT_GPIO == 0 && config::pins::RIGHT_XSHUT_GPIO == 2);
    assert!(config::pins::LED_GPIO == 16);
};

const SDA_MASK: u32 = 1 << config::pins::SDA_GPIO;
const SCL_MASK: u32 = 1 << config::pins::SCL_GPIO;
const LEFT_SERVO_MASK: u32 = 1 << config::pins::LEFT_SERVO_GPIO;
const RIGHT_SERVO_MASK: u32 = 1 << config::pins::RIGHT_SERVO_GPIO;
/// Interrupt number of FRC1 on the lx106 (esp8266-hal `InterruptType::TIMER1`).
const FRC1_INTERRUPT_MASK: u32 = 1 << 9;

// Upstream rustc has no inline assembly for Xtensa: `cargo fw-image` links
// xtensa/asm/handover.S (and sets this cfg); the esp toolchain
// (`cargo +esp fw-build`) assembles the same three steps inline.
#[cfg(paperbot_asm_objects)]
extern "C" {
    /// xtensa/asm/handover.S: INTENABLE = 0, then PS = UM (INTLEVEL 0,
    /// EXCM clear).
    fn paperbot_interrupt_handover();
}

/// Takes the interrupts over from whatever ran before (the ROM hands over
/// with PS.INTLEVEL high, PS.EXCM set and INTENABLE bits the firmware does
/// not own): every interrupt disabled, then PS at interrupt level 0 with
/// EXCM clear. Each interrupt the firmware owns is enabled by its owner
/// (FRC1: [`ServoTimer::start`]), so INTENABLE holds exactly those bits.
/// Call first thing in `main`.
pub fn take_over_interrupts() {
    // SAFETY: writes INTENABLE and PS only; nothing is enabled yet, so no
    // handler can run between the two writes.
    #[cfg(paperbot_asm_objects)]
    unsafe {
        paperbot_interrupt_handover()
    }
    // SAFETY: as above; the steps of xtensa/asm/handover.S (PS.UM = 0x20).
    #[cfg(not(paperbot_asm_objects))]
    unsafe {
        core::arch::asm!(
            "movi {t}, 0",
            "wsr.intenable {t}",
            "rsync",
            "movi {t}, 0x20",
            "wsr.ps {t}",
            "rsync",
            t = out(reg) _,
            options(nostack)
        )
    }
}

#[inline(always)]
fn gpio() -> &'static pac::gpio::RegisterBlock {
    // SAFETY: the W1TS/W1TC registers are stateless set/clear strobes and
    // GPIO_IN is read-only; each pin is written only by its owner.
    unsafe { &*pac::GPIO::ptr() }
}

#[inline(always)]
fn frc1() -> &'static pac::timer::RegisterBlock {
    // SAFETY: FRC1 belongs to the servo interrupt once `ServoTimer` owns TIMER.
    unsafe { &*pac::TIMER::ptr() }
}

#[inline(always)]
#[allow(unused_unsafe)]
fn gpio_set(mask: u32) {
    gpio().gpio_out_w1ts.write(|w| unsafe { w.bits(mask) });
}

#[inline(always)]
#[allow(unused_unsafe)]
fn gpio_clear(mask: u32) {
    gpio().gpio_out_w1tc.write(|w| unsafe { w.bits(mask) });
}

#[inline(always)]
fn gpio_in(mask: u32) -> bool {
    gpio().gpio_in.read().bits() & mask != 0
}

/// CCOUNT, the CPU cycle counter (80 MHz).
#[derive(Clone, Copy, Debug, Default)]
pub struct Ccount;

impl CycleClock for Ccount {
    #[inline(always)]
    fn now(&mut self) -> u32 {
        xtensa_lx::timer::get_cycle_count()
    }
}

/// Busy-wait delays on CCOUNT (embedded-hal 1.0), for the drivers.
#[derive(Clone, Copy, Debug, Default)]
pub struct CcountDelay;

impl embedded_hal::delay::DelayNs for CcountDelay {
    fn delay_ns(&mut self, ns: u32) {
        // ceil(ns * 80 / 1000): at most 343.6e6 cycles (< 4.3 s of CCOUNT,
        // well inside one wrap), never saturates for the 80 MHz core.
        let cycles = ns_to_cycles(ns, config::board::CPU_HZ);
        let start = xtensa_lx::timer::get_cycle_count();
        while xtensa_lx::timer::get_cycle_count().wrapping_sub(start) < cycles {}
    }
}

/// A microsecond clock from CCOUNT that wraps at 2^32 us (what the control
/// loop's `tick(now_us)` wants). Call [`Self::now_us`] at least every 53 s
/// (one CCOUNT wrap).
#[derive(Debug, Default)]
pub struct MicrosClock {
    last: u32,
    spare_cycles: u32,
    us: u32,
}

impl MicrosClock {
    pub fn new() -> Self {
        Self { last: xtensa_lx::timer::get_cycle_count(), spare_cycles: 0, us: 0 }
    }

    pub fn now_us(&mut self) -> u32 {
        let c = xtensa_lx::timer::get_cycle_count();
        let d = c.wrapping_sub(self.last);
        self.last = c;
        // spare < 80 and d < 2^32 - 80 in any realistic call pattern; saturate anyway.
        let total = self.spare_cycles.saturating_add(d);
        let per_us = config::board::CPU_HZ / 1_000_000;
        self.us = self.us.wrapping_add(total / per_us);
        self.spare_cycles = total % per_us;
        self.us
    }
}

/// The I2C lines: open-drain, so "release" = output latch high.
pub struct I2cGpio {
    _sda: Gpio14<Output<OpenDrain>>,
    _scl: Gpio12<Output<OpenDrain>>,
}

impl I2cGpio {
    pub fn new(sda: Gpio14<Output<OpenDrain>>, scl: Gpio12<Output<OpenDrain>>, iomux: &pac::IO_MUX) -> Self {
        // Internal pull-ups (~30-50 kOhm) as a backstop to the modules' own.
        iomux.io_mux_mtms.modify(|_, w| w.pullup().set_bit()); // GPIO14
        iomux.io_mux_mtdi.modify(|_, w| w.pullup().set_bit()); // GPIO12
        gpio_set(SDA_MASK | SCL_MASK);
        Self { _sda: sda, _scl: scl }
    }
}

impl I2cPins for I2cGpio {
    #[inline(always)]
    fn scl_release(&mut self) {
        gpio_set(SCL_MASK);
    }
    #[inline(always)]
    fn scl_low(&mut self) {
        gpio_clear(SCL_MASK);
    }
    #[inline(always)]
    fn scl_is_high(&mut self) -> bool {
        gpio_in(SCL_MASK)
    }
    #[inline(always)]
    fn sda_release(&mut self) {
        gpio_set(SDA_MASK);
    }
    #[inline(always)]
    fn sda_low(&mut self) {
        gpio_clear(SDA_MASK);
    }
    #[inline(always)]
    fn sda_is_high(&mut self) -> bool {
        gpio_in(SDA_MASK)
    }
}

/// The robot's I2C bus.
pub type I2cBus = BitBangI2c<I2cGpio, Ccount>;

/// An esp8266-hal (embedded-hal 0.2) output pin as an embedded-hal 1.0 one,
/// for the drivers' XSHUT pins.
pub struct Eh1Output<P>(pub P);

impl<P> embedded_hal::digital::ErrorType for Eh1Output<P> {
    type Error = Infallible;
}

impl<P: OutputPin02<Error = Infallible>> embedded_hal::digital::OutputPin for Eh1Output<P> {
    fn set_low(&mut self) -> Result<(), Infallible> {
        self.0.set_low()
    }
    fn set_high(&mut self) -> Result<(), Infallible> {
        self.0.set_high()
    }
}

/// The on-board LED (GPIO16, lit when low).
pub struct Led {
    pin: Gpio16<Output<PushPull>>,
    lit: bool,
}

impl Led {
    pub fn set(&mut self, lit: bool) {
        self.lit = lit;
        // Infallible
        let _ = if lit { self.pin.set_low() } else { self.pin.set_high() };
    }
    pub fn toggle(&mut self) {
        self.set(!self.lit);
    }
}

// ---- servo pulses ---------------------------------------------------------

/// The loop-to-interrupt handoff of the servo pulse widths.
pub static SERVO_MAILBOX: PulseMailbox = PulseMailbox::new();

/// A cell only the FRC1 interrupt touches once the interrupt is enabled.
struct IsrCell<T>(UnsafeCell<T>);
// SAFETY: single core; `ServoTimer::start` writes it before enabling the
// interrupt, afterwards only the (non-reentrant, level-1) handler does.
unsafe impl<T> Sync for IsrCell<T> {}

static SCHEDULER: IsrCell<PulseScheduler> = IsrCell(UnsafeCell::new(PulseScheduler::new()));

/// Pulse frames started so far, as the FRC1 interrupt last saw them: the
/// loop's proof that the interrupt runs ([`ServoTimer::running`]).
static SERVO_FRAMES: AtomicU32 = AtomicU32::new(0);

/// What the scheduler drives: CCOUNT, FRC1_LOAD and the two servo pins.
struct Frc1Hw;

impl PulseTimer for Frc1Hw {
    #[inline(always)]
    fn cycles(&mut self) -> u32 {
        xtensa_lx::timer::get_cycle_count()
    }
    #[inline(always)]
    #[allow(unused_unsafe)]
    fn load(&mut self, ticks: u32) {
        frc1().frc1_load.write(|w| unsafe { w.bits(ticks) });
    }
    #[inline(always)]
    fn set_pin(&mut self, channel: Channel, high: bool) {
        let mask = match channel {
            Channel::Left => LEFT_SERVO_MASK,
            Channel::Right => RIGHT_SERVO_MASK,
        };
        if high {
            gpio_set(mask)
        } else {
            gpio_clear(mask)
        }
    }
}

#[interrupt(timer1)]
#[ram]
fn frc1_servo_edge() {
    frc1().frc1_int.write(|w| w.frc1_int_clr_mask().set_bit());
    // SAFETY: see `IsrCell`: this handler is the only user now.
    let scheduler = unsafe { &mut *SCHEDULER.0.get() };
    scheduler.on_alarm(&mut Frc1Hw, &SERVO_MAILBOX);
    SERVO_FRAMES.store(scheduler.frames(), Ordering::Relaxed);
}

/// Owns FRC1 and the two servo pins while the pulses run.
pub struct ServoTimer {
    _timer: pac::TIMER,
    _left: Gpio5<Output<PushPull>>,
    _right: Gpio4<Output<PushPull>>,
    /// CCOUNT when the timer started.
    started: u32,
}

impl ServoTimer {
    /// Starts the pulses (both off until the loop publishes widths).
    pub fn start(timer: pac::TIMER, left: Gpio5<Output<PushPull>>, right: Gpio4<Output<PushPull>>) -> Self {
        SERVO_MAILBOX.publish(crate::driver::servo::PulseWidthUs::OFF, crate::driver::servo::PulseWidthUs::OFF);
        timer.frc1_ctrl.write(|w| {
            w.timer_enable().set_bit().prescale_divider().devided_by_16().interrupt_type().edge().rollover().clear_bit()
        });
        timer.frc1_int.write(|w| w.frc1_int_clr_mask().set_bit());
        // SAFETY: DPORT edge-interrupt enable, one bit read-modify-written
        // before the interrupt is on.
        let dport = unsafe { &*pac::DPORT::ptr() };
        dport.edge_int_enable.modify(|_, w| w.timer1_edge_int_enable().set_bit());
        SERVO_FRAMES.store(0, Ordering::Relaxed);
        let started = xtensa_lx::timer::get_cycle_count();
        // SAFETY: the interrupt is not enabled yet: no other user.
        unsafe { (*SCHEDULER.0.get()).start(&mut Frc1Hw) };
        esp8266_hal::interrupt::enable_interrupt(esp8266_hal::interrupt::InterruptType::TIMER1);
        Self { _timer: timer, _left: left, _right: right, started }
    }

    /// Waits until a pulse frame has completed (the second one started),
    /// at most [`config::board::SERVO_TIMER_CHECK_MS`] after the start; false
    /// if none did: the FRC1 interrupt does not run, and the pulses are
    /// stopped (both pins low, [`stop_servo_pulses`]).
    pub fn running(&self) -> bool {
        let limit = config::board::SERVO_TIMER_CHECK_MS.saturating_mul(config::board::CPU_HZ / 1_000);
        while SERVO_FRAMES.load(Ordering::Relaxed) < 2 {
            if xtensa_lx::timer::get_cycle_count().wrapping_sub(self.started) > limit {
                stop_servo_pulses();
                return false;
            }
        }
        true
    }

    /// The loop's handle for the servo driver.
    pub fn output(&self) -> ServoPulses<'static> {
        ServoPulses::new(&SERVO_MAILBOX)
    }
}

/// Stops the servo pulses at once: FRC1 interrupt masked, timer off, both
/// pins low. Safe to call from anywhere (the panic handler does).
pub fn stop_servo_pulses() {
    xtensa_lx::interrupt::disable_mask(FRC1_INTERRUPT_MASK);
    frc1().frc1_ctrl.modify(|_, w| w.timer_enable().clear_bit());
    gpio_clear(LEFT_SERVO_MASK | RIGHT_SERVO_MASK);
}

// ---- the board ------------------------------------------------------------

/// Everything the firmware needs, set up.
pub struct Board {
    pub i2c: I2cBus,
    pub servo_timer: ServoTimer,
    pub serial: UART0Serial,
    pub watchdog: Watchdog,
    pub led: Led,
    pub front_xshut: Eh1Output<Gpio0<Output<PushPull>>>,
    pub right_xshut: Eh1Output<Gpio2<Output<PushPull>>>,
    pub delay: CcountDelay,
}

impl Board {
    /// Takes the peripherals (once; `None` on a second call) and sets up
    /// UART0, the pins, the I2C lines (not yet recovered: call
    /// `i2c.init()`) and the servo interrupt (pulses off). Lidars are held in
    /// reset (XSHUT low). The watchdog is not started: see
    /// [`start_watchdog`].
    pub fn take() -> Option<Self> {
        let dp = Peripherals::take()?;
        let pins = dp.GPIO.split();

        // UART0: baud divider through the PAC, then the HAL's serial port.
        #[allow(unused_unsafe)]
        dp.UART0.uart_clkdiv.write(|w| unsafe { w.uart_clkdiv().bits(UART0_DIVIDER) });
        let serial = dp.UART0.serial(pins.gpio1.into_uart(), pins.gpio3.into_uart());

        let mut front_xshut = pins.gpio0.into_push_pull_output();
        let mut right_xshut = pins.gpio2.into_push_pull_output();
        let _ = front_xshut.set_low();
        let _ = right_xshut.set_low();

        let mut led = Led { pin: pins.gpio16.into_push_pull_output(), lit: false };
        led.set(true);

        let i2c_pins =
            I2cGpio::new(pins.gpio14.into_open_drain_output(), pins.gpio12.into_open_drain_output(), &dp.IO_MUX);
        let i2c = BitBangI2c::new(i2c_pins, Ccount, Timing::FAST);

        let mut left = pins.gpio5.into_push_pull_output();
        let mut right = pins.gpio4.into_push_pull_output();
        let _ = left.set_low();
        let _ = right.set_low();
        let servo_timer = ServoTimer::start(dp.TIMER, left, right);

        Some(Board {
            i2c,
            servo_timer,
            serial,
            watchdog: dp.WDT.watchdog(),
            led,
            front_xshut: Eh1Output(front_xshut),
            right_xshut: Eh1Output(right_xshut),
            delay: CcountDelay,
        })
    }
}

/// Starts the hardware watchdog ([`config::board::WATCHDOG_MS`]); feed it
/// every loop iteration from then on.
pub fn start_watchdog(watchdog: &mut Watchdog) {
    watchdog.start(Milliseconds(config::board::WATCHDOG_MS));
}

pub use super::halt::{halt, release_strapping_pins};
