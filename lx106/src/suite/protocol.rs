//! `paperbot::control::protocol`: the command grammar's examples (module
//! docs) parse to the documented canonical form, the canonical form parses
//! back to the same command, and bad lines are refused.

use super::{Mismatches, Test, TestResult};
use crate::println;
use core::hint::black_box;
use heapless::String;
use paperbot::control::protocol::{format_command, parse, MAX_LINE};

pub const TESTS: &[Test] = &[("documented_examples", documented_examples), ("refused_lines", refused_lines)];

/// (line, canonical form)
const OK: [(&[u8], &str); 11] = [
    (b"fwd 0.13 2.5", "fwd 0.130 2.500"),
    (b"BACK .1", "back 0.100"),
    (b"ccw 2.5 1s", "ccw 2.500 1.000"),
    (b"servo 107 61.5 0.8", "servo 107.00 61.50 0.800"),
    (b"trim r -1.25", "trim right -1.25"),
    (b"pose 100 -50 90", "pose 100 -50 90.000"),
    (b"cal", "cal 1000"),
    (b"rate 20", "rate 20"),
    (b"  stop \r\n", "stop"),
    (b"fwd\t0.1300", "fwd 0.130"),
    (b"cw 6", "cw 6.000"),
];

const BAD: [&[u8]; 9] =
    [b"fwd 0.5", b"fwd", b"fwd 0.1305", b"fwd 0.1 2 3", b"jump", b"", b"fwd -0.1", b"servo 181 90", b"fwd 0.1\x01"];

fn documented_examples() -> TestResult {
    let mut m = Mismatches::new();
    for (line, canonical) in OK {
        match parse(black_box(line)) {
            Ok(cmd) => {
                let mut s: String<128> = String::new();
                if format_command(&cmd, &mut s).is_err() || s.as_str() != canonical {
                    m.fail(format_args!(
                        "{:?}: canonical {:?}, want {:?}",
                        core::str::from_utf8(line),
                        s.as_str(),
                        canonical
                    ));
                }
                if parse(s.as_bytes()) != Ok(cmd) {
                    m.fail(format_args!("{:?} does not parse back to {:?}", s.as_str(), cmd));
                }
            }
            Err(e) => m.fail(format_args!("{:?} refused: {:?}", core::str::from_utf8(line), e)),
        }
    }
    println!("      {} lines", OK.len());
    m.result("a documented command line is not understood as documented")
}

fn refused_lines() -> TestResult {
    let mut m = Mismatches::new();
    let long = [b'a'; MAX_LINE + 1];
    for line in BAD.iter().copied().chain([&long[..]]) {
        if let Ok(cmd) = parse(black_box(line)) {
            m.fail(format_args!("{:?} accepted as {:?}", core::str::from_utf8(line), cmd));
        }
    }
    m.result("a bad line was accepted")
}
