//! The consistent grid points of a search pass gathered into clusters:
//! places far apart that the readings fit, each with its mean, spread and
//! share of the points ([`Cluster`]), so a fix is never the mean of two
//! places (a point between them that explains nothing).
//!
//! Online, in the grid's scan order: a point joins the cluster whose
//! bounding box, grown by [`cfg::CLUSTER_GAP_MM`], holds it (two clusters
//! it bridges merge); a point near none starts a cluster while there are
//! [`SLOTS`], else joins the nearest. At the pass's end, clusters that
//! together span no more than [`cfg::AMBIGUOUS_SPAN_MM`] on either axis
//! merge (one place, as the search always took it), and the heaviest
//! [`MAX_CLUSTERS`] are reported.

use crate::config::locate as cfg;
use crate::math::{div_i64, isqrt64, Length};

/// Clusters reported at most (the estimator's hypotheses, issue #29).
pub const MAX_CLUSTERS: usize = 4;
/// Clusters kept during a pass (more than reported: a stray point's cluster
/// must not force two places together while the pass goes on).
pub const SLOTS: usize = 6;

/// Sums over a set of grid points, whole mm.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub(super) struct Sums {
    pub n: u32,
    x: i64,
    y: i64,
    xx: i64,
    yy: i64,
    pub min_x: i32,
    pub max_x: i32,
    pub min_y: i32,
    pub max_y: i32,
}

impl Sums {
    pub const EMPTY: Sums =
        Sums { n: 0, x: 0, y: 0, xx: 0, yy: 0, min_x: i32::MAX, max_x: i32::MIN, min_y: i32::MAX, max_y: i32::MIN };

    pub fn add(&mut self, x: i32, y: i32) {
        self.n = self.n.saturating_add(1);
        self.x = self.x.saturating_add(i64::from(x));
        self.y = self.y.saturating_add(i64::from(y));
        self.xx = self.xx.saturating_add(i64::from(x) * i64::from(x));
        self.yy = self.yy.saturating_add(i64::from(y) * i64::from(y));
        (self.min_x, self.max_x) = (self.min_x.min(x), self.max_x.max(x));
        (self.min_y, self.max_y) = (self.min_y.min(y), self.max_y.max(y));
    }

    fn merge(&mut self, o: &Sums) {
        self.n = self.n.saturating_add(o.n);
        self.x = self.x.saturating_add(o.x);
        self.y = self.y.saturating_add(o.y);
        self.xx = self.xx.saturating_add(o.xx);
        self.yy = self.yy.saturating_add(o.yy);
        (self.min_x, self.max_x) = (self.min_x.min(o.min_x), self.max_x.max(o.max_x));
        (self.min_y, self.max_y) = (self.min_y.min(o.min_y), self.max_y.max(o.max_y));
    }

    /// The points spread over more than [`cfg::AMBIGUOUS_SPAN_MM`] on an
    /// axis.
    pub fn wide(&self) -> bool {
        let span = cfg::AMBIGUOUS_SPAN_MM;
        self.max_x.saturating_sub(self.min_x) > span || self.max_y.saturating_sub(self.min_y) > span
    }

    /// How far (x, y) lies outside the bounding box, mm (Chebyshev; 0
    /// inside).
    fn gap(&self, x: i32, y: i32) -> i32 {
        let dx = self.min_x.saturating_sub(x).max(x.saturating_sub(self.max_x)).max(0);
        let dy = self.min_y.saturating_sub(y).max(y.saturating_sub(self.max_y)).max(0);
        dx.max(dy)
    }

    /// The mean (1/256 mm) and the one-sigma spread per axis (Q16 mm), the
    /// grid's and the lidars' noise included; `None` for no points. Two
    /// divisions per call: once per cluster per pass, not per point.
    pub fn stats(&self) -> Option<((i64, i64), Length, Length)> {
        if self.n == 0 {
            return None;
        }
        let n = i64::from(self.n);
        let mean = |sum: i64| div_i64(sum << 8, n).unwrap_or(0);
        let (mx, my) = (mean(self.x), mean(self.y));
        // variance in mm^2 << 16: E[x^2] - mean^2, never negative
        let var = |sq: i64, m: i64| (div_i64(sq << 16, n).unwrap_or(0) - m * m).max(0);
        // plus the grid's (step^2 / 12) and the lidar's noise, mm^2 << 16
        let step = i64::from(cfg::GRID_MM);
        let lidar = i64::from(crate::config::estimator::LIDAR_SIGMA.0 >> 8);
        let floor = ((step * step) << 16) / 12 + lidar * lidar;
        // sqrt(v << 16) = sigma << 8 -> Q16: << 8
        let sigma = |v: i64| Length((isqrt64((v + floor) as u64).min(1 << 22) << 8) as i32);
        Some(((mx, my), sigma(var(self.xx, mx)), sigma(var(self.yy, my))))
    }
}

/// One place the readings fit, at the fix's heading
/// ([`super::Fix::pose_of`] gives its pose).
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub struct Cluster {
    /// Its points' mean.
    pub x: crate::math::Coord,
    pub y: crate::math::Coord,
    /// One-sigma uncertainty per axis, mm (Q16): its points' spread, the
    /// grid's and the lidars' noise.
    pub sigma_x: Length,
    pub sigma_y: Length,
    /// Its share of all the consistent points, Q16 (65,536: all of them).
    pub weight: u32,
    /// Its grid points.
    pub points: u32,
}

/// A pass's clusters as they grow (see the module docs).
#[derive(Clone, Copy, Debug)]
pub(super) struct Gather {
    pub slots: [Sums; SLOTS],
}

impl Gather {
    pub const EMPTY: Gather = Gather { slots: [Sums::EMPTY; SLOTS] };

    /// A consistent point at (x, y), whole mm.
    pub fn add(&mut self, x: i32, y: i32) {
        let gap = cfg::CLUSTER_GAP_MM;
        let mut home: Option<usize> = None;
        for i in 0..SLOTS {
            let Some(s) = self.slots.get(i).copied() else { break };
            if s.n == 0 || s.gap(x, y) > gap {
                continue;
            }
            match home {
                None => home = Some(i),
                // the point bridges two clusters: one place
                Some(h) => {
                    if let Some(into) = self.slots.get_mut(h) {
                        into.merge(&s);
                    }
                    if let Some(gone) = self.slots.get_mut(i) {
                        *gone = Sums::EMPTY;
                    }
                }
            }
        }
        let home = home
            .or_else(|| self.slots.iter().position(|s| s.n == 0))
            .or_else(|| (0..SLOTS).min_by_key(|&i| self.slots.get(i).map_or(i32::MAX, |s| s.gap(x, y))));
        if let Some(s) = home.and_then(|h| self.slots.get_mut(h)) {
            s.add(x, y);
        }
    }

    /// Merges clusters that together span no more than
    /// [`cfg::AMBIGUOUS_SPAN_MM`] (one place), then sorts them heaviest
    /// first.
    pub fn settle(&mut self) {
        let mut merged = true;
        while merged {
            merged = false;
            for i in 0..SLOTS {
                for j in i.saturating_add(1)..SLOTS {
                    let (Some(a), Some(b)) = (self.slots.get(i).copied(), self.slots.get(j).copied()) else { continue };
                    if a.n == 0 || b.n == 0 {
                        continue;
                    }
                    let mut both = a;
                    both.merge(&b);
                    if !both.wide() {
                        if let Some(s) = self.slots.get_mut(i) {
                            *s = both;
                        }
                        if let Some(s) = self.slots.get_mut(j) {
                            *s = Sums::EMPTY;
                        }
                        merged = true;
                    }
                }
            }
        }
        // a few slots: an insertion sort (core's sort brings panic paths)
        for i in 1..SLOTS {
            let mut j = i;
            while let (Some(a), Some(b)) = (self.slots.get(j.wrapping_sub(1)), self.slots.get(j)) {
                if a.n >= b.n {
                    break;
                }
                let k = j.wrapping_sub(1); // j >= 1: the get above was Some
                self.slots.swap(k, j);
                j = k;
            }
        }
    }

    /// The settled clusters with points, heaviest first.
    pub fn clusters(&self) -> impl Iterator<Item = &Sums> {
        self.slots.iter().filter(|s| s.n > 0)
    }
}
