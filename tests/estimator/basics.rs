//! The estimator on a simulated 60 s drive in the arena, with the lab's
//! measured noise: tracking accuracy against dead reckoning, recovery from a
//! wrong start, a lidar dropout, outlier gating.

use crate::common;
use common::estimator::*;
use paperbot::model::measurement::LidarId;

const SEEDS: [u64; 6] = [1, 2, 3, 4, 5, 6];
const MAX_RMS_MM: f64 = 15.0;
const MAX_RMS_DEG: f64 = 2.0;

fn report(name: &str, seed: u64, res: &RunResult, from_s: f64) -> ((f64, f64), (f64, f64)) {
    let e = rms(&res.est, from_s);
    let d = rms(&res.dr, from_s);
    let b = rms(&res.best, from_s);
    println!(
        "{name} seed {seed}: estimator {:.2} mm / {:.2} deg rms (best hypothesis {:.2} mm); dead reckoning {:.1} mm / {:.1} deg rms; stats {:?}",
        e.0, e.1, b.0, d.0, d.1, res.stats
    );
    (e, d)
}

#[test]
fn lab_spread_is_what_the_config_assumes() {
    let s = lab_spread();
    println!("lab spread: {s:?}");
    // the config takes the larger of the straight and of the turn spreads
    let straight = s.forward.max(s.backward);
    let turn = s.cw.max(s.ccw);
    assert!((paperbot::config::estimator::SPEED_SPREAD - straight).abs() < 0.002, "{straight}");
    assert!((paperbot::config::estimator::TURN_SPREAD - turn).abs() < 0.002, "{turn}");
}

#[test]
fn tracks_a_60s_drive_much_better_than_dead_reckoning() {
    for seed in SEEDS {
        let res = run(&Scenario::new(seed), |_, _, _| {});
        let (e, d) = report("drive", seed, &res, 0.0);
        assert!(res.min_wall_clearance > 50.0, "the drive left the arena: {}", res.min_wall_clearance);
        assert!(e.0 < MAX_RMS_MM && e.1 < MAX_RMS_DEG, "seed {seed}: {e:?}");
        assert!(d.0 > 2.0 * e.0, "dead reckoning should be much worse: {d:?} vs {e:?}");
        let st = res.stats.unwrap();
        assert_eq!(st.repairs, 0);
        assert!(st.front.accepted > 1000 && st.right.accepted > 1000 && st.compass.accepted > 5000, "{st:?}");
    }
}

#[test]
fn recovers_from_a_start_100mm_and_20deg_off() {
    for seed in SEEDS {
        let ang = seed as f64 * 1.1;
        let mut sc = Scenario::new(seed);
        sc.start_error = (100.0 * ang.cos(), 100.0 * ang.sin(), if seed % 2 == 0 { 20.0 } else { -20.0 });
        let res = run(&sc, |_, _, _| {});
        // dead reckoning starts from the same wrong pose
        let first = res.dr.first().unwrap();
        assert!(first.1 > 95.0 && first.2.abs() > 19.0, "the start really was off: {first:?}");
        let (e, _) = report("wrong start", seed, &res, 5.0);
        assert!(e.0 < MAX_RMS_MM && e.1 < MAX_RMS_DEG, "seed {seed}: {e:?}");
        let (m_pos, m_deg) = max_err(&res.est, 5.0, 60.0);
        assert!(m_pos < 40.0 && m_deg < 8.0, "seed {seed}: after 5 s max error {m_pos} mm {m_deg} deg");
    }
}

#[test]
fn survives_a_lidar_dropping_out_for_5s() {
    for seed in SEEDS {
        for which in [LidarId::Front, LidarId::Right] {
            let mut sc = Scenario::new(seed);
            sc.dropouts.push((which, 20.0, 25.0));
            let res = run(&sc, |_, _, _| {});
            let (e, _) = report(&format!("{which:?} out 20..25 s"), seed, &res, 0.0);
            assert!(e.0 < MAX_RMS_MM && e.1 < MAX_RMS_DEG, "seed {seed}: {e:?}");
            let (m_pos, _) = max_err(&res.est, 20.0, 25.0);
            let (m_after, _) = max_err(&res.est, 27.0, 60.0);
            println!("  max error during the dropout {m_pos:.1} mm, after it {m_after:.1} mm");
            assert!(m_pos < 50.0 && m_after < 40.0, "seed {seed} {which:?}: {m_pos} {m_after}");
        }
    }
}

#[test]
fn both_lidars_out_for_5s_falls_back_to_dead_reckoning_and_recovers() {
    for seed in SEEDS {
        let mut sc = Scenario::new(seed);
        sc.dropouts.push((LidarId::Front, 20.0, 25.0));
        sc.dropouts.push((LidarId::Right, 20.0, 25.0));
        let mut sigma_at_25 = 0.0;
        let res = run(&sc, |t, est, _| {
            if (t - 24.99).abs() < 0.005 {
                sigma_at_25 = est.sigma().x.to_mm_f64().max(est.sigma().y.to_mm_f64());
            }
        });
        let (e, _) = report("both out 20..25 s", seed, &res, 30.0);
        assert!(sigma_at_25 > 5.0, "the uncertainty grows without lidars: {sigma_at_25}");
        assert!(e.0 < MAX_RMS_MM && e.1 < MAX_RMS_DEG, "seed {seed}: {e:?}");
    }
}

#[test]
fn gates_and_counts_outliers() {
    for seed in SEEDS {
        let mut sc = Scenario::new(seed);
        sc.lidar_outlier_p = 0.05;
        sc.compass_outlier_p = 0.05;
        let res = run(&sc, |_, _, _| {});
        let (e, _) = report("5% outliers", seed, &res, 0.0);
        let st = res.stats.unwrap();
        let lidar_out = st.front.outliers + st.right.outliers;
        println!(
            "  injected {} lidar / {} compass outliers; rejected {} / {}",
            res.injected_lidar_outliers, res.injected_compass_outliers, lidar_out, st.compass.outliers
        );
        // every disturbed compass reading is 30..90 degrees off: all caught;
        // a spurious lidar reading can land near the truth by chance.
        assert!(st.compass.outliers >= res.injected_compass_outliers, "{st:?}");
        assert!(st.compass.outliers <= res.injected_compass_outliers + 60, "{st:?}");
        assert!(f64::from(lidar_out) > 0.7 * f64::from(res.injected_lidar_outliers), "{st:?}");
        assert!(e.0 < MAX_RMS_MM && e.1 < MAX_RMS_DEG, "seed {seed}: {e:?}");
    }
}
