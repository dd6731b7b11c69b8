//! The real drive (`tests/data/lab2/drive1.csv`, see its README) replayed
//! with no start pose, as the robot would run it: localization from the
//! first readings, then the estimator. No ground truth exists, so the tests
//! ask for plausibility, on the drive and on variants built from it that
//! nobody tuned to (issue #29): the compass offset by +-10 degrees, stops
//! of 0.5 to 2 s inserted (the robot stands, its sensors read the same),
//! every other row dropped, starts at later rows.
//!
//! The invariants, on every variant: while the servos stand still the
//! reported position moves at most 10 mm; between consecutive rows it never
//! moves more than the wheels can drive (0.30 m/s) plus 25 mm; every
//! reported pose lies in the box.
//!
//! The test prints every variant's result and asserts them all. (The
//! one-hypothesis estimator with re-acquisition broke three: the compass
//! at -10 degrees jumped 46.9 mm between rows against 44.5 allowed, and
//! both halved drives 68-70 mm against 64.)

use paperbot::config;
use paperbot::math::Angle;
use paperbot::model::estimator::replay::{self, Estimate, Sample};
use paperbot::model::measurement::Arena;
use paperbot::model::Motion;

/// Between rows the position moves at most what the wheels can drive,
/// 0.30 mm per ms (the protocol's fastest, `config::serial::MAX_SPEED_MM_S`),
/// plus this, mm.
const STEP_SLACK_MM: f64 = 25.0;
/// While the servos stand still it moves at most this, mm.
const STANDSTILL_MM: f64 = 10.0;

fn drive1() -> Vec<Sample> {
    let text = std::fs::read_to_string("tests/data/lab2/drive1.csv").unwrap();
    replay::parse(&text).unwrap()
}

/// `rows` with the compass turned by `degrees`.
fn compass_offset(rows: &[Sample], degrees: f64) -> Vec<Sample> {
    let off = Angle::from_degrees_f64(degrees);
    rows.iter().map(|s| Sample { heading: s.heading.map(|h| h.wrapping_add(off)), ..*s }).collect()
}

/// `rows` with the robot standing `ms` after row `at`: rows every 65 ms
/// (the log's period) with the servos at neutral and the sensors reading
/// what they read at row `at`; the later rows come that much later.
fn stop_after(rows: &[Sample], at: usize, ms: u32) -> Vec<Sample> {
    let m = &config::actuators::MODEL;
    let period = 65;
    let mut out: Vec<Sample> = rows[..=at].to_vec();
    let last = rows[at];
    let standing = Sample { left: m.left_neutral(), right: m.right_neutral(), ..last };
    let n = ms / period;
    for k in 1..=n {
        out.push(Sample { t_ms: last.t_ms + k * period, ..standing });
    }
    let shift = (n + 1) * period;
    out.extend(rows[at + 1..].iter().map(|s| Sample { t_ms: s.t_ms + shift, ..*s }));
    out
}

/// The variants (see the module docs), by name.
fn variants() -> Vec<(String, Vec<Sample>)> {
    let rows = drive1();
    let mut v = vec![("drive1".to_string(), rows.clone())];
    for deg in [10.0, -10.0] {
        v.push((format!("compass {deg:+.0} deg"), compass_offset(&rows, deg)));
    }
    for (at, ms) in [(15, 500), (30, 1_000), (45, 2_000)] {
        v.push((format!("stop {ms} ms after row {at}"), stop_after(&rows, at, ms)));
    }
    v.push((
        "stops of 0.5, 1 and 2 s".into(),
        stop_after(&stop_after(&stop_after(&rows, 45, 2_000), 30, 1_000), 15, 500),
    ));
    v.push(("every other row dropped".into(), rows.iter().step_by(2).copied().collect()));
    v.push(("every other row dropped, from row 1".into(), rows.iter().skip(1).step_by(2).copied().collect()));
    for from in [10, 20, 30] {
        v.push((format!("starts at row {from}"), rows[from..].to_vec()));
    }
    v.push(("compass +10 deg, stopping 1 s after row 30".into(), stop_after(&compass_offset(&rows, 10.0), 30, 1_000)));
    v
}

/// The replay of `rows` from the localization of its first readings: its
/// estimates, or why there are none.
fn replayed(rows: &[Sample]) -> Result<Vec<Estimate>, String> {
    let arena = Arena::DEFAULT;
    let fix = replay::locate_start(rows, arena).map_err(|e| format!("no start: {e:?}"))?;
    Ok(replay::replay(rows, replay::Start::Fix(fix), arena).0)
}

/// The invariants' violations on one replay (none: kept).
fn violations(rows: &[Sample], est: &[Estimate]) -> Vec<String> {
    let arena = Arena::DEFAULT;
    let (lx, wy) = (arena.length_x.to_mm_f64(), arena.width_y.to_mm_f64());
    let at = |e: &Estimate| (e.pose.x.to_mm_f64(), e.pose.y.to_mm_f64());
    let mut out = vec![];
    for (i, e) in est.iter().enumerate() {
        let (x, y) = at(e);
        if !((0.0..=lx).contains(&x) && (0.0..=wy).contains(&y)) {
            out.push(format!("row {i}: ({x:.1}, {y:.1}) outside the box"));
        }
    }
    for (i, w) in est.windows(2).enumerate() {
        let ((ax, ay), (bx, by)) = (at(&w[0]), at(&w[1]));
        let step = (bx - ax).hypot(by - ay);
        let allowed =
            f64::from(config::serial::MAX_SPEED_MM_S) / 1000.0 * f64::from(w[1].t_ms - w[0].t_ms) + STEP_SLACK_MM;
        if step > allowed {
            out.push(format!("rows {i}-{}: moved {step:.1} mm (allowed {allowed:.1})", i + 1));
        }
    }
    // standing: the servos' commands stop the wheels from one row to the
    // next (the row's commands drive until the next row)
    let mut anchor: Option<(usize, (f64, f64))> = None;
    for (i, w) in rows.windows(2).enumerate() {
        let stands = config::actuators::MODEL.motion_from_commands(w[0].left, w[0].right) == Motion::Stop;
        if !stands {
            anchor = None;
            continue;
        }
        let (a, (ax, ay)) = *anchor.get_or_insert((i, at(&est[i])));
        let (x, y) = at(&est[i + 1]);
        let moved = (x - ax).hypot(y - ay);
        if moved > STANDSTILL_MM {
            out.push(format!("rows {a}-{}: moved {moved:.1} mm standing still", i + 1));
        }
    }
    out
}

#[test]
fn drive1_and_its_variants_keep_the_invariants() {
    let mut failed = vec![];
    for (name, rows) in variants() {
        let result = replayed(&rows).map(|est| violations(&rows, &est));
        match &result {
            Ok(v) if v.is_empty() => println!("{name:45} {} rows: invariants kept", rows.len()),
            Ok(v) => println!("{name:45} {} rows: {} broken, first: {}", rows.len(), v.len(), v[0]),
            Err(e) => println!("{name:45} {} rows: {e}", rows.len()),
        }
        if !matches!(&result, Ok(v) if v.is_empty()) {
            failed.push(name);
        }
    }
    assert!(failed.is_empty(), "variants that break the invariants: {failed:?}");
}

/// The drive itself: the first heading follows the compass, and what the
/// localization found.
#[test]
fn the_real_drive_replays_plausibly_with_no_start_pose() {
    let samples = drive1();
    assert_eq!(samples.len(), 61);
    let arena = Arena::DEFAULT;
    let fix = replay::locate_start(&samples, arena).expect("the first readings locate the robot");
    let (est, stats) = replay::replay(&samples, replay::Start::Fix(fix), arena);
    assert!(violations(&samples, &est).is_empty());
    let compass = samples[0].heading.unwrap();
    let first = est[0].pose.theta;
    let off = f64::from(first.diff(compass)) * 360.0 / 4_294_967_296.0;
    println!(
        "drive1: located at ({:.0}, {:.0}) mm, {:.1} deg ({} points, ambiguous {}, {} clusters); first heading {off:.1} deg \
         from the compass; front {:?}, right {:?}",
        fix.pose.x.to_mm_f64(),
        fix.pose.y.to_mm_f64(),
        first.to_radians_f64().to_degrees(),
        fix.points,
        fix.ambiguous,
        fix.clusters().len(),
        stats.front,
        stats.right,
    );
    assert!(off.abs() <= 15.0, "first heading {off:.1} deg from the compass");
}

/// `replay`'s agreement figures (`host::replay_stats`): from the drive's
/// own localization the estimate accepts most readings and is not lost;
/// started at a wrong pose with the fix's certainty it is reported lost
/// (the estimator still accepts most of the readings, so it is their
/// disagreement that says so): while it is wrong its readings disagree
/// more than twice as much. Its readings bring it back: it ends within 30
/// mm of the located replay (116 mm off before readings near a corner
/// carried their heading's uncertainty, `config::estimator::CORNER_SIGMAS`).
#[test]
fn replay_says_how_the_estimate_agrees_with_its_readings() {
    use paperbot::host::replay_stats::agreement;
    use paperbot::math::{Coord, Length};
    let rows = drive1();
    let arena = Arena::DEFAULT;
    let fix = replay::locate_start(&rows, arena).unwrap();
    let (good_est, good_stats) = replay::replay(&rows, replay::Start::Fix(fix), arena);
    let good = agreement(&rows, &good_est, &good_stats, &arena);
    let wrong = paperbot::model::Pose::new(
        Coord::from_length(Length::from_mm(600)),
        Coord::from_length(Length::from_mm(100)),
        Angle::from_degrees_f64(150.0),
    );
    // the fix's certainty at a wrong place: confident and wrong
    let mut confident = fix;
    confident.pose = wrong;
    let (est, stats) = replay::replay(&rows, replay::Start::Fix(confident), arena);
    let lost = agreement(&rows, &est, &stats, &arena);
    // while the wrong start is still wrong: the rows before it first comes
    // within 50 mm of the located one
    let apart = |a: &replay::Estimate, b: &replay::Estimate| {
        (a.pose.x.to_mm_f64() - b.pose.x.to_mm_f64()).hypot(a.pose.y.to_mm_f64() - b.pose.y.to_mm_f64())
    };
    let wrong_rows = good_est.iter().zip(&est).position(|(g, l)| apart(g, l) <= 50.0).unwrap_or(rows.len());
    assert!(wrong_rows >= 10, "the wrong start was right after {wrong_rows} rows");
    let early_good = agreement(&rows[..wrong_rows], &good_est[..wrong_rows], &good_stats, &arena);
    let early_lost = agreement(&rows[..wrong_rows], &est[..wrong_rows], &stats, &arena);
    for (name, a) in [
        ("located", &good),
        ("wrong start", &lost),
        ("while wrong, located", &early_good),
        ("while wrong, wrong", &early_lost),
    ] {
        println!(
            "{name}: {:.0} % accepted; mean normalised innovation front {:.1}, right {:.1}; lost {}",
            100.0 * a.accepted_share(),
            a.front.mean_normalised,
            a.right.mean_normalised,
            a.lost()
        );
    }
    assert!(!good.lost() && good.accepted_share() > 0.7);
    assert!(lost.lost(), "a wrong start is lost");
    println!(
        "its first {wrong_rows} rows: mean normalised innovation {:.1} located, {:.1} wrong",
        early_good.mean_normalised(),
        early_lost.mean_normalised()
    );
    // the right lidar says it: the located estimate explains it (a mean
    // normalised innovation near 4), the wrong one does not; drive1's
    // front fits poorly even located (about 22, open: the real drive's
    // front readings are not all of the box's walls), so the two lidars'
    // mean says it less (38.3 against 14.0 before a reading's age was
    // modelled, 20.9 against 14.1 since: the wrong start's path changed)
    assert!(early_lost.right.mean_normalised > 2.0 * early_good.right.mean_normalised);
    assert!(early_lost.mean_normalised() > early_good.mean_normalised());
    // ... and its readings bring it back: it ends where the located one does
    let end = apart(good_est.last().unwrap(), est.last().unwrap());
    println!("the wrong start ends {end:.1} mm from the located one");
    assert!(end <= 30.0);
}
