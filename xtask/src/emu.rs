//! `cargo fw-emu`: the firmware image on the emulated ESP8266 (emu/).
//!
//! Boots `target/image/` (building it with `cargo fw-image` when missing)
//! on the project's QEMU board: UART0 output on stdout; with `--seconds` a
//! timed, deterministic run (virtual time, `-icount`), otherwise UART0 on a
//! pseudo-terminal until stopped. `--self-test` runs the board's checks.
//! `--sim` wires the board's pins to the simulated robot (`sim.rs`),
//! `--sim-test` checks the image driving it.

mod cost;
mod events;
mod flash;
mod flashtest;
mod qemu;
mod selftest;
mod sim;
mod simtest;
mod strict;

use std::path::{Path, PathBuf};
use std::process::Command;

use events::{summarize, Events};
use qemu::{Board, Session};

const USAGE: &str = "\
usage: cargo fw-emu [--seconds S] [--input FILE] [--pulses]
       cargo fw-emu --sim [--script FILE] [--seconds S] [--seed N] [--fault F]... [--quiet]
       cargo fw-emu --self-test | --sim-test

  --seconds S   stop after S virtual seconds (exit 0); without it the board
                runs until stopped, UART0 on a pseudo-terminal
  --input FILE  feed FILE's lines to UART0 once the banner is out, one line
                every 100 virtual ms
  --pulses      at the end, per servo pin: gpioN pulses=N period_us=P
                width_us=W (median period, last pulse's width)
  --self-test   boot the image and the board's test images, check the
                board and the firmware on it, and that the board refuses
                deliberately broken images as the chip would (issue 28);
                prints 'N passed, N failed'
  --sim         the board's I2C, XSHUT and servo pins and UART0 wired to
                the simulated robot (src/sim/link.rs): the script (default:
                laps, as `simulate`) runs for --seconds (default 20) after
                bring-up; prints simulate's summary and the loop's cost,
                writes target/emu/sim.svg
  --script FILE, --seed N   as for `cargo run --example simulate`
  --fault KIND@A-B          a wire fault from A to B virtual seconds after
                power-on: nack:ADDR (hex), sda-low, stall:front|right
  --quiet       do not echo UART0
  --sim-test    the image against the simulated robot: bring-up, a scripted
                drive, the deadman, the loop rate, wire faults

The event log (GPIO edges, input lines, resets; virtual ns) is left in
target/emu/events.log.";

/// Servo pins, left then right (config::pins).
const SERVO_PINS: [u8; 2] = [5, 4];
/// Seconds of robot time of a `--sim` run without `--seconds`.
const DEFAULT_SIM_SECONDS: f64 = 20.0;
/// Virtual ms before the first input line and between lines.
const INPUT_GAP_MS: u32 = 100;

#[derive(Debug, Default, PartialEq)]
struct Options {
    seconds: Option<f64>,
    input: Option<PathBuf>,
    pulses: bool,
    self_test: bool,
    sim: Option<sim::SimOptions>,
    quiet: bool,
    sim_test: bool,
    help: bool,
}

impl Options {
    fn parse(args: &[String]) -> Result<Self, String> {
        let mut o = Options::default();
        let mut sim_options = sim::SimOptions::default();
        let mut it = args.iter();
        while let Some(arg) = it.next() {
            let mut value = || it.next().ok_or_else(|| format!("{arg} needs a value"));
            match arg.as_str() {
                "--seconds" => {
                    let v = value()?;
                    let s: f64 = v.parse().map_err(|_| format!("--seconds: '{v}' is not a number"))?;
                    if !(s > 0.0 && s <= 3600.0) {
                        return Err(format!("--seconds: {s} is outside 0 < S <= 3600"));
                    }
                    o.seconds = Some(s);
                }
                "--input" => o.input = Some(PathBuf::from(value()?)),
                "--pulses" => o.pulses = true,
                "--self-test" => o.self_test = true,
                "--sim" => o.sim = Some(o.sim.take().unwrap_or_default()),
                "--script" => sim_options.script = Some(PathBuf::from(value()?)),
                "--seed" => {
                    let v = value()?;
                    sim_options.seed = Some(v.parse().map_err(|_| format!("--seed: '{v}' is not an integer"))?);
                }
                "--fault" => sim_options.faults.push(value()?.clone()),
                "--quiet" => o.quiet = true,
                "--sim-test" => o.sim_test = true,
                "--help" | "-h" => o.help = true,
                other => return Err(format!("fw-emu: unknown option '{other}'\n{USAGE}")),
            }
        }
        if o.pulses && o.seconds.is_none() {
            return Err("--pulses needs --seconds (the pulses are counted at the end)".into());
        }
        let wants_sim = sim_options != sim::SimOptions::default();
        match o.sim.as_mut() {
            Some(s) => {
                *s = sim::SimOptions { seconds: o.seconds.unwrap_or(DEFAULT_SIM_SECONDS), ..sim_options };
            }
            None if wants_sim => return Err("--script, --seed and --fault need --sim".into()),
            None => {}
        }
        Ok(o)
    }
}

pub fn main(args: &[String]) -> Result<(), String> {
    let options = Options::parse(args)?;
    if options.help {
        println!("{USAGE}");
        return Ok(());
    }
    let root = repo_root();
    let (boot, irom) = image_files(&root)?;
    let board = Board::build(&root)?;
    let work = root.join("target/emu");
    std::fs::create_dir_all(&work).map_err(|e| format!("{}: {e}", work.display()))?;
    if options.self_test {
        return selftest::run(&root, &board, &work, &boot, &irom);
    }
    let flash_path = work.join("flash.bin");
    write_flash(&flash_path, &boot, &irom)?;
    if options.sim_test {
        return simtest::run(&root, &board, &work, &flash_path);
    }
    if let Some(o) = &options.sim {
        let run = sim::run(&root, &board, &work, &flash_path, "sim", o, !options.quiet)?;
        eprint!("{}", run.summary);
        println!("{}", run.cost.report());
        return if run.simulator_ok { Ok(()) } else { Err("the simulated run failed (see above)".into()) };
    }
    let banner = banner(&root)?;
    let events_path = work.join("events.log");
    let session = Session {
        flash: &flash_path,
        events: &events_path,
        input: options.input.as_deref(),
        input_after: &banner,
        input_gap_ms: INPUT_GAP_MS,
        sim: None,
        profile: None,
        board_options: "",
    };
    let Some(seconds) = options.seconds else {
        return board.run_pty(&session);
    };
    board.run_timed(&session, (seconds * 1000.0).round() as u32, true)?;
    if options.pulses {
        let events = read_events(&events_path)?;
        for pin in SERVO_PINS {
            println!("gpio{pin} {}", summarize(&events.pulses(pin, 0, u64::MAX)));
        }
    }
    Ok(())
}

/// The repository: xtask/ is one level down.
fn repo_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).parent().map_or_else(|| PathBuf::from("."), Path::to_path_buf)
}

/// The two files of `cargo fw-image`, built first if either is missing.
fn image_files(root: &Path) -> Result<(PathBuf, PathBuf), String> {
    let dir = root.join("target/image");
    let boot = dir.join("paperbot-0x00000.bin");
    let irom = dir.join("paperbot-0x10000.bin");
    if !boot.exists() || !irom.exists() {
        eprintln!("fw-emu: {} is incomplete, running cargo fw-image", dir.display());
        let cargo = std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into());
        let status = Command::new(cargo)
            .arg("fw-image")
            .current_dir(root)
            .status()
            .map_err(|e| format!("cannot run cargo fw-image: {e}"))?;
        if !status.success() {
            return Err(format!("cargo fw-image failed ({status})"));
        }
    }
    Ok((boot, irom))
}

fn read(path: &Path) -> Result<Vec<u8>, String> {
    std::fs::read(path).map_err(|e| format!("{}: {e}", path.display()))
}

fn write_flash(path: &Path, boot: &Path, irom: &Path) -> Result<(), String> {
    let flash = flash::compose(&read(boot)?, &read(irom)?)?;
    std::fs::write(path, flash).map_err(|e| format!("{}: {e}", path.display()))
}

fn read_events(path: &Path) -> Result<Events, String> {
    Events::parse(&String::from_utf8_lossy(&read(path)?))
}

/// The firmware's first line, `paperbot <version> up` (src/bin/firmware.rs),
/// with the version of the root Cargo.toml.
fn banner(root: &Path) -> Result<String, String> {
    let manifest = String::from_utf8_lossy(&read(&root.join("Cargo.toml"))?).into_owned();
    let version = manifest
        .lines()
        .skip_while(|l| l.trim() != "[package]")
        .find_map(|l| l.trim().strip_prefix("version").and_then(|v| v.trim().strip_prefix('=')))
        .map(|v| v.trim().trim_matches('"').to_string())
        .ok_or("no [package] version in Cargo.toml")?;
    Ok(format!("paperbot {version} up"))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn args(s: &str) -> Vec<String> {
        s.split_whitespace().map(String::from).collect()
    }

    #[test]
    fn options() {
        let o = Options::parse(&args("--seconds 2.5 --input cmds.txt --pulses")).unwrap();
        assert_eq!(o.seconds, Some(2.5));
        assert_eq!(o.input, Some(PathBuf::from("cmds.txt")));
        assert!(o.pulses);
        assert_eq!(Options::parse(&[]).unwrap(), Options::default());
        assert!(Options::parse(&args("--seconds")).is_err());
        assert!(Options::parse(&args("--seconds -1")).is_err());
        assert!(Options::parse(&args("--pulses")).is_err(), "pulses need a timed run");
        assert!(Options::parse(&args("--fast")).is_err());
    }

    #[test]
    fn banner_has_the_package_version() {
        let b = banner(&repo_root()).unwrap();
        assert!(b.starts_with("paperbot ") && b.ends_with(" up"), "{b}");
    }
}
