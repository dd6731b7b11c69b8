//! What the page is told, as JSON messages: every line from the robot
//! becomes at most a few of them, built here so the page only draws.
//!
//! Messages (`type` names each):
//! - `hello`: the box (mm), the body's outline and the lidars' mounts, the
//!   timing the page keeps (repeat period of a held motion), its role;
//! - `row`: one telemetry row: the `estimate` (pose, its state, the
//!   one-sigma ellipse when known, and `hypotheses`, each a pose with its
//!   sigma and weight, drawn as ghosts; empty until the robot reports
//!   several), motion, servo commands, the fresh sensor readings, the fault
//!   counters, and the `rays`: each fresh lidar reading from the lidar to
//!   where its beam ended, computed as `replay` draws them
//!   ([`LidarMount::beam_f64`], as `sim::svg::Ray::of_reading`);
//! - `message`: a `#` line for the messages panel (refresh acknowledgements
//!   are left out, as the terminal UI does);
//! - `truth`: the simulator's true pose, from `sim_pty --truth-hz`'s
//!   `# truth ...` lines (a real robot sends none);
//! - `state`: the link's counts and health, the driver's held motion,
//!   speed level and last command, the page's role;
//! - `notice`: something the page must show its user (it lost control).
//!
//! The estimate's uncertainty comes from the robot's `# located x y
//! heading sigma sx sy mm ...` answer (the localization's fix); the
//! telemetry row carries no covariance today. When rows carry one (or
//! hypotheses), only this module changes: the page draws `estimate` as
//! it is.

use std::vec::Vec;

use serde_json::{json, Value};

use super::super::teleop::{Dashboard, Driver};
use crate::config;
use crate::control::protocol::{telemetry, LineKind, TelemetryRow};
use crate::model::estimator::Tracking;
use crate::model::lidar::LidarMount;

/// A pose as the page draws it: mm (x north, y east) and heading in
/// degrees clockwise from north.
#[derive(Clone, Copy, PartialEq, Debug, Default)]
pub struct MapPose {
    pub x: f64,
    pub y: f64,
    pub heading_deg: f64,
}

impl MapPose {
    /// Distance between the two positions, mm.
    pub fn distance(&self, other: &MapPose) -> f64 {
        (self.x - other.x).hypot(self.y - other.y)
    }
}

/// Who a page is: the one that drives, or one that watches.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum Role {
    Pilot,
    Viewer,
}

impl Role {
    pub fn word(self) -> &'static str {
        match self {
            Role::Pilot => "pilot",
            Role::Viewer => "viewer",
        }
    }
}

/// How sure the robot is of its pose, as far as its lines tell.
#[derive(Clone, Copy, PartialEq, Debug)]
pub enum Fix {
    /// No localization seen this session (the pose may still be right: set
    /// at power-up or before the tool connected).
    Unknown,
    /// `# located ...`: the fix's pose and one-sigma x, y (mm); `ambiguous`
    /// when more than one place fits.
    Located { pose: MapPose, sigma_x: f64, sigma_y: f64, ambiguous: bool, t_ms: Option<u32> },
    /// `# locate failed ...`: the robot says its pose is unknown.
    Lost,
    /// `# ok pose ...`: set by the user.
    Set,
}

/// Parses `# located X Y HEADING sigma SX SY mm, views N[, ambiguous...]`.
pub fn parse_located(line: &str) -> Option<Fix> {
    let rest = line.strip_prefix("# located ")?;
    let w: Vec<&str> = rest.split([' ', ',']).filter(|w| !w.is_empty()).collect();
    let num = |i: usize| w.get(i).and_then(|s| s.parse::<f64>().ok()).filter(|v| v.is_finite());
    if w.get(3) != Some(&"sigma") {
        return None;
    }
    Some(Fix::Located {
        pose: MapPose { x: num(0)?, y: num(1)?, heading_deg: num(2)? },
        sigma_x: num(4)?,
        sigma_y: num(5)?,
        ambiguous: rest.contains("ambiguous"),
        t_ms: None,
    })
}

/// Parses `# truth t_ms=T x_mm=X y_mm=Y heading_deg=H` (`sim_pty --truth-hz`,
/// `sim::serve::truth_line`).
pub fn parse_truth(line: &str) -> Option<(u32, MapPose)> {
    let rest = line.strip_prefix("# truth ")?;
    let field = |key: &str| rest.split(' ').find_map(|kv| kv.strip_prefix(key)?.strip_prefix('=')?.parse::<f64>().ok());
    let (t, x, y, h) = (field("t_ms")?, field("x_mm")?, field("y_mm")?, field("heading_deg")?);
    (t >= 0.0 && t <= f64::from(u32::MAX) && x.is_finite() && y.is_finite() && h.is_finite())
        .then_some((t as u32, MapPose { x, y, heading_deg: h }))
}

fn mm(dmm: i32) -> f64 {
    f64::from(dmm) / 10.0
}

/// A row's estimated pose.
fn row_pose(r: &TelemetryRow) -> MapPose {
    MapPose { x: mm(r.x_dmm), y: mm(r.y_dmm), heading_deg: f64::from(r.heading_mdeg) / 1000.0 }
}

/// How far ahead of the nose the body's outline points, mm (a drawing's
/// mark of the heading, not a part of the robot).
const HEADING_MARK_MM: f64 = 15.0;

fn pose_json(p: &MapPose) -> Value {
    json!({ "x": p.x, "y": p.y, "heading": p.heading_deg.rem_euclid(360.0) })
}

/// The lidars as the page draws them: name, colour (replay's), mount.
const LIDARS: [(&str, &str, LidarMount); 2] =
    [("front", "#1f77b4", config::geometry::FRONT_LIDAR), ("right", "#2ca02c", config::geometry::RIGHT_LIDAR)];

/// The page's view of the link: lines in, messages out.
#[derive(Clone, Debug)]
pub struct Live {
    arena: (f64, f64),
    dash: Dashboard,
    fix: Fix,
}

impl Live {
    /// For a box `length_x` by `width_y` mm.
    pub fn new(length_x: f64, width_y: f64) -> Live {
        Live { arena: (length_x, width_y), dash: Dashboard::new(), fix: Fix::Unknown }
    }

    pub fn dashboard(&self) -> &Dashboard {
        &self.dash
    }
    pub fn fix(&self) -> Fix {
        self.fix
    }

    /// The first message a page gets.
    pub fn hello(&self, role: Role) -> Value {
        let d = config::geometry::ROTATION_TO_REFERENCE.to_mm_f64();
        let half = config::geometry::AXLE_LENGTH.to_mm_f64() / 2.0;
        let skid = config::geometry::SKID_BEHIND_AXLE.to_mm_f64();
        // the body in its own frame (forward, right) mm from the reference
        // point (the nose): a point ahead shows the heading, the sides run
        // back past the wheels on the axle to the skid
        let body = [[HEADING_MARK_MM, 0.0], [0.0, half], [-d - skid, half], [-d - skid, -half], [0.0, -half]];
        let wheels = [[-d, -half], [-d, half]];
        let lidars: Vec<Value> = LIDARS
            .iter()
            .map(|(name, color, m)| {
                json!({ "name": name, "color": color, "forward": m.forward.to_mm_f64(), "right": m.right.to_mm_f64() })
            })
            .collect();
        json!({
            "type": "hello",
            "role": role.word(),
            "arena": { "x": self.arena.0, "y": self.arena.1 },
            "body": body,
            "wheels": wheels,
            "lidars": lidars,
            "refresh_ms": config::teleop::REFRESH_MS,
            "hold_ms": config::teleop::WEB_HOLD_MS,
            "trail_points": config::teleop::WEB_TRAIL_POINTS,
        })
    }

    /// One line from the robot at `now_ms`: the messages for the pages,
    /// and the telemetry row it held (for a recorder).
    pub fn on_line(&mut self, line: &str, now_ms: u64) -> (Vec<Value>, Option<TelemetryRow>) {
        let line = line.trim_end_matches(['\r', '\n']);
        let mut out = Vec::new();
        if let Some((t_ms, p)) = parse_truth(line) {
            out.push(json!({ "type": "truth", "t_ms": t_ms, "pose": pose_json(&p) }));
            return (out, None);
        }
        let added = self.dash.messages_added();
        let row = self.dash.on_line(line, now_ms);
        if let Some(r) = &row {
            out.push(self.row(r));
        } else if telemetry::classify_line(line) == LineKind::Comment {
            self.on_comment(line);
        }
        // what the terminal UI would show (not a refresh's acknowledgement)
        if self.dash.messages_added() != added {
            if let Some(text) = self.dash.messages().last() {
                out.push(json!({ "type": "message", "text": text }));
            }
        }
        (out, row)
    }

    fn on_comment(&mut self, line: &str) {
        if let Some(Fix::Located { pose, sigma_x, sigma_y, ambiguous, .. }) = parse_located(line) {
            let t_ms = self.dash.last_row().map(|r| r.t_ms);
            self.fix = Fix::Located { pose, sigma_x, sigma_y, ambiguous, t_ms };
        } else if line.starts_with("# locate failed") {
            self.fix = Fix::Lost;
        } else if line.starts_with("# ok pose") {
            self.fix = Fix::Set;
        }
    }

    /// The estimate's state: the row's (how sure the estimator is now),
    /// told apart by the robot's last `#` line where the row says unknown
    /// (a failed localization, a typed pose); the spread of the last fix.
    fn estimate(&self, pose: &MapPose, tracking: Tracking) -> Value {
        let state = match (tracking, self.fix) {
            (Tracking::Located, _) => "located",
            (Tracking::Ambiguous, _) => "ambiguous",
            (Tracking::Unknown, Fix::Lost) => "lost",
            (Tracking::Unknown, Fix::Set) => "set",
            (Tracking::Unknown, _) => "unknown",
        };
        let sigma = match self.fix {
            Fix::Located { pose: at, sigma_x, sigma_y, t_ms, .. } => {
                json!({ "x": sigma_x, "y": sigma_y, "at": pose_json(&at), "t_ms": t_ms })
            }
            _ => Value::Null,
        };
        let mut e = pose_json(pose);
        if let Some(o) = e.as_object_mut() {
            o.insert("state".into(), state.into());
            o.insert("sigma".into(), sigma);
            o.insert("hypotheses".into(), Value::Array(Vec::new()));
        }
        e
    }

    fn row(&self, r: &TelemetryRow) -> Value {
        let pose = row_pose(r);
        let mut rays = Vec::new();
        for ((name, color, mount), dmm) in LIDARS.iter().zip([r.front_dmm, r.right_dmm]) {
            let Some(d) = dmm else { continue };
            let (from, to) = mount.beam_f64(pose.x, pose.y, pose.heading_deg.to_radians(), mm(d));
            rays.push(json!({ "lidar": name, "color": color, "from": [from.0, from.1], "to": [to.0, to.1] }));
        }
        let lidar = |raw: Option<u16>, d: Option<i32>| match raw {
            None => Value::Null,
            Some(raw) => json!({ "raw": raw, "mm": d.map(mm) }),
        };
        let f = &r.faults;
        json!({
            "type": "row",
            "t_ms": r.t_ms,
            "estimate": self.estimate(&pose, r.tracking),
            "motion": telemetry::motion_word(r.motion),
            "v": f64::from(r.v_mm_s) / 1000.0,
            "w": f64::from(r.w_mrad_s) / 1000.0,
            "servos": [f64::from(r.left_cmd_centi) / 100.0, f64::from(r.right_cmd_centi) / 100.0],
            "front": lidar(r.front_raw_mm, r.front_dmm),
            "right": lidar(r.right_raw_mm, r.right_dmm),
            "compass": r.compass_mdeg.map(|c| f64::from(c) / 1000.0),
            "mag": r.mag_raw,
            "faults": {
                "bus": f.bus, "timeout": f.timeout, "missing": f.missing,
                "bad_sample": f.bad_sample, "outliers": f.rejected_outliers, "overruns": f.overruns,
            },
            "rays": rays,
        })
    }

    /// The link's and the driver's state at `now_ms`, for a page in `role`.
    pub fn state(&self, now_ms: u64, driver: &Driver, role: Role, pilots: bool) -> Value {
        let d = &self.dash;
        json!({
            "type": "state",
            "role": role.word(),
            "pilot_present": pilots,
            "link": {
                "rows": d.rows(), "errors": d.errors(), "bad": d.bad_lines(),
                "stale": d.stale(now_ms), "waiting": d.last_row().is_none(),
            },
            "drive": {
                "holding": telemetry::motion_word(driver.wanted()),
                "command": driver.command(),
                "last_sent": driver.last_sent(),
                "sent": driver.sent(),
                "level": driver.speeds().level() + 1,
                "levels": driver.speeds().count(),
                "speeds": driver.speeds().describe(),
            },
        })
    }
}
