//! Going places on the estimate (`goto`, `face`) and the wall stop
//! (`control::goto`, `control::tick`).

use super::{geometry, Length};

/// The wall stop: a forward motion stops when the front lidar reads a
/// target closer than this to the reference point (the car's nose), mm.
/// The reading is up to one timing budget (33 ms, 5 mm at 0.15 m/s)
/// old and the servos take a tick or two to stop (another 3 mm), so a
/// wall square ahead is met at about 40 mm; a wall met at a slant is
/// nearer to the nose's corners than to the beam (at 45 degrees the
/// corner of the 85 mm-wide body is about 30 mm nearer).
pub const WALL_STOP_MM: i32 = 50;
/// `goto` arrives when the estimated reference point is this close to
/// the target, mm: half the promised 20 mm, leaving the other half to
/// the estimate's own error.
pub const ARRIVE_MM: i32 = 8;
/// `goto` and `face` turn in place until the heading is this close to
/// the one wanted, millidegrees: a turn at `TURN_MRAD_S` moves 1.4
/// degrees per loop tick, so stopping within 1 degree leaves the
/// promised 3 degrees for the estimate's error.
pub const TURN_TOLERANCE_MDEG: i32 = 1_000;
/// While driving straight, a heading error past this (millidegrees)
/// stops the leg and turns again (re-planning from the estimate).
pub const STEER_TOLERANCE_MDEG: i32 = 4_000;
/// Speed of `goto`'s straight legs, mm/s: inside what the servos drive
/// both ways at no trim (fwd 124..150, back 108..154, `config::serial`).
pub const SPEED_MM_S: i32 = 130;
/// Turn rate of `goto`'s and `face`'s turns, mrad/s: the slow end of
/// what the servos drive both ways (cw 2377..3300, ccw 2353..3169).
pub const TURN_MRAD_S: i32 = 2_400;
/// A target must be at least this far inside every wall, mm: the wall
/// stop's distance plus the arrival tolerance, so a `goto` that ends
/// facing the wall is not stopped short by the wall stop (and the
/// wheels, 42.5 mm to each side, stay clear of a wall it drives along).
pub const TARGET_WALL_MARGIN_MM: i32 = WALL_STOP_MM + 20;
/// `goto` and `face` refuse to start (and stop) when the estimate's
/// one-sigma position uncertainty is above this, mm: the promise is
/// 20 mm. After `pose` it is 100 mm (`config::estimator`): a second of
/// lidar readings standing still brings it under.
pub const MAX_SIGMA_MM: i32 = 15;
/// The same for the heading, millidegrees.
pub const MAX_SIGMA_MDEG: i32 = 3_000;
/// An estimate too uncertain to steer by (at the start, or grown so on the
/// way) that standing can settle is waited for, standing, at most this
/// long, ms, before the robot localizes: hypotheses that compete (a
/// local re-search's, `config::estimator::RESEARCH_AFTER`), which the
/// tracker weighs on each sensor's next readings, and a standing robot's
/// count once each `config::estimator::EVIDENCE_PERIOD_S` (two of each),
/// or a position the lidars narrow. Not a heading (the compass's bias
/// hides it while the robot stands) nor an unknown pose. Issue 29's hard
/// world, 80 runs of 10 minutes of laps (`tests/sim/hard_world.rs`,
/// `PAPERBOT_SEEDS=80`): 1,908 localizations without the wait, 1,081 with
/// it; median RMS 14.9 -> 14.1 mm, worst run 68.9 -> 41.0.
pub const SETTLE_MS: u32 = (2.0 * super::estimator::EVIDENCE_PERIOD_S * 1000.0) as u32;
/// A `goto` stops when the front lidar sees something this much nearer
/// than the target along the way (an obstacle), mm.
pub const OBSTACLE_MARGIN_MM: i32 = 30;
/// ... for at least this long, ms: more than two lidar periods (33 ms
/// each), so one spurious echo (a glancing beam's, `sim::SPURIOUS_SHARE`)
/// does not stop a `goto` (in the realistic simulator's hour of laps
/// five did); 10 mm of driving at 0.15 m/s.
pub const OBSTACLE_CONFIRM_MS: u32 = 70;
/// Longest a `goto` or `face` may take, ms: the box's diagonal (0.9 m)
/// at 0.13 m/s is 7 s, plus turns.
pub const TIME_LIMIT_MS: u32 = 20_000;
/// Where `goto` plans its turns in place to pivot, mm behind the axle.
/// A turn pivots between the axle and the paper skid that drags 70 mm
/// behind it (report 1), the skid's drag pulling the centre back; the
/// robot's own has not been measured (the hard simulator draws 60 +- 20
/// mm per run, `config::sim::HARD_PIVOT_BEHIND_AXLE_MM`, the lab's world
/// 10). The skid is the conservative end for the walls: planned there,
/// the body's swept circle (the rectangle of `config::geometry::
/// BODY_HALF_WIDTH`, reference point to skid) reaches at most 19.3 mm past
/// the planned one for any true pivot from 10 mm (8.0 mm past) to 80 mm
/// (19.3) behind the axle, and 21.1 mm for one at the axle itself.
pub const TURN_PIVOT_BEHIND_AXLE_MM: i32 = 70;
/// That turning centre's distance behind the reference point (`D` plus
/// the pivot): what `control::tick` passes to `control::goto::Nav::step`
/// until the estimator learns the pivot.
pub const TURN_CENTRE_BEHIND_REFERENCE: Length =
    Length(geometry::ROTATION_TO_REFERENCE.0 + Length::from_mm(TURN_PIVOT_BEHIND_AXLE_MM).0);
/// `goto` turns in place only where the body's swept circle about its
/// turning centre clears every wall by this, mm (else it first drives
/// along its heading until it does): the planned pivot's error, up to
/// 19.3 mm for a true pivot from 10 to 80 mm behind the axle
/// (`TURN_PIVOT_BEHIND_AXLE_MM`); the estimate's own error (the promised
/// 20 mm) comes on top and is not covered.
pub const TURN_WALL_MARGIN_MM: i32 = 20;
