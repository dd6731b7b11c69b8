//! The on-target test suite: groups of named tests, run in order.
//!
//! Adding a group: write a module with `pub const TESTS: &[Test]` (one
//! function per test) and add one line to [`GROUPS`].

use crate::println;

mod actuator;
mod compass;
mod control;
mod counter;
mod estimator;
mod lidar;
mod math;
pub mod ports;
mod protocol;
mod state;

/// A test fails with a short reason; details are printed before returning.
pub type TestResult = Result<(), &'static str>;
pub type Test = (&'static str, fn() -> TestResult);

/// Every group, in run order: (group name, its tests).
pub const GROUPS: &[(&str, &[Test])] = &[
    ("counter", counter::TESTS),
    ("math", math::TESTS),
    ("actuator", actuator::TESTS),
    ("lidar", lidar::TESTS),
    ("compass", compass::TESTS),
    ("state", state::TESTS),
    ("ports", ports::TESTS),
    ("protocol", protocol::TESTS),
    ("estimator", estimator::TESTS),
    ("control", control::TESTS),
];

pub fn check(cond: bool, msg: &'static str) -> TestResult {
    if cond {
        Ok(())
    } else {
        Err(msg)
    }
}

/// Counts failing cases of a vector table, printing the first few.
pub struct Mismatches {
    pub count: u32,
}

impl Mismatches {
    pub const fn new() -> Self {
        Mismatches { count: 0 }
    }
    /// Records a failing case; prints it if it is among the first five.
    pub fn fail(&mut self, what: core::fmt::Arguments) {
        self.count += 1;
        if self.count <= 5 {
            println!("      mismatch: {}", what);
        }
    }
    pub fn result(&self, msg: &'static str) -> TestResult {
        if self.count > 0 {
            println!("      {} mismatches", self.count);
        }
        check(self.count == 0, msg)
    }
}

/// Runs every group; returns (passed, failed).
pub fn run() -> (u32, u32) {
    let (mut pass, mut fail) = (0, 0);
    for (group, tests) in GROUPS {
        for (name, t) in tests.iter() {
            match t() {
                Ok(()) => {
                    pass += 1;
                    println!("test {}::{} ... ok", group, name);
                }
                Err(m) => {
                    fail += 1;
                    println!("test {}::{} ... FAILED: {}", group, name, m);
                }
            }
        }
    }
    (pass, fail)
}
