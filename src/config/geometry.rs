//! Robot geometry.

use super::*;
use crate::model::lidar::LidarMount;

/// Wheel radius: 20 mm (report 3.2 uses r = 0.02 m; its "200 mm
/// diameter" is a typo).
pub const WHEEL_RADIUS: Length = Length::from_mm_f64(20.0);
/// Distance between the wheels: 85 mm (report 1).
pub const AXLE_LENGTH: Length = Length::from_mm_f64(85.0);
/// D: from the rotation axis (axle midpoint) to the car's reference
/// point, mm. The report gives no number; the team's later estimator used
/// 56 mm (fact sheet). Must stay below 128 mm (with a pivot learned up to
/// `estimator::PIVOT_MAX_MM` behind the axle the turn's lever stays below
/// the state update's 255 mm, `model::state::Lever`).
pub const ROTATION_TO_REFERENCE: Length = Length::from_mm_f64(56.0);
/// The paper skid drags about 70 mm behind the axle (report 1).
pub const SKID_BEHIND_AXLE: Length = Length::from_mm_f64(70.0);
/// Half the body's width, mm: its widest point is the right lidar, 53 mm
/// left of the reference point (`RIGHT_LIDAR`, fact sheet); the wheels
/// are 42.5 mm to each side (`AXLE_LENGTH`). With the reference point in
/// front and the skid behind, the body fits in a rectangle from the
/// reference point back to the skid, this far to each side (the points
/// the simulator keeps in the box, `sim::robot::body_fits`, all lie in it).
pub const BODY_HALF_WIDTH: Length = Length::from_mm_f64(53.0);

/// Front lidar: 50 mm behind the reference point, looking forward
/// (fact sheet, from the team's later estimator; lateral offset not
/// recorded, taken as 0).
pub const FRONT_LIDAR: LidarMount =
    LidarMount { forward: Length::from_mm_f64(-50.0), right: Length::ZERO, direction: Angle::ZERO };
/// Right lidar: 53 mm left of the reference point, looking right
/// (fact sheet, from the team's later estimator).
pub const RIGHT_LIDAR: LidarMount =
    LidarMount { forward: Length::ZERO, right: Length::from_mm_f64(-53.0), direction: Angle::QUARTER_TURN };

const _: () = assert!(ROTATION_TO_REFERENCE.0 >= 0 && ROTATION_TO_REFERENCE.0 < (128 << 16));
