//! The lidar sensor model (report section 3.3), in the direction the data
//! was fitted: `distance = slope * reading + intercept`, where `reading` is
//! the VL53L0X's output in mm and `distance` is from the car's reference
//! point (the report's text has it the other way round; its data does not).

use crate::math::{round_f64, sat_i32, Angle, Length};

/// Where a lidar sits relative to the car's reference point, in the car's
/// frame (mm forward, mm right), and which way it looks (the config's
/// `geometry::FRONT_LIDAR` and `RIGHT_LIDAR`).
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub struct LidarMount {
    pub forward: Length,
    pub right: Length,
    /// Beam direction relative to the heading (clockwise).
    pub direction: Angle,
}

/// The mount's geometry in f64 for the host's pictures and simulator
/// (`sim::body`, `sim::svg`, the teleop tool's page): never on the robot.
#[cfg(feature = "std")]
impl LidarMount {
    /// Where this lidar sits and which way it looks on a body whose
    /// reference point is at (`x`, `y`) mm heading `theta` (radians
    /// clockwise from north): (x, y) in mm and the beam's direction.
    pub fn placed_f64(&self, x: f64, y: f64, theta: f64) -> (f64, f64, f64) {
        let (s, c) = theta.sin_cos();
        let (f, r) = (self.forward.to_mm_f64(), self.right.to_mm_f64());
        // in (x north, y east) the heading is (cos, sin) and the car's right (-sin, cos)
        (x + f * c - r * s, y + f * s + r * c, theta + self.direction.to_radians_f64())
    }

    /// How far the lidar sits ahead of the reference point along its own
    /// beam, mm (the lidar model's distance is the range from the mount
    /// plus this).
    pub fn along_beam_mm(&self) -> f64 {
        let (bs, bc) = self.direction.to_radians_f64().sin_cos();
        self.forward.to_mm_f64() * bc + self.right.to_mm_f64() * bs
    }

    /// A reading's beam on that body, from the lidar to where it ended:
    /// `distance_mm` is the lidar model's distance from the reference point
    /// along the beam, so the beam runs that less [`Self::along_beam_mm`].
    pub fn beam_f64(&self, x: f64, y: f64, theta: f64, distance_mm: f64) -> ((f64, f64), (f64, f64)) {
        let (lx, ly, dir) = self.placed_f64(x, y, theta);
        let range = distance_mm - self.along_beam_mm();
        ((lx, ly), (lx + range * dir.cos(), ly + range * dir.sin()))
    }
}

/// One lidar's fitted line and its valid reading window.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub struct LidarModel {
    /// Slope in Q16 (dimensionless, mm per mm).
    pub slope_q16: i32,
    /// Intercept in mm.
    pub intercept: Length,
    /// Readings below this (mm) mean a distance closer than the mounting
    /// allows (see [`LidarModel::new`]): reported as too close.
    pub min_reading_mm: u16,
    /// Readings above this (mm) are beyond reliable range: no target.
    pub max_reading_mm: u16,
}

/// What one lidar reading means.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum Range {
    /// Distance from the car's reference point to the target.
    Target(Length),
    /// Nothing in range (8190/8191 from the chip, or past the valid window).
    NoTarget,
    /// Closer than the mounting allows (below the valid window): not a
    /// measurement (a lidar whose beam starts behind the reference point
    /// and meets a wall before it, or a target pressed against the car).
    TooClose,
}

impl Range {
    pub fn distance(self) -> Option<Length> {
        match self {
            Range::Target(d) => Some(d),
            _ => None,
        }
    }
}

/// VL53L0X readings at or above this mean "no target" (8190 and 8191).
pub const NO_TARGET_READING: u16 = 8190;

impl LidarModel {
    /// The line `distance = slope reading + intercept_mm`; readings whose
    /// distance is below `min_distance_mm` are [`Range::TooClose`] (the
    /// smallest reading kept is the first whose distance reaches it), those
    /// above `max_reading_mm` [`Range::NoTarget`]. `slope` must be positive.
    pub const fn new(slope: f64, intercept_mm: f64, min_distance_mm: f64, max_reading_mm: u16) -> LidarModel {
        // the reading at min_distance, rounded up
        let at = (min_distance_mm - intercept_mm) / slope;
        let r = round_f64(at);
        let r = if (r as f64) < at { r + 1 } else { r };
        let min_reading_mm = if r < 0 {
            0
        } else if r > u16::MAX as i64 {
            u16::MAX
        } else {
            r as u16
        };
        LidarModel {
            slope_q16: sat_i32(round_f64(slope * 65536.0)),
            intercept: Length::from_mm_f64(intercept_mm),
            min_reading_mm,
            max_reading_mm,
        }
    }

    /// Applies the model to a raw reading (mm). One 32-bit multiply.
    pub fn range(&self, reading_mm: u16) -> Range {
        if reading_mm >= NO_TARGET_READING || reading_mm > self.max_reading_mm {
            return Range::NoTarget;
        }
        if reading_mm < self.min_reading_mm {
            return Range::TooClose;
        }
        // reading < 8190 < 2^13, so the product fits in i32 for any slope
        // below 2^17 (2.0); the saturation only guards a nonsense config.
        let d = self.slope_q16.saturating_mul(i32::from(reading_mm)).saturating_add(self.intercept.0);
        Range::Target(Length(d))
    }

    /// The raw reading (mm, rounded) that the model maps to `distance`:
    /// what a simulated chip reports for a true distance.
    pub fn reading_for(&self, distance: Length) -> Option<u16> {
        let num = i64::from(distance.0) - i64::from(self.intercept.0);
        let r = crate::math::div_round(num, i64::from(self.slope_q16))?;
        u16::try_from(r.max(0)).ok()
    }
}
