//! The robot's hardware as the control loop sees it: one type per part.

use crate::control::log::RowLog;
use crate::control::settings::SettingsStore;
use crate::driver::{HeadingSensor, MagCalibrate, RangeSensor, Servos};

/// The types of the parts a [`crate::control::Controller`] drives: the
/// robot's drivers in the firmware, simulated ones in `sim`, doubles in
/// tests. An implementing type is a name only (it holds nothing); the
/// controller owns one value of each part.
pub trait Hardware {
    /// The lidar looking ahead.
    type Front: RangeSensor;
    /// The lidar looking to the right.
    type Right: RangeSensor;
    /// The magnetometer, with its run-time calibration.
    type Compass: HeadingSensor + MagCalibrate;
    /// The two wheel servos.
    type Servos: Servos;
    /// The on-board log a mission writes (`RingLog<0>` keeps none: every
    /// row is dropped and counted).
    type Log: RowLog;
    /// Where the settings survive power-off (`save`, `forget`): the
    /// flash's two settings sectors.
    type Settings: SettingsStore;
}
