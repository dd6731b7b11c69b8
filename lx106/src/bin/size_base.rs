//! Baseline for the size probe: the same minimal runtime, no core code.
#![no_std]
#![no_main]

#[no_mangle]
pub extern "C" fn rust_main() -> i32 {
    0
}

include!("../probe_rt.rs");
