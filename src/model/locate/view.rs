//! One view as the search tries it at a grid point: where its reference
//! point is (the turns in place between views, about a pivot the search
//! does not know), which of its readings the point explains, and how well.
//!
//! # The turns between views
//! A turn in place pivots about a point `p` behind the axle (the skid's
//! drag: the lab's 10 mm, `sim::PIVOT_BEHIND_AXLE_MM`; the hard world's
//! 60 +- 20, issue #29): the reference point, D ahead of the axle, circles
//! it at radius D + p. From heading `from` to `to` it moves by
//! `(D + p) (cos to - cos from, sin to - sin from)`, and the pivot stays
//! where it is over all the turns, so each view's point is that chord from
//! the first's: a one-parameter family of places. The search tries each
//! of [`cfg::PIVOTS_BEHIND_AXLE_MM`] at every grid point that explains the
//! first view, and keeps the one whose readings fit best ([`Score`]).

use crate::config::locate as cfg;
use crate::math::{mul_q30, Angle, Coord, Length};
use crate::model::measurement::{Arena, Beam, LidarId};
use crate::model::state::Pose;

use super::{Readings, GLANCING_NORMAL};

/// Pivots tried.
pub const PIVOTS: usize = cfg::PIVOTS_BEHIND_AXLE_MM.len();

/// How well a grid point explains a view's readings (or several views').
#[derive(Clone, Copy, PartialEq, Eq, Debug, Default)]
pub(super) struct Score {
    /// Readings the point does not explain (within the tolerance).
    pub missed: u32,
    /// Readings it explains.
    pub explained: u32,
    /// The explained readings' misses along their walls' normals, mm Q16:
    /// the lower, the better the point fits (which pivot: [`View`]).
    pub cost: u32,
}

impl Score {
    pub fn add(self, o: Score) -> Score {
        Score {
            missed: self.missed.saturating_add(o.missed),
            explained: self.explained.saturating_add(o.explained),
            cost: self.cost.saturating_add(o.cost),
        }
    }
}

/// One view at a tried heading.
#[derive(Clone, Copy)]
pub(super) struct View {
    pub pose: Pose,
    front: Option<Length>,
    right: Option<Length>,
    /// Where this view's reference point is from the first view's, whole
    /// mm, per pivot tried (all zero for the first view).
    pub offsets: [(i32, i32); PIVOTS],
    lidars: [(i32, i32); 2],
    tol: Length,
    /// Where in its spot a range comes from (Q30, the estimator's learned
    /// share: `model::estimator`'s spot.rs).
    share: i32,
    pub box_mm: (i32, i32),
}

impl View {
    /// `r` (its heading the one tried), taken after turns in place from the
    /// first view's heading `first` (`r`'s own for the first view), with
    /// the tolerance `tol` and the lidar spot's share `share`.
    pub fn new(arena: &Arena, r: &Readings, first: Angle, tol: Length, share: i32) -> View {
        let pose = Pose::from_mm(0, 0, r.heading);
        let (s, c) = { pose }.sin_cos();
        let (s0, c0) = Pose::from_mm(0, 0, first).sin_cos();
        // each lidar's offset from the reference point in the box, mm
        let lidar = |id: LidarId| {
            let m = id.mount();
            let dx = mul_q30(m.forward.0, c).saturating_sub(mul_q30(m.right.0, s)) >> 16;
            let dy = mul_q30(m.forward.0, s).saturating_add(mul_q30(m.right.0, c)) >> 16;
            (dx, dy)
        };
        let d = crate::config::geometry::ROTATION_TO_REFERENCE;
        let mut offsets = [(0, 0); PIVOTS];
        for (o, p) in offsets.iter_mut().zip(cfg::PIVOTS_BEHIND_AXLE_MM) {
            let radius = d.saturating_add(Length::from_mm(p)).0;
            let dx = mul_q30(radius, c).saturating_sub(mul_q30(radius, c0)) >> 16;
            let dy = mul_q30(radius, s).saturating_sub(mul_q30(radius, s0)) >> 16;
            *o = (dx, dy);
        }
        View {
            pose,
            front: r.front,
            right: r.right,
            offsets,
            lidars: [lidar(LidarId::Front), lidar(LidarId::Right)],
            tol,
            share,
            box_mm: (arena.length_x.0 >> 16, arena.width_y.0 >> 16),
        }
    }

    /// Where this view's reference point is when the first view's is at
    /// the grid point (x, y), with the pivot `pivot` (its index), whole mm.
    pub fn at(&self, x: i32, y: i32, pivot: usize) -> (i32, i32) {
        let offset = self.offsets.get(pivot).copied().unwrap_or((0, 0));
        (x.saturating_add(offset.0), y.saturating_add(offset.1))
    }

    /// How well the first view's grid point (x, y) explains this view's
    /// readings with the pivot `pivot` (its index), or `None` when the body
    /// does not fit in the box there. A beam that would meet its wall past
    /// [`cfg::GLANCING_DEG`] says nothing about the point (glancing
    /// readings fail or lie): neither explained nor missed.
    pub fn score(&self, arena: &Arena, x: i32, y: i32, pivot: usize) -> Option<Score> {
        let (x, y) = self.at(x, y, pivot);
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
            None => Score::default(),
            Some(z) => {
                let beam = Beam::new(arena, &pose, &id.mount());
                if !beam.square_enough(GLANCING_NORMAL) {
                    return Score::default();
                }
                let mut miss = beam.normal_miss(z).0;
                // (a learned share costs a slice about 9 %: skipped at 0)
                if self.share != 0 {
                    miss = miss.saturating_sub(mul_q30(beam.spot_spread(z).0, self.share));
                }
                let miss = miss.saturating_abs();
                if miss <= mul_q30(self.tol.0, beam.cone_normal) {
                    Score { explained: 1, cost: miss.max(0) as u32, ..Score::default() }
                } else {
                    Score { missed: 1, ..Score::default() }
                }
            }
        };
        Some(fits(LidarId::Front, self.front).add(fits(LidarId::Right, self.right)))
    }
}
