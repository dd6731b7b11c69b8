//! Room to turn: a turn in place sweeps the body on a circle about its
//! turning centre `C`, of the radius of the body's farthest corner from
//! `C` (the body is the rectangle of [`config::geometry::BODY_HALF_WIDTH`]
//! from the reference point back to the skid). Before `goto` turns, that
//! circle must clear every wall by [`config::goto::TURN_WALL_MARGIN_MM`]:
//! `C` must lie in the box shrunk by radius plus margin on every side (the
//! safe rectangle). If it does not, driving straight moves `C` along the
//! heading; [`room`] says which way moves it off the walls it is too near,
//! until it clears them, or that no way does.
//!
//! Integer only, no division (the lx106 has no divide instruction): one
//! square root for the radius, then sums. Positions in 1/16 mm as in
//! `control::goto`, the heading's unit vector in Q30.

use crate::config;
use crate::math::{isqrt64, Length};
use crate::model::measurement::Arena;

/// A heading within 30 degrees of a wall runs along it: the sine of 30
/// degrees in Q30 (driving 100 mm moves the centre off it 50 mm at most).
const ALONG_WALL: i64 = 1 << 29;

/// What a turn about a centre needs first.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum Room {
    /// The swept circle clears every wall: turn here.
    Fits,
    /// Drive straight forward (or backward, false) first: that way the
    /// centre moves off the walls it is too near.
    Drive { forward: bool },
    /// Too near a wall, and driving along the heading does not help: it
    /// runs along that wall, or moves the centre off one wall and onto
    /// another.
    Cramped,
}

/// The body's length from the reference point back to the skid (its back
/// end).
pub fn reference_to_skid() -> Length {
    config::geometry::ROTATION_TO_REFERENCE.saturating_add(config::geometry::SKID_BEHIND_AXLE)
}

/// The body's swept radius about a centre `centre_q4` behind the
/// reference point (1/16 mm): its farthest corner, front (the reference
/// point's side) or back (the skid's).
pub fn swept_radius(centre_q4: i64) -> i64 {
    let back = q4(reference_to_skid().0);
    let half_width = q4(config::geometry::BODY_HALF_WIDTH.0);
    let along = centre_q4.saturating_abs().max(back.saturating_sub(centre_q4).saturating_abs());
    let sq = along.saturating_mul(along).saturating_add(half_width.saturating_mul(half_width));
    i64::from(isqrt64(sq.unsigned_abs()))
}

/// Where a turn of swept radius `radius` about the centre `(cx, cy)` can
/// be made, moving along the heading `(ux, uy)` (Q30) in `arena` (see the
/// module docs). Each wall the circle comes too near asks for one way
/// along the heading (the way that moves the centre off it); a wall the
/// heading runs within [`ALONG_WALL`] of asks nothing (driving hardly moves
/// the centre off it). Asked both ways, or not at all: `Cramped`.
pub fn room(cx: i64, cy: i64, ux: i64, uy: i64, radius: i64, arena: &Arena) -> Room {
    let reach = radius.saturating_add(i64::from(config::goto::TURN_WALL_MARGIN_MM) << 4);
    let mut clear = true;
    let mut way = None;
    for (c, u, size) in [(cx, ux, q4(arena.length_x.0)), (cy, uy, q4(arena.width_y.0))] {
        // the centre's distance inside the low wall's limit and the high
        // wall's, and how each changes driving forward (Q30)
        for (slack, rate) in
            [(c.saturating_sub(reach), u), (size.saturating_sub(reach).saturating_sub(c), u.saturating_neg())]
        {
            if slack >= 0 {
                continue;
            }
            clear = false;
            if rate.saturating_abs() < ALONG_WALL {
                continue;
            }
            let forward = rate > 0;
            if way.is_some_and(|w| w != forward) {
                return Room::Cramped;
            }
            way = Some(forward);
        }
    }
    match way {
        _ if clear => Room::Fits,
        Some(forward) => Room::Drive { forward },
        None => Room::Cramped,
    }
}

/// The body at the reference point `(px, py)` with heading `(ux, uy)`
/// (Q30) may drive straight forward (or backward, false): the two corners
/// of its leading end (the reference point's, or the skid's) are each
/// [`config::goto::TURN_WALL_MARGIN_MM`] or more inside every wall they
/// move towards. A drive to make room never pushes the body into a wall.
pub fn may_drive(px: i64, py: i64, ux: i64, uy: i64, forward: bool, arena: &Arena) -> bool {
    let margin = i64::from(config::goto::TURN_WALL_MARGIN_MM) << 4;
    let half_width = q4(config::geometry::BODY_HALF_WIDTH.0);
    let back = q4(reference_to_skid().0);
    // the leading end's middle, and half its width along the right (-uy, ux)
    let along = if forward { 0 } else { back.saturating_neg() };
    let (mx, my) =
        (px.saturating_add(along.saturating_mul(ux) >> 30), py.saturating_add(along.saturating_mul(uy) >> 30));
    let (wx, wy) = (half_width.saturating_mul(uy.saturating_neg()) >> 30, half_width.saturating_mul(ux) >> 30);
    let (vx, vy) = if forward { (ux, uy) } else { (ux.saturating_neg(), uy.saturating_neg()) };
    let clear = |k: i64, v: i64, size: i64| match v {
        0 => true,
        v if v > 0 => size.saturating_sub(k) >= margin,
        _ => k >= margin,
    };
    let (lx, ly) = (q4(arena.length_x.0), q4(arena.width_y.0));
    [(mx.saturating_add(wx), my.saturating_add(wy)), (mx.saturating_sub(wx), my.saturating_sub(wy))]
        .iter()
        .all(|&(x, y)| clear(x, vx, lx) && clear(y, vy, ly))
}

/// A Q16 length in 1/16 mm.
fn q4(bits: i32) -> i64 {
    i64::from(bits >> 12)
}
