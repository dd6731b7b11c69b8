//! The control layer: the tick (sensing, state update, acting, deadman,
//! telemetry) and the serial protocol.

pub mod protocol;
