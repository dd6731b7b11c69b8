//! The MPU9250's AK8963 magnetometer.

use super::Angle;
use crate::model::compass::{Axis, AxisMap, CompassModel, MagCalibration};

/// Hard-iron biases x 79, y 35, z 2 counts; soft-iron scales x 0.679012,
/// y 0.833333, z 3.055556 (report 2.4, Figure 4).
pub const CALIBRATION: MagCalibration = MagCalibration::from_f64([79.0, 35.0, 2.0], [0.679012, 0.833333, 3.055556]);
/// Declination at UCLA: 11 deg 56 min east (report 2.4; the course
/// sketch's `11 + (56/60)` is 11 in integer arithmetic). 0 for a frame
/// whose x is magnetic north.
pub const DECLINATION: Angle = Angle::from_degrees_f64(11.0 + 56.0 / 60.0);
/// The magnetometer's +x faced north when the car did (report 2.4), so
/// its x is the car's front; the AK8963 frame is right-handed with z
/// down, so its y is the car's right. (Its axes are not the
/// accelerometer's: x and y swapped, z inverted.)
pub const AXES: AxisMap = AxisMap { forward: Axis::X, right: Axis::Y };

/// The compass model the firmware reads headings with: the calibration,
/// the axes and the declination above.
pub const MODEL: CompassModel = CompassModel { calibration: CALIBRATION, axes: AXES, declination: DECLINATION };

/// Calibration sweep: samples to collect while turning in place.
pub const CALIBRATION_SAMPLES: u16 = 1000;
/// A sweep that has its samples but not its sectors keeps collecting up
/// to this many more: two turns at the calibration turn rate (the first
/// turn only builds the min/max box and counts about 9 sectors).
pub const CALIBRATION_EXTRA_SAMPLES: u16 = 500;
/// A sweep must visit this many of 12 30-degree sectors to be accepted.
pub const CALIBRATION_MIN_SECTORS: u8 = 11;
/// A calibration sample only marks a sector if its horizontal field,
/// seen from the sweep's running centre, is at least this long (larger
/// component), ASA-adjusted counts: 7.5 uT at 0.15 uT per count, a
/// third of the horizontal field at UCLA (~24 uT, NOAA WMM), well above
/// the AK8963's noise (a few counts), so a robot standing still visits
/// no sectors.
pub const CALIBRATION_MIN_RADIUS: i32 = 50;
/// Turn rate of the calibration sweep (clockwise), mrad/s: inside the
/// clockwise lines' common measured range (about 2.2..3.2 rad/s, data
/// `servo_runs.csv`), so one turn takes 2.5 s, 250 samples at 100 Hz.
pub const CALIBRATION_TURN_MRAD_S: i32 = 2_500;
/// A sweep that has not collected its samples after this long per
/// sample is abandoned (and the robot stops), ms: twice the AK8963's
/// 10 ms period in continuous mode 2.
pub const CALIBRATION_MS_PER_SAMPLE: u32 = 20;

/// Wait after the MPU9250's device reset (PWR_MGMT_1 H_RESET), us: the
/// register start-up time is 100 ms (MPU-9250 datasheet, table 6.2;
/// the mpu9250 crate waits the same).
pub const MPU_RESET_TIME_US: u32 = 100_000;
/// Wait after each AK8963 mode change, us: at least 100 us in power-down
/// before the next mode (AK8963 datasheet 6.3), with margin.
pub const MODE_CHANGE_US: u32 = 200;
