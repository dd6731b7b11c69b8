//! The emulated board: emu/build-qemu.sh builds (or finds in its cache)
//! QEMU with the project's `esp8266` machine and the board's ROM; this
//! starts it on a flash image.

use std::io::{BufRead, BufReader, Read, Write};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

/// Virtual time per guest instruction: 2^4 ns = 16 ns, 1.28 cycles of the
/// 80 MHz lx106, near its average cycles per instruction. Fixed, so every
/// run of the same image and input is the same run.
const ICOUNT_SHIFT: u32 = 4;

/// Virtual ns between PC samples: prime, so the samples do not lock onto
/// the loop's or the I2C clock's period.
pub const PROFILE_NS: u32 = 10_007;

/// The built board: QEMU, the ROM and the test images.
pub struct Board {
    dir: PathBuf,
}

/// One boot of the board.
pub struct Session<'a> {
    pub flash: &'a Path,
    /// Where the board writes its event log (see `events.rs`).
    pub events: &'a Path,
    /// Lines fed to UART0 once UART0 has sent `input_after`.
    pub input: Option<&'a Path>,
    pub input_after: &'a str,
    /// Virtual ms before the first input line and between lines.
    pub input_gap_ms: u32,
    /// The simulator's socket (`sim.rs`): the pins wired to the simulated robot.
    pub sim: Option<&'a Path>,
    /// Where the board writes its PC samples.
    pub profile: Option<&'a Path>,
    /// More machine options, `name=value,...` (e.g. `uart-baud=74880`), or "".
    pub board_options: &'a str,
}

/// What a timed run printed.
pub struct Output {
    pub uart: String,
    pub stderr: String,
}

impl Board {
    /// Builds the board if emu/'s sources changed since the cached build.
    pub fn build(root: &Path) -> Result<Self, String> {
        let script = root.join("emu/build-qemu.sh");
        let out = Command::new("bash")
            .arg(&script)
            .stderr(Stdio::inherit())
            .output()
            .map_err(|e| format!("cannot run {}: {e}", script.display()))?;
        if !out.status.success() {
            return Err(format!("{} failed ({})", script.display(), out.status));
        }
        let dir = PathBuf::from(String::from_utf8_lossy(&out.stdout).trim());
        Ok(Board { dir })
    }

    /// The ELF of a test image: emu/test/probe.c built for `mode` (wdt,
    /// gpio0-low, no-pll, ram, narrow-iram, narrow-flash).
    pub fn probe_elf(&self, mode: &str) -> PathBuf {
        self.dir.join(format!("probe-{mode}.elf"))
    }

    fn command(&self, s: &Session, stop_ms: Option<u32>, icount: &str, serial: &str) -> Command {
        // QEMU's option syntax: a comma in a value is written twice
        let value = |p: &Path| p.display().to_string().replace(',', ",,");
        let mut machine = format!(
            "esp8266,rom={},flash={},events={}",
            value(&self.dir.join("rom.elf")),
            value(s.flash),
            value(s.events)
        );
        if let Some(input) = s.input {
            machine += &format!(
                ",uart-input={},uart-input-after={},input-gap-ms={}",
                value(input),
                s.input_after.replace(',', ",,"),
                s.input_gap_ms
            );
        }
        if let Some(sim) = s.sim {
            machine += &format!(",sim={}", value(sim));
        }
        if let Some(profile) = s.profile {
            machine += &format!(",profile={},profile-ns={PROFILE_NS}", value(profile));
        }
        if let Some(ms) = stop_ms {
            machine += &format!(",stop-ms={ms}");
        }
        if !s.board_options.is_empty() {
            machine += &format!(",{}", s.board_options);
        }
        let mut cmd = Command::new(self.dir.join("qemu-system-xtensa"));
        cmd.args(["-M", &machine, "-cpu", "lx106", "-nodefaults", "-display", "none", "-monitor", "none"]);
        cmd.args(["-icount", icount, "-serial", serial]);
        cmd
    }

    /// Runs `stop_ms` virtual milliseconds; UART0 output is returned and,
    /// with `echo`, printed as it comes (stderr too).
    pub fn run_timed(&self, s: &Session, stop_ms: u32, echo: bool) -> Result<Output, String> {
        let icount = format!("shift={ICOUNT_SHIFT},sleep=off");
        let mut child = self
            .command(s, Some(stop_ms), &icount, "stdio")
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .map_err(|e| format!("cannot start QEMU: {e}"))?;
        let stderr = child.stderr.take().ok_or("no stderr")?;
        let stderr_reader = std::thread::spawn(move || copy_text(stderr, echo.then(std::io::stderr)));
        let uart = copy_text(child.stdout.take().ok_or("no stdout")?, echo.then(std::io::stdout));
        let status = child.wait().map_err(|e| format!("QEMU: {e}"))?;
        let stderr = stderr_reader.join().unwrap_or_default();
        if !status.success() {
            return Err(format!("QEMU exited with {status}:\n{stderr}"));
        }
        Ok(Output { uart, stderr })
    }

    /// Runs until stopped, UART0 on a pseudo-terminal, virtual time kept
    /// near wall time (`align=on`) so a host program can drive it.
    pub fn run_pty(&self, s: &Session) -> Result<(), String> {
        let icount = format!("shift={ICOUNT_SHIFT},align=on");
        let mut child = self
            .command(s, None, &icount, "pty")
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .spawn()
            .map_err(|e| format!("cannot start QEMU: {e}"))?;
        // QEMU prints "char device redirected to /dev/pts/N (label serial0)"
        let stdout = BufReader::new(child.stdout.take().ok_or("no stdout")?);
        for line in stdout.lines().map_while(Result::ok) {
            match line.split_once("redirected to ") {
                Some((_, rest)) => {
                    let pty = rest.split_whitespace().next().unwrap_or(rest);
                    println!("UART0 is on {pty} (stop with Ctrl-C); drive the robot with");
                    println!("  cargo run --example teleop -- {pty}");
                }
                None => println!("{line}"),
            }
        }
        let status = child.wait().map_err(|e| format!("QEMU: {e}"))?;
        if status.success() {
            Ok(())
        } else {
            Err(format!("QEMU exited with {status}"))
        }
    }
}

/// Reads `from` to the end as text, passing it on to `echo` as it comes.
fn copy_text(mut from: impl Read, mut echo: Option<impl Write>) -> String {
    let mut all = Vec::new();
    let mut buf = [0u8; 4096];
    while let Ok(n @ 1..) = from.read(&mut buf) {
        all.extend_from_slice(&buf[..n]);
        if let Some(out) = echo.as_mut() {
            let _ = out.write_all(&buf[..n]);
            let _ = out.flush();
        }
    }
    String::from_utf8_lossy(&all).into_owned()
}
