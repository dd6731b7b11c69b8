//! The compass: the MPU9250's AK8963 magnetometer, in I2C bypass mode.
//!
//! Bring-up ([`HeadingSensor::reinit`]):
//! 1. MPU9250 at [`config::i2c::MPU9250_ADDR`], through the `mpu9250`
//!    crate's [`I2cDevice`] and [`Device`] register access (over the
//!    [`Eh0Compat`] adapter, the crate speaks embedded-hal 0.2): identity
//!    check (WHO_AM_I 0x71 MPU9250 or 0x73 MPU9255), device reset, clock
//!    select, accelerometer and gyroscope off (only the magnetometer is
//!    used), I2C master off, bypass on (INT_PIN_CFG BYPASS_EN): the AK8963
//!    now sits on our bus at [`config::i2c::AK8963_ADDR`].
//! 2. AK8963, directly: identity (WIA 0x48), fuse-ROM mode to read the
//!    sensitivity adjustment (ASA, read twice and compared), then
//!    continuous mode 2 (100 Hz) with 16-bit output.
//!
//! Why the AK8963 is not driven through the `mpu9250` crate: its
//! magnetometer access is private to its `Mpu9250<_, Marg>` driver, whose
//! constructor also configures the accelerometer and gyroscope (there is no
//! magnetometer-only mode); it computes the ASA as `f32` from `asa - 128` on
//! a `u8` (an overflow panic in debug builds for any ASA below 128), reads
//! scaled floats, and ignores the overflow flag. Here the ASA is applied in
//! integers by [`crate::model::compass::apply_asa`], data-ready (ST1 DRDY) is
//! honoured, and an overflowed sample (ST2 HOFL) is dropped.
//!
//! Reading ([`HeadingSensor::poll`]): ST1; if DRDY, the six data bytes and
//! ST2 in one transfer (reading ST2 releases the chip's data lock); then the
//! compass model (ASA, hard and soft iron, axes, declination): all integer.

use embedded_hal::delay::DelayNs;
use embedded_hal::i2c::I2c;
use mpu9250::{Device, I2CError, I2cDevice, Register};

use super::bus::{classify, Eh0Compat, Retry};
use super::{CompassSample, HeadingSensor, MagCalibrate, SensorError};
use crate::config;
use crate::model::compass::{CompassModel, MagCalibration, MagCounts};

/// The MPU9250's registers and bits used here (MPU-9250 register map rev
/// 1.6): the one map of the chip, which the fake chip (`sim::mpu9250`) and
/// the tests' transaction scripts use too. The addresses are the `mpu9250`
/// crate's `Register`, which the driver writes through, and its
/// identities are the crate's `MpuXDevice`.
pub mod mpu {
    use mpu9250::{MpuXDevice, Register};

    pub const WHO_AM_I: u8 = Register::WHO_AM_I as u8;
    pub const PWR_MGMT_1: u8 = Register::PWR_MGMT_1 as u8;
    pub const PWR_MGMT_2: u8 = Register::PWR_MGMT_2 as u8;
    pub const USER_CTRL: u8 = Register::USER_CTRL as u8;
    pub const INT_PIN_CFG: u8 = Register::INT_PIN_CFG as u8;
    /// WHO_AM_I of an MPU9250.
    pub const MPU9250_ID: u8 = MpuXDevice::MPU9250 as u8;
    /// WHO_AM_I of an MPU9255 (the same magnetometer).
    pub const MPU9255_ID: u8 = MpuXDevice::MPU9255 as u8;
    /// PWR_MGMT_1: device reset.
    pub const H_RESET: u8 = 0x80;
    /// PWR_MGMT_1: clock auto-select (PLL if ready, else internal); also
    /// the register's value after a reset.
    pub const CLKSEL_AUTO: u8 = 0x01;
    /// PWR_MGMT_2: all accelerometer and gyroscope axes disabled.
    pub const DISABLE_ACCEL_GYRO: u8 = 0x3F;
    /// INT_PIN_CFG: I2C bypass (the AK8963 joins the host bus).
    pub const BYPASS_EN: u8 = 0x02;
    /// USER_CTRL: nothing (I2C master off, FIFO off).
    pub const USER_CTRL_NONE: u8 = 0x00;
    /// USER_CTRL: the chip's own I2C master on (the AK8963 then leaves the
    /// host bus even in bypass).
    pub const I2C_MST_EN: u8 = 0x20;
}

/// The AK8963's registers and bits (AK8963 datasheet, section 8): the one
/// map of the chip, shared as [`mpu`] is.
pub mod ak {
    pub const WIA: u8 = 0x00;
    pub const INFO: u8 = 0x01;
    pub const ST1: u8 = 0x02;
    /// The first of the six data registers (X, Y, Z, little-endian).
    pub const HXL: u8 = 0x03;
    /// The last data register.
    pub const HZH: u8 = 0x08;
    pub const ST2: u8 = 0x09;
    pub const CNTL1: u8 = 0x0A;
    pub const CNTL2: u8 = 0x0B;
    /// The fuse ROM's sensitivity adjustment, X (Y and Z follow).
    pub const ASAX: u8 = 0x10;
    pub const ASAZ: u8 = 0x12;
    /// WIA value (device ID of AKM).
    pub const DEVICE_ID: u8 = 0x48;
    /// ST1: data ready.
    pub const DRDY: u8 = 0x01;
    /// ST1: data overrun (a sample was skipped).
    pub const DOR: u8 = 0x02;
    /// ST2: magnetic sensor overflow.
    pub const HOFL: u8 = 0x08;
    /// ST2: output is 16-bit.
    pub const BITM: u8 = 0x10;
    /// CNTL1 modes (bits 3:0).
    pub const MODE_MASK: u8 = 0x0F;
    pub const MODE_POWER_DOWN: u8 = 0x00;
    pub const MODE_SINGLE: u8 = 0x01;
    pub const MODE_CONT1_8HZ: u8 = 0x02;
    pub const MODE_CONT2_100HZ: u8 = 0x06;
    pub const MODE_FUSE_ROM: u8 = 0x0F;
    /// CNTL1 bit 4: 16-bit output.
    pub const BIT_16: u8 = 0x10;
    /// CNTL2: soft reset.
    pub const SRST: u8 = 0x01;
}

fn mpu_error<E: embedded_hal::i2c::Error>(e: I2CError<E>) -> SensorError {
    match e {
        I2CError::BusError(e) => classify(&e),
        // Only from write_many, which is not used here.
        I2CError::WriteManyError => SensorError::Bus,
    }
}

/// The AK8963 behind an MPU9250, with the compass model.
///
/// `I2C` is the compass's handle on the shared bus (e.g. a
/// [`SharedI2c`](super::bus::SharedI2c)), `D` a delay for the reset and
/// mode-change waits.
pub struct Compass<I2C, D> {
    i2c: I2C,
    delay: D,
    model: CompassModel,
    asa: [u8; 3],
    running: bool,
}

impl<I2C: I2c, D: DelayNs> Compass<I2C, D> {
    /// A compass with `model`. Does not touch the hardware: call
    /// [`HeadingSensor::reinit`].
    pub fn new(i2c: I2C, delay: D, model: CompassModel) -> Self {
        Compass { i2c, delay, model, asa: [128; 3], running: false }
    }

    /// A compass with the configured model ([`config::compass::MODEL`]).
    pub fn with_config(i2c: I2C, delay: D) -> Self {
        Self::new(i2c, delay, config::compass::MODEL)
    }

    pub fn is_running(&self) -> bool {
        self.running
    }

    pub fn model(&self) -> &CompassModel {
        &self.model
    }

    /// The MPU9250 side, through the `mpu9250` crate's register access.
    fn init_mpu(&mut self) -> Result<(), SensorError> {
        let mut mpu = I2cDevice::new(Eh0Compat(Retry::with_config(&mut self.i2c)));
        let who = Device::read(&mut mpu, Register::WHO_AM_I).map_err(mpu_error)?;
        if who != mpu::MPU9250_ID && who != mpu::MPU9255_ID {
            return Err(SensorError::Missing);
        }
        Device::write(&mut mpu, Register::PWR_MGMT_1, mpu::H_RESET).map_err(mpu_error)?;
        self.delay.delay_us(config::compass::MPU_RESET_TIME_US);
        let mut mpu = I2cDevice::new(Eh0Compat(Retry::with_config(&mut self.i2c)));
        Device::write(&mut mpu, Register::PWR_MGMT_1, mpu::CLKSEL_AUTO).map_err(mpu_error)?;
        Device::write(&mut mpu, Register::PWR_MGMT_2, mpu::DISABLE_ACCEL_GYRO).map_err(mpu_error)?;
        Device::write(&mut mpu, Register::USER_CTRL, mpu::USER_CTRL_NONE).map_err(mpu_error)?;
        Device::write(&mut mpu, Register::INT_PIN_CFG, mpu::BYPASS_EN).map_err(mpu_error)
    }

    /// A register write, retried on a failure (idempotent).
    fn ak_write(&mut self, reg: u8, value: u8) -> Result<(), SensorError> {
        let mut i2c = Retry::with_config(&mut self.i2c);
        i2c.write(config::i2c::AK8963_ADDR, &[reg, value]).map_err(|e| classify(&e))
    }

    /// A register read, retried on a failure: idempotent for every register
    /// read here (ST1 clears nothing; a repeated HXL..ST2 read gets the same
    /// or the next whole sample, see `Retry`).
    fn ak_read(&mut self, reg: u8, buf: &mut [u8]) -> Result<(), SensorError> {
        let mut i2c = Retry::with_config(&mut self.i2c);
        i2c.write_read(config::i2c::AK8963_ADDR, &[reg], buf).map_err(|e| classify(&e))
    }

    fn ak_mode(&mut self, mode: u8) -> Result<(), SensorError> {
        self.ak_write(ak::CNTL1, mode)?;
        self.delay.delay_us(config::compass::MODE_CHANGE_US);
        Ok(())
    }

    /// The AK8963 side, directly (see the module docs).
    fn init_ak8963(&mut self) -> Result<(), SensorError> {
        let mut wia = [0u8; 1];
        self.ak_read(ak::WIA, &mut wia)?;
        if wia[0] != ak::DEVICE_ID {
            return Err(SensorError::Missing);
        }
        self.ak_mode(ak::MODE_POWER_DOWN)?;
        self.ak_mode(ak::MODE_FUSE_ROM)?;
        // The fuse ROM is read twice: a corrupted transfer would otherwise
        // give a wrong sensitivity for as long as the robot runs.
        let (mut asa, mut again) = ([0u8; 3], [0u8; 3]);
        self.ak_read(ak::ASAX, &mut asa)?;
        self.ak_read(ak::ASAX, &mut again)?;
        if asa != again {
            return Err(SensorError::Bus);
        }
        self.ak_mode(ak::MODE_POWER_DOWN)?;
        self.ak_mode(ak::MODE_CONT2_100HZ | ak::BIT_16)?;
        self.asa = asa;
        Ok(())
    }

    /// Full bring-up; on failure the compass stays not running.
    fn start(&mut self) -> Result<(), SensorError> {
        self.running = false;
        self.init_mpu()?;
        self.init_ak8963()?;
        self.running = true;
        Ok(())
    }

    /// The newest raw sample in the chip's axes, or `WouldBlock` if none is
    /// ready; `BadSample` if it overflowed (dropped). Never blocks.
    pub fn read_raw(&mut self) -> nb::Result<MagCounts, SensorError> {
        if !self.running {
            return Err(nb::Error::Other(SensorError::NotReady));
        }
        let mut st1 = [0u8; 1];
        self.ak_read(ak::ST1, &mut st1)?;
        if st1[0] & ak::DRDY == 0 {
            return Err(nb::Error::WouldBlock);
        }
        // HXL..HZH and ST2: reading ST2 ends the read (the chip's data lock).
        let mut d = [0u8; 7];
        self.ak_read(ak::HXL, &mut d)?;
        let [xl, xh, yl, yh, zl, zh, st2] = d;
        if st2 & ak::HOFL != 0 {
            return Err(nb::Error::Other(SensorError::BadSample));
        }
        Ok(MagCounts {
            x: i16::from_le_bytes([xl, xh]),
            y: i16::from_le_bytes([yl, yh]),
            z: i16::from_le_bytes([zl, zh]),
        })
    }

    /// Gives the parts back.
    pub fn release(self) -> (I2C, D) {
        (self.i2c, self.delay)
    }
}

impl<I2C: I2c, D: DelayNs> HeadingSensor for Compass<I2C, D> {
    fn poll(&mut self) -> nb::Result<CompassSample, SensorError> {
        let raw = self.read_raw()?;
        let field = self.model.correct(raw, self.asa);
        Ok(CompassSample { raw, field, heading: self.model.heading(&field) })
    }

    /// MPU9250 reset and bypass, AK8963 identity, ASA, continuous 100 Hz.
    fn reinit(&mut self) -> Result<(), SensorError> {
        self.start()
    }
}

impl<I2C: I2c, D: DelayNs> MagCalibrate for Compass<I2C, D> {
    fn asa(&self) -> [u8; 3] {
        self.asa
    }
    fn calibration(&self) -> MagCalibration {
        self.model.calibration
    }
    fn set_calibration(&mut self, calibration: MagCalibration) {
        self.model.calibration = calibration;
    }
    fn declination(&self) -> crate::math::Angle {
        self.model.declination
    }
    fn set_declination(&mut self, declination: crate::math::Angle) {
        self.model.declination = declination;
    }
}
