//! Size probe: the core's robot-side entry points and nothing else (no
//! formatting, no tests). run.sh compares its .text, .rodata, .data and
//! .bss with `size_base` (the same runtime, no core calls): the difference
//! is the core's footprint. Also checked: no soft-float routine is linked.
//! Add each new robot-side entry point (protocol parser, control tick) here.
#![no_std]
#![no_main]

use core::hint::black_box as bb;
use paperbot::config;
use paperbot::math::{atan2, sin_cos, Angle, Dt};
use paperbot::model::compass::MagCounts;
use paperbot::model::{step, Motion, Pose, ServoCmd};

#[no_mangle]
pub extern "C" fn rust_main() -> i32 {
    bb(step(&bb(Pose::default()), bb(Motion::Stop), bb(Dt::MAX)));
    bb(config::compass::MODEL.heading_from_raw(bb(MagCounts::default()), bb([128; 3])));
    bb(config::lidar::FRONT.range(bb(0)));
    bb(config::lidar::RIGHT.range(bb(0)));
    bb(config::actuators::MODEL.drive(bb(Motion::Stop)));
    bb(config::actuators::MODEL.motion_from_commands(bb(ServoCmd::NEUTRAL), bb(ServoCmd::NEUTRAL)));
    bb(sin_cos(bb(Angle::ZERO)));
    bb(atan2(bb(0), bb(0)));
    bb(bb(Angle::ZERO).to_signed_millidegrees());
    bb(paperbot::control::protocol::parse(bb(b"fwd 0.13 2.5")).is_ok());
    0
}

include!("../probe_rt.rs");
