//! Drive the paperbot from a laptop over its USB serial line: a terminal
//! UI with live telemetry, or a plain line mode for scripts; either one
//! records the session for the replay tool.
//!
//! ```text
//! cargo run --example teleop -- [PORT] [options]
//!   PORT             the robot's serial port, e.g. /dev/ttyUSB0 (default: the only USB serial port)
//!   --list           list the serial ports and exit
//!   --baud N         baud rate (default 115200, config::serial::BAUD)
//!   --record FILE    record the drive as a replay log (cargo run --example replay -- FILE)
//!   --raw FILE       also keep every line the robot sends (telemetry CSV and # lines)
//!   --rate HZ        telemetry rate to ask for (default 50 when recording, else 10; 0 = off)
//!   --lines FILE     line mode: send FILE's commands ('-' = stdin), print what comes back
//!   --linger S       line mode: listen S seconds after the last command (default 1)
//!   --no-keepalive   line mode: do not repeat untimed motions (the deadman cuts them)
//!   --mission FILE   upload FILE's mission steps (one per line, as after 'mission add')
//!   --start          start the robot's mission (after --mission), then unplug the cable
//!   --save           keep the robot's trims, calibration and mission in flash (after --mission)
//!   --log-hz HZ      with --start: the on-board log's rows per second (default: the robot's)
//!   --dump FILE      download the on-board log as telemetry CSV (with --record also as a replay log)
//!   --web [ADDR:PORT] serve a live map and drive pad to browsers instead of the terminal UI
//!                    (default 127.0.0.1:8080; 0.0.0.0:8080 lets a phone in; Ctrl-C quits)
//!   --arena LxW      with --web: the box drawn, mm (default config::arena)
//! ```
//! Keys: arrows / WASD drive, space stops, + / - speed level, k saves the settings, q quits.
// Host tool: a panic fails a command on the laptop, never the robot
// (the robot's lints, Cargo.toml).
#![allow(clippy::restriction)]

use std::fs::File;
use std::io::{self, BufWriter, IsTerminal, Read, Write};
use std::process::ExitCode;
use std::time::{Duration, Instant};

use paperbot::config;
use paperbot::host::teleop::{
    action, keys, link, mission, parse_plan, run_line_mode, Action, Dashboard, Driver, Key, LineModeOptions,
    LineReader, Panel, Recorder,
};
use paperbot::host::web::{self, server::is_loopback, WebOptions, WebServer};
use ratatui::crossterm::event::{self, Event, KeyCode, KeyEventKind, KeyModifiers};
use ratatui::layout::{Constraint, Layout};
use ratatui::widgets::{Block, Paragraph, Wrap};
use serialport::{SerialPort, SerialPortType};
use std::sync::atomic::AtomicBool;
use std::sync::Arc;

/// Read timeout of the port: the UI loop's pace when no key comes, ms.
const POLL_MS: u64 = 5;

#[derive(Default)]
struct Args {
    port: Option<String>,
    list: bool,
    baud: u32,
    record: Option<String>,
    raw: Option<String>,
    rate: Option<u16>,
    lines: Option<String>,
    linger_s: f64,
    keepalive: bool,
    mission: Option<String>,
    start: bool,
    save: bool,
    log_hz: Option<u16>,
    dump: Option<String>,
    web: Option<String>,
    arena: Option<(f64, f64)>,
}

fn parse_args() -> Result<Args, String> {
    let mut a = Args { baud: config::serial::BAUD, linger_s: 1.0, keepalive: true, ..Args::default() };
    let mut it = std::env::args().skip(1).peekable();
    while let Some(flag) = it.next() {
        let mut value = |name: &str| it.next().ok_or(format!("{name} needs a value"));
        match flag.as_str() {
            "--list" => a.list = true,
            "--baud" => a.baud = value("--baud")?.parse().map_err(|_| "--baud wants an integer")?,
            "--record" => a.record = Some(value("--record")?),
            "--raw" => a.raw = Some(value("--raw")?),
            "--rate" => a.rate = Some(value("--rate")?.parse().map_err(|_| "--rate wants 0..100")?),
            "--lines" => a.lines = Some(value("--lines")?),
            "--linger" => {
                a.linger_s = value("--linger")?.parse().map_err(|_| "--linger wants seconds")?;
                if !(0.0..=3600.0).contains(&a.linger_s) {
                    return Err("--linger wants 0..3600 s".into());
                }
            }
            "--no-keepalive" => a.keepalive = false,
            "--mission" => a.mission = Some(value("--mission")?),
            "--start" => a.start = true,
            "--save" => a.save = true,
            "--log-hz" => a.log_hz = Some(value("--log-hz")?.parse().map_err(|_| "--log-hz wants 0..100")?),
            "--dump" => a.dump = Some(value("--dump")?),
            // the address is optional: the next word is one if it has a ':' (a port's path has none)
            "--web" => {
                let addr = it.next_if(|v| v.contains(':') && !v.starts_with(['-', '/']));
                a.web = Some(addr.unwrap_or_else(|| config::teleop::WEB_ADDR.into()));
            }
            "--arena" => a.arena = Some(paperbot::host::args::arena(&value("--arena")?)?),
            f if f.starts_with('-') && f != "-" => return Err(format!("unknown option {f}")),
            p if a.port.is_none() => a.port = Some(p.to_string()),
            p => return Err(format!("one port only ({p}?)")),
        }
    }
    Ok(a)
}

fn usage() -> String {
    include_str!("teleop.rs")
        .lines()
        .skip(4)
        .take(21)
        .map(|l| l.strip_prefix("//! ").unwrap_or(l.trim_start_matches("//!")))
        .filter(|l| !l.starts_with("```"))
        .collect::<Vec<_>>()
        .join("\n")
}

/// USB serial chips of the usual ESP8266 boards.
fn board_hint(vid: u16, pid: u16) -> &'static str {
    match (vid, pid) {
        (0x10c4, 0xea60) => " (CP210x: NodeMCU?)",
        (0x1a86, 0x7523) => " (CH340: NodeMCU / Wemos?)",
        (0x0403, 0x6001) => " (FTDI)",
        _ => "",
    }
}

fn list_ports() -> Result<Vec<(String, bool)>, String> {
    let ports = serialport::available_ports().map_err(|e| format!("cannot list ports: {e}"))?;
    Ok(ports
        .into_iter()
        .map(|p| {
            let usb = matches!(p.port_type, SerialPortType::UsbPort(_));
            let desc = match &p.port_type {
                SerialPortType::UsbPort(u) => format!(
                    "{}  USB {:04x}:{:04x} {}{}",
                    p.port_name,
                    u.vid,
                    u.pid,
                    u.product.as_deref().unwrap_or(""),
                    board_hint(u.vid, u.pid)
                ),
                t => format!("{}  {t:?}", p.port_name),
            };
            (desc, usb)
        })
        .collect())
}

fn pick_port(args: &Args) -> Result<String, String> {
    if let Some(p) = &args.port {
        return Ok(p.clone());
    }
    let usb: Vec<String> = serialport::available_ports()
        .map_err(|e| format!("cannot list ports: {e}"))?
        .into_iter()
        .filter(|p| matches!(p.port_type, SerialPortType::UsbPort(_)))
        .map(|p| p.port_name)
        .collect();
    match usb.as_slice() {
        [one] => Ok(one.clone()),
        [] => Err("no USB serial port found: plug the robot in, or name the port (see --list)".into()),
        many => Err(format!("several USB serial ports ({}): name one", many.join(", "))),
    }
}

/// Writes to stdout and, if set, a raw log.
struct Tee<A: Write, B: Write>(A, Option<B>);

impl<A: Write, B: Write> Write for Tee<A, B> {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        self.0.write_all(buf)?;
        if let Some(b) = self.1.as_mut() {
            b.write_all(buf)?;
        }
        Ok(buf.len())
    }
    fn flush(&mut self) -> io::Result<()> {
        self.0.flush()?;
        self.1.as_mut().map_or(Ok(()), Write::flush)
    }
}

fn create(path: &str) -> Result<BufWriter<File>, String> {
    File::create(path).map(BufWriter::new).map_err(|e| format!("{path}: {e}"))
}

fn key_of(code: KeyCode, mods: KeyModifiers) -> Option<Key> {
    Some(match code {
        KeyCode::Up => Key::Up,
        KeyCode::Down => Key::Down,
        KeyCode::Left => Key::Left,
        KeyCode::Right => Key::Right,
        KeyCode::Esc => Key::Esc,
        KeyCode::Char('c') if mods.contains(KeyModifiers::CONTROL) => Key::CtrlC,
        KeyCode::Char(c) => Key::Char(c),
        _ => return None,
    })
}

fn draw(frame: &mut ratatui::Frame, panels: &[Panel], help: bool) {
    fn para(p: &Panel) -> Paragraph<'_> {
        Paragraph::new(p.lines.join("\n")).wrap(Wrap { trim: false }).block(Block::bordered().title(p.title.as_str()))
    }
    let height = |ps: &[&Panel]| ps.iter().map(|p| p.lines.len()).max().unwrap_or(1) as u16 + 2;
    let find = |t: &str| panels.iter().find(|p| p.title == t);
    let (Some(link), Some(pose), Some(sensors), Some(faults), Some(drive), Some(msgs)) =
        (find("link"), find("pose and motion"), find("sensors"), find("faults"), find("drive"), find("messages"))
    else {
        return;
    };
    let help_panel = Panel { title: "keys".into(), lines: keys::HELP.iter().map(|s| s.to_string()).collect() };
    let rows = Layout::vertical([
        Constraint::Length(height(&[pose, sensors])),
        Constraint::Length(height(&[link, faults])),
        Constraint::Length(height(&[drive])),
        Constraint::Min(3),
        Constraint::Length(if help { height(&[&help_panel]) } else { 0 }),
    ])
    .split(frame.area());
    let halves = |i: usize| Layout::horizontal([Constraint::Percentage(50), Constraint::Percentage(50)]).split(rows[i]);
    let top = halves(0);
    frame.render_widget(para(pose), top[0]);
    frame.render_widget(para(sensors), top[1]);
    let mid = halves(1);
    frame.render_widget(para(link), mid[0]);
    frame.render_widget(para(faults), mid[1]);
    frame.render_widget(para(drive), rows[2]);
    frame.render_widget(para(msgs), rows[3]);
    if help {
        frame.render_widget(para(&help_panel), rows[4]);
    }
}

/// The terminal UI until the user quits.
fn run_tui(
    port: &mut dyn SerialPort,
    recorder: &mut Option<Recorder<BufWriter<File>>>,
    raw: &mut Option<BufWriter<File>>,
    record_name: Option<&str>,
) -> io::Result<()> {
    let mut terminal = ratatui::init();
    let start = Instant::now();
    let now_ms = || start.elapsed().as_millis() as u64;
    let mut driver = Driver::from_config();
    let mut dash = Dashboard::new();
    let mut reader = LineReader::new();
    let mut help = true;
    let mut next_frame = 0u64;
    let result = (|| -> io::Result<()> {
        loop {
            while event::poll(Duration::ZERO)? {
                let Event::Key(k) = event::read()? else { continue };
                if k.kind == KeyEventKind::Release {
                    continue;
                }
                match key_of(k.code, k.modifiers).and_then(action) {
                    Some(Action::Drive(kind)) => driver.set(kind),
                    Some(Action::Faster) => {
                        driver.faster();
                    }
                    Some(Action::Slower) => {
                        driver.slower();
                    }
                    Some(Action::Locate) => link::send(port, keys::LOCATE_COMMAND)?,
                    Some(Action::Status) => link::send(port, "status")?,
                    Some(Action::Save) => link::send(port, mission::SAVE_COMMAND)?,
                    Some(Action::ToggleHelp) => help = !help,
                    Some(Action::Quit) => return Ok(()),
                    None => {}
                }
            }
            let now = now_ms();
            if let Some(cmd) = driver.poll(now) {
                link::send(port, &cmd)?;
            }
            take_lines(port, &mut reader, &mut dash, raw, recorder, now)?;
            if now >= next_frame {
                next_frame = now + u64::from(config::teleop::FRAME_MS);
                let rec = recorder
                    .as_ref()
                    .map(|r| format!("{}: {} rows ({} skipped)", record_name.unwrap_or("?"), r.rows(), r.skipped()));
                let panels = dash.panels(now, &driver, rec.as_deref());
                terminal.draw(|f| draw(f, &panels, help))?;
            }
        }
    })();
    // stop the robot whatever happened; its answer and the last rows go
    // into the logs too; then give the terminal back
    let stopped = link::send(port, "stop");
    let end = now_ms() + u64::from(config::teleop::REFRESH_MS);
    while stopped.is_ok() && now_ms() < end {
        if take_lines(port, &mut reader, &mut dash, raw, recorder, now_ms()).is_err() {
            break;
        }
    }
    ratatui::restore();
    result.and(stopped)
}

/// One read from the port: lines to the raw log, the screen and the recorder.
fn take_lines(
    port: &mut dyn SerialPort,
    reader: &mut LineReader,
    dash: &mut Dashboard,
    raw: &mut Option<BufWriter<File>>,
    recorder: &mut Option<Recorder<BufWriter<File>>>,
    now: u64,
) -> io::Result<()> {
    for line in reader.poll(port)? {
        if let Some(r) = raw.as_mut() {
            writeln!(r, "{line}")?;
        }
        if let Some(row) = dash.on_line(&line, now) {
            if let Some(rec) = recorder.as_mut() {
                rec.record(&row)?;
            }
        }
    }
    Ok(())
}

fn run() -> Result<(), String> {
    let args = parse_args()?;
    if args.list {
        for (desc, _) in list_ports()? {
            println!("{desc}");
        }
        return Ok(());
    }
    let plan = match &args.lines {
        None => None,
        Some(path) => {
            let mut text = String::new();
            let read = if path == "-" {
                io::stdin().read_to_string(&mut text).map(|_| ())
            } else {
                std::fs::read_to_string(path).map(|t| text = t)
            };
            read.map_err(|e| format!("{path}: {e}"))?;
            Some(parse_plan(&text).map_err(|e| format!("{path}: {e}"))?)
        }
    };
    let missions = args.mission.is_some() || args.start || args.dump.is_some() || args.save;
    let steps = match &args.mission {
        None => None,
        Some(path) => {
            let text = std::fs::read_to_string(path).map_err(|e| format!("{path}: {e}"))?;
            Some(mission::parse_mission_file(&text).map_err(|e| format!("{path}: {e}"))?)
        }
    };
    // bound before the port is opened: a port in use fails at once
    let web = args.web.as_deref().map(WebServer::bind).transpose()?;
    if web.is_some() && (plan.is_some() || missions) {
        return Err("--web drives from the page: not with --lines, --mission, --start, --save or --dump".into());
    }
    if web.is_none() && plan.is_none() && !missions && !(io::stdout().is_terminal() && io::stdin().is_terminal()) {
        return Err("not a terminal: use --lines FILE (or '-' for stdin) for the line mode".into());
    }
    let port_name = pick_port(&args)?;
    let mut port = serialport::new(&port_name, args.baud)
        .timeout(Duration::from_millis(POLL_MS))
        .open()
        .map_err(|e| format!("{port_name}: {e}"))?;
    // what the robot sent before we listened (boot text, old rows) is stale
    let _ = port.clear(serialport::ClearBuffer::Input);
    let mut recorder = match &args.record {
        None => None,
        Some(path) => Some(Recorder::new(create(path)?).map_err(|e| format!("{path}: {e}"))?),
    };
    let mut raw = args.raw.as_deref().map(create).transpose()?;
    // telemetry is restarted (so its header comes again) at the chosen rate
    let rate = args.rate.unwrap_or(if recorder.is_some() {
        config::teleop::RECORD_TELEMETRY_HZ
    } else {
        config::timing::TELEMETRY_HZ as u16
    });

    if let Some(server) = web {
        let arena = args.arena.unwrap_or(WebOptions::default().arena);
        run_web(&mut *port, server, WebOptions { rate_hz: Some(rate), arena }, &mut recorder, &mut raw)
            .map_err(|e| format!("{port_name}: {e}"))?;
    } else if missions {
        return run_missions(&args, steps, &mut *port, &port_name, recorder.as_mut());
    } else {
        match plan {
            Some(plan) => {
                let opts = LineModeOptions {
                    linger_ms: (args.linger_s * 1000.0) as u64,
                    keepalive: args.keepalive,
                    rate_hz: Some(rate),
                    ..LineModeOptions::default()
                };
                let mut out = Tee(io::stdout().lock(), raw.take());
                let report = run_line_mode(&mut *port, plan, opts, &mut out, recorder.as_mut())
                    .map_err(|e| format!("{port_name}: {e}"))?;
                eprintln!(
                    "teleop: sent {} lines and {} keep-alive repeats; {} telemetry rows, {} refused",
                    report.sent, report.refreshes, report.rows, report.errors
                );
            }
            None => {
                link::start_telemetry(&mut *port, rate).map_err(|e| format!("{port_name}: {e}"))?;
                run_tui(&mut *port, &mut recorder, &mut raw, args.record.as_deref())
                    .map_err(|e| format!("{port_name}: {e}"))?;
            }
        }
    }
    if let (Some(rec), Some(path)) = (&recorder, &args.record) {
        eprintln!("teleop: {} rows recorded in {path} ({} skipped: time went back)", rec.rows(), rec.skipped());
        if let Some(start) = rec.replay_start() {
            eprintln!("teleop: replay it with `cargo run --example replay -- {path} --start {start}`");
        }
    }
    Ok(())
}

/// `--web`: serves the page until Ctrl-C (or `kill`); the robot is stopped then.
fn run_web(
    port: &mut dyn SerialPort,
    server: WebServer,
    opts: WebOptions,
    recorder: &mut Option<Recorder<BufWriter<File>>>,
    raw: &mut Option<BufWriter<File>>,
) -> io::Result<()> {
    let addr = server.local_addr();
    if !is_loopback(&addr) {
        eprintln!(
            "teleop: WARNING: serving on {addr}, not only this machine: anyone who can reach this port \
             can watch AND DRIVE the robot (use 127.0.0.1 to keep it to this laptop)"
        );
    }
    let shown =
        if addr.ip().is_unspecified() { format!("<this machine's address>:{}", addr.port()) } else { addr.to_string() };
    eprintln!("teleop: open http://{shown}/ in a browser; Ctrl-C stops the robot and quits");
    let stop = Arc::new(AtomicBool::new(false));
    for signal in [signal_hook::consts::SIGINT, signal_hook::consts::SIGTERM] {
        signal_hook::flag::register(signal, Arc::clone(&stop))?;
    }
    let report = web::run(port, server, opts, &stop, |line, row| {
        if let Some(r) = raw.as_mut() {
            writeln!(r, "{line}")?;
        }
        if let (Some(rec), Some(row)) = (recorder.as_mut(), row) {
            rec.record(row)?;
        }
        Ok(())
    })?;
    eprintln!(
        "teleop: {} pages, {} rows, {} commands sent, {} messages dropped for slow pages",
        report.pages, report.rows, report.sent, report.dropped
    );
    Ok(())
}

/// `--mission`, `--save`, `--start`, `--dump`: upload, save, start,
/// download, in that order (each optional), printing what the robot
/// answers.
fn run_missions(
    args: &Args,
    steps: Option<Vec<String>>,
    port: &mut dyn SerialPort,
    port_name: &str,
    recorder: Option<&mut Recorder<BufWriter<File>>>,
) -> Result<(), String> {
    let io_err = |e: io::Error| format!("{port_name}: {e}");
    let mut out = io::stdout().lock();
    if let Some(steps) = steps {
        mission::upload(port, &steps, &mut out).map_err(io_err)??;
        eprintln!(
            "teleop: mission of {} steps uploaded (kept on the robot across a reset; --save keeps it after a power-off)",
            steps.len()
        );
    }
    if args.save {
        let saved = mission::save(port, &mut out).map_err(io_err)??;
        eprintln!("teleop: {}: kept after a power-off", saved.trim_start_matches("# "));
    }
    if args.start {
        mission::start(port, args.log_hz, &mut out).map_err(io_err)??;
        eprintln!("teleop: mission started: unplug the cable now (any byte after the countdown aborts it);");
        eprintln!("teleop: afterwards plug it in again and download the log with --dump FILE");
        return Ok(());
    }
    if let Some(path) = &args.dump {
        let mut csv = create(path)?;
        let got = mission::download(port, &mut csv, recorder).map_err(io_err)??;
        eprintln!("teleop: {}; {} rows written to {path}", got.summary.trim_start_matches("# "), got.rows);
    }
    Ok(())
}

fn main() -> ExitCode {
    if std::env::args().skip(1).any(|a| a == "-h" || a == "--help") {
        println!("{}", usage());
        return ExitCode::SUCCESS;
    }
    if let Err(e) = parse_args() {
        eprintln!("teleop: {e}\n{}", usage());
        return ExitCode::from(2);
    }
    match run() {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("teleop: {e}");
            ExitCode::FAILURE
        }
    }
}
