//! The survey's moves: the drive that makes room before the first view,
//! each view kept, and the turns between views (which way, and how far,
//! as the room the views show allows: `room.rs`, `sweep.rs`; ended on the
//! compass: `turning.rs`).

use super::room::{self, Ahead};
use super::turning::Turning;
use super::{ticks, Action, Failure, Phase, Survey, BLOCKED};
use crate::config;
use crate::math::Angle;
use crate::model::locate::turns::Turn;

impl Survey {
    /// A view is in: kept, then a search or another turn.
    pub(super) fn view_taken(&mut self) -> Action {
        let Some(r) = self.view.readings() else {
            return Action::Done(Err(Failure::NoHeading));
        };
        if !self.positioned {
            self.positioned = true;
            let mm = room::positioning_mm(r.front);
            if mm != 0 {
                return self.drive(mm);
            }
        }
        let previous = self.views().last().copied();
        if let Some(previous) = previous {
            if r.heading.diff(previous.heading).saturating_abs() < BLOCKED {
                self.sweep.blocked(self.clockwise);
                self.clockwise = !self.clockwise;
            } else {
                self.sweep.turned(self.clockwise);
            }
        }
        self.sweep.view_taken(self.count);
        if let Some(slot) = self.views.get_mut(self.count) {
            *slot = r;
            self.count = self.count.saturating_add(1);
        }
        if self.count < config::locate::MIN_VIEWS {
            return self.turn();
        }
        self.search()
    }

    /// Drives `mm` (forward positive) to make room before the first view.
    fn drive(&mut self, mm: i32) -> Action {
        self.room.moved_mm = mm;
        // ms = mm * 1000 / (mm/s), whole ticks (a planned drive of at most
        // a few hundred mm: no overflow)
        let ms = mm.unsigned_abs().saturating_mul(1000).checked_div(config::locate::POSITION_MM_S.unsigned_abs());
        self.enter(Phase::Drive { forward: mm > 0, ticks: ticks(ms.unwrap_or(0)) })
    }

    /// Which way the next turn has room, past the edge of the swept
    /// ground the view taken there shows room beyond, and how sure of the
    /// wall ahead it is; `None` when neither way has room.
    pub(super) fn way(&self) -> Option<(bool, Ahead)> {
        let sw = self.sweep;
        let views = self.views();
        let room = |clockwise: bool, ahead: Ahead| {
            let edge_view = sw.open_edge_view(clockwise).and_then(|i| views.get(i));
            edge_view.is_some_and(|v| {
                room::room_to_turn(v, clockwise, ahead) && (clockwise || room::left_clear(views, v.heading))
            })
        };
        let few = self.count < config::locate::MIN_VIEWS;
        [(self.clockwise, Ahead::Slanted), (!self.clockwise, Ahead::Slanted)]
            .into_iter()
            .chain(
                few.then_some([(self.clockwise, Ahead::Square), (!self.clockwise, Ahead::Square)])
                    .into_iter()
                    .flatten(),
            )
            .find(|&(clockwise, ahead)| room(clockwise, ahead))
    }

    /// The next turn ([`Survey::way`]), or the search of the views there
    /// are when neither way has room.
    pub(super) fn turn(&mut self) -> Action {
        self.turn_to(self.way())
    }

    /// The next turn, the way [`Survey::way`] found: or the search of the
    /// views there are when it found none.
    pub(super) fn turn_to(&mut self, way: Option<(bool, Ahead)>) -> Action {
        let Some((clockwise, ahead)) = way else {
            self.room.cut_short = true;
            return self.search();
        };
        if clockwise != self.clockwise {
            self.clockwise = clockwise;
            self.room.reversed = self.room.reversed.saturating_add(1);
        }
        if ahead == Ahead::Square {
            self.room.squeezed = self.room.squeezed.saturating_add(1);
        }
        let steps = self.sweep.plan(clockwise);
        // turn `count - 1`, begun only after a view is kept, of fewer than
        // `MAX_VIEWS` (`searched` ends the survey at that many): there is
        // room for it
        let _ = self.turns.push(Turn::new(clockwise, steps));
        // (a turn starts from a view kept: `from` is its heading)
        let from = self.views().last().map_or(Angle::ZERO, |v| v.heading);
        self.turning = Turning::start(from, clockwise, steps);
        self.enter(Phase::Turn)
    }

    /// A turn is over: its readings are kept, the body settles. The tick
    /// this is called from turns no more, so the turn ran the ticks
    /// before it. A turn that ended before the compass showed its angle
    /// (stalled, or out of time) was blocked for part of its ticks, where
    /// the refinement would read its readings at headings in proportion
    /// to them: they are forgotten.
    pub(super) fn turned(&mut self) -> Action {
        let ticks = u16::try_from(self.ticks.saturating_sub(1)).unwrap_or(u16::MAX);
        if let Some(turn) = self.turns.last_mut() {
            turn.end(ticks);
            if !self.turning.reached() {
                turn.forget();
            }
        }
        self.enter(Phase::Settle)
    }
}
