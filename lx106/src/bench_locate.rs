//! Instructions of the localization search (`model::locate`), which runs
//! once at power-up and on `locate`: a figure, not a bar. The views are what
//! the firmware's own arena model says the lidars read at a pose and after
//! turns in place of 45 degrees (the axle stays), so the compass's heading
//! fits and the search does its usual work once per view count.

use crate::println;
use crate::rt::count;
use core::hint::black_box;
use paperbot::config::geometry::ROTATION_TO_REFERENCE;
use paperbot::math::{mul_q30, Angle};
use paperbot::model::locate::{locate, Fix, LocateError, Readings};
use paperbot::model::measurement::{expected_lidar, Arena, LidarId};
use paperbot::model::Pose;

/// The lx106's clock, MHz (the ESP8266 at its default 80 MHz).
const CLOCK_MHZ: u32 = 80;

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
}
