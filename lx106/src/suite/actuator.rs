//! `paperbot::model::actuator` with the config's lines (report 3.2): the
//! forward model (commands to motion), the inverse (motion to commands, with
//! saturation) and stop, against the host's f64 evaluation of the lines.

use super::state::motion;
use super::{check, Mismatches, Test, TestResult};
use crate::println;
use crate::vectors::{Mv, ACTUATOR_FORWARD, ACTUATOR_INVERSE};
use core::hint::black_box;
use paperbot::config::actuators::MODEL;
use paperbot::model::{Motion, MotionKind, ServoCmd};

pub const TESTS: &[Test] = &[
    ("forward_model", forward_model),
    ("inverse_model_and_saturation", inverse_model),
    ("stop_is_neutral", stop_is_neutral),
    ("inverse_then_forward_round_trip", round_trip),
];

/// Bits of the motion and whether the kinds agree.
fn same_kind(a: Motion, b: Mv) -> Option<(i32, i32)> {
    match (a, b) {
        (Motion::Stop, Mv::Stop) => Some((0, 0)),
        (Motion::Straight(v), Mv::Straight(w)) => Some((v.to_bits(), w)),
        (Motion::Turn(v), Mv::Turn(w)) => Some((v.to_bits(), w)),
        _ => None,
    }
}

fn forward_model() -> TestResult {
    let mut m = Mismatches::new();
    let mut worst = 0.0f32;
    for v in ACTUATOR_FORWARD {
        let left = ServoCmd::from_q8(u32::from(black_box(v.left_q8)));
        let right = ServoCmd::from_q8(u32::from(black_box(v.right_q8)));
        let got = MODEL.motion_from_commands(left, right);
        match same_kind(got, v.expect) {
            // integer rounding of the Q16 lines and unit conversions: 1e-4 relative
            Some((g, w)) if (i64::from(g) - i64::from(w)).abs() <= i64::from(w).abs() / 10_000 + 2 => {
                if w != 0 {
                    worst = worst.max(((g - w) as f32 / w as f32).abs());
                }
            }
            _ => m.fail(format_args!("({}, {}) -> {:?}, f64 {:?}", v.left_q8, v.right_q8, got, v.expect)),
        }
    }
    println!("      {} command pairs, worst relative speed error {:.1e}", ACTUATOR_FORWARD.len(), worst);
    m.result("forward model differs from the report's lines")
}

fn inverse_model() -> TestResult {
    let mut m = Mismatches::new();
    let mut worst = 0;
    for v in ACTUATOR_INVERSE {
        let d = MODEL.drive(black_box(motion(v.request)));
        let (el, er) = (
            (i32::from(d.left.to_q8()) - i32::from(v.left_q8)).abs(),
            (i32::from(d.right.to_q8()) - i32::from(v.right_q8)).abs(),
        );
        worst = worst.max(el).max(er);
        let kind_ok = d.motion.kind() == motion(v.request).kind();
        // 3/256 of a command step
        if el > 3 || er > 3 || d.saturated != v.saturated || !kind_ok {
            m.fail(format_args!(
                "{:?} -> ({}, {}) sat {} {:?}; f64 ({}, {}) sat {}",
                v.request,
                d.left.to_q8(),
                d.right.to_q8(),
                d.saturated,
                d.motion,
                v.left_q8,
                v.right_q8,
                v.saturated
            ));
        }
    }
    println!("      {} requests, worst command error {}/256 step", ACTUATOR_INVERSE.len(), worst);
    m.result("inverse model differs from the report's lines")
}

fn stop_is_neutral() -> TestResult {
    let d = MODEL.drive(black_box(Motion::Stop));
    check(d.left == ServoCmd::NEUTRAL && d.right == ServoCmd::NEUTRAL, "stop is not 90/90")?;
    check(d.motion == Motion::Stop && !d.saturated, "stop reports motion")?;
    check(MODEL.stop() == d, "stop() differs from drive(Stop)")?;
    check(MODEL.motion_from_commands(ServoCmd::NEUTRAL, ServoCmd::NEUTRAL) == Motion::Stop, "90/90 moves")?;
    check(
        MODEL.motion_from_commands(black_box(ServoCmd::from_int(110)), ServoCmd::from_int(110)).kind()
            == MotionKind::Cw,
        "110/110 is not clockwise",
    )
}

fn round_trip() -> TestResult {
    // every non-saturated request comes back within 0.2 % through the forward model
    let mut m = Mismatches::new();
    for v in ACTUATOR_INVERSE.iter().filter(|v| !v.saturated) {
        let d = MODEL.drive(motion(v.request));
        let back = MODEL.motion_from_commands(black_box(d.left), black_box(d.right));
        match same_kind(back, v.request) {
            Some((g, w)) if (i64::from(g) - i64::from(w)).abs() <= i64::from(w).abs() / 500 => {}
            _ => m.fail(format_args!("{:?} -> {:?} -> {:?}", v.request, d, back)),
        }
    }
    m.result("inverse then forward does not return the request")
}
