//! The host tools (`examples/`) as a user runs them: `--help` on stdout
//! with exit code 0, bad options and bad input refused with a message and a
//! non-zero exit code, the files they write; `teleop --web` serving
//! `sim_pty --truth-hz` as processes. `cargo test` builds the
//! examples first (`cargo build --examples` when running this file alone).

use std::path::PathBuf;
use std::process::{Command, Output};

fn tool(name: &str) -> Command {
    // target/debug/deps/tools-HASH -> target/debug/examples/NAME
    let exe = std::env::current_exe().unwrap();
    let path: PathBuf = exe.parent().unwrap().parent().unwrap().join("examples").join(name);
    assert!(path.exists(), "{} is not built: run `cargo build --examples`", path.display());
    let mut c = Command::new(path);
    c.current_dir(std::env::temp_dir());
    c
}

fn run(name: &str, args: &[&str]) -> Output {
    tool(name).args(args).output().unwrap()
}

fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

fn data(file: &str) -> String {
    format!("{}/tests/data/{file}", env!("CARGO_MANIFEST_DIR"))
}

fn scratch(name: &str) -> PathBuf {
    std::env::temp_dir().join(format!("paperbot-tools-{}-{name}", std::process::id()))
}

#[test]
fn help_goes_to_stdout_with_exit_code_0_on_every_tool() {
    for name in ["fit", "replay", "simulate", "teleop", "sim_pty"] {
        let out = run(name, &["--help"]);
        let help = text(&out.stdout);
        assert!(out.status.success(), "{name}: {:?} {}", out.status, text(&out.stderr));
        assert!(help.contains("usage") || help.contains("cargo run"), "{name}: {help}");
        assert!(!help.contains("```"), "{name}: {help}");
        assert!(out.stderr.is_empty(), "{name}: {}", text(&out.stderr));
    }
}

#[test]
fn fit_refuses_non_finite_and_zero_times_and_too_few_pairs() {
    let head = "motion,left_cmd,right_cmd,trial,seconds,what_was_timed\n";
    for (name, body) in [
        ("nan", "forward,100,80,1,nan,x\nforward,110,70,1,3,x\n"),
        ("inf", "forward,100,80,1,inf,x\nforward,110,70,1,3,x\n"),
        ("zero", "forward,100,80,1,0,x\nforward,110,70,1,3,x\n"),
        ("one-pair", "forward,100,80,1,3,x\nforward,100,80,2,3.1,x\n"),
        ("no-rows", ""),
    ] {
        let path = scratch(&format!("{name}.csv"));
        std::fs::write(&path, format!("{head}{body}")).unwrap();
        let out = run("fit", &[path.to_str().unwrap()]);
        std::fs::remove_file(&path).unwrap();
        assert_eq!(out.status.code(), Some(1), "{name}: {}", text(&out.stdout));
        assert!(out.stdout.is_empty(), "{name}: nothing to paste, got {}", text(&out.stdout));
        assert!(text(&out.stderr).starts_with("fit: "), "{name}: {}", text(&out.stderr));
    }
    let out = run("fit", &[&data("lab1/lidar_front.csv")]);
    assert!(out.status.success());
    assert!(text(&out.stdout).contains("LidarModel::new(0.9849, -56.2555,"), "{}", text(&out.stdout));
    assert_eq!(run("fit", &[&data("lab1/lidar_front.csv"), "--all-readings"]).status.code(), Some(2));
}

#[test]
fn replay_takes_simulates_syntax_and_draws_a_labelled_picture() {
    let svg = scratch("replay.svg");
    let out = run(
        "replay",
        &[&data("estimator/replay_sample.csv"), "--arena", "800x500", "--start", "153.6,146.5,0", "--out"],
    );
    assert_eq!(out.status.code(), Some(2), "--out without a value");
    let out = tool("replay")
        .args([&data("estimator/replay_sample.csv"), "--arena", "800x500", "--start", "153.6,146.5,0", "--out"])
        .arg(&svg)
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert_eq!(text(&out.stdout).lines().count(), 2001, "header and one row per log row");
    let picture = std::fs::read_to_string(&svg).unwrap();
    std::fs::remove_file(&svg).unwrap();
    for want in [
        "paperbot replay of replay_sample.csv:",
        "arena 800.0 x 500.0 mm",
        "N ^",
        "firmware estimate",
        "open circle: start",
    ] {
        assert!(picture.contains(want), "no {want:?} in the SVG");
    }
    assert!(!picture.contains("estimator/replay_sample.csv"), "the title names the log by file name, not its path");
    legend_fits(&picture);
    // how the estimate agrees with its readings (issue #29)
    let err = text(&out.stderr);
    for want in ["front lidar", "% of", "usable readings accepted, mean normalised innovation"] {
        assert!(err.contains(want), "no {want:?} in {err}");
    }
    // an empty log: an error, and no picture
    let log = scratch("empty.csv");
    std::fs::write(&log, "t_ms,left_cmd,right_cmd,front_mm,right_mm,heading_deg\n").unwrap();
    let out = tool("replay").arg(&log).arg("--out").arg(&svg).output().unwrap();
    std::fs::remove_file(&log).unwrap();
    assert_eq!(out.status.code(), Some(1));
    assert!(text(&out.stderr).contains("no rows"), "{}", text(&out.stderr));
    assert!(!svg.exists(), "no SVG for an empty log");
}

/// The replay's picture colours the path by the hypothesis the estimator
/// reported, a legend row per id inside the picture, and dashes where it
/// was not located (issue #29): the sample log (a typed start, no
/// re-search) is one hypothesis throughout; on drive1 the right lidar
/// starts a re-search whose hypothesis takes over: a second id.
#[test]
fn replay_colours_the_path_by_the_reported_hypothesis() {
    let legend = |args: &[&str]| -> Vec<String> {
        let svg = scratch("hypotheses.svg");
        let out = tool("replay").args(args).arg("--out").arg(&svg).output().unwrap();
        assert!(out.status.success(), "{}", text(&out.stderr));
        let picture = std::fs::read_to_string(&svg).unwrap();
        std::fs::remove_file(&svg).unwrap();
        legend_fits(&picture);
        let height: f64 = picture.split(" height=\"").nth(1).unwrap().split('"').next().unwrap().parse().unwrap();
        let mut rows = Vec::new();
        for part in picture.split("<text").skip(1) {
            let y: f64 = part.split(" y=\"").nth(1).unwrap().split('"').next().unwrap().parse().unwrap();
            assert!(y < height, "a text at y {y}, below the picture's {height} px");
            rows.push(part.split_once('>').unwrap().1.split("</text>").next().unwrap().to_string());
        }
        rows
    };
    let ids = |rows: &[String]| rows.iter().filter(|r| r.starts_with("reported: hypothesis ")).count();
    let sample = legend(&[&data("estimator/replay_sample.csv"), "--start", "153.6,146.5,0"]);
    assert_eq!(ids(&sample), 1, "{sample:?}");
    let drive1 = legend(&[&data("lab2/drive1.csv")]);
    assert_eq!(ids(&drive1), 2, "{drive1:?}");
    // drive1 starts from an ambiguous fix
    assert!(drive1.iter().any(|r| r.starts_with("dashed: not located")), "{drive1:?}");
}

#[test]
fn arena_and_start_outside_it_are_refused_clearly() {
    for (name, args, want) in [
        ("simulate", &["--arena", "0x0"][..], "--arena 0x0: each side must be 1..30000 mm"),
        ("simulate", &["--arena", "800"][..], "--arena wants LxW"),
        ("simulate", &["--start", "900,100,0"][..], "outside the 762.5 x 495 mm arena"),
        ("simulate", &["--arena", "100x100"][..], "default start (170, 170) mm is outside"),
        ("replay", &["log.csv", "--arena", "0x0"][..], "--arena 0x0: each side must be 1..30000 mm"),
        ("replay", &["log.csv", "--start", "100,-5,0"][..], "outside the 762.5 x 495 mm arena"),
        ("sim_pty", &["--start", "100,600,0"][..], "outside the 762.5 x 495 mm arena"),
    ] {
        let out = run(name, args);
        assert!(!out.status.success(), "{name} {args:?}");
        assert!(text(&out.stderr).contains(want), "{name} {args:?}: {}", text(&out.stderr));
    }
}

#[test]
fn simulate_fails_when_the_robot_refuses_a_script_command_and_quiet_prints_nothing() {
    let script = scratch("script.txt");
    let svg = scratch("sim.svg");
    std::fs::write(&script, "@0 fwd 0.13 0.5\n@0.6 fwd 5\n").unwrap();
    let out = tool("simulate")
        .args(["--duration", "1", "--quiet", "--script"])
        .arg(&script)
        .arg("--out")
        .arg(&svg)
        .output()
        .unwrap();
    std::fs::remove_file(&script).unwrap();
    std::fs::remove_file(&svg).unwrap();
    let err = text(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(out.stdout.is_empty(), "--quiet: {}", text(&out.stdout));
    assert!(err.contains("refused 1 script command") && err.contains("# err speed out of range"), "{err}");
    assert!(err.contains("faults: bus 0, timeout 0, missing 0, bad sample 0, outliers 0, overruns 0"), "{err}");
    assert!(err.ends_with('\n'), "{err:?}");
    let out = run("simulate", &["--print-script"]);
    assert!(out.status.success() && text(&out.stdout).ends_with('\n'));
}

#[test]
fn teleop_web_serves_sim_pty_with_its_truth_and_refuses_a_port_in_use() {
    use std::io::{BufRead, BufReader};
    use std::process::Stdio;
    use std::time::{Duration, Instant};
    // a port in use: refused before the robot's port is even opened
    let taken = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    let addr = taken.local_addr().unwrap().to_string();
    let out = run("teleop", &["/dev/null", "--web", &addr]);
    assert!(!out.status.success() && text(&out.stderr).contains("the port is in use"), "{}", text(&out.stderr));
    drop(taken);
    let out = run("sim_pty", &["--truth-hz", "1000"]);
    assert!(!out.status.success() && text(&out.stderr).contains("--truth-hz wants 0..100"));

    // the two commands of docs/web.md, as processes
    let mut sim = tool("sim_pty")
        .args(["--no-noise", "--truth-hz", "20", "--duration", "30"])
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let mut pty = String::new();
    BufReader::new(sim.stdout.take().unwrap()).read_line(&mut pty).unwrap();
    let teleop = tool("teleop").args([pty.trim(), "--web", &addr]).stderr(Stdio::piped()).spawn().unwrap();
    let start = Instant::now();
    let mut ws = loop {
        match tungstenite::connect(format!("ws://{addr}/ws")) {
            Ok((ws, _)) => break ws,
            Err(e) => assert!(start.elapsed() < Duration::from_secs(10), "teleop --web never served: {e}"),
        }
        std::thread::sleep(Duration::from_millis(50));
    };
    let mut seen = std::collections::BTreeSet::new();
    while !(seen.contains("row") && seen.contains("truth")) {
        assert!(start.elapsed() < Duration::from_secs(15), "only {seen:?}");
        let msg: serde_json::Value = serde_json::from_str(ws.read().unwrap().to_text().unwrap()).unwrap();
        seen.insert(msg["type"].as_str().unwrap().to_string());
    }
    assert!(seen.contains("hello"));
    // Ctrl-C stops the robot and quits cleanly
    let int = |pid: u32| Command::new("kill").args(["-INT", &pid.to_string()]).status().unwrap();
    assert!(int(teleop.id()).success());
    let out = teleop.wait_with_output().unwrap();
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(text(&out.stderr).contains("1 pages"), "{}", text(&out.stderr));
    int(sim.id());
    sim.wait().unwrap();
}

/// Every text line of an SVG fits inside its width, at the widest the
/// 12 px sans-serif runs (`sim::svg::CHAR_PX` a character).
fn legend_fits(svg: &str) {
    let attr = |tag: &str, name: &str| -> f64 {
        let at = tag.find(&format!(" {name}=\"")).unwrap_or_else(|| panic!("no {name} in {tag}")) + name.len() + 3;
        tag[at..].split('"').next().unwrap().parse().unwrap()
    };
    let width = attr(svg.lines().next().unwrap(), "width");
    let mut texts = 0;
    for part in svg.split("<text").skip(1) {
        let (tag, rest) = part.split_once('>').unwrap();
        let content =
            rest.split("</text>").next().unwrap().replace("&amp;", "&").replace("&lt;", "<").replace("&gt;", ">");
        let end = attr(tag, "x") + paperbot::sim::svg::CHAR_PX * content.chars().count() as f64;
        assert!(end <= width, "{content:?} runs to {end:.0} px, past the picture's {width} px");
        texts += 1;
    }
    assert!(texts >= 4, "{texts} texts");
}
