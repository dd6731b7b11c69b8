//! The paperbot firmware for the ESP8266 (`xtensa-esp8266-none-elf`).
//!
//! Build and flash with the esp toolchain (see README):
//! `cargo +esp fw-flash` (= `cargo +esp run --release --features firmware
//! --target xtensa-esp8266-none-elf --bin firmware`). It needs the
//! non-default `firmware` feature, so host `cargo test` / `clippy
//! --all-targets` never build it; on a non-xtensa target it is a stub.
//!
//! Boot: board bring-up (UART0 115200, pins, servo interrupt with pulses
//! off, I2C bus recovery), the two lidars (XSHUT sequence, new addresses),
//! the compass; then [`run`]: the control loop at `config::timing::LOOP_HZ`
//! fed by UART0, the watchdog fed every pass, the LED blinking the state.
#![cfg_attr(target_arch = "xtensa", no_std, no_main)]
// The library's panic lints (Cargo.toml's `[lints.clippy]`) are errors here
// too; the host stub has nothing they could catch.

#[cfg(not(target_arch = "xtensa"))]
fn main() {
    eprintln!("paperbot firmware: build it for xtensa-esp8266-none-elf with the esp toolchain (see README)");
}

#[cfg(target_arch = "xtensa")]
mod robot {
    use core::cell::RefCell;
    use core::fmt::Write as _;

    use embedded_hal_02::serial::Read as _;
    use esp8266_hal::ehal::watchdog::Watchdog as _;
    use esp8266_hal::entry;
    use esp8266_hal::gpio::{Gpio0, Gpio2, Output, PushPull};
    use esp8266_hal::uart::UART0Serial;

    use paperbot::board::bitbang_i2c::CycleClock as _;
    use paperbot::board::esp8266::{
        halt, start_watchdog, take_over_interrupts, Board, Ccount, CcountDelay, Eh1Output, I2cBus, MicrosClock,
    };
    use paperbot::board::rom_flash::RomFlash;
    use paperbot::board::rtc_store::RtcMissionStore;
    use paperbot::board::servo_pulse::ServoPulses;
    use paperbot::config;
    use paperbot::control::log::RingLog;
    use paperbot::control::mission::{Mission, MissionStore as _};
    use paperbot::control::settings::FlashSettings;
    use paperbot::control::tick::{Controller, Hardware, LineSink, TICK_US};
    use paperbot::driver::bus::SharedI2c;
    use paperbot::driver::compass::Compass;
    use paperbot::driver::lidar::{bring_up, Lidar};
    use paperbot::driver::servo::ServoPair;
    use paperbot::driver::HeadingSensor as _;
    use paperbot::model::measurement::Arena;

    const CYCLES_PER_MS: u32 = config::board::CPU_HZ / 1_000;
    /// The loop period in CPU cycles.
    const TICK_CYCLES: u32 = TICK_US * (config::board::CPU_HZ / 1_000_000);

    /// The on-board log: a static, so that it counts in the image's DRAM
    /// budget (`cargo fw-image`), not on the ROM's stack.
    static mut LOG: RingLog<{ config::log::ROWS }> = RingLog::new();

    /// Telemetry and replies go out on UART0, one line each, CR LF.
    struct UartLines<'a>(&'a mut UART0Serial);

    impl LineSink for UartLines<'_> {
        fn write_line(&mut self, line: &str) {
            // Blocking on the 128-byte FIFO; the HAL's error type is Void.
            let _ = self.0.write_str(line);
            let _ = self.0.write_str("\r\n");
        }
    }

    /// The robot's parts: the three chips on the one bit-banged bus (shared
    /// through a `RefCell` that lives for `'a`), the servo pulses and the
    /// static log.
    struct Robot<'a>(core::marker::PhantomData<&'a ()>);

    impl<'a> Hardware for Robot<'a> {
        type Front = Lidar<SharedI2c<'a, I2cBus>, Eh1Output<Gpio0<Output<PushPull>>>, CcountDelay>;
        type Right = Lidar<SharedI2c<'a, I2cBus>, Eh1Output<Gpio2<Output<PushPull>>>, CcountDelay>;
        type Compass = Compass<SharedI2c<'a, I2cBus>, CcountDelay>;
        type Servos = ServoPair<ServoPulses<'static>>;
        type Log = &'static mut RingLog<{ config::log::ROWS }>;
        type Settings = FlashSettings<RomFlash>;
    }

    #[entry]
    fn main() -> ! {
        take_over_interrupts();
        let Some(board) = Board::take() else {
            // Only reachable if main ran twice: stop and reset.
            halt(format_args!("peripherals already taken"));
        };
        run(board)
    }

    /// All hardware is created by [`Board::take`] and handed over here.
    fn run(b: Board) -> ! {
        let Board { mut i2c, servo_timer, mut serial, mut watchdog, mut led, front_xshut, right_xshut, delay } = b;
        // Every line on UART0 ends in CR LF.
        let _ = write!(serial, "\r\npaperbot {} up\r\n", env!("CARGO_PKG_VERSION"));
        if !servo_timer.running() {
            // pulses stopped, both pins low; the robot still answers
            let _ = write!(serial, "# fault: servo timer interrupt not running\r\n");
        }
        if let Err(e) = i2c.init() {
            let _ = write!(serial, "!i2c bus stuck: {:?}\r\n", e);
        }

        // One bit-banged bus, shared by the three chips from the main loop only.
        let bus: RefCell<I2cBus> = RefCell::new(i2c);
        let mut front = Lidar::front(SharedI2c::new(&bus), front_xshut, delay);
        let mut right = Lidar::right(SharedI2c::new(&bus), right_xshut, delay);
        let up = bring_up(&mut front, &mut right);
        let mut compass = Compass::with_config(SharedI2c::new(&bus), delay);
        let compass_up = compass.reinit();
        let _ = write!(serial, "lidars {:?} {:?}, compass {:?}\r\n", up.front, up.right, compass_up);

        let servos = ServoPair::with_config(servo_timer.output());
        // SAFETY: `run` is entered once (main never returns): the only reference to LOG
        let log = unsafe { &mut *core::ptr::addr_of_mut!(LOG) };
        let start = Arena::DEFAULT.centre();
        let settings = FlashSettings::new(RomFlash);
        let mut ctl =
            Controller::<Robot>::with_log(front, right, compass, servos, start, Arena::DEFAULT, log, settings);
        // the settings in flash, then a mission uploaded before a reset (RTC
        // memory, newer than the flash's; not after power-off)
        ctl.restore_settings(&mut UartLines(&mut serial));
        let mut store = RtcMissionStore;
        if let Some(mission) = Mission::decode(&store.load()).filter(|m| m != ctl.mission()) {
            let _ = write!(serial, "mission of {} steps kept from before the reset\r\n", mission.len());
            ctl.set_mission(mission);
        }

        // The loop spins on CCOUNT and converts it to microseconds only for
        // a tick: the conversion divides, which the lx106 does in software.
        let mut clock = MicrosClock::new();
        let mut last_tick = Ccount.now();
        let mut last_blink = last_tick;
        start_watchdog(&mut watchdog);
        if config::locate::AT_POWER_UP {
            ctl.power_up(&mut UartLines(&mut serial));
        }
        loop {
            watchdog.feed();
            let now = Ccount.now();

            // Commands: every byte waiting in the RX FIFO.
            while let Ok(byte) = serial.read() {
                ctl.feed(byte, &mut UartLines(&mut serial));
            }

            if now.wrapping_sub(last_tick) >= TICK_CYCLES {
                last_tick = now;
                ctl.tick(clock.now_us(), &mut UartLines(&mut serial));
            }
            if ctl.take_mission_changed() {
                store.save(&ctl.mission().encode());
            }

            // LED: slow blink when every sensor is up, fast when one is down.
            let healthy = ctl.front_health().up && ctl.right_health().up && ctl.compass_health().up;
            let half_ms = if healthy { config::board::LED_BLINK_OK_MS } else { config::board::LED_BLINK_FAULT_MS };
            if now.wrapping_sub(last_blink) >= half_ms.saturating_mul(CYCLES_PER_MS) {
                last_blink = now;
                led.toggle();
            }
        }
    }
}
