//! Re-acquisition and the arena limit: a run of `REACQUIRE_AFTER` outliers
//! from one sensor makes the estimator take its side (single outliers and
//! shorter runs stay rejected); readings no position in the arena could give
//! never do; the position never leaves the arena by more than `ARENA_MARGIN`.

use crate::common;
use paperbot::config::arena;
use paperbot::config::estimator::{ARENA_MARGIN, REACQUIRE_AFTER};
use paperbot::math::{Angle, Dt, Length, Speed};
use paperbot::model::estimator::{Estimator, Update};
use paperbot::model::measurement::{expected_lidar, Arena, LidarId};
use paperbot::model::{Motion, Pose};

const TICK: Dt = Dt::from_micros_saturating(10_000);

fn deg(d: f64) -> Angle {
    Angle::from_degrees_f64(d)
}

/// An estimator that has settled at `truth` (2 s of exact readings), so its
/// gate is narrow: a few mm, a degree.
fn settled(truth: Pose) -> Estimator {
    let est = common::estimator::settled(truth);
    let s = est.sigma();
    assert!(
        s.x.to_mm_f64() < 3.0 && s.y.to_mm_f64() < 3.0 && f64::from(s.theta.0) * 360.0 / 4_294_967_296.0 < 1.5,
        "{s:?}"
    );
    est
}

fn heading_error_deg(est: &Estimator, truth: Angle) -> f64 {
    f64::from(truth.diff(est.pose().theta)) * 360.0 / 4_294_967_296.0
}

// (at 10 degrees both lidars read square enough to fix both axes; at 30 the
// cones of both meet the east wall first and x is not observable)
#[test]
fn a_run_of_compass_outliers_wins_and_shorter_runs_do_not() {
    let start = Pose::from_mm(380, 250, deg(10.0));
    // (heading the compass insists on, degrees from the estimate)
    for off in [25.0, 41.0, 90.0, 179.0, -60.0] {
        let truth = start.theta.wrapping_add(deg(off));
        let mut est = settled(start);
        // runs one short of the limit, each ended by a reading that agrees
        // with the estimate: all rejected, the heading does not move
        for _ in 0..3 {
            for _ in 1..REACQUIRE_AFTER {
                assert_eq!(est.update_heading(truth), Update::Outlier, "{off}");
            }
            assert_eq!(est.update_heading(est.pose().theta), Update::Accepted);
        }
        assert!(heading_error_deg(&est, start.theta).abs() < 0.5, "{off}");
        assert_eq!(est.stats().compass.reacquired, 0);
        // a full run: the last reading is taken, the heading follows it
        for i in 1..=REACQUIRE_AFTER {
            let u = est.update_heading(truth);
            assert_eq!(u, if i < REACQUIRE_AFTER { Update::Outlier } else { Update::Accepted }, "{off} {i}");
        }
        let e = heading_error_deg(&est, truth);
        assert!(e.abs() < 0.5, "{off}: still {e} deg off");
        let st = est.stats();
        assert_eq!((st.compass.reacquired, st.compass.outliers), (1, 4 * u32::from(REACQUIRE_AFTER - 1)), "{st:?}");
        // the next reading agrees
        assert_eq!(est.update_heading(truth), Update::Accepted);
        // the position did not move (its correlation with the heading was dropped)
        let p = est.pose();
        assert!((p.x.to_mm_f64() - 380.0).abs() < 0.5 && (p.y.to_mm_f64() - 250.0).abs() < 0.5, "{off}: {p:?}");
    }
}

#[test]
fn a_run_of_lidar_outliers_moves_the_position() {
    // facing north: the front lidar reads the north wall (x), the right one the east wall (y)
    let believed = Pose::from_mm(300, 250, deg(0.0));
    for (dx, dy) in [(100, 0), (-150, 0), (0, 80), (60, -120)] {
        let truth = Pose::from_mm(300 + dx, 250 + dy, deg(0.0));
        let mut est = settled(believed);
        for i in 1..=REACQUIRE_AFTER {
            // both lidars disagree, each counting its own run
            for id in [LidarId::Front, LidarId::Right] {
                let z = expected_lidar(&Arena::DEFAULT, &truth, id).unwrap();
                let want = if (id == LidarId::Front && dx == 0) || (id == LidarId::Right && dy == 0) {
                    Update::Accepted
                } else if i < REACQUIRE_AFTER {
                    Update::Outlier
                } else {
                    Update::Accepted
                };
                assert_eq!(est.update_lidar(id, z), want, "{dx} {dy} {id:?} {i}");
            }
        }
        let p = est.pose();
        let (ex, ey) = (p.x.to_mm_f64() - (300 + dx) as f64, p.y.to_mm_f64() - (250 + dy) as f64);
        assert!(ex.abs() < 2.0 && ey.abs() < 2.0, "{dx} {dy}: off by {ex} {ey}");
        assert!(heading_error_deg(&est, truth.theta).abs() < 0.5);
        let st = est.stats();
        // the front lidar's re-acquisition re-inflates both axes: the right
        // lidar's reading of the same round then passes the wide gate
        let right = dy != 0 && dx == 0;
        assert_eq!((st.front.reacquired, st.right.reacquired), (u32::from(dx != 0), u32::from(right)), "{st:?}");
    }
}

#[test]
fn readings_no_position_in_the_arena_gives_never_win() {
    let truth = Pose::from_mm(300, 250, deg(0.0));
    let mut est = settled(truth);
    // the front lidar looks north from x = 300: a reading past the whole
    // box's length, or negative (a lidar against an obstacle inside the
    // car's own setback), is no evidence the position is lost
    for z in [900.0, 2000.0, -30.0] {
        for _ in 0..3 * u32::from(REACQUIRE_AFTER) {
            assert_eq!(est.update_lidar(LidarId::Front, Length::from_mm_f64(z)), Update::Outlier, "{z}");
            est.update_heading(truth.theta);
        }
    }
    assert_eq!(est.stats().front.reacquired, 0);
    assert!((est.pose().x.to_mm_f64() - 300.0).abs() < 1.0, "{:?}", est.pose());
}

#[test]
fn the_position_stays_within_the_margin_of_the_arena() {
    // the bounds in whole mm, rounded inward (812 x 545 mm, from -50)
    let m = ARENA_MARGIN.to_mm_f64().floor();
    let (lx, wy) = ((arena::LENGTH_X.to_mm_f64() + m).floor() - m, (arena::WIDTH_Y.to_mm_f64() + m).floor() - m);
    // driving on blind for 20 s in each direction (a body held at a wall)
    for (heading, v, want_x, want_y) in [
        (0.0, 150, Some(lx + m), None),
        (0.0, -150, Some(-m), None),
        (90.0, 150, None, Some(wy + m)),
        (270.0, 150, None, Some(-m)),
        (45.0, 150, Some(lx + m), Some(wy + m)),
    ] {
        let mut est = Estimator::new(Pose::from_mm(380, 250, deg(heading)));
        for _ in 0..2_000 {
            est.predict(Motion::Straight(Speed::from_mm_s(v)), TICK);
        }
        let p = est.pose();
        let (x, y) = (p.x.to_mm_f64(), p.y.to_mm_f64());
        assert!(x >= -m && x <= lx + m && y >= -m && y <= wy + m, "{heading} {v}: {x} {y}");
        if let Some(wx) = want_x {
            assert!((x - wx).abs() < 1e-3, "{heading} {v}: x {x}");
        }
        if let Some(wy) = want_y {
            assert!((y - wy).abs() < 1e-3, "{heading} {v}: y {y}");
        }
    }
    // a start outside is brought to the edge; so is a reset
    let mut est = Estimator::new(Pose::from_mm(2_000, -300, deg(0.0)));
    assert_eq!((est.pose().x.to_mm_f64(), est.pose().y.to_mm_f64()), (lx + m, -m));
    est.reset(Pose::from_mm(-5_000, 9_000, deg(0.0)));
    assert_eq!((est.pose().x.to_mm_f64(), est.pose().y.to_mm_f64()), (-m, wy + m));
}

/// The integer square roots behind the one-sigma telemetry figures.
#[test]
fn integer_square_roots_are_floors() {
    use paperbot::math::{isqrt, isqrt64};
    let mut rng = paperbot::sim::noise::Rng::new(99);
    let mut xs: Vec<u64> = vec![0, 1, 2, 3, 4, 15, 16, 17, u64::from(u32::MAX), u64::MAX, (1 << 62) - 1, 1 << 62];
    for _ in 0..100_000 {
        xs.push(rng.next_u64() >> (rng.next_u64() % 64));
    }
    for x in xs {
        let r = u64::from(isqrt64(x));
        assert!(r * r <= x && (r + 1).checked_mul(r + 1).is_none_or(|s| s > x), "isqrt64({x}) = {r}");
        if let Ok(x32) = u32::try_from(x) {
            assert_eq!(u64::from(isqrt(x32)), r, "isqrt({x32})");
        }
    }
}
