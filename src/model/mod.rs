//! Pure models from the lab report: actuator lines (both directions), lidar
//! lines, the compass, and the state update. No I/O.

pub mod actuator;
pub mod compass;
pub mod estimator;
#[cfg(feature = "std")]
pub mod fit;
pub mod lidar;
pub mod measurement;
pub mod state;

pub use actuator::{ActuatorModel, Drive, Motion, MotionKind, ServoCmd, Trim};
pub use lidar::{LidarModel, Range};
pub use state::{advance, step, Pose};
