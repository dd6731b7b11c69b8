//! A view's readings as they come, and the view they make: the lidars'
//! medians and the compass's mean.

use crate::config;
use crate::math::{div_i64, Angle, Length};
use crate::model::locate::Readings;

/// One lidar's distances in a view.
pub(super) type Distances = heapless::Vec<Length, { config::locate::LIDAR_READINGS as usize }>;

/// A view's readings as they come.
#[derive(Clone, Default, Debug)]
pub(super) struct ViewSums {
    pub front: Distances,
    pub right: Distances,
    /// The first heading, and the sum of the others' differences from it
    /// (a mean that does not wrap at north).
    pub first_heading: Option<Angle>,
    pub heading_diffs: i64,
    pub headings: u8,
}

impl ViewSums {
    pub fn complete(&self) -> bool {
        self.front.is_full() && self.right.is_full() && self.headings >= config::locate::COMPASS_READINGS
    }

    /// The view: the lidars' medians (a glancing beam's spurious echo
    /// among them does not move it) and the compass's mean (`None`: no
    /// compass heading).
    pub fn readings(&mut self) -> Option<Readings> {
        let first = self.first_heading?;
        let diff = div_i64(self.heading_diffs, i64::from(self.headings)).unwrap_or(0);
        Some(Readings {
            heading: first.wrapping_add(Angle(diff as u32)),
            front: median(&mut self.front),
            right: median(&mut self.right),
        })
    }
}

/// The middle of `d` (the lower of the two middles of an even count), by
/// an insertion sort of its few readings (core's sort brings panic paths
/// and their messages into the image).
fn median(d: &mut Distances) -> Option<Length> {
    for i in 1..d.len() {
        let mut j = i;
        while let (Some(&a), Some(&b)) = (d.get(j.wrapping_sub(1)), d.get(j)) {
            if a <= b {
                break;
            }
            let k = j.wrapping_sub(1); // j >= 1: d.get(j - 1) was Some
            d.swap(k, j);
            j = k;
        }
    }
    d.get(d.len().saturating_sub(1) / 2).copied()
}
