//! The simulated paperbot (host only, feature `sim`; std and f64 allowed):
//! the arena and its ray casting, the physical robot with noise, the fake
//! chips on a simulated I2C bus, and [`robot::SimRobot`], which runs the
//! firmware's control loop against all of it. Shared by the tests, the
//! `simulate` example, fuzzing and the teleop tool.

pub mod arena;
pub mod body;
pub mod bus;
pub mod drawn;
pub mod link;
pub mod mpu9250;
pub mod noise;
pub mod realism;
pub mod robot;
pub mod script;
pub mod sensors;
pub mod serve;
pub mod summary;
pub mod svg;
pub mod vl53l0x;
pub mod wire;
