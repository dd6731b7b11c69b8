//! Every example in docs/protocol.md, run on the real control loop on the
//! simulated robot: each `session` block on a fresh robot, each `> line`
//! sent as typed, and the lines the robot answers compared with the lines
//! the document shows after it (the rules are at the top of
//! docs/protocol.md). The document's telemetry header is the loop's, and
//! its example row reads back.

use paperbot::control::protocol::{parse_telemetry_row, telemetry_header};
use paperbot::sim::body::PoseF64;
use paperbot::sim::robot::{SimConfig, SimRobot};

const TICKS_PER_S: u32 = 1_000_000 / paperbot::control::TICK_US;
/// The longest a documented answer may take to come, s.
const ANSWER_WITHIN_S: u32 = 40;
/// After a block's last answer the robot must stay quiet this long, s.
const QUIET_S: u32 = 1;

/// One `> line` and the answer lines shown after it.
#[derive(Debug)]
struct Exchange {
    /// Line number in the document, for messages.
    at: usize,
    command: String,
    answers: Vec<String>,
}

/// The fenced blocks of `doc` whose info string is `lang`: each as its
/// first line's number and its lines.
fn blocks<'a>(doc: &'a str, lang: &str) -> Vec<(usize, Vec<&'a str>)> {
    let mut out = Vec::new();
    let mut current: Option<(usize, Vec<&str>)> = None;
    for (i, line) in doc.lines().enumerate() {
        match (&mut current, line.strip_prefix("```")) {
            (None, Some(info)) if info.trim() == lang => current = Some((i + 2, Vec::new())),
            (Some(_), Some("")) => out.extend(current.take()),
            (Some((_, lines)), _) => lines.push(line),
            (None, _) => {}
        }
    }
    assert!(current.is_none(), "an unclosed ```{lang} block");
    out
}

/// A session block's exchanges.
fn exchanges(first_line: usize, lines: &[&str]) -> Vec<Exchange> {
    let mut out: Vec<Exchange> = Vec::new();
    for (i, line) in lines.iter().enumerate() {
        if let Some(command) = line.strip_prefix('>') {
            let command = command.strip_prefix(' ').unwrap_or(command);
            out.push(Exchange { at: first_line + i, command: command.to_string(), answers: Vec::new() });
        } else {
            let ex = out.last_mut().unwrap_or_else(|| panic!("line {}: an answer before any `>`", first_line + i));
            ex.answers.push(line.to_string());
        }
    }
    out
}

/// Whether the robot's `got` is the documented `want`: the same line, or
/// for a `want` ending in `...` a line that starts with what precedes it.
fn matches(want: &str, got: &str) -> bool {
    match want.strip_suffix("...") {
        Some(prefix) => got.starts_with(prefix),
        None => got == want,
    }
}

/// The documented start: x 200 mm, y 250 mm, heading 0 (north), the pose
/// known, telemetry off, two seconds standing so the estimate settles.
fn robot() -> SimRobot {
    let cfg = SimConfig {
        start: PoseF64::new(200.0, 250.0, 0.0),
        seed: 1,
        locate_at_power_up: false,
        ..SimConfig::default()
    };
    let mut r = SimRobot::new(cfg);
    r.send("rate 0");
    for _ in 0..2 * TICKS_PER_S {
        r.tick();
    }
    r.take_output();
    r
}

/// Runs one session; returns the first difference.
fn run_session(exchanges: &[Exchange]) -> Result<(), String> {
    let mut r = robot();
    for ex in exchanges {
        r.send(&ex.command);
        let mut got = r.take_output();
        let mut ticks = 0;
        while got.len() < ex.answers.len() && ticks < ANSWER_WITHIN_S * TICKS_PER_S {
            r.tick();
            got.extend(r.take_output());
            ticks += 1;
        }
        let same = got.len() == ex.answers.len() && ex.answers.iter().zip(&got).all(|(w, g)| matches(w, g));
        if !same {
            return Err(format!(
                "line {}: `> {}`\n  documented: {:#?}\n  the robot:  {:#?}",
                ex.at, ex.command, ex.answers, got
            ));
        }
    }
    for _ in 0..QUIET_S * TICKS_PER_S {
        r.tick();
    }
    let late = r.take_output();
    match (late.is_empty(), exchanges.last()) {
        (false, Some(ex)) => Err(format!("line {}: after the block's last answer the robot went on: {late:#?}", ex.at)),
        _ => Ok(()),
    }
}

fn protocol_md() -> String {
    let path = format!("{}/docs/protocol.md", env!("CARGO_MANIFEST_DIR"));
    std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{path}: {e}"))
}

#[test]
fn every_session_in_the_protocol_document_gets_the_documented_answers() {
    let doc = protocol_md();
    let sessions = blocks(&doc, "session");
    assert!(sessions.len() >= 5, "docs/protocol.md has {} session blocks", sessions.len());
    let mut commands = 0;
    let mut failures = Vec::new();
    for (first_line, lines) in &sessions {
        let ex = exchanges(*first_line, lines);
        assert!(!ex.is_empty(), "line {first_line}: a session block without a `>` line");
        commands += ex.len();
        if let Err(e) = run_session(&ex) {
            failures.push(e);
        }
    }
    assert!(failures.is_empty(), "docs/protocol.md disagrees with the robot:\n{}", failures.join("\n"));
    println!("{} sessions, {commands} commands, as documented", sessions.len());
}

#[test]
fn the_documented_telemetry_header_is_the_loops_and_its_row_reads_back() {
    let doc = protocol_md();
    let csv = blocks(&doc, "csv");
    assert_eq!(csv.len(), 1, "one csv block");
    let lines = &csv[0].1;
    assert_eq!(lines[0], telemetry_header());
    assert!(lines.len() >= 2);
    for row in &lines[1..] {
        parse_telemetry_row(row).unwrap_or_else(|e| panic!("{row}: {e:?}"));
    }
}

#[test]
fn the_session_reader_sees_commands_answers_and_prefixes() {
    let doc = "text\n```session\n> fwd 0.13 1\n# ok fwd 0.130 1.000\n# done...\n>\n```\n```text\n> x\n```\n";
    let b = blocks(doc, "session");
    assert_eq!(b.len(), 1);
    let ex = exchanges(b[0].0, &b[0].1);
    assert_eq!(ex.len(), 2);
    assert_eq!((ex[0].at, ex[0].command.as_str(), ex[0].answers.len()), (3, "fwd 0.13 1", 2));
    assert_eq!((ex[1].command.as_str(), ex[1].answers.len()), ("", 0));
    assert!(matches("# done...", "# done at x_mm=1"));
    assert!(!matches("# done", "# done at x_mm=1"));
    assert!(!matches("# ok fwd 0.130", "# ok fwd 0.124"));
}
