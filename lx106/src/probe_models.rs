// The models' and protocol's entry points on their own, as a tool might call
// them: included by src/bin/core_probe.rs and src/bin/size_probe.rs.

fn models_entry_points() {
    use core::hint::black_box as bb;
    use paperbot::config;
    use paperbot::control::protocol::{parse, LineBuffer};
    use paperbot::math::{atan2, sin_cos, Angle, Dt};
    use paperbot::model::compass::MagCounts;
    use paperbot::model::measurement::{expected_heading, expected_lidar, Arena, LidarId};
    use paperbot::model::{step, Motion, Pose, ServoCmd};

    bb(step(&bb(Pose::default()), bb(Motion::Stop), bb(Dt::MAX)));
    bb(config::compass::MODEL.heading_from_raw(bb(MagCounts::default()), bb([128; 3])));
    bb(config::lidar::FRONT.range(bb(0)));
    bb(config::lidar::RIGHT.range(bb(0)));
    bb(config::actuators::MODEL.drive(bb(Motion::Stop)));
    bb(config::actuators::MODEL.motion_from_commands(bb(ServoCmd::NEUTRAL), bb(ServoCmd::NEUTRAL)));
    bb(sin_cos(bb(Angle::ZERO)));
    bb(atan2(bb(0), bb(0)));
    bb(bb(Angle::ZERO).to_signed_millidegrees());
    bb(parse(bb(b"fwd 0.13 2.5")).is_ok());
    let mut lb = LineBuffer::new();
    bb(lb.push(bb(b'x')).is_some());
    bb(expected_lidar(&Arena::DEFAULT, &bb(Pose::default()), bb(LidarId::Front)));
    bb(expected_heading(&bb(Pose::default())));
}
