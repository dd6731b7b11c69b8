//! The physical robot in f64: the true pose of the car's reference point,
//! moved by the motion its servo commands make (with noise), and where its
//! lidars sit. Host only.

use crate::model::lidar::LidarMount;
use crate::model::Motion;

/// How a turn in place moves the reference point.
#[derive(Clone, Copy, PartialEq, Eq, Debug, Default)]
pub enum Kinematics {
    /// A rigid car: the reference point sits D ahead of the axle midpoint
    /// and circles it, `p' - p = D (cos th' - cos th, sin th' - sin th)`
    /// (what `model::step` implements).
    #[default]
    Rigid,
    /// The report's equations as printed (section 3.1):
    /// `x' - x = D (cos th' - cos th)`, `y' - y = D (sin th - sin th')`.
    /// Its y term has the opposite sign of any rigid point; kept to show what
    /// the printed form would do to the firmware's estimate.
    Report,
}

/// A pose in f64: mm, and radians clockwise from north. The one host pose
/// type: the simulator's truth, the tests' f64 references and truths.
#[derive(Clone, Copy, PartialEq, Debug, Default)]
pub struct PoseF64 {
    pub x: f64,
    pub y: f64,
    pub theta: f64,
}

impl PoseF64 {
    pub fn new(x: f64, y: f64, theta: f64) -> PoseF64 {
        PoseF64 { x, y, theta }
    }
    /// From the firmware's fixed-point pose.
    pub fn from_pose(p: &crate::model::Pose) -> PoseF64 {
        PoseF64 { x: p.x.to_mm_f64(), y: p.y.to_mm_f64(), theta: p.theta.to_radians_f64() }
    }
    /// The firmware's fixed-point pose nearest to this one.
    pub fn to_pose(&self) -> crate::model::Pose {
        use crate::math::{Angle, Coord};
        crate::model::Pose::new(
            Coord::from_mm_f64(self.x),
            Coord::from_mm_f64(self.y),
            Angle::from_radians_f64(self.theta),
        )
    }
    /// Where a lidar mounted at `mount` sits and which way it looks
    /// (x, y in mm, direction in radians clockwise from north).
    pub fn lidar_ray(&self, mount: &LidarMount) -> (f64, f64, f64) {
        mount.placed_f64(self.x, self.y, self.theta)
    }
    /// How far a lidar mounted at `mount` sits ahead of the reference
    /// point along its own beam, mm (the lidar model's distance is the
    /// range from the mount plus this).
    pub fn along_beam_mm(mount: &LidarMount) -> f64 {
        mount.along_beam_mm()
    }
    /// Signed heading difference `self - other`, radians in (-pi, pi].
    pub fn heading_error(&self, other: &PoseF64) -> f64 {
        wrap_pi(self.theta - other.theta)
    }
    /// Distance between the two positions, mm.
    pub fn distance(&self, other: &PoseF64) -> f64 {
        (self.x - other.x).hypot(self.y - other.y)
    }
}

/// An angle wrapped into (-pi, pi].
pub fn wrap_pi(a: f64) -> f64 {
    let t = core::f64::consts::TAU;
    let w = a.rem_euclid(t);
    if w > core::f64::consts::PI {
        w - t
    } else {
        w
    }
}

/// A motion in f64 units: straight speed in mm/s (positive forward) or turn
/// rate in rad/s (positive clockwise).
#[derive(Clone, Copy, PartialEq, Debug)]
pub enum MotionF64 {
    Stop,
    Straight(f64),
    Turn(f64),
}

impl MotionF64 {
    pub fn from_motion(m: Motion) -> MotionF64 {
        match m {
            Motion::Stop => MotionF64::Stop,
            Motion::Straight(v) => MotionF64::Straight(v.to_mps_f64() * 1000.0),
            Motion::Turn(w) => MotionF64::Turn(w.to_rad_s_f64()),
        }
    }
}

/// Moves `pose` by `motion` held for `dt_s` seconds (exact for a constant
/// motion), with the turn geometry `kin` and D = `d_mm`.
pub fn advance(pose: &PoseF64, motion: MotionF64, dt_s: f64, kin: Kinematics, d_mm: f64) -> PoseF64 {
    match motion {
        MotionF64::Stop => *pose,
        MotionF64::Straight(v) => {
            let (s, c) = pose.theta.sin_cos();
            PoseF64 { x: pose.x + v * dt_s * c, y: pose.y + v * dt_s * s, theta: pose.theta }
        }
        MotionF64::Turn(w) => {
            let theta = pose.theta + w * dt_s;
            let (s0, c0) = pose.theta.sin_cos();
            let (s1, c1) = theta.sin_cos();
            let dy = match kin {
                Kinematics::Rigid => d_mm * (s1 - s0),
                Kinematics::Report => d_mm * (s0 - s1),
            };
            PoseF64 {
                x: pose.x + d_mm * (c1 - c0),
                y: pose.y + dy,
                theta: wrap_pi(theta).rem_euclid(core::f64::consts::TAU),
            }
        }
    }
}
