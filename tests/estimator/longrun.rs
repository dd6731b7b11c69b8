//! Hours of operation: the covariance stays symmetric (by storage) and
//! positive definite (f64 Cholesky after every tick), bounded, and the
//! estimate keeps tracking; then an hour standing still (compass at 100 Hz,
//! no process noise but the floors) must not collapse the covariance.

use crate::common;
use common::estimator::*;
use paperbot::model::estimator::{Covariance, Estimator, N};

/// Smallest pivot of the f64 Cholesky factorisation (negative if `P` is
/// not positive definite).
fn min_pivot(p: &Covariance) -> f64 {
    let m: Vec<Vec<f64>> = (0..N).map(|i| (0..N).map(|j| f64::from(p.get(i, j))).collect()).collect();
    let mut l = vec![vec![0.0f64; N]; N];
    let mut min = f64::INFINITY;
    for i in 0..N {
        for j in 0..=i {
            let s: f64 = (0..j).map(|k| l[i][k] * l[j][k]).sum();
            if i == j {
                let d = m[i][i] - s;
                min = min.min(d);
                l[i][i] = d.max(1e-300).sqrt();
            } else {
                l[i][j] = (m[i][j] - s) / l[j][j];
            }
        }
    }
    min
}

fn check(est: &Estimator, worst: &mut f64) {
    let p = est.covariance();
    let piv = min_pivot(&p);
    *worst = worst.min(piv);
    assert!(piv > 0.0, "not positive definite: {p:?}");
    for d in est.covariance_diagonal() {
        assert!(d > 0 && d <= 1 << 28, "{p:?}");
    }
}

#[test]
fn two_hours_of_driving_keep_the_covariance_valid_and_the_estimate_on_track() {
    let mut sc = Scenario::new(7);
    sc.seconds = 2.0 * 3600.0;
    sc.lidar_outlier_p = 0.02;
    sc.compass_outlier_p = 0.02;
    let mut worst = f64::INFINITY;
    let res = run(&sc, |_, est, _| check(est, &mut worst));
    let (e, d) = (rms(&res.est, 0.0), rms(&res.dr, 0.0));
    let (m_pos, m_deg) = max_err(&res.est, 10.0, f64::INFINITY);
    println!(
        "2 h drive: estimator {:.2} mm / {:.2} deg rms (max {m_pos:.1} mm / {m_deg:.1} deg); dead reckoning {:.0} mm / {:.0} deg rms; smallest Cholesky pivot {worst:.0} (Q14 mm^2); {:?}",
        e.0, e.1, d.0, d.1, res.stats
    );
    assert!(res.min_wall_clearance > 50.0);
    assert!(e.0 < 15.0 && e.1 < 2.0);
    assert!(m_pos < 40.0 && m_deg < 10.0);
    assert_eq!(res.stats.unwrap().repairs, 0);
}

#[test]
fn an_hour_standing_still_does_not_collapse_the_covariance() {
    let (lx, wy) = (762.5, 495.0);
    let truth = PoseF64 { x: 300.0, y: 200.0, theta: 30f64.to_radians() };
    let mut est = Estimator::new(truth.to_pose());
    let mut rng = Rng::new(9);
    let dt = paperbot::math::Dt::from_micros(10_000).unwrap();
    let mut worst = f64::INFINITY;
    let mut min_var = i32::MAX;
    for tick in 0..(3600 * 100) {
        est.predict(paperbot::model::Motion::Stop, dt);
        if tick % 3 == 0 {
            for (which, model, mount) in [
                (
                    paperbot::model::measurement::LidarId::Front,
                    &paperbot::config::lidar::FRONT,
                    &paperbot::config::geometry::FRONT_LIDAR,
                ),
                (
                    paperbot::model::measurement::LidarId::Right,
                    &paperbot::config::lidar::RIGHT,
                    &paperbot::config::geometry::RIGHT_LIDAR,
                ),
            ] {
                let z = true_range(truth, mount, lx, wy);
                let reading = (raw_reading(model, z) + 1.6 * rng.normal()).round() as u16;
                if let Some(d) = model.range(reading).distance() {
                    est.update_lidar(which, d);
                }
            }
        }
        let h = truth.theta.to_degrees() + 2.5 * rng.normal();
        est.update_heading(paperbot::math::Angle::from_degrees_f64(h));
        check(&est, &mut worst);
        min_var = min_var.min(est.covariance_diagonal().into_iter().min().unwrap());
    }
    let p = est.pose();
    let (ex, ey) = (p.x.to_mm_f64() - truth.x, p.y.to_mm_f64() - truth.y);
    let eth = wrap(p.theta.to_radians_f64() - truth.theta).to_degrees();
    println!("1 h still: error {ex:.2}, {ey:.2} mm, {eth:.3} deg; sigma {:?}; smallest variance {min_var} (Q14 mm^2); smallest pivot {worst:.0}; {:?}", est.sigma(), est.stats());
    assert!(ex.abs() < 2.0 && ey.abs() < 2.0 && eth.abs() < 0.5);
    // the floors keep every variance well above the Q14 resolution
    assert!(min_var > 500, "{min_var}");
    assert_eq!(est.stats().repairs, 0);
}
