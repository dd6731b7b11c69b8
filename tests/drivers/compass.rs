//! The compass driver against embedded-hal-mock scripts: the exact
//! bring-up (MPU9250 through the mpu9250 crate's register access, AK8963
//! directly), a read with the ASA applied in integers, data-ready, the
//! overflow flag, and every error path. Every mock ends with `.done()`.

use crate::common;
use common::i2c::{retried, NACK};
use common::mpu9250::*;
use embedded_hal::i2c::ErrorKind;
use embedded_hal_mock::eh1::delay::CheckedDelay;
use embedded_hal_mock::eh1::i2c::{Mock as I2cMock, Transaction as I2cT};
use paperbot::config;
use paperbot::driver::compass::Compass;
use paperbot::driver::{HeadingSensor, MagCalibrate, SensorError};
use paperbot::model::compass::{apply_asa, MagCounts};

/// The one register map of each chip (`driver::compass::{mpu, ak}`, which
/// the driver, the fake chip and these scripts use) against the datasheets'
/// numbers: MPU-9250 register map rev 1.6, AK8963 datasheet section 8.
#[test]
fn the_register_maps_are_the_datasheets() {
    use paperbot::driver::compass::{ak, mpu};
    let mpu_map = [mpu::WHO_AM_I, mpu::PWR_MGMT_1, mpu::PWR_MGMT_2, mpu::USER_CTRL, mpu::INT_PIN_CFG];
    assert_eq!(mpu_map, [0x75, 0x6B, 0x6C, 0x6A, 0x37]);
    let mpu_bits = [mpu::H_RESET, mpu::CLKSEL_AUTO, mpu::DISABLE_ACCEL_GYRO, mpu::BYPASS_EN, mpu::I2C_MST_EN];
    assert_eq!(mpu_bits, [0x80, 0x01, 0x3F, 0x02, 0x20]);
    assert_eq!((mpu::MPU9250_ID, mpu::MPU9255_ID), (0x71, 0x73));
    let ak_map = [ak::WIA, ak::INFO, ak::ST1, ak::HXL, ak::HZH, ak::ST2, ak::CNTL1, ak::CNTL2, ak::ASAX, ak::ASAZ];
    assert_eq!(ak_map, [0x00, 0x01, 0x02, 0x03, 0x08, 0x09, 0x0A, 0x0B, 0x10, 0x12]);
    let ak_bits = [ak::DEVICE_ID, ak::DRDY, ak::DOR, ak::HOFL, ak::BITM, ak::BIT_16, ak::SRST];
    assert_eq!(ak_bits, [0x48, 0x01, 0x02, 0x08, 0x10, 0x10, 0x01]);
    let modes = [ak::MODE_POWER_DOWN, ak::MODE_SINGLE, ak::MODE_CONT1_8HZ, ak::MODE_CONT2_100HZ, ak::MODE_FUSE_ROM];
    assert_eq!(modes, [0x00, 0x01, 0x02, 0x06, 0x0F]);
}

#[test]
fn bring_up_is_the_exact_sequence() {
    done(new_compass(&[]));
}

#[test]
fn a_read_applies_asa_calibration_axes_and_declination_in_integers() {
    let raw = [1000, -400, 300];
    let c_script = read_script(DRDY, raw, BITM);
    let mut c = new_compass(&c_script);
    let s = c.poll().unwrap();
    assert_eq!(s.raw, MagCounts { x: 1000, y: -400, z: 300 });
    // ASA by hand: raw * (asa + 128) / 256.
    assert_eq!(apply_asa(1000, 0x40), 750);
    assert_eq!(apply_asa(-400, 0xB0), -475);
    assert_eq!(apply_asa(300, 0xFF), 449);
    // f64 reference of the whole path.
    let cal = config::compass::CALIBRATION;
    let adj = [750.0, -475.0, 449.0];
    let f: Vec<f64> =
        (0..3).map(|i| (adj[i] - f64::from(cal.bias[i])) * f64::from(cal.scale_q16[i]) / 65536.0).collect();
    assert!((f64::from(s.field.x) - f[0]).abs() <= 1.0 && (f64::from(s.field.y) - f[1]).abs() <= 1.0);
    let want =
        ((-f[1]).atan2(f[0]).to_degrees() + config::compass::DECLINATION.to_radians_f64().to_degrees() + 360.0) % 360.0;
    let got = f64::from(s.heading.to_millidegrees()) / 1000.0;
    assert!((got - want).abs() < 0.2, "{got} vs {want}");
    done(c);
}

#[test]
fn no_data_ready_means_would_block_and_one_transfer() {
    let mut c = new_compass(&[I2cT::write_read(AK, vec![ST1], vec![0x00])]);
    assert_eq!(c.poll(), Err(nb::Error::WouldBlock));
    done(c);
}

#[test]
fn an_overflowed_sample_is_dropped_and_the_next_one_is_used() {
    let script =
        [read_script(DRDY, [30000, 20000, 0], BITM | HOFL), read_script(DRDY | 0x02, [10, 20, 30], BITM)].concat();
    let mut c = new_compass(&script);
    assert_eq!(c.poll(), Err(nb::Error::Other(SensorError::BadSample)));
    // DOR set too (a skipped sample): the sample itself is fine.
    assert_eq!(c.poll().map(|s| s.raw), Ok(MagCounts { x: 10, y: 20, z: 30 }));
    done(c);
}

#[test]
fn read_errors_are_typed() {
    let cases: [(usize, ErrorKind, SensorError); 3] = [
        (0, NACK, SensorError::Missing),
        (0, ErrorKind::Bus, SensorError::Bus),
        (1, ErrorKind::ArbitrationLoss, SensorError::Bus),
    ];
    for (step, kind, want) in cases {
        let mut script = read_script(DRDY, [1, 2, 3], BITM);
        script.truncate(step + 1);
        let failing = script.pop().unwrap().with_error(kind);
        script.extend(retried(failing));
        let mut c = new_compass(&script);
        assert_eq!(c.poll(), Err(nb::Error::Other(want)), "{step} {kind:?}");
        done(c);
    }
}

/// A bring-up that stops at `step` with `fail`; `delays` waits happen.
fn failing_bring_up(step: usize, fail: Vec<I2cT>, delays: usize, want: SensorError) {
    let mut script = bring_up_script(ASA);
    script.truncate(step);
    script.extend(fail);
    let mut w = waits();
    w.truncate(delays);
    let mut c = Compass::with_config(I2cMock::new(&script), CheckedDelay::new(&w));
    assert_eq!(c.reinit(), Err(want), "step {step}");
    assert!(!c.is_running());
    assert_eq!(c.poll(), Err(nb::Error::Other(SensorError::NotReady)));
    done(c);
}

#[test]
fn bring_up_errors_are_typed() {
    // Nobody at 0x68.
    failing_bring_up(
        0,
        retried(I2cT::write_read(MPU, vec![WHO_AM_I], vec![0]).with_error(NACK)),
        0,
        SensorError::Missing,
    );
    // An MPU6500: no magnetometer.
    failing_bring_up(0, vec![I2cT::write_read(MPU, vec![WHO_AM_I], vec![0x70])], 0, SensorError::Missing);
    // Reset not acknowledged.
    failing_bring_up(
        1,
        retried(I2cT::write(MPU, vec![PWR_MGMT_1, 0x80]).with_error(ErrorKind::Bus)),
        0,
        SensorError::Bus,
    );
    // Bypass write lost.
    failing_bring_up(
        5,
        retried(I2cT::write(MPU, vec![INT_PIN_CFG, 0x02]).with_error(ErrorKind::Bus)),
        1,
        SensorError::Bus,
    );
    // The AK8963 does not show up (bypass did not take).
    failing_bring_up(6, retried(I2cT::write_read(AK, vec![WIA], vec![0]).with_error(NACK)), 1, SensorError::Missing);
    // Something else at 0x0C.
    failing_bring_up(6, vec![I2cT::write_read(AK, vec![WIA], vec![0x00])], 1, SensorError::Missing);
    // The two fuse-ROM reads disagree: a corrupted transfer.
    failing_bring_up(10, vec![I2cT::write_read(AK, vec![ASAX], vec![0x40, 0xB0, 0xFE])], 3, SensorError::Bus);
    // Continuous mode not set.
    failing_bring_up(
        12,
        retried(I2cT::write(AK, vec![CNTL1, CONTINUOUS_100HZ_16BIT]).with_error(ErrorKind::Bus)),
        4,
        SensorError::Bus,
    );
}

#[test]
fn a_new_calibration_takes_effect_on_the_next_read() {
    let script = [read_script(DRDY, [300, 0, 0], BITM), read_script(DRDY, [300, 0, 0], BITM)].concat();
    let mut c = new_compass(&script);
    let before = c.poll().unwrap();
    let mut cal = c.calibration();
    cal.bias = [0, 0, 0];
    cal.scale_q16 = [65536; 3];
    c.set_calibration(cal);
    let after = c.poll().unwrap();
    assert_ne!(before.field, after.field);
    assert_eq!(after.field.x, apply_asa(300, ASA[0]));
    done(c);
}
