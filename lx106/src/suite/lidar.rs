//! `paperbot::model::lidar` with the config's lines (report 3.3): distances,
//! too close, and 8190/8191 (and beyond the valid window) as no target.

use super::{check, Mismatches, Test, TestResult};
use crate::println;
use crate::vectors::{LidarExp, LIDAR};
use core::hint::black_box;
use paperbot::config::lidar::{FRONT, RIGHT};
use paperbot::model::Range;

pub const TESTS: &[Test] = &[("readings_vs_f64", readings), ("no_target_codes", no_target)];

fn readings() -> TestResult {
    let mut m = Mismatches::new();
    for v in LIDAR {
        let model = if v.front { &FRONT } else { &RIGHT };
        let got = model.range(black_box(v.reading));
        let ok = match (got, v.expect) {
            (Range::Target(d), LidarExp::Target(w)) => (d.0 - w).abs() <= 1,
            (Range::NoTarget, LidarExp::NoTarget) | (Range::TooClose, LidarExp::TooClose) => true,
            _ => false,
        };
        if !ok {
            m.fail(format_args!("front {} reading {} -> {:?}, f64 {:?}", v.front, v.reading, got, v.expect));
        }
    }
    println!("      {} readings on both lidars", LIDAR.len());
    m.result("lidar model differs from the report's lines")
}

fn no_target() -> TestResult {
    for model in [&FRONT, &RIGHT] {
        check(model.range(black_box(8190)) == Range::NoTarget, "8190 is not 'no target'")?;
        check(model.range(black_box(8191)) == Range::NoTarget, "8191 is not 'no target'")?;
        check(model.range(black_box(500)).distance().is_some(), "500 mm gives no distance")?;
    }
    Ok(())
}
