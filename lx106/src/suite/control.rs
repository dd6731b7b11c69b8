//! `paperbot::control::Controller::tick` on the lx106 against the core built
//! for the host: the scripted run of `crate::scripts::run_control` (commands
//! of every kind and bad lines, timed commands and the deadman, telemetry at
//! 20 and 50 Hz, fresh and failing sensors, a silent lidar's timeout and
//! re-initialisation, a wrapping microsecond counter, overruns) must leave
//! the host's bits after every tick: pose, covariance, servo commands, mode,
//! fault counters, sensor health and every output byte (`crate::host_bits`).

use super::{check, Mismatches, Test, TestResult};
use crate::host_bits::CONTROL;
use crate::println;
use crate::scripts::{run_control, TickRec, TICKS};

pub const TESTS: &[Test] = &[("scripted_ticks_bit_exact_vs_host", scripted_ticks)];

fn scripted_ticks() -> TestResult {
    check(CONTROL.len() == TICKS as usize, "host_bits.rs has another number of ticks (stale?)")?;
    let mut m = Mismatches::new();
    let mut i = 0usize;
    let mut last = None;
    run_control(
        |got: TickRec| {
            match CONTROL.get(i) {
                Some(w) if *w == got => {}
                Some(w) => m.fail(format_args!("tick {i}: got {:?}, host {:?}", got, w)),
                None => m.fail(format_args!("tick {i}: more ticks than the host ran")),
            }
            last = Some(got);
            i += 1;
        },
        &mut |_| {},
    );
    if let Some(r) = last {
        println!("      {} ticks bit-exact, {} output lines (FNV-1a {:#010x})", i, r.5, r.6);
    }
    m.result("the lx106 control loop differs from the host build")
}
