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
//! point (glancing readings fail or lie). The consistent points'
//! mean is the position; their spread, with the grid's own and the lidars'
//! noise, its uncertainty ([`Fix`]).
//!
//! Two ranges and a heading fix a position when the beams meet walls of
//! both axes; when they meet walls of one axis (near a corner, at about 45
//! degrees) the other coordinate is free, and the consistent points spread
//! along it, or they fall into separate groups. Either way the fix is
//! [`Fix::ambiguous`] (spread past [`cfg::AMBIGUOUS_SPAN_MM`]) and its
//! uncertainty says how much: reported, not guessed silently.
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
//! at 5 mm, about 17.5 million lx106 instructions for one view (0.22 s at 80
//! MHz, measured by the lx106 benchmarks); a later view is tried only where
//! the earlier ones fit, and a failed search is repeated at other headings.
//! The loops are bounded by [`MAX_STEPS`] per axis, [`MAX_VIEWS`] and the
//! headings tried. [`Search`] does the same work a few grid columns at a
//! time, so the robot's loop spreads it over its ticks.

use crate::config::locate as cfg;
use crate::math::{isqrt64, mul_q30, Angle, Coord, Length};
use crate::model::measurement::{Arena, Beam, LidarId};
use crate::model::state::Pose;

/// `cos` of [`cfg::GLANCING_DEG`], Q2.30.
const GLANCING_NORMAL: i32 =
    (crate::math::cos_f64(cfg::GLANCING_DEG * core::f64::consts::TAU / 360.0) * (1u32 << 30) as f64) as i32;

/// Grid points per axis at most (a 2 m box at 5 mm).
pub const MAX_STEPS: i32 = 400;

/// Where the search put the robot.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub struct Fix {
    /// The consistent points' mean, at the compass heading.
    pub pose: Pose,
    /// One-sigma uncertainty per axis, mm (Q16): the consistent points'
    /// spread, the grid's and the lidars' noise.
    pub sigma_x: Length,
    pub sigma_y: Length,
    /// How many grid points fit the readings.
    pub points: u32,
    /// The points spread over more than [`cfg::AMBIGUOUS_SPAN_MM`] on an
    /// axis: the readings do not say where along it the robot is.
    pub ambiguous: bool,
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
    sums: Sums,
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
            search_column(arena, &views, self.allowed, x, &mut self.sums);
        }
        None
    }

    /// A pass is over: its fix, or the next pass.
    fn pass_done(&mut self, views: &[Option<View>; MAX_VIEWS]) -> Option<Result<Fix, LocateError>> {
        if let Some(fix) = fix_from(&self.sums, views) {
            return Some(Ok(fix));
        }
        (self.column, self.sums) = (0, Sums::EMPTY);
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
    /// explain (within the tolerance of the model's), or `None` when the
    /// body does not fit in the box there.
    fn misses(&self, arena: &Arena, x: i32, y: i32) -> Option<u32> {
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
        let fits = |id: LidarId, z: Option<Length>| match z {
            None => true,
            Some(z) => {
                let beam = Beam::new(arena, &pose, &id.mount());
                // a beam this glancing may fail or lie: its reading says
                // nothing about this point
                !beam.square_enough(GLANCING_NORMAL)
                    || beam.normal_miss(z).0.saturating_abs() <= mul_q30(self.tol.0, beam.cone_normal)
            }
        };
        Some(u32::from(!fits(LidarId::Front, self.front)) + u32::from(!fits(LidarId::Right, self.right)))
    }
}

/// Sums over the consistent points, whole mm.
#[derive(Clone, Copy, Debug)]
struct Sums {
    n: u32,
    x: i64,
    y: i64,
    xx: i64,
    yy: i64,
    min_x: i32,
    max_x: i32,
    min_y: i32,
    max_y: i32,
}

impl Sums {
    const EMPTY: Sums =
        Sums { n: 0, x: 0, y: 0, xx: 0, yy: 0, min_x: i32::MAX, max_x: i32::MIN, min_y: i32::MAX, max_y: i32::MIN };

    fn add(&mut self, x: i32, y: i32) {
        self.n = self.n.saturating_add(1);
        self.x = self.x.saturating_add(i64::from(x));
        self.y = self.y.saturating_add(i64::from(y));
        self.xx = self.xx.saturating_add(i64::from(x) * i64::from(x));
        self.yy = self.yy.saturating_add(i64::from(y) * i64::from(y));
        (self.min_x, self.max_x) = (self.min_x.min(x), self.max_x.max(x));
        (self.min_y, self.max_y) = (self.min_y.min(y), self.max_y.max(y));
    }
}

/// One grid column (the first view's reference point at `x`): a point must
/// fit the body in the box in every view and explain all the views'
/// readings but `allowed`.
fn search_column(arena: &Arena, views: &[Option<View>; MAX_VIEWS], allowed: u32, x: i32, sums: &mut Sums) {
    let Some(Some(first)) = views.first() else {
        return;
    };
    let wy = first.box_mm.1;
    for j in 0..MAX_STEPS {
        let y = cfg::GRID_MM.saturating_mul(j);
        if y > wy {
            break;
        }
        let mut missed = Some(0u32);
        for v in views.iter().flatten() {
            missed = missed.zip(v.misses(arena, x, y)).map(|(a, b)| a.saturating_add(b)).filter(|&m| m <= allowed);
            if missed.is_none() {
                break;
            }
        }
        if missed.is_some() {
            sums.add(x, y);
        }
    }
}

/// The fix from a pass's consistent points (none: no fix); the pose is the
/// last view's.
fn fix_from(sums: &Sums, views: &[Option<View>; MAX_VIEWS]) -> Option<Fix> {
    let step = cfg::GRID_MM;
    let last = views.iter().flatten().last()?;
    if sums.n == 0 {
        return None;
    }
    let n = i64::from(sums.n);
    // the mean and the spread in 1/256 mm (n >= 1; one division each: once
    // per search, not on the loop)
    let mean = |sum: i64| crate::math::div_i64(sum << 8, n).unwrap_or(0);
    let (mx, my) = (mean(sums.x), mean(sums.y));
    // variance in mm^2 << 16: E[x^2] - mean^2, never negative
    let var = |sq: i64, m: i64| (crate::math::div_i64(sq << 16, n).unwrap_or(0) - m * m).max(0);
    // plus the grid's (step^2 / 12) and the lidar's noise, mm^2 << 16
    let floor = ((i64::from(step) * i64::from(step)) << 16) / 12
        + i64::from(crate::config::estimator::LIDAR_SIGMA.0 >> 8)
            * i64::from(crate::config::estimator::LIDAR_SIGMA.0 >> 8);
    // sqrt(v << 16) = sigma << 8 -> Q16: << 8
    let sigma = |v: i64| Length((isqrt64((v + floor) as u64).min(1 << 22) << 8) as i32);
    let span = cfg::AMBIGUOUS_SPAN_MM;
    let (ox, oy) = (i64::from(last.offset.0) << 8, i64::from(last.offset.1) << 8);
    let pose = Pose::new(
        Coord::from_length(Length(((mx + ox) << 8) as i32)),
        Coord::from_length(Length(((my + oy) << 8) as i32)),
        last.pose.theta,
    );
    Some(Fix {
        pose,
        sigma_x: sigma(var(sums.xx, mx)),
        sigma_y: sigma(var(sums.yy, my)),
        points: sums.n,
        ambiguous: sums.max_x.saturating_sub(sums.min_x) > span || sums.max_y.saturating_sub(sums.min_y) > span,
    })
}
