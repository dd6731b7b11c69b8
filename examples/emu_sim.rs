//! The simulated robot for the emulated board (`cargo fw-emu --sim` starts
//! it): listens on a Unix socket, serves the board's pins and UART0 (see
//! `paperbot::sim::link`), then prints the same closing summary as
//! `simulate` and writes the same SVG.
//!
//! ```text
//! cargo run --release --example emu_sim -- --socket PATH [options]
//!   --script FILE     command script (see paperbot::sim::script); default: laps around the box
//!   --seconds S       seconds of robot time after bring-up (default 20)
//!   --seed N          noise seed (default 1)
//!   --no-noise        exact run: no motion, lidar or compass noise
//!   --fault F@A-B     a fault at the wire from A to B virtual seconds after power-on:
//!                     nack:ADDR (hex), sda-low, stall:front or stall:right (repeatable)
//!   --out FILE        SVG output (default target/emu/emu-sim.svg)
//! ```
//!
//! The estimate is the telemetry's pose from the image's fix on (its
//! `# located` line, or the answer to `pose`); the dead reckoning is the
//! telemetry's motion column integrated from the fix at the rows' times
//! (the image does not report its own), so it is only as fine as the
//! telemetry rate. Each `# located` line is printed with the true pose at
//! its time.
//! Exit code 1 when the robot refused a script command, 2 for bad options.
// Host tool: a panic fails a command on the laptop, never the robot
// (the robot's lints, Cargo.toml).
#![allow(clippy::restriction)]

use std::io::{BufReader, Write};
use std::os::unix::net::UnixListener;
use std::process::ExitCode;

use paperbot::control::protocol::parse_telemetry_row;
use paperbot::control::protocol::telemetry::TelemetryRow;
use paperbot::sim::body::{advance, MotionF64, PoseF64};
use paperbot::sim::link::{read_event, EmulatedRobot, FaultWindow, WireFault};
use paperbot::sim::robot::{Noise, SimConfig};
use paperbot::sim::script::{default_script, Script};
use paperbot::sim::summary::{Compared, Summary};
use paperbot::sim::svg::{render, Track};

struct Args {
    socket: String,
    cfg: SimConfig,
    script: Option<String>,
    seconds: f64,
    faults: Vec<FaultWindow>,
    out: String,
}

fn parse_fault(spec: &str) -> Result<FaultWindow, String> {
    let bad = || format!("--fault {spec:?}: want KIND@FROM-TO (seconds), KIND nack:ADDR, sda-low, stall:front|right");
    let (kind, window) = spec.split_once('@').ok_or_else(bad)?;
    let (a, b) = window.split_once('-').ok_or_else(bad)?;
    let secs = |s: &str| s.trim().parse::<f64>().ok().filter(|v| *v >= 0.0).map(|v| (v * 1e9) as u64);
    let (from_ns, to_ns) = (secs(a).ok_or_else(bad)?, secs(b).ok_or_else(bad)?);
    let fault = match kind.split_once(':') {
        Some(("nack", addr)) => {
            WireFault::Nack(u8::from_str_radix(addr.trim_start_matches("0x"), 16).map_err(|_| bad())?)
        }
        Some(("stall", "front")) => WireFault::LidarStall { right: false },
        Some(("stall", "right")) => WireFault::LidarStall { right: true },
        None if kind == "sda-low" => WireFault::SdaLow,
        _ => return Err(bad()),
    };
    Ok(FaultWindow { fault, from_ns, to_ns })
}

fn parse_args() -> Result<Args, String> {
    let mut a = Args {
        socket: String::new(),
        cfg: SimConfig::default(),
        script: None,
        seconds: 20.0,
        faults: Vec::new(),
        out: "target/emu/emu-sim.svg".into(),
    };
    let mut it = std::env::args().skip(1);
    while let Some(flag) = it.next() {
        let mut value = |name: &str| it.next().ok_or(format!("{name} needs a value"));
        match flag.as_str() {
            "--socket" => a.socket = value("--socket")?,
            "--script" => a.script = Some(value("--script")?),
            "--seconds" => {
                a.seconds = value("--seconds")?.parse().map_err(|_| "--seconds wants a number")?;
            }
            "--seed" => a.cfg.seed = value("--seed")?.parse().map_err(|_| "--seed wants an integer")?,
            "--no-noise" => a.cfg.noise = Noise::OFF,
            "--fault" => a.faults.push(parse_fault(&value("--fault")?)?),
            "--out" => a.out = value("--out")?,
            f => return Err(format!("unknown option {f}")),
        }
    }
    if a.socket.is_empty() {
        return Err("--socket PATH is required".into());
    }
    if !(a.seconds.is_finite() && a.seconds > 0.0 && a.seconds <= 3600.0) {
        return Err("--seconds wants 0 < S <= 3600".into());
    }
    Ok(a)
}

/// Serves one board until it ends the run.
fn serve(socket: &str, robot: &mut EmulatedRobot) -> std::io::Result<()> {
    let _ = std::fs::remove_file(socket);
    let listener = UnixListener::bind(socket)?;
    let (stream, _) = listener.accept()?;
    let _ = std::fs::remove_file(socket);
    let mut reader = BufReader::with_capacity(1 << 16, stream.try_clone()?);
    let mut writer = stream;
    while let Some(ev) = read_event(&mut reader)? {
        if let Some(answer) = robot.handle(ev) {
            writer.write_all(&answer.encode())?;
        }
        if robot.ended_ns.is_some() {
            break;
        }
    }
    Ok(())
}

fn pose_of(r: &TelemetryRow) -> PoseF64 {
    PoseF64::new(f64::from(r.x_dmm) / 10.0, f64::from(r.y_dmm) / 10.0, f64::from(r.heading_mdeg).to_radians() / 1000.0)
}

/// ` (truth ...; fix error N mm, heading error N deg)` for a `# located x
/// y heading ...` line; empty for any other.
fn against_truth(line: &str, truth: &PoseF64) -> String {
    let mut words = line.strip_prefix("# located ").unwrap_or_default().split_whitespace();
    let mut number = || words.next().and_then(|w| w.parse::<f64>().ok());
    let (Some(x), Some(y), Some(deg)) = (number(), number(), number()) else {
        return String::new();
    };
    let fix = PoseF64::new(x, y, deg.to_radians());
    format!(
        " (truth x {:.1} y {:.1} heading {:.1} deg; fix error {:.1} mm, heading error {:.1} deg)",
        truth.x,
        truth.y,
        truth.theta.to_degrees().rem_euclid(360.0),
        truth.distance(&fix),
        truth.heading_error(&fix).to_degrees()
    )
}

fn motion_of(r: &TelemetryRow) -> MotionF64 {
    match (r.v_mm_s, r.w_mrad_s) {
        (0, 0) => MotionF64::Stop,
        (v, 0) => MotionF64::Straight(f64::from(v)),
        (_, w) => MotionF64::Turn(f64::from(w) / 1000.0),
    }
}

fn main() -> ExitCode {
    let args = match parse_args() {
        Ok(a) => a,
        Err(e) => {
            eprintln!("emu_sim: {e}");
            return ExitCode::from(2);
        }
    };
    let text = match &args.script {
        None => default_script(args.seconds),
        Some(path) => match std::fs::read_to_string(path) {
            Ok(t) => t,
            Err(e) => {
                eprintln!("emu_sim: {path}: {e}");
                return ExitCode::from(2);
            }
        },
    };
    let script = match Script::parse(&text) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("emu_sim: {e}");
            return ExitCode::from(2);
        }
    };
    let mut robot = EmulatedRobot::new(args.cfg, script, (args.seconds * 1e9) as u64, &args.faults);
    if let Err(e) = serve(&args.socket, &mut robot) {
        eprintln!("emu_sim: {}: {e}", args.socket);
        return ExitCode::FAILURE;
    }
    summary(&args, &robot)
}

fn summary(args: &Args, robot: &EmulatedRobot) -> ExitCode {
    // The image powers up at the box's centre, not knowing where it is:
    // its rows count from its fix, the power-up localization's `# located`
    // (or the answer to `pose` when it is told its start)
    let up_ns = robot.script_start_ns().unwrap_or(0);
    let start_ns = robot
        .lines
        .iter()
        .find(|(t, l)| *t >= up_ns && (l.starts_with("# located") || l.starts_with("# ok pose")))
        .map_or(0, |(t, _)| *t);
    let rows: Vec<(u64, TelemetryRow)> = robot
        .lines
        .iter()
        .filter(|(t, _)| *t >= start_ns)
        .filter_map(|(t, l)| parse_telemetry_row(l).ok().map(|r| (*t, r)))
        .collect();
    // t_ms counts from the loop's first tick: a row's first byte leaves
    // right after its tick, so the least lag of any row gives the tick's
    // virtual time
    let offset_ns = rows.iter().map(|(t, r)| t.saturating_sub(u64::from(r.t_ms) * 1_000_000)).min().unwrap_or(0);
    let d = paperbot::config::geometry::ROTATION_TO_REFERENCE.to_mm_f64();
    // the image's dead reckoning starts from its fix
    let mut dead = rows.first().map_or(args.cfg.start, |(_, r)| pose_of(r));
    let mut truth = Vec::new();
    let mut est = Vec::new();
    let mut dead_track = Vec::new();
    for (i, (_, r)) in rows.iter().enumerate() {
        if let Some((_, prev)) = i.checked_sub(1).and_then(|j| rows.get(j)) {
            let dt = f64::from(r.t_ms.wrapping_sub(prev.t_ms)) / 1000.0;
            dead = advance(&dead, motion_of(prev), dt, args.cfg.kinematics, d);
        }
        truth.push(robot.truth_at(u64::from(r.t_ms) * 1_000_000 + offset_ns));
        est.push(pose_of(r));
        dead_track.push(dead);
    }
    let title = format!("paperbot on the emulated ESP8266: {:.1} s, seed {}", args.seconds, args.cfg.seed);
    let svg = render(
        &args.cfg.arena,
        &[
            Track { label: "true path", color: "#1f77b4", dashed: false, poses: &truth },
            Track { label: "image's estimate (telemetry pose)", color: "#d62728", dashed: true, poses: &est },
            Track { label: "dead reckoning (telemetry motions)", color: "#999999", dashed: true, poses: &dead_track },
        ],
        &title,
    );
    if let Err(e) = std::fs::write(&args.out, svg) {
        eprintln!("emu_sim: {}: {e}", args.out);
        return ExitCode::FAILURE;
    }
    let (addressed, nacked) = robot.wire.addressed();
    eprintln!(
        "emu-sim: {:.1} s of robot time ({} telemetry rows, {} I2C address phases, {} not acknowledged); path written to {}",
        args.seconds,
        rows.len(),
        addressed,
        nacked,
        args.out
    );
    for (t, l) in &robot.lines {
        if l.starts_with("lidars ") {
            eprintln!("  bring-up at {:.3} s: {l}", *t as f64 * 1e-9);
        }
    }
    for (t, l) in &robot.lines {
        if l.starts_with("# located") || l.starts_with("# locate failed") {
            let after = t.saturating_sub(up_ns) as f64 * 1e-9;
            eprintln!("  {after:.3} s after bring-up: {l}{}", against_truth(l, &robot.truth_at(*t)));
        }
    }
    let f = robot.sensors.front.borrow();
    let r = robot.sensors.right.borrow();
    eprintln!("  lidar addresses: front 0x{:02x}, right 0x{:02x}", f.address(), r.address());
    let (Some((_, last)), Some(t), Some(e), Some(dr)) = (rows.last(), truth.last(), est.last(), dead_track.last())
    else {
        eprintln!("emu-sim: no telemetry rows after bring-up");
        return ExitCode::FAILURE;
    };
    let samples: Vec<Compared> = truth
        .iter()
        .zip(&est)
        .zip(&dead_track)
        .map(|((&truth, &estimate), &dead_reckoned)| Compared { truth, estimate, dead_reckoned })
        .collect();
    eprint!(
        "{}",
        Summary {
            end: Compared { truth: *t, estimate: *e, dead_reckoned: *dr },
            samples: &samples,
            collisions: robot.collisions(),
            faults: last.faults,
        }
    );
    let refused: Vec<&String> = robot.lines.iter().map(|(_, l)| l).filter(|l| l.starts_with("# err")).collect();
    if refused.is_empty() {
        return ExitCode::SUCCESS;
    }
    eprintln!("emu_sim: the robot refused {} script command(s):", refused.len());
    for r in refused {
        eprintln!("  {r}");
    }
    ExitCode::FAILURE
}
