//! The pages and who drives: one page at a time is the pilot, the others
//! watch; the motion the pilot holds and when it runs out.
//!
//! - The first page to connect drives; a page that connects while another
//!   drives watches, and is told so. A watching page may take over
//!   (`take`): the robot stops, and the page that drove is told it now
//!   watches. When the pilot leaves, the robot stops and nobody drives
//!   until a page takes over (a watcher never starts driving by itself).
//! - Any page may stop the robot (`stop` goes out even when nothing is
//!   held: it also ends a `locate`); only the pilot drives it.
//! - A held motion lasts [`WEB_HOLD_MS`] after the pilot's last `hold`
//!   (the page repeats it every [`REFRESH_MS`](crate::config::teleop::REFRESH_MS)),
//!   then `stop` is sent: a closed tab, a sleeping phone or a dropped
//!   network stops the robot well within its deadman. While it lasts, the
//!   [`Driver`] sends it again every refresh period, as in the terminal UI.

use std::string::{String, ToString};
use std::sync::mpsc::{SyncSender, TrySendError};
use std::sync::Arc;
use std::vec::Vec;

use serde_json::{json, Value};

use super::command::Command;
use super::model::{Live, Role};
use crate::config::teleop::WEB_HOLD_MS;
use crate::host::teleop::{keys, Driver};
use crate::model::MotionKind;

/// A connected page: its id and the queue its connection writes from.
struct Page {
    id: u64,
    tx: SyncSender<Arc<str>>,
    role: Role,
}

/// The pages, the pilot and the held motion.
pub struct Session {
    pages: Vec<Page>,
    driver: Driver,
    /// When the held motion runs out, ms.
    hold_until: u64,
    /// Messages a full queue dropped (a page that cannot keep up).
    dropped: u64,
}

impl Default for Session {
    fn default() -> Self {
        Session::new(Driver::from_config())
    }
}

impl Session {
    pub fn new(driver: Driver) -> Session {
        Session { pages: Vec::new(), driver, hold_until: 0, dropped: 0 }
    }

    pub fn driver(&self) -> &Driver {
        &self.driver
    }
    /// The pilot's id, if a page drives.
    pub fn pilot(&self) -> Option<u64> {
        self.pages.iter().find(|p| p.role == Role::Pilot).map(|p| p.id)
    }
    pub fn pages(&self) -> usize {
        self.pages.len()
    }
    pub fn dropped(&self) -> u64 {
        self.dropped
    }

    fn send(&mut self, id: u64, msg: &Value) {
        let text: Arc<str> = Arc::from(msg.to_string());
        if let Some(p) = self.pages.iter().find(|p| p.id == id) {
            if let Err(TrySendError::Full(_)) = p.tx.try_send(text) {
                self.dropped += 1;
            }
        }
    }

    /// Sends `msg` to every page.
    pub fn broadcast(&mut self, msg: &Value) {
        let text: Arc<str> = Arc::from(msg.to_string());
        for p in &self.pages {
            if let Err(TrySendError::Full(_)) = p.tx.try_send(Arc::clone(&text)) {
                self.dropped += 1;
            }
        }
    }

    /// Sends each page the link's and driver's state (its own role in it).
    pub fn send_state(&mut self, live: &Live, now_ms: u64) {
        let pilot = self.pilot().is_some();
        let states: Vec<(u64, Value)> =
            self.pages.iter().map(|p| (p.id, live.state(now_ms, &self.driver, p.role, pilot))).collect();
        for (id, s) in states {
            self.send(id, &s);
        }
    }

    fn notice(&mut self, id: u64, text: &str) {
        self.send(id, &json!({ "type": "notice", "text": text }));
    }

    /// A page connected: it drives if none does, else it watches.
    pub fn join(&mut self, id: u64, tx: SyncSender<Arc<str>>, live: &Live, now_ms: u64) {
        let role = if self.pilot().is_none() { Role::Pilot } else { Role::Viewer };
        self.pages.push(Page { id, tx, role });
        self.send(id, &live.hello(role));
        if role == Role::Viewer {
            self.notice(id, "another page drives: this one watches (take over to drive)");
        }
        self.send_state(live, now_ms);
    }

    /// A page left (closed, lost, or closed by the server): if it drove,
    /// the robot stops and nobody drives.
    pub fn leave(&mut self, id: u64, live: &Live, now_ms: u64) {
        let was_pilot = self.pilot() == Some(id);
        self.pages.retain(|p| p.id != id);
        if was_pilot {
            self.driver.set(MotionKind::Stop);
            self.send_state(live, now_ms);
        }
    }

    /// A page's command at `now_ms`; returns the lines for the robot now
    /// (held motions go out through [`Session::poll`]).
    pub fn command(&mut self, id: u64, cmd: Command, live: &Live, now_ms: u64) -> Vec<String> {
        let pilot = self.pilot() == Some(id);
        match cmd {
            Command::Stop => {
                // sent even when nothing is held: it also ends a `locate`'s turns
                let out = self.stop_now(now_ms);
                self.send_state(live, now_ms);
                return out;
            }
            Command::Take if !pilot => {
                if let Some(old) = self.pilot() {
                    self.notice(old, "another page took over: this one watches now (take over to drive)");
                }
                for p in &mut self.pages {
                    p.role = if p.id == id { Role::Pilot } else { Role::Viewer };
                }
                self.driver.set(MotionKind::Stop);
                self.send_state(live, now_ms);
                return Vec::new();
            }
            Command::Take => return Vec::new(),
            _ if !pilot => {
                self.notice(id, "this page watches: take over to drive");
                return Vec::new();
            }
            Command::Hold(kind) => {
                self.driver.set(kind);
                self.hold_until = now_ms.saturating_add(u64::from(WEB_HOLD_MS));
            }
            Command::Faster => {
                self.driver.faster();
            }
            Command::Slower => {
                self.driver.slower();
            }
            Command::Locate => {
                // a held motion stops first (its refreshes would cut the turns short)
                let mut out = self.stop_now(now_ms);
                out.push(String::from(keys::LOCATE_COMMAND));
                self.send_state(live, now_ms);
                return out;
            }
        }
        self.send_state(live, now_ms);
        Vec::new()
    }

    /// Lets go of any held motion and says `stop` (once).
    fn stop_now(&mut self, now_ms: u64) -> Vec<String> {
        self.driver.set(MotionKind::Stop);
        let sent = self.driver.poll(now_ms);
        std::vec![sent.unwrap_or_else(|| String::from("stop"))]
    }

    /// The line to send the robot at `now_ms`, if one is due: a held motion
    /// that ran out becomes `stop`; otherwise the [`Driver`]'s schedule.
    pub fn poll(&mut self, now_ms: u64) -> Option<String> {
        if self.driver.wanted() != MotionKind::Stop && now_ms >= self.hold_until {
            self.driver.set(MotionKind::Stop);
        }
        self.driver.poll(now_ms)
    }

    /// Tells every page the server is going away and forgets them (their
    /// connections close when their queues are dropped).
    pub fn close_all(&mut self) {
        self.broadcast(&json!({ "type": "notice", "text": "teleop has quit: the robot was stopped" }));
        self.pages.clear();
    }
}
