//! Instruction counts (ICOUNT: exact and repeatable) of the core's hot
//! paths, the state update against the same step in Rust f32 and C float,
//! and the bars they must meet. Prints a Markdown table for BENCHMARKS.md
//! and machine-readable `BENCH name count` lines.
//!
//! Adding a benchmark: one entry in [`core_benches`] (or a row in the step
//! table); adding a bar: one entry in [`bars`].

use crate::float::{c_step_safe, step as f32_step, PoseF};
use crate::println;
use crate::rt::count;
use crate::suite::ports::{d_mm, fixed_motion, fixed_pose, CASES, DT_S};
use crate::vectors::{COMPASS, LIDAR};
use core::hint::black_box;
use paperbot::config;
use paperbot::control::protocol::parse;
use paperbot::math::{atan2, Angle, Dt, Speed, TurnRate};
use paperbot::model::compass::MagCounts;
use paperbot::model::{advance, Motion, ServoCmd};

/// Most instructions a state update (any motion) may take.
pub const STEP_MAX: u32 = 180;
/// The fixed-point step must be at least this many times cheaper than C float.
pub const STEP_VS_C: u32 = 15;

/// Headings the steps are counted at (float sin/cos cost depends on the argument).
const HEADINGS: [f32; 8] = [0.0, 0.5, 1.0, 1.5707964, 2.5, 3.1, -0.8, -2.9];

/// Worst (max) count of `f` over the headings.
fn worst<F: FnMut(f32) -> u32>(mut f: F) -> u32 {
    HEADINGS.iter().map(|&th| f(th)).max().unwrap_or(0)
}

pub struct StepRow {
    pub name: &'static str,
    pub fixed: u32,
    pub rust_f32: u32,
    pub c_float: u32,
    /// The same step when the pose's sin/cos cache is stale (its heading was
    /// just set from outside): one extra `sin_cos`.
    pub cold: u32,
}

pub fn step_rows() -> [StepRow; 3] {
    let dt = Dt::from_micros_saturating(10_000);
    CASES.map(|(name, kind, rate)| {
        let fixed = worst(|th| {
            let p = fixed_pose(&PoseF { x: 100.0, y: -50.0, th });
            let m = fixed_motion(kind, rate);
            let mut p = p;
            count(|| advance(black_box(&mut p), black_box(m), black_box(dt)))
        });
        let rust_f32 = worst(|th| {
            let mut p = PoseF { x: 100.0, y: -50.0, th };
            let d = d_mm();
            count(|| f32_step(black_box(&mut p), black_box(kind), black_box(rate), black_box(DT_S), black_box(d)))
        });
        let c_float = worst(|th| {
            let mut p = PoseF { x: 100.0, y: -50.0, th };
            let d = d_mm();
            count(|| c_step_safe(black_box(&mut p), black_box(kind), black_box(rate), black_box(DT_S), black_box(d)))
        });
        let cold = worst(|th| {
            let mut p = fixed_pose(&PoseF { x: 100.0, y: -50.0, th: th + 1.0 });
            p.theta = fixed_pose(&PoseF { x: 100.0, y: -50.0, th }).theta; // cache now stale
            let m = fixed_motion(kind, rate);
            count(|| advance(black_box(&mut p), black_box(m), black_box(dt)))
        });
        StepRow { name, fixed, rust_f32, c_float, cold }
    })
}

/// Other hot paths of the core: (name, worst count over its inputs).
pub fn core_benches() -> [(&'static str, u32); 9] {
    let compass = COMPASS
        .iter()
        .map(|v| {
            let raw = MagCounts { x: v.raw[0], y: v.raw[1], z: v.raw[2] };
            count(|| {
                black_box(config::compass::MODEL.heading_from_raw(black_box(raw), black_box(v.asa)));
            })
        })
        .max()
        .unwrap_or(0);
    let lidar = LIDAR
        .iter()
        .filter(|v| v.front)
        .map(|v| {
            count(|| {
                black_box(config::lidar::FRONT.range(black_box(v.reading)));
            })
        })
        .max()
        .unwrap_or(0);
    let sincos = crate::bench_trig::sin_cos_instructions();
    let at2 = [(1, 1), (-300, 200), (123_456, -7_654_321), (i32::MAX, 5)]
        .iter()
        .map(|&(y, x)| {
            count(|| {
                black_box(atan2(black_box(y), black_box(x)));
            })
        })
        .max()
        .unwrap_or(0);
    let am = &config::actuators::MODEL;
    let drive = [
        Motion::Straight(Speed::from_mm_s(140)),
        Motion::Straight(Speed::from_mm_s(-125)),
        Motion::Turn(TurnRate::from_mrad_s(2500)),
        Motion::Turn(TurnRate::from_mrad_s(-2600)),
    ]
    .iter()
    .map(|&m| {
        count(|| {
            black_box(am.drive(black_box(m)));
        })
    })
    .max()
    .unwrap_or(0);
    let fwd = [(108u8, 60u8), (64, 105), (105, 113), (65, 50)]
        .iter()
        .map(|&(l, r)| {
            count(|| {
                black_box(am.motion_from_commands(black_box(ServoCmd::from_int(l)), black_box(ServoCmd::from_int(r))));
            })
        })
        .max()
        .unwrap_or(0);
    let mdeg = count(|| {
        black_box(black_box(Angle(0x9abc_def0)).to_signed_millidegrees());
    });
    let parse_fwd = count(|| {
        black_box(parse(black_box(b"fwd 0.13 2.5")).is_ok());
    });
    let parse_servo = count(|| {
        black_box(parse(black_box(b"servo 107 61.5 0.8")).is_ok());
    });
    [
        ("protocol: parse `fwd 0.13 2.5`", parse_fwd),
        ("protocol: parse `servo 107 61.5 0.8`", parse_servo),
        ("compass heading from raw counts (ASA, iron, atan2, declination)", compass),
        ("lidar reading to distance (front)", lidar),
        ("sin_cos", sincos),
        ("atan2", at2),
        ("actuator inverse: motion to servo commands (drive)", drive),
        ("actuator forward: servo commands to motion", fwd),
        ("Angle to signed millidegrees (telemetry)", mdeg),
    ]
}

/// Runs the benchmarks, prints the tables, and checks the bars; returns
/// (passed, failed) bars.
pub fn run() -> (u32, u32) {
    let rows = step_rows();
    println!();
    println!("## State update, one step (instructions, worst of {} headings, dt = 10 ms)", HEADINGS.len());
    println!();
    println!(
        "| motion | fixed point (paperbot::model::advance) | Rust f32 (libm, soft-float) | C float (gcc -O2, libgcc) | C / fixed | fixed, heading just set from outside |"
    );
    println!("| --- | ---: | ---: | ---: | ---: | ---: |");
    for r in &rows {
        println!(
            "| {} | {} | {} | {} | {:.1}x | {} |",
            r.name,
            r.fixed,
            r.rust_f32,
            r.c_float,
            r.c_float as f32 / r.fixed.max(1) as f32,
            r.cold
        );
    }
    let others = core_benches();
    println!();
    println!("## Other core paths (instructions, worst of the inputs tried)");
    println!();
    println!("| path | instructions |");
    println!("| --- | ---: |");
    for (name, n) in &others {
        println!("| {} | {} |", name, n);
    }
    println!();
    for r in &rows {
        println!("BENCH step_{}_fixed {}", r.name, r.fixed);
        println!("BENCH step_{}_rust_f32 {}", r.name, r.rust_f32);
        println!("BENCH step_{}_c_float {}", r.name, r.c_float);
        println!("BENCH step_{}_fixed_cold_cache {}", r.name, r.cold);
    }
    for (name, n) in &others {
        println!("BENCH {} {}", name, n);
    }

    let (mut pass, mut fail) = (0, 0);
    let mut bar = |name: core::fmt::Arguments, ok: bool| {
        if ok {
            pass += 1;
            println!("test bar::{} ... ok", name);
        } else {
            fail += 1;
            println!("test bar::{} ... FAILED", name);
        }
    };
    for r in &rows {
        bar(format_args!("step_{}: {} <= {} instructions", r.name, r.fixed, STEP_MAX), r.fixed <= STEP_MAX);
        // Stop in C is a bare switch (a handful of instructions): the ratio
        // bar is for the motions that compute something.
        if r.name != "Stop" {
            bar(
                format_args!("step_{}: C float {} >= {} x fixed {}", r.name, r.c_float, STEP_VS_C, r.fixed),
                r.c_float >= STEP_VS_C * r.fixed,
            );
        }
    }
    (pass, fail)
}
