// Minimal runtime for the size probes (no formatting): included by
// src/bin/size_probe.rs and src/bin/size_base.rs.

extern "C" {
    fn sim_exit(code: i32) -> !;
}

#[panic_handler]
fn panic(_: &core::panic::PanicInfo) -> ! {
    // SAFETY: semihosting exit, never returns.
    unsafe { sim_exit(101) }
}

#[no_mangle]
pub extern "C" fn rust_exception(_vector: u32, _cause: u32, _epc1: u32, _excvaddr: u32) -> ! {
    // SAFETY: semihosting exit, never returns.
    unsafe { sim_exit(102) }
}
