//! `teleop --web`: a live map of the robot in a browser, served by the
//! laptop the robot is plugged into (feature `web`, host only). See
//! docs/web.md for the user's side.
//!
//! - [`model`]: the robot's lines as the page's JSON messages (pose and
//!   its uncertainty, lidar rays as `replay` draws them, sensors, faults,
//!   messages, the simulator's true pose);
//! - [`command`]: what a page may ask, and why a message is malformed;
//! - [`session`]: the pages, which one drives, and the held motion, which
//!   runs out unless the page repeats it (so a closed tab stops the robot);
//! - [`server`]: the port: the page's files and its WebSocket (tungstenite);
//! - [`run()`]: the loop that ties them to the serial link.

pub mod command;
pub mod model;
pub mod run;
pub mod server;
pub mod session;

pub use command::{parse_command, Command};
pub use model::{parse_truth, Live, MapPose, Role};
pub use run::{run, WebOptions, WebReport};
pub use server::{Event, WebServer};
pub use session::Session;
