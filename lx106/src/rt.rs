//! Glue to the bare-metal runtime in `asm/start.S`: semihosting output and
//! exit, the ICOUNT instruction counter, and the panic/exception handlers.
//! Shared by both binaries (`#[path]`-included by `src/bin/size_probe.rs`).

use core::fmt::Write;

extern "C" {
    fn sim_write(fd: i32, buf: *const u8, len: usize) -> i32;
    pub fn sim_exit(code: i32) -> !;
    fn icount_start();
    fn icount_read() -> u32;
    fn icount_stop();
    /// Executes exactly `2 n + 2` instructions (a check of the counter).
    pub fn icount_calib_loop(n: u32);
}

/// Semihosting stdout.
pub struct Out;

impl Write for Out {
    fn write_str(&mut self, s: &str) -> core::fmt::Result {
        // SAFETY: sim_write reads `len` bytes from `buf`, which is a valid &str.
        unsafe { sim_write(1, s.as_ptr(), s.len()) };
        Ok(())
    }
}

#[macro_export]
macro_rules! println {
    () => {{ let _ = core::fmt::Write::write_str(&mut $crate::rt::Out, "\n"); }};
    ($($t:tt)*) => {{
        let _ = core::fmt::Write::write_fmt(&mut $crate::rt::Out, format_args!($($t)*));
        let _ = core::fmt::Write::write_str(&mut $crate::rt::Out, "\n");
    }};
}

/// Instructions executed between `icount_start()` and `icount_read()`,
/// including the fixed bracket cost (subtract [`overhead`]).
#[inline(never)]
pub fn measure<F: FnOnce()>(f: F) -> u32 {
    // SAFETY: plain special-register accesses (asm/start.S).
    unsafe { icount_start() };
    f();
    let n = unsafe { icount_read() };
    unsafe { icount_stop() };
    n
}

/// The bracket cost of [`measure`] (an empty closure).
pub fn overhead() -> u32 {
    measure(|| {})
}

/// Instructions executed by `f`, bracket cost removed.
pub fn count<F: FnOnce()>(f: F) -> u32 {
    measure(f).saturating_sub(overhead())
}

#[panic_handler]
fn panic(info: &core::panic::PanicInfo) -> ! {
    crate::println!("PANIC: {}", info);
    // SAFETY: semihosting exit, never returns.
    unsafe { sim_exit(101) }
}

/// Called from the exception vectors in start.S.
#[no_mangle]
pub extern "C" fn rust_exception(vector: u32, cause: u32, epc1: u32, excvaddr: u32) -> ! {
    crate::println!("EXCEPTION vector={} EXCCAUSE={} EPC1={:#010x} EXCVADDR={:#010x}", vector, cause, epc1, excvaddr);
    // SAFETY: semihosting exit, never returns.
    unsafe { sim_exit(102) }
}
