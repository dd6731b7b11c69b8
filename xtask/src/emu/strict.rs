//! The self-test's checks of the board's strictness (issue 28): where the
//! chip is unforgiving, the board must be too. Each check boots an image
//! the chip would refuse or punish (the firmware with one thing broken, or
//! a test image of emu/test/probe.c) and shows that the board does, for
//! the reason the check names; and the firmware, which does each thing
//! right, passes the same hurdle (the rest of the self-test).
//!
//! | strictness | broken image | the board's answer |
//! |---|---|---|
//! | the ROM boots the header's flash mode only if the flash answers it | the firmware with a QIO header | no start, `flash-mode-refused qio` |
//! | the ROM's lines at 74880 baud, the firmware's at 115200 after its PLL write | a probe without the PLL write | its line garbage at 115200, readable at 74880 |
//! | interrupts masked at hand-over | the firmware with its PS/INTENABLE take-over skipped | the firmware's own fault line, no servo pulses |
//! | ... and INTENABLE holding the ROM's bits, UART0's live | the firmware with only its INTENABLE write skipped | it never gets to its banner |
//! | flash unreadable until the cache is on | the firmware entered at xtensa-lx-rt's `Reset` (in flash), not esp8266-hal's `ESP8266Reset` | `flash-cache-off`, the ROM's exception report |
//! | RAM not zero at power-up | a probe that prints a word it never wrote | not zero |
//! | 8/16-bit loads from IRAM or flash | two probes | EXCCAUSE 3 (LoadStoreError) |
//! | GPIO0 low at a reset: UART download mode | a probe that starves the watchdog with GPIO0 low | `download-mode`, no second boot |
//! | ... while the firmware's own reset releases GPIO0 | the firmware made to panic (an illegal instruction in its command handler) with a lidar's XSHUT low | it boots again |

use std::path::{Path, PathBuf};

use object::{Object, ObjectSection, ObjectSymbol};

use super::flash::compose;
use super::qemu::{Board, Session};
use super::selftest::{boot, probe_flash, Expect, Report, Run};
use super::{read, read_events};
use crate::esptool::{boot_image, FlashParams};

/// The board's listener at the ROM's rate: 115200 * 26 / 40 (a 26 MHz
/// crystal where the ROM assumes 40 MHz).
const ROM_BAUD: &str = "uart-baud=74880";
/// The ROM's banner (Espressif's ESP8266 boot messages) for a power-on boot
/// from flash.
const ROM_BANNER: &str = " ets Jan  8 2013,rst cause:1, boot mode:(3,6)";
/// The pin the front lidar's XSHUT shares with the strapping (config::pins).
const GPIO0: u8 = 0;

pub(super) fn run(r: &mut Report, root: &Path, board: &Board, work: &Path, e: &Expect) -> Result<(), String> {
    let elf = root.join("target/image/paperbot.elf");
    let firmware = Firmware { root, board, work, elf: &elf };
    rom_baud(r, &firmware, e)?;
    qio_header(r, &firmware, e)?;
    handover(r, &firmware, e)?;
    intenable_kept(r, &firmware, e)?;
    cache_off(r, &firmware, e)?;
    probes(r, root, board, work)?;
    panic_with_xshut_low(r, &firmware, e)?;
    Ok(())
}

/// The firmware's ELF and what it takes to boot a variant of it.
struct Firmware<'a> {
    root: &'a Path,
    board: &'a Board,
    work: &'a Path,
    elf: &'a Path,
}

impl Firmware<'_> {
    /// The flash file of `elf` (the firmware or a patched copy) made with
    /// esptool's elf2image and `params`, as `cargo fw-image` makes it.
    fn flash(&self, name: &str, elf: &Path, params: &FlashParams) -> Result<PathBuf, String> {
        let prefix = self.work.join(format!("strict-{name}-"));
        let boot = boot_image(self.root, elf, &prefix, params)?;
        let irom = PathBuf::from(format!("{}0x10000.bin", prefix.display()));
        let flash = self.work.join(format!("strict-{name}-flash.bin"));
        let data = compose(&read(&boot)?, &read(&irom)?)?;
        std::fs::write(&flash, data).map_err(|e| format!("{}: {e}", flash.display()))?;
        Ok(flash)
    }

    /// A copy of the firmware's ELF changed by `patch`, as `name`.
    fn patched(&self, name: &str, patch: impl FnOnce(&mut Vec<u8>) -> Result<(), String>) -> Result<PathBuf, String> {
        let mut data = read(self.elf)?;
        patch(&mut data)?;
        let path = self.work.join(format!("strict-{name}.elf"));
        std::fs::write(&path, data).map_err(|e| format!("{}: {e}", path.display()))?;
        Ok(path)
    }

    fn boot(
        &self,
        name: &str,
        flash: &Path,
        input: &[&str],
        seconds: f64,
        e: &Expect,
        options: &str,
    ) -> Result<Run, String> {
        boot(self.board, self.work, &format!("strict-{name}"), flash, input, seconds, &e.banner, options)
    }
}

/// The ELF's symbol whose demangled name `matches`: its address.
fn symbol(elf: &[u8], matches: impl Fn(&str) -> bool) -> Result<u32, String> {
    let file = object::File::parse(elf).map_err(|e| format!("ELF: {e}"))?;
    file.symbols()
        .find(|s| s.name().is_ok_and(|n| matches(&format!("{:#}", rustc_demangle::demangle(n)))))
        .map(|s| s.address() as u32)
        .ok_or_else(|| "symbol not found in the firmware".to_string())
}

/// Overwrites the bytes at `addr` in the ELF's loaded sections.
fn write_at(elf: &mut [u8], addr: u32, bytes: &[u8]) -> Result<(), String> {
    let file = object::File::parse(&*elf).map_err(|e| format!("ELF: {e}"))?;
    let offset = file
        .sections()
        .find_map(|s| {
            let (start, len) = s.file_range()?;
            let at = u64::from(addr).checked_sub(s.address())?;
            (at + bytes.len() as u64 <= len).then_some(start + at)
        })
        .ok_or_else(|| format!("{addr:#010x} is in no section of the ELF"))? as usize;
    elf[offset..offset + bytes.len()].copy_from_slice(bytes);
    Ok(())
}

/// The ELF's code symbols, by address, each taken to run to the next (the
/// assembly's have no size): (address, demangled name).
fn text_symbols(elf: &[u8]) -> Result<Vec<(u64, String)>, String> {
    let file = object::File::parse(elf).map_err(|e| format!("ELF: {e}"))?;
    let mut symbols: Vec<(u64, String)> = file
        .symbols()
        .filter(|s| s.kind() == object::SymbolKind::Text)
        .filter_map(|s| Some((s.address(), format!("{:#}", rustc_demangle::demangle(s.name().ok()?)))))
        .collect();
    symbols.sort();
    Ok(symbols)
}

/// `len` bytes at `addr` in the ELF's loaded sections.
fn elf_bytes(elf: &[u8], addr: u32, len: usize) -> Result<Vec<u8>, String> {
    let file = object::File::parse(elf).map_err(|e| format!("ELF: {e}"))?;
    file.sections()
        .find_map(|s| {
            let at = u64::from(addr).checked_sub(s.address())?;
            let data = s.data().ok()?;
            data.get(at as usize..at as usize + len).map(<[u8]>::to_vec)
        })
        .ok_or_else(|| format!("{addr:#010x} is in no section of the ELF"))
}

/// The ELF32 header's entry point (e_entry, offset 24, little-endian).
fn set_entry(elf: &mut [u8], entry: u32) {
    elf[24..28].copy_from_slice(&entry.to_le_bytes());
}

/// The rest of the line of `uart` from `needle` on (the line may start
/// with the garbage of bytes sent at another baud rate), trimmed.
fn line_from<'a>(uart: &'a str, needle: &str) -> Option<&'a str> {
    let at = uart.find(needle)?;
    Some(uart[at..].lines().next().unwrap_or("").trim())
}

/// Xtensa `ret` (call0 ABI), 3 bytes.
const RET: [u8; 3] = [0x80, 0x00, 0x00];
/// The functions of the level-1 interrupt path (xtensa/asm/xtensa_lx_rt.S,
/// xtensa-lx-rt, esp8266-hal's dispatcher), by part of their names.
const INTERRUPT_PATH: [&str; 5] = ["ExceptionVector", "_exception", "save_context", "restore_context", "interrupt"];
/// Xtensa `wsr.intenable a2`, 3 bytes, and `nop`.
const WSR_INTENABLE_A2: [u8; 3] = [0x20, 0xe4, 0x13];
const NOP: [u8; 3] = [0xf0, 0x20, 0x00];
/// Xtensa `ill`: an illegal instruction (all zeros), 3 bytes.
const ILL: [u8; 3] = [0x00, 0x00, 0x00];

/// The ROM's lines at 74880 baud and the firmware's at 115200: at 74880
/// the ROM's banner is readable and the firmware's is not.
fn rom_baud(r: &mut Report, fw: &Firmware, e: &Expect) -> Result<(), String> {
    let flash = fw.flash("rom-baud", fw.elf, &FlashParams::default())?;
    let run = fw.boot("rom-baud", &flash, &[], 0.5, e, ROM_BAUD)?;
    let uart = &run.output.uart;
    let rom = uart.contains(ROM_BANNER) && uart.contains("csum 0x");
    let banner = uart.contains(&e.banner);
    let rates: Vec<f64> =
        run.events.others.iter().filter_map(|(_, ev)| ev.strip_prefix("uart0-baud ")?.parse().ok()).collect();
    let near = |rate: Option<&f64>, want: f64| rate.is_some_and(|r| (r - want).abs() < want / 100.0);
    r.check(
        "at 74880 baud: the ROM's boot lines readable, the firmware's (115200 after its PLL write) not",
        rom && !banner && near(rates.first(), 74_880.0) && near(rates.last(), 115_200.0),
        format!(
            "ROM banner and csum line {}, firmware banner {}, UART0 baud {:?}",
            if rom { "read" } else { "missing" },
            if banner { "read (wrong)" } else { "garbage" },
            rates
        ),
    );
    Ok(())
}

/// A QIO header on the board's DIO flash: nothing starts.
fn qio_header(r: &mut Report, fw: &Firmware, e: &Expect) -> Result<(), String> {
    let qio = FlashParams { mode: "qio".into(), ..FlashParams::default() };
    let flash = fw.flash("qio", fw.elf, &qio)?;
    let run = fw.boot("qio", &flash, &[], 1.0, e, ROM_BAUD)?;
    let refused = run.events.first("flash-mode-refused qio").is_some()
        && run.output.stderr.contains("qio mode, which this board's flash (flash-mode=dio) does not answer");
    let started = run.output.uart.contains(&e.banner) || run.events.first("cpu-clock 80000000").is_some();
    let rom_said = line_from(&run.output.uart, "rom:").or_else(|| line_from(&run.output.uart, "csum")).unwrap_or("");
    r.check(
        "negative: the firmware with a QIO header does not start on the DIO flash",
        refused && !started,
        format!(
            "flash read in QIO {}, image {}; the ROM: '{}'",
            if refused { "refused" } else { "NOT refused" },
            if started { "started (wrong)" } else { "never started" },
            rom_said.trim()
        ),
    );
    Ok(())
}

/// The firmware with its take-over of PS and INTENABLE made a `ret`: the
/// ROM's masked interrupts stay masked, the servo interrupt never runs,
/// and the firmware says so.
fn handover(r: &mut Report, fw: &Firmware, e: &Expect) -> Result<(), String> {
    let elf = fw.patched("handover", |elf| {
        let at = symbol(elf, |n| n == "paperbot_interrupt_handover")?;
        write_at(elf, at, &RET)
    })?;
    let flash = fw.flash("handover", &elf, &FlashParams::default())?;
    let run = fw.boot("handover", &flash, &["status"], 1.5, e, "")?;
    let fault = run.output.uart.contains(e.fault_servo_timer);
    let answered = run.output.uart.contains("# status");
    let pulses: usize = super::SERVO_PINS.iter().map(|&p| run.events.pulses(p, 0, u64::MAX).len()).sum();
    r.check(
        "negative: the firmware without its PS/INTENABLE take-over gets no interrupt",
        fault && answered && pulses == 0,
        format!(
            "'{}' {}, status {}, {pulses} servo pulses",
            e.fault_servo_timer,
            if fault { "printed" } else { "NOT printed" },
            if answered { "answered" } else { "not answered" }
        ),
    );
    Ok(())
}

/// The firmware with only the INTENABLE half of its take-over skipped (its
/// `wsr.intenable` made a `nop`): PS comes down with the ROM's INTENABLE
/// bits still on, UART0's level interrupt among them, which it has no
/// handler for: it takes that interrupt for ever and never gets to its
/// banner.
fn intenable_kept(r: &mut Report, fw: &Firmware, e: &Expect) -> Result<(), String> {
    let elf = fw.patched("intenable", |elf| {
        let at = symbol(elf, |n| n == "paperbot_interrupt_handover")?;
        let code = elf_bytes(elf, at, 16)?;
        let offset = code
            .windows(3)
            .position(|w| w == WSR_INTENABLE_A2)
            .ok_or("no wsr.intenable a2 in paperbot_interrupt_handover")?;
        write_at(elf, at + offset as u32, &NOP)
    })?;
    let flash = fw.flash("intenable", &elf, &FlashParams::default())?;
    let events = fw.work.join("strict-intenable.events");
    let profile = fw.work.join("strict-intenable.profile");
    let session = Session {
        flash: &flash,
        events: &events,
        input: None,
        input_after: "",
        input_gap_ms: super::INPUT_GAP_MS,
        sim: None,
        profile: Some(&profile),
        board_options: "",
    };
    let output = fw.board.run_timed(&session, 1000, false)?;
    let booted = read_events(&events)?.first("cpu-clock 80000000").is_some();
    let banner = output.uart.contains(&e.banner);
    // where the CPU was: the level-1 interrupt path (vector, context save
    // and restore, esp8266-hal's dispatcher)
    let symbols = text_symbols(&read(&elf)?)?;
    let (mut all, mut in_interrupt) = (0u64, 0u64);
    for line in std::fs::read_to_string(&profile).map_err(|e| format!("{}: {e}", profile.display()))?.lines() {
        let w: Vec<&str> = line.split_whitespace().collect();
        let (Some(Ok(pc)), Some(Ok(n))) =
            (w.first().map(|v| u64::from_str_radix(v, 16)), w.get(2).map(|v| v.parse::<u64>()))
        else {
            continue;
        };
        let i = symbols.partition_point(|(a, _)| *a <= pc);
        let name = i.checked_sub(1).and_then(|i| symbols.get(i)).map_or("", |(_, n)| n.as_str());
        all += n;
        if INTERRUPT_PATH.iter().any(|p| name.contains(p)) {
            in_interrupt += n;
        }
    }
    let share = in_interrupt as f64 / all.max(1) as f64;
    r.check(
        "negative: the firmware that keeps the ROM's INTENABLE bits never gets past UART0's interrupt",
        booted && !banner && share > 0.9,
        format!(
            "PLL written {}, banner {}, {:.1} % of the PC samples in the level-1 interrupt path",
            if booted { "(the image ran)" } else { "NOT (the image never ran)" },
            if banner { "printed (wrong)" } else { "never printed" },
            share * 100.0
        ),
    );
    Ok(())
}

/// The firmware entered at xtensa-lx-rt's `Reset` (in flash) instead of
/// esp8266-hal's `ESP8266Reset` (IRAM), which enables the flash cache
/// first: the first fetch from flash is refused.
fn cache_off(r: &mut Report, fw: &Firmware, e: &Expect) -> Result<(), String> {
    let elf = fw.patched("cache-off", |elf| {
        let reset = symbol(elf, |n| n == "Reset")?;
        set_entry(elf, reset);
        Ok(())
    })?;
    let flash = fw.flash("cache-off", &elf, &FlashParams::default())?;
    let run = fw.boot("cache-off", &flash, &[], 0.5, e, ROM_BAUD)?;
    let refused = run.events.first("flash-cache-off").map(|(_, ev)| ev.clone());
    let report = line_from(&run.output.uart, "rom: ").unwrap_or("").to_string();
    let started = run.output.uart.contains(&e.banner);
    r.check(
        "negative: the firmware entered past its cache enable cannot run from flash",
        refused.is_some() && report.contains("EXCCAUSE 14 (InstrPIFAddrError)") && !started,
        format!("{}; the ROM: '{report}'", refused.unwrap_or_else(|| "no flash-cache-off event".into())),
    );
    Ok(())
}

/// The probes: RAM at power-up, the PLL, narrow loads, GPIO0 at a reset.
fn probes(r: &mut Report, root: &Path, board: &Board, work: &Path) -> Result<(), String> {
    let run_probe = |mode: &str, seconds: f64, options: &str| -> Result<Run, String> {
        let flash = probe_flash(root, board, work, mode)?;
        boot(board, work, &format!("probe-{mode}"), &flash, &[], seconds, "", options)
    };

    let run = run_probe("ram", 0.2, "")?;
    let line = line_from(&run.output.uart, "probe: unloaded").unwrap_or("").to_string();
    let word = line.rsplit(' ').next().unwrap_or("");
    r.check(
        "negative: a word the image never wrote is not zero at power-up",
        !line.is_empty() && word != "0x00000000",
        if line.is_empty() { "no probe line".into() } else { line },
    );

    let fast = run_probe("no-pll", 0.2, "")?;
    let slow = run_probe("no-pll", 0.2, ROM_BAUD)?;
    let at_115200 = fast.output.uart.contains("probe: no PLL write");
    let at_74880 = slow.output.uart.contains("probe: no PLL write");
    r.check(
        "negative: an image that never writes the PLL talks at 74880 baud",
        !at_115200 && at_74880,
        format!(
            "its line {} at 115200, {} at 74880",
            if at_115200 { "read (wrong)" } else { "garbage" },
            if at_74880 { "read" } else { "missing" }
        ),
    );

    for (mode, what) in [("narrow-iram", "an 8-bit load from IRAM"), ("narrow-flash", "a 16-bit load from flash")] {
        let run = run_probe(mode, 0.2, "")?;
        let report = line_from(&run.output.uart, "rom: ").unwrap_or("").to_string();
        let loaded = run.output.uart.contains("no exception");
        r.check(
            &format!("negative: {what} raises LoadStoreError"),
            report.contains("EXCCAUSE 3 (LoadStoreError)") && !loaded,
            if report.is_empty() { "no exception report (the load went through)".into() } else { report },
        );
    }

    let run = run_probe("gpio0-low", 3.0, "")?;
    let download = run.events.first("download-mode").is_some() && run.output.stderr.contains("UART download mode");
    let boots = run.output.uart.matches("probe: boot").count();
    r.check(
        "negative: a watchdog reset with GPIO0 driven low enters UART download mode",
        download && boots == 1 && run.events.watchdog_resets.len() == 1,
        format!(
            "{} reset(s), download mode {}, {boots} boot(s)",
            run.events.watchdog_resets.len(),
            if download { "entered" } else { "NOT entered" }
        ),
    );
    Ok(())
}

/// The firmware made to panic in its command handler (an illegal
/// instruction) while a lidar's XSHUT (GPIO0) is low: its halt releases
/// the strapping pins, so the watchdog reset boots it again.
fn panic_with_xshut_low(r: &mut Report, fw: &Firmware, e: &Expect) -> Result<(), String> {
    let elf = fw.patched("panic", |elf| {
        let handle =
            symbol(elf, |n| n.starts_with("<paperbot::control::tick::Controller<") && n.contains(">>::handle::<"))?;
        write_at(elf, handle, &ILL)
    })?;
    let flash = fw.flash("panic", &elf, &FlashParams::default())?;
    let run = fw.boot("panic", &flash, &["status"], 4.0, e, "")?;
    let uart = &run.output.uart;
    let reset = run.events.watchdog_resets.first().copied().unwrap_or(u64::MAX);
    // the last GPIO0 edge before the reset is the release, from low
    let gpio0: Vec<_> = run.events.edges.iter().filter(|g| g.pin == GPIO0 && g.ns < reset).collect();
    let released = matches!(gpio0.as_slice(), [.., low, high] if !low.high && high.high);
    let panicked = uart.contains("!panic");
    let banners = uart.matches(&e.banner).count();
    let resets = run.events.watchdog_resets.len();
    let download = run.events.first("download-mode").is_some();
    // the patched image panics again at each boot: every reset boots again
    r.check(
        "the firmware's panic with a lidar's XSHUT low releases GPIO0: it boots again",
        released && panicked && resets >= 1 && banners == resets + 1 && !download,
        format!(
            "GPIO0 {} before the reset, panic {}, {} reset(s), {banners} banner(s), download mode {}",
            if released { "low, then released" } else { "not low then released" },
            if panicked { "reported" } else { "NOT reported" },
            resets,
            if download { "entered (wrong)" } else { "not entered" }
        ),
    );
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_line_is_found_after_the_garbage_of_another_baud_rate() {
        let uart = "\u{fffd}\u{fffd}probe: unloaded DRAM word 0x3ffe9000 reads 0xa5a5a5a5\r\nnext\r\n";
        assert_eq!(line_from(uart, "probe: unloaded"), Some("probe: unloaded DRAM word 0x3ffe9000 reads 0xa5a5a5a5"));
        assert_eq!(line_from(uart, "rom: "), None);
    }

    #[test]
    fn set_entry_writes_the_elf_header_field() {
        let mut elf = vec![0u8; 32];
        set_entry(&mut elf, 0x4022_1560);
        assert_eq!(&elf[24..28], &[0x60, 0x15, 0x22, 0x40]);
    }
}
