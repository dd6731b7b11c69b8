//! The search's fix refined with every reading of the survey (issue #29):
//! the views and the readings taken while turning between them
//! ([`Turn`]), explained by one model of the survey (`rows.rs`: a pivot
//! that moves a little each turn, a heading per view, each way's turn rate, the
//! compass's bias and the floor's bend of it across the pivot's circle
//! give or take a little a view, the lidars'
//! noise growing with incidence and at corners), fitted by
//! Levenberg-Marquardt (`fit.rs`, `solve.rs`) with a bounded loss per reading.
//!
//! Why: the search scores each view at its compass heading, and a
//! disturbed compass (the hard world's 12 to 20 degrees, 5 to 8 more
//! between the views of one start) leaves its fix at the last view's
//! compass heading and its place resting on headings that are wrong. The
//! lidars pin the headings; the compass only says roughly where they are.
//!
//! The fit starts from [`cfg::START_HEADINGS_DEG`] x [`cfg::START_LEVERS_MM`]
//! x [`cfg::START_AXIS_SHARES`] around each place the search found, stays
//! near that place ([`cfg::NEAR_SIGMA_MM`]), and keeps the start that
//! explains the readings best ([`cfg::AWAY_MARGIN`] against turned
//! headings). It vouches for its pose when the readings fit
//! ([`cfg::FIT_LIMIT`] a reading) and no pose apart fits nearly as well
//! ([`cfg::RIVAL_GAP`]).
//!
//! `tests/localization/refine.rs` is the f64 reference this follows (a
//! Welsch loss and summed mixtures there; a Geman-McClure loss and
//! max-mixtures here, no `exp` or `ln` on the robot: the reference
//! measured the same with both). [`Refine::step`] does one pass over the
//! readings (a `Beam` each) per call, so the loop spreads the fit over
//! its ticks.

mod fit;
mod rows;
mod solve;
#[cfg(test)]
mod tests;

use crate::config::locate::{BLOCKED_TURN_DEG, TURN_MRAD_S};
use crate::config::refine as cfg;
use crate::config::timing::LOOP_HZ;
use crate::math::{div_i64, sin_cos, Angle, Coord, Length};
use crate::model::locate::turns::Turn;
use crate::model::locate::{Fix, Readings, MAX_CLUSTERS};
use crate::model::measurement::Arena;
use crate::model::state::Pose;
use fit::Fit;
use rows::{Model, Params, BIAS, CCW, CW, FIT_VIEWS, HEADING, LEVER, MAX_PARAMS, ONE_SIGMA, PX, PY};

/// Where in its spot a range is read from, held through a start.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum Share {
    /// The cone's nearest wall point.
    Nearest,
    /// The beam's axis.
    Axis,
}

impl Share {
    fn q30(self) -> i64 {
        match self {
            Share::Nearest => 0,
            Share::Axis => 1 << 30,
        }
    }

    /// The cosine of the incidence the range is read at (Q30): the cone's
    /// nearest point's, or the axis's.
    fn read_normal(self, beam: &crate::model::measurement::Beam) -> i32 {
        match self {
            Share::Nearest => beam.cone_normal,
            Share::Axis => beam.normal,
        }
    }
}

/// Q24 costs from the config's (sigmas squared).
const fn q24(v: f64) -> i64 {
    (v * (ONE_SIGMA * ONE_SIGMA) as f64) as i64
}
const AWAY_MARGIN: i64 = q24(cfg::AWAY_MARGIN);
const FIT_LIMIT: i64 = q24(cfg::FIT_LIMIT);
const SEARCH_ON_LIMIT: i64 = q24(cfg::SEARCH_ON_LIMIT);
const SECOND_LOOK_FIT: i64 = q24(cfg::SECOND_LOOK_FIT);
const WELL_FIT: i32 = q24(cfg::WELL_FIT) as i32;
const RIVAL_GAP: i64 = q24(cfg::RIVAL_GAP);
const RIVAL_ANGLE: i32 = Angle::from_degrees_f64(cfg::RIVAL_DEG).0 as i32;
/// A turn the compass shows shorter than this was blocked: no rate from it.
const BLOCKED: i64 = Angle::from_degrees_f64(BLOCKED_TURN_DEG as f64).0 as i64;
const NEAR_INV: i64 = ((1u64 << 40) as f64 / (cfg::NEAR_SIGMA_MM * 65536.0)) as i64;
const NEAR_SIGMA: i32 = Length::from_mm_f64(cfg::NEAR_SIGMA_MM).0;

/// Starts a place.
const STARTS: usize = cfg::START_HEADINGS_DEG.len() * cfg::START_LEVERS_MM.len() * cfg::START_AXIS_SHARES.len();
/// Ends kept for the rival's cost.
const KEPT: usize = 4;

/// The refined pose, and whether the fit vouches for it.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub struct Refined {
    /// The last view's pose.
    pub pose: Pose,
    /// Its readings fit within [`cfg::FIT_LIMIT`] apiece and no pose apart
    /// fits within [`cfg::RIVAL_GAP`] of it.
    pub vouched: bool,
    /// Its cost a reading, Q24 sigmas squared.
    pub per_reading: i64,
}

impl Refined {
    /// Its readings fit worse than [`cfg::SEARCH_ON_LIMIT`] apiece: the
    /// search's place may not be the robot's ([`cfg::SEARCH_ON_STEPS`]).
    pub fn poor(&self) -> bool {
        self.per_reading > SEARCH_ON_LIMIT
    }
}

/// A fit costing `per_reading` a reading (Q24, as
/// [`Refined::per_reading`]) explains no place well enough to report on
/// a survey's first look ([`cfg::SECOND_LOOK_FIT`]).
pub fn worth_a_second_look(per_reading: i64) -> bool {
    per_reading > SECOND_LOOK_FIT
}

/// Where a start ended.
#[derive(Clone, Copy, Debug)]
struct End {
    cost: i64,
    per_reading: i32,
    x_mm: i16,
    y_mm: i16,
    theta: Angle,
}

impl End {
    fn apart(&self, o: &End) -> bool {
        let (dx, dy) = (i64::from(self.x_mm) - i64::from(o.x_mm), i64::from(self.y_mm) - i64::from(o.y_mm));
        let far = i64::from(cfg::RIVAL_MM);
        dx.saturating_mul(dx).saturating_add(dy.saturating_mul(dy)) > far.saturating_mul(far)
            || self.theta.diff(o.theta).saturating_abs() > RIVAL_ANGLE
    }
}

/// The refinement, a slice of a pass over the readings at a time (see
/// the module docs).
#[derive(Clone, Copy, Debug)]
pub struct Refine {
    /// The search's fix: its places, refined.
    fix: Fix,
    /// Each way's turn a tick from the compass, angle LSB (clockwise,
    /// counterclockwise).
    rates: (i64, i64),
    /// The next start, counted over the places.
    start: usize,
    fit: Option<Fit>,
    ends: [Option<End>; KEPT],
    /// An end was dropped from `ends` (the rival is at least the dearest kept).
    dropped: bool,
    /// The best cost a reading of this place's starts at the fix's heading
    /// (Q24; `i32::MAX` before one ended).
    compass_fit: i32,
}

impl Refine {
    /// The refinement of `fix`, found from `views` and `turns` (turn `j`
    /// between views `j` and `j + 1`): it weighs the last
    /// [`cfg::REFINE_VIEWS`] views and the turns between them.
    pub fn new(fix: Fix, views: &[Readings], turns: &[Turn]) -> Refine {
        let (views, turns) = weighed(views, turns);
        Refine {
            fix,
            rates: compass_rates(views, turns),
            start: 0,
            fit: None,
            ends: [None; KEPT],
            dropped: false,
            compass_fit: i32::MAX,
        }
    }

    /// Where to stay near: a place of the fix (Q16 mm) and `2^40 / sigma`.
    fn place(&self, index: usize) -> (i64, i64, i64) {
        let Some(c) = self.fix.clusters().get(index) else {
            return (0, 0, NEAR_INV);
        };
        let spread = c.sigma_x.0.max(c.sigma_y.0);
        let inv = if spread > NEAR_SIGMA { div_i64(1 << 40, i64::from(spread)).unwrap_or(NEAR_INV) } else { NEAR_INV };
        (c.x.to_length().0.into(), c.y.to_length().0.into(), inv)
    }

    /// The fix, refined: its pose the best fit's, and uncertain
    /// ([`Fix::untrusted`]) unless the fit vouches for it.
    pub fn refined_fix(&self) -> Fix {
        let mut fix = self.fix;
        if let Some(r) = self.result() {
            fix.refine_to(r.pose, r.vouched);
        }
        fix
    }

    /// The fit's next [`cfg::ROWS_PER_STEP`] rows (a `Beam` for each
    /// reading): `None` while the fit goes on, then the refined pose
    /// (`None` inside when there were no views). `views` and `turns` must
    /// be the ones [`Refine::new`] had.
    pub fn step(&mut self, arena: &Arena, views: &[Readings], turns: &[Turn]) -> Option<Option<Refined>> {
        let (views, turns) = weighed(views, turns);
        let starts = self.fix.clusters().len().min(MAX_CLUSTERS).saturating_mul(STARTS);
        if self.start >= starts || views.is_empty() {
            return Some(self.result());
        }
        let (place, choice) = (self.start / STARTS, self.start % STARTS);
        let (levers, shares) = (cfg::START_LEVERS_MM.len(), cfg::START_AXIS_SHARES.len());
        let (heading_at, rest) = (choice / (levers * shares), choice % (levers * shares));
        let lever = START_LEVERS.get(rest / shares).copied().unwrap_or(0);
        let share = if cfg::START_AXIS_SHARES.get(rest % shares) == Some(&true) { Share::Axis } else { Share::Nearest };
        let (nx, ny, inv) = self.place(place);
        let model = Model { arena, views, turns, share, near: (nx, ny, inv) };
        let turned = START_TURNS.get(heading_at).copied().unwrap_or(0);
        if self.fit.is_none() {
            if choice == 0 {
                self.compass_fit = i32::MAX;
            }
            // the compass's heading fits this place well: no more starts here
            if self.compass_fit <= WELL_FIT {
                self.start = self.start.saturating_add(1);
                return None;
            }
            // the fit in place (a copy would be 0.7 kB more of the robot's stack)
            self.fit = Some(Fit::new(self.start_params(views, (nx, ny), turned, lever)));
        }
        let fit = self.fit.as_mut()?;
        if fit.pass(&model) && fit.next(model.params()) {
            let margin = if turned == 0 { 0 } else { AWAY_MARGIN };
            let end = fit.end(views.len(), margin);
            if turned == 0 {
                self.compass_fit = self.compass_fit.min(end.per_reading);
            }
            self.keep(end);
            self.fit = None;
            self.start = self.start.saturating_add(1);
        }
        None
    }

    /// A start's parameters: the last view at the place `at` (Q16 mm) and
    /// the fix's heading turned by `turned`, the earlier views at the
    /// compass's turns from it, the pivot `lever_mm` behind.
    fn start_params(&self, views: &[Readings], at: (i64, i64), turned: i32, lever: i64) -> Params {
        let mut p: Params = [0; MAX_PARAMS];
        let last = views.len().saturating_sub(1);
        let theta = i64::from(self.fix.pose.theta.0).saturating_add(i64::from(turned));
        let (s, c) = sin_cos(Angle(theta as u32));
        // (a place, the lever and a rate are well within `i32`; an angle wraps)
        p[PX] = at.0.saturating_sub(lever.saturating_mul(i64::from(c)) >> 30) as i32;
        p[PY] = at.1.saturating_sub(lever.saturating_mul(i64::from(s)) >> 30) as i32;
        p[LEVER] = lever as i32;
        p[BIAS] = views.get(last).map_or(0, |v| v.heading.diff(Angle(theta as u32)));
        (p[CW], p[CCW]) = (self.rates.0 as i32, self.rates.1 as i32);
        // the views' headings, back from the last by the compass's turns
        let mut t = theta;
        for i in (0..=last).rev() {
            if let Some(slot) = p.get_mut(HEADING.saturating_add(i)) {
                *slot = t as i32;
            }
            if let (Some(a), Some(b)) = (views.get(i.wrapping_sub(1)), views.get(i)) {
                t = t.saturating_sub(i64::from(b.heading.diff(a.heading)));
            }
        }
        p
    }

    /// Keeps `end` among the cheapest [`KEPT`].
    fn keep(&mut self, end: End) {
        let dearest = self.ends.iter_mut().max_by_key(|e| e.map_or(i64::MAX, |e| e.cost));
        if let Some(slot) = dearest {
            match slot {
                None => *slot = Some(end),
                Some(e) if e.cost > end.cost => {
                    *slot = Some(end);
                    self.dropped = true;
                }
                Some(_) => self.dropped = true,
            }
        }
    }

    /// The cheapest end, vouched for or not (`None` before any start ended).
    pub fn result(&self) -> Option<Refined> {
        let best = self.ends.iter().flatten().min_by_key(|e| e.cost)?;
        let apart = self.ends.iter().flatten().filter(|e| e.apart(best)).map(|e| e.cost).min();
        let dearest = self.ends.iter().flatten().map(|e| e.cost).max().unwrap_or(i64::MAX);
        let rival = match apart {
            Some(c) => c,
            None if self.dropped => dearest,
            None => i64::MAX,
        };
        let vouched = i64::from(best.per_reading) <= FIT_LIMIT && rival.saturating_sub(best.cost) >= RIVAL_GAP;
        let pose = Pose::new(
            Coord::from_length(Length::from_mm(best.x_mm.into())),
            Coord::from_length(Length::from_mm(best.y_mm.into())),
            best.theta,
        );
        Some(Refined { pose, vouched, per_reading: best.per_reading.into() })
    }
}

/// The starts' levers, Q16 mm.
// evaluated by the compiler: an index out of bounds fails the build
#[allow(clippy::indexing_slicing)]
const START_LEVERS: [i64; cfg::START_LEVERS_MM.len()] = {
    let mut t = [0; cfg::START_LEVERS_MM.len()];
    let mut i = 0;
    while i < t.len() {
        t[i] = Length::from_mm_f64(cfg::START_LEVERS_MM[i]).0 as i64;
        i += 1;
    }
    t
};

/// The starts' headings off the fix's, angle LSB.
// evaluated by the compiler: an index out of bounds fails the build
#[allow(clippy::indexing_slicing)]
const START_TURNS: [i32; cfg::START_HEADINGS_DEG.len()] = {
    let mut t = [0; cfg::START_HEADINGS_DEG.len()];
    let mut i = 0;
    while i < t.len() {
        t[i] = Angle::from_degrees_f64(cfg::START_HEADINGS_DEG[i]).0 as i32;
        i += 1;
    }
    t
};

/// Of `views` and the `turns` between them, those the refinement weighs:
/// the last [`cfg::REFINE_VIEWS`] views and the turns between those.
fn weighed<'a>(views: &'a [Readings], turns: &'a [Turn]) -> (&'a [Readings], &'a [Turn]) {
    let first = views.len().saturating_sub(FIT_VIEWS);
    (views.get(first..).unwrap_or(views), turns.get(first..).unwrap_or(&[]))
}

/// Each way's turn a tick from the compass (the median over the turns not
/// blocked), angle LSB: clockwise, counterclockwise; a way never turned
/// gets the survey's planned rate.
fn compass_rates(views: &[Readings], turns: &[Turn]) -> (i64, i64) {
    const PLANNED: i64 = Angle::from_radians_f64(TURN_MRAD_S as f64 / 1000.0 / LOOP_HZ as f64).0 as i64;
    let mut per_way = [[0i64; FIT_VIEWS]; 2];
    let mut counts = [0usize; 2];
    for (pair, t) in views.windows(2).zip(turns) {
        let (Some(a), Some(b)) = (pair.first(), pair.get(1)) else { continue };
        let turned = i64::from(b.heading.diff(a.heading)).saturating_abs();
        let way = usize::from(t.clockwise);
        if t.ticks > 0 && turned > BLOCKED {
            if let (Some(list), Some(n)) = (per_way.get_mut(way), counts.get_mut(way)) {
                if let Some(slot) = list.get_mut(*n) {
                    *slot = div_i64(turned, i64::from(t.ticks)).unwrap_or(PLANNED);
                    *n = n.saturating_add(1);
                }
            }
        }
    }
    // the value with n / 2 of the others below it (no sort: core's brings
    // panic paths into the image)
    let median = |way: usize| {
        let n = counts.get(way).copied().unwrap_or(0);
        let used = per_way.get(way).and_then(|l| l.get(..n)).unwrap_or(&[]);
        let below = |v: i64| used.iter().filter(|&&u| u < v).count();
        let upto = |v: i64| used.iter().filter(|&&u| u <= v).count();
        used.iter().copied().find(|&v| below(v) <= n / 2 && n / 2 < upto(v)).unwrap_or(PLANNED)
    };
    (median(1), median(0))
}
