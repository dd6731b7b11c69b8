//! `cargo fw-emu --sim`: the image on the emulated board with its pins wired
//! to the project's simulated robot. The simulator is `examples/emu_sim.rs`
//! (paperbot::sim::link), built here and started on a Unix socket the board
//! connects to (`sim=`); it feeds the script to UART0, ends the run after
//! the script's seconds and prints `simulate`'s summary. The board samples
//! the PC meanwhile (`profile=`), for the loop's cost (`cost.rs`).

use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use super::cost::{self, Cost};
use super::qemu::{Board, Output, Session};

/// What a simulated run is asked to do.
#[derive(Debug, Default, Clone, PartialEq)]
pub struct SimOptions {
    pub script: Option<PathBuf>,
    pub seconds: f64,
    pub seed: Option<u64>,
    /// `KIND@FROM-TO` (examples/emu_sim.rs).
    pub faults: Vec<String>,
}

/// A finished run.
pub struct SimRun {
    pub output: Output,
    /// The simulator's summary (its stderr).
    pub summary: String,
    pub simulator_ok: bool,
    pub events: PathBuf,
    pub cost: Cost,
}

/// Virtual seconds allowed for bring-up before the script starts; past
/// them (and the script) the board stops on its own.
const BRING_UP_ALLOWANCE_S: f64 = 30.0;

/// Builds the simulator (release: it answers every I2C bit).
fn build_simulator(root: &Path) -> Result<PathBuf, String> {
    let cargo = std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into());
    let status = Command::new(cargo)
        .args(["build", "--quiet", "--release", "--example", "emu_sim"])
        .current_dir(root)
        .status()
        .map_err(|e| format!("cannot build examples/emu_sim.rs: {e}"))?;
    if !status.success() {
        return Err(format!("building examples/emu_sim.rs failed ({status})"));
    }
    Ok(root.join("target/release/examples/emu_sim"))
}

pub fn run(
    root: &Path,
    board: &Board,
    work: &Path,
    flash: &Path,
    name: &str,
    o: &SimOptions,
    echo: bool,
) -> Result<SimRun, String> {
    let simulator = build_simulator(root)?;
    let socket = work.join(format!("{name}.sock"));
    let _ = std::fs::remove_file(&socket);
    let mut cmd = Command::new(simulator);
    cmd.arg("--socket").arg(&socket).args(["--seconds", &o.seconds.to_string()]);
    cmd.arg("--out").arg(work.join(format!("{name}.svg")));
    if let Some(script) = &o.script {
        cmd.arg("--script").arg(script);
    }
    if let Some(seed) = o.seed {
        cmd.args(["--seed", &seed.to_string()]);
    }
    for f in &o.faults {
        cmd.args(["--fault", f]);
    }
    let mut sim = cmd.stderr(Stdio::piped()).spawn().map_err(|e| format!("cannot start emu_sim: {e}"))?;
    let waited = Instant::now();
    while !socket.exists() {
        if waited.elapsed() > Duration::from_secs(10) || sim.try_wait().map_or(true, |s| s.is_some()) {
            let _ = sim.kill();
            return Err("the simulator did not open its socket".into());
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    let events = work.join(format!("{name}.events"));
    let profile = work.join(format!("{name}.profile"));
    let session = Session {
        flash,
        events: &events,
        input: None,
        input_after: "",
        input_gap_ms: 0,
        sim: Some(&socket),
        profile: Some(&profile),
        board_options: "",
    };
    let stop_ms = ((o.seconds + BRING_UP_ALLOWANCE_S) * 1000.0) as u32;
    let output = board.run_timed(&session, stop_ms, echo);
    let mut summary = String::new();
    if let Some(mut err) = sim.stderr.take() {
        let _ = err.read_to_string(&mut summary);
    }
    let status = sim.wait().map_err(|e| format!("emu_sim: {e}"))?;
    let output = output?;
    let cost = cost::measure(&profile, &root.join("target/image/paperbot.elf"))?;
    Ok(SimRun { output, summary, simulator_ok: status.success(), events, cost })
}
