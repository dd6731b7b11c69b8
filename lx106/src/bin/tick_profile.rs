//! One control tick of the bar (turning in place at (380, 250) mm, 10 deg,
//! fresh readings from both lidars and the compass, one accepted
//! correction, no telemetry row), for run.sh step 7: QEMU traces every
//! executed instruction between `icount_start` and `icount_read` and
//! `tools/profile.py` attributes them to functions. Not part of the suite.
#![no_std]
#![no_main]

#[path = "../bench_loop.rs"]
#[allow(dead_code)]
mod bench_loop;
#[path = "../rt.rs"]
#[allow(dead_code)]
mod rt;
#[path = "../scripts.rs"]
#[allow(dead_code)]
mod scripts;

use core::hint::black_box;

#[no_mangle]
pub extern "C" fn rust_main() -> i32 {
    let (mut c, now) = bench_loop::worst_tick_setup(bench_loop::pose(&(380, 250, 10)), false);
    let mut sink = scripts::NullSink;
    let n = rt::measure(|| black_box(&mut c).tick(black_box(now), &mut sink));
    println!("tick: {} instructions (incl. the measuring bracket)", n);
    0
}
