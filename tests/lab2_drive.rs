//! The real drive (`tests/data/lab2/drive1.csv`, see its README) replayed
//! with no start pose, as the robot would run it: localization from the
//! first readings, then the estimator. No ground truth exists, so the test
//! asks for plausibility.

use paperbot::model::estimator::replay;
use paperbot::model::measurement::Arena;

#[test]
fn the_real_drive_replays_plausibly_with_no_start_pose() {
    let text = std::fs::read_to_string("tests/data/lab2/drive1.csv").unwrap();
    let samples = replay::parse(&text).unwrap();
    assert_eq!(samples.len(), 61);
    let arena = Arena::DEFAULT;
    let fix = replay::locate_start(&samples, arena).expect("the first readings locate the robot");
    let (est, stats) = replay::replay(&samples, replay::Start::Fix(fix), arena);
    let (lx, wy) = (arena.length_x.to_mm_f64(), arena.width_y.to_mm_f64());
    let mut worst_step: f64 = f64::MIN;
    for (i, e) in est.iter().enumerate() {
        let (x, y) = (e.pose.x.to_mm_f64(), e.pose.y.to_mm_f64());
        assert!((0.0..=lx).contains(&x) && (0.0..=wy).contains(&y), "row {i}: ({x:.1}, {y:.1}) outside the box");
    }
    for (i, w) in est.windows(2).enumerate() {
        let (a, b) = (&w[0], &w[1]);
        let step = (b.pose.x.to_mm_f64() - a.pose.x.to_mm_f64()).hypot(b.pose.y.to_mm_f64() - a.pose.y.to_mm_f64());
        let allowed = 0.30 * f64::from(b.t_ms - a.t_ms) + 25.0; // 0.30 m/s = 0.30 mm/ms
        worst_step = worst_step.max(step - allowed);
        assert!(step <= allowed, "rows {i}-{}: {step:.1} mm in {} ms (allowed {allowed:.1})", i + 1, b.t_ms - a.t_ms);
    }
    let compass = samples[0].heading.unwrap();
    let first = est[0].pose.theta;
    let off = f64::from(first.diff(compass)) * 360.0 / 4_294_967_296.0;
    println!(
        "drive1: located at ({:.0}, {:.0}) mm, {:.1} deg ({} points, ambiguous {}); first heading {off:.1} deg from the compass; \
         largest step {worst_step:.1} mm within its allowance; front {:?}, right {:?}",
        fix.pose.x.to_mm_f64(),
        fix.pose.y.to_mm_f64(),
        first.to_radians_f64().to_degrees(),
        fix.points,
        fix.ambiguous,
        stats.front,
        stats.right,
    );
    assert!(off.abs() <= 15.0, "first heading {off:.1} deg from the compass");
}
