//! Pure models from the lab report: actuator lines (both directions), lidar
//! lines, the compass, and the state update. No I/O.

pub mod actuator;
pub mod compass;
pub mod estimator;
// host only (std): fits over CSV rows whose width `rows` checked first
#[cfg(feature = "std")]
#[allow(clippy::indexing_slicing)]
pub mod fit;
pub mod lidar;
pub mod locate;
pub mod measurement;
pub mod state;

pub use actuator::{ActuatorModel, Drive, Motion, MotionKind, ServoCmd, Trim};
pub use lidar::{LidarModel, LidarMount, Range};
pub use state::{advance, step, Pose};
