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
//!   --known-start      the firmware starts believing the start pose (default: it localizes at power-up)
//!   --seed N           noise seed (default 1)
//!   --no-noise         exact run: no motion, lidar or compass noise
//!   --kinematics K     rigid (default) or report (the report's turn equations)
//!   --realism W        the world: lab (default: the lab's beliefs), hard (what real drives meet,
//!                      drawn per seed: issue #29) or ideal (the exact robot); the options below adjust it
//!   --ideal            --realism ideal: the effects below off but the cone (rigid turns, ...)
//!   --body B           whole (default: lidars and skid kept in the box too) or wheels
//!   --speed-spread F   trial-to-trial speed spread, one sigma, all motions (default: the lab's per motion)
//!   --pivot MM,SD      turns pivot MM behind the axle, SD from turn to turn (default 10,5)
//!   --cone DEG         lidar cone, full angle (default 25; hard 0: a thin ray)
//!   --glancing DEG     incidence past which lidar readings start failing (default 60; 90: never)
//!   --compass-disturbance DEG  heading error varying over the floor (default 2)
//!   --out FILE         SVG output (default simulate.svg)
//!   --quiet            do not print the robot's serial output (the summary still goes to stderr)
//!   --print-script     print the script (the built-in one unless --script) and exit
//! ```
//!
//! The firmware's pose is that of the start of its latest tick, so it trails
//! the body by one tick (10 ms: 1.3 mm at 0.13 m/s, 1.4 deg at 2.5 rad/s);
//! an exact run (`--no-noise`) shows only that, and the error at the end
//! depends on what the robot is doing at that moment. The rms over the run
//! compares runs fairly.
//!
//! Exit code 1 when the robot refused a script command (answered `# err`),
//! after the run and the summary; 2 for bad options or a bad script.
// Host tool: a panic fails a command on the laptop, never the robot
// (the robot's lints, Cargo.toml).
#![allow(clippy::restriction)]

use std::io::Write;
use std::process::ExitCode;
use std::time::Instant;

use paperbot::host::args;
use paperbot::sim::arena::Arena;
use paperbot::sim::body::{Kinematics, PoseF64};
use paperbot::sim::realism::Realism;
use paperbot::sim::robot::{Noise, SimConfig, SimRobot};
use paperbot::sim::script::{default_script, Script};
use paperbot::sim::summary::{Compared, Summary};
use paperbot::sim::svg::{render, Track};

struct Args {
    cfg: SimConfig,
    script: Option<String>,
    duration_s: f64,
    out: String,
    quiet: bool,
    print_script: bool,
}

/// `Ok(None)` for `--help`.
fn parse_args() -> Result<Option<Args>, String> {
    let mut a = Args {
        cfg: SimConfig::default(),
        script: None,
        duration_s: 60.0,
        out: "simulate.svg".into(),
        quiet: false,
        print_script: false,
    };
    let mut start = None;
    let mut it = std::env::args().skip(1);
    while let Some(flag) = it.next() {
        let mut value = |name: &str| it.next().ok_or(format!("{name} needs a value"));
        let num = |s: &str, name: &str| s.trim().parse::<f64>().map_err(|_| format!("{name}: bad number {s:?}"));
        match flag.as_str() {
            "--script" => a.script = Some(value("--script")?),
            "--duration" => a.duration_s = num(&value("--duration")?, "--duration")?,
            "--arena" => {
                let (l, w) = args::arena(&value("--arena")?)?;
                a.cfg.arena = Arena::from_mm_f64(l, w);
            }
            "--start" => start = Some(value("--start")?),
            "--known-start" => a.cfg.locate_at_power_up = false,
            "--seed" => a.cfg.seed = value("--seed")?.parse().map_err(|_| "--seed wants an integer")?,
            "--no-noise" => a.cfg.noise = Noise::OFF,
            "--kinematics" => {
                a.cfg.kinematics = match value("--kinematics")?.as_str() {
                    "rigid" => Kinematics::Rigid,
                    "report" => Kinematics::Report,
                    k => return Err(format!("--kinematics: {k:?}, want rigid or report")),
                }
            }
            "--ideal" => a.cfg.realism = Realism::IDEAL,
            "--realism" => {
                let w = value("--realism")?;
                a.cfg.realism = Realism::named(&w).ok_or(format!("--realism: {w:?}, want lab, hard or ideal"))?;
            }
            "--body" => {
                a.cfg.realism.whole_body = match value("--body")?.as_str() {
                    "whole" => true,
                    "wheels" => false,
                    b => return Err(format!("--body: {b:?}, want whole or wheels")),
                }
            }
            "--speed-spread" => a.cfg.realism.speed_spread = [num(&value("--speed-spread")?, "--speed-spread")?; 4],
            "--pivot" => {
                let v = value("--pivot")?;
                let (m, sd) = v.split_once(',').ok_or("--pivot wants MM,SD")?;
                a.cfg.realism.pivot_behind_mm = num(m, "--pivot")?;
                a.cfg.realism.pivot_spread_mm = num(sd, "--pivot")?;
            }
            "--cone" => a.cfg.realism.cone_deg = num(&value("--cone")?, "--cone")?,
            "--glancing" => a.cfg.realism.glancing_deg = num(&value("--glancing")?, "--glancing")?,
            "--compass-disturbance" => {
                a.cfg.realism.compass_disturbance_deg = num(&value("--compass-disturbance")?, "--compass-disturbance")?
            }
            "--out" => a.out = value("--out")?,
            "--quiet" => a.quiet = true,
            "--print-script" => a.print_script = true,
            "-h" | "--help" => return Ok(None),
            f => return Err(format!("unknown option {f}")),
        }
    }
    if !(a.duration_s.is_finite() && a.duration_s >= 0.0 && a.duration_s <= 86_400.0) {
        return Err("--duration wants 0..86400 s".into());
    }
    if let Some(s) = start {
        let (x, y, deg) = args::start(&s, a.cfg.arena.length_x_mm(), a.cfg.arena.width_y_mm())?;
        a.cfg.start = PoseF64::new(x, y, deg.to_radians());
    } else if !a.cfg.arena.contains(a.cfg.start.x, a.cfg.start.y) {
        return Err(format!(
            "the default start ({}, {}) mm is outside a {} x {} mm arena: give --start",
            a.cfg.start.x,
            a.cfg.start.y,
            a.cfg.arena.length_x_mm(),
            a.cfg.arena.width_y_mm()
        ));
    }
    Ok(Some(a))
}

fn usage() -> String {
    let doc = include_str!("simulate.rs");
    doc.lines().skip(5).take(21).map(|l| l.trim_start_matches("//! ")).collect::<Vec<_>>().join("\n")
}

fn main() -> ExitCode {
    let args = match parse_args() {
        Ok(Some(a)) => a,
        Ok(None) => {
            println!("{}", usage());
            return ExitCode::SUCCESS;
        }
        Err(e) => {
            eprintln!("simulate: {e}\n{}", usage());
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
        if !text.ends_with('\n') {
            println!();
        }
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
    let mut refused = Vec::new();
    let samples = robot.run_script(&script, (args.duration_s * 1e6) as u64, 5, |line| {
        if line.starts_with("# err") {
            refused.push(line.to_string());
        }
        if !quiet {
            let _ = writeln!(out, "{line}");
        }
    });
    let _ = out.flush();
    drop(out);
    let elapsed = wall.elapsed();

    let truth: Vec<PoseF64> = samples.iter().map(|s| s.truth).collect();
    // the firmware's poses from its power-up localization's fix on (before
    // it, it does not know where it is)
    let located = samples.iter().position(|s| !s.locating).unwrap_or(samples.len());
    let since_fix = samples.get(located..).unwrap_or(&[]);
    let est: Vec<PoseF64> = since_fix.iter().map(|s| s.estimate).collect();
    let dead: Vec<PoseF64> = since_fix.iter().map(|s| s.dead_reckoned).collect();
    let world = ["ideal", "lab", "hard"]
        .into_iter()
        .find(|w| Realism::named(w) == Some(args.cfg.realism))
        .unwrap_or("adjusted");
    let title = format!("paperbot simulation: {:.1} s, seed {}, {world} world", args.duration_s, args.cfg.seed);
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
    if located == samples.len() {
        eprintln!("  never located at power-up: no estimate to compare (the figures below are empty)");
    } else if located > 0 {
        let t_s = since_fix.first().map_or(args.duration_s, |s| s.t_us as f64 * 1e-6);
        eprintln!("  located at power-up after {t_s:.2} s; the errors over the run count from there");
    }
    let samples: Vec<Compared> = since_fix
        .iter()
        .map(|s| Compared { truth: s.truth, estimate: s.estimate, dead_reckoned: s.dead_reckoned })
        .collect();
    eprint!(
        "{}",
        Summary {
            end: Compared { truth: t, estimate: e, dead_reckoned: d },
            samples: &samples,
            collisions: robot.collisions(),
            faults: ctl.faults(),
        }
    );
    if refused.is_empty() {
        return ExitCode::SUCCESS;
    }
    eprintln!("simulate: the robot refused {} script command(s):", refused.len());
    for r in &refused {
        eprintln!("  {r}");
    }
    ExitCode::FAILURE
}
