//! Serves the simulated paperbot on a pseudo-terminal, in real time, with
//! the robot's serial protocol: anything that talks to the robot (the
//! teleop tool, `picocom`, a script) can talk to the simulator instead.
//!
//! ```text
//! cargo run --example sim_pty -- [options]
//!   --link PATH        also make PATH a symlink to the PTY (e.g. /tmp/paperbot; replaces only a symlink)
//!   --seed N           noise seed (default 1)
//!   --no-noise         exact run: no motion, lidar or compass noise
//!   --start X,Y,DEG    true start pose (default from config::sim)
//!   --duration S       stop after S seconds of wall time (default: run until killed)
//!   --truth-hz HZ      also send the true pose as `# truth` lines HZ times a second (teleop --web draws it)
//! ```
//! Then, in another terminal: `cargo run --example teleop -- /dev/pts/N`.
//! Ctrl-C (or the end of `--duration`) stops the server and removes the link.
// Host tool: a panic fails a command on the laptop, never the robot
// (the robot's lints, Cargo.toml).
#![allow(clippy::restriction)]

use std::process::ExitCode;
use std::sync::atomic::AtomicBool;
use std::sync::Arc;
use std::time::Duration;

use paperbot::host::args;
use paperbot::sim::body::PoseF64;
use paperbot::sim::robot::{Noise, SimConfig, SimRobot};
use paperbot::sim::serve::Server;
use serialport::{SerialPort, TTYPort};

struct Args {
    cfg: SimConfig,
    link: Option<String>,
    duration_s: Option<f64>,
    truth_hz: u32,
}

fn parse_args() -> Result<Args, String> {
    let mut a = Args { cfg: SimConfig::default(), link: None, duration_s: None, truth_hz: 0 };
    let mut it = std::env::args().skip(1);
    while let Some(flag) = it.next() {
        let mut value = |name: &str| it.next().ok_or(format!("{name} needs a value"));
        match flag.as_str() {
            "--link" => a.link = Some(value("--link")?),
            "--seed" => a.cfg.seed = value("--seed")?.parse().map_err(|_| "--seed wants an integer")?,
            "--no-noise" => a.cfg.noise = Noise::OFF,
            "--start" => {
                let (x, y, deg) = args::start(&value("--start")?, a.cfg.arena.length_x_mm(), a.cfg.arena.width_y_mm())?;
                a.cfg.start = PoseF64::new(x, y, deg.to_radians());
            }
            "--truth-hz" => {
                a.truth_hz = value("--truth-hz")?.parse().map_err(|_| "--truth-hz wants an integer")?;
                let most = u32::from(paperbot::config::serial::MAX_TELEMETRY_HZ);
                if a.truth_hz > most {
                    return Err(format!("--truth-hz wants 0..{most} (telemetry's fastest)"));
                }
            }
            "--duration" => a.duration_s = Some(args::number("--duration", &value("--duration")?)?),
            f => return Err(format!("unknown option {f}")),
        }
    }
    Ok(a)
}

fn usage() -> String {
    include_str!("sim_pty.rs")
        .lines()
        .skip(5)
        .take(9)
        .map(|l| l.strip_prefix("//! ").unwrap_or(l.trim_start_matches("//!")))
        .filter(|l| !l.starts_with("```"))
        .collect::<Vec<_>>()
        .join("\n")
}

fn main() -> ExitCode {
    if std::env::args().skip(1).any(|a| a == "-h" || a == "--help") {
        println!("{}", usage());
        return ExitCode::SUCCESS;
    }
    let args = match parse_args() {
        Ok(a) => a,
        Err(e) => {
            eprintln!("sim_pty: {e}\n{}", usage());
            return ExitCode::from(2);
        }
    };
    // the slave end stays open here, so the PTY lives between clients
    let (mut master, slave) = match TTYPort::pair() {
        Ok(p) => p,
        Err(e) => {
            eprintln!("sim_pty: cannot open a pseudo-terminal: {e}");
            return ExitCode::FAILURE;
        }
    };
    if let Err(e) = master.set_timeout(Duration::ZERO) {
        eprintln!("sim_pty: {e}");
        return ExitCode::FAILURE;
    }
    let path = slave.name().unwrap_or_default();
    if let Some(link) = &args.link {
        // an old link (from a run that was killed) is replaced; anything else is the user's
        match std::fs::symlink_metadata(link) {
            Ok(m) if m.file_type().is_symlink() => {
                let _ = std::fs::remove_file(link);
            }
            Ok(_) => {
                eprintln!("sim_pty: {link} exists and is not a symlink; not replacing it");
                return ExitCode::FAILURE;
            }
            Err(_) => {}
        }
        if let Err(e) = std::os::unix::fs::symlink(&path, link) {
            eprintln!("sim_pty: cannot link {link} -> {path}: {e}");
            return ExitCode::FAILURE;
        }
    }
    println!("{path}");
    eprintln!(
        "sim_pty: simulated paperbot on {path}{}; try `cargo run --example teleop -- {}`",
        args.link.as_deref().map(|l| format!(" (and {l})")).unwrap_or_default(),
        args.link.as_deref().unwrap_or(&path)
    );
    let stop = Arc::new(AtomicBool::new(false));
    // Ctrl-C and `kill` end the serving loop like --duration does, so the link is removed
    for signal in [signal_hook::consts::SIGINT, signal_hook::consts::SIGTERM] {
        if let Err(e) = signal_hook::flag::register(signal, Arc::clone(&stop)) {
            eprintln!("sim_pty: cannot catch signal {signal}: {e}");
        }
    }
    if let Some(s) = args.duration_s {
        let stop = Arc::clone(&stop);
        let d = Duration::from_secs_f64(s.clamp(0.0, 1e6));
        std::thread::spawn(move || {
            std::thread::sleep(d);
            stop.store(true, std::sync::atomic::Ordering::Relaxed);
        });
    }
    let mut server = Server::new(SimRobot::new(args.cfg)).with_truth(args.truth_hz);
    let result = server.run(&mut master, &stop);
    drop(slave);
    if let Some(link) = &args.link {
        let _ = std::fs::remove_file(link);
    }
    let s = server.stats();
    eprintln!(
        "sim_pty: {} ticks, {} bytes in, {} bytes out, {} lines dropped, {} resyncs",
        s.ticks, s.bytes_in, s.bytes_out, s.dropped_lines, s.resyncs
    );
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("sim_pty: {e}");
            ExitCode::FAILURE
        }
    }
}
