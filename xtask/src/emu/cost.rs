//! The loop's cost on the emulated board, from the board's PC samples
//! (`profile=`: the PC and a0 every `PROFILE_NS` virtual ns from the loop's
//! start). Each sample stands for `PROFILE_NS / 16` instructions (-icount
//! shift=4: one instruction every 16 ns), and is put in the group of the
//! firmware function that holds its PC (the ELF's symbols): I2C
//! bit-banging, UART0 output, the servo interrupt, the main loop's own
//! polling (idle: the loop spins between ticks, reading its microsecond
//! clock) or, for everything else, the control tick. A sample in a shared
//! helper (compiler_builtins' division, the ROM's routines) goes to the
//! group of its caller, the function a0 returns to (call0 ABI, leaf
//! helpers); a helper called by a helper (u32_div_rem under __udivsi3) is
//! shared out like the directly called helpers' samples: an estimate.
//!
//! The share of the core counts one instruction as one cycle of the 80 MHz
//! lx106 (the bar's convention). Busy-waits (the I2C bit timing, a full
//! UART FIFO) spin for a time, not a count, so on the chip they cost 1.28
//! times the instructions counted here.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::Path;

use object::{Object, ObjectSymbol, SymbolKind};

use super::qemu::PROFILE_NS;

const NS_PER_INSTRUCTION: f64 = 16.0;
const CORE_HZ: f64 = 80e6;
/// The bar: the loop's work at most this share of the core.
const BAR_SHARE: f64 = 0.10;

/// Where the samples fell.
#[derive(Debug, Default)]
pub struct Cost {
    pub seconds: f64,
    pub samples: u64,
    /// Samples per group, in report order.
    pub groups: Vec<(&'static str, u64)>,
    /// Samples in a helper called by a helper (shared out).
    pub nested_helpers: u64,
}

/// The function that holds `addr` ("" for none: the ROM's routines).
fn function_at(functions: &[(u64, u64, String)], addr: u64) -> &str {
    let i = functions.partition_point(|(a, _, _)| *a <= addr);
    i.checked_sub(1)
        .and_then(|i| functions.get(i))
        .filter(|(a, size, _)| addr < a + size)
        .map_or("", |(_, _, name)| name.as_str())
}

/// Shared leaf helpers: counted for their caller.
fn is_helper(name: &str) -> bool {
    name.is_empty() || name.starts_with("compiler_builtins::") || name.starts_with("__") && !name.contains("xtensa")
}

const I2C: &str = "I2C bit-banging";
const TICK: &str = "control tick (drivers, estimator, telemetry text)";
const UART: &str = "UART0 output (blocking on the FIFO)";
const ISR: &str = "servo interrupt";
const IDLE: &str = "main loop polling between ticks (idle)";

fn group(name: &str) -> &'static str {
    if name.starts_with("<paperbot::board::bitbang_i2c::") || name.contains("board::esp8266::I2cGpio") {
        I2C
    } else if name.starts_with("<esp8266_hal::uart::") || name.contains("UartLines") {
        UART
    } else if name.contains("frc1_servo_edge") || name.contains("interrupt") || name.contains("exception") {
        ISR
    } else if name == "firmware::robot::run" || name == "main" || name.contains("MicrosClock") {
        IDLE
    } else {
        TICK
    }
}

/// Reads the samples and sorts them into groups by the ELF's symbols.
pub fn measure(profile: &Path, elf: &Path) -> Result<Cost, String> {
    let text = std::fs::read_to_string(profile).map_err(|e| format!("{}: {e}", profile.display()))?;
    let data = std::fs::read(elf).map_err(|e| format!("{}: {e}", elf.display()))?;
    let file = object::File::parse(&*data).map_err(|e| format!("{}: {e}", elf.display()))?;
    let mut functions: Vec<(u64, u64, String)> = file
        .symbols()
        .filter(|s| s.kind() == SymbolKind::Text && s.size() > 0)
        .filter_map(|s| Some((s.address(), s.size(), format!("{:#}", rustc_demangle::demangle(s.name().ok()?)))))
        .collect();
    functions.sort();
    let mut cost = Cost::default();
    let mut counts: BTreeMap<&'static str, u64> = BTreeMap::new();
    let mut helpers: BTreeMap<&'static str, u64> = BTreeMap::new();
    let mut nested = 0;
    for line in text.lines() {
        if let Some(head) = line.strip_prefix("# samples ") {
            // "# samples N every P ns from A to B ns"
            let w: Vec<&str> = head.split_whitespace().collect();
            let num = |i: usize| w.get(i).and_then(|v| v.parse::<f64>().ok()).unwrap_or(0.0);
            cost.seconds = (num(7) - num(5)) / 1e9;
            continue;
        }
        let w: Vec<&str> = line.split_whitespace().collect();
        let (Some(Ok(pc)), Some(Ok(a0)), Some(Ok(n))) = (
            w.first().map(|v| u64::from_str_radix(v, 16)),
            w.get(1).map(|v| u64::from_str_radix(v, 16)),
            w.get(2).map(|v| v.parse::<u64>()),
        ) else {
            continue;
        };
        let name = function_at(&functions, pc);
        let caller = function_at(&functions, a0);
        cost.samples += n;
        if !is_helper(name) {
            *counts.entry(group(name)).or_default() += n;
        } else if !is_helper(caller) {
            *helpers.entry(group(caller)).or_default() += n;
        } else {
            nested += n;
        }
    }
    let direct: u64 = helpers.values().sum();
    cost.nested_helpers = nested;
    cost.groups = [I2C, TICK, UART, ISR, IDLE]
        .iter()
        .map(|g| {
            let h = helpers.get(g).copied().unwrap_or(0);
            let share = if direct > 0 { (nested as f64 * h as f64 / direct as f64).round() as u64 } else { 0 };
            (*g, counts.get(g).copied().unwrap_or(0) + h + share)
        })
        .collect();
    Ok(cost)
}

impl Cost {
    /// Instructions per second of robot time in `samples`.
    pub fn per_second(&self, samples: u64) -> f64 {
        samples as f64 * (f64::from(PROFILE_NS) / NS_PER_INSTRUCTION) / self.seconds.max(1e-9)
    }

    /// The loop's work (everything but the idle polling), per second.
    pub fn work_per_second(&self) -> f64 {
        self.per_second(self.groups.iter().filter(|(g, _)| *g != IDLE).map(|(_, n)| n).sum())
    }

    pub fn report(&self) -> String {
        let mut s = String::new();
        let _ = writeln!(
            s,
            "loop cost: {} PC samples every {PROFILE_NS} virtual ns over {:.2} s from the loop's start; \
             one instruction = 16 ns of virtual time, counted as one cycle of the 80 MHz core",
            self.samples, self.seconds
        );
        let _ = writeln!(
            s,
            "  ({:.1} % of the samples in a division helper under another helper, shared out as an estimate)",
            self.nested_helpers as f64 * 100.0 / self.samples.max(1) as f64
        );
        for (g, n) in &self.groups {
            let ips = self.per_second(*n);
            let _ = writeln!(
                s,
                "  {g:<52} {:>6.3} M instructions/s  {:>5.2} % of the core",
                ips / 1e6,
                ips / CORE_HZ * 100.0
            );
        }
        let work = self.work_per_second();
        let verdict = if work <= BAR_SHARE * CORE_HZ {
            "within".to_string()
        } else {
            format!("OVER by {:.3} M/s", (work - BAR_SHARE * CORE_HZ) / 1e6)
        };
        let _ = writeln!(
            s,
            "  the loop's work (all but the idle polling)           {:>6.3} M instructions/s  {:>5.2} % of the core \
             ({verdict} the bar: 8 M/s, 10 %)",
            work / 1e6,
            work / CORE_HZ * 100.0
        );
        s
    }
}
