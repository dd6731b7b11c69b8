//! The tool's loop with the page: the robot's lines to every page as they
//! come, the pilot's commands to the robot, until told to stop.

use std::io::{self, Read, Write};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc;
use std::sync::Arc;
use std::time::Instant;

use super::model::Live;
use super::server::{Event, WebServer};
use super::session::Session;
use crate::config;
use crate::control::protocol::TelemetryRow;
use crate::host::teleop::{link, LineReader};

/// How a run goes.
#[derive(Clone, Copy, PartialEq, Debug)]
pub struct WebOptions {
    /// Telemetry rate to ask for, Hz (0 switches it off; `None` leaves it as it is).
    pub rate_hz: Option<u16>,
    /// The box, mm (x north, y east).
    pub arena: (f64, f64),
}

impl Default for WebOptions {
    fn default() -> Self {
        WebOptions {
            rate_hz: Some(config::timing::TELEMETRY_HZ as u16),
            arena: (config::arena::LENGTH_X.to_mm_f64(), config::arena::WIDTH_Y.to_mm_f64()),
        }
    }
}

/// What a run did.
#[derive(Clone, Copy, PartialEq, Eq, Debug, Default)]
pub struct WebReport {
    pub rows: u64,
    /// Pages that connected.
    pub pages: u64,
    /// Commands sent to the robot (held motions and their refreshes included).
    pub sent: u64,
    /// Messages dropped for pages that could not keep up.
    pub dropped: u64,
}

/// Serves the page on `server` and runs the link on `port` until `stop`
/// is set; every line from the robot goes to `on_line` too (with its
/// telemetry row, if it is one: for a raw log or a recorder). The robot is
/// stopped at the end, whatever ended the run.
pub fn run<P, F>(
    port: &mut P,
    server: WebServer,
    opts: WebOptions,
    stop: &Arc<AtomicBool>,
    mut on_line: F,
) -> io::Result<WebReport>
where
    P: Read + Write + ?Sized,
    F: FnMut(&str, Option<&TelemetryRow>) -> io::Result<()>,
{
    let start = Instant::now();
    let now_ms = || start.elapsed().as_millis() as u64;
    let (events_tx, events) = mpsc::channel();
    let serving = Arc::new(AtomicBool::new(false));
    let accept = server.start(events_tx, Arc::clone(&serving))?;
    let mut live = Live::new(opts.arena.0, opts.arena.1);
    let mut session = Session::default();
    let mut reader = LineReader::new();
    let mut report = WebReport::default();
    if let Some(hz) = opts.rate_hz {
        link::start_telemetry(port, hz)?;
    }
    let mut next_state = 0u64;
    let result = (|| -> io::Result<()> {
        while !stop.load(Ordering::Relaxed) {
            let now = now_ms();
            while let Ok(ev) = events.try_recv() {
                match ev {
                    Event::Joined { id, tx } => {
                        report.pages += 1;
                        session.join(id, tx, &live, now);
                    }
                    Event::Command { id, cmd } => {
                        for line in session.command(id, cmd, &live, now) {
                            link::send(port, &line)?;
                            report.sent += 1;
                        }
                    }
                    Event::Left { id } => session.leave(id, &live, now),
                }
            }
            if let Some(cmd) = session.poll(now) {
                link::send(port, &cmd)?;
                report.sent += 1;
            }
            // one read (the port's timeout paces the loop)
            for line in reader.poll(port)? {
                let (msgs, row) = live.on_line(&line, now);
                for m in &msgs {
                    session.broadcast(m);
                }
                report.rows += u64::from(row.is_some());
                on_line(&line, row.as_ref())?;
            }
            if now >= next_state {
                next_state = now + u64::from(config::teleop::WEB_STATE_MS);
                session.send_state(&live, now);
            }
        }
        Ok(())
    })();
    // stop the robot whatever happened, then the pages and the server
    let stopped = link::send(port, "stop");
    let end = now_ms() + u64::from(config::teleop::REFRESH_MS);
    while stopped.is_ok() && now_ms() < end {
        match reader.poll(port) {
            Ok(lines) => {
                for line in lines {
                    let (msgs, row) = live.on_line(&line, now_ms());
                    msgs.iter().for_each(|m| session.broadcast(m));
                    let _ = on_line(&line, row.as_ref());
                }
            }
            Err(_) => break,
        }
    }
    session.close_all();
    serving.store(true, Ordering::Relaxed);
    let _ = accept.join();
    report.dropped = session.dropped();
    result.and(stopped).map(|()| report)
}
