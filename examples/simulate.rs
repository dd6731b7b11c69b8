//! Runs the firmware's control loop against a simulated paperbot in a box
//! arena, prints its serial output (telemetry and responses) and writes the
//! true and the estimated path as an SVG picture.
//!
//! ```text
//! cargo run --release --example simulate -- [options]
//!   --script FILE      command script (see paperbot::sim::script); default: laps around the box
//!   --duration S       seconds of robot time (default 60)
//!   --arena LxW        arena size in mm, x (north) by y (east) (default 762.5x495)
//!   --start X,Y,DEG    true start pose (default from config::sim)
//!   --seed N           noise seed (default 1)
//!   --no-noise         exact run: no motion, lidar or compass noise
//!   --kinematics K     rigid (default) or report (the report's turn equations)
//!   --out FILE         SVG output (default simulate.svg)
//!   --quiet            do not print the robot's output
//!   --print-script     print the built-in script and exit
//! ```

use std::io::Write;
use std::process::ExitCode;
use std::time::Instant;

use paperbot::sim::arena::Arena;
use paperbot::sim::body::{Kinematics, PoseF64};
use paperbot::sim::robot::{Noise, SimConfig, SimRobot};
use paperbot::sim::script::{default_script, Script};
use paperbot::sim::svg::{render, Track};

struct Args {
    cfg: SimConfig,
    script: Option<String>,
    duration_s: f64,
    out: String,
    quiet: bool,
    print_script: bool,
}

fn parse_args() -> Result<Args, String> {
    let mut a = Args {
        cfg: SimConfig::default(),
        script: None,
        duration_s: 60.0,
        out: "simulate.svg".into(),
        quiet: false,
        print_script: false,
    };
    let mut it = std::env::args().skip(1);
    while let Some(flag) = it.next() {
        let mut value = |name: &str| it.next().ok_or(format!("{name} needs a value"));
        let num = |s: &str, name: &str| s.trim().parse::<f64>().map_err(|_| format!("{name}: bad number {s:?}"));
        match flag.as_str() {
            "--script" => a.script = Some(value("--script")?),
            "--duration" => a.duration_s = num(&value("--duration")?, "--duration")?,
            "--arena" => {
                let v = value("--arena")?;
                let (l, w) = v.split_once(['x', 'X', ',']).ok_or("--arena wants LxW, e.g. 762.5x495")?;
                a.cfg.arena = Arena::new(num(l, "--arena")?, num(w, "--arena")?);
            }
            "--start" => {
                let v = value("--start")?;
                let p: Vec<&str> = v.split(',').collect();
                let [x, y, deg] = p.as_slice() else { return Err("--start wants X,Y,DEG".into()) };
                a.cfg.start = PoseF64::new(num(x, "--start")?, num(y, "--start")?, num(deg, "--start")?.to_radians());
            }
            "--seed" => a.cfg.seed = value("--seed")?.parse().map_err(|_| "--seed wants an integer")?,
            "--no-noise" => a.cfg.noise = Noise::OFF,
            "--kinematics" => {
                a.cfg.kinematics = match value("--kinematics")?.as_str() {
                    "rigid" => Kinematics::Rigid,
                    "report" => Kinematics::Report,
                    k => return Err(format!("--kinematics: {k:?}, want rigid or report")),
                }
            }
            "--out" => a.out = value("--out")?,
            "--quiet" => a.quiet = true,
            "--print-script" => a.print_script = true,
            "-h" | "--help" => return Err(String::new()),
            f => return Err(format!("unknown option {f}")),
        }
    }
    if !(a.duration_s.is_finite() && a.duration_s >= 0.0 && a.duration_s <= 86_400.0) {
        return Err("--duration wants 0..86400 s".into());
    }
    let ar = a.cfg.arena;
    if !(ar.length_x > 0.0 && ar.width_y > 0.0 && ar.length_x < 30_000.0 && ar.width_y < 30_000.0) {
        return Err("--arena wants sizes in 0..30000 mm".into());
    }
    Ok(a)
}

fn main() -> ExitCode {
    let args = match parse_args() {
        Ok(a) => a,
        Err(e) => {
            if !e.is_empty() {
                eprintln!("simulate: {e}");
            }
            eprintln!(
                "{}",
                include_str!("simulate.rs")
                    .lines()
                    .skip(5)
                    .take(12)
                    .map(|l| l.trim_start_matches("//! "))
                    .collect::<Vec<_>>()
                    .join("\n")
            );
            return ExitCode::from(2);
        }
    };
    let text = match &args.script {
        None => default_script(args.duration_s),
        Some(path) => match std::fs::read_to_string(path) {
            Ok(t) => t,
            Err(e) => {
                eprintln!("simulate: {path}: {e}");
                return ExitCode::from(2);
            }
        },
    };
    if args.print_script {
        print!("{text}");
        return ExitCode::SUCCESS;
    }
    let script = match Script::parse(&text) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("simulate: {e}");
            return ExitCode::from(2);
        }
    };

    let wall = Instant::now();
    let mut robot = SimRobot::new(args.cfg);
    let stdout = std::io::stdout();
    let mut out = std::io::BufWriter::new(stdout.lock());
    let quiet = args.quiet;
    let samples = robot.run_script(&script, (args.duration_s * 1e6) as u64, 5, |line| {
        if !quiet {
            let _ = writeln!(out, "{line}");
        }
    });
    let _ = out.flush();
    drop(out);
    let elapsed = wall.elapsed();

    let truth: Vec<PoseF64> = samples.iter().map(|s| s.truth).collect();
    let est: Vec<PoseF64> = samples.iter().map(|s| s.estimate).collect();
    let dead: Vec<PoseF64> = samples.iter().map(|s| s.dead_reckoned).collect();
    let title = format!("paperbot simulation: {:.1} s, seed {}", args.duration_s, args.cfg.seed);
    let svg = render(
        &args.cfg.arena,
        &[
            Track { label: "true path", color: "#1f77b4", dashed: false, poses: &truth },
            Track { label: "firmware estimate (telemetry pose)", color: "#d62728", dashed: true, poses: &est },
            Track {
                label: "firmware dead reckoning (state update alone)",
                color: "#999999",
                dashed: true,
                poses: &dead,
            },
        ],
        &title,
    );
    if let Err(e) = std::fs::write(&args.out, svg) {
        eprintln!("simulate: {}: {e}", args.out);
        return ExitCode::FAILURE;
    }
    let last = robot.sample();
    let (t, e, d) = (last.truth, last.estimate, last.dead_reckoned);
    let ctl = robot.controller();
    eprintln!(
        "simulate: {:.1} s of robot time ({} ticks, {} I2C transactions) in {:.3} s; path written to {}",
        args.duration_s,
        ctl.ticks(),
        robot.sensors.bus.transactions(),
        elapsed.as_secs_f64(),
        args.out
    );
    eprintln!("  true      x {:8.1} mm  y {:8.1} mm  heading {:6.1} deg", t.x, t.y, t.theta.to_degrees());
    eprintln!("  estimate  x {:8.1} mm  y {:8.1} mm  heading {:6.1} deg", e.x, e.y, e.theta.to_degrees());
    eprintln!("  dead reck x {:8.1} mm  y {:8.1} mm  heading {:6.1} deg", d.x, d.y, d.theta.to_degrees());
    eprintln!(
        "  estimate error {:.1} mm, {:.1} deg (dead reckoning {:.1} mm); wall collisions: {} ticks; faults {:?}",
        t.distance(&e),
        t.heading_error(&e).to_degrees(),
        t.distance(&d),
        robot.collisions(),
        ctl.faults()
    );
    ExitCode::SUCCESS
}
