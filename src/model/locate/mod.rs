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
//! A turn in place keeps the axle and swings the reference point D ahead of
//! it (the state update's model), so a grid point for the first view is,
//! after turns, a known point for each later view: a point is consistent
//! when it explains every view. Views in more directions put beams on walls
//! of both axes. A view after a turn that did not happen (a body against a
//! wall; the compass shows it) is the same view again and adds nothing.
//! One reading in all may go unexplained (a spurious echo) when nothing
//! explains them all ([`cfg::MIN_READINGS_FOR_OUTLIER`]).
//!
//! # Cost
//! Two [`Beam`]s per grid point and view: 153 x 99 points in the team's box
//! at 5 mm, about 17.7 million lx106 instructions for one view (0.22 s at 80
//! MHz, measured by the lx106 benchmarks); a later view is tried only where
//! the earlier ones fit, and a failed search is repeated at other headings.
//! The loops are bounded by [`MAX_STEPS`] per axis, [`MAX_VIEWS`] and the
//! headings tried. [`Search`] does the same work a few grid columns at a
//! time, so the robot's loop spreads it over its ticks.

pub mod clusters;

pub use clusters::{Cluster, MAX_CLUSTERS};

use crate::config::locate as cfg;
use crate::math::{mul_q30, Angle, Coord, Length};
use crate::model::measurement::{Arena, Beam, LidarId};
use crate::model::state::Pose;
use clusters::{Gather, Sums};

/// `cos` of [`cfg::GLANCING_DEG`], Q2.30.
const GLANCING_NORMAL: i32 =
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
/// several taken in turn with a turn in place between each (the axle
/// stays, the reference point D ahead of it circles it, as in the state
/// update). Each turn is the difference of two compass headings, so a
/// disturbed compass shifts all views alike. A pose must explain every
/// view; the fix is the last view's pose (where the robot now is). The
/// turned views' tolerance adds [`cfg::TURN_TOLERANCE_MM`] for a real
/// turn's pivot off the axle. Views past [`MAX_VIEWS`] are not used. Two
/// views can agree on a wrong pose far off; the robot's procedure
/// (`control::localize`) takes at least three, 45 degrees apart (turning
/// the other way when the compass shows a turn blocked), and more while
/// the fix is ambiguous.
///
/// The headings tried are the compass's and, when nothing fits there,
/// [`cfg::HEADING_STEP_DEG`] apart ever further from it, up to
/// [`cfg::HEADING_STEPS`] each way (the compass may be disturbed).
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
    /// Readings a point may leave unexplained in this pass (0 or 1).
    allowed: u32,
    /// The next grid column of this pass.
    column: i32,
    /// All the consistent points, and their clusters.
    sums: Sums,
    gather: Gather,
}

impl Search {
    /// Passes over the grid at most: two per heading tried.
    pub const MAX_PASSES: u32 = 2 * (2 * cfg::HEADING_STEPS as u32 + 1);

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
            sums: Sums::EMPTY,
            gather: Gather::EMPTY,
        })
    }

    /// Searches up to `columns` more grid columns: `None` while the search
    /// goes on, then its answer (the same as [`locate`]'s).
    pub fn step(&mut self, arena: &Arena, columns: u32) -> Option<Result<Fix, LocateError>> {
        if self.heading_try > 2 * u32::from(cfg::HEADING_STEPS) {
            return Some(Err(LocateError::NothingFits));
        }
        let views = self.tried(arena);
        let lx = arena.length_x.0 >> 16;
        for _ in 0..columns {
            let x = cfg::GRID_MM.saturating_mul(self.column);
            if x > lx || self.column >= MAX_STEPS {
                return self.pass_done(&views);
            }
            self.column = self.column.saturating_add(1);
            search_column(arena, &views, self.allowed, x, &mut self.sums, &mut self.gather);
        }
        None
    }

    /// A pass is over: its fix, or the next pass.
    fn pass_done(&mut self, views: &[Option<View>; MAX_VIEWS]) -> Option<Result<Fix, LocateError>> {
        self.gather.settle();
        if let Some(fix) = fix_from(&self.sums, &self.gather, views) {
            return Some(Ok(fix));
        }
        (self.column, self.sums, self.gather) = (0, Sums::EMPTY, Gather::EMPTY);
        // one failed reading (a spurious echo) among many must not hide
        // the pose the others agree on
        if self.allowed == 0 && self.readings > cfg::MIN_READINGS_FOR_OUTLIER {
            self.allowed = 1;
            return None;
        }
        self.allowed = 0;
        self.heading_try = self.heading_try.saturating_add(1);
        None
    }

    /// The views at this pass's heading: the compass's, or shifted by
    /// whole heading steps (a disturbed compass), alternately up and down.
    fn tried(&self, arena: &Arena) -> [Option<View>; MAX_VIEWS] {
        let k = self.heading_try;
        let off = Angle(Angle::from_degrees_f64(cfg::HEADING_STEP_DEG).0.wrapping_mul(k.div_ceil(2)));
        let shifted = |r: &Readings| if k % 2 == 1 { r.heading.wrapping_add(off) } else { r.heading.wrapping_sub(off) };
        let views = self.views.get(..self.count).unwrap_or(&[]);
        let mut tried: [Option<View>; MAX_VIEWS] = [None; MAX_VIEWS];
        let Some(first) = views.first() else {
            return tried;
        };
        for (i, (slot, r)) in tried.iter_mut().zip(views).enumerate() {
            let heading = shifted(r);
            let (offset, tol) = if i == 0 {
                ((0, 0), cfg::TOLERANCE_MM)
            } else {
                (turn_offset(shifted(first), heading), cfg::TOLERANCE_MM + cfg::TURN_TOLERANCE_MM)
            };
            *slot = Some(View::new(arena, &Readings { heading, ..*r }, offset, tol));
        }
        tried
    }
}

/// How far a turn in place from heading `from` to `to` moves the reference
/// point, whole mm: `D (cos to - cos from, sin to - sin from)`.
fn turn_offset(from: Angle, to: Angle) -> (i32, i32) {
    let d = crate::config::geometry::ROTATION_TO_REFERENCE.0;
    let (s0, c0) = Pose::from_mm(0, 0, from).sin_cos();
    let (s1, c1) = Pose::from_mm(0, 0, to).sin_cos();
    let dx = mul_q30(d, c1).saturating_sub(mul_q30(d, c0)) >> 16;
    let dy = mul_q30(d, s1).saturating_sub(mul_q30(d, s0)) >> 16;
    (dx, dy)
}

/// One view as the search tries it: its readings, where its reference
/// point is from the grid point (whole mm), and its lidars' offsets.
#[derive(Clone, Copy)]
struct View {
    pose: Pose,
    front: Option<Length>,
    right: Option<Length>,
    offset: (i32, i32),
    lidars: [(i32, i32); 2],
    tol: Length,
    box_mm: (i32, i32),
}

impl View {
    fn new(arena: &Arena, r: &Readings, offset: (i32, i32), tol_mm: f64) -> View {
        let mut pose = Pose::from_mm(0, 0, r.heading);
        let (s, c) = pose.sin_cos();
        // each lidar's offset from the reference point in the box, mm
        let lidar = |id: LidarId| {
            let m = id.mount();
            let dx = mul_q30(m.forward.0, c).saturating_sub(mul_q30(m.right.0, s)) >> 16;
            let dy = mul_q30(m.forward.0, s).saturating_add(mul_q30(m.right.0, c)) >> 16;
            (dx, dy)
        };
        View {
            pose,
            front: r.front,
            right: r.right,
            offset,
            lidars: [lidar(LidarId::Front), lidar(LidarId::Right)],
            tol: Length::from_mm_f64(tol_mm),
            box_mm: (arena.length_x.0 >> 16, arena.width_y.0 >> 16),
        }
    }

    /// How many of this view's readings the grid point (x, y) does not
    /// explain (within the tolerance of the model's), and how many it does
    /// (a glancing beam's reading is neither), or `None` when the body does
    /// not fit in the box there.
    fn misses(&self, arena: &Arena, x: i32, y: i32) -> Option<(u32, u32)> {
        let (x, y) = (x.saturating_add(self.offset.0), y.saturating_add(self.offset.1));
        let (lx, wy) = self.box_mm;
        let inside = |o: &(i32, i32)| {
            let (px, py) = (x.saturating_add(o.0), y.saturating_add(o.1));
            px >= 0 && px <= lx && py >= 0 && py <= wy
        };
        if !self.lidars.iter().all(inside) {
            return None;
        }
        let mut pose = self.pose;
        pose.x = Coord::from_length(Length::from_mm(x));
        pose.y = Coord::from_length(Length::from_mm(y));
        // (missed, explained)
        let fits = |id: LidarId, z: Option<Length>| match z {
            None => (0, 0),
            Some(z) => {
                let beam = Beam::new(arena, &pose, &id.mount());
                // a beam this glancing may fail or lie: its reading says
                // nothing about this point
                if !beam.square_enough(GLANCING_NORMAL) {
                    (0, 0)
                } else if beam.normal_miss(z).0.saturating_abs() <= mul_q30(self.tol.0, beam.cone_normal) {
                    (0, 1)
                } else {
                    (1, 0)
                }
            }
        };
        let (front, right) = (fits(LidarId::Front, self.front), fits(LidarId::Right, self.right));
        Some((front.0 + right.0, front.1 + right.1))
    }
}

/// One grid column (the first view's reference point at `x`): a point must
/// fit the body in the box in every view, explain all the views' readings
/// but `allowed`, and explain at least one.
fn search_column(
    arena: &Arena,
    views: &[Option<View>; MAX_VIEWS],
    allowed: u32,
    x: i32,
    sums: &mut Sums,
    gather: &mut Gather,
) {
    let Some(Some(first)) = views.first() else {
        return;
    };
    let wy = first.box_mm.1;
    for j in 0..MAX_STEPS {
        let y = cfg::GRID_MM.saturating_mul(j);
        if y > wy {
            break;
        }
        // (missed, explained) over the views so far
        let mut counts = Some((0u32, 0u32));
        for v in views.iter().flatten() {
            counts = counts
                .zip(v.misses(arena, x, y))
                .map(|((m, e), (vm, ve))| (m.saturating_add(vm), e.saturating_add(ve)))
                .filter(|&(m, _)| m <= allowed);
            if counts.is_none() {
                break;
            }
        }
        if counts.is_some_and(|(_, explained)| explained > 0) {
            sums.add(x, y);
            gather.add(x, y);
        }
    }
}

/// The fix from a pass's consistent points and their settled clusters
/// (none: no fix); the poses are the last view's.
fn fix_from(sums: &Sums, gather: &Gather, views: &[Option<View>; MAX_VIEWS]) -> Option<Fix> {
    let last = views.iter().flatten().last()?;
    let (_, sigma_x, sigma_y) = sums.stats()?;
    let (ox, oy) = (i64::from(last.offset.0) << 8, i64::from(last.offset.1) << 8);
    // a mean in 1/256 mm of the first view's point -> the last view's
    let at = |m: i64, o: i64| Coord::from_length(Length(((m + o) << 8) as i32));
    let empty = Cluster { x: last.pose.x, y: last.pose.y, sigma_x, sigma_y, weight: 0, points: 0 };
    let mut slots = [empty; MAX_CLUSTERS];
    let mut count = 0u8;
    for (slot, c) in slots.iter_mut().zip(gather.clusters()) {
        let Some((mean, sx, sy)) = c.stats() else { continue };
        let weight = crate::math::div_i64(i64::from(c.n) << 16, i64::from(sums.n)).unwrap_or(0) as u32;
        let (mx, my) = mean;
        *slot = Cluster { x: at(mx, ox), y: at(my, oy), sigma_x: sx, sigma_y: sy, weight, points: c.n };
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
