//! The two VL53L0X time-of-flight lidars on one bus.
//!
//! Both chips boot at 0x29 ([`config::i2c::LIDAR_DEFAULT_ADDR`]), so each is
//! started alone: [`bring_up`] holds both in reset (XSHUT low; on the
//! NodeMCU both XSHUT lines are boot-strap pins pulled high, so both chips
//! are awake at power-up), releases the front one, waits the boot time,
//! initialises it at 0x29 and moves it to its own address, then does the
//! same for the right one. A lidar that is not running is always held in
//! reset, so it can never answer at 0x29 and disturb the other's bring-up;
//! [`RangeSensor::reinit`] repeats one lidar's sequence at any time without
//! a reset of the robot.
//!
//! The `vl53l0x` crate (1.0.1) does the chip's initialisation (SPAD setup,
//! tuning table, reference calibrations), the address change, the timing
//! budget and the start of continuous ranging. Two things are ours:
//! - The crate's driver owns its bus handle and cannot give it back (no
//!   `release`), and a re-initialisation needs the bus again. So the crate's
//!   driver is built on a borrowed bus for the bring-up only and dropped
//!   after it; the continuous reads ([`Lidar::read_raw`]) are ours: the same
//!   three transfers as the crate's `read_range_mm` (interrupt status, range
//!   result, interrupt clear), with our typed errors.
//! - The crate does unchecked arithmetic on some register values and polls
//!   up to 65535 times; the bring-up runs it behind a [`PollGuard`] with
//!   [`Vl53l0xCheck`], which turns implausible values (a corrupted transfer)
//!   into a bus error and long waits into a timeout, so the robot never
//!   panics or stalls for seconds in it.

use embedded_hal::delay::DelayNs;
use embedded_hal::digital::OutputPin;
use embedded_hal::i2c::I2c;
use vl53l0x::VL53L0x;

use super::bus::{classify, GuardError, PollGuard, RegisterCheck, Retry};
use super::{LidarSample, RangeSensor, SensorError};
use crate::config;
use crate::model::lidar::LidarModel;

/// The VL53L0X registers this module touches itself (datasheet / ST API
/// names).
pub mod reg {
    pub const SYSTEM_INTERRUPT_CLEAR: u8 = 0x0B;
    pub const RESULT_INTERRUPT_STATUS: u8 = 0x13;
    /// RESULT_RANGE_STATUS + 10: the range in mm, big-endian.
    pub const RESULT_RANGE_MM: u8 = 0x1E;
    pub const MSRC_CONFIG_TIMEOUT_MACROP: u8 = 0x46;
    pub const PRE_RANGE_CONFIG_VCSEL_PERIOD: u8 = 0x50;
    pub const PRE_RANGE_CONFIG_TIMEOUT_MACROP_HI: u8 = 0x51;
    pub const FINAL_RANGE_CONFIG_VCSEL_PERIOD: u8 = 0x70;
    pub const FINAL_RANGE_CONFIG_TIMEOUT_MACROP_HI: u8 = 0x71;
    pub const I2C_SLAVE_DEVICE_ADDRESS: u8 = 0x8A;
    pub const WHO_AM_I: u8 = 0xC0;
    /// RESULT_INTERRUPT_STATUS bits 2:0: nonzero when a result is ready.
    pub const INTERRUPT_MASK: u8 = 0x07;
}

const _: () = {
    use config::i2c::{FRONT_LIDAR_ADDR, LIDAR_DEFAULT_ADDR, RIGHT_LIDAR_ADDR};
    // The chip takes 7-bit addresses 0x08..=0x77 (the crate rejects others).
    assert!(FRONT_LIDAR_ADDR >= 0x08 && FRONT_LIDAR_ADDR <= 0x77);
    assert!(RIGHT_LIDAR_ADDR >= 0x08 && RIGHT_LIDAR_ADDR <= 0x77);
    assert!(FRONT_LIDAR_ADDR != RIGHT_LIDAR_ADDR);
    assert!(FRONT_LIDAR_ADDR != LIDAR_DEFAULT_ADDR && RIGHT_LIDAR_ADDR != LIDAR_DEFAULT_ADDR);
    // The crate refuses budgets under 20 ms.
    assert!(config::lidar::TIMING_BUDGET_US >= 20_000);
    // The chip needs 1.2 ms to boot after XSHUT goes high (datasheet).
    assert!(config::lidar::BOOT_TIME_US >= 1_200);
};

/// The register values a real VL53L0X can hold, where the `vl53l0x` crate's
/// arithmetic needs them (it panics in debug builds, or divides by zero, on
/// others). Stateful: the final-range timeout is compared with the
/// pre-range one read just before it (the crate subtracts them).
#[derive(Clone, Copy, Default, Debug)]
pub struct Vl53l0xCheck {
    pre_range_mclks: u32,
}

/// A timeout register pair as the chip encodes it, `(lsb << msb) + 1`
/// macro clocks; `None` past 2^15 (more than a second of ranging, which
/// this driver never sets and which would overflow the crate's products).
fn decode_timeout(msb: u8, lsb: u8) -> Option<u32> {
    (msb <= 7).then(|| (u32::from(lsb) << msb).saturating_add(1)) // < 2^15 + 1
}

impl RegisterCheck for Vl53l0xCheck {
    fn plausible(&mut self, r: u8, data: &[u8]) -> bool {
        match (r, data) {
            // VCSEL periods: 12..18 PCLKs (pre-range) and 8..14 (final),
            // encoded as period / 2 - 1.
            (reg::PRE_RANGE_CONFIG_VCSEL_PERIOD | reg::FINAL_RANGE_CONFIG_VCSEL_PERIOD, [v]) => (3..=8).contains(v),
            // The crate adds one to it in a u8.
            (reg::MSRC_CONFIG_TIMEOUT_MACROP, [v]) => *v != 0xFF,
            (reg::PRE_RANGE_CONFIG_TIMEOUT_MACROP_HI, [msb, lsb]) => match decode_timeout(*msb, *lsb) {
                Some(m) => {
                    self.pre_range_mclks = m;
                    true
                }
                None => false,
            },
            // The final-range timeout includes the pre-range one.
            (reg::FINAL_RANGE_CONFIG_TIMEOUT_MACROP_HI, [msb, lsb]) => {
                decode_timeout(*msb, *lsb).is_some_and(|m| m >= self.pre_range_mclks)
            }
            _ => true,
        }
    }
}

fn vl_error<E: embedded_hal::i2c::Error>(e: vl53l0x::Error<GuardError<E>>) -> SensorError {
    match e {
        vl53l0x::Error::BusError(g) => g.sensor_error(),
        vl53l0x::Error::InvalidDevice(_) => SensorError::Missing,
        vl53l0x::Error::Timeout => SensorError::Timeout,
        // Addresses are checked at compile time (above); a refusal here
        // can only come from a corrupted state: treat it as a bus error.
        vl53l0x::Error::InvalidAddress(_) => SensorError::Bus,
    }
}

/// One VL53L0X with its XSHUT pin, its address and its model.
///
/// `I2C` is this lidar's handle on the shared bus (e.g. a
/// [`SharedI2c`](super::bus::SharedI2c)), `X` its XSHUT pin (embedded-hal
/// 1.0 `OutputPin`; high = running), `D` a delay for the reset and boot
/// waits.
pub struct Lidar<I2C, X, D> {
    i2c: I2C,
    xshut: X,
    delay: D,
    address: u8,
    model: LidarModel,
    running: bool,
}

impl<I2C: I2c, X: OutputPin, D: DelayNs> Lidar<I2C, X, D> {
    /// A lidar that will live at `address` and read through `model`. Does
    /// not touch the hardware: call [`bring_up`] or [`RangeSensor::reinit`].
    pub fn new(i2c: I2C, xshut: X, delay: D, address: u8, model: LidarModel) -> Self {
        Lidar { i2c, xshut, delay, address, model, running: false }
    }

    /// The front lidar: [`config::i2c::FRONT_LIDAR_ADDR`], [`config::lidar::FRONT`].
    pub fn front(i2c: I2C, xshut: X, delay: D) -> Self {
        Self::new(i2c, xshut, delay, config::i2c::FRONT_LIDAR_ADDR, config::lidar::FRONT)
    }

    /// The right lidar: [`config::i2c::RIGHT_LIDAR_ADDR`], [`config::lidar::RIGHT`].
    pub fn right(i2c: I2C, xshut: X, delay: D) -> Self {
        Self::new(i2c, xshut, delay, config::i2c::RIGHT_LIDAR_ADDR, config::lidar::RIGHT)
    }

    /// The address the lidar answers at once running.
    pub fn address(&self) -> u8 {
        self.address
    }

    /// True after a successful bring-up, until the next reset.
    pub fn is_running(&self) -> bool {
        self.running
    }

    /// Holds the chip in reset (XSHUT low): it stops answering on the bus.
    pub fn hold_in_reset(&mut self) -> Result<(), SensorError> {
        self.running = false;
        self.xshut.set_low().map_err(|_| SensorError::Bus)
    }

    /// Releases XSHUT and waits the boot time.
    fn release_reset(&mut self) -> Result<(), SensorError> {
        self.xshut.set_high().map_err(|_| SensorError::Bus)?;
        self.delay.delay_us(config::lidar::BOOT_TIME_US);
        Ok(())
    }

    /// The crate's initialisation at the boot address, the move to our
    /// address, the timing budget and continuous (back-to-back) ranging.
    fn init_chip(&mut self) -> Result<(), SensorError> {
        // Retry outside the guard: an implausible value (a corrupted read)
        // is read again too, not only a failed transfer. The address change
        // is not retried (not idempotent, see `Retry`).
        let guard = PollGuard::new(&mut self.i2c, Vl53l0xCheck::default(), config::lidar::INIT_POLL_LIMIT);
        let bus = Retry::with_config(guard).except_writes_to(reg::I2C_SLAVE_DEVICE_ADDRESS);
        let mut chip = VL53L0x::with_address(bus, config::i2c::LIDAR_DEFAULT_ADDR).map_err(vl_error)?;
        if self.address != config::i2c::LIDAR_DEFAULT_ADDR {
            chip.set_address(self.address).map_err(vl_error)?;
        }
        let budget_set =
            chip.set_measurement_timing_budget(config::lidar::TIMING_BUDGET_US).map_err(|e| e.sensor_error())?;
        if !budget_set {
            // The budget is valid (checked at compile time), so the chip's
            // timing registers made no sense: a corrupted transfer.
            return Err(SensorError::Bus);
        }
        // Period 0: back-to-back ranging, one result per timing budget.
        chip.start_continuous(0).map_err(|e| e.sensor_error())
    }

    /// Reset, boot, initialise, move. On failure the chip is left held in
    /// reset (so it cannot answer at the shared boot address).
    fn start(&mut self) -> Result<(), SensorError> {
        self.hold_in_reset()?;
        self.delay.delay_us(config::lidar::RESET_TIME_US);
        self.release_reset()?;
        match self.init_chip() {
            Ok(()) => {
                self.running = true;
                Ok(())
            }
            Err(e) => {
                // The error that matters is the init's; a pin that cannot be
                // set would show again at the next attempt.
                let _ = self.hold_in_reset();
                Err(e)
            }
        }
    }

    /// The newest raw reading in mm (8190/8191: no target), or
    /// `WouldBlock` if none is ready. Never blocks.
    pub fn read_raw(&mut self) -> nb::Result<u16, SensorError> {
        if !self.running {
            return Err(nb::Error::Other(SensorError::NotReady));
        }
        // All three are idempotent (see `Retry`): retried on a failure.
        let mut i2c = Retry::with_config(&mut self.i2c);
        let mut status = [0u8; 1];
        i2c.write_read(self.address, &[reg::RESULT_INTERRUPT_STATUS], &mut status).map_err(|e| classify(&e))?;
        if status[0] & reg::INTERRUPT_MASK == 0 {
            return Err(nb::Error::WouldBlock);
        }
        let mut range = [0u8; 2];
        i2c.write_read(self.address, &[reg::RESULT_RANGE_MM], &mut range).map_err(|e| classify(&e))?;
        i2c.write(self.address, &[reg::SYSTEM_INTERRUPT_CLEAR, 0x01]).map_err(|e| classify(&e))?;
        Ok(u16::from_be_bytes(range))
    }

    /// Gives the parts back.
    pub fn release(self) -> (I2C, X, D) {
        (self.i2c, self.xshut, self.delay)
    }
}

impl<I2C: I2c, X: OutputPin, D: DelayNs> RangeSensor for Lidar<I2C, X, D> {
    fn poll(&mut self) -> nb::Result<LidarSample, SensorError> {
        let raw_mm = self.read_raw()?;
        Ok(LidarSample { raw_mm, range: self.model.range(raw_mm) })
    }

    /// XSHUT low, reset wait, release, boot wait, initialisation at 0x29,
    /// address change, timing budget, continuous ranging. Assumes the other
    /// lidar is running at its own address or held in reset (which every
    /// path of this module guarantees).
    fn reinit(&mut self) -> Result<(), SensorError> {
        self.start()
    }
}

/// What [`bring_up`] achieved for each lidar.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub struct BringUp {
    pub front: Result<(), SensorError>,
    pub right: Result<(), SensorError>,
}

impl BringUp {
    pub fn all_ok(&self) -> bool {
        self.front.is_ok() && self.right.is_ok()
    }
}

/// Brings both lidars up on one bus: both held in reset, then the front
/// one started and moved to its address, then the right one. A lidar that
/// fails is held in reset and does not stop the other from starting; retry
/// it later with [`RangeSensor::reinit`].
pub fn bring_up<I2C1, X1, D1, I2C2, X2, D2>(front: &mut Lidar<I2C1, X1, D1>, right: &mut Lidar<I2C2, X2, D2>) -> BringUp
where
    I2C1: I2c,
    X1: OutputPin,
    D1: DelayNs,
    I2C2: I2c,
    X2: OutputPin,
    D2: DelayNs,
{
    // Both off first: at power-up both are awake at 0x29.
    let front_off = front.hold_in_reset();
    let right_off = right.hold_in_reset();
    if let Err(e) = right_off {
        // The right one cannot be silenced: starting the front one at 0x29
        // would talk to both at once.
        return BringUp { front: Err(e), right: Err(e) };
    }
    let front_res = front_off.and_then(|()| front.start());
    let right_res = right.start();
    BringUp { front: front_res, right: right_res }
}
