//! Localization: where in the box the robot can be, from compass headings
//! and the two lidars' distances (the lidar models' outputs), with no prior
//! pose, in one view or several with turns in place between them. Run at
//! power-up and on `locate`, before the filter starts.
//!
//! # The search
//! With the heading taken from the compass, every point of a grid over the
//! box ([`cfg::GRID_MM`]) where the whole body fits (both lidars inside the
//! walls) is tried as the reference point: the arena model
//! ([`crate::model::measurement::Beam`], the lidars' cones included) says
//! what each lidar should read there (where in its spot the range comes
//! from as the estimator has learned it, [`Search::with_spot_share`]: the
//! cone's nearest wall point at power-up, and the beam's axis as a guess
//! when nothing fits that at the compass's heading: its fix is
//! [`Fix::untrusted`]), and the point is consistent when
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
//! A turn in place swings the reference point about a pivot behind the
//! axle (the skid's drag), at a radius the search does not know: a grid
//! point for the first view is, after turns, one of a family of points for
//! each later view, one per pivot tried ([`cfg::PIVOTS_BEHIND_AXLE_MM`],
//! `view.rs`). A point is consistent when it explains every view with some
//! pivot; its place is the last view's with the pivot that fits best. Views in more directions put beams on walls
//! of both axes. A view after a turn that did not happen (a body against a
//! wall; the compass shows it) is the same view again and adds nothing.
//! A reading may go unexplained (a spurious echo) when nothing explains
//! them all, one more for each [`cfg::READINGS_PER_UNEXPLAINED`] readings
//! up to [`cfg::MAX_UNEXPLAINED`] ([`cfg::MIN_READINGS_FOR_OUTLIER`]).
//!
//! # Cost
//! Two [`crate::model::measurement::Beam`]s per grid point and view: 153 x 99 points in the team's box
//! at 5 mm, about 17.7 million lx106 instructions for one view (0.22 s at 80
//! MHz, measured by the lx106 benchmarks); a later view is tried, once per
//! pivot, only where the first fits, and a failed search is repeated at
//! other headings. The loops are bounded by [`MAX_STEPS`] per axis,
//! [`MAX_VIEWS`], the pivots and the headings tried. [`Search`] does the
//! same work a few hundred view scores at a time, so the robot's loop
//! spreads it over its ticks.

pub mod clusters;
pub mod refine;
pub mod turns;
mod view;

pub use clusters::{Cluster, MAX_CLUSTERS};

use crate::config::locate as cfg;
use crate::math::{Angle, Coord, Length};
use crate::model::measurement::Arena;
use crate::model::state::Pose;
use clusters::{Gather, Sums};
use view::{View, PIVOTS};

/// `cos` of [`cfg::GLANCING_DEG`], Q2.30.
const GLANCING_NORMAL: i32 =
    (crate::math::cos_f64(cfg::GLANCING_DEG * core::f64::consts::TAU / 360.0) * (1u32 << 30) as f64) as i32;

/// Grid points per axis at most (a 2 m box at 5 mm).
pub const MAX_STEPS: i32 = 400;
/// The config's tolerances and pivot prior as lengths, and the heading
/// step as an angle, evaluated by the compiler (no float on the robot).
const TOLERANCE: Length = Length::from_mm_f64(cfg::TOLERANCE_MM);
const TURNED_TOLERANCE: Length = Length::from_mm_f64(cfg::TOLERANCE_MM + cfg::TURN_TOLERANCE_MM);
const PIVOT_PRIOR: u32 = Length::from_mm_f64(cfg::PIVOT_PRIOR_MM).0 as u32;
const HEADING_STEP: Angle = Angle::from_degrees_f64(cfg::HEADING_STEP_DEG);
const _: () = assert!(Length::from_mm_f64(cfg::PIVOT_PRIOR_MM).0 >= 0);
/// A vouched refinement's places apart fit at least
/// [`crate::config::refine::RIVAL_GAP`] worse (twice a log-likelihood):
/// their weights shrink by that likelihood ratio, in whole bits, rounded
/// down (5: 12 to 1, 3 bits).
pub const RIVAL_BITS: u32 = (crate::config::refine::RIVAL_GAP / (2.0 * core::f64::consts::LN_2)) as u32;

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
    /// One place fits, but the search cannot vouch for the fix: the
    /// compass's own heading fitted nowhere (the compass is disturbed
    /// there, and by how much differs from view to view: issue #29's hard
    /// world, 5 to 8 degrees between the views of one start, so the
    /// common offset found says little about the last view's heading), or
    /// the fit leaves a reading unexplained and rests on fewer than
    /// [`cfg::MIN_POINTS_WITH_OUTLIER`] grid points (a sliver of the box
    /// fits: the readings are not what the model expects), or it fits only
    /// reading the ranges as the beam's axis's, a guess where no spot share
    /// was learned. Reported as uncertain; more views do not help (each
    /// brings its own compass error).
    pub untrusted: bool,
    /// Heading steps ([`cfg::HEADING_STEP_DEG`]) between the fix's heading
    /// and the compass's: 0 when the compass's own heading fits.
    pub compass_steps: u8,
    /// Readings the fix may leave unexplained (its pass's allowance).
    pub unexplained: u8,
    /// The search's heading try that found it ([`Search::skip_to`]).
    heading_try: u8,
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

    /// The fix refined to `pose` (`model::locate::refine`): the place
    /// nearest it moved there and made the heaviest, first (the tracker's
    /// hypotheses start from the places by weight, and the reported pose
    /// is the heaviest's: the one the line `# located` prints), the heading
    /// its; uncertain unless the refinement `vouched` for it (the search's
    /// own flags kept). A vouched fix's other places weigh what its rival
    /// gap leaves them ([`RIVAL_BITS`]).
    pub fn refine_to(&mut self, pose: Pose, vouched: bool) {
        let count = usize::from(self.count);
        let dist = |c: &Cluster| {
            let (dx, dy) = (
                c.x.to_length().to_mm() - pose.x.to_length().to_mm(),
                c.y.to_length().to_mm() - pose.y.to_length().to_mm(),
            );
            i64::from(dx).saturating_mul(i64::from(dx)).saturating_add(i64::from(dy).saturating_mul(i64::from(dy)))
        };
        if let Some(places) = self.cluster_slots.get_mut(..count) {
            let heaviest = places.iter().map(|c| c.weight).max().unwrap_or(0);
            let nearest = places.iter().enumerate().min_by_key(|(_, c)| dist(c)).map_or(0, |(i, _)| i);
            // (rotated, not swapped: the others keep their order by weight)
            if let Some(moved) = places.get_mut(..=nearest) {
                moved.rotate_right(1);
            }
            for (i, c) in places.iter_mut().enumerate() {
                if i == 0 {
                    (c.x, c.y, c.weight) = (pose.x, pose.y, heaviest);
                } else if vouched {
                    c.weight >>= RIVAL_BITS;
                }
            }
        }
        self.pose = pose;
        self.untrusted |= !vouched;
    }

    /// The search's heading try that found it: 0 the compass's heading,
    /// then `2n - 1` (+n steps) and `2n` (-n), [`cfg::HEADING_STEP_DEG`]
    /// each.
    pub fn heading_try(&self) -> u8 {
        self.heading_try
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
/// several taken in turn with a turn in place between each (the reference
/// point circles a pivot behind the axle, tried at each of
/// [`cfg::PIVOTS_BEHIND_AXLE_MM`]). Each turn is the difference of two
/// compass headings. A pose must explain every view; the fix is the last
/// view's pose (where the robot now is). The turned views' tolerance adds
/// [`cfg::TURN_TOLERANCE_MM`] for the pivot between those tried and a
/// turn's own spread. Views past [`MAX_VIEWS`] are not used. Two
/// views can agree on a wrong pose far off; the robot's procedure
/// (`control::localize`) takes at least four, 45 degrees apart (turning
/// the other way when the compass shows a turn blocked), and more while
/// the fix is ambiguous.
///
/// The headings tried are the compass's and, when nothing fits there,
/// [`cfg::HEADING_STEP_DEG`] apart ever further from it, up to
/// [`cfg::HEADING_STEPS`] each way (the compass may be disturbed).
pub fn locate(arena: &Arena, views: &[Readings]) -> Result<Fix, LocateError> {
    locate_with_spot_share(arena, views, 0)
}

/// [`locate`] reading each range `share` of the way into its spot
/// ([`Search::with_spot_share`]).
pub fn locate_with_spot_share(arena: &Arena, views: &[Readings], share: i32) -> Result<Fix, LocateError> {
    let mut search = Search::new(views)?.with_spot_share(share);
    // a step ends its pass at the latest
    for _ in 0..=Search::MAX_PASSES {
        if let Some(result) = search.step(arena, u32::MAX) {
            return result;
        }
    }
    Err(LocateError::NothingFits)
}

/// The search of [`locate`] a few hundred view scores at a time, so the robot's
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
        let views = views.get(..MAX_VIEWS).unwrap_or(views);
        if views.iter().all(|r| r.front.is_none() && r.right.is_none()) {
            return Err(LocateError::NoReading);
        }
        let mut kept = [Readings { heading: Angle::ZERO, front: None, right: None }; MAX_VIEWS];
        for (slot, r) in kept.iter_mut().zip(views) {
            *slot = *r;
        }
        let readings = views.iter().map(|r| u32::from(r.front.is_some()) + u32::from(r.right.is_some())).sum();
        Ok(Search {
            views: kept,
            count: views.len(),
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
    /// [`locate`]'s). A step ends at its pass's end.
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
