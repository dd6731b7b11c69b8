//! Property tests for the models' inverses: the actuator model's `drive`
//! (motion -> servo commands) against its forward model (commands ->
//! motion), with any trims; each fitted line's inverse; the lidar model's
//! inverse; and the compass correction over every raw reading and ASA.
//! Overflow checks are on in the test build, so any overflow is a failure.

use paperbot::config;
use paperbot::math::{Length, Speed, TurnRate};
use paperbot::model::compass::MagCounts;
use paperbot::model::{ActuatorModel, Motion, MotionKind, ServoCmd, Trim};
use proptest::prelude::*;

fn model_with_trims(l: i16, r: i16) -> ActuatorModel {
    ActuatorModel { left_trim: Trim(l), right_trim: Trim(r), ..config::actuators::MODEL }
}

/// Any trim the protocol accepts (1/256 steps): up to `MAX_TRIM_CENTI`
/// (10 steps) either way, which puts a neutral inside the backward-right
/// and clockwise-left ranges (99..111 and 100..111: a +10 trim moves the
/// stop to 100) and next to others.
fn trim() -> impl Strategy<Value = i16> {
    let max = (config::serial::MAX_TRIM_CENTI * 256 / 100) as i16;
    -max..=max
}

fn any_motion() -> impl Strategy<Value = Motion> {
    prop_oneof![
        1 => Just(Motion::Stop),
        1 => any::<i32>().prop_map(|b| Motion::Straight(Speed::from_bits(b))),
        1 => any::<i32>().prop_map(|b| Motion::Turn(TurnRate::from_bits(b))),
        // most requests near and inside the measured ranges (0.12..0.15 m/s, 2.2..3.2 rad/s)
        4 => (-200i32..=200).prop_map(|mm_s| Motion::Straight(Speed::from_mm_s(mm_s))),
        4 => (-4000i32..=4000).prop_map(|mrad_s| Motion::Turn(TurnRate::from_mrad_s(mrad_s))),
    ]
}

/// Speed magnitude of a motion in a common unit (Q16 rad/s of the wheel
/// for straight motion, of the car for turns), for comparisons.
fn magnitude(m: &ActuatorModel, motion: Motion) -> f64 {
    match motion {
        Motion::Stop => 0.0,
        Motion::Straight(v) => v.to_mps_f64().abs() / (m.wheel_radius.to_mm_f64() / 1000.0),
        Motion::Turn(w) => w.to_rad_s_f64().abs(),
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 4000, ..ProptestConfig::default() })]

    /// Any request, any trims: the commands stay inside the lines'
    /// measured ranges, past each servo's neutral, the motion they make by the forward model is the
    /// one `drive` reports, of the requested kind, and equal to the request
    /// unless the request was outside what both wheels reach (then
    /// `saturated` says so and the result is at the range's edge).
    #[test]
    fn drive_inverts_the_forward_model(request in any_motion(), lt in trim(), rt in trim()) {
        let m = model_with_trims(lt, rt);
        let d = m.drive(request);
        let Some(measured) = m.lines(request.kind()) else {
            prop_assert_eq!(d, m.stop());
            return Ok(());
        };
        // no trim the protocol accepts moves a stop past a range's far end
        let lines = m.usable_lines(request.kind()).unwrap();
        prop_assert!(d.left >= measured.left.min && d.left <= measured.left.max, "{:?}", d);
        prop_assert!(d.right >= measured.right.min && d.right <= measured.right.max, "{:?}", d);
        if request.kind() != MotionKind::Stop {
            prop_assert!(d.left != m.left_neutral() && d.right != m.right_neutral(), "{:?}", d);
        }
        prop_assert!(d.left >= lines.left.min && d.left <= lines.left.max, "{:?}", d);
        prop_assert!(d.right >= lines.right.min && d.right <= lines.right.max, "{:?}", d);
        // the commands are on the request's side of neutral for each wheel
        let forward = m.motion_from_commands(d.left, d.right);
        prop_assert_eq!(forward.kind(), request.kind(), "{:?} -> {:?}", request, d);
        prop_assert_eq!(forward, d.motion);
        let (lo, hi) = lines.common_range_q16().unwrap();
        let (lo, hi) = (f64::from(lo) / 65536.0, f64::from(hi) / 65536.0);
        let (want, got) = (magnitude(&m, request), magnitude(&m, d.motion));
        // 1/256-step commands on Q16 lines: within 0.1 % of the fastest speed
        let tol = 0.001 * hi;
        if want >= lo && want <= hi {
            prop_assert!(!d.saturated || (want - lo).abs() < tol || (want - hi).abs() < tol, "{:?}", d);
            prop_assert!((got - want).abs() < tol, "want {want} got {got} ({:?} -> {:?})", request, d);
        } else {
            prop_assert!(d.saturated);
            let edge = if want < lo { lo } else { hi };
            prop_assert!((got - edge).abs() < tol, "edge {edge} got {got}");
        }
    }

    /// Any pair of commands, any trims: the forward model gives a motion of
    /// bounded speed (never more than the mean of its two lines' values at
    /// their ranges' far ends: no extrapolation) and a stop for the pairs
    /// the report did not model.
    #[test]
    fn forward_model_is_total_and_bounded(l in 0u32..=180 * 256, r in 0u32..=180 * 256, lt in trim(), rt in trim()) {
        let m = model_with_trims(lt, rt);
        let (l, r) = (ServoCmd::from_q8(l), ServoCmd::from_q8(r));
        let motion = m.motion_from_commands(l, r);
        if let Some(lines) = m.lines(motion.kind()) {
            // every line's magnitude grows toward its range's far end
            let (_, a) = lines.left.speed_range_q16();
            let (_, b) = lines.right.speed_range_q16();
            let fastest = (f64::from(a) + f64::from(b)) / 2.0 / 65536.0;
            prop_assert!(magnitude(&m, motion) <= fastest + 1e-3, "{:?} {:?} -> {:?}", l, r, motion);
        }
        if l == m.left_neutral() || r == m.right_neutral() {
            prop_assert_eq!(motion, Motion::Stop);
        }
    }

    /// Each fitted line's inverse: the command for the line's value at a
    /// command inside its measured range is that command (to 1/256 step).
    #[test]
    fn line_inverse_recovers_the_command(which in 0usize..8, frac in 0.0f64..=1.0) {
        let m = config::actuators::MODEL;
        let lines = [m.forward, m.backward, m.cw, m.ccw];
        let ml = lines[which / 2];
        let w = if which % 2 == 0 { ml.left } else { ml.right };
        let span = f64::from(w.max.to_q8() - w.min.to_q8());
        let cmd = ServoCmd::from_q8(u32::from(w.min.to_q8()) + (frac * span).round() as u32);
        let y = w.line.eval_q16(cmd);
        let back = w.line.inverse(y).unwrap();
        // a Q16 y step is worth 1/(256 |slope|) command steps, < 1/256 for the report's slopes
        prop_assert!((i32::from(back.to_q8()) - i32::from(cmd.to_q8())).abs() <= 1, "{:?} -> {} -> {:?}", cmd, y, back);
    }

    /// The lidar model's inverse (what the simulator's chips report) maps
    /// back to the distance within half a reading step.
    #[test]
    fn lidar_reading_for_inverts_range(front: bool, reading in 0u16..9000) {
        let model = if front { config::lidar::FRONT } else { config::lidar::RIGHT };
        match model.range(reading) {
            paperbot::model::Range::Target(d) => {
                let r = model.reading_for(d).unwrap();
                prop_assert_eq!(r, reading);
            }
            other => prop_assert!(
                reading >= paperbot::model::lidar::NO_TARGET_READING
                    || reading > model.max_reading_mm
                    || reading < model.min_reading_mm,
                "{} -> {:?}", reading, other
            ),
        }
        // any distance at all: a reading or None, never a panic
        let any = Length(i32::from(reading).wrapping_mul(0x9E37) ^ i32::from(front));
        let _ = model.reading_for(any);
    }

    /// The compass correction and heading for every raw reading and ASA
    /// byte: the corrected field stays within its documented clamp.
    #[test]
    fn compass_correction_is_total(x: i16, y: i16, z: i16, asa: [u8; 3]) {
        let m = config::compass::MODEL;
        let raw = MagCounts { x, y, z };
        let f = m.correct(raw, asa);
        for v in [f.x, f.y, f.z] {
            prop_assert!(v.abs() <= 1 << 24, "{:?}", f);
        }
        let h = m.heading(&f);
        prop_assert_eq!(m.heading_from_raw(raw, asa), h);
    }
}
