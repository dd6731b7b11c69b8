//! `paperbot::model::compass` with the config's calibration (report 2.4):
//! raw counts and ASA to heading, against the host's f64 evaluation.

use super::{check, Mismatches, Test, TestResult};
use crate::println;
use crate::vectors::COMPASS;
use core::hint::black_box;
use paperbot::config::compass::MODEL;
use paperbot::math::Angle;
use paperbot::model::compass::{apply_asa, MagCounts};

pub const TESTS: &[Test] = &[("heading_from_raw_vs_f64", heading_from_raw), ("asa_adjustment", asa)];

fn heading_from_raw() -> TestResult {
    // The model works in whole counts (ASA and soft-iron results rounded):
    // at 250 counts of field that is up to ~2/250 rad; bound 0.5 degree.
    const TOL: i32 = 5_965_232; // 0.5 deg in angle LSB
    let mut m = Mismatches::new();
    let mut worst = 0;
    for v in COMPASS {
        let raw = MagCounts { x: v.raw[0], y: v.raw[1], z: v.raw[2] };
        let got = MODEL.heading_from_raw(black_box(raw), black_box(v.asa));
        let e = got.diff(Angle(v.heading)).abs();
        worst = worst.max(e);
        if e > TOL {
            m.fail(format_args!(
                "{:?} asa {:?}: {} mdeg, f64 {} mdeg",
                v.raw,
                v.asa,
                got.to_millidegrees(),
                Angle(v.heading).to_millidegrees()
            ));
        }
    }
    println!(
        "      {} headings round the circle, worst error {:.3} deg (bound 0.5)",
        COMPASS.len(),
        worst as f32 * (360.0 / 4294967296.0)
    );
    m.result("heading differs from the f64 compass model")
}

fn asa() -> TestResult {
    check(apply_asa(black_box(1000), 128) == 1000, "ASA 128 is not 1.0")?;
    check(apply_asa(black_box(1000), 255) == 1496, "ASA 255: 1000 * 383 / 256 = 1496.1")?;
    check(apply_asa(black_box(-1000), 0) == -500, "ASA 0: -1000 / 2")?;
    check(apply_asa(black_box(i16::MIN), 255) == -49_024, "ASA 255 at i16::MIN")
}
