//! The page's server: one TCP port for the page, its script and the
//! WebSocket the page opens, a thread per connection (blocking std I/O,
//! like the rest of the tool).
//!
//! Each connection's request head is read with tungstenite's own HTTP
//! request parser; a WebSocket upgrade to `/ws` is handed to tungstenite's
//! server handshake, anything else is answered with tungstenite's response
//! writer (`write_response`, an `http::Response`): the page's files are
//! compiled in ([`FILES`]), so it works offline and needs no CDN. Why not a
//! general HTTP server crate: tiny_http's upgraded connection is an opaque
//! blocking stream (no read timeout), so one thread could not both wait for
//! the page's commands and push rows as they arrive; with the `TcpStream`
//! ours, the connection's thread polls both.
//!
//! The connection threads and the tool's loop talk through channels: a
//! connection reports [`Event`]s (joined with its queue, a valid command,
//! left); the loop writes the page's messages into that queue. A WebSocket
//! asked for by another site's page (its Origin is not this server) is
//! refused (403), so a web page open in the same browser cannot drive. A malformed
//! message closes the connection with its reason (close code 1008, or
//! 1003 for binary data) and reaches nothing else.

use std::boxed::Box;
use std::format;
use std::io::{self, ErrorKind, Read, Write};
use std::net::{Shutdown, SocketAddr, TcpListener, TcpStream};
use std::string::{String, ToString};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{self, Receiver, Sender, SyncSender, TryRecvError};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use tungstenite::error::ProtocolError;
use tungstenite::handshake::machine::TryParse;
use tungstenite::handshake::server::{write_response, ErrorResponse, Request, Response as HandshakeResponse};
use tungstenite::http::{Response, StatusCode};
use tungstenite::protocol::frame::coding::CloseCode;
use tungstenite::protocol::{CloseFrame, WebSocketConfig};
use tungstenite::{Message, WebSocket};

use super::command::{parse_command, Command};
use crate::config::teleop::{WEB_MAX_MESSAGE, WEB_QUEUE};

/// The page's files: path, content type, content.
pub const FILES: &[(&str, &str, &str)] = &[
    ("/", "text/html; charset=utf-8", include_str!("page/index.html")),
    ("/app.js", "text/javascript; charset=utf-8", include_str!("page/app.js")),
    ("/style.css", "text/css; charset=utf-8", include_str!("page/style.css")),
];

/// The WebSocket's path.
pub const WS_PATH: &str = "/ws";

/// How long a connection may take to send its request head.
const HEAD_TIMEOUT: Duration = Duration::from_secs(5);
/// Largest request head read, bytes.
const MAX_HEAD: usize = 8 * 1024;
/// A connection's poll period: how long a read waits for the page before
/// the queue is written out again (rows leave within this of arriving).
const POLL: Duration = Duration::from_millis(5);
/// Largest WebSocket message or frame tungstenite buffers, bytes: a
/// bound on memory; the commands' own limit is far lower
/// ([`WEB_MAX_MESSAGE`], checked by [`parse_command`]).
const MAX_FRAME: usize = 64 * 1024;
/// A close frame's reason holds at most this many bytes (RFC 6455 5.5:
/// 125 bytes of payload, 2 of them the code).
const MAX_REASON: usize = 123;
/// A page that takes this long to take a message is gone.
const WRITE_TIMEOUT: Duration = Duration::from_secs(2);

/// What a connection tells the tool's loop.
#[derive(Debug)]
pub enum Event {
    /// A page's WebSocket is open; the loop writes its messages into `tx`.
    Joined { id: u64, tx: SyncSender<Arc<str>> },
    /// A valid command from that page.
    Command { id: u64, cmd: Command },
    /// The page's connection ended (closed, lost, or closed for a malformed message).
    Left { id: u64 },
}

/// A bound port, not yet serving.
pub struct WebServer {
    listener: TcpListener,
    addr: SocketAddr,
}

/// True for an address only this machine reaches.
pub fn is_loopback(addr: &SocketAddr) -> bool {
    addr.ip().is_loopback()
}

impl WebServer {
    /// Binds `addr` (`ADDR:PORT`); a port in use or a bad address is an
    /// error that says so.
    pub fn bind(addr: &str) -> Result<WebServer, String> {
        let listener = TcpListener::bind(addr).map_err(|e| match e.kind() {
            ErrorKind::AddrInUse => format!(
                "--web {addr}: the port is in use (another teleop --web, or another server?); \
                 pick another, e.g. --web 127.0.0.1:8081"
            ),
            ErrorKind::AddrNotAvailable => format!("--web {addr}: no such address on this machine"),
            ErrorKind::PermissionDenied => format!("--web {addr}: not allowed (ports below 1024 need root)"),
            _ => format!("--web {addr}: {e} (wants ADDR:PORT, e.g. 127.0.0.1:8080)"),
        })?;
        let addr = listener.local_addr().map_err(|e| format!("--web {addr}: {e}"))?;
        Ok(WebServer { listener, addr })
    }

    pub fn local_addr(&self) -> SocketAddr {
        self.addr
    }

    /// Serves until `stop` is set: accepts connections, each on its own
    /// thread, reporting to `events`.
    pub fn start(self, events: Sender<Event>, stop: Arc<AtomicBool>) -> io::Result<JoinHandle<()>> {
        self.listener.set_nonblocking(true)?;
        Ok(std::thread::spawn(move || {
            let mut next_id = 0u64;
            while !stop.load(Ordering::Relaxed) {
                match self.listener.accept() {
                    Ok((stream, _)) => {
                        next_id += 1;
                        let id = next_id;
                        let (events, stop) = (events.clone(), Arc::clone(&stop));
                        std::thread::spawn(move || {
                            let _ = connection(stream, id, &events, &stop);
                        });
                    }
                    // nothing to accept (or a refused one): look again shortly
                    Err(_) => std::thread::sleep(Duration::from_millis(10)),
                }
            }
        }))
    }
}

/// A request head, as far as it came.
enum Head {
    /// Complete: its length and the request.
    Request(usize, Box<Request>),
    /// Not a request we take (tungstenite's parser takes GET only): the
    /// status to answer, and the bytes that came.
    Refused(StatusCode, usize),
    /// Closed, too long or too slow.
    Nothing,
}

/// Waits until the request head has arrived (peeking, so tungstenite's
/// handshake reads it again).
fn peek_head(stream: &TcpStream) -> io::Result<Head> {
    let start = Instant::now();
    let mut buf = std::vec![0u8; MAX_HEAD];
    loop {
        let n = stream.peek(&mut buf)?;
        match Request::try_parse(buf.get(..n).unwrap_or(&[])) {
            Ok(Some((len, req))) => return Ok(Head::Request(len, Box::new(req))),
            Ok(None) if n > 0 && n < MAX_HEAD && start.elapsed() < HEAD_TIMEOUT => {}
            Ok(None) => return Ok(Head::Nothing),
            Err(tungstenite::Error::Protocol(ProtocolError::WrongHttpMethod)) => {
                return Ok(Head::Refused(StatusCode::METHOD_NOT_ALLOWED, n))
            }
            Err(_) => return Ok(Head::Refused(StatusCode::BAD_REQUEST, n)),
        }
        std::thread::sleep(Duration::from_millis(2));
    }
}

fn respond(stream: &mut TcpStream, status: StatusCode, content_type: &str, body: &[u8]) -> io::Result<()> {
    let response = Response::builder()
        .status(status)
        .header("Content-Type", content_type)
        .header("Content-Length", body.len().to_string())
        .header("Cache-Control", "no-store")
        .header("Connection", "close")
        .body(())
        .map_err(io::Error::other)?;
    write_response(&mut *stream, &response).map_err(io::Error::other)?;
    stream.write_all(body)?;
    stream.flush()
}

/// Whether a WebSocket request comes from this server's own page: a
/// browser names the page's origin, and any web site open in the same
/// browser could otherwise drive the robot through `ws://127.0.0.1:8080`.
/// A request without an Origin (a script, a test) is not from a browser's
/// page and is let in.
pub fn same_origin(req: &Request) -> bool {
    let header = |name: &str| req.headers().get(name).and_then(|v| v.to_str().ok());
    match (header("origin"), header("host")) {
        (None, _) => true,
        (Some(origin), Some(host)) => {
            origin.strip_prefix("http://").or_else(|| origin.strip_prefix("https://")) == Some(host)
        }
        (Some(_), None) => false,
    }
}

/// The handshake's check: [`same_origin`], or 403.
#[allow(clippy::result_large_err)] // tungstenite's callback signature
fn same_site(req: &Request, response: HandshakeResponse) -> Result<HandshakeResponse, ErrorResponse> {
    if same_origin(req) {
        Ok(response)
    } else {
        let mut refused = ErrorResponse::new(Some("the page must come from this server\n".into()));
        *refused.status_mut() = StatusCode::FORBIDDEN;
        Err(refused)
    }
}

fn is_upgrade(req: &Request) -> bool {
    req.headers().get("upgrade").and_then(|v| v.to_str().ok()).is_some_and(|v| v.eq_ignore_ascii_case("websocket"))
}

/// One connection: a file, or the page's WebSocket.
fn connection(mut stream: TcpStream, id: u64, events: &Sender<Event>, stop: &AtomicBool) -> io::Result<()> {
    stream.set_nonblocking(false)?;
    stream.set_read_timeout(Some(HEAD_TIMEOUT))?;
    stream.set_write_timeout(Some(WRITE_TIMEOUT))?;
    let _ = stream.set_nodelay(true);
    let (len, req) = match peek_head(&stream)? {
        Head::Request(len, req) => (len, req),
        Head::Nothing => return Ok(()),
        Head::Refused(status, n) => {
            // what came is read (the peer sees our answer, not a reset for unread bytes)
            let mut head = std::vec![0u8; n];
            stream.read_exact(&mut head)?;
            let result = respond(&mut stream, status, "text/plain", b"GET only\n");
            let _ = stream.shutdown(Shutdown::Write);
            return result;
        }
    };
    let path = req.uri().path().to_string();
    if is_upgrade(&req) && path == WS_PATH {
        let config = WebSocketConfig::default().max_message_size(Some(MAX_FRAME)).max_frame_size(Some(MAX_FRAME));
        let ws = tungstenite::accept_hdr_with_config(stream, same_site, Some(config)).map_err(io::Error::other)?;
        return page(ws, id, events, stop);
    }
    // a plain request: its head is read (the peer sees our answer, not a
    // reset for unread bytes), answered, and the connection closed
    let mut head = std::vec![0u8; len];
    stream.read_exact(&mut head)?;
    let result = match FILES.iter().find(|(p, _, _)| *p == path) {
        Some((_, ctype, body)) => respond(&mut stream, StatusCode::OK, ctype, body.as_bytes()),
        None => respond(&mut stream, StatusCode::NOT_FOUND, "text/plain", b"not found\n"),
    };
    let _ = stream.shutdown(Shutdown::Write);
    result
}

/// Why a page's connection is closed by the server.
fn close(ws: &mut WebSocket<TcpStream>, code: CloseCode, reason: &str) {
    let mut reason = reason.to_string();
    while reason.len() > MAX_REASON {
        reason.pop();
    }
    let _ = ws.close(Some(CloseFrame { code, reason: reason.into() }));
    // let the close frame go out and the page answer it, briefly
    let until = Instant::now() + Duration::from_millis(200);
    while Instant::now() < until {
        match ws.read() {
            Err(tungstenite::Error::Io(e)) if matches!(e.kind(), ErrorKind::WouldBlock | ErrorKind::TimedOut) => {}
            Err(_) => break,
            Ok(_) => {}
        }
    }
}

/// A page's WebSocket: reports its commands, writes its queue.
fn page(mut ws: WebSocket<TcpStream>, id: u64, events: &Sender<Event>, stop: &AtomicBool) -> io::Result<()> {
    ws.get_mut().set_read_timeout(Some(POLL))?;
    let (tx, rx): (SyncSender<Arc<str>>, Receiver<Arc<str>>) = mpsc::sync_channel(WEB_QUEUE);
    if events.send(Event::Joined { id, tx }).is_err() {
        close(&mut ws, CloseCode::Away, "teleop is quitting");
        return Ok(());
    }
    let result = serve_page(&mut ws, id, &rx, events, stop);
    let _ = events.send(Event::Left { id });
    result
}

fn serve_page(
    ws: &mut WebSocket<TcpStream>,
    id: u64,
    rx: &Receiver<Arc<str>>,
    events: &Sender<Event>,
    stop: &AtomicBool,
) -> io::Result<()> {
    loop {
        match ws.read() {
            Ok(Message::Text(text)) => match parse_command(text.as_str()) {
                Ok(cmd) => {
                    if events.send(Event::Command { id, cmd }).is_err() {
                        close(ws, CloseCode::Away, "teleop is quitting");
                        return Ok(());
                    }
                }
                Err(why) => {
                    close(ws, CloseCode::Policy, &why);
                    return Ok(());
                }
            },
            Ok(Message::Binary(_)) => {
                close(ws, CloseCode::Unsupported, "binary messages are not understood: send JSON text");
                return Ok(());
            }
            Ok(Message::Close(_)) => return Ok(()),
            Ok(_) => {} // ping, pong: tungstenite answers
            Err(tungstenite::Error::Io(e)) if matches!(e.kind(), ErrorKind::WouldBlock | ErrorKind::TimedOut) => {}
            Err(tungstenite::Error::Capacity(_)) => {
                close(ws, CloseCode::Size, &format!("message too long: at most {WEB_MAX_MESSAGE} bytes"));
                return Ok(());
            }
            Err(tungstenite::Error::ConnectionClosed | tungstenite::Error::AlreadyClosed) => return Ok(()),
            Err(e) => return Err(io::Error::other(e)),
        }
        if stop.load(Ordering::Relaxed) {
            close(ws, CloseCode::Away, "teleop is quitting");
            return Ok(());
        }
        // the queue, written out: rows leave within a poll period
        let mut wrote = false;
        loop {
            match rx.try_recv() {
                Ok(text) => {
                    ws.write(Message::text(text.as_ref())).map_err(io::Error::other)?;
                    wrote = true;
                }
                Err(TryRecvError::Empty) => break,
                Err(TryRecvError::Disconnected) => {
                    ws.flush().map_err(io::Error::other)?;
                    close(ws, CloseCode::Away, "teleop is quitting");
                    return Ok(());
                }
            }
        }
        if wrote {
            ws.flush().map_err(io::Error::other)?;
        }
    }
}
