//! Localization: where in the box the robot can be, from compass headings
//! and the two lidars' distances (the lidar models' outputs), with no prior
//! pose, in one view or several with turns in place between them. Run at
//! power-up and on `locate`, before the filter starts.
//!
//! # The search
//! With a heading (the compass's, or offset: below), every point of a grid over the
//! box ([`cfg::GRID_MM`]) where the whole body fits (both lidars inside the
//! walls) is tried as the reference point: the arena model
//! ([`crate::model::measurement::Beam`], the lidars' cones included) says
//! what each lidar should read there, and the point is consistent when
//! every given reading is within [`cfg::TOLERANCE_MM`] of that (as
//! `|normal_miss| <= tol cone_normal`: no division). A beam that would meet
//! its wall past [`cfg::GLANCING_DEG`] at a point says nothing about that
//! point (glancing readings fail or lie); a point must explain at least one
//! reading (one whose readings all say nothing is no fit). The consistent
//! points gather into clusters, places apart that the readings fit
//! ([`clusters`]): each cluster's mean is a position, its spread, with the
//! grid's own and the lidars' noise, its uncertainty, its share of the
//! points its weight ([`Cluster`]). The fix ([`Fix`]) is the heaviest
//! cluster, never the mean of places apart.
//!
//! Two ranges and a heading fix a position when the beams meet walls of
//! both axes; when they meet walls of one axis (near a corner, at about 45
//! degrees) the other coordinate is free, and the consistent points spread
//! along it, or they fall into separate clusters. Either way the fix is
//! [`Fix::ambiguous`] (a cluster spread past [`cfg::AMBIGUOUS_SPAN_MM`], or
//! several) and its uncertainty, the spread of all the points, says how
//! much: reported, not guessed silently. [`Fix::clusters`] lists the places
//! (up to [`MAX_CLUSTERS`], weighted), for a tracker that keeps several
//! hypotheses.
//!
//! # Several views
//! A turn in place swings the reference point, D ahead of the axle, about
//! the turn's pivot somewhere behind the axle (`view.rs`: the pivot is not
//! known, so each of [`cfg::PIVOTS_BEHIND_AXLE_MM`] is tried and the one
//! that explains the views best counts), so a grid point for the first
//! view is, after turns, a known point for each later view: a point is
//! consistent when it explains every view. Views in more directions put
//! beams on walls of both axes. A view after a turn that did not happen (a
//! body against a wall; the compass shows it) is the same view again and
//! adds nothing. With more than [`cfg::MIN_READINGS_FOR_OUTLIER`]
//! readings, one may go unexplained (a spurious echo, a mixed return near
//! a corner); the points that leave fewest unexplained are the pass's.
//!
//! # The compass's bias
//! The views' headings are the compass's, and a compass near desks and
//! walls is biased (issue #29: 12 degrees over the floor, 20 near walls),
//! about alike at the views of one standing robot. The search makes one
//! pass over the grid per common offset of the compass,
//! [`cfg::HEADING_STEP_DEG`] apart up to [`cfg::BIAS_STEPS`] each way
//! (further, up to [`cfg::HEADING_STEPS`], only while nothing fits), and
//! scores each point by its readings' misses along their walls' normals
//! (`view::Score`); the pass whose best point costs least, each step from the
//! compass adding [`cfg::BIAS_PRIOR_MM_PER_STEP`], gives the fix, at its
//! heading. When another pass's best point, at a place apart or a heading
//! [`cfg::RIVAL_STEPS`] apart, costs within [`cfg::RIVAL_MARGIN_MM`] of
//! it, the readings do not say which: the fix is ambiguous.
//!
//! # Cost
//! Two [`Beam`]s per grid point and view: 153 x 99 points in the team's box
//! at 5 mm, about 17.7 million lx106 instructions a pass for one view
//! (0.22 s at 80 MHz, measured by the lx106 benchmarks); a later view is
//! tried (at each pivot) only where the earlier ones fit. A search makes
//! up to 17 passes (fewer when the compass's offset costs more than the
//! best pass: those cannot win). The loops are bounded by [`MAX_STEPS`]
//! per axis, [`MAX_VIEWS`], the pivots and the offsets tried. [`Search`]
//! does the same work a few grid columns at a time, so the robot's loop
//! spreads it over its ticks.
//!
//! [`Beam`]: crate::model::measurement::Beam

pub mod clusters;
mod view;

pub use clusters::{Cluster, MAX_CLUSTERS};

use crate::config::locate as cfg;
use crate::math::{Angle, Coord, Length};
use crate::model::measurement::Arena;
use crate::model::state::Pose;
use clusters::{Gather, Sums};
use view::View;

/// `cos` of [`cfg::GLANCING_DEG`], Q2.30.
pub(crate) const GLANCING_NORMAL: i32 =
    (crate::math::cos_f64(cfg::GLANCING_DEG * core::f64::consts::TAU / 360.0) * (1u32 << 30) as f64) as i32;

/// Grid points per axis at most (a 2 m box at 5 mm).
pub const MAX_STEPS: i32 = 400;

/// Where the search put the robot.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub struct Fix {
    /// The heaviest cluster's mean (with one cluster, the consistent
    /// points' mean), at the compass heading.
    pub pose: Pose,
    /// One-sigma uncertainty per axis, mm (Q16): all the consistent
    /// points' spread (clusters apart included), the grid's and the
    /// lidars' noise.
    pub sigma_x: Length,
    pub sigma_y: Length,
    /// How many grid points fit the readings.
    pub points: u32,
    /// The readings fit several places apart, or one spread over more than
    /// [`cfg::AMBIGUOUS_SPAN_MM`] on an axis: they do not say which, or
    /// where along it the robot is.
    pub ambiguous: bool,
    /// The places, heaviest first: `clusters[..count]` ([`Fix::clusters`]).
    cluster_slots: [Cluster; MAX_CLUSTERS],
    count: u8,
}

impl Fix {
    /// The places the readings fit, heaviest first (at least one, at most
    /// [`MAX_CLUSTERS`]; lighter ones past that are left out, so the
    /// weights may sum to less than one).
    pub fn clusters(&self) -> &[Cluster] {
        self.cluster_slots.get(..usize::from(self.count)).unwrap_or(&[])
    }

    /// A cluster's pose: its position at the fix's heading.
    pub fn pose_of(&self, c: &Cluster) -> Pose {
        Pose::new(c.x, c.y, self.pose.theta)
    }
}

/// Why there is no fix.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum LocateError {
    /// Neither lidar gave a distance.
    NoReading,
    /// No point of the box explains the readings (a reading from something
    /// other than the walls, or a box of another size).
    NothingFits,
}

/// The readings the search explains.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub struct Readings {
    pub heading: Angle,
    pub front: Option<Length>,
    pub right: Option<Length>,
}

/// Views the search combines at most.
pub const MAX_VIEWS: usize = 8;

/// Searches `arena` for the poses that explain `views` (see the module
/// docs), to the end: [`Search`] run until it has its answer. One view, or
/// several taken in turn with a turn in place between each. A pose must
/// explain every view (but one reading, with enough of them); the fix is
/// the last view's pose (where the robot now is), at the compass offset
/// that explains the views best. Views past [`MAX_VIEWS`] are not used.
/// Two views can agree on a wrong pose far off; the robot's procedure
/// (`control::survey`) takes at least three, 45 degrees apart (turning the
/// other way when the compass shows a turn blocked), and more while the
/// fix is ambiguous.
pub fn locate(arena: &Arena, views: &[Readings]) -> Result<Fix, LocateError> {
    let mut search = Search::new(views)?;
    // a step of more columns than a grid has ends its pass
    for _ in 0..=Search::MAX_PASSES {
        if let Some(result) = search.step(arena, MAX_STEPS as u32 + 1) {
            return result;
        }
    }
    Err(LocateError::NothingFits)
}

/// The search of [`locate`] a few grid columns at a time, so the robot's
/// loop can spread it over its ticks ([`Search::step`]): one pass over the
/// grid per compass offset tried, the same passes in the same order.
#[derive(Clone, Copy, Debug)]
pub struct Search {
    views: [Readings; MAX_VIEWS],
    count: usize,
    /// Readings a point may leave unexplained (0, or 1 with more than
    /// [`cfg::MIN_READINGS_FOR_OUTLIER`] readings).
    allowed: u32,
    /// The compass offset tried: 0 none, then 2n - 1 (+n steps), 2n (-n).
    heading_try: u32,
    /// The next grid column of this pass.
    column: i32,
    /// This pass: its best point, and the points at its fewest misses.
    pass: Pass,
    /// The best pass so far.
    best: Option<Pass>,
    /// Each pass's best point (cost, x, y), for rivals far from the best.
    tried_best: [(u32, i32, i32); TRIES],
}

/// Compass offsets tried at most.
const TRIES: usize = 2 * cfg::HEADING_STEPS as usize + 1;

/// One pass's points: its lowest-cost point (cost, x, y in the last view's
/// whole mm), and the consistent points at its fewest misses, their sums
/// and clusters.
#[derive(Clone, Copy, Debug)]
struct Pass {
    heading_try: u32,
    best: (u32, i32, i32),
    missed: u32,
    sums: Sums,
    gather: Gather,
}

impl Pass {
    const fn new(heading_try: u32) -> Pass {
        Pass { heading_try, best: (u32::MAX, 0, 0), missed: u32::MAX, sums: Sums::EMPTY, gather: Gather::EMPTY }
    }

    /// A consistent point at (x, y) of the last view with its score.
    fn add(&mut self, x: i32, y: i32, s: &view::Score) {
        if s.cost < self.best.0 {
            self.best = (s.cost, x, y);
        }
        if s.missed < self.missed {
            // a point that explains more: the points that missed more go
            (self.missed, self.sums, self.gather) = (s.missed, Sums::EMPTY, Gather::EMPTY);
        }
        if s.missed == self.missed {
            self.sums.add(x, y);
            self.gather.add(x, y);
        }
    }
}

impl Search {
    /// Passes over the grid at most: one per compass offset tried.
    pub const MAX_PASSES: u32 = TRIES as u32;

    /// A search of `views` (the first [`MAX_VIEWS`]), not started.
    pub fn new(views: &[Readings]) -> Result<Search, LocateError> {
        let views = views.get(..MAX_VIEWS).unwrap_or(views);
        if views.iter().all(|r| r.front.is_none() && r.right.is_none()) {
            return Err(LocateError::NoReading);
        }
        let mut kept = [Readings { heading: Angle::ZERO, front: None, right: None }; MAX_VIEWS];
        for (slot, r) in kept.iter_mut().zip(views) {
            *slot = *r;
        }
        let readings: u32 = views.iter().map(|r| u32::from(r.front.is_some()) + u32::from(r.right.is_some())).sum();
        Ok(Search {
            views: kept,
            count: views.len(),
            // one failed reading (a spurious echo, a mixed return) among
            // many must not hide the pose the others agree on
            allowed: u32::from(readings > cfg::MIN_READINGS_FOR_OUTLIER),
            heading_try: 0,
            column: 0,
            pass: Pass::new(0),
            best: None,
            tried_best: [(u32::MAX, 0, 0); TRIES],
        })
    }

    /// Searches up to `columns` more grid columns: `None` while the search
    /// goes on, then its answer (the same as [`locate`]'s).
    pub fn step(&mut self, arena: &Arena, columns: u32) -> Option<Result<Fix, LocateError>> {
        if self.heading_try >= TRIES as u32 {
            return Some(self.answer(arena));
        }
        let views = self.tried(arena, self.heading_try);
        let lx = arena.length_x.0 >> 16;
        for _ in 0..columns {
            let x = cfg::GRID_MM.saturating_mul(self.column);
            if x > lx || self.column >= MAX_STEPS {
                return self.pass_done(arena);
            }
            self.column = self.column.saturating_add(1);
            search_column(arena, &views, self.allowed, x, &mut self.pass);
        }
        None
    }

    /// A pass is over: the next, or the answer.
    fn pass_done(&mut self, arena: &Arena) -> Option<Result<Fix, LocateError>> {
        let mut pass = self.pass;
        pass.gather.settle();
        // the compass is more often near right than far off: each step
        // from its heading costs a little (ties go to the compass)
        let prior = Length::from_mm_f64(cfg::BIAS_PRIOR_MM_PER_STEP).0.max(0) as u32;
        pass.best.0 = pass.best.0.saturating_add(prior.saturating_mul(self.heading_try.div_ceil(2)));
        if let Some(slot) = self.tried_best.get_mut(self.heading_try as usize) {
            *slot = pass.best;
        }
        if pass.sums.n > 0 && self.best.is_none_or(|b| pass.best.0 < b.best.0) {
            self.best = Some(pass);
        }
        self.heading_try = self.heading_try.saturating_add(1);
        (self.column, self.pass) = (0, Pass::new(self.heading_try));
        // the compass's bias range tried, and further only while nothing
        // fits; offsets whose prior alone costs more than the best pass
        // plus the rivals' margin can neither win nor be its rival
        let bias_tried = self.heading_try > 2 * u32::from(cfg::BIAS_STEPS);
        let next_prior = prior.saturating_mul(self.heading_try.div_ceil(2));
        let hopeless = self.best.is_some_and(|b| next_prior > b.best.0.saturating_add(rival_margin()));
        if self.heading_try >= TRIES as u32 || (self.best.is_some() && (bias_tried || hopeless)) {
            self.heading_try = TRIES as u32;
            return Some(self.answer(arena));
        }
        None
    }

    /// The best pass's fix, ambiguous too when another pass's best point,
    /// far from its or at a compass offset [`cfg::RIVAL_STEPS`] apart,
    /// fits nearly as well ([`cfg::RIVAL_MARGIN_MM`]): the readings do not
    /// say which place, or which heading.
    fn answer(&self, arena: &Arena) -> Result<Fix, LocateError> {
        let best = self.best.as_ref().ok_or(LocateError::NothingFits)?;
        let views = self.tried(arena, best.heading_try);
        let mut fix = fix_from(&best.sums, &best.gather, &views).ok_or(LocateError::NothingFits)?;
        let margin = rival_margin();
        let (cost, bx, by) = best.best;
        let span = cfg::AMBIGUOUS_SPAN_MM;
        let apart = |k: usize| offset_steps(k as u32).abs_diff(offset_steps(best.heading_try)) >= cfg::RIVAL_STEPS;
        fix.ambiguous |= self.tried_best.iter().enumerate().any(|(k, &(c, x, y))| {
            let far = x.abs_diff(bx) > span as u32 || y.abs_diff(by) > span as u32;
            c != u32::MAX && c <= cost.saturating_add(margin) && (far || apart(k))
        });
        Ok(fix)
    }

    /// The views at compass offset `k`: none, or whole heading steps (a
    /// disturbed compass, the same at all views taken at one place),
    /// alternately up and down.
    fn tried(&self, arena: &Arena, k: u32) -> [Option<View>; MAX_VIEWS] {
        let off = Angle(Angle::from_degrees_f64(cfg::HEADING_STEP_DEG).0.wrapping_mul(k.div_ceil(2)));
        let shifted = |r: &Readings| if k % 2 == 1 { r.heading.wrapping_add(off) } else { r.heading.wrapping_sub(off) };
        let views = self.views.get(..self.count).unwrap_or(&[]);
        let mut tried: [Option<View>; MAX_VIEWS] = [None; MAX_VIEWS];
        let Some(first) = views.first() else {
            return tried;
        };
        for (i, (slot, r)) in tried.iter_mut().zip(views).enumerate() {
            let tol = if i == 0 { cfg::TOLERANCE_MM } else { cfg::TOLERANCE_MM + cfg::TURN_TOLERANCE_MM };
            *slot = Some(View::new(arena, &Readings { heading: shifted(r), ..*r }, shifted(first), tol));
        }
        tried
    }
}

/// [`cfg::RIVAL_MARGIN_MM`] as a cost (Q16 mm).
fn rival_margin() -> u32 {
    Length::from_mm_f64(cfg::RIVAL_MARGIN_MM).0.max(0) as u32
}

/// Compass offset try `k` in heading steps: 0, +1, -1, +2, -2, ...
fn offset_steps(k: u32) -> i32 {
    let n = k.div_ceil(2) as i32;
    if k % 2 == 1 {
        n
    } else {
        -n
    }
}

/// One grid column (the first view's reference point at `x`): a point must
/// fit the body in the box in every view, explain all the views' readings
/// but `allowed`, and explain at least one; of the pivots tried, the one
/// that explains the views best counts.
fn search_column(arena: &Arena, views: &[Option<View>; MAX_VIEWS], allowed: u32, x: i32, pass: &mut Pass) {
    let Some(Some(first)) = views.first() else {
        return;
    };
    let last = views.iter().flatten().last().unwrap_or(first);
    let wy = first.box_mm.1;
    for j in 0..MAX_STEPS {
        let y = cfg::GRID_MM.saturating_mul(j);
        if y > wy {
            break;
        }
        // the first view: the same whatever the pivot
        let Some(s0) = first.score(arena, x, y, 0).filter(|s| s.missed <= allowed) else { continue };
        let mut best: Option<(view::Score, usize)> = None;
        for pivot in 0..view::PIVOTS {
            let mut s = Some(s0);
            for v in views.iter().flatten().skip(1) {
                s = s.zip(v.score(arena, x, y, pivot)).map(|(a, b)| a.add(b)).filter(|a| a.missed <= allowed);
                if s.is_none() {
                    break;
                }
            }
            if let Some(s) = s.filter(|s| s.explained > 0 && best.is_none_or(|(b, _)| s.cost < b.cost)) {
                best = Some((s, pivot));
            }
        }
        if let Some((s, pivot)) = best {
            let o = last.offsets.get(pivot).copied().unwrap_or((0, 0));
            pass.add(x.saturating_add(o.0), y.saturating_add(o.1), &s);
        }
    }
}

/// The fix from a pass's consistent points and their settled clusters
/// (none: no fix); the points are the last view's, the heading too.
fn fix_from(sums: &Sums, gather: &Gather, views: &[Option<View>; MAX_VIEWS]) -> Option<Fix> {
    let last = views.iter().flatten().last()?;
    let (_, sigma_x, sigma_y) = sums.stats()?;
    // a mean in 1/256 mm -> a coordinate
    let at = |m: i64| Coord::from_length(Length((m << 8) as i32));
    let empty = Cluster { x: last.pose.x, y: last.pose.y, sigma_x, sigma_y, weight: 0, points: 0 };
    let mut slots = [empty; MAX_CLUSTERS];
    let mut count = 0u8;
    for (slot, c) in slots.iter_mut().zip(gather.clusters()) {
        let Some((mean, sx, sy)) = c.stats() else { continue };
        let weight = crate::math::div_i64(i64::from(c.n) << 16, i64::from(sums.n)).unwrap_or(0) as u32;
        let (mx, my) = mean;
        *slot = Cluster { x: at(mx), y: at(my), sigma_x: sx, sigma_y: sy, weight, points: c.n };
        count = count.saturating_add(1);
    }
    let first = gather.clusters().next()?;
    Some(Fix {
        pose: slots.first().map_or(last.pose, |c| Pose::new(c.x, c.y, last.pose.theta)),
        sigma_x,
        sigma_y,
        points: sums.n,
        ambiguous: gather.clusters().nth(1).is_some() || first.wide(),
        cluster_slots: slots,
        count,
    })
}
