//! The state update in Rust `f32` (soft-float on the lx106, sin/cos from the
//! pure-Rust `libm`): a line-by-line port of `csrc/step_c.c`, for the
//! benchmark only. Same equations as `paperbot::model::step` (report 3.1):
//! straight `x += v t cos th, y += v t sin th`; turn `th' = th + w t,
//! x' = x - D (cos th - cos th'), y' = y - D (sin th - sin th')` (the
//! core's rigid-body sign of the y term; the report prints `+`).
//! Units: mm, rad, mm/s, rad/s, s. Like the C version th is not wrapped.

/// Same layout as the C `struct pose_f`.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C)]
pub struct PoseF {
    pub x: f32,
    pub y: f32,
    pub th: f32,
}

/// Motion kinds, numbered as in `csrc/step_c.c`.
pub const STOP: i32 = 0;
pub const STRAIGHT: i32 = 1;
pub const TURN: i32 = 2;

#[inline(never)]
pub fn step(p: &mut PoseF, kind: i32, rate: f32, dt: f32, d: f32) {
    match kind {
        STRAIGHT => {
            let (s, c) = (libm::sinf(p.th), libm::cosf(p.th));
            let dist = rate * dt;
            p.x += dist * c;
            p.y += dist * s;
        }
        TURN => {
            let th1 = p.th + rate * dt;
            let (s0, c0) = (libm::sinf(p.th), libm::cosf(p.th));
            let (s1, c1) = (libm::sinf(th1), libm::cosf(th1));
            p.x -= d * (c0 - c1);
            p.y -= d * (s0 - s1);
            p.th = th1;
        }
        _ => {}
    }
}

extern "C" {
    /// `csrc/step_c.c`: the same step in C float (gcc -O2, GCC libgcc soft-float).
    fn c_step(p: *mut PoseF, kind: i32, rate: f32, dt: f32, d: f32);
}

pub fn c_step_safe(p: &mut PoseF, kind: i32, rate: f32, dt: f32, d: f32) {
    // SAFETY: `p` is a valid, exclusive pointer to a repr(C) pose_f.
    unsafe { c_step(p, kind, rate, dt, d) }
}
