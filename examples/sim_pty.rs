//! Serves the simulated paperbot on a pseudo-terminal, in real time, with
//! the robot's serial protocol: anything that talks to the robot (the
//! teleop tool, `picocom`, a script) can talk to the simulator instead.
//!
//! ```text
//! cargo run --example sim_pty -- [options]
//!   --link PATH        also make PATH a symlink to the PTY (e.g. /tmp/paperbot)
//!   --seed N           noise seed (default 1)
//!   --no-noise         exact run: no motion, lidar or compass noise
//!   --start X,Y,DEG    true start pose (default from config::sim)
//!   --duration S       stop after S seconds of wall time (default: run until killed)
//! ```
//! Then, in another terminal: `cargo run --example teleop -- /dev/pts/N`.

use std::process::ExitCode;
use std::sync::atomic::AtomicBool;
use std::sync::Arc;
use std::time::Duration;

use paperbot::sim::body::PoseF64;
use paperbot::sim::robot::{Noise, SimConfig, SimRobot};
use paperbot::sim::serve::Server;
use serialport::{SerialPort, TTYPort};

struct Args {
    cfg: SimConfig,
    link: Option<String>,
    duration_s: Option<f64>,
}

fn parse_args() -> Result<Args, String> {
    let mut a = Args { cfg: SimConfig::default(), link: None, duration_s: None };
    let mut it = std::env::args().skip(1);
    while let Some(flag) = it.next() {
        let mut value = |name: &str| it.next().ok_or(format!("{name} needs a value"));
        let num = |s: &str, name: &str| s.trim().parse::<f64>().map_err(|_| format!("{name}: bad number {s:?}"));
        match flag.as_str() {
            "--link" => a.link = Some(value("--link")?),
            "--seed" => a.cfg.seed = value("--seed")?.parse().map_err(|_| "--seed wants an integer")?,
            "--no-noise" => a.cfg.noise = Noise::OFF,
            "--start" => {
                let v = value("--start")?;
                let p: Vec<&str> = v.split(',').collect();
                let [x, y, deg] = p.as_slice() else { return Err("--start wants X,Y,DEG".into()) };
                a.cfg.start = PoseF64::new(num(x, "--start")?, num(y, "--start")?, num(deg, "--start")?.to_radians());
            }
            "--duration" => a.duration_s = Some(num(&value("--duration")?, "--duration")?),
            "-h" | "--help" => return Err(String::new()),
            f => return Err(format!("unknown option {f}")),
        }
    }
    Ok(a)
}

fn usage() -> String {
    include_str!("sim_pty.rs")
        .lines()
        .skip(5)
        .take(8)
        .map(|l| l.strip_prefix("//! ").unwrap_or(l.trim_start_matches("//!")))
        .filter(|l| !l.starts_with("```"))
        .collect::<Vec<_>>()
        .join("\n")
}

fn main() -> ExitCode {
    let args = match parse_args() {
        Ok(a) => a,
        Err(e) => {
            if !e.is_empty() {
                eprintln!("sim_pty: {e}");
            }
            eprintln!("{}", usage());
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
        let _ = std::fs::remove_file(link);
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
    if let Some(s) = args.duration_s {
        let stop = Arc::clone(&stop);
        let d = Duration::from_secs_f64(s.clamp(0.0, 1e6));
        std::thread::spawn(move || {
            std::thread::sleep(d);
            stop.store(true, std::sync::atomic::Ordering::Relaxed);
        });
    }
    let mut server = Server::new(SimRobot::new(args.cfg));
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
