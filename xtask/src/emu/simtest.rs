//! `cargo fw-emu --sim-test`: the unchanged image driving the simulated
//! robot through the emulated board's pins (`sim.rs`). Checks: bring-up
//! finds both lidars at their new addresses and the compass; the image
//! localizes at power-up (within 30 mm and 5 degrees of the truth) before
//! the built-in 20 s drive, which ends with the estimate within 10 mm of
//! the truth; a command interrupts the localization; the deadman stops the
//! wheels; the loop runs at its configured rate; and after each
//! wire fault (a chip that NACKs, SDA held low, a lidar that never gets
//! ready) the image recovers: the fault is counted and the sensor reads
//! again; and the stack's low-water mark stays within the static bound of
//! `cargo fw-image`'s stack check. Prints `N passed, N failed`; fails when
//! any check does.

use std::path::Path;

use super::events::{summarize, Events};
use super::qemu::Board;
use super::selftest::{config_source, Expect, Report};
use super::sim::{self, SimOptions, SimRun};
use crate::stack;

const MS: u64 = 1_000_000;
/// The bar of the scripted drive: estimate error at the end, mm.
const DRIVE_ERROR_MM: f64 = 10.0;
/// The bars of the power-up localization (issue 23): position mm, heading
/// degrees.
const LOCATE_ERROR_MM: f64 = 30.0;
const LOCATE_ERROR_DEG: f64 = 5.0;
/// Servo pins, left then right (config::pins).
const SERVO_PINS: [u8; 2] = [5, 4];
/// Telemetry columns (control::protocol::telemetry::HEADER).
const FRONT_RAW: usize = 9;
const RIGHT_RAW: usize = 11;
const COMPASS: usize = 19;
const F_BUS: usize = 20;
const F_TIMEOUT: usize = 21;
const F_MISSING: usize = 22;
const F_OVERRUNS: usize = 25;

/// A telemetry row of UART0 output, split into fields: a time first and at
/// least the columns read here (the firmware's header names them; columns
/// it appends later do not matter here, as xtask cannot link its parser).
fn row(line: &str) -> Option<Vec<&str>> {
    Some(line.trim_end().split(',').collect::<Vec<_>>()).filter(|f| f.len() > F_OVERRUNS && f[0].parse::<u32>().is_ok())
}

/// Telemetry rows of a run's UART0 output.
fn rows(uart: &str) -> Vec<Vec<&str>> {
    uart.lines().filter_map(row).collect()
}

/// The overrun counter a second before the first `# located` line (the
/// search's slices run in the ticks before it) and in the row after it.
fn overruns_around_fix(uart: &str) -> Option<(u64, u64)> {
    let mut lines = uart.lines();
    let before: Vec<Vec<&str>> = lines.by_ref().take_while(|l| !l.starts_with("# located")).filter_map(row).collect();
    let after = lines.find_map(row)?;
    let earlier = before.iter().rev().find(|r| t_ms(r) + 1000 <= t_ms(&after))?;
    Some((counter(earlier, F_OVERRUNS), counter(&after, F_OVERRUNS)))
}

fn t_ms(row: &[&str]) -> u32 {
    row[0].parse().unwrap_or(0)
}

fn counter(row: &[&str], col: usize) -> u64 {
    row.get(col).and_then(|v| v.parse().ok()).unwrap_or(0)
}

/// Rows of the last `ms` of the run.
fn last<'a>(rows: &'a [Vec<&'a str>], ms: u32) -> &'a [Vec<&'a str>] {
    let end = rows.last().map_or(0, |r| t_ms(r));
    let from = rows.partition_point(|r| t_ms(r) + ms < end);
    &rows[from..]
}

fn reads(rows: &[Vec<&str>], col: usize) -> usize {
    rows.iter().filter(|r| !r[col].is_empty()).count()
}

fn script(work: &Path, name: &str, text: &str) -> Result<std::path::PathBuf, String> {
    let path = work.join(format!("simtest-{name}.script"));
    std::fs::write(&path, text).map_err(|e| format!("{}: {e}", path.display()))?;
    Ok(path)
}

/// The number after `label` in the simulator's summary.
fn summary_number(summary: &str, label: &str) -> Option<f64> {
    let rest = &summary[summary.find(label)? + label.len()..];
    rest.split_whitespace().next()?.trim_end_matches(',').parse().ok()
}

pub fn run(root: &Path, board: &Board, work: &Path, flash: &Path) -> Result<(), String> {
    let e = Expect::load(root)?;
    let mut r = Report::default();
    let go = |name: &str, o: SimOptions| -> Result<SimRun, String> {
        sim::run(root, board, work, flash, &format!("simtest-{name}"), &o, false)
    };

    // bring-up and the built-in 20 s drive
    let drive = go("drive", SimOptions { seconds: 20.0, ..SimOptions::default() })?;
    let config = config_source(root)?;
    let addr = |name: &str| {
        let prefix = format!("pub const {name}: u8 = 0x");
        config.lines().find_map(|l| l.trim().strip_prefix(&prefix)?.strip_suffix(';').map(str::to_lowercase))
    };
    let want = format!(
        "lidar addresses: front 0x{}, right 0x{}",
        addr("FRONT_LIDAR_ADDR").unwrap_or_default(),
        addr("RIGHT_LIDAR_ADDR").unwrap_or_default()
    );
    let up = drive.output.uart.contains("lidars Ok(()) Ok(()), compass Ok(())");
    r.check(
        "bring-up over the wire finds both lidars at their new addresses and the compass",
        up && drive.summary.contains(&want),
        format!("{}; {want}", if up { "all three up" } else { "a sensor down" }),
    );
    // the power-up localization: found before the script's first `goto`
    // (which would interrupt it), near the truth at that time
    let uart = &drive.output.uart;
    let fix = drive.summary.lines().find(|l| l.contains("after bring-up: # located"));
    let fix_mm = fix.and_then(|l| summary_number(l, "fix error")).unwrap_or(f64::INFINITY);
    let fix_deg = fix.and_then(|l| summary_number(l, "heading error")).unwrap_or(f64::INFINITY);
    let before_drive = match (uart.find("# located"), uart.find("# ok goto")) {
        (Some(located), Some(goto)) => located < goto,
        _ => false,
    };
    r.check(
        "the image localizes at power-up, near the truth, before the drive",
        fix.is_some_and(|l| !l.contains("ambiguous"))
            && fix_mm <= LOCATE_ERROR_MM
            && fix_deg.abs() <= LOCATE_ERROR_DEG
            && before_drive
            && !uart.contains("# locate failed"),
        format!(
            "{} (bars {LOCATE_ERROR_MM} mm, {LOCATE_ERROR_DEG} deg){}",
            fix.map_or("no '# located' line", str::trim),
            if before_drive { "" } else { "; not before the first goto" }
        ),
    );
    let overruns = overruns_around_fix(uart);
    r.check(
        "the search's slices keep the loop's rate (no overrun in the second before the fix)",
        overruns.is_some_and(|(a, b)| a == b),
        overruns.map_or("no rows around the fix".into(), |(a, b)| format!("overruns {a} then {b}")),
    );
    let err = summary_number(&drive.summary, "estimate error at the end").unwrap_or(f64::INFINITY);
    r.check(
        "the built-in 20 s drive ends with the estimate near the truth",
        drive.simulator_ok && err <= DRIVE_ERROR_MM,
        format!("{err:.1} mm (bar {DRIVE_ERROR_MM} mm)"),
    );
    let work_ips = drive.cost.work_per_second();
    r.check("the loop's cost is measured", work_ips > 0.0, format!("{:.3} M instructions/s of work", work_ips / 1e6));
    // the stack: the board's low-water mark over bring-up, the power-up
    // localization and the drive, against the static bound of cargo
    // fw-image's stack check (xtask/src/stack.rs), which it must not pass
    let low = Events::parse(&std::fs::read_to_string(&drive.events).map_err(|e| e.to_string())?)?
        .others
        .iter()
        .find_map(|(_, e)| u32::from_str_radix(e.strip_prefix("stack-low 0x")?, 16).ok());
    let bound = stack::worst_case(&root.join("target/image/paperbot.elf"))?;
    let used = low.map(|low| stack::STACK_TOP.saturating_sub(low));
    r.check(
        "the stack stays within the static bound (the board's low-water mark)",
        used.is_some_and(|used| used <= bound),
        match (low, used) {
            (Some(low), Some(used)) => format!(
                "{used} B used, down to {low:#010x}; static bound {bound} B; the ROM's flash parameters end at {:#010x}",
                stack::STACK_FLOOR
            ),
            _ => "no stack-low event".into(),
        },
    );

    // the deadman: an untimed raw command, then silence
    let deadman = go(
        "deadman",
        SimOptions { script: Some(script(work, "deadman", "@0 servo 120 60\n")?), seconds: 1.5, ..Default::default() },
    )?;
    let events = Events::parse(&std::fs::read_to_string(&deadman.events).map_err(|e| e.to_string())?)?;
    let end = events.edges.last().map_or(0, |e| e.ns);
    let neutral = e.width_us(90.0);
    let widths: Vec<Option<f64>> =
        SERVO_PINS.iter().map(|p| summarize(&events.pulses(*p, end.saturating_sub(200 * MS), end)).width_us).collect();
    let stopped = widths.iter().all(|w| w.is_some_and(|w| (w - neutral).abs() <= 5.0));
    let interrupted = deadman.output.uart.contains("# locate failed: interrupted by a command");
    r.check(
        "a command interrupts the power-up localization",
        interrupted,
        format!("'# locate failed: interrupted by a command' {}", if interrupted { "found" } else { "missing" }),
    );
    let said = deadman.output.uart.contains("deadman");
    r.check(
        "the deadman stops the wheels",
        stopped && said,
        format!(
            "widths at the end {widths:?} us (neutral {neutral:.0}); {}",
            if said { "reported" } else { "not reported" }
        ),
    );

    // the loop rate: a row every tick
    let rate = go(
        "rate",
        SimOptions { script: Some(script(work, "rate", "@0 rate 100\n")?), seconds: 2.0, ..Default::default() },
    )?;
    let rows_rate = rows(&rate.output.uart);
    let second = last(&rows_rate, 1000);
    let gaps: Vec<u32> = second.windows(2).map(|w| t_ms(&w[1]) - t_ms(&w[0])).collect();
    let tick_ms = 1000 / 100;
    r.check(
        "the loop runs at its configured rate (100 Hz)",
        second.len() >= 99 && gaps.iter().all(|g| g.abs_diff(tick_ms) <= 1),
        format!("{} rows in the last second, gaps {:?}..{:?} ms", second.len(), gaps.iter().min(), gaps.iter().max()),
    );

    // wire faults, each from 2 s after power-on; 3 s to recover
    let faults: [(&str, &str, usize, &[usize]); 3] = [
        ("nack", "nack:0c@2-2.5", COMPASS, &[F_BUS, F_MISSING, F_TIMEOUT]),
        ("sda-low", "sda-low@2-2.3", FRONT_RAW, &[F_BUS]),
        ("stall", "stall:front@2-3", FRONT_RAW, &[F_TIMEOUT]),
    ];
    for (name, fault, col, counters) in faults {
        let run = go(name, SimOptions { seconds: 6.0, faults: vec![fault.into()], ..Default::default() })?;
        let all = rows(&run.output.uart);
        let end = last(&all, 1000);
        let counted: u64 = all.last().map_or(0, |row| counters.iter().map(|c| counter(row, *c)).sum());
        let back = [FRONT_RAW, RIGHT_RAW, COMPASS].map(|c| reads(end, c));
        r.check(
            &format!("the image recovers from {fault}"),
            counted > 0 && reads(end, col) > 0 && back.iter().all(|n| *n > 0),
            format!("faults counted {counted}; readings in the last second front/right/compass {back:?}"),
        );
    }
    r.finish()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A telemetry row at `t_ms` with `overruns` (the other fields 0).
    fn row_at(t_ms: u32, overruns: u32) -> String {
        let mut fields = vec!["0".to_string(); 26];
        fields[0] = t_ms.to_string();
        fields[F_OVERRUNS] = overruns.to_string();
        fields.join(",")
    }

    /// The columns read here are the ones the firmware's header names there.
    #[test]
    fn the_columns_read_are_where_the_firmware_header_puts_them() {
        let path = crate::image::repo_root().join("src/control/protocol/telemetry.rs");
        let src = std::fs::read_to_string(&path).unwrap();
        let start = src.find("pub const HEADER: &str = \"").unwrap() + 26;
        let header = src[start..].split("\";").next().unwrap().replace("\\\n", "");
        let names: Vec<&str> = header.split(',').collect();
        for (col, name) in [
            (FRONT_RAW, "front_raw_mm"),
            (RIGHT_RAW, "right_raw_mm"),
            (COMPASS, "compass_deg"),
            (F_BUS, "f_bus"),
            (F_TIMEOUT, "f_timeout"),
            (F_MISSING, "f_missing"),
            (F_OVERRUNS, "f_overruns"),
        ] {
            assert_eq!(names[col], name, "{header}");
        }
    }

    #[test]
    fn overruns_are_read_a_second_before_the_fix_and_after_it() {
        let uart = |overrun_at_ms: u32| {
            let mut lines: Vec<String> =
                (0..=20).map(|i| row_at(i * 100, u32::from(i * 100 >= overrun_at_ms))).collect();
            lines.insert(19, "# located 115 223 88.883 sigma 7 7 mm, views 3".into());
            lines.join("\n")
        };
        // the fix follows the row at 1,800 ms; the row after it is at 1,900
        assert_eq!(overruns_around_fix(&uart(100)), Some((1, 1)));
        assert_eq!(overruns_around_fix(&uart(1_500)), Some((0, 1)));
        assert_eq!(overruns_around_fix(&uart(5_000)), Some((0, 0)));
        assert_eq!(overruns_around_fix("0,1,2\n# located 1 2 3"), None);
    }
}
