//! The settings in flash on the emulated board (part of `--self-test`):
//! the firmware's `save` through the ROM's flash routines with the cache
//! off, kept in the flash file; a power-cycle (a new run on the same file)
//! that restores it; a power cut between the erase and the write, and one
//! mid-write, that keep the older record; a damaged record that gives the
//! config and says so; and the servo pulses, period and width, while the
//! flash is erased and written (the loop paused, the cache off). Then the
//! on-board log: kept in its slot when a mission ends, and sent by `dump`
//! after a power-cycle.
//!
//! Every run works on its own copy of the flash file (`flash-*.bin` in the
//! work folder), the firmware image plus what the runs before it wrote.

use std::path::{Path, PathBuf};

use super::qemu::Board;
use super::selftest::{boot, check_pulses, Expect, Report, Run};

const MS: u64 = 1_000_000;
/// The settings sectors (src/config/settings.rs: 0x3F9000, 0x3FA000).
const SECTOR_A: usize = 0x3F_9000;
/// The log's first slot (src/config/settings.rs: 0x3F3000, three sectors).
const LOG_SLOT_A: u32 = 0x3F_3000;
const LOG_SLOT_BYTES: u32 = 0x3000;
/// The trims the test saves, as `settings` prints them.
const SAVED: &str = "# trims (flash): left 1.50 right 0.00";

fn copy(from: &Path, to: &Path) -> Result<(), String> {
    std::fs::copy(from, to).map(|_| ()).map_err(|e| format!("{}: {e}", to.display()))
}

/// The line of `uart` that starts with `prefix`.
fn line<'a>(uart: &'a str, prefix: &str) -> Option<&'a str> {
    uart.lines().map(|l| l.trim_end_matches('\r')).find(|l| l.starts_with(prefix))
}

fn shown(l: Option<&str>) -> String {
    l.map_or("missing".to_string(), |l| format!("'{l}'"))
}

/// The erase and program commands of the run outside `[from, from + len)`.
fn written_outside(run: &Run, from: u32, len: u32) -> Vec<&String> {
    run.events
        .others
        .iter()
        .filter(|(_, e)| e.starts_with("flash-erase") || e.starts_with("flash-program"))
        .map(|(_, e)| e)
        .filter(|e| {
            let addr = e.split(' ').nth(1).and_then(|a| u32::from_str_radix(a.trim_start_matches("0x"), 16).ok());
            !addr.is_some_and(|a| (from..from + len).contains(&a))
        })
        .collect()
}

/// When the run logged `event` (its first word) first and last, ns.
fn span(run: &Run, event: &str) -> Option<(u64, u64)> {
    let times: Vec<u64> =
        run.events.others.iter().filter(|(_, e)| e.split(' ').next() == Some(event)).map(|&(ns, _)| ns).collect();
    Some((*times.first()?, *times.last()?))
}

pub(super) fn run(r: &mut Report, board: &Board, work: &Path, image: &Path, e: &Expect) -> Result<(), String> {
    let path = |name: &str| -> PathBuf { work.join(format!("flash-{name}.bin")) };

    // 1. trim, save: the record written, the pause reported, pulses kept
    let saved = path("saved");
    copy(image, &saved)?;
    let run = boot(board, work, "flash-save", &saved, &["trim left 1.5", "save"], 2.0, &e.banner, "")?;
    let uart = &run.output.uart;
    let blank = line(uart, "# settings: config (none in flash)");
    r.check("flash: blank sectors boot on the config", blank.is_some(), shown(blank));
    let answer = line(uart, "# saved: record 1 at 0x3f9000, paused ");
    let erase = span(&run, "flash-erase");
    let program = span(&run, "flash-program");
    r.check(
        "flash: save erases the sector and writes the record through the ROM",
        answer.is_some() && erase.is_some() && program.is_some(),
        format!("{}; {} erase, {} program commands", shown(answer), erase.map_or(0, |_| 1), {
            run.events.others.iter().filter(|(_, e)| e.starts_with("flash-program")).count()
        }),
    );
    let outside = written_outside(&run, SECTOR_A as u32, 0x2000);
    r.check(
        "flash: every erase and program inside the two settings sectors",
        outside.is_empty(),
        if outside.is_empty() { "0x3f9000..0x3fb000".to_string() } else { format!("outside: {outside:?}") },
    );
    let no_fetch = !run.events.others.iter().any(|(_, e)| e.starts_with("flash-cache-off"));
    r.check("flash: nothing fetched from flash with the cache off", no_fetch, "no flash-cache-off event");
    if let (Some((from, _)), Some((_, to))) = (erase, program) {
        // the erase keeps the chip busy 45 ms: two servo frames at least;
        // the wheels at their neutral, the left one trimmed by 1.5 steps
        let neutral = [e.width_us(91.5), e.width_us(90.0)];
        check_pulses(
            r,
            &run,
            "flash: servo pulses while the flash is erased and written",
            from,
            to + 20 * MS,
            neutral,
            e,
        );
    }

    // 2. power-cycle: a new run on the same flash file
    let cycled = path("cycled");
    copy(&saved, &cycled)?;
    let run = boot(board, work, "flash-cycle", &cycled, &["settings"], 1.0, &e.banner, "")?;
    let uart = &run.output.uart;
    let restored = line(uart, "# settings from flash, record 1: ");
    let trims = line(uart, "# trims (");
    r.check(
        "flash: after a power-cycle the saved settings are back",
        restored.is_some() && trims == Some(SAVED),
        format!("{}, {}", shown(restored), shown(trims)),
    );

    // 3. power cuts during a second save: after the erase, and mid-write
    for (name, ops, what) in [("cut-erase", 1, "between the erase and the write"), ("cut-write", 5, "mid-write")] {
        let cut = path(name);
        copy(&saved, &cut)?;
        let options = format!("flash-power-ops={ops}");
        let run =
            boot(board, work, &format!("flash-{name}"), &cut, &["trim left 3", "save"], 2.0, &e.banner, &options)?;
        let stopped = run.events.others.iter().any(|(_, e)| e == "stopped: power cut");
        let after = boot(board, work, &format!("flash-{name}-boot"), &cut, &["settings"], 1.0, &e.banner, "")?;
        let uart = &after.output.uart;
        let restored = line(uart, "# settings from flash, record 1: ");
        let trims = line(uart, "# trims (");
        let ignored = line(uart, "# settings at 0x3fa000 ignored: ");
        r.check(
            &format!("flash: a power cut {what} keeps the older record"),
            stopped && restored.is_some() && trims == Some(SAVED),
            format!(
                "power cut {}; then {}, {}{}",
                if stopped { "happened" } else { "never came" },
                shown(restored),
                shown(trims),
                ignored.map_or(String::new(), |l| format!(", '{l}'"))
            ),
        );
    }

    // 4. a damaged record: the config, with the reason
    let damaged = path("damaged");
    let mut bytes = std::fs::read(&saved).map_err(|e| format!("{}: {e}", saved.display()))?;
    match bytes.get_mut(SECTOR_A + 20) {
        Some(b) => *b ^= 0x10,
        None => return Err(format!("{}: no record at {SECTOR_A:#x}", saved.display())),
    }
    std::fs::write(&damaged, bytes).map_err(|e| format!("{}: {e}", damaged.display()))?;
    let run = boot(board, work, "flash-damaged", &damaged, &["settings"], 1.0, &e.banner, "")?;
    let uart = &run.output.uart;
    let ignored = line(uart, "# settings at 0x3f9000 ignored: CRC mismatch");
    let config = line(uart, "# settings: config (none in flash)");
    let trims = line(uart, "# trims (");
    r.check(
        "flash: a damaged record is ignored, the config used",
        ignored.is_some() && config.is_some() && trims == Some("# trims (config): left 0.00 right 0.00"),
        format!("{}, {}, {}", shown(ignored), shown(config), shown(trims)),
    );
    Ok(())
}

/// A mission's log kept in flash at its end, then sent by `dump` after a
/// power-cycle: a full log (100 Hz for 2.5 s: the ring's 198 rows, 52
/// dropped), so the pause reported is the longest a keep takes.
pub(super) fn kept_log(r: &mut Report, board: &Board, work: &Path, image: &Path, e: &Expect) -> Result<(), String> {
    let flash = work.join("flash-log.bin");
    copy(image, &flash)?;
    let mission = ["mission add wait 2.5", "log 100", "mission start"];
    let run = boot(board, work, "flash-log", &flash, &mission, 14.0, &e.banner, "")?;
    let uart = &run.output.uart;
    let kept = line(uart, "# kept the log in flash: ");
    let rows: Option<usize> =
        kept.and_then(|l| l.trim_start_matches("# kept the log in flash: ").split(' ').next()?.parse().ok());
    let outside = written_outside(&run, LOG_SLOT_A, LOG_SLOT_BYTES);
    r.check(
        "flash: a mission's end keeps its log in the log's slot",
        kept.is_some_and(|l| l.contains(" rows, log 1 at 0x3f3000, paused ")) && rows.is_some() && outside.is_empty(),
        format!(
            "{}{}",
            shown(kept),
            if outside.is_empty() { String::new() } else { format!("; outside: {outside:?}") }
        ),
    );
    let run = boot(board, work, "flash-log-dump", &flash, &["dump"], 3.5, &e.banner, "")?;
    let uart = &run.output.uart;
    let summary = line(uart, "# log ");
    // the rows between the summary and its end (telemetry runs before)
    let dumped = uart.lines().map(|l| l.trim_end_matches('\r')).skip_while(|l| !l.starts_with("# log ")).skip(1);
    let sent = dumped.take_while(|l| *l != "# log end").filter(|l| l.starts_with(|c: char| c.is_ascii_digit())).count();
    // 2.5 s at 100 Hz: about 250 rows pushed, the newest 198 kept
    let dropped = |l: &str| -> Option<u32> {
        let rest = l.strip_prefix(&format!("# log {} rows at 100 Hz, ", rows?))?;
        rest.strip_suffix(" dropped (oldest first), kept in flash, log 1")?.parse().ok()
    };
    r.check(
        "flash: after a power-cycle dump sends the kept log",
        summary.and_then(dropped).is_some_and(|d| (45..=55).contains(&d))
            && Some(sent) == rows
            && line(uart, "# log end").is_some(),
        format!("{}, {sent} rows", shown(summary)),
    );
    Ok(())
}
