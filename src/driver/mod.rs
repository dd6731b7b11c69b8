//! The chips, through embedded-hal traits: the two lidars, the compass and
//! the servos. The control loop sees them only through the traits below, so
//! the same loop runs on the robot, in tests and in the simulator.

use crate::math::Angle;
use crate::model::compass::{MagCounts, MagField};
use crate::model::lidar::Range;
use crate::model::ServoCmd;

/// Why a sensor could not deliver.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum SensorError {
    /// The bus transaction failed (NACK, arbitration, stuck line...).
    Bus,
    /// The chip did not answer in time or never became ready.
    Timeout,
    /// The chip answered with the wrong identity (or not at all at bring-up).
    Missing,
    /// The chip reported a measurement it could not make (e.g. magnetic
    /// overflow); the sample was dropped.
    BadSample,
    /// The sensor is not initialised (never brought up, or failed since).
    NotReady,
}

/// One lidar reading: the chip's raw value and what the model makes of it.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub struct LidarSample {
    /// The VL53L0X's reading, mm (8190/8191 = no target).
    pub raw_mm: u16,
    /// Distance from the car's reference point, or no target.
    pub range: Range,
}

/// One compass reading: raw counts, corrected field and heading.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub struct CompassSample {
    pub raw: MagCounts,
    pub field: MagField,
    /// Heading clockwise from north (declination applied).
    pub heading: Angle,
}

/// A distance sensor that measures continuously.
pub trait RangeSensor {
    /// The newest reading if one is ready (`WouldBlock` otherwise). Never blocks.
    fn poll(&mut self) -> nb::Result<LidarSample, SensorError>;
    /// Brings the sensor (back) up from scratch; may take a few ms.
    fn reinit(&mut self) -> Result<(), SensorError>;
}

/// A heading sensor that measures continuously.
pub trait HeadingSensor {
    /// The newest reading if one is ready (`WouldBlock` otherwise). Never blocks.
    fn poll(&mut self) -> nb::Result<CompassSample, SensorError>;
    /// Brings the sensor (back) up from scratch; may take a few ms.
    fn reinit(&mut self) -> Result<(), SensorError>;
}

/// The two wheel servos.
pub trait Servos {
    /// Sets both commands (0..180 scale, 90 = stop; trims are applied by the
    /// caller through the actuator model).
    fn set(&mut self, left: ServoCmd, right: ServoCmd);
}

/// A compass whose hard- and soft-iron calibration can be measured and
/// replaced at run time (see [`crate::model::compass::MagCalibrator`]).
pub trait MagCalibrate {
    /// The chip's factory sensitivity adjustment (read at bring-up).
    fn asa(&self) -> [u8; 3];
    /// The calibration in use.
    fn calibration(&self) -> crate::model::compass::MagCalibration;
    /// Replaces the calibration (e.g. with a fresh sweep's result).
    fn set_calibration(&mut self, calibration: crate::model::compass::MagCalibration);
    /// The declination added to the magnetic heading.
    fn declination(&self) -> crate::math::Angle;
    /// Replaces the declination (e.g. from the settings in flash).
    fn set_declination(&mut self, declination: crate::math::Angle);
}

pub mod bus;
pub mod compass;
pub mod lidar;
pub mod servo;
