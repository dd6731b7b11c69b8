//! Instructions of the localization search (`model::locate`), which runs
//! once at power-up and on `locate`: a figure, not a bar. The views are what
//! the firmware's own arena model says the lidars read at a pose and after
//! turns in place of 45 degrees (the axle stays), so the compass's heading
//! fits and the search does its usual work once per view count.
//!
//! The loop does the search a slice at a time (`Search::step` of
//! `config::locate::SCORES_PER_TICK` view scores a tick, while the robot
//! stands): each slice's count, worst and median over the whole search,
//! against the 10 ms tick.

use crate::println;
use crate::rt::count;
use core::hint::black_box;
use paperbot::config::geometry::ROTATION_TO_REFERENCE;
use paperbot::config::locate::SCORES_PER_TICK;
use paperbot::config::timing::LOOP_HZ;
use paperbot::math::{mul_q30, Angle};
use paperbot::model::locate::{locate, Fix, LocateError, Readings, Search};
use paperbot::model::measurement::{expected_lidar, Arena, LidarId};
use paperbot::model::Pose;

/// The lx106's clock, MHz (the ESP8266 at its default 80 MHz).
const CLOCK_MHZ: u32 = 80;

/// Instructions in one loop tick at [`CLOCK_MHZ`], at one per cycle.
const TICK_INSTRUCTIONS: u32 = CLOCK_MHZ * 1_000_000 / LOOP_HZ;
/// Most slices whose counts are kept (a pass over the box is 77).
const MAX_SLICES: usize = 1024;

/// Where the views are taken: mm, mm, degrees clockwise from north.
const START: (i32, i32, i32) = (380, 250, 30);

/// The view at (x, y) mm and `deg` degrees: the compass's heading and what
/// the arena model says each lidar reads.
fn view(x: i32, y: i32, deg: i32) -> Readings {
    let pose = Pose::from_mm(x, y, Angle::from_millidegrees(deg * 1000));
    Readings {
        heading: pose.theta,
        front: expected_lidar(&Arena::DEFAULT, &pose, LidarId::Front),
        right: expected_lidar(&Arena::DEFAULT, &pose, LidarId::Right),
    }
}

/// `n` views from [`START`], each after a further 45-degree turn in place
/// clockwise: the reference point swings D about the axle.
fn views(n: usize) -> [Readings; 3] {
    let (x, y, deg) = START;
    let trig = |d: i32| Pose::from_mm(0, 0, Angle::from_millidegrees(d * 1000)).sin_cos();
    let (s0, c0) = trig(deg);
    let d = ROTATION_TO_REFERENCE.0;
    let mut out = [view(x, y, deg); 3];
    for (i, v) in out.iter_mut().enumerate().take(n).skip(1) {
        let turned = deg + 45 * i as i32;
        let (s, c) = trig(turned);
        let dx = (mul_q30(d, c) - mul_q30(d, c0)) >> 16;
        let dy = (mul_q30(d, s) - mul_q30(d, s0)) >> 16;
        *v = view(x + dx, y + dy, turned);
    }
    out
}

pub fn run() {
    println!();
    println!(
        "## Localization search (instructions, once at power-up; at {} MHz; from ({}, {}) mm, {} deg)",
        CLOCK_MHZ, START.0, START.1, START.2
    );
    println!();
    println!("| views | instructions | seconds at {} MHz | fix |", CLOCK_MHZ);
    println!("| ---: | ---: | ---: | --- |");
    for n in [1usize, 3] {
        let all = views(n);
        let v = &all[..n];
        let mut fix: Result<Fix, LocateError> = Err(LocateError::NoReading);
        let instructions = count(|| fix = black_box(locate(&Arena::DEFAULT, black_box(v))));
        let ms = instructions / (CLOCK_MHZ * 1000);
        match fix {
            Ok(f) => {
                let (x, y) = (f.pose.x.to_length().to_mm(), f.pose.y.to_length().to_mm());
                let amb = if f.ambiguous { ", ambiguous" } else { "" };
                println!(
                    "| {} | {} | {}.{:03} | ({}, {}) mm, {} points{} |",
                    n,
                    instructions,
                    ms / 1000,
                    ms % 1000,
                    x,
                    y,
                    f.points,
                    amb
                );
            }
            Err(e) => println!("| {} | {} | {}.{:03} | {:?} |", n, instructions, ms / 1000, ms % 1000, e),
        }
        println!("BENCH locate_{}_views {}", n, instructions);
    }
    per_tick();
}

/// The search as the loop runs it: one `Search::step` of
/// `SCORES_PER_TICK` view scores a tick, to its answer.
fn per_tick() {
    println!();
    println!(
        "### One tick's slice of the search ({} view scores, `Search::step`); the tick at {} MHz is {} instructions",
        SCORES_PER_TICK, CLOCK_MHZ, TICK_INSTRUCTIONS
    );
    println!();
    println!("| views | slices (ticks) | worst slice | median slice | worst, share of the tick |");
    println!("| ---: | ---: | ---: | ---: | ---: |");
    for n in [1usize, 3] {
        let all = views(n);
        let Ok(mut search) = Search::new(&all[..n]) else {
            println!("| {} | no search: no reading | | | |", n);
            continue;
        };
        let mut counts = [0u32; MAX_SLICES];
        let mut slices = 0usize;
        let mut worst = 0u32;
        loop {
            let mut answer = None;
            let c = count(|| answer = black_box(search.step(&Arena::DEFAULT, black_box(SCORES_PER_TICK))));
            if let Some(slot) = counts.get_mut(slices) {
                *slot = c;
            }
            slices += 1;
            worst = worst.max(c);
            if answer.is_some() {
                break;
            }
        }
        let kept = &mut counts[..slices.min(MAX_SLICES)];
        kept.sort_unstable();
        let median = kept[kept.len() / 2];
        // per mille of the tick, printed as a percentage with one decimal
        let per_mille = worst / (TICK_INSTRUCTIONS / 1000);
        println!("| {} | {} | {} | {} | {}.{} % |", n, slices, worst, median, per_mille / 10, per_mille % 10);
        println!("BENCH locate_slice_{}_views_worst {}", n, worst);
        println!("BENCH locate_slice_{}_views_median {}", n, median);
    }
}
