//! The MPU9250 and its AK8963 magnetometer as the compass driver talks to
//! them: the driver's register map (`driver::compass::{mpu, ak}`, from the
//! MPU-9250 register map rev 1.6 and the AK8963 datasheet section 8), the
//! exact bring-up and read scripts (bit values written out), and a
//! compass over mocks (`new_compass`) with its `done` check.

use embedded_hal_mock::eh1::delay::{CheckedDelay, Transaction as DelayT};
use embedded_hal_mock::eh1::i2c::{Mock as I2cMock, Transaction as I2cT};
use paperbot::config;
use paperbot::driver::compass::Compass;
use paperbot::driver::{HeadingSensor, MagCalibrate};

/// The chips' addresses (AD0 low; the AK8963 on the bypassed bus).
pub use paperbot::config::i2c::{AK8963_ADDR as AK, MPU9250_ADDR as MPU};
/// The AK8963's registers and bits: the driver's map (`tests/drivers/compass.rs`
/// checks it against the datasheet), under the names the scripts use.
pub use paperbot::driver::compass::ak::{
    ASAX, BITM, CNTL1, DEVICE_ID as AK8963_ID, DRDY, HOFL, HXL, MODE_FUSE_ROM as FUSE_ROM,
    MODE_POWER_DOWN as POWER_DOWN, ST1, WIA,
};
/// The MPU9250's registers: the driver's map.
pub use paperbot::driver::compass::mpu::{INT_PIN_CFG, MPU9250_ID, PWR_MGMT_1, PWR_MGMT_2, USER_CTRL, WHO_AM_I};
/// CNTL1: continuous mode 2 (100 Hz), 16 bit.
pub const CONTINUOUS_100HZ_16BIT: u8 =
    paperbot::driver::compass::ak::MODE_CONT2_100HZ | paperbot::driver::compass::ak::BIT_16;

/// ASA below 128 on x: the mpu9250 crate's `asa - 128` on a u8 would panic.
pub const ASA: [u8; 3] = [0x40, 0xB0, 0xFF];

/// The bring-up, transfer by transfer.
pub fn bring_up_script(asa: [u8; 3]) -> Vec<I2cT> {
    vec![
        I2cT::write_read(MPU, vec![WHO_AM_I], vec![MPU9250_ID]),
        I2cT::write(MPU, vec![PWR_MGMT_1, 0x80]),  // reset
        I2cT::write(MPU, vec![PWR_MGMT_1, 0x01]),  // clock auto
        I2cT::write(MPU, vec![PWR_MGMT_2, 0x3F]),  // accel, gyro off
        I2cT::write(MPU, vec![USER_CTRL, 0x00]),   // I2C master off
        I2cT::write(MPU, vec![INT_PIN_CFG, 0x02]), // bypass
        I2cT::write_read(AK, vec![WIA], vec![AK8963_ID]),
        I2cT::write(AK, vec![CNTL1, POWER_DOWN]),
        I2cT::write(AK, vec![CNTL1, FUSE_ROM]),
        I2cT::write_read(AK, vec![ASAX], asa.to_vec()),
        I2cT::write_read(AK, vec![ASAX], asa.to_vec()),
        I2cT::write(AK, vec![CNTL1, POWER_DOWN]),
        I2cT::write(AK, vec![CNTL1, CONTINUOUS_100HZ_16BIT]),
    ]
}

/// The bring-up's waits: the MPU's reset, then one per AK8963 mode change.
pub fn waits() -> Vec<DelayT> {
    let mode = DelayT::delay_us(config::compass::MODE_CHANGE_US);
    vec![DelayT::delay_us(config::compass::MPU_RESET_TIME_US), mode.clone(), mode.clone(), mode.clone(), mode]
}

/// One read: ST1, then the three axes (little-endian) and ST2.
pub fn read_script(st1: u8, raw: [i16; 3], st2: u8) -> Vec<I2cT> {
    let mut data: Vec<u8> = raw.iter().flat_map(|v| v.to_le_bytes()).collect();
    data.push(st2);
    vec![I2cT::write_read(AK, vec![ST1], vec![st1]), I2cT::write_read(AK, vec![HXL], data)]
}

/// A compass brought up (with [`ASA`]) over a mock that then expects `then`.
pub fn new_compass(then: &[I2cT]) -> Compass<I2cMock, CheckedDelay> {
    let i2c = I2cMock::new(&[bring_up_script(ASA), then.to_vec()].concat());
    let mut c = Compass::with_config(i2c, CheckedDelay::new(&waits()));
    c.reinit().unwrap();
    assert_eq!(c.asa(), ASA);
    c
}

/// Checks that every expected transfer and wait happened.
pub fn done(c: Compass<I2cMock, CheckedDelay>) {
    let (mut i2c, mut delay) = c.release();
    i2c.done();
    delay.done();
}
