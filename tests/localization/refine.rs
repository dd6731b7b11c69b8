//! The survey's fix refined with every lidar reading the survey saw (issue
//! #29; an f64 reference for a step the firmware does not take yet,
//! docs/simulator.md, "Refining the fix").
//!
//! The search (`model::locate`) scores each view at its compass heading,
//! and the hard world's compass is off by up to 12 to 20 degrees, by 5 to
//! 8 more between the views of one start. Here one model explains the
//! views and the readings taken while turning between them: the body turns
//! about a fixed pivot `P`, the reference point at a lever `D` from it;
//! view `i` at its own heading `theta_i`; a turn's readings at headings
//! between its two views' in proportion to its ticks, and each way's turn
//! at one rate; the compass reads `theta_i` plus a bias common to the
//! views, give or take a little per view (both priors a mixture: usually
//! the lab's compass, sometimes the hard world's); the lidars read the
//! model's range, from the cone's nearest wall point (share 0) or the
//! beam's axis (share 1), with noise growing with incidence and a corner
//! in the footprint. Levenberg-Marquardt with numerical derivatives and a
//! bounded (Welsch) loss per reading, from starts around each of the
//! search's places.

use super::locate::World;
use crate::common::rng::Rng;
use paperbot::config;
use paperbot::math::Length;
use paperbot::model::locate::turns::{Turn, SAMPLES};
use paperbot::model::locate::{Fix, Readings};
use paperbot::model::measurement::LidarId;
use paperbot::sim::arena::Arena as SimArena;
use paperbot::sim::body::{wrap_pi, PoseF64};
use paperbot::sim::robot::lidar_truth;
use std::f64::consts::{FRAC_PI_2, PI, TAU};
use std::sync::atomic::{AtomicU64, Ordering};

/// The lidars' readings during one turn between views.
#[derive(Default, Clone, Debug)]
pub(crate) struct TurnSamples {
    /// (the turn's ticks done when it came, front, right): model distances
    /// from the reference point, mm.
    samples: Vec<(u32, Option<f64>, Option<f64>)>,
    /// The body's poses so far, from the turn's start: a reading is of
    /// the pose [`AGE_TICKS`] before it comes.
    poses: Vec<PoseF64>,
    /// The turn's ticks and its way.
    ticks: u32,
    clockwise: bool,
}

/// How long before the tick it comes at a reading describes the body,
/// ticks (`config::lidar::READING_AGE_US`: the chip measures over its
/// timing budget, the loop polls once a tick); the world reads the body
/// whole ticks back (`common::reading_age::TICKS`).
const AGE_TICKS: f64 = config::lidar::READING_AGE_US as f64 * config::timing::LOOP_HZ as f64 / 1e6;

impl TurnSamples {
    /// A turn from `start` about to begin.
    pub(crate) fn from(start: &PoseF64) -> TurnSamples {
        TurnSamples { poses: vec![*start], ..TurnSamples::default() }
    }

    /// After one of a turn's `ticks` ticks at `p`: a reading of each lidar
    /// every third tick (the lidars' 33 ms period), of the body
    /// `reading_age::TICKS` before.
    pub(crate) fn tick(&mut self, w: &World, p: &PoseF64, ticks: u32, clockwise: bool, rng: &mut Rng) {
        self.poses.push(*p);
        (self.ticks, self.clockwise) = (ticks, clockwise);
        let done = self.poses.len() as u32 - 1;
        if done % 3 == 0 {
            let read = self.poses[self.poses.len().saturating_sub(1 + crate::common::reading_age::TICKS)];
            self.samples.push((done, reading(w, &read, LidarId::Front, rng), reading(w, &read, LidarId::Right, rng)));
        }
    }

    /// A reading's share of the turn done when it was measured.
    fn share(&self, done: u32) -> f64 {
        ((f64::from(done) - AGE_TICKS) / f64::from(self.ticks.max(1))).clamp(0.0, 1.0)
    }
}

impl TurnSamples {
    /// The same readings as the robot's survey keeps them
    /// (`model::locate::turns`: whole mm, at their ticks, a longer turn's
    /// spread over it).
    pub(crate) fn to_turn(&self) -> Turn {
        let steps = self.samples.len().div_ceil(SAMPLES).max(1) as u8;
        let mut turn = Turn::new(self.clockwise, steps);
        for &(tick, front, right) in &self.samples {
            let tick = tick as u16;
            for (id, d) in [(LidarId::Front, front), (LidarId::Right, right)] {
                if let Some(d) = d {
                    turn.push(id, tick, Length::from_mm_f64(d.round()));
                }
            }
        }
        turn.end(self.ticks as u16);
        turn
    }
}

/// The beam's direction from the heading, and how far along its beam the
/// lidar sits from the reference point, mm (both beams run through the
/// reference point: a reading is the distance from it).
fn beam_of(lidar: LidarId, theta: f64) -> (f64, f64) {
    let mount = lidar.mount();
    (theta + mount.direction.to_radians_f64(), mount.along_beam_mm())
}

/// One reading as the firmware gets it: the simulator's range with its
/// noise, through the lidar's model and back.
fn reading(w: &World, p: &PoseF64, lidar: LidarId, rng: &mut Rng) -> Option<f64> {
    let model = match lidar {
        LidarId::Front => config::lidar::FRONT,
        LidarId::Right => config::lidar::RIGHT,
    };
    let d =
        lidar_truth(&SimArena::default(), &w.realism, p, &lidar.mount(), rng)? + rng.gauss(config::sim::LIDAR_NOISE_MM);
    let raw = model.reading_for(Length::from_mm_f64(d))?;
    model.range(raw).distance().map(|l| l.to_mm_f64())
}

/// The lidar model's evaluations so far (what a port would pay for: one
/// is a `Beam` on the robot, about 900 lx106 instructions,
/// lx106/BENCHMARKS.md).
pub(crate) static EVALUATIONS: AtomicU64 = AtomicU64::new(0);

/// Half the lidar's cone, radians.
const HALF_CONE: f64 = config::lidar::CONE_DEG / 2.0 * PI / 180.0;
/// A reading's growth of sigma with incidence, a share of its range per
/// unit of `tan(incidence)` (with `config::estimator::LIDAR_SIGMA` at
/// square), and the incidence past which a reading says nothing, radians.
const INCIDENCE_SPREAD: f64 = config::refine::INCIDENCE_SPREAD;
const MAX_INCIDENCE: f64 = config::refine::MAX_INCIDENCE_DEG * PI / 180.0;
/// The loss's scale, sigmas (Welsch): a reading this far off weighs about
/// a third, one much farther almost nothing (spurious echoes, corners).
const ROBUST: f64 = 3.0;
/// A turn's angle apart from its way's rate times its ticks, degrees: the
/// trial's speed spread (2.6 %, `config::estimator::TURN_SPREAD`) of a
/// 45-degree turn and the ticks' noise.
const TURN_SIGMA_DEG: f64 = 1.5;
/// A prior that is usually narrow, sometimes wide: (share narrow, sigma
/// narrow, sigma wide), degrees. The compass's common bias: the lab's
/// compass (`config::estimator::COMPASS_SIGMA_DEG`) or a disturbed floor
/// (the 12 degrees) ...
const BIAS_MIX: (f64, f64, f64) = (0.7, config::estimator::COMPASS_SIGMA_DEG, 12.0);
/// ... and each view's apart from it (the compass's own spread, or a
/// floor disturbed unevenly: the hard world's views spread by 5 to 8).
const VIEW_MIX: (f64, f64, f64) = (0.7, config::estimator::COMPASS_SIGMA_DEG, 12.0);
/// The lever's prior, mm: the pivot anywhere the estimator allows
/// (`config::estimator::PIVOT_MIN_MM` to `PIVOT_MAX_MM` behind the axle,
/// the axle `config::geometry::ROTATION_TO_REFERENCE` behind the reference
/// point); its mean and one sigma.
fn lever_prior() -> (f64, f64) {
    let (min, max) = (config::estimator::PIVOT_MIN_MM, config::estimator::PIVOT_MAX_MM);
    (config::geometry::ROTATION_TO_REFERENCE.to_mm_f64() + (min + max) / 2.0, (max - min) / 3.0)
}
/// The fit stays near the search's place: one sigma, mm (at least the
/// cluster's own spread).
const NEAR_SIGMA_MM: f64 = 30.0;
/// A start away from the compass's heading must fit better than the one at
/// it by this much (cost, twice a log-likelihood): the lab's compass is
/// right, and a turned heading can fit a cone's flat readings as well.
const AWAY_MARGIN: f64 = 4.0;
/// A fit the refinement vouches for costs at most this per reading: a
/// reading within the model's noise costs about 0.9 (the bounded loss's
/// mean for a normal residual), so this is readings fitting about twice
/// as badly as the model's noise, on average.
const FIT_LIMIT: f64 = 2.0;
/// ... and no fit 30 mm or 5 degrees away costs within this more (twice
/// the log of a likelihood ratio of 12).
const RIVAL_GAP: f64 = 5.0;
/// The starts: headings off the search's (its compass heading), degrees
/// (nine 4 apart fixed 2 more hard starts of 300 at 1.8 times the cost;
/// the compass's alone 9 fewer); levers (the lab's pivot, the issue's),
/// mm; spot shares.
const START_HEADINGS_DEG: [f64; 3] = [-12.0, 0.0, 12.0];
const START_LEVERS_MM: [f64; 2] = [66.0, 116.0];
const START_SHARES: [f64; 2] = [0.0, 1.0];

/// A thin ray from (x, y) along `dir`: its length and the wall it ends on.
fn ray(x: f64, y: f64, dir: f64) -> Option<(f64, usize)> {
    let a = SimArena::default();
    let (lx, wy) = (a.length_x_mm(), a.width_y_mm());
    let (s, c) = dir.sin_cos();
    let lengths = [
        if c > 1e-9 { (lx - x) / c } else { f64::INFINITY },
        if c < -1e-9 { -x / c } else { f64::INFINITY },
        if s > 1e-9 { (wy - y) / s } else { f64::INFINITY },
        if s < -1e-9 { -y / s } else { f64::INFINITY },
    ];
    lengths
        .into_iter()
        .enumerate()
        .filter(|(_, t)| t.is_finite() && *t >= 0.0)
        .map(|(k, t)| (t, k))
        .min_by(|a, b| a.0.total_cmp(&b.0))
}

/// What the fit expects a lidar to read (written apart from the simulator's
/// `sim::realism::lidar_range`, the world's truth: a belief shared by the
/// world and the model of it would pass unseen), with the reference point
/// at (x, y) and its beam at `beam`, `along` mm from it: `share` of the way
/// from the cone's nearest wall point to the axis's; with the axis's
/// incidence and how far apart the ranges a footprint spanning a corner
/// mixes (0: one wall).
fn expected(x: f64, y: f64, beam: f64, along: f64, share: f64) -> Option<(f64, f64, f64)> {
    EVALUATIONS.fetch_add(1, Ordering::Relaxed);
    let a = SimArena::default();
    let (lx, wy) = (a.length_x_mm(), a.width_y_mm());
    if !(0.0..=lx).contains(&x) || !(0.0..=wy).contains(&y) {
        return None;
    }
    let (sx, sy) = (x + along * beam.cos(), y + along * beam.sin());
    let (axis, wall) = ray(sx, sy, beam)?;
    let normals = [0.0, PI, FRAC_PI_2, -FRAC_PI_2];
    let incidence = wrap_pi(beam - normals[wall]).abs();
    // the cone's nearest point: each wall's normal, or the cone's edge
    // nearest it, where that lands on the wall
    let distances = [lx - sx, sx, wy - sy, sy];
    let mut cone = axis;
    for (normal, d) in normals.into_iter().zip(distances) {
        let alpha = wrap_pi(beam - normal);
        let off = alpha.abs() - HALF_CONE;
        let (t, dir) = if off <= 0.0 { (d, normal) } else { (d / off.cos(), normal + alpha.signum() * off) };
        if off >= FRAC_PI_2 || t >= cone {
            continue;
        }
        let (px, py) = (sx + t * dir.cos(), sy + t * dir.sin());
        if px >= -1e-6 && py >= -1e-6 && px <= lx + 1e-6 && py <= wy + 1e-6 {
            cone = t;
        }
    }
    let span = match (ray(sx, sy, beam - HALF_CONE), ray(sx, sy, beam + HALF_CONE)) {
        (Some((t1, w1)), Some((t2, w2))) if w1 != w2 => (t1 - t2).abs(),
        _ => 0.0,
    };
    Some((cone + share * (axis - cone) + along, incidence, span))
}

/// The residual whose square is a mixture prior's cost over its least.
fn mixture(x: f64, (w, narrow, wide): (f64, f64, f64)) -> f64 {
    let density = |x: f64| {
        w / narrow * (-0.5 * (x / narrow).powi(2)).exp() + (1.0 - w) / wide * (-0.5 * (x / wide).powi(2)).exp()
    };
    (-2.0 * (density(x) / density(0.0)).ln()).max(0.0).sqrt().copysign(x)
}

/// The parameters' places: the pivot, the lever, the compass's common
/// bias, the spot share (held at its start), each way's turn per tick
/// (radians, clockwise and counter-clockwise, both positive), then the
/// views' headings.
const P_X: usize = 0;
const P_Y: usize = 1;
const P_D: usize = 2;
const P_B: usize = 3;
const P_S: usize = 4;
const P_CW: usize = 5;
const P_CCW: usize = 6;
const P_T: usize = 7;

/// A parameter's step for the numerical derivatives (none for the share:
/// it is not fitted; a turned heading fits a cone's readings with a thin
/// beam's share).
fn step(k: usize) -> Option<f64> {
    match k {
        P_S => None,
        P_X | P_Y | P_D => Some(0.3),
        P_CW | P_CCW => Some(1e-5),
        _ => Some(0.002),
    }
}

struct Problem<'a> {
    views: &'a [Readings],
    turns: &'a [TurnSamples],
    /// The search's place for the last view, and one sigma, mm.
    near: (f64, f64, f64),
}

impl Problem<'_> {
    fn params(&self) -> usize {
        P_T + self.views.len()
    }

    /// Each residual over its sigma, and whether it takes the bounded loss.
    fn residuals(&self, p: &[f64], out: &mut Vec<(f64, bool)>) {
        out.clear();
        let (px, py, d, b, share) = (p[P_X], p[P_Y], p[P_D], p[P_B], p[P_S]);
        let place = |theta: f64| (px + d * theta.cos(), py + d * theta.sin());
        let square = config::estimator::LIDAR_SIGMA.to_mm_f64();
        let lidars = |theta: f64, front: Option<f64>, right: Option<f64>, out: &mut Vec<(f64, bool)>| {
            let (x, y) = place(theta);
            for (lidar, z) in [(LidarId::Front, front), (LidarId::Right, right)] {
                let Some(z) = z else { continue };
                let (beam, along) = beam_of(lidar, theta);
                let r = expected(x, y, beam, along, share).map_or(2.0 * ROBUST, |(e, incidence, span)| {
                    // the incidence the range is read at: the axis's, or
                    // the cone's nearest point's
                    let read = if share >= 0.5 { incidence } else { (incidence - HALF_CONE).max(0.0) };
                    if read > MAX_INCIDENCE {
                        return 1.0;
                    }
                    let slope = INCIDENCE_SPREAD * z * incidence.tan().min(4.0);
                    (z - e) / (square.powi(2) + slope.powi(2) + (span / 2.0).powi(2)).sqrt()
                });
                out.push((r, true));
            }
        };
        for (i, v) in self.views.iter().enumerate() {
            let theta = p[P_T + i];
            lidars(theta, v.front.map(|l| l.to_mm_f64()), v.right.map(|l| l.to_mm_f64()), out);
            out.push((mixture(wrap_pi(v.heading.to_radians_f64() - theta - b).to_degrees(), VIEW_MIX), false));
        }
        for (j, t) in self.turns.iter().enumerate() {
            let (from, to) = (p[P_T + j], p[P_T + j + 1]);
            let rate = if t.clockwise { p[P_CW] } else { -p[P_CCW] };
            out.push(((to - from - rate * f64::from(t.ticks)).to_degrees() / TURN_SIGMA_DEG, true));
            for &(done, front, right) in &t.samples {
                lidars(from + t.share(done) * (to - from), front, right, out);
            }
        }
        out.push((mixture(b.to_degrees(), BIAS_MIX), false));
        let (lever, lever_sigma) = lever_prior();
        out.push(((d - lever) / lever_sigma, false));
        let (x, y) = place(p[P_T + self.views.len() - 1]);
        let (nx, ny, sigma) = self.near;
        out.push(((x - nx) / sigma, false));
        out.push(((y - ny) / sigma, false));
    }

    fn cost(&self, p: &[f64], scratch: &mut Vec<(f64, bool)>) -> f64 {
        self.residuals(p, scratch);
        scratch
            .iter()
            .map(|&(r, bounded)| if bounded { ROBUST * ROBUST * (1.0 - (-(r / ROBUST).powi(2)).exp()) } else { r * r })
            .sum()
    }

    /// Levenberg-Marquardt on the reweighted squares; the parameters and
    /// their cost.
    fn solve(&self, mut p: Vec<f64>) -> (Vec<f64>, f64) {
        let n = self.params();
        let (mut r0, mut r1) = (vec![], vec![]);
        let mut lambda = 1e-3;
        let mut cost = self.cost(&p, &mut r0);
        for _ in 0..30 {
            self.residuals(&p, &mut r0);
            let m = r0.len();
            let mut jac = vec![vec![0.0; n]; m];
            for k in 0..n {
                let Some(h) = step(k) else { continue };
                let mut q = p.clone();
                q[k] += h;
                self.residuals(&q, &mut r1);
                for (row, (a, b)) in jac.iter_mut().zip(r0.iter().zip(&r1)) {
                    row[k] = (b.0 - a.0) / h;
                }
            }
            let mut a = vec![vec![0.0; n]; n];
            let mut g = vec![0.0; n];
            for (row, &(r, bounded)) in jac.iter().zip(&r0) {
                let w = if bounded { (-(r / ROBUST).powi(2)).exp() } else { 1.0 };
                for k in 0..n {
                    g[k] += w * row[k] * r;
                    for l in 0..n {
                        a[k][l] += w * row[k] * row[l];
                    }
                }
            }
            let mut improved = false;
            for _ in 0..6 {
                let mut damped = a.clone();
                for (k, row) in damped.iter_mut().enumerate() {
                    row[k] = row[k] * (1.0 + lambda) + if step(k).is_none() { 1.0 } else { 1e-9 };
                }
                let Some(delta) = solve_linear(damped, g.iter().map(|v| -v).collect()) else { break };
                let q: Vec<f64> = p.iter().zip(&delta).map(|(a, b)| a + b).collect();
                let c = self.cost(&q, &mut r1);
                if c < cost {
                    (p, cost, improved) = (q, c, true);
                    lambda = (lambda / 3.0).max(1e-6);
                    break;
                }
                lambda *= 10.0;
            }
            if !improved {
                break;
            }
        }
        (p, cost)
    }
}

/// Gaussian elimination with partial pivoting.
fn solve_linear(mut a: Vec<Vec<f64>>, mut b: Vec<f64>) -> Option<Vec<f64>> {
    let n = b.len();
    for col in 0..n {
        let pivot = (col..n).max_by(|&i, &j| a[i][col].abs().total_cmp(&a[j][col].abs()))?;
        if a[pivot][col].abs() < 1e-12 {
            return None;
        }
        a.swap(col, pivot);
        b.swap(col, pivot);
        let b_col = b[col];
        let (upper, lower) = a.split_at_mut(col + 1);
        let pivot_row = &upper[col];
        for (row, rhs) in lower.iter_mut().zip(b.iter_mut().skip(col + 1)) {
            let f = row[col] / pivot_row[col];
            for (x, p) in row[col..].iter_mut().zip(&pivot_row[col..]) {
                *x -= f * p;
            }
            *rhs -= f * b_col;
        }
    }
    let mut x = vec![0.0; n];
    for row in (0..n).rev() {
        let s: f64 = (row + 1..n).map(|k| a[row][k] * x[k]).sum();
        x[row] = (b[row] - s) / a[row][row];
    }
    Some(x)
}

/// Each way's turn per tick from the compass over the turns (the median),
/// or the lab's `cw` (2.5 rad/s) for a way never turned.
fn compass_rates(views: &[Readings], turns: &[TurnSamples]) -> (f64, f64) {
    let mut per_way = [vec![], vec![]];
    for (pair, t) in views.windows(2).zip(turns) {
        let turned = wrap_pi(pair[1].heading.to_radians_f64() - pair[0].heading.to_radians_f64());
        if t.ticks > 0 && turned.abs() > f64::from(config::locate::BLOCKED_TURN_DEG).to_radians() {
            per_way[usize::from(t.clockwise)].push(turned.abs() / f64::from(t.ticks));
        }
    }
    let median = |v: &mut Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v.get(v.len() / 2).copied().unwrap_or(2.5 / f64::from(config::timing::LOOP_HZ))
    };
    (median(&mut per_way[1]), median(&mut per_way[0]))
}

/// The refined pose, and whether the fit vouches for it.
pub(crate) struct Refined {
    pub pose: PoseF64,
    /// Its readings fit within [`FIT_LIMIT`] apiece and no other place or
    /// heading fits within [`RIVAL_GAP`] of it.
    pub vouched: bool,
}

/// The pose at the last view that best explains every reading, from
/// starts around each of the fix's places; `None` without views.
pub(crate) fn refine(views: &[Readings], turns: &[TurnSamples], fix: &Fix) -> Option<Refined> {
    let last = views.len().checked_sub(1)?;
    let h_last = views[last].heading.to_radians_f64();
    let (cw, ccw) = compass_rates(views, turns);
    // every start's end: its cost, pose, and cost per reading
    let mut ends: Vec<(f64, PoseF64, f64)> = vec![];
    let mut scratch = vec![];
    for c in fix.clusters() {
        let at = PoseF64::from_pose(&fix.pose_of(c));
        let sigma = NEAR_SIGMA_MM.max(c.sigma_x.to_mm_f64()).max(c.sigma_y.to_mm_f64());
        let problem = Problem { views, turns, near: (at.x, at.y, sigma) };
        for dh in START_HEADINGS_DEG {
            for d in START_LEVERS_MM {
                for share in START_SHARES {
                    let theta = at.theta + dh.to_radians();
                    let mut p = vec![
                        at.x - d * theta.cos(),
                        at.y - d * theta.sin(),
                        d,
                        wrap_pi(h_last - theta),
                        share,
                        cw,
                        ccw,
                    ];
                    p.extend(views.iter().map(|v| theta + wrap_pi(v.heading.to_radians_f64() - h_last)));
                    let (q, cost) = problem.solve(p);
                    let cost = if dh == 0.0 { cost } else { cost + AWAY_MARGIN };
                    let theta = q[P_T + last];
                    let pose = PoseF64::new(
                        q[P_X] + q[P_D] * theta.cos(),
                        q[P_Y] + q[P_D] * theta.sin(),
                        theta.rem_euclid(TAU),
                    );
                    problem.residuals(&q, &mut scratch);
                    let readings = scratch.iter().filter(|r| r.1).count().max(1) as f64;
                    ends.push((cost, pose, cost / readings));
                }
            }
        }
    }
    let &(cost, pose, per_reading) = ends.iter().min_by(|a, b| a.0.total_cmp(&b.0))?;
    let apart = |p: &PoseF64| p.distance(&pose) > 30.0 || wrap_pi(p.theta - pose.theta).abs() > 5f64.to_radians();
    let rival = ends.iter().filter(|e| apart(&e.1)).map(|e| e.0).fold(f64::INFINITY, f64::min);
    Some(Refined { pose, vouched: per_reading <= FIT_LIMIT && rival - cost >= RIVAL_GAP })
}
