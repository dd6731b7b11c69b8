//! The control layer: the tick (sensing, state update, acting, deadman,
//! telemetry) and the serial protocol.

pub mod goto;
pub mod hardware;
pub mod log;
pub mod mission;
pub mod protocol;
pub mod settings;
pub mod survey;
pub mod tick;

pub use hardware::Hardware;
pub use tick::{Controller, LineSink, Mode, SensorHealth, TICK_US};
