//! Instructions of the refinement of the search's fix (`model::locate::
//! refine`), which runs once at power-up and on `locate` after the
//! search: a figure, not a bar. The survey is what the firmware's own arena
//! model says the lidars read as the body turns about a pivot 60 mm behind
//! the axle (issue #29's hard world), four views 45 degrees apart and the
//! readings of the three turns between them (a pair every third of a
//! turn's 33 ticks), the compass 4 degrees off.
//!
//! The loop does the fit a pass at a time (`Refine::step`: one pass over
//! the readings, a `Beam` each): each pass's count, worst and median,
//! against the 10 ms tick.

use crate::println;
use crate::rt::count;
use core::hint::black_box;
use paperbot::config::geometry::ROTATION_TO_REFERENCE;
use paperbot::config::timing::LOOP_HZ;
use paperbot::math::{mul_q30, Angle, Length};
use paperbot::model::locate::refine::Refine;
use paperbot::model::locate::turns::Turn;
use paperbot::model::locate::{locate, Readings};
use paperbot::model::measurement::{expected_lidar, Arena, LidarId};
use paperbot::model::Pose;

const CLOCK_MHZ: u32 = 80;
const TICK_INSTRUCTIONS: u32 = CLOCK_MHZ * 1_000_000 / LOOP_HZ;
/// Most passes whose counts are kept.
const MAX_PASSES: usize = 2048;
/// The pivot, mm, and the first view's heading, degrees; the views 45
/// degrees apart clockwise.
const PIVOT: (i32, i32) = (380, 250);
const FIRST_DEG: i32 = 30;
const VIEWS: usize = 4;
/// The compass's error, degrees; the turn's ticks.
const BIAS_DEG: i32 = 4;
const TURN_TICKS: u16 = 33;

/// The reference point at `mdeg` millidegrees about the pivot (the lever
/// D + 60 mm).
fn pose(mdeg: i32) -> Pose {
    let lever = ROTATION_TO_REFERENCE.0 + Length::from_mm(60).0;
    let mut p = Pose::from_mm(0, 0, Angle::from_millidegrees(mdeg));
    let (s, c) = p.sin_cos();
    Pose::from_mm(PIVOT.0 + (mul_q30(lever, c) >> 16), PIVOT.1 + (mul_q30(lever, s) >> 16), p.theta)
}

fn survey() -> ([Readings; VIEWS], [Turn; VIEWS - 1]) {
    let read = |p: &Pose, id| expected_lidar(&Arena::DEFAULT, p, id);
    let mut views = [Readings { heading: Angle::ZERO, front: None, right: None }; VIEWS];
    for (i, v) in views.iter_mut().enumerate() {
        let deg = FIRST_DEG + 45 * i as i32;
        let p = pose(deg * 1000);
        *v = Readings {
            heading: Angle::from_millidegrees((deg + BIAS_DEG) * 1000),
            front: read(&p, LidarId::Front),
            right: read(&p, LidarId::Right),
        };
    }
    let turns = core::array::from_fn(|j| {
        let mut t = Turn::new(true, 1);
        for tick in (3..TURN_TICKS).step_by(3) {
            let mdeg = (FIRST_DEG + 45 * j as i32) * 1000 + 45_000 * i32::from(tick) / i32::from(TURN_TICKS);
            let p = pose(mdeg);
            for id in [LidarId::Front, LidarId::Right] {
                if let Some(d) = read(&p, id) {
                    t.push(id, tick, d);
                }
            }
        }
        t.end(TURN_TICKS);
        t
    });
    (views, turns)
}

pub fn run() {
    let (views, turns) = survey();
    println!();
    println!(
        "## Refining the fix (instructions a pass, `Refine::step`; {} views about ({}, {}) mm, the tick at {} MHz is {})",
        VIEWS, PIVOT.0, PIVOT.1, CLOCK_MHZ, TICK_INSTRUCTIONS
    );
    println!();
    let Ok(fix) = locate(&Arena::DEFAULT, &views) else {
        println!("no fix: the search found nothing");
        return;
    };
    let mut refine = Refine::new(fix, &views, &turns);
    let mut counts = [0u32; MAX_PASSES];
    let (mut passes, mut worst, mut total) = (0usize, 0u32, 0u64);
    let refined = loop {
        let mut answer = None;
        let c = count(|| answer = black_box(refine.step(&Arena::DEFAULT, black_box(&views), black_box(&turns))));
        if let Some(slot) = counts.get_mut(passes) {
            *slot = c;
        }
        passes += 1;
        worst = worst.max(c);
        total += u64::from(c);
        if let Some(r) = answer {
            break r;
        }
    };
    let kept = &mut counts[..passes.min(MAX_PASSES)];
    kept.sort_unstable();
    let median = kept[kept.len() / 2];
    let per_mille = worst / (TICK_INSTRUCTIONS / 1000);
    println!("| passes (ticks) | worst pass | median pass | worst, share of the tick | all | pose |");
    println!("| ---: | ---: | ---: | ---: | ---: | --- |");
    let pose = refined.map(|r| (r.pose.x.to_length().to_mm(), r.pose.y.to_length().to_mm(), r.vouched));
    println!("| {} | {} | {} | {}.{} % | {} | {:?} |", passes, worst, median, per_mille / 10, per_mille % 10, total, pose);
    println!("BENCH refine_pass_worst {}", worst);
    println!("BENCH refine_pass_median {}", median);
    println!("BENCH refine_passes {}", passes);
}
