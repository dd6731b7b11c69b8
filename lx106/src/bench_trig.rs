//! Evidence for issue 2's choice of sin/cos ("from a well-kept crate
//! (cordic, fixed) or a small table with interpolation, whichever is more
//! accurate per instruction"): `paperbot::math::sin_cos` (binary angle in,
//! Q2.30 out: a 256-entry table, second-order correction) against
//! `cordic::sin_cos` 0.1.5 on `fixed` numbers, on the lx106.
//!
//! `cordic::sin_cos` accepts any `fixed` signed type whose PI fits:
//! `FixedI32<U0..=U29>` (and I8/I16/I64 alike); it takes radians. Compared:
//! `I3F29` (the most precise i32 it accepts, 29 CORDIC rounds) and `I16F16`
//! (16 rounds). Error: worst `|sin - sin_f64|`, `|cos - cos_f64|` over
//! [`N`] angles round the circle plus random ones, each against f64
//! `libm::sin`/`cos` of the exact input the function was given (so the
//! radian inputs' own quantisation, 2^-29 or 2^-16 rad, is not counted
//! against CORDIC; a binary angle needs a multiply to become radians, not
//! counted in its instructions either). Instructions: worst of 8 angles, as
//! called.

use crate::println;
use crate::rt::count;
use crate::scripts::Rng;
use core::f64::consts::TAU;
use core::hint::black_box;
use fixed::types::{I16F16, I3F29};
use paperbot::math::{sin_cos, Angle};

/// Angles evenly spread round the circle for the error sweep (plus as many random).
pub const N: u32 = 2048;

pub struct TrigRow {
    pub name: &'static str,
    pub instructions: u32,
    /// Worst absolute error of sin or cos.
    pub worst: f64,
    /// Resolution of the output format.
    pub lsb: f64,
}

fn angles() -> impl Iterator<Item = u32> {
    let mut rng = Rng(0x51_c0_5e);
    (0..N).map(|k| k.wrapping_mul(u32::MAX / N + 1).wrapping_add(12_345)).chain((0..N).map(move |_| rng.next()))
}

/// The binary angle as radians in [-pi, pi).
fn radians(a: u32) -> f64 {
    f64::from(a as i32) * (TAU / 4_294_967_296.0)
}

fn err(got_s: f64, got_c: f64, x: f64) -> f64 {
    let (s, c) = (libm::sin(x), libm::cos(x));
    libm::fabs(got_s - s).max(libm::fabs(got_c - c))
}

const COUNT_AT: [u32; 8] = [0, 0x1234_5678, 0x4000_0000, 0x6000_0001, 0x9abc_def0, 0xc000_0000, 0xe000_0000, u32::MAX];

/// `paperbot::math::sin_cos`'s instructions, worst of [`COUNT_AT`] (also the
/// `sin_cos` row of `bench::run`'s other core paths).
pub fn sin_cos_instructions() -> u32 {
    COUNT_AT
        .iter()
        .map(|&a| {
            count(|| {
                black_box(sin_cos(black_box(Angle(a))));
            })
        })
        .max()
        .unwrap_or(0)
}

#[inline(never)]
fn table() -> (u32, f64) {
    // paperbot: binary angle in, Q2.30 out
    let n = sin_cos_instructions();
    let e = angles()
        .map(|a| {
            let (s, c) = sin_cos(Angle(a));
            let q = 1.0 / 1_073_741_824.0;
            err(f64::from(s) * q, f64::from(c) * q, f64::from(a) * (TAU / 4_294_967_296.0))
        })
        .fold(0.0, f64::max);
    (n, e)
}

/// `cordic::sin_cos` on `T`: (worst instructions, worst error).
#[inline(never)]
fn cordic_on<T: cordic::CordicNumber + fixed::traits::Fixed>() -> (u32, f64) {
    let n = COUNT_AT
        .iter()
        .map(|&a| {
            let x = T::from_num(radians(a));
            count(|| {
                black_box(cordic::sin_cos(black_box(x)));
            })
        })
        .max()
        .unwrap_or(0);
    let e = angles()
        .map(|a| {
            let x = T::from_num(radians(a));
            let (s, c) = cordic::sin_cos(x);
            err(s.to_num::<f64>(), c.to_num::<f64>(), x.to_num::<f64>())
        })
        .fold(0.0, f64::max);
    (n, e)
}

pub fn rows() -> [TrigRow; 3] {
    let (table_n, table_e) = table();
    let (c29_n, c29_e) = cordic_on::<I3F29>();
    let (c16_n, c16_e) = cordic_on::<I16F16>();
    [
        TrigRow {
            name: "paperbot::math::sin_cos (table + 2nd order, Angle -> Q2.30)",
            instructions: table_n,
            worst: table_e,
            lsb: 1.0 / 1_073_741_824.0,
        },
        TrigRow {
            name: "cordic::sin_cos::<I3F29> (29 rounds)",
            instructions: c29_n,
            worst: c29_e,
            lsb: 1.0 / 536_870_912.0,
        },
        TrigRow {
            name: "cordic::sin_cos::<I16F16> (16 rounds)",
            instructions: c16_n,
            worst: c16_e,
            lsb: 1.0 / 65_536.0,
        },
    ]
}

/// Prints the table; returns the rows for the bars.
pub fn run() -> [TrigRow; 3] {
    let rows = rows();
    println!();
    println!(
        "## sin/cos: table vs CORDIC (instructions worst of {} angles; error vs f64 over {} angles)",
        COUNT_AT.len(),
        2 * N
    );
    println!();
    println!(
        "| implementation | instructions per call | worst abs error | in output LSB | correct bits (-log2 error) |"
    );
    println!("| --- | ---: | ---: | ---: | ---: |");
    for r in &rows {
        println!(
            "| {} | {} | {:.2e} | {:.1} | {:.1} |",
            r.name,
            r.instructions,
            // f32 for printing: formatting an f64 trips the LLVM Xtensa
            // register-scavenger crash (see Cargo.toml)
            r.worst as f32,
            (r.worst / r.lsb) as f32,
            -libm::log2f(r.worst.max(1e-30) as f32)
        );
    }
    for (tag, r) in ["table", "cordic_i3f29", "cordic_i16f16"].iter().zip(&rows) {
        println!("BENCH sincos_{}_instructions {}", tag, r.instructions);
        println!("BENCH sincos_{}_worst_error_e9 {}", tag, libm::round(r.worst * 1e9) as u64);
    }
    rows
}
