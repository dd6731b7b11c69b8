//! Core size probe: the no_std core alone (math, models, estimator, control
//! loop and protocol) over trait doubles whose readings come from a register
//! read, so nothing folds away. run.sh compares it with `size_base`.
#![no_std]
#![no_main]

use core::hint::black_box as bb;
use core::ptr::{read_volatile, write_volatile};

use paperbot::config;
use paperbot::control::protocol::{parse, LineBuffer};
use paperbot::control::{Controller, LineSink};
use paperbot::driver::{CompassSample, HeadingSensor, LidarSample, MagCalibrate, RangeSensor, SensorError, Servos};
use paperbot::math::{atan2, sin_cos, Angle, Dt};
use paperbot::model::compass::{MagCalibration, MagCounts};
use paperbot::model::measurement::{expected_heading, expected_lidar, Arena, LidarId};
use paperbot::model::{step, Motion, Pose, ServoCmd};

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

#[no_mangle]
pub extern "C" fn rust_main() -> i32 {
    let mut ctl = Controller::new(InLidar, InLidar, InCompass(MagCalibration::IDENTITY), OutServos, Pose::default());
    let mut uart = Uart;
    ctl.feed(input() as u8, &mut uart);
    ctl.tick(input(), &mut uart);
    bb(ctl.pose());
    bb(step(&bb(Pose::default()), bb(Motion::Stop), bb(Dt::MAX)));
    bb(config::compass::MODEL.heading_from_raw(bb(MagCounts::default()), bb([128; 3])));
    bb(config::lidar::FRONT.range(bb(0)));
    bb(config::lidar::RIGHT.range(bb(0)));
    bb(config::actuators::MODEL.drive(bb(Motion::Stop)));
    bb(config::actuators::MODEL.motion_from_commands(bb(ServoCmd::NEUTRAL), bb(ServoCmd::NEUTRAL)));
    bb(sin_cos(bb(Angle::ZERO)));
    bb(atan2(bb(0), bb(0)));
    bb(bb(Angle::ZERO).to_signed_millidegrees());
    bb(parse(bb(b"fwd 0.13 2.5")).is_ok());
    let mut lb = LineBuffer::new();
    bb(lb.push(bb(b'x')).is_some());
    bb(expected_lidar(&Arena::DEFAULT, &bb(Pose::default()), bb(LidarId::Front)));
    bb(expected_heading(&bb(Pose::default())));
    0
}

include!("../probe_rt.rs");
