//! On-target tests and instruction-count benchmarks of the paperbot core on
//! the ESP8266's Xtensa lx106, under
//! `qemu-system-xtensa -M sim -cpu lx106 -semihosting` (see run.sh).
//!
//! Output: one line per test (`test group::name ... ok|FAILED`), the
//! benchmark tables, one line per bar, then `N passed, N failed`. The exit
//! status is the number of failures (0 = all passed).
#![no_std]
#![no_main]

mod bench;
mod bench_locate;
mod bench_refine;
mod bench_loop;
mod bench_trig;
mod float;
#[rustfmt::skip]
mod host_bits;
mod rt;
mod scripts;
mod suite;
#[rustfmt::skip]
mod vectors;

#[no_mangle]
pub extern "C" fn rust_main() -> i32 {
    println!("paperbot-lx106: the paperbot core on the lx106 ISA (qemu-system-xtensa -M sim -cpu lx106)");
    let (p1, f1) = suite::run();
    let (p2, f2) = bench::run();
    let (p3, f3) = bench_loop::run();
    bench_trig::run();
    bench_locate::run();
    bench_refine::run();
    let (p2, f2) = (p2 + p3, f2 + f3);
    #[cfg(feature = "demo-fail")]
    let (p2, f2) = {
        println!("test demo::deliberate_failure ... FAILED: demo-fail feature");
        (p2, f2 + 1)
    };
    println!("{} passed, {} failed", p1 + p2, f1 + f2);
    (f1 + f2) as i32
}
