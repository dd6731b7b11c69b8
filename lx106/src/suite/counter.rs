//! The instruction counter itself: repeatable, and one count per instruction.

use super::{check, Test, TestResult};
use crate::println;
use crate::rt::{icount_calib_loop, measure};
use core::hint::black_box;

pub const TESTS: &[Test] = &[("icount_exact_and_repeatable", icount_exact_and_repeatable)];

fn icount_exact_and_repeatable() -> TestResult {
    let (a, b) = (measure(|| {}), measure(|| {}));
    check(a == b, "bracket cost not repeatable")?;
    // SAFETY: asm loop of exactly 2 n + 2 instructions, no memory access.
    let n0 = measure(|| unsafe { icount_calib_loop(black_box(0)) });
    let n1000 = measure(|| unsafe { icount_calib_loop(black_box(1000)) });
    println!(
        "      bracket {} insns; calib loop n=0 -> {}, n=1000 -> {} (diff {}, expect 2000)",
        a,
        n0,
        n1000,
        n1000 - n0
    );
    check(n1000 - n0 == 2000, "ICOUNT does not count one per instruction")
}
