//! Size probe: every robot-side entry point the firmware uses, and nothing
//! else (no formatting, no tests). run.sh compares its .text, .rodata, .data
//! and .bss with `size_base` (the same runtime, no core calls): the
//! difference is the core's footprint. Also checked: no soft-float routine is
//! linked.
//!
//! What `src/bin/firmware.rs` builds, minus the esp8266-hal glue: the
//! bit-banged I2C master over GPIO registers, the shared bus
//! (`RefCellDevice`), both lidars' bring-up and the compass's, the servo
//! pair on the FRC1 pulse mailbox and its interrupt-side scheduler, and the
//! control loop (`Controller::feed` + `tick`: line buffer, parser, estimator,
//! deadman, telemetry and responses) writing to a UART FIFO register. The
//! drivers apply the lidar and compass models. Library functions only host
//! tools and the simulator call (`step`, `expected_lidar`, ...) are not
//! linked, as they are not in the firmware. The "hardware" here is volatile
//! accesses to the ESP8266's register addresses (never run).
#![no_std]
#![no_main]

use core::cell::RefCell;
use core::convert::Infallible;
use core::hint::black_box as bb;
use core::ptr::{read_volatile, write_volatile};

use paperbot::board::bitbang_i2c::{BitBangI2c, CycleClock, I2cPins, Timing};
use paperbot::board::servo_pulse::{Channel, PulseMailbox, PulseScheduler, PulseTimer, ServoPulses};
use paperbot::control::log::RingLog;
use paperbot::control::settings::{FlashSettings, NoFlash};
use paperbot::control::{Controller, Hardware, LineSink};
use paperbot::driver::bus::SharedI2c;
use paperbot::driver::compass::Compass;
use paperbot::driver::lidar::{bring_up, Lidar};
use paperbot::driver::servo::ServoPair;
use paperbot::driver::HeadingSensor;
use paperbot::model::Pose;

/// ESP8266 GPIO_OUT / GPIO_IN, FRC1, UART0 FIFO (register addresses).
const GPIO_OUT: *mut u32 = 0x6000_0300 as *mut u32;
const GPIO_IN: *const u32 = 0x6000_0318 as *const u32;
const FRC1_LOAD: *mut u32 = 0x6000_0600 as *mut u32;
const UART0_FIFO: *mut u32 = 0x6000_0000 as *mut u32;

fn out(v: u32) {
    // SAFETY: a register address on the ESP8266; this binary is only linked.
    unsafe { write_volatile(GPIO_OUT, v) }
}
fn input() -> u32 {
    // SAFETY: as above.
    unsafe { read_volatile(GPIO_IN) }
}

struct Pins;
impl I2cPins for Pins {
    fn scl_release(&mut self) {
        out(1);
    }
    fn scl_low(&mut self) {
        out(2);
    }
    fn scl_is_high(&mut self) -> bool {
        input() & 1 != 0
    }
    fn sda_release(&mut self) {
        out(4);
    }
    fn sda_low(&mut self) {
        out(8);
    }
    fn sda_is_high(&mut self) -> bool {
        input() & 2 != 0
    }
}

struct Clock;
impl CycleClock for Clock {
    fn now(&mut self) -> u32 {
        input()
    }
}

#[derive(Clone, Copy)]
struct Delay;
impl embedded_hal::delay::DelayNs for Delay {
    fn delay_ns(&mut self, ns: u32) {
        out(ns);
    }
}

struct Xshut(u32);
impl embedded_hal::digital::ErrorType for Xshut {
    type Error = Infallible;
}
impl embedded_hal::digital::OutputPin for Xshut {
    fn set_low(&mut self) -> Result<(), Infallible> {
        out(16 << self.0);
        Ok(())
    }
    fn set_high(&mut self) -> Result<(), Infallible> {
        out(64 << self.0);
        Ok(())
    }
}

struct Frc1;
impl PulseTimer for Frc1 {
    fn cycles(&mut self) -> u32 {
        input()
    }
    fn load(&mut self, ticks: u32) {
        // SAFETY: as above.
        unsafe { write_volatile(FRC1_LOAD, ticks) }
    }
    fn set_pin(&mut self, channel: Channel, high: bool) {
        out(match channel {
            Channel::Left => 256,
            Channel::Right => 512,
        } | u32::from(high));
    }
}

struct Uart;
impl LineSink for Uart {
    fn write_line(&mut self, line: &str) {
        for &b in line.as_bytes().iter().chain(b"\r\n") {
            // SAFETY: as above.
            unsafe { write_volatile(UART0_FIFO, u32::from(b)) }
        }
    }
}

/// The firmware's drivers over this probe's pins (no on-board log).
struct Stack<'a>(core::marker::PhantomData<&'a ()>);

impl<'a> Hardware for Stack<'a> {
    type Front = Lidar<SharedI2c<'a, BitBangI2c<Pins, Clock>>, Xshut, Delay>;
    type Right = Lidar<SharedI2c<'a, BitBangI2c<Pins, Clock>>, Xshut, Delay>;
    type Compass = Compass<SharedI2c<'a, BitBangI2c<Pins, Clock>>, Delay>;
    type Servos = ServoPair<ServoPulses<'a>>;
    type Log = RingLog<0>;
    type Settings = FlashSettings<NoFlash>;
}

#[no_mangle]
pub extern "C" fn rust_main() -> i32 {
    // the firmware's stack
    let bus = RefCell::new(BitBangI2c::new(Pins, Clock, Timing::FAST));
    bb(bus.borrow_mut().init().is_ok());
    let mut front = Lidar::front(SharedI2c::new(&bus), Xshut(0), Delay);
    let mut right = Lidar::right(SharedI2c::new(&bus), Xshut(1), Delay);
    bb(bring_up(&mut front, &mut right).all_ok());
    let mut compass = Compass::with_config(SharedI2c::new(&bus), Delay);
    bb(compass.reinit().is_ok());
    let mailbox = PulseMailbox::default();
    let servos = ServoPair::with_config(ServoPulses::new(&mailbox));
    control_loop(Controller::<Stack>::new(front, right, compass, servos, Pose::default()));
    let mut sched = PulseScheduler::default();
    let mut frc1 = Frc1;
    sched.start(&mut frc1);
    sched.on_alarm(&mut frc1, &mailbox);
    0
}

/// The firmware's main loop body. Its own function: inlined into
/// `rust_main`, the whole stack in one function made LLVM's Xtensa backend
/// fail ("Cannot scavenge register without an emergency spill slot").
#[inline(never)]
fn control_loop(mut ctl: Controller<Stack<'_>>) {
    let mut uart = Uart;
    for &b in bb(b"fwd 0.13 2.5\n") {
        ctl.feed(bb(b), &mut uart);
    }
    ctl.tick(bb(0), &mut uart);
    bb(ctl.pose());
}

/// Upstream LLVM lowers `AtomicU32::load`/`store` (the servo mailbox) on the
/// lx106 (no S32C1I) to these libcalls; on a single core an aligned 32-bit
/// load or store is atomic, so they are a plain access. Counted as part of
/// the core's footprint (a few bytes each).
#[no_mangle]
pub unsafe extern "C" fn __atomic_load_4(p: *const u32, _order: i32) -> u32 {
    // SAFETY: the caller's valid, aligned AtomicU32.
    unsafe { read_volatile(p) }
}
#[no_mangle]
pub unsafe extern "C" fn __atomic_store_4(p: *mut u32, v: u32, _order: i32) {
    // SAFETY: the caller's valid, aligned AtomicU32.
    unsafe { write_volatile(p, v) }
}

include!("../probe_rt.rs");
