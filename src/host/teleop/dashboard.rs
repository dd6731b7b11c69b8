//! What the terminal shows, as plain text: the newest telemetry row
//! (pose, motion, sensors, fault counters), link health, the recent
//! messages (`#` lines), and the driver's state. The terminal layer draws
//! each [`Panel`] in a box; tests read the text.
//!
//! Every line from the robot goes through [`Dashboard::on_line`], which
//! returns the parsed row (for the recorder). Refresh acknowledgements
//! (`# ok` repeating the previous `# ok`) are counted, not shown, so the
//! messages keep what matters: refusals, notes, status, help, boot text.

use std::collections::VecDeque;
use std::format;
use std::string::{String, ToString};
use std::vec::Vec;

use super::drive::Driver;
use crate::config;
use crate::control::protocol::{classify_line, parse_telemetry_row, telemetry, LineKind, TelemetryRow, ERR, OK};
use crate::model::estimator::Tracking;
use crate::model::MotionKind;

/// A titled box of text lines.
#[derive(Clone, PartialEq, Eq, Debug)]
pub struct Panel {
    pub title: String,
    pub lines: Vec<String>,
}

/// Counts and the newest state of the link.
#[derive(Clone, Debug, Default)]
pub struct Dashboard {
    last: Option<TelemetryRow>,
    last_row_ms: Option<u64>,
    rows: u64,
    /// Lines that were neither `#` lines, the header nor a telemetry row.
    bad: u64,
    oks: u64,
    errs: u64,
    headers: u64,
    last_ok: Option<String>,
    messages: VecDeque<String>,
    max_messages: usize,
    /// Messages added since the start (shown or since dropped).
    added: u64,
    /// The newest reading of each sensor and its row time (rows leave a
    /// field empty when the sensor had nothing new): front and right lidar
    /// (raw mm, distance 0.1 mm), compass (millidegrees, raw counts).
    front: Option<(u32, u16, Option<i32>)>,
    right: Option<(u32, u16, Option<i32>)>,
    compass: Option<(u32, u32, Option<[i16; 3]>)>,
}

fn dmm(v: i32) -> String {
    let sign = if v < 0 { "-" } else { "" };
    format!("{sign}{}.{}", v.unsigned_abs() / 10, v.unsigned_abs() % 10)
}
fn milli(v: i32) -> String {
    let sign = if v < 0 { "-" } else { "" };
    format!("{sign}{}.{:03}", v.unsigned_abs() / 1000, v.unsigned_abs() % 1000)
}
fn centi(v: u32) -> String {
    format!("{}.{:02}", v / 100, v % 100)
}
fn opt<T>(v: Option<T>, f: impl Fn(T) -> String) -> String {
    v.map_or_else(|| String::from("-"), f)
}

impl Dashboard {
    pub fn new() -> Dashboard {
        Dashboard { max_messages: config::teleop::MESSAGES_SHOWN, ..Dashboard::default() }
    }

    /// Takes one line from the robot (received at `now_ms`); returns the
    /// telemetry row it holds, if it is one.
    pub fn on_line(&mut self, line: &str, now_ms: u64) -> Option<TelemetryRow> {
        let line = line.trim_end_matches(['\r', '\n']);
        match classify_line(line) {
            LineKind::Header => {
                self.headers = self.headers.saturating_add(1);
                None
            }
            LineKind::Comment => {
                if line.starts_with(OK) {
                    self.oks = self.oks.saturating_add(1);
                    if self.last_ok.as_deref() == Some(line) {
                        return None; // a refresh's acknowledgement
                    }
                    self.last_ok = Some(line.to_string());
                } else if line.starts_with(ERR) {
                    self.errs = self.errs.saturating_add(1);
                }
                self.message(line.to_string());
                None
            }
            LineKind::Row => match parse_telemetry_row(line) {
                Ok(row) => {
                    self.rows = self.rows.saturating_add(1);
                    if let Some(raw) = row.front_raw_mm {
                        self.front = Some((row.t_ms, raw, row.front_dmm));
                    }
                    if let Some(raw) = row.right_raw_mm {
                        self.right = Some((row.t_ms, raw, row.right_dmm));
                    }
                    if let Some(h) = row.compass_mdeg {
                        self.compass = Some((row.t_ms, h, row.mag_raw));
                    }
                    self.last = Some(row);
                    self.last_row_ms = Some(now_ms);
                    Some(row)
                }
                Err(_) if line.trim().is_empty() => None,
                Err(_) => {
                    self.bad = self.bad.saturating_add(1);
                    self.message(format!("? {line}"));
                    None
                }
            },
        }
    }

    /// Adds a line to the messages (the oldest goes when full).
    pub fn message(&mut self, text: String) {
        if self.messages.len() >= self.max_messages.max(1) {
            self.messages.pop_front();
        }
        self.messages.push_back(text);
        self.added = self.added.saturating_add(1);
    }

    /// Messages added since the start: a line that changed this count is
    /// shown (the newest of [`Dashboard::messages`]).
    pub fn messages_added(&self) -> u64 {
        self.added
    }

    pub fn last_row(&self) -> Option<&TelemetryRow> {
        self.last.as_ref()
    }
    pub fn rows(&self) -> u64 {
        self.rows
    }
    pub fn errors(&self) -> u64 {
        self.errs
    }
    pub fn bad_lines(&self) -> u64 {
        self.bad
    }
    pub fn messages(&self) -> impl Iterator<Item = &str> {
        self.messages.iter().map(String::as_str)
    }

    /// True when no row came for [`config::teleop::STALE_LINK_MS`] (or none yet).
    pub fn stale(&self, now_ms: u64) -> bool {
        self.last_row_ms.is_none_or(|t| now_ms.saturating_sub(t) > u64::from(config::teleop::STALE_LINK_MS))
    }

    /// The screen: link, pose and motion, sensors, faults, messages.
    /// `recording` is a one-line recorder state (e.g. `drive.csv: 120 rows`).
    pub fn panels(&self, now_ms: u64, driver: &Driver, recording: Option<&str>) -> Vec<Panel> {
        let mut out = Vec::new();
        let link = if self.last_row_ms.is_none() {
            String::from("waiting for telemetry")
        } else if self.stale(now_ms) {
            format!("STALE: no telemetry for {} ms", now_ms.saturating_sub(self.last_row_ms.unwrap_or(0)))
        } else {
            String::from("ok")
        };
        out.push(Panel {
            title: String::from("link"),
            lines: [
                format!("telemetry {link}"),
                format!("rows {}  ok {}  err {}  bad {}", self.rows, self.oks, self.errs, self.bad),
                format!("sent {}  last `{}`", driver.sent(), driver.last_sent().unwrap_or("-")),
                format!("record {}", recording.unwrap_or("off")),
            ]
            .into(),
        });
        let r = self.last.as_ref();
        out.push(Panel {
            title: String::from("pose and motion"),
            lines: match r {
                None => ["-".to_string()].into(),
                Some(r) => [
                    format!("t {} ms", r.t_ms),
                    format!("x {} mm  y {} mm", dmm(r.x_dmm), dmm(r.y_dmm)),
                    format!("heading {} deg", milli(r.heading_mdeg as i32)),
                    match r.tracking {
                        Tracking::Located => "estimate located".to_string(),
                        Tracking::Ambiguous => "estimate AMBIGUOUS: several places fit, the pose holds".to_string(),
                        Tracking::Unknown => "estimate UNKNOWN: locate (r) or pose".to_string(),
                    },
                    format!(
                        "motion {}  v {} m/s  w {} rad/s",
                        telemetry::motion_word(r.motion),
                        milli(r.v_mm_s),
                        milli(r.w_mrad_s)
                    ),
                    format!("servos L {}  R {}", centi(r.left_cmd_centi), centi(r.right_cmd_centi)),
                ]
                .into(),
            },
        });
        // the newest reading of each sensor, with its age against the newest row
        let now_t = r.map_or(0, |r| r.t_ms);
        let age = |t: u32| format!("({} ms ago)", now_t.saturating_sub(t));
        let lidar = |name: &str, l: Option<(u32, u16, Option<i32>)>| match l {
            None => format!("{name} -"),
            Some((t, raw, d)) => format!("{name} raw {raw} mm  dist {} mm  {}", opt(d, dmm), age(t)),
        };
        out.push(Panel {
            title: String::from("sensors"),
            lines: [
                lidar("front", self.front),
                lidar("right", self.right),
                match self.compass {
                    None => String::from("compass -"),
                    Some((t, h, _)) => format!("compass {} deg  {}", milli(h as i32), age(t)),
                },
                format!("mag raw {}", opt(self.compass.and_then(|c| c.2), |m| format!("{} {} {}", m[0], m[1], m[2]))),
            ]
            .into(),
        });
        out.push(Panel {
            title: String::from("faults"),
            lines: match r {
                None => ["-".to_string()].into(),
                Some(r) => {
                    let f = &r.faults;
                    [
                        format!("bus {}  timeout {}  missing {}", f.bus, f.timeout, f.missing),
                        format!(
                            "bad sample {}  outliers {}  overruns {}",
                            f.bad_sample, f.rejected_outliers, f.overruns
                        ),
                    ]
                    .into()
                }
            },
        });
        out.push(Panel {
            title: String::from("drive"),
            lines: [
                match driver.wanted() {
                    MotionKind::Stop => String::from("stopped (arrows / WASD drive)"),
                    _ => format!("holding `{}`, sent again every {} ms", driver.command(), driver.refresh_ms()),
                },
                format!("speed {}", driver.speeds().describe()),
            ]
            .into(),
        });
        out.push(Panel { title: String::from("messages"), lines: self.messages.iter().cloned().collect() });
        out
    }
}
