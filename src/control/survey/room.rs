//! Room to turn, from what the survey reads: it does not know where it is
//! (that is what it is finding out), so it cannot check the body's swept
//! circle against the box's walls as `goto` does (`control::goto::room`);
//! it checks it against the walls its lidars show.
//!
//! A turn in place sweeps the body on a circle of radius `R` about its
//! turning centre, [`config::locate::TURN_CENTRE_BEHIND_REFERENCE`] behind
//! the reference point (`R`: the body's farthest corner from it,
//! `control::goto::room::swept_radius`). The survey wants `R` plus [`config::locate::ROOM_MARGIN_MM`]
//! (the reach) of room around the centre:
//!
//! - Ahead, the front lidar reads from the reference point, the centre's
//!   distance ahead of the centre: the drive before the first view leaves
//!   the reach ahead of the reference point (room even for a wall met at a
//!   slant of 55 degrees); before each turn the wall ahead must be
//!   [`config::locate::FRONT_REACH_HALVES`] halves of the reach from the
//!   centre, or, before the search has its [`config::locate::MIN_VIEWS`]
//!   views, at least the reach (room if the wall is square to the beam):
//!   a survey cut short at its first view leaves the fix ambiguous.
//! - To the right, the right lidar reads across the body (the centre lies
//!   on that line's perpendicular): a clockwise turn swings the nose that
//!   way, so it wants the reach there.
//! - Behind and to the left the view sees nothing. Before the first view
//!   the survey drives forward until a wall right behind the centre would
//!   be cleared (as far as the front shows room), or backs up from a wall
//!   seen ahead; a counterclockwise turn is taken only when the right
//!   shows no room, and only when no earlier view saw a wall within the
//!   reach to the left ([`left_clear`]: the views share the turning
//!   centre, and one taken facing the other way saw the left with its
//!   right lidar).
//!
//! A reading that is missing (no target, or a glancing beam) shows no
//! wall: the survey does not stop for it.

use crate::config;
use crate::control::goto::room::{reference_to_skid, swept_radius};
use crate::math::{Angle, Length};
use crate::model::locate::Readings;

/// The room the survey wants around its turning centre, mm: the swept
/// radius plus the margin.
pub fn reach_mm() -> i32 {
    let centre = i64::from(config::locate::TURN_CENTRE_BEHIND_REFERENCE.0 >> 12);
    let radius_mm = (swept_radius(centre) >> 4) as i32; // under 400 mm: fits
    radius_mm.saturating_add(config::locate::ROOM_MARGIN_MM)
}

/// From the turning centre back to the body's back end (the skid), mm
/// (0 when the centre is at the skid).
fn centre_to_back_mm() -> i32 {
    reference_to_skid().saturating_sub(config::locate::TURN_CENTRE_BEHIND_REFERENCE).to_mm().max(0)
}

/// How sure of the wall ahead a turn must be.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum Ahead {
    /// Clear even if met at a slant (up to 48 degrees).
    Slanted,
    /// Clear if met square: the wall the beam reads is the reach or more
    /// from the turning centre.
    Square,
}

/// The front reading a turn wants (see [`room_to_turn`]), mm.
fn front_needed_mm(ahead: Ahead) -> i32 {
    let halves = match ahead {
        Ahead::Slanted => config::locate::FRONT_REACH_HALVES,
        Ahead::Square => 2,
    };
    let from_centre = reach_mm().saturating_mul(halves) / 2;
    from_centre.saturating_sub(config::locate::TURN_CENTRE_BEHIND_REFERENCE.to_mm())
}

/// How far to drive before the first view, mm, forward positive, from the
/// readings taken standing (see the module docs). The aim: the wall ahead
/// [`config::locate::POSITION_SLACK_MM`] farther than a turn wants
/// ([`room_to_turn`]). Nearer: back up to it (at most
/// [`config::locate::MAX_BACK_UP_MM`]: behind is unseen). Farther: drive
/// forward until a wall touching the body's back would be the reach behind
/// the turning centre, but not past the aim. No front reading: stay.
pub fn positioning_mm(front: Option<Length>) -> i32 {
    let Some(front) = front else { return 0 };
    let room = front.to_mm().saturating_sub(aim_mm());
    if room < 0 {
        return room.max(config::locate::MAX_BACK_UP_MM.saturating_neg());
    }
    reach_mm().saturating_sub(centre_to_back_mm()).min(room)
}

/// The front reading the drive before the first view aims for, mm.
fn aim_mm() -> i32 {
    front_needed_mm(Ahead::Slanted).saturating_add(config::locate::POSITION_SLACK_MM)
}

/// A front reading `front` taken while driving forward before the first
/// view ends the drive: the wall ahead is nearer than the aim. The view
/// the drive was planned from read a wall met at a slant along the beam,
/// where glancing readings scatter (the hard world's known-start laps,
/// seed 1, read 285 mm with the wall 266 away, 63 degrees off square) and
/// the wheels run their own distance. The readings while driving are as
/// glancing: a guard, not a guarantee.
pub fn drive_ends(front: Length) -> bool {
    front.to_mm() < aim_mm()
}

/// The view's readings show room for a turn that way: the wall ahead at
/// least [`config::locate::FRONT_REACH_HALVES`] halves of the reach from
/// the turning centre (a wall at a slant is nearer it than the beam
/// says; `Square`: the reach), and for a clockwise turn nothing to the
/// right nearer than the reach.
pub fn room_to_turn(view: &Readings, clockwise: bool, ahead: Ahead) -> bool {
    let front = view.front.is_none_or(|d| d.to_mm() >= front_needed_mm(ahead));
    let right = !clockwise || view.right.is_none_or(|d| d.to_mm() >= reach_mm());
    front && right
}

/// [`config::locate::LEFT_SEEN_DEG`] (below half a turn: fits an i32).
const LEFT_SEEN: Angle = Angle::from_degrees_f64(config::locate::LEFT_SEEN_DEG as f64);

/// No earlier view saw a wall to the left of `heading` within the reach
/// of the turning centre: each reading of `views` in a direction within
/// [`config::locate::LEFT_SEEN_DEG`] of the left is the reach or more from
/// the centre (a front reading from the reference point, ahead of the
/// centre; a right one across it). A view with no such reading says
/// nothing.
pub fn left_clear(views: &[Readings], heading: Angle) -> bool {
    let left = heading.wrapping_sub(Angle::QUARTER_TURN);
    let near = |direction: Angle| direction.diff(left).saturating_abs() <= LEFT_SEEN.0 as i32;
    let behind = config::locate::TURN_CENTRE_BEHIND_REFERENCE.to_mm();
    let clear = |reading: Option<Length>, from_centre: i32| {
        reading.is_none_or(|d| d.to_mm().saturating_add(from_centre) >= reach_mm())
    };
    views.iter().all(|v| {
        (!near(v.heading) || clear(v.front, behind))
            && (!near(v.heading.wrapping_add(Angle::QUARTER_TURN)) || clear(v.right, 0))
    })
}

/// What the survey did to keep the body off the walls (see the module
/// docs).
#[derive(Clone, Copy, Default, PartialEq, Eq, Debug)]
pub struct RoomLog {
    /// The drive before the first view, mm, forward positive (as planned:
    /// the wheels' true distance may differ).
    pub moved_mm: i32,
    /// Turns taken the other way than the last one because the view showed
    /// no room for it (the first turn counterclockwise included).
    pub reversed: u8,
    /// Turns taken with room only for a wall square ahead (before the
    /// search had its views).
    pub squeezed: u8,
    /// Neither way had room: the survey took the views it had.
    pub cut_short: bool,
}
