//! The fixed-point filter against an f64 extended Kalman filter of the
//! same equations (issue 29: seven states, no floats on the robot): the
//! same prediction (the state update with the learned scales, its Jacobian
//! as the docs give it, the same noise terms from the config) and the same
//! corrections (the lidars square on to their walls, where the cone's
//! incidence is zero and the innovation is the range's, of the body a
//! reading's age ago; the compass as heading plus bias), in f64. Over a
//! scripted drive (straights, turns both ways with a car that turns and
//! drives off its lines, stops, readings of the truth with noise, the
//! lidars' two ticks old) the two must agree: pose, scales, bias and the
//! covariance, step by step.

// matrix arithmetic reads as indices
#![allow(clippy::needless_range_loop)]

use crate::common;

use common::estimator::Rng;
use paperbot::config::{self, estimator as cfg};
use paperbot::math::{Angle, Dt, Length, Speed, TurnRate};
use paperbot::model::estimator::{Estimator, LidarId, Seed, Update, N};
use paperbot::model::measurement::expected_lidar;
use paperbot::model::{step, Motion, Pose};
use std::f64::consts::TAU;

const L: f64 = 256.0;
const Q12: f64 = 4096.0;

/// The f64 filter: the state in natural units, the covariance in mm^2 over
/// (x, y, L theta, L speed scale, L cw scale, L ccw scale, L bias).
#[derive(Clone)]
struct Reference {
    x: f64,
    y: f64,
    th: f64,
    scales: [f64; 3],
    bias: f64,
    p: [[f64; N]; N],
    /// The body's move over a lidar reading's age (`model::estimator`'s
    /// lag.rs): the mean of the last two steps', a turn's angle (rad) and
    /// a straight distance (mm); and the last step's.
    lag: (f64, f64),
    last: (f64, f64),
}

/// A lidar reading's age, s (`config::lidar::READING_AGE_US`).
const AGE_S: f64 = config::lidar::READING_AGE_US as f64 * 1e-6;

fn deg2(d: f64) -> f64 {
    let s = d.to_radians() * L;
    s * s
}

impl Reference {
    fn new(pose: Pose, sigma_mm: f64) -> Reference {
        let mut p = [[0.0; N]; N];
        let d = [
            sigma_mm * sigma_mm,
            sigma_mm * sigma_mm,
            deg2(cfg::COMPASS_SIGMA_DEG),
            (cfg::SPEED_SCALE_SIGMA * L).powi(2),
            (cfg::TURN_SCALE_SIGMA * L).powi(2),
            (cfg::TURN_SCALE_SIGMA * L).powi(2),
            deg2(cfg::COMPASS_BIAS_SIGMA_DEG),
        ];
        for i in 0..N {
            p[i][i] = d[i];
        }
        Reference {
            x: pose.x.to_mm_f64(),
            y: pose.y.to_mm_f64(),
            th: pose.theta.to_radians_f64(),
            scales: [1.0; 3],
            bias: 0.0,
            p,
            lag: (0.0, 0.0),
            last: (0.0, 0.0),
        }
    }

    /// `P <- F P F^T + Q` with `F = I + f`.
    fn propagate(&mut self, f: &[(usize, usize, f64)], q: &[[f64; N]; N]) {
        let mut m = [[0.0; N]; N];
        for i in 0..N {
            m[i][i] = 1.0;
        }
        for &(i, j, v) in f {
            m[i][j] += v;
        }
        let mut out = [[0.0; N]; N];
        for i in 0..N {
            for j in 0..N {
                let mut s = 0.0;
                for a in 0..N {
                    for b in 0..N {
                        s += m[i][a] * self.p[a][b] * m[j][b];
                    }
                }
                out[i][j] = s + q[i][j];
            }
        }
        self.p = out;
    }

    fn predict(&mut self, motion: Motion, dt: f64) {
        // the move over a reading's age at the motion by the scales
        let step = match motion {
            Motion::Stop => (0.0, 0.0),
            Motion::Straight(v) => (0.0, v.to_mps_f64() * 1000.0 * self.scales[0] * AGE_S),
            Motion::Turn(w) => {
                let k = if w.to_rad_s_f64() >= 0.0 { 1 } else { 2 };
                (w.to_rad_s_f64() * self.scales[k] * AGE_S, 0.0)
            }
        };
        self.lag = ((step.0 + self.last.0) / 2.0, (step.1 + self.last.1) / 2.0);
        self.last = step;
        let mut q = [[0.0; N]; N];
        let mut f = Vec::new();
        let (s, c) = self.th.sin_cos();
        match motion {
            Motion::Stop => {}
            Motion::Straight(v) => {
                let d0 = v.to_mps_f64() * 1000.0 * dt;
                let d = d0 * self.scales[0];
                self.x += d * c;
                self.y += d * s;
                f = vec![(0, 2, -d * s / L), (1, 2, d * c / L), (0, 3, d0 * c / L), (1, 3, d0 * s / L)];
                let k = cfg::SPEED_SPREAD.powi(2) * cfg::SPEED_CORRELATION_MM * d0.abs();
                q[0][0] = k * c * c;
                q[0][1] = k * c * s;
                q[1][0] = k * c * s;
                q[1][1] = k * s * s;
                let axle = config::geometry::AXLE_LENGTH.to_mm_f64();
                q[2][2] = (cfg::SPEED_SPREAD * L / axle).powi(2) * cfg::SPEED_CORRELATION_MM * d0.abs();
                q[6][6] = deg2(1.0) * cfg::COMPASS_BIAS_WALK_DEG2_PER_MM * d0.abs();
                q[3][3] = (cfg::SCALE_WALK_PER_SQRT_S * L).powi(2) * dt;
            }
            Motion::Turn(w) => {
                let a0 = w.to_rad_s_f64() * dt;
                let k = if a0 >= 0.0 { 1 } else { 2 };
                let th1 = self.th + a0 * self.scales[k];
                let dd = config::geometry::ROTATION_TO_REFERENCE.to_mm_f64();
                let (s1, c1) = th1.sin_cos();
                self.x -= dd * (c - c1);
                self.y -= dd * (s - s1);
                let g = [-dd * s1 / L, dd * c1 / L, 1.0];
                f = vec![
                    (0, 2, dd * (s - s1) / L),
                    (1, 2, dd * (c1 - c) / L),
                    (0, 3 + k, a0 * g[0]),
                    (1, 3 + k, a0 * g[1]),
                    (2, 3 + k, a0),
                ];
                let lc = cfg::TURN_CORRELATION_DEG.to_radians();
                let turned = (a0 * self.scales[k]).abs();
                let vt = cfg::TURN_SPREAD.powi(2) * lc * L * L * turned;
                // the pivot's slop, and the learned pivot's uncertainty (not
                // learned here: its start, 40 mm) as a random walk that
                // gives a quarter turn its chord's variance
                let unlearned = cfg::PIVOT_STATE_SIGMA_MM.powi(2) * 4.0 / std::f64::consts::PI;
                let vp = cfg::PIVOT_SIGMA_MM.powi(2) * lc * turned + unlearned * turned;
                let u = [-s1, c1];
                for i in 0..3 {
                    for j in 0..3 {
                        q[i][j] += vt * g[i] * g[j];
                    }
                }
                for i in 0..2 {
                    for j in 0..2 {
                        q[i][j] += vp * u[i] * u[j];
                    }
                }
                q[3 + k][3 + k] = (cfg::SCALE_WALK_PER_SQRT_S * L).powi(2) * dt;
                self.th = th1;
            }
        }
        q[0][0] += cfg::POSITION_FLOOR_MM2_PER_S * dt;
        q[1][1] += cfg::POSITION_FLOOR_MM2_PER_S * dt;
        q[2][2] += deg2(1.0) * cfg::HEADING_FLOOR_DEG2_PER_S * dt;
        q[6][6] += deg2(1.0) * cfg::COMPASS_BIAS_WALK_DEG2_PER_S * dt;
        self.propagate(&f, &q);
    }

    /// The scalar correction: innovation `nu`, row `h`, noise `r` (mm^2);
    /// gated as the filter is.
    fn correct(&mut self, h: [f64; N], nu: f64, r: f64) -> Update {
        let b: Vec<f64> = (0..N).map(|i| (0..N).map(|j| self.p[i][j] * h[j]).sum()).collect();
        let s: f64 = (0..N).map(|i| h[i] * b[i]).sum::<f64>() + r;
        if nu * nu > cfg::GATE_SIGMAS.powi(2) * s {
            return Update::Outlier;
        }
        let k: Vec<f64> = b.iter().map(|v| v / s).collect();
        self.x += k[0] * nu;
        self.y += k[1] * nu;
        self.th += k[2] * nu / L;
        for i in 0..3 {
            self.scales[i] += k[3 + i] * nu / L;
        }
        self.bias += k[6] * nu / L;
        for i in 0..N {
            for j in 0..N {
                self.p[i][j] -= k[i] * b[j];
            }
        }
        Update::Accepted
    }

    /// The front lidar square on to the north wall, the right one to the
    /// east wall (headings within the cone's half of north), of the body a
    /// reading's age ago: moved back by `lag`, a turn about the axle's
    /// lever to first order, as the filter does.
    fn lidar(&mut self, which: LidarId, z: f64) -> Update {
        let (lx, wy) = (config::arena::LENGTH_X.to_mm_f64(), config::arena::WIDTH_Y.to_mm_f64());
        let (s, c) = self.th.sin_cos();
        let (turn, along) = self.lag;
        let (x, y, (s, c)) = if turn != 0.0 {
            let dd = config::geometry::ROTATION_TO_REFERENCE.to_mm_f64();
            (self.x + dd * s * turn, self.y - dd * c * turn, (s - c * turn, c + s * turn))
        } else {
            (self.x - along * c, self.y - along * s, (s, c))
        };
        let m = which.mount();
        let (f, r) = (m.forward.to_mm_f64(), m.right.to_mm_f64());
        let (dx, dy) = (f * c - r * s, f * s + r * c);
        let dir = m.direction.to_radians_f64();
        let setback = -(f * dir.cos() + r * dir.sin());
        let mut h = [0.0; N];
        let nu = match which {
            LidarId::Front => {
                h[0] = -1.0;
                h[2] = dy / L;
                (z + setback) - (lx - (x + dx))
            }
            LidarId::Right => {
                h[1] = -1.0;
                h[2] = -dx / L;
                (z + setback) - (wy - (y + dy))
            }
        };
        self.correct(h, nu, config::estimator::LIDAR_SIGMA.to_mm_f64().powi(2))
    }

    fn compass(&mut self, heading: f64) -> Update {
        let d = (heading - self.th - self.bias + TAU / 2.0).rem_euclid(TAU) - TAU / 2.0;
        let mut h = [0.0; N];
        h[2] = 1.0;
        h[6] = 1.0;
        self.correct(h, d * L, deg2(cfg::COMPASS_SIGMA_DEG))
    }
}

#[test]
fn the_fixed_point_filter_follows_the_f64_reference() {
    let tick = Dt::from_micros_saturating(10_000);
    let mut truth = Pose::from_mm(380, 250, Angle::ZERO);
    let start = Pose::from_mm(385, 244, Angle::from_degrees_f64(1.0));
    let sigma = 10.0;
    let mut est = Estimator::new(start);
    let s = Length::from_mm_f64(sigma);
    est.seed(&[Seed { pose: start, sigma_x: s, sigma_y: s, weight: 1 }]);
    let mut reference = Reference::new(start, sigma);
    let mut rng = Rng::new(5);
    // the car: turns 1.3 (cw) and 0.8 (ccw) times its lines, drives 5 % slow
    let car = |m: Motion| match m {
        Motion::Turn(w) if w.to_bits() > 0 => Motion::Turn(TurnRate::from_rad_s_f64(w.to_rad_s_f64() * 1.3)),
        Motion::Turn(w) => Motion::Turn(TurnRate::from_rad_s_f64(w.to_rad_s_f64() * 0.8)),
        Motion::Straight(v) => Motion::Straight(Speed::from_mps_f64(v.to_mps_f64() * 0.95)),
        Motion::Stop => Motion::Stop,
    };
    // (the turns cancel on the car: the headings stay within the cone's half
    // of north, where the reference's square-on lidars hold)
    let plan = [
        (Motion::Straight(Speed::from_mm_s(80)), 80),
        (Motion::Turn(TurnRate::from_rad_s_f64(1.0)), 8),
        (Motion::Stop, 20),
        (Motion::Turn(TurnRate::from_rad_s_f64(-1.0)), 13),
        (Motion::Straight(Speed::from_mm_s(-80)), 120),
        (Motion::Straight(Speed::from_mm_s(60)), 60),
    ];
    let (mut worst_pos, mut worst_deg, mut worst_scale, mut worst_cov, mut n) = (0.0f64, 0.0f64, 0.0f64, 0.0f64, 0);
    let mut k = 0u32;
    // the truth a lidar reading describes
    let mut back = common::reading_age::Lagged::new(truth);
    for &(motion, ticks) in plan.iter().cycle().take(plan.len() * 3) {
        for _ in 0..ticks {
            truth = step(&truth, car(motion), tick);
            back.push(truth);
            est.predict(motion, tick);
            reference.predict(motion, 0.01);
            let mut updates = Vec::new();
            if k % 3 == 0 {
                for id in [LidarId::Front, LidarId::Right] {
                    let z = expected_lidar(&paperbot::model::measurement::Arena::DEFAULT, &back.read(), id).unwrap();
                    let z = z.to_mm_f64() + rng.gauss(1.5);
                    updates.push((est.update_lidar(id, Length::from_mm_f64(z)), reference.lidar(id, z)));
                }
            }
            let h = truth.theta.to_radians_f64() + rng.gauss(2.0f64.to_radians());
            updates.push((est.update_heading(Angle::from_radians_f64(h)), reference.compass(h)));
            for (a, b) in updates {
                assert_eq!(a, b, "tick {k}");
            }
            // the reference's state and the filter's (the best hypothesis: the only one)
            let p = est.best_pose();
            worst_pos = worst_pos.max((p.x.to_mm_f64() - reference.x).abs()).max((p.y.to_mm_f64() - reference.y).abs());
            let dth = (p.theta.to_radians_f64() - reference.th + TAU / 2.0).rem_euclid(TAU) - TAU / 2.0;
            worst_deg = worst_deg.max(dth.to_degrees().abs());
            let sc = est.scales();
            for (fixed, f64s) in [sc.speed, sc.cw, sc.ccw].iter().zip(reference.scales) {
                worst_scale = worst_scale.max((f64::from(*fixed) / f64::from(1 << 29) - f64s).abs());
            }
            let cov = est.covariance();
            for i in 0..N {
                for j in 0..N {
                    let (a, b) = (f64::from(cov.get(i, j)) / Q12, reference.p[i][j]);
                    let scale = (reference.p[i][i] * reference.p[j][j]).sqrt();
                    worst_cov = worst_cov.max((a - b).abs() / scale);
                }
            }
            n += 1;
            k += 1;
        }
    }
    let bias =
        ((est.compass_bias().to_radians_f64() - reference.bias + TAU / 2.0).rem_euclid(TAU) - TAU / 2.0).to_degrees();
    println!(
        "{n} ticks against the f64 reference: position within {worst_pos:.3} mm, heading {worst_deg:.4} deg, \
         scales {worst_scale:.5}, covariance {worst_cov:.5} of sqrt(P_ii P_jj); bias {bias:.4} deg at the end; \
         learned scales (f64) {:.3?}",
        reference.scales
    );
    // measured: 0.003 mm, 0.003 deg, 3e-4, 0.006 (the cross terms near 0:
    // a few LSB of Q12 against sqrt(P_ii P_jj) of a few mm^2)
    assert!(worst_pos < 0.02 && worst_deg < 0.02 && worst_scale < 2e-3 && worst_cov < 1e-2);
    assert!(bias.abs() < 0.01);
}
