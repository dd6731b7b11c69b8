//! What the page is told for the robot's lines (`host::web::model`): a
//! row's pose, and its lidar readings as rays that end where the wall was
//! measured (the lidar model's distance is from the reference point along
//! the beam; the geometry is `LidarMount::beam_f64`, replay's too); the uncertainty from the robot's `# located` answer; the
//! simulator's `# truth` lines from `sim::serve`; messages as the terminal
//! UI shows them.

use paperbot::host::web::model::{parse_located, Fix};
use paperbot::host::web::{parse_truth, Live, MapPose, Role};
use paperbot::sim::body::PoseF64;
use paperbot::sim::robot::{Noise, SimConfig, SimRobot};
use paperbot::sim::serve::{truth_line, Server};
use serde_json::Value;

/// A row at (200, 250) mm heading north, the front lidar reading 300.0 mm
/// and the right one 200.0 mm (distances from the reference point).
const ROW: &str = "1000,200.0,250.0,0.000,stop,0.000,0.000,90.00,90.00,310,300.0,210,200.0,,,,,,,,0,0,0,0,1,0,unknown";

fn close(a: &Value, b: f64) -> bool {
    (a.as_f64().unwrap() - b).abs() < 1e-6
}

#[test]
fn a_row_draws_the_pose_and_rays_that_end_at_the_measured_walls() {
    let mut live = Live::new(762.5, 495.0);
    let (msgs, row) = live.on_line(ROW, 0);
    assert!(row.is_some());
    let [m] = &msgs[..] else { panic!("{msgs:?}") };
    assert_eq!(m["type"], "row");
    let e = &m["estimate"];
    assert!(close(&e["x"], 200.0) && close(&e["y"], 250.0) && close(&e["heading"], 0.0), "{e}");
    assert_eq!(e["state"], "unknown");
    assert_eq!(e["hypotheses"], Value::Array(vec![]), "room for the estimator's hypotheses");
    assert_eq!(m["faults"]["outliers"], 1);
    let rays = m["rays"].as_array().unwrap();
    let ray = |name: &str| rays.iter().find(|r| r["lidar"] == name).unwrap();
    // the front lidar sits 50 mm behind the nose, looking north: its beam
    // starts there and ends 300 mm north of the nose
    let front = ray("front");
    assert!(close(&front["from"][0], 150.0) && close(&front["from"][1], 250.0), "{front}");
    assert!(close(&front["to"][0], 500.0) && close(&front["to"][1], 250.0), "{front}");
    // the right lidar sits 53 mm left of the nose, looking east: 200 mm east of the nose
    let right = ray("right");
    assert!(close(&right["from"][0], 200.0) && close(&right["from"][1], 197.0), "{right}");
    assert!(close(&right["to"][0], 200.0) && close(&right["to"][1], 450.0), "{right}");
    // a row without fresh readings has no rays
    let quiet = ROW.replace("310,300.0,210,200.0", ",,,");
    let (msgs, _) = live.on_line(&quiet, 10);
    assert_eq!(msgs[0]["rays"], Value::Array(vec![]));
    assert_eq!(msgs[0]["front"], Value::Null);
}

#[test]
fn the_uncertainty_comes_from_the_fix_and_the_state_follows_the_robot() {
    let line = "# located 212 301 87.500 sigma 6 9 mm, views 3";
    let Some(Fix::Located { pose, sigma_x, sigma_y, ambiguous, .. }) = parse_located(line) else { panic!() };
    assert_eq!((pose.x, pose.y, pose.heading_deg, sigma_x, sigma_y, ambiguous), (212.0, 301.0, 87.5, 6.0, 9.0, false));
    let amb = parse_located("# located 212 301 87.500 sigma 6 9 mm, views 4, ambiguous: more than one place fits");
    assert!(matches!(amb, Some(Fix::Located { ambiguous: true, .. })));
    assert_eq!(parse_located("# located nowhere"), None);

    // the robot's state is the row's `pose` column; the `#` lines add the
    // fix's spread and tell an unknown pose's story
    let mut live = Live::new(762.5, 495.0);
    let state = |live: &mut Live, tracking: &str| {
        let row = ROW.replace(",unknown", &format!(",{tracking}"));
        live.on_line(&row, 0).0[0]["estimate"].clone()
    };
    let (msgs, _) = live.on_line(line, 0);
    assert_eq!(msgs[0]["type"], "message", "the answer is shown too");
    let e = state(&mut live, "located");
    assert_eq!(e["state"], "located");
    assert!(close(&e["sigma"]["x"], 6.0) && close(&e["sigma"]["y"], 9.0) && close(&e["sigma"]["at"]["x"], 212.0));
    assert_eq!(state(&mut live, "ambiguous")["state"], "ambiguous", "the robot's word, whatever the last fix said");
    live.on_line("# locate failed: no fit; the pose is unknown until `pose` or `locate`", 0);
    assert_eq!(state(&mut live, "unknown")["state"], "lost");
    assert_eq!(state(&mut live, "unknown")["sigma"], Value::Null);
    live.on_line("# ok pose 100 100 0.000", 0);
    assert_eq!(state(&mut live, "unknown")["state"], "set");
    assert_eq!(state(&mut live, "located")["state"], "located", "then the readings narrow it");
}

#[test]
fn messages_are_what_the_terminal_shows_and_truth_is_not_a_message() {
    let mut live = Live::new(762.5, 495.0);
    let kinds = |live: &mut Live, line: &str| -> Vec<String> {
        live.on_line(line, 0).0.iter().map(|m| m["type"].as_str().unwrap().to_string()).collect()
    };
    assert_eq!(kinds(&mut live, "# ok fwd 0.137"), ["message"]);
    assert!(kinds(&mut live, "# ok fwd 0.137").is_empty(), "a refresh's acknowledgement");
    assert_eq!(kinds(&mut live, "# err unknown command"), ["message"]);
    assert_eq!(kinds(&mut live, "# err unknown command"), ["message"], "a refusal twice is shown twice");
    assert!(kinds(&mut live, paperbot::control::protocol::telemetry::HEADER).is_empty());
    let (msgs, _) = live.on_line("garbage,1,2", 0);
    assert_eq!(msgs[0]["text"], "? garbage,1,2");
    assert_eq!(kinds(&mut live, "# truth t_ms=5 x_mm=1.5 y_mm=2.0 heading_deg=359.50"), ["truth"]);
    assert_eq!(live.dashboard().messages().count(), 4);
    let hello = live.hello(Role::Viewer);
    assert_eq!(hello["role"], "viewer");
    assert!(close(&hello["arena"]["x"], 762.5) && close(&hello["arena"]["y"], 495.0));
}

#[test]
fn the_simulator_sends_its_true_pose_when_asked() {
    let p = PoseF64::new(123.45, 67.0, (-90f64).to_radians());
    let (t, back) = parse_truth(&truth_line(1500, &p)).unwrap();
    assert_eq!(t, 1500);
    assert!((back.x - p.x).abs() < 0.06 && (back.y - p.y).abs() < 0.06 && (back.heading_deg - 270.0).abs() < 0.01);
    assert_eq!(parse_truth("# truth t_ms=1 x_mm=nan y_mm=0 heading_deg=0"), None);
    // served at 20 Hz of simulated time: one line every 50 ms, at the robot's pose
    let cfg = SimConfig { noise: Noise::OFF, locate_at_power_up: false, ..SimConfig::default() };
    let start = cfg.start;
    let mut server = Server::new(SimRobot::new(cfg)).with_truth(20);
    let mut port = std::io::Cursor::new(Vec::new());
    for _ in 0..100 {
        server.step(&mut port).unwrap();
    }
    let out = String::from_utf8(port.into_inner()).unwrap();
    let truths: Vec<(u32, MapPose)> = out.lines().filter_map(parse_truth).collect();
    assert_eq!(truths.len(), 20, "{out}");
    assert!(truths.windows(2).all(|w| w[1].0 - w[0].0 == 50));
    let start = MapPose { x: start.x, y: start.y, heading_deg: start.theta.to_degrees() };
    assert!(truths.iter().all(|(_, p)| p.distance(&start) < 0.05));
    // without it, none
    let mut plain = Server::new(SimRobot::new(SimConfig::default()));
    let mut port = std::io::Cursor::new(Vec::new());
    plain.step(&mut port).unwrap();
    assert!(!String::from_utf8(port.into_inner()).unwrap().contains("# truth"));
}
