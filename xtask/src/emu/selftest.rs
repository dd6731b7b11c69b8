//! `cargo fw-emu --self-test`: the firmware image and a watchdog test image
//! on the board, checked from what UART0 sent and from the pin edges in
//! virtual time (the event log). Prints one line per check and a closing
//! `N passed, N failed`; fails when any check does.
//!
//! Expected figures come from the config's files, src/config/ (read at run time, so a tuned
//! constant moves the check with it), not from copies here.

use std::path::Path;

use super::events::{median_gap_ns, Events};
use super::flash::compose;
use super::qemu::{Board, Output, Session};
use super::{banner, read, read_events, write_flash, INPUT_GAP_MS, SERVO_PINS};

const MS: u64 = 1_000_000;
/// Pulse widths must match to this, us (the issue's tolerance).
const WIDTH_TOLERANCE_US: f64 = 5.0;
/// The servo frame may drift this much from config::servo::FRAME_US, us.
const PERIOD_TOLERANCE_US: f64 = 20.0;
/// The LED's half period may be off by this much, ms (the loop's 10 ms tick
/// polls it).
const BLINK_TOLERANCE_MS: f64 = 10.0;
/// The firmware's line when the servo timer interrupt does not run
/// (src/bin/firmware.rs).
const FAULT_SERVO_TIMER: &str = "# fault: servo timer interrupt not running";

#[derive(Default)]
pub(super) struct Report {
    passed: usize,
    failed: usize,
}

impl Report {
    /// `N passed, N failed`; an error when a check failed.
    pub(super) fn finish(&self) -> Result<(), String> {
        println!("{} passed, {} failed", self.passed, self.failed);
        if self.failed == 0 {
            Ok(())
        } else {
            Err(format!("{} check(s) failed", self.failed))
        }
    }

    pub(super) fn check(&mut self, name: &str, ok: bool, detail: impl std::fmt::Display) {
        if ok {
            self.passed += 1;
            println!("ok    {name}: {detail}");
        } else {
            self.failed += 1;
            println!("FAIL  {name}: {detail}");
        }
    }
}

/// The numbers the checks need from the config (src/config/).
pub(super) struct Expect {
    pub(super) banner: String,
    pub(super) deadman_ns: u64,
    pub(super) fault_servo_timer: &'static str,
    blink_fault_ms: f64,
    frame_us: f64,
    pulse_at_0_us: f64,
    pulse_at_180_us: f64,
}

impl Expect {
    pub(super) fn load(root: &Path) -> Result<Self, String> {
        let config = config_source(root)?;
        let get = |name: &str| config_u32(&config, name).ok_or(format!("src/config/ has no `const {name}: u32`"));
        Ok(Expect {
            banner: banner(root)?,
            fault_servo_timer: FAULT_SERVO_TIMER,
            deadman_ns: u64::from(get("DEADMAN_MS")?) * MS,
            blink_fault_ms: f64::from(get("LED_BLINK_FAULT_MS")?),
            frame_us: f64::from(get("FRAME_US")?),
            pulse_at_0_us: f64::from(get("PULSE_AT_0_US")?),
            pulse_at_180_us: f64::from(get("PULSE_AT_180_US")?),
        })
    }

    /// The pulse width of a servo command in steps (0..180, untrimmed).
    pub(super) fn width_us(&self, steps: f64) -> f64 {
        self.pulse_at_0_us + (self.pulse_at_180_us - self.pulse_at_0_us) * steps / 180.0
    }
}

/// The config's source: every file of src/config/, in name order.
pub(super) fn config_source(root: &Path) -> Result<String, String> {
    let dir = root.join("src/config");
    let mut files: Vec<_> = std::fs::read_dir(&dir)
        .map_err(|e| format!("{}: {e}", dir.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "rs"))
        .collect();
    files.sort();
    let mut source = String::new();
    for f in files {
        source.push_str(&String::from_utf8_lossy(&read(&f)?));
    }
    Ok(source)
}

/// `pub const NAME: u32 = 1_000;` in the config's source.
fn config_u32(source: &str, name: &str) -> Option<u32> {
    let prefix = format!("pub const {name}: u32 = ");
    source.lines().find_map(|l| l.trim().strip_prefix(&prefix)?.strip_suffix(';')?.replace('_', "").parse().ok())
}

/// One timed boot: UART0 output and the event log.
pub(super) struct Run {
    pub(super) output: Output,
    pub(super) events: Events,
}

/// A timed boot of `flash`, with more machine options (`uart-baud=74880`,
/// ...) or none ("").
#[allow(clippy::too_many_arguments)]
pub(super) fn boot(
    board: &Board,
    work: &Path,
    name: &str,
    flash: &Path,
    input: &[&str],
    seconds: f64,
    after: &str,
    board_options: &str,
) -> Result<Run, String> {
    let events_path = work.join(format!("selftest-{name}.events"));
    let input_path = work.join(format!("selftest-{name}.input"));
    let lines: String = input.iter().map(|l| format!("{l}\n")).collect();
    std::fs::write(&input_path, lines).map_err(|e| format!("{}: {e}", input_path.display()))?;
    let session = Session {
        flash,
        events: &events_path,
        input: (!input.is_empty()).then_some(&input_path),
        input_after: after,
        input_gap_ms: INPUT_GAP_MS,
        sim: None,
        profile: None,
        board_options,
    };
    let output = board.run_timed(&session, (seconds * 1000.0) as u32, false)?;
    let events = read_events(&events_path)?;
    Ok(Run { output, events })
}

/// When the run fed `line` to UART0, ns.
fn input_time(run: &Run, line: &str) -> Result<u64, String> {
    run.events.inputs.iter().find(|(_, l)| l == line).map(|&(ns, _)| ns).ok_or(format!("'{line}' was never fed"))
}

/// Checks every pulse of the servo pins in `[from, to)` against the widths
/// (left, right) and the frame.
pub(super) fn check_pulses(r: &mut Report, run: &Run, name: &str, from: u64, to: u64, widths_us: [f64; 2], e: &Expect) {
    for (pin, want) in SERVO_PINS.into_iter().zip(widths_us) {
        let pulses = run.events.pulses(pin, from, to);
        let widths: Vec<f64> = pulses.iter().map(|p| p.width_ns as f64 / 1e3).collect();
        let (lo, hi) = widths.iter().fold((f64::MAX, f64::MIN), |(lo, hi), &w| (lo.min(w), hi.max(w)));
        let rises: Vec<u64> = pulses.iter().map(|p| p.rise_ns).collect();
        let period = median_gap_ns(&rises).map_or(0.0, |ns| ns as f64 / 1e3);
        let ok = pulses.len() >= 3
            && (lo - want).abs() <= WIDTH_TOLERANCE_US
            && (hi - want).abs() <= WIDTH_TOLERANCE_US
            && (period - e.frame_us).abs() <= PERIOD_TOLERANCE_US;
        let detail = format!(
            "gpio{pin} {} pulses {lo:.1}..{hi:.1} us (want {want:.1} +-{WIDTH_TOLERANCE_US}), period {period:.1} us",
            pulses.len()
        );
        r.check(name, ok, detail);
    }
}

/// Idle run: banner, `status`, sensors down, the power-up localization
/// failing, the wheels still, LED blink, no watchdog reset.
fn idle(r: &mut Report, board: &Board, work: &Path, flash: &Path, e: &Expect) -> Result<(), String> {
    const SECONDS: f64 = 10.0;
    let run = boot(board, work, "idle", flash, &["status"], SECONDS, &e.banner, "")?;
    let uart = &run.output.uart;
    r.check("banner", uart.contains(&e.banner), format!("'{}' {}", e.banner, found(uart.contains(&e.banner))));
    let fault = uart.contains(FAULT_SERVO_TIMER);
    r.check(
        "the servo timer interrupt runs (PS and INTENABLE taken over from the ROM)",
        !fault,
        format!("'{FAULT_SERVO_TIMER}' {}", if fault { "printed" } else { "not printed" }),
    );
    // from the CR LF before the banner to the end: every LF after a CR
    let from_banner = uart.find(&e.banner).map_or("", |at| &uart[at.saturating_sub(2)..]);
    let bare = from_banner.as_bytes().windows(2).filter(|w| w[1] == b'\n' && w[0] != b'\r').count();
    let lines = from_banner.matches('\n').count();
    r.check(
        "every line on UART0 ends in CR LF",
        !from_banner.is_empty() && bare == 0,
        format!("{lines} lines from the banner on, {bare} ending in a bare LF"),
    );
    let status = uart.lines().find(|l| l.starts_with("# status"));
    r.check("status answered", status.is_some(), status.unwrap_or("no '# status' line"));
    let down = ["front=down", "right=down", "compass=down"];
    let all_down = status.is_some_and(|s| down.iter().all(|d| s.contains(d)));
    r.check("no sensors: each reported down", all_down, down.join(" "));
    let after_banner = uart.split_once(&e.banner).map_or("", |(_, rest)| rest);
    let asked = after_banner.find("# ok locate");
    let failed = after_banner.find("# locate failed: no compass heading");
    let located = after_banner.contains("# located");
    r.check(
        "power-up localization: asked, and failed for want of a compass heading",
        matches!((asked, failed), (Some(a), Some(f)) if a < f) && !located,
        format!(
            "'# ok locate' {}, '# locate failed: no compass heading' {}{}",
            found(asked.is_some()),
            found(failed.is_some()),
            if located { ", but a '# located' line" } else { "" }
        ),
    );
    let neutral = [e.width_us(90.0); 2];
    check_pulses(r, &run, "the wheels stay still with sensors down", 0, u64::MAX, neutral, e);
    let banners = uart.matches(&e.banner).count();
    let resets = run.events.watchdog_resets.len();
    r.check(
        "no watchdog reset over 10 virtual s",
        resets == 0 && banners == 1,
        format!("{resets} resets, {banners} banner(s)"),
    );
    let toggles = run.events.toggles(16, 2_000 * MS, u64::MAX);
    let half_ms = median_gap_ns(&toggles).map_or(0.0, |ns| ns as f64 / 1e6);
    r.check(
        "LED (GPIO16) blinks fast with sensors down",
        toggles.len() > 10 && (half_ms - e.blink_fault_ms).abs() <= BLINK_TOLERANCE_MS,
        format!("{} toggles, half period {half_ms:.1} ms (want {} ms)", toggles.len(), e.blink_fault_ms),
    );
    Ok(())
}

/// `servo 120 60 5` (5 s): the commanded widths.
fn servo(r: &mut Report, board: &Board, work: &Path, flash: &Path, e: &Expect) -> Result<(), String> {
    let run = boot(board, work, "servo", flash, &["servo 120 60 5"], 1.5, &e.banner, "")?;
    let t = input_time(&run, "servo 120 60 5")?;
    let driving = [e.width_us(120.0), e.width_us(60.0)];
    check_pulses(r, &run, "servo 120 60 5", t + 60 * MS, u64::MAX, driving, e);
    Ok(())
}

/// `servo 120 60` (no duration: until the next command), then silence: the
/// commanded widths until the deadman stops the wheels, neutral after.
fn deadman(r: &mut Report, board: &Board, work: &Path, flash: &Path, e: &Expect) -> Result<(), String> {
    let run = boot(board, work, "deadman", flash, &["servo 120 60"], 2.0, &e.banner, "")?;
    let t = input_time(&run, "servo 120 60")?;
    let driving = [e.width_us(120.0), e.width_us(60.0)];
    check_pulses(r, &run, "servo 120 60 until the deadman", t + 60 * MS, t + e.deadman_ns - 50 * MS, driving, e);
    let neutral = [e.width_us(90.0); 2];
    check_pulses(r, &run, "neutral after the deadman", t + e.deadman_ns + 100 * MS, u64::MAX, neutral, e);
    Ok(())
}

/// `servo 120 60 5` then `stop` 100 ms later: neutral before the deadman.
fn stop(r: &mut Report, board: &Board, work: &Path, flash: &Path, e: &Expect) -> Result<(), String> {
    let run = boot(board, work, "stop", flash, &["servo 120 60 5", "stop"], 1.5, &e.banner, "")?;
    let t = input_time(&run, "stop")?;
    let neutral = [e.width_us(90.0); 2];
    check_pulses(r, &run, "neutral after stop", t + 40 * MS, t + e.deadman_ns - 50 * MS, neutral, e);
    Ok(())
}

/// A test image (emu/test/probe.c, `mode`) as a DIO boot image on the
/// board's flash; the flash file.
pub(super) fn probe_flash(root: &Path, board: &Board, work: &Path, mode: &str) -> Result<std::path::PathBuf, String> {
    let flash_params = crate::esptool::FlashParams::default();
    let prefix = work.join(format!("selftest-probe-{mode}-"));
    let image = crate::esptool::boot_image(root, &board.probe_elf(mode), &prefix, &flash_params)?;
    let flash = work.join(format!("selftest-probe-{mode}-flash.bin"));
    std::fs::write(&flash, compose(&read(&image)?, &[])?).map_err(|e| format!("{}: {e}", flash.display()))?;
    Ok(flash)
}

/// The test image stops feeding the watchdog 0.5 s after its PLL write:
/// the board must reset it two stages (2 x 0.84 s) later, and the ROM boot
/// it again.
fn watchdog(r: &mut Report, root: &Path, board: &Board, work: &Path) -> Result<(), String> {
    const STARVE_NS: u64 = 500 * MS;
    const STAGES_NS: u64 = 2 * (1 << 26) * 1000 / 80; // 2 x 2^26 cycles at 80 MHz
    let flash = probe_flash(root, board, work, "wdt")?;
    let run = boot(board, work, "wdt", &flash, &[], 3.0, "", "")?;
    let resets = &run.events.watchdog_resets;
    let pll_at = run.events.first("cpu-clock 80000000").map_or(0, |&(ns, _)| ns);
    let want = pll_at + STARVE_NS + STAGES_NS;
    let at = resets.first().copied().unwrap_or(0);
    let close = at.abs_diff(want) < MS;
    let uart = &run.output.uart;
    let rebooted = uart.contains("probe: starving") && uart.contains("probe: boot 2");
    let reported = run.output.stderr.contains("watchdog reset");
    r.check(
        "an image that stops feeding the watchdog is reset",
        resets.len() == 1 && close && rebooted && reported,
        format!(
            "{} reset(s), at {:.4} s (want {:.4} s), {}",
            resets.len(),
            at as f64 / 1e9,
            want as f64 / 1e9,
            if rebooted { "booted again" } else { "no second boot" }
        ),
    );
    Ok(())
}

fn found(yes: bool) -> &'static str {
    if yes {
        "found"
    } else {
        "missing"
    }
}

pub fn run(root: &Path, board: &Board, work: &Path, boot_bin: &Path, irom_bin: &Path) -> Result<(), String> {
    let expect = Expect::load(root)?;
    let flash = work.join("selftest-flash.bin");
    write_flash(&flash, boot_bin, irom_bin)?;
    let mut report = Report { passed: 0, failed: 0 };
    idle(&mut report, board, work, &flash, &expect)?;
    servo(&mut report, board, work, &flash, &expect)?;
    deadman(&mut report, board, work, &flash, &expect)?;
    stop(&mut report, board, work, &flash, &expect)?;
    super::flashtest::run(&mut report, board, work, &flash, &expect)?;
    super::flashtest::kept_log(&mut report, board, work, &flash, &expect)?;
    watchdog(&mut report, root, board, work)?;
    super::strict::run(&mut report, root, board, work, &expect)?;
    println!("{} passed, {} failed", report.passed, report.failed);
    if report.failed > 0 {
        return Err(format!("fw-emu self-test: {} check(s) failed", report.failed));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn config_constants_are_read() {
        let src = "    pub const DEADMAN_MS: u32 = 500;\n    pub const FRAME_US: u32 = 20_000;\n";
        assert_eq!(config_u32(src, "DEADMAN_MS"), Some(500));
        assert_eq!(config_u32(src, "FRAME_US"), Some(20_000));
        assert_eq!(config_u32(src, "MISSING"), None);
    }

    #[test]
    fn servo_widths_match_the_issue() {
        let e = Expect {
            banner: String::new(),
            fault_servo_timer: FAULT_SERVO_TIMER,
            deadman_ns: 0,
            blink_fault_ms: 0.0,
            frame_us: 0.0,
            pulse_at_0_us: 544.0,
            pulse_at_180_us: 2400.0,
        };
        assert!((e.width_us(120.0) - 1781.0).abs() < 1.0);
        assert!((e.width_us(60.0) - 1163.0).abs() < 1.0);
    }
}
