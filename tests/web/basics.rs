//! `teleop --web`'s server over real sockets, with a fake robot port that
//! records what the tool sends: the files (and only they) are served, a
//! port in use is a clear error, a second page watches and may take over
//! (the first is told), any page stops the robot, malformed messages close that page's connection
//! with the reason and change nothing, and a held motion runs out when
//! the pilot stops repeating it (a sleeping phone) or leaves (a closed tab).

use std::io::{self, Read, Write};
use std::net::{TcpListener, TcpStream};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use paperbot::config::teleop::{REFRESH_MS, WEB_HOLD_MS};
use paperbot::config::timing::DEADMAN_MS;
use paperbot::host::web::server::FILES;
use paperbot::host::web::{self, WebOptions, WebReport, WebServer};
use serde_json::Value;
use tungstenite::protocol::frame::coding::CloseCode;
use tungstenite::stream::MaybeTlsStream;
use tungstenite::{Message, WebSocket};

/// The robot's side: records each line the tool sends, with when; sends nothing.
#[derive(Clone, Default)]
struct FakePort {
    sent: Arc<Mutex<Vec<(Instant, String)>>>,
    partial: Vec<u8>,
}

impl Read for FakePort {
    fn read(&mut self, _: &mut [u8]) -> io::Result<usize> {
        std::thread::sleep(Duration::from_millis(2));
        Err(io::ErrorKind::TimedOut.into())
    }
}

impl Write for FakePort {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        for &b in buf {
            if b == b'\n' {
                let line = String::from_utf8(std::mem::take(&mut self.partial)).unwrap();
                self.sent.lock().unwrap().push((Instant::now(), line));
            } else {
                self.partial.push(b);
            }
        }
        Ok(buf.len())
    }
    fn flush(&mut self) -> io::Result<()> {
        Ok(())
    }
}

struct Tool {
    addr: String,
    sent: Arc<Mutex<Vec<(Instant, String)>>>,
    stop: Arc<AtomicBool>,
    thread: JoinHandle<WebReport>,
}

impl Tool {
    fn start() -> Tool {
        let server = WebServer::bind("127.0.0.1:0").unwrap();
        let addr = server.local_addr().to_string();
        let port = FakePort::default();
        let sent = Arc::clone(&port.sent);
        let stop = Arc::new(AtomicBool::new(false));
        let s = Arc::clone(&stop);
        let opts = WebOptions { rate_hz: None, ..WebOptions::default() };
        let thread = std::thread::spawn(move || {
            let mut port = port;
            web::run(&mut port, server, opts, &s, |_, _| Ok(())).unwrap()
        });
        Tool { addr, sent, stop, thread }
    }
    /// The lines sent since `from`.
    fn sent_since(&self, from: Instant) -> Vec<String> {
        self.sent.lock().unwrap().iter().filter(|(t, _)| *t >= from).map(|(_, l)| l.clone()).collect()
    }
    fn finish(self) -> (WebReport, Vec<String>) {
        self.stop.store(true, Ordering::Relaxed);
        let report = self.thread.join().unwrap();
        let sent = self.sent.lock().unwrap().iter().map(|(_, l)| l.clone()).collect();
        (report, sent)
    }
}

type Ws = WebSocket<MaybeTlsStream<TcpStream>>;

fn page(addr: &str) -> Ws {
    let (mut ws, _) = tungstenite::connect(format!("ws://{addr}/ws")).unwrap();
    if let MaybeTlsStream::Plain(s) = ws.get_mut() {
        s.set_read_timeout(Some(Duration::from_millis(20))).unwrap();
    }
    ws
}

/// The page's messages for `ms`, parsed; the close frame, if one came.
fn messages(ws: &mut Ws, ms: u64) -> (Vec<Value>, Option<(CloseCode, String)>) {
    let until = Instant::now() + Duration::from_millis(ms);
    let mut out = Vec::new();
    while Instant::now() < until {
        match ws.read() {
            Ok(Message::Text(t)) => out.push(serde_json::from_str(t.as_str()).unwrap()),
            Ok(Message::Close(Some(f))) => return (out, Some((f.code, f.reason.to_string()))),
            Ok(_) => {}
            Err(tungstenite::Error::Io(e)) if e.kind() == io::ErrorKind::WouldBlock => {}
            Err(tungstenite::Error::ConnectionClosed | tungstenite::Error::AlreadyClosed) => break,
            Err(e) => panic!("{e}"),
        }
    }
    (out, None)
}

fn send(ws: &mut Ws, text: &str) {
    ws.send(Message::text(text)).unwrap();
}

fn of_type<'a>(msgs: &'a [Value], t: &str) -> Vec<&'a Value> {
    msgs.iter().filter(|m| m["type"] == t).collect()
}

fn get(addr: &str, request: &str) -> String {
    let mut s = TcpStream::connect(addr).unwrap();
    s.write_all(request.as_bytes()).unwrap();
    let mut out = String::new();
    s.read_to_string(&mut out).unwrap();
    out
}

#[test]
fn the_page_is_served_from_the_tool_alone() {
    let tool = Tool::start();
    let index = get(&tool.addr, "GET / HTTP/1.1\r\nHost: x\r\n\r\n");
    assert!(index.starts_with("HTTP/1.1 200"), "{index}");
    // everything the page loads is one of the tool's own files: no CDN
    let (_, _, html) = FILES[0];
    let links: Vec<&str> = ["src=\"", "href=\""]
        .iter()
        .flat_map(|attr| html.split(attr).skip(1).map(|rest| rest.split('"').next().unwrap()))
        .collect();
    assert_eq!(links, ["/app.js", "/style.css"]);
    assert!(links.iter().all(|l| FILES.iter().any(|(p, _, _)| p == l)));
    for (path, ctype, body) in FILES {
        let r = get(&tool.addr, &format!("GET {path} HTTP/1.1\r\nHost: x\r\n\r\n"));
        assert!(r.starts_with("HTTP/1.1 200") && r.contains(ctype) && r.ends_with(body), "{path}");
    }
    assert!(get(&tool.addr, "GET /x.js HTTP/1.1\r\nHost: x\r\n\r\n").starts_with("HTTP/1.1 404"));
    assert!(get(&tool.addr, "POST / HTTP/1.1\r\nHost: x\r\nContent-Length: 0\r\n\r\n").starts_with("HTTP/1.1 405"));
    tool.finish();
}

#[test]
fn another_sites_page_cannot_open_the_websocket() {
    use tungstenite::client::IntoClientRequest;
    let tool = Tool::start();
    let url = format!("ws://{}/ws", tool.addr);
    let with_origin = |origin: &str| {
        let mut req = url.as_str().into_client_request().unwrap();
        req.headers_mut().insert("Origin", origin.parse().unwrap());
        tungstenite::connect(req)
    };
    match with_origin("http://evil.example") {
        Err(tungstenite::Error::Http(r)) => assert_eq!(r.status(), 403),
        other => panic!("another site's page got in: {:?}", other.map(|_| ())),
    }
    let (mut own, _) = with_origin(&format!("http://{}", tool.addr)).expect("the page's own origin gets in");
    let Ok(Message::Text(hello)) = own.read() else { panic!("no hello") };
    assert!(hello.contains("\"pilot\""), "{hello}");
    let (report, _) = tool.finish();
    assert_eq!(report.pages, 1);
}

#[test]
fn a_port_in_use_is_a_clear_error() {
    let taken = TcpListener::bind("127.0.0.1:0").unwrap();
    let addr = taken.local_addr().unwrap().to_string();
    let e = WebServer::bind(&addr).err().expect("a second bind fails");
    assert!(e.contains(&addr) && e.contains("in use") && e.contains("--web"), "{e}");
    assert!(WebServer::bind("not-an-address").is_err());
}

#[test]
fn a_second_page_watches_until_it_takes_over() {
    let tool = Tool::start();
    let mut a = page(&tool.addr);
    let (msgs, _) = messages(&mut a, 100);
    assert_eq!(of_type(&msgs, "hello")[0]["role"], "pilot");
    let mut b = page(&tool.addr);
    let (msgs, _) = messages(&mut b, 100);
    assert_eq!(of_type(&msgs, "hello")[0]["role"], "viewer");
    assert!(of_type(&msgs, "notice")[0]["text"].as_str().unwrap().contains("watches"));
    // the watcher cannot drive: it is told so, and nothing is sent
    let t0 = Instant::now();
    send(&mut b, r#"{"cmd":"hold","motion":"fwd"}"#);
    let (msgs, _) = messages(&mut b, 150);
    assert!(of_type(&msgs, "notice")[0]["text"].as_str().unwrap().contains("take over"));
    assert!(!tool.sent_since(t0).iter().any(|l| l.starts_with("fwd")), "{:?}", tool.sent_since(t0));
    // the pilot drives
    send(&mut a, r#"{"cmd":"hold","motion":"fwd"}"#);
    messages(&mut a, 150);
    assert!(tool.sent_since(t0).iter().any(|l| l.starts_with("fwd ")), "{:?}", tool.sent_since(t0));
    // the watcher takes over while the pilot holds: the robot stops, the old pilot is told
    send(&mut a, r#"{"cmd":"hold","motion":"fwd"}"#);
    let t1 = Instant::now();
    send(&mut b, r#"{"cmd":"take"}"#);
    let (msgs, _) = messages(&mut a, 100);
    assert!(of_type(&msgs, "notice")[0]["text"].as_str().unwrap().contains("took over"));
    assert_eq!(of_type(&msgs, "state").last().unwrap()["role"], "viewer");
    let (msgs, _) = messages(&mut b, 250);
    let after = tool.sent_since(t1);
    let stop = after.iter().position(|l| l == "stop").unwrap_or_else(|| panic!("no stop: {after:?}"));
    assert!(after[stop..].iter().all(|l| l == "stop"), "nothing drives after the take: {after:?}");
    assert_eq!(of_type(&msgs, "state").last().unwrap()["role"], "pilot");
    // any page may stop the robot, watchers too (even with nothing held: a `locate` ends)
    let t2 = Instant::now();
    send(&mut a, r#"{"cmd":"stop"}"#);
    messages(&mut a, 150);
    assert_eq!(tool.sent_since(t2), ["stop"]);
    let (report, _) = tool.finish();
    assert_eq!(report.pages, 2);
}

#[test]
fn malformed_messages_close_that_page_and_change_nothing() {
    let tool = Tool::start();
    let mut pilot = page(&tool.addr);
    messages(&mut pilot, 50);
    for (bad, code, why) in [
        (Message::text("fwd please"), CloseCode::Policy, "not JSON"),
        (Message::text(r#"{"cmd":"hold","motion":"sideways"}"#), CloseCode::Policy, "hold wants"),
        (Message::text(r#"{"cmd":"stop","speed":9}"#), CloseCode::Policy, "unexpected field"),
        (Message::text(format!(r#"{{"cmd":"{}"}}"#, "x".repeat(300))), CloseCode::Policy, "message of"),
        (Message::binary(vec![1, 2, 3]), CloseCode::Unsupported, "binary"),
    ] {
        // the pilot holds forward the whole time, as a page does (from its
        // first hold: between rounds its hold may run out, as it should)
        let mut other = page(&tool.addr);
        messages(&mut other, 30);
        send(&mut pilot, r#"{"cmd":"hold","motion":"fwd"}"#);
        messages(&mut pilot, 20);
        let t0 = Instant::now();
        other.send(bad).unwrap();
        let mut closed = None;
        while t0.elapsed() < Duration::from_millis(600) {
            send(&mut pilot, r#"{"cmd":"hold","motion":"fwd"}"#);
            let (_, c) = messages(&mut other, u64::from(REFRESH_MS) / 2);
            closed = closed.or(c);
            messages(&mut pilot, u64::from(REFRESH_MS) / 2);
        }
        let (got_code, reason) = closed.expect("the bad page is closed");
        assert_eq!(got_code, code, "{reason}");
        assert!(reason.starts_with(why), "{reason}");
        let sent = tool.sent_since(t0);
        assert!(!sent.iter().any(|l| l == "stop"), "the robot kept going: {sent:?}");
        assert!(sent.iter().filter(|l| l.starts_with("fwd ")).count() >= 3, "{sent:?}");
    }
    let (_, sent) = tool.finish();
    assert_eq!(sent.last().map(String::as_str), Some("stop"), "quitting stops the robot");
}

/// When `stop` followed the last `fwd` sent, ms after `from`.
fn stop_after(tool: &Tool, from: Instant) -> Option<u128> {
    let sent = tool.sent.lock().unwrap();
    sent.iter().filter(|(t, _)| *t >= from).find(|(_, l)| l == "stop").map(|(t, _)| (*t - from).as_millis())
}

#[test]
fn a_silent_or_gone_pilot_stops_the_robot() {
    // silent (a phone asleep, the socket still open): stop once the hold runs out
    let tool = Tool::start();
    let mut pilot = page(&tool.addr);
    messages(&mut pilot, 50);
    // (the instant before the hold is sent: the tool may take it before
    // `send` returns, and its hold runs from then)
    let held = Instant::now();
    send(&mut pilot, r#"{"cmd":"hold","motion":"cw"}"#);
    messages(&mut pilot, 600);
    let sent = tool.sent_since(held);
    assert!(sent.iter().filter(|l| l.starts_with("cw ")).count() >= 2, "refreshed while held: {sent:?}");
    let at = stop_after(&tool, held).expect("stopped");
    // not before the hold runs out (the tool's clock counts whole ms,
    // `host::web::run`: a hold taken late in one runs out up to 1 ms
    // early), and before the robot's own deadman would stop it (the
    // hold's purpose)
    let hold = u128::from(WEB_HOLD_MS);
    assert!((hold - 1..u128::from(DEADMAN_MS)).contains(&at), "stop {at} ms after the last hold");
    // gone (a tab closed while holding): stop at once
    send(&mut pilot, r#"{"cmd":"hold","motion":"fwd"}"#);
    messages(&mut pilot, 60);
    let closed = Instant::now();
    drop(pilot);
    std::thread::sleep(Duration::from_millis(200));
    let at = stop_after(&tool, closed).expect("stopped");
    assert!(at < 100, "stop {at} ms after the page went");
    tool.finish();
}
