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
mod search;
pub mod turns;
mod view;

pub use clusters::{Cluster, MAX_CLUSTERS};
pub use search::Search;

use crate::config::locate as cfg;
use crate::math::{Angle, Length};
use crate::model::measurement::Arena;
use crate::model::state::Pose;

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
    Search::new(views)?.with_spot_share(share).finish(arena)
}
