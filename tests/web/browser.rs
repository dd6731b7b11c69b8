//! End to end in a real browser: the simulated robot served on a PTY as
//! `sim_pty --truth-hz 50` serves it, `teleop --web`'s loop on that PTY
//! (`host::web::run`, what the example calls), and Debian's headless
//! Chromium driven through its DevTools protocol (over tungstenite):
//! - the page loads, is the pilot, and draws the robot where the simulator
//!   has it (the drawn SVG transform, read back, within 3 mm and 3 degrees);
//! - a row listing hypotheses (none yet from the estimator) draws them;
//! - its "locate" button has the robot find its pose, and the page draws
//!   the fix's uncertainty ellipse;
//! - a press on the page's "forward" button moves the simulated robot;
//! - closing the tab while the button is held stops the robot within the
//!   500 ms deadman (the true pose stops changing);
//! - in a second tab (it drives: nobody did), a held arrow key turns the
//!   robot and letting go stops it, a finger held on "backward" backs it,
//!   and killing the browser with the finger down stops it in time too;
//! - a screenshot is saved (target/web-e2e.png; docs/web.png is one).
//!
//! Needs `chromium` (apt-get install chromium); without it the test says
//! so loudly and passes, unless PAPERBOT_REQUIRE_CHROMIUM is set (CI sets it).

use std::io::{BufRead, BufReader};
use std::net::TcpStream;
use std::process::{Child, Command, Stdio};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use paperbot::config;
use paperbot::host::web::{self, WebOptions, WebServer};
use paperbot::sim::body::PoseF64;
use paperbot::sim::robot::{Noise, SimConfig, SimRobot};
use paperbot::sim::serve::Server;
use serde_json::{json, Value};
use serialport::{SerialPort, TTYPort};
use tungstenite::stream::MaybeTlsStream;
use tungstenite::{Message, WebSocket};

type Ws = WebSocket<MaybeTlsStream<TcpStream>>;

/// A DevTools protocol connection to the browser, attached to one page.
struct Cdp {
    ws: Ws,
    next: u64,
    session: Option<String>,
}

impl Cdp {
    fn call(&mut self, method: &str, params: Value) -> Value {
        self.next += 1;
        let id = self.next;
        let mut msg = json!({ "id": id, "method": method, "params": params });
        if let Some(s) = &self.session {
            msg["sessionId"] = json!(s);
        }
        self.ws.send(Message::text(msg.to_string())).expect("send to chromium");
        loop {
            let m = self.ws.read().unwrap_or_else(|e| panic!("{method}: no answer from chromium: {e}"));
            let Ok(text) = m.into_text() else { continue };
            let v: Value = serde_json::from_str(text.as_str()).expect("chromium sends JSON");
            if v["id"] == json!(id) {
                assert!(v.get("error").is_none(), "{method}: {}", v["error"]);
                return v["result"].clone();
            }
        }
    }

    /// Evaluates `expr` in the page, returns its value.
    fn eval(&mut self, expr: &str) -> Value {
        let r = self.call("Runtime.evaluate", json!({ "expression": expr, "returnByValue": true }));
        assert!(r.get("exceptionDetails").is_none(), "{expr}: {}", r["exceptionDetails"]);
        r["result"]["value"].clone()
    }

    /// Opens `url` in a new tab and attaches to it; returns the tab's id.
    fn open(&mut self, url: &str) -> Value {
        self.session = None;
        let target = self.call("Target.createTarget", json!({ "url": "about:blank" }))["targetId"].clone();
        let session =
            self.call("Target.attachToTarget", json!({ "targetId": target, "flatten": true }))["sessionId"].clone();
        self.session = session.as_str().map(String::from);
        self.call(
            "Emulation.setDeviceMetricsOverride",
            json!({ "width": 1280, "height": 800, "deviceScaleFactor": 1, "mobile": false }),
        );
        // a headless tab has no window focus: keys need it emulated
        self.call("Emulation.setFocusEmulationEnabled", json!({ "enabled": true }));
        self.call("Emulation.setTouchEmulationEnabled", json!({ "enabled": true, "maxTouchPoints": 1 }));
        self.call("Page.navigate", json!({ "url": url }));
        target
    }

    /// The centre of the element with id `id`, CSS px.
    fn centre(&mut self, id: &str) -> (f64, f64) {
        let r = self.eval(&format!(
            "(() => {{ const r = document.getElementById('{id}').getBoundingClientRect(); \
             return [r.x + r.width / 2, r.y + r.height / 2]; }})()"
        ));
        (r[0].as_f64().unwrap(), r[1].as_f64().unwrap())
    }

    fn key(&mut self, kind: &str, key: &str, code: u32) {
        self.call(
            "Input.dispatchKeyEvent",
            json!({ "type": kind, "key": key, "code": key, "windowsVirtualKeyCode": code }),
        );
    }

    fn mouse(&mut self, kind: &str, x: f64, y: f64) {
        self.call(
            "Input.dispatchMouseEvent",
            json!({ "type": kind, "x": x, "y": y, "button": "left", "buttons": 1, "clickCount": 1 }),
        );
    }
}

/// The true poses the page's server relays (`truth` messages), with when
/// they arrived; read by a second page (a watcher) on its own thread.
type Truths = Arc<Mutex<Vec<(Instant, PoseF64)>>>;

fn watch_truth(url: &str, stop: Arc<AtomicBool>) -> Truths {
    let truths: Truths = Arc::default();
    let (mut ws, _) = tungstenite::connect(url).expect("the watcher connects");
    if let MaybeTlsStream::Plain(s) = ws.get_mut() {
        s.set_read_timeout(Some(Duration::from_millis(50))).unwrap();
    }
    let t = Arc::clone(&truths);
    std::thread::spawn(move || {
        while !stop.load(Ordering::Relaxed) {
            let Ok(Message::Text(text)) = ws.read() else { continue };
            let v: Value = serde_json::from_str(text.as_str()).unwrap();
            if v["type"] == "hello" {
                assert_eq!(v["role"], "viewer", "the watcher connects second: it only watches");
            }
            if v["type"] == "truth" {
                let p = &v["pose"];
                let pose = PoseF64::new(
                    p["x"].as_f64().unwrap(),
                    p["y"].as_f64().unwrap(),
                    p["heading"].as_f64().unwrap().to_radians(),
                );
                t.lock().unwrap().push((Instant::now(), pose));
            }
        }
    });
    truths
}

fn latest(t: &Truths) -> PoseF64 {
    t.lock().unwrap().last().expect("truth lines arrive").1
}

fn chromium() -> Option<String> {
    ["chromium", "chromium-browser", "google-chrome"].into_iter().map(String::from).find(|c| {
        Command::new(c).arg("--version").stdout(Stdio::null()).stderr(Stdio::null()).status().is_ok_and(|s| s.success())
    })
}

/// Starts headless Chromium with an empty profile; returns it and its DevTools URL.
fn start_chromium(bin: &str, profile: &std::path::Path) -> (Child, String) {
    let mut child = Command::new(bin)
        .args([
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--disable-quic",
            "--no-first-run",
            "--disable-background-networking",
            "--disable-component-update",
            "--disable-sync",
            "--remote-debugging-port=0",
            "--window-size=1280,800",
        ])
        .arg(format!("--user-data-dir={}", profile.display()))
        .arg("about:blank")
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("chromium starts");
    let mut lines = BufReader::new(child.stderr.take().unwrap()).lines();
    let url = loop {
        let line = lines.next().expect("chromium says where DevTools listen").unwrap();
        if let Some(u) = line.strip_prefix("DevTools listening on ") {
            break u.trim().to_string();
        }
    };
    // keep draining its stderr so it never blocks on a full pipe
    std::thread::spawn(move || lines.for_each(drop));
    (child, url)
}

/// The robot's drawn pose, from the SVG transform of `#robot`:
/// `translate(y_mm, L - x_mm) rotate(heading_deg)`.
fn drawn_pose(cdp: &mut Cdp, length_x: f64) -> Option<PoseF64> {
    let t = cdp.eval("document.getElementById('robot')?.getAttribute('transform') ?? null");
    let t = t.as_str()?;
    let nums: Vec<f64> = t
        .split(|c: char| !(c.is_ascii_digit() || c == '.' || c == '-'))
        .filter(|s| !s.is_empty())
        .map(|s| s.parse().unwrap())
        .collect();
    let [sx, sy, deg] = nums[..] else { panic!("transform {t:?}") };
    Some(PoseF64::new(length_x - sy, sx, deg.to_radians()))
}

fn wait_for<T>(what: &str, ms: u64, mut f: impl FnMut() -> Option<T>) -> T {
    let start = Instant::now();
    loop {
        if let Some(v) = f() {
            return v;
        }
        assert!(start.elapsed() < Duration::from_millis(ms), "timed out waiting for {what}");
        std::thread::sleep(Duration::from_millis(50));
    }
}

#[test]
fn the_page_draws_drives_and_a_closed_tab_stops_the_robot() {
    let Some(bin) = chromium() else {
        let msg = "\n\n!!!!! tests/web/browser.rs SKIPPED: no chromium (apt-get install chromium) !!!!!\n\n";
        assert!(std::env::var_os("PAPERBOT_REQUIRE_CHROMIUM").is_none(), "{msg}");
        eprintln!("{msg}");
        return;
    };
    // the simulator on a PTY, as sim_pty --no-noise --truth-hz 50 serves it
    let start = PoseF64::new(380.0, 120.0, 0.0);
    let cfg = SimConfig { noise: Noise::OFF, locate_at_power_up: false, start, ..SimConfig::default() };
    let (mut master, slave) = TTYPort::pair().expect("a pseudo-terminal");
    master.set_timeout(Duration::ZERO).unwrap();
    let path = slave.name().unwrap();
    let stop = Arc::new(AtomicBool::new(false));
    let sim_stop = Arc::clone(&stop);
    let sim = std::thread::spawn(move || {
        let mut server = Server::new(SimRobot::new(cfg)).with_truth(50);
        server.run(&mut master, &sim_stop).expect("the simulator runs");
        drop(slave);
    });
    // teleop --web on it
    let server = WebServer::bind("127.0.0.1:0").unwrap();
    let addr = server.local_addr();
    // the tool stops first (its last word to the robot is `stop`), then the simulator
    let tool_stop = Arc::new(AtomicBool::new(false));
    let web_stop = Arc::clone(&tool_stop);
    let tool = std::thread::spawn(move || {
        let mut port = serialport::new(&path, config::serial::BAUD).timeout(Duration::from_millis(5)).open().unwrap();
        web::run(&mut *port, server, WebOptions::default(), &web_stop, |_, _| Ok(())).expect("teleop --web runs")
    });
    let length_x = WebOptions::default().arena.0;

    let profile = std::env::temp_dir().join(format!("paperbot-chromium-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&profile);
    let (mut browser, devtools) = start_chromium(&bin, &profile);
    let (ws, _) = tungstenite::connect(&devtools).expect("DevTools connect");
    let mut cdp = Cdp { ws, next: 0, session: None };
    let target = cdp.open(&format!("http://{addr}/"));

    // the page loads, drives, and draws the robot where the simulator has it
    wait_for("the robot drawn", 10_000, || drawn_pose(&mut cdp, length_x));
    assert_eq!(cdp.eval("document.body.className"), "pilot", "the first page drives");
    let truths = watch_truth(&format!("ws://{addr}/ws"), Arc::clone(&stop));
    std::thread::sleep(Duration::from_millis(600));
    let (drawn, truth) = (drawn_pose(&mut cdp, length_x).unwrap(), latest(&truths));
    println!("standing: drawn {drawn:?}, simulator {truth:?}");
    assert!(drawn.distance(&truth) < 3.0, "drawn {drawn:?} vs simulator {truth:?}");
    // the heading is the estimate's: the lab world's compass disturbance
    // (a couple of degrees, config::sim) pulls it off the truth a little
    assert!(drawn.heading_error(&truth).abs() < 3f64.to_radians(), "drawn {drawn:?} vs simulator {truth:?}");

    // room for the estimator's hypotheses: a row that lists two draws two ghosts
    let ghosts = cdp.eval(
        "(() => { const r = structuredClone(state.row); r.estimate.hypotheses = [\
         { x: 300, y: 200, heading: 90, sigma: { x: 10, y: 20 }, weight: 0.6 },\
         { x: 500, y: 300, heading: 180, sigma: null, weight: 0.3 }]; onRow(r); \
         return [document.querySelectorAll('#hypotheses > g').length, \
                 document.querySelectorAll('#hypotheses > ellipse').length]; })()",
    );
    assert_eq!(ghosts, json!([2, 1]), "two ghost bodies, one with its ellipse");

    // "locate": the robot turns in place, finds its pose and reports its
    // sigma, which the page draws as an ellipse
    let located = Instant::now();
    cdp.eval("document.getElementById('locate').click()");
    wait_for("the fix's ellipse", 30_000, || {
        (cdp.eval("document.querySelectorAll('#sigma ellipse').length") == 1).then_some(())
    });
    let text = cdp.eval("document.getElementById('messages').textContent");
    println!("located in {} ms: {}", located.elapsed().as_millis(), text.as_str().unwrap().replace('\n', " | "));
    assert!(text.as_str().unwrap().contains("# located "), "{text}");
    std::thread::sleep(Duration::from_millis(300));
    let truth = latest(&truths);

    // a press on "forward" (held) moves the simulated robot
    let (bx, by) = cdp.centre("btn-fwd");
    cdp.mouse("mouseMoved", bx, by);
    cdp.mouse("mousePressed", bx, by);
    std::thread::sleep(Duration::from_millis(1000));
    let moved = latest(&truths);
    println!("after 1 s of forward: simulator {moved:?}");
    let ahead = (moved.x - truth.x) * truth.theta.cos() + (moved.y - truth.y) * truth.theta.sin();
    assert!(ahead > 80.0, "forward moved the robot ahead: {truth:?} -> {moved:?}");
    let drawn = drawn_pose(&mut cdp, length_x).unwrap();
    // while moving at ~0.14 m/s the drawing lags the truth by a row (10 Hz:
    // 14 mm) and the link's latency (more on a loaded machine)
    assert!(drawn.distance(&moved) < 45.0, "drawn {drawn:?} follows {moved:?}");
    let shot = cdp.call("Page.captureScreenshot", json!({ "format": "png" }));
    let png = data_encoding::BASE64.decode(shot["data"].as_str().unwrap().as_bytes()).unwrap();
    let out = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("target/web-e2e.png");
    std::fs::write(&out, png).unwrap();
    println!("screenshot: {}", out.display());

    // closing the tab with the button still held stops the robot in time
    cdp.session = None;
    // (still moving then: the wall ahead is not what stops it)
    let closed = Instant::now();
    let recent = truths.lock().unwrap().iter().rev().take(5).map(|(_, p)| *p).collect::<Vec<_>>();
    assert!(recent[0].distance(&recent[4]) > 5.0, "moving when the tab closes: {recent:?}");
    cdp.call("Target.closeTarget", json!({ "targetId": target }));
    std::thread::sleep(Duration::from_millis(1500));
    let (took, last) = still_since(&truths, closed);
    println!("closed the tab: the robot stood still {} ms later", took.as_millis());
    assert!(last.distance(&moved) > 0.0, "it kept going until the tab closed");
    assert!(
        took < Duration::from_millis(u64::from(config::timing::DEADMAN_MS)),
        "stopped {} ms after the tab closed",
        took.as_millis()
    );
    assert!(closed.elapsed() - took > Duration::from_millis(800), "and stays still");

    // a new tab: nobody drives (the watcher does not start by itself), so it drives
    let _second = cdp.open(&format!("http://{addr}/"));
    wait_for("the second tab's robot", 10_000, || drawn_pose(&mut cdp, length_x));
    assert_eq!(cdp.eval("document.body.className"), "pilot");
    // keys: the left arrow held turns the robot counter-clockwise; let go, it stops
    let before = latest(&truths);
    cdp.key("keyDown", "ArrowLeft", 37);
    std::thread::sleep(Duration::from_millis(400));
    cdp.key("keyUp", "ArrowLeft", 37);
    std::thread::sleep(Duration::from_millis(300));
    let turned = latest(&truths);
    println!("left arrow for 0.4 s: heading {:.1} -> {:.1} deg", before.theta.to_degrees(), turned.theta.to_degrees());
    assert!(turned.heading_error(&before) < -20f64.to_radians(), "turned counter-clockwise");
    std::thread::sleep(Duration::from_millis(200));
    assert!(latest(&truths).distance(&turned) < 0.05, "and stopped when the key came up");
    // touch: a finger held on "backward" drives it backwards
    let (bx, by) = cdp.centre("btn-back");
    cdp.call("Input.dispatchTouchEvent", json!({ "type": "touchStart", "touchPoints": [{ "x": bx, "y": by }] }));
    std::thread::sleep(Duration::from_millis(800));
    let backed = latest(&truths);
    let behind = (turned.x - backed.x) * turned.theta.cos() + (turned.y - backed.y) * turned.theta.sin();
    println!("touch on backward for 0.8 s: {behind:.0} mm back");
    assert!(behind > 50.0, "{turned:?} -> {backed:?}");
    // a dead browser (killed while the finger is down) stops the robot too
    let killed = Instant::now();
    let recent = truths.lock().unwrap().iter().rev().take(5).map(|(_, p)| *p).collect::<Vec<_>>();
    assert!(recent[0].distance(&recent[4]) > 5.0, "moving when the browser dies: {recent:?}");
    let _ = browser.kill();
    let _ = browser.wait();
    std::thread::sleep(Duration::from_millis(1500));
    let (took, _) = still_since(&truths, killed);
    println!("killed the browser: the robot stood still {} ms later", took.as_millis());
    assert!(took < Duration::from_millis(u64::from(config::timing::DEADMAN_MS)), "{} ms", took.as_millis());

    tool_stop.store(true, Ordering::Relaxed);
    let report = tool.join().unwrap();
    stop.store(true, Ordering::Relaxed);
    sim.join().unwrap();
    let _ = std::fs::remove_dir_all(&profile);
    assert_eq!(report.pages, 3, "two tabs and the watcher");
}

/// How long after `from` the true pose stopped changing for good, and the last pose.
fn still_since(truths: &Truths, from: Instant) -> (Duration, PoseF64) {
    let t = truths.lock().unwrap().clone();
    let last = t.last().unwrap().1;
    let still_from = t.iter().rev().take_while(|(_, p)| p.distance(&last) < 0.05).last().unwrap().0;
    (still_from.saturating_duration_since(from), last)
}
