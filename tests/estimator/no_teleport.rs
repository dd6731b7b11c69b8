//! No teleports: every correction, accepted through the gate or re-acquiring
//! after a run of outliers, moves the state `(x, y, L theta)` by a step
//! with `step^T P^-1 step <= gate^2`, `P` the covariance the correction
//! starts from (for a re-acquisition: after its re-inflation, computed here
//! from the config). A lost estimate walks back to the sensors in such
//! steps.

use crate::common;
use common::estimator::{true_range, wrap, PoseF64, Rng};
use paperbot::config::arena;
use paperbot::config::estimator::{ARENA_MARGIN, GATE_SIGMAS, MAX_VARIANCE_MM2, REACQUIRE_SIGMA_MM};
use paperbot::math::{Angle, Dt, Length, Speed, TurnRate};
use paperbot::model::estimator::{Covariance, Estimator, EstimatorStats, LidarId, Update, HEADING_LEVER_MM};
use paperbot::model::measurement::{expected_lidar, Arena};
use paperbot::model::{Motion, Pose};
use std::f64::consts::TAU;

const TICK: Dt = Dt::from_micros_saturating(10_000);
/// Q14 mm^2 per mm^2.
const Q14: f64 = 16384.0;

fn reacquired(s: &EstimatorStats) -> u32 {
    s.front.reacquired + s.right.reacquired + s.compass.reacquired
}

/// The covariance a correction starts from, mm^2: `before`, re-inflated as
/// the estimator does when the correction re-acquires (`lidar`: the
/// position's variances to at least the re-acquisition's, the compass: the
/// heading's to the cap; correlations with what is re-inflated dropped).
fn start_covariance(before: Covariance, reacquiring: Option<bool>) -> [[f64; 3]; 3] {
    let mut p = before;
    match reacquiring {
        Some(true) => {
            let v = (REACQUIRE_SIGMA_MM * REACQUIRE_SIGMA_MM * Q14).round() as i32;
            (p.xx, p.yy, p.xy, p.xt, p.yt) = (p.xx.max(v), p.yy.max(v), 0, 0, 0);
        }
        Some(false) => (p.tt, p.xt, p.yt) = ((MAX_VARIANCE_MM2 * Q14).round() as i32, 0, 0),
        None => {}
    }
    let f = |v: i32| f64::from(v) / Q14;
    [[f(p.xx), f(p.xy), f(p.xt)], [f(p.xy), f(p.yy), f(p.yt)], [f(p.xt), f(p.yt), f(p.tt)]]
}

/// `d^T P^-1 d` by an f64 Cholesky factorisation of `P` (positive definite:
/// the estimator keeps its variances above a floor).
fn mahalanobis_sq(p: [[f64; 3]; 3], d: [f64; 3]) -> f64 {
    let mut l = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..=i {
            let s = p[i][j] - (0..j).map(|k| l[i][k] * l[j][k]).sum::<f64>();
            l[i][j] = if i == j { s.max(1e-12).sqrt() } else { s / l[j][j] };
        }
    }
    // solve L w = d: d^T P^-1 d = |w|^2
    let mut w = [0.0; 3];
    for i in 0..3 {
        w[i] = (d[i] - (0..i).map(|k| l[i][k] * w[k]).sum::<f64>()) / l[i][i];
    }
    w.iter().map(|v| v * v).sum()
}

/// One correction's outcome: its result, whether it re-acquired, its step's
/// `sqrt(step^T P^-1 step)` (sigmas) and the position step, mm.
struct Checked {
    update: Update,
    reacquired: bool,
    sigmas: f64,
    step_mm: f64,
    /// Ends on the arena's limit (see [`checked`]).
    limited: bool,
}

fn checked(est: &mut Estimator, correct: impl FnOnce(&mut Estimator) -> Update, lidar: bool) -> Checked {
    let (before, p0, n0) = (est.pose(), est.covariance(), reacquired(&est.stats()));
    let update = correct(est);
    let after = est.pose();
    let reacquired = reacquired(&est.stats()) > n0;
    let p = start_covariance(p0, reacquired.then_some(lidar));
    let l = f64::from(HEADING_LEVER_MM);
    let d = [
        after.x.to_mm_f64() - before.x.to_mm_f64(),
        after.y.to_mm_f64() - before.y.to_mm_f64(),
        l * f64::from(after.theta.diff(before.theta)) * TAU / 4_294_967_296.0,
    ];
    let sigmas = mahalanobis_sq(p, d).sqrt();
    // the estimator keeps the position within the arena's margin after
    // every step, a projection apart from the correction: a step that ends
    // on that limit is not the correction's alone
    let (m, x, y) = (ARENA_MARGIN.to_mm_f64(), after.x.to_mm_f64(), after.y.to_mm_f64());
    let limited = x <= -m.floor()
        || y <= -m.floor()
        || x >= (arena::LENGTH_X.to_mm_f64() + m).floor()
        || y >= (arena::WIDTH_Y.to_mm_f64() + m).floor();
    Checked { update, reacquired, sigmas, step_mm: d[0].hypot(d[1]), limited }
}

/// Rounding slack on the bound, sigmas (the gain is exact to about 2^-24).
const SLACK: f64 = 1e-3;

#[test]
fn every_correction_stays_within_the_gate_of_its_covariance() {
    let mut rng = Rng::new(23);
    let arena = Arena::DEFAULT;
    let mut n_limited = 0u32;
    let (mut n, mut n_reacq, mut worst, mut worst_reacq, mut longest) = (0u32, 0u32, 0.0f64, 0.0f64, 0.0f64);
    for round in 0..2_000 {
        // somewhere in the box, with a history of random motion and
        // readings of a truth that is near it, or far (lost)
        let at = |rng: &mut Rng| {
            Pose::from_mm(rng.range_u32(60, 700) as i32, rng.range_u32(60, 440) as i32, Angle(rng.next_u32()))
        };
        let mut est = Estimator::new(at(&mut rng));
        for _ in 0..rng.range_u32(0, 200) {
            let motion = match rng.range_u32(0, 3) {
                0 => Motion::Stop,
                1 => Motion::Straight(Speed::from_mm_s(rng.range_u32(0, 300) as i32 - 150)),
                _ => Motion::Turn(TurnRate::from_rad_s_f64(rng.range_f64(-3.5, 3.5))),
            };
            est.predict(motion, TICK);
        }
        let truth = if rng.chance(0.5) {
            let p = est.pose();
            let near = |c: f64, rng: &mut Rng| (c + rng.gauss(30.0)).round() as i32;
            let theta = p.theta.wrapping_add(Angle::from_degrees_f64(rng.gauss(10.0)));
            Pose::from_mm(near(p.x.to_mm_f64(), &mut rng), near(p.y.to_mm_f64(), &mut rng), theta)
        } else {
            at(&mut rng)
        };
        for _ in 0..rng.range_u32(10, 80) {
            let r = match rng.range_u32(0, 4) {
                0 => checked(
                    &mut est,
                    |e| e.update_heading(truth.theta.wrapping_add(Angle::from_degrees_f64(rng.gauss(2.5)))),
                    false,
                ),
                k => {
                    let id = if k == 1 { LidarId::Front } else { LidarId::Right };
                    let z = match expected_lidar(&arena, &truth, id) {
                        Some(z) if k < 3 => z.to_mm_f64() + rng.gauss(1.6),
                        // junk: anything the lidar might give
                        _ => rng.range_f64(-50.0, 900.0),
                    };
                    checked(&mut est, |e| e.update_lidar(id, Length::from_mm_f64(z)), true)
                }
            };
            if r.update == Update::Accepted && r.limited {
                n_limited += 1;
            } else if r.update == Update::Accepted {
                n += 1;
                n_reacq += u32::from(r.reacquired);
                longest = longest.max(r.step_mm);
                if r.reacquired {
                    worst_reacq = worst_reacq.max(r.sigmas);
                } else {
                    worst = worst.max(r.sigmas);
                }
                assert!(r.sigmas <= GATE_SIGMAS + SLACK, "round {round}: a step of {:.2} sigmas", r.sigmas);
            }
            if rng.chance(0.3) {
                est.predict(Motion::Stop, TICK);
            }
        }
    }
    println!(
        "{n} corrections ({n_reacq} re-acquiring): largest step {worst:.3} sigmas accepted, {worst_reacq:.3} \
         re-acquiring (gate {GATE_SIGMAS}); longest position step {longest:.0} mm; {n_limited} more ended on \
         the arena's limit"
    );
    assert!(n_reacq > 100, "too few re-acquisitions to say anything: {n_reacq}");
    // some re-acquisitions were clipped (their readings lay past the gate)
    assert!(worst_reacq > GATE_SIGMAS - 0.01, "{worst_reacq}");
}

/// An estimate far from a robot standing in the box (550 mm and half a
/// turn off, as on the team's real drive), fed the f64 truth's readings
/// (the lidars' cone, their noise, the compass's) at the robot's rates:
/// it walks back in bounded steps. Returns the time until it is within
/// 20 mm and 5 degrees for good (s), re-acquisitions, the largest step in
/// sigmas and mm.
fn recover(truth: PoseF64, start: Pose, settled: bool, seed: u64) -> (Option<f64>, EstimatorStats, f64, f64) {
    let mut rng = Rng::new(seed);
    let (lx, wy) = common::estimator::arena_mm();
    let (lx, wy) = (lx.to_mm_f64(), wy.to_mm_f64());
    // sure of itself at the wrong pose, or just started there
    let mut est = if settled { common::estimator::settled(start) } else { Estimator::new(start) };
    let before = est.stats();
    let (mut back_at, mut worst, mut longest) = (None, 0.0f64, 0.0f64);
    for tick in 0..500 {
        est.predict(Motion::Stop, TICK);
        let compass = Angle::from_radians_f64(truth.theta + rng.gauss(2.5f64.to_radians()));
        let mut steps = vec![checked(&mut est, |e| e.update_heading(compass), false)];
        if tick % 3 == 0 {
            for id in [LidarId::Front, LidarId::Right] {
                let z = true_range(truth, &id.mount(), lx, wy) + rng.gauss(1.6);
                steps.push(checked(&mut est, |e| e.update_lidar(id, Length::from_mm_f64(z)), true));
            }
        }
        for s in steps.iter().filter(|s| s.update == Update::Accepted && !s.limited) {
            worst = worst.max(s.sigmas);
            longest = longest.max(s.step_mm);
        }
        let p = est.pose();
        let e_mm = (p.x.to_mm_f64() - truth.x).hypot(p.y.to_mm_f64() - truth.y);
        let e_deg = wrap(p.theta.to_radians_f64() - truth.theta).to_degrees();
        if e_mm < 20.0 && e_deg.abs() < 5.0 {
            back_at.get_or_insert(f64::from(tick + 1) * 0.01);
        } else {
            back_at = None;
        }
    }
    let mut st = est.stats();
    st.front.reacquired -= before.front.reacquired;
    st.right.reacquired -= before.right.reacquired;
    st.compass.reacquired -= before.compass.reacquired;
    (back_at, st, worst, longest)
}

#[test]
fn a_lost_estimate_walks_back_in_bounded_steps() {
    let deg = |d: f64| Angle::from_degrees_f64(d);
    // (truth x, y, heading; estimate x, y, heading)
    let cases = [
        ((620.0, 150.0, 5.0), (70, 150, 185.0)),
        ((650.0, 350.0, 95.0), (150, 120, 275.0)),
        ((620.0, 150.0, 5.0), (70, 150, 5.0)),
    ];
    for ((tx, ty, th), (sx, sy, sh)) in cases {
        let truth = PoseF64 { x: tx, y: ty, theta: f64::to_radians(th) };
        for settled in [false, true] {
            for seed in 1..=2 {
                let (back, st, worst, longest) = recover(truth, Pose::from_mm(sx, sy, deg(sh)), settled, seed);
                println!(
                    "{:.0} mm / {:.0} deg off, {}, seed {seed}: within 20 mm / 5 deg after {back:?} s; \
                     re-acquisitions front {} right {} compass {}; largest step {worst:.2} sigmas, {longest:.0} mm",
                    (tx - f64::from(sx)).hypot(ty - f64::from(sy)),
                    wrap((th - sh).to_radians()).to_degrees().abs(),
                    if settled { "settled there" } else { "fresh" },
                    st.front.reacquired,
                    st.right.reacquired,
                    st.compass.reacquired,
                );
                assert!(worst <= GATE_SIGMAS + SLACK, "a step of {worst:.2} sigmas");
                // at most gate times the larger of the re-acquisition's and the initial sigma
                assert!(longest <= GATE_SIGMAS * 100.0 + 1.0, "a step of {longest:.0} mm");
                let back = back.unwrap_or_else(|| panic!("not back within 5 s"));
                assert!(back < 3.0, "back only after {back} s");
            }
        }
    }
}
