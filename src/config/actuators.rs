//! The servo actuator model: eight lines from command (0..180) to speed, and
//! the command ranges they were measured on (report 3.2, data
//! `servo_runs.csv`). Forward and backward lines give wheel speed in rad/s
//! (car speed = wheel speed * wheel radius); cw and ccw lines give the car's
//! turn rate in rad/s. Every line is a magnitude (see `model::actuator`).

use super::geometry::WHEEL_RADIUS;
use crate::model::actuator::{ActuatorModel, MotionLines, Trim, WheelLine};

/// Forward: left `y = 0.14 x - 8.205` on 103..112, right
/// `y = -0.146 x + 15.85` on 57..66 (data says -0.146; the report printed
/// `0.145 x - 15.85`, which is negative over the whole range).
pub const FORWARD: MotionLines =
    MotionLines { left: WheelLine::new(0.14, -8.205, 103, 112), right: WheelLine::new(-0.146, 15.85, 57, 66) };
/// Backward: left `y = -0.205 x + 19.77` on 58..70, right `y = 0.195 x - 13.95` on 99..111.
pub const BACKWARD: MotionLines =
    MotionLines { left: WheelLine::new(-0.205, 19.77, 58, 70), right: WheelLine::new(0.195, -13.95, 99, 111) };
/// Clockwise: left `y = 0.0862 x - 6.2423` on 100..111, right `y = 0.1431 x - 13.442` on 110..117.
pub const CW: MotionLines =
    MotionLines { left: WheelLine::new(0.0862, -6.2423, 100, 111), right: WheelLine::new(0.1431, -13.442, 110, 117) };
/// Counter-clockwise: left `y = -0.0908 x + 8.6171` on 60..71, right `y = -0.0344 x + 4.7604` on 43..70.
pub const CCW: MotionLines =
    MotionLines { left: WheelLine::new(-0.0908, 8.6171, 60, 71), right: WheelLine::new(-0.0344, 4.7604, 43, 70) };

/// Left servo trim in command steps (moves its stop point from 90).
/// Tune on the robot with the `trim` command until the wheel stands still.
pub const LEFT_TRIM: Trim = Trim::from_f64(0.0);
/// Right servo trim in command steps.
pub const RIGHT_TRIM: Trim = Trim::from_f64(0.0);

/// The actuator model the firmware drives with: the lines above, the
/// wheel radius and the trims.
pub const MODEL: ActuatorModel = ActuatorModel {
    forward: FORWARD,
    backward: BACKWARD,
    cw: CW,
    ccw: CCW,
    wheel_radius: WHEEL_RADIUS,
    left_trim: LEFT_TRIM,
    right_trim: RIGHT_TRIM,
};
