//! Core size probe: the no_std core as the firmware links it (math, models,
//! estimator, control loop and protocol) over trait doubles whose readings
//! come from a register read, so nothing folds away. run.sh compares it with
//! `size_base`.
//!
//! What it links is what `src/bin/firmware.rs` links from the core: the
//! control loop (`Controller::new`, `feed`, `tick`) and the two models the
//! drivers apply to each sample (`LidarModel::range`, the compass's
//! correction and heading). Library functions that only host tools, tests
//! and the simulator call (`step`, `expected_lidar`, `expected_heading`, ...)
//! are not in the firmware, so not counted here.
#![no_std]
#![no_main]

use core::hint::black_box as bb;
use core::ptr::{read_volatile, write_volatile};

use paperbot::control::log::RingLog;
use paperbot::control::settings::{FlashSettings, NoFlash};
use paperbot::math::Angle;
use paperbot::control::{Controller, Hardware, LineSink};
use paperbot::driver::{CompassSample, HeadingSensor, LidarSample, MagCalibrate, RangeSensor, SensorError, Servos};
use paperbot::model::compass::MagCalibration;
use paperbot::model::{Pose, ServoCmd};

const REG_IN: *const u32 = 0x6000_0318 as *const u32;
const REG_OUT: *mut u32 = 0x6000_0000 as *mut u32;

fn input() -> u32 {
    // SAFETY: a register address on the ESP8266; this binary is only linked.
    unsafe { read_volatile(REG_IN) }
}
fn out(v: u32) {
    // SAFETY: as above.
    unsafe { write_volatile(REG_OUT, v) }
}

struct InLidar;
impl RangeSensor for InLidar {
    fn poll(&mut self) -> nb::Result<LidarSample, SensorError> {
        bb(Err(nb::Error::WouldBlock))
    }
    fn reinit(&mut self) -> Result<(), SensorError> {
        bb(Ok(()))
    }
}
struct InCompass(MagCalibration);
impl HeadingSensor for InCompass {
    fn poll(&mut self) -> nb::Result<CompassSample, SensorError> {
        bb(Err(nb::Error::WouldBlock))
    }
    fn reinit(&mut self) -> Result<(), SensorError> {
        bb(Ok(()))
    }
}
impl MagCalibrate for InCompass {
    fn asa(&self) -> [u8; 3] {
        bb([176, 177, 165])
    }
    fn calibration(&self) -> MagCalibration {
        self.0
    }
    fn set_calibration(&mut self, calibration: MagCalibration) {
        self.0 = bb(calibration);
    }
    // no field, as in scripts.rs: the probe's store never restores one
    fn declination(&self) -> Angle {
        bb(Angle(0))
    }
    fn set_declination(&mut self, declination: Angle) {
        bb(declination);
    }
}
struct OutServos;
impl Servos for OutServos {
    fn set(&mut self, left: ServoCmd, right: ServoCmd) {
        bb((left, right));
    }
}
struct Uart;
impl LineSink for Uart {
    fn write_line(&mut self, line: &str) {
        for &b in line.as_bytes() {
            out(u32::from(b));
        }
    }
}

/// The doubles above as the loop's hardware (no on-board log).
struct Probe;

impl Hardware for Probe {
    type Front = InLidar;
    type Right = InLidar;
    type Compass = InCompass;
    type Servos = OutServos;
    type Log = RingLog<0>;
    type Settings = FlashSettings<NoFlash>;
}

#[no_mangle]
pub extern "C" fn rust_main() -> i32 {
    let mut ctl = Controller::<Probe>::new(InLidar, InLidar, InCompass(MagCalibration::IDENTITY), OutServos, Pose::default());
    let mut uart = Uart;
    ctl.feed(input() as u8, &mut uart);
    ctl.tick(input(), &mut uart);
    bb(ctl.pose());
    driver_models();
    0
}

/// What the drivers do with each sample (`driver::lidar`, `driver::compass`),
/// with the configured models.
fn driver_models() {
    use paperbot::config;
    use paperbot::model::compass::MagCounts;
    let raw = MagCounts { x: input() as i16, y: input() as i16, z: input() as i16 };
    bb(config::compass::MODEL.heading_from_raw(raw, bb([176, 177, 165])));
    bb(config::lidar::FRONT.range(input() as u16));
    bb(config::lidar::RIGHT.range(input() as u16));
}

include!("../probe_rt.rs");
