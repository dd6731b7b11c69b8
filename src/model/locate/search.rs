//! [`Search`]: the grid search of [`super::locate`], a pass over the grid
//! per heading tried and readings let go, a few hundred view scores at a
//! time (see the parent module's docs).

use super::clusters::{Gather, Sums};
use super::view::{View, PIVOTS};
use super::{Cluster, Fix, LocateError, Readings, HEADING_STEP, MAX_CLUSTERS, MAX_STEPS, MAX_VIEWS, PIVOT_PRIOR};
use super::{TOLERANCE, TURNED_TOLERANCE};
use crate::config::locate as cfg;
use crate::math::{Angle, Coord, Length};
use crate::model::measurement::Arena;
use crate::model::state::Pose;

/// The search of [`locate`](super::locate) a few hundred view scores at a time, so the robot's
/// loop can spread it over its ticks ([`Search::step`]): one pass over the
/// grid per heading tried (and a second, letting one reading go, when
/// there are enough readings), the same passes in the same order.
#[derive(Clone, Copy, Debug)]
pub struct Search {
    views: [Readings; MAX_VIEWS],
    count: usize,
    /// Readings over all views (for the one-unexplained-reading pass).
    readings: u32,
    /// The heading tried: 0 the compass's, then 2n - 1 (+n steps), 2n (-n).
    heading_try: u32,
    /// Readings a point may leave unexplained in this pass (0 to
    /// [`cfg::MAX_UNEXPLAINED`]).
    allowed: u32,
    /// The next grid point of this pass: its column and row.
    column: i32,
    row: i32,
    /// All the consistent points, and their clusters.
    sums: Sums,
    gather: Gather,
    /// Where in its spot a lidar's range comes from (Q30; see
    /// [`Search::with_spot_share`]).
    share: i32,
    /// The axis's share tried at the compass's heading when no share was
    /// learned and nothing fits the nearest point: not yet, under way, done.
    axis_guess: Guess,
    /// The last heading try ([`Search::up_to`]).
    last_try: u32,
}

/// The search's guess of the beam's axis (see [`Search::pass_done`]).
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
enum Guess {
    NotYet,
    UnderWay,
    Done,
}

impl Search {
    /// Passes over the grid at most: one per heading tried and number of
    /// readings left unexplained, and the axis's guess at the compass's
    /// heading.
    pub const MAX_PASSES: u32 = (1 + cfg::MAX_UNEXPLAINED) * (2 * cfg::HEADING_STEPS as u32 + 2);

    /// A search of `views` (the first [`MAX_VIEWS`]), not started.
    pub fn new(views: &[Readings]) -> Result<Search, LocateError> {
        Search::of(views.iter().copied())
    }

    /// A search of the views `views` yields (the first [`MAX_VIEWS`]), not
    /// started.
    pub fn of(views: impl Iterator<Item = Readings>) -> Result<Search, LocateError> {
        let mut kept = [Readings { heading: Angle::ZERO, front: None, right: None }; MAX_VIEWS];
        let mut count: usize = 0;
        for (slot, r) in kept.iter_mut().zip(views) {
            *slot = r;
            count = count.saturating_add(1);
        }
        let views = kept.get(..count).unwrap_or(&[]);
        if views.iter().all(|r| r.front.is_none() && r.right.is_none()) {
            return Err(LocateError::NoReading);
        }
        let readings = views.iter().map(|r| u32::from(r.front.is_some()) + u32::from(r.right.is_some())).sum();
        Ok(Search {
            views: kept,
            count,
            readings,
            heading_try: 0,
            allowed: 0,
            column: 0,
            row: 0,
            sums: Sums::EMPTY,
            gather: Gather::EMPTY,
            share: 0,
            axis_guess: Guess::NotYet,
            last_try: 2 * u32::from(cfg::HEADING_STEPS),
        })
    }

    /// The search reading each range `share` (Q30, 0 to 2^30) of the way
    /// from its cone's nearest wall point to its beam's axis, as the
    /// estimator has learned it (`Estimator::lidar_spot`); a new search
    /// reads the nearest point (0).
    pub fn with_spot_share(self, share: i32) -> Search {
        let axis_guess = if share == 0 { Guess::NotYet } else { Guess::Done };
        Search { share: share.clamp(0, 1 << 30), axis_guess, ..self }
    }

    /// Tries headings up to `steps` heading steps each way
    /// ([`cfg::HEADING_STEP_DEG`]; at most [`cfg::HEADING_STEPS`]), not
    /// started: nothing fits beyond.
    pub fn up_to(&mut self, steps: u8) {
        self.last_try = 2 * u32::from(steps.min(cfg::HEADING_STEPS));
    }

    /// Goes on from the heading try `heading_try` (as [`Fix::heading_try`]
    /// counts them), before the search has begun: the passes of the tries
    /// before it are not taken, and a search from a fix's own try finds
    /// that fix again. In place (a search is 0.6 kB of the robot's stack).
    pub fn skip_to(&mut self, heading_try: u8) {
        if heading_try > 0 {
            // past the compass's heading the axis's guess is over (the
            // share the learned one, as it was)
            (self.heading_try, self.axis_guess) = (heading_try.into(), Guess::Done);
        }
    }

    /// Searches on for up to `scores` more view scores (a view's two
    /// lidar models at a grid point and a pivot: the slice's work, about
    /// even; a grid point takes one to the pivots tried,
    /// [`cfg::PIVOTS_BEHIND_AXLE_MM`], per later view): `None`
    /// while the search goes on, then its answer (the same as
    /// [`locate`](super::locate)'s). A step ends at its pass's end.
    pub fn step(&mut self, arena: &Arena, scores: u32) -> Option<Result<Fix, LocateError>> {
        if self.heading_try > self.last_try {
            return Some(Err(LocateError::NothingFits));
        }
        let views = self.tried(arena);
        let Some(Some(first)) = views.first() else {
            return Some(Err(LocateError::NoReading));
        };
        let (lx, wy) = first.box_mm;
        let mut work = 0u32;
        while work < scores {
            let (x, y) = (cfg::GRID_MM.saturating_mul(self.column), cfg::GRID_MM.saturating_mul(self.row));
            if x > lx || self.column >= MAX_STEPS {
                return self.pass_done(&views);
            }
            if y > wy || self.row >= MAX_STEPS {
                (self.column, self.row) = (self.column.saturating_add(1), 0);
                continue;
            }
            self.row = self.row.saturating_add(1);
            let (at, spent) = search_point(arena, &views, self.allowed, x, y);
            work = work.saturating_add(spent);
            if let Some((px, py)) = at {
                self.sums.add(px, py);
                self.gather.add(px, py);
            }
        }
        None
    }

    /// Searches on to the answer ([`Search::step`] until it has one), in
    /// one call.
    pub fn finish(mut self, arena: &Arena) -> Result<Fix, LocateError> {
        // a step ends its pass at the latest
        for _ in 0..=Search::MAX_PASSES {
            if let Some(result) = self.step(arena, u32::MAX) {
                return result;
            }
        }
        Err(LocateError::NothingFits)
    }

    /// A pass is over: its fix, or the next pass.
    fn pass_done(&mut self, views: &[Option<View>; MAX_VIEWS]) -> Option<Result<Fix, LocateError>> {
        self.gather.settle();
        if let Some(mut fix) = fix_from(&self.sums, &self.gather, views) {
            fix.compass_steps = u8::try_from(self.heading_try.div_ceil(2)).unwrap_or(u8::MAX);
            fix.unexplained = u8::try_from(self.allowed).unwrap_or(u8::MAX);
            fix.heading_try = u8::try_from(self.heading_try).unwrap_or(u8::MAX);
            fix.untrusted = fix.compass_steps > 0
                || self.axis_guess == Guess::UnderWay
                || self.allowed > 1
                || (self.allowed > 0 && fix.points < cfg::MIN_POINTS_WITH_OUTLIER);
            return Some(Ok(fix));
        }
        (self.column, self.row, self.sums, self.gather) = (0, 0, Sums::EMPTY, Gather::EMPTY);
        // a failed reading (a spurious echo) among many must not hide the
        // pose the others agree on: one, and one more a further
        // READINGS_PER_UNEXPLAINED readings
        let most = (self.readings / cfg::READINGS_PER_UNEXPLAINED).clamp(1, cfg::MAX_UNEXPLAINED);
        if self.allowed < most && self.readings > cfg::MIN_READINGS_FOR_OUTLIER {
            self.allowed = self.allowed.saturating_add(1);
            return None;
        }
        self.allowed = 0;
        // nothing fits the compass's heading reading the cone's nearest
        // point, and no share was learned: the beam's axis, a guess (its
        // fix untrusted), before the other headings
        match self.axis_guess {
            Guess::NotYet if self.heading_try == 0 => {
                (self.axis_guess, self.share) = (Guess::UnderWay, 1 << 30);
                return None;
            }
            Guess::UnderWay => (self.axis_guess, self.share) = (Guess::Done, 0),
            _ => {}
        }
        self.heading_try = self.heading_try.saturating_add(1);
        None
    }

    /// The views at this pass's heading: the compass's, or shifted by
    /// whole heading steps (a disturbed compass), alternately up and down.
    fn tried(&self, arena: &Arena) -> [Option<View>; MAX_VIEWS] {
        let k = self.heading_try;
        let off = Angle(HEADING_STEP.0.wrapping_mul(k.div_ceil(2)));
        let shifted = |r: &Readings| if k % 2 == 1 { r.heading.wrapping_add(off) } else { r.heading.wrapping_sub(off) };
        let views = self.views.get(..self.count).unwrap_or(&[]);
        let mut tried: [Option<View>; MAX_VIEWS] = [None; MAX_VIEWS];
        let Some(first) = views.first() else {
            return tried;
        };
        for (i, (slot, r)) in tried.iter_mut().zip(views).enumerate() {
            let heading = shifted(r);
            let tol = if i == 0 { TOLERANCE } else { TURNED_TOLERANCE };
            *slot = Some(View::new(arena, &Readings { heading, ..*r }, shifted(first), tol, self.share));
        }
        tried
    }
}

/// One grid point (the first view's reference point at (x, y)): where the
/// last view's reference point is, when the point fits the body in the box
/// in every view, explains all the views' readings but `allowed` and at
/// least one, with some pivot (the best fitting one, [`view`]); and the
/// view scores it took (the slice's work).
fn search_point(
    arena: &Arena,
    views: &[Option<View>; MAX_VIEWS],
    allowed: u32,
    x: i32,
    y: i32,
) -> (Option<(i32, i32)>, u32) {
    let Some(Some(first)) = views.first() else {
        return (None, 0);
    };
    let mut work = 1u32;
    let Some(base) = first.score(arena, x, y, 0).filter(|s| s.missed <= allowed) else {
        return (None, work);
    };
    let later = views.get(1..).unwrap_or(&[]);
    let Some(last) = later.iter().flatten().last() else {
        return ((base.explained > 0).then_some((x, y)), work);
    };
    // (cost, pivot) of the best pivot: each further one in the config's
    // list costs a little more (the nearer the lab's, the likelier)
    let prior = PIVOT_PRIOR;
    let mut best: Option<(u32, usize)> = None;
    for pivot in 0..PIVOTS {
        let mut total = Some(base);
        for v in later.iter().flatten() {
            work = work.saturating_add(1);
            total = total.zip(v.score(arena, x, y, pivot)).map(|(t, s)| t.add(s)).filter(|t| t.missed <= allowed);
            if total.is_none() {
                break;
            }
        }
        if let Some(t) = total.filter(|t| t.explained > 0) {
            let cost = t.cost.saturating_add(prior.saturating_mul(pivot as u32));
            if best.is_none_or(|(c, _)| cost < c) {
                best = Some((cost, pivot));
            }
        }
    }
    (best.map(|(_, pivot)| last.at(x, y, pivot)), work)
}

/// The fix from a pass's consistent points and their settled clusters
/// (none: no fix), the last view's places.
fn fix_from(sums: &Sums, gather: &Gather, views: &[Option<View>; MAX_VIEWS]) -> Option<Fix> {
    let last = views.iter().flatten().last()?;
    let (_, sigma_x, sigma_y) = sums.stats()?;
    // a mean in 1/256 mm (of the last view's points) -> Q16
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
        untrusted: false,
        compass_steps: 0,
        unexplained: 0,
        heading_try: 0,
        cluster_slots: slots,
        count,
    })
}
