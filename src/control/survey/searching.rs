//! The survey's searches and their answers: a search begun from the tick
//! ([`Phase::Begin`]), of the last views
//! ([`config::refine::SEARCH_VIEWS`]) or the last few
//! ([`config::refine::FEW_VIEWS`]); its fix refined with every reading of
//! the last [`config::refine::REFINE_VIEWS`] views;
//! and the search going on past a refined fit that explains the readings
//! poorly ([`config::refine::SEARCH_ON_STEPS`]), each place found at the
//! next headings refined and the cheapest fit reported, found again by the
//! search from its heading.

use super::{ticks, Action, Failure, Phase, Survey};
use crate::config;
use crate::config::locate::MIN_VIEWS;
use crate::control::goto::position_steerable;
use crate::math::Angle;
use crate::model::locate::refine::{worth_a_second_look, Refine, Refined};
use crate::model::locate::{Fix, LocateError, Readings, Search, MAX_VIEWS};

/// The cheapest refined fit so far while the search goes on past fits
/// that explain the readings poorly ([`config::refine::SEARCH_ON_STEPS`]):
/// kept as the search's heading try that found it and its cost, not as the
/// fix (200 bytes more of the robot's stack): reporting it, the search
/// finds it again from that try (`again`).
#[derive(Clone, Copy, Debug)]
pub(super) struct Cheapest {
    heading_try: u8,
    /// Cost a reading, Q24 sigmas squared ([`Refined::per_reading`]).
    per_reading: i64,
    again: bool,
}

/// Views a search reads at most with the refinement on
/// ([`config::refine::SEARCH_VIEWS`]) ...
const SEARCH_VIEWS: usize = config::refine::SEARCH_VIEWS;
/// ... and when a search of those found nothing
/// ([`config::refine::FEW_VIEWS`]): fewer than the views before a search.
const FEW_VIEWS: usize = config::refine::FEW_VIEWS;
// (the refinement weighs every view the search read, and more)
const _: () = assert!(
    FEW_VIEWS >= 1
        && FEW_VIEWS < MIN_VIEWS
        && SEARCH_VIEWS >= MIN_VIEWS
        && config::refine::REFINE_VIEWS >= SEARCH_VIEWS
);

/// [`config::refine::REPEAT_DEG`] in angle LSB (under a quarter turn).
const REPEAT: i32 = Angle::from_degrees_f64(config::refine::REPEAT_DEG).0 as i32;

/// View `i` of `views` is repeated by the next: the turn between them was
/// blocked ([`config::refine::REPEAT_DEG`]).
fn repeated(views: &[Readings], i: usize) -> bool {
    match (views.get(i), views.get(i.saturating_add(1))) {
        (Some(a), Some(b)) => b.heading.diff(a.heading).saturating_abs() < REPEAT,
        _ => false,
    }
}

/// The views of `views` the next one does not repeat.
fn unrepeated(views: &[Readings]) -> impl Iterator<Item = Readings> + '_ {
    views.iter().enumerate().filter(|&(i, _)| !repeated(views, i)).map(|(_, v)| *v)
}

/// The last heading try the search goes on to past a poor fit, and the
/// procedure's ticks it may go on until.
const LAST_TRY_ON: u8 = config::refine::SEARCH_ON_STEPS.saturating_mul(2);
const SEARCH_ON_TICKS: u32 = ticks(config::refine::SEARCH_ON_MS);

impl Survey {
    /// The views the search reads: all of them without the refinement;
    /// with it the last [`SEARCH_VIEWS`], or the last [`FEW_VIEWS`] once a
    /// search of those found nothing, a view the next one repeats not
    /// counted ([`config::refine::REPEAT_DEG`]; the search reads the later
    /// of the two). The fix is the last view's either way, refined with
    /// the last [`config::refine::REFINE_VIEWS`], and a later view is among
    /// the last.
    fn searched_views(&self) -> &[Readings] {
        let views = self.views();
        let last = match (self.refine, self.few) {
            (false, _) => return views,
            (true, false) => SEARCH_VIEWS,
            (true, true) => FEW_VIEWS,
        };
        // back from the newest, a view the next repeats not counted
        let (mut first, mut counted) = (views.len(), 0usize);
        while first > 0 && counted < last {
            first = first.saturating_sub(1);
            counted = counted.saturating_add(usize::from(!repeated(views, first)));
        }
        views.get(first..).unwrap_or(views)
    }

    /// The search of [`Survey::searched_views`]; with the refinement on,
    /// of those the next does not repeat.
    fn new_search(&self) -> Result<Search, LocateError> {
        let views = self.searched_views();
        if self.refine {
            Search::of(unrepeated(views))
        } else {
            Search::new(views)
        }
    }

    /// The search reads the last [`SEARCH_VIEWS`], at the headings near
    /// the compass's ([`config::refine::LAST_VIEWS_STEPS`]), before the
    /// last few ([`FEW_VIEWS`]): with the refinement on, and more views
    /// than those.
    fn last_views_first(&self) -> bool {
        self.refine && !self.few && self.count > FEW_VIEWS
    }

    /// The search of the views so far ([`Phase::Begin`]).
    pub(super) fn search(&mut self) -> Action {
        self.enter(Phase::Begin(0))
    }

    /// The search begins ([`Phase::Begin`]).
    // out of line: its search (0.6 kB) in a frame of its own beside the
    // tick's deepest calls, not in the tick's (`cargo fw-image`: inlined,
    // the Xtensa backend could not spill a register in the tick's frame)
    #[inline(never)]
    pub(super) fn begin(&mut self, heading_try: u8) -> Action {
        match (self.new_search(), self.cheapest) {
            (Ok(search), _) => {
                let action = self.enter(Phase::Search(search.with_spot_share(self.share)));
                let last_views = self.last_views_first();
                if let Phase::Search(s) = &mut self.phase {
                    s.skip_to(heading_try);
                    if last_views {
                        s.up_to(config::refine::LAST_VIEWS_STEPS);
                    }
                }
                action
            }
            (Err(e), Some(c)) => self.searched_on(Err(e.into()), c),
            (Err(e), None) => self.searched(Err(e.into())),
        }
    }

    /// A search's answer: the end, or another view.
    pub(super) fn searched(&mut self, result: Result<Fix, Failure>) -> Action {
        // (the fix's heading is the compass's, within goto's limit)
        let settles = |fix: &Fix| !fix.ambiguous && position_steerable(fix.sigma_x, fix.sigma_y, 1);
        // another view is wanted and neither way has room to turn: these
        // views are all there will be (a search of them again finds the same)
        let way = self.way();
        if !matches!(&result, Ok(fix) if settles(fix)) && way.is_none() {
            self.room.cut_short = true;
        }
        let last_view = self.count >= MAX_VIEWS || self.room.cut_short;
        match result {
            Ok(fix) if settles(&fix) || last_view => {
                if self.refine {
                    // refined from the next tick (not here, deep in the
                    // search's calls: `Survey::refine`)
                    self.enter(Phase::Searched(fix))
                } else {
                    Action::Done(Ok(fix))
                }
            }
            // the views disagree (their compass errors differ): the last
            // few may fit, and the refinement weighs more (`REFINE_VIEWS`)
            Err(Failure::NothingFits) if self.last_views_first() => {
                self.few = true;
                self.search()
            }
            Err(e) if last_view => Action::Done(Err(e)),
            _ => self.turn_to(way),
        }
    }

    /// The search's fix refined next ([`Phase::Refine`]). Out of line, and
    /// from a tick: its 1.1 kB are on the robot's stack only here, not in
    /// the search's calls (`cargo fw-image`'s stack check).
    #[inline(never)]
    pub(super) fn refine(&mut self, fix: Fix) -> Action {
        self.phase = Phase::Refine(Refine::new(fix, self.views(), self.turns()));
        self.ticks = 0;
        Action::Stand
    }

    /// The search of the views so far going on from its heading try
    /// `heading_try`, past a poor fit ([`Phase::Begin`]).
    fn search_on(&mut self, heading_try: u8) -> Action {
        self.enter(Phase::Begin(heading_try))
    }

    /// The cheapest fit so far, when the search going on past poor fits
    /// is out of time ([`config::refine::SEARCH_ON_MS`]): to be found again.
    pub(super) fn out_of_time_to_search_on(&self) -> Option<Cheapest> {
        match (&self.phase, self.cheapest) {
            (Phase::Search(_), Some(c)) if !c.again && self.elapsed > SEARCH_ON_TICKS => Some(c),
            _ => None,
        }
    }

    /// A fix refined: the answer, or the search goes on past a poor fit
    /// ([`config::refine::SEARCH_ON_STEPS`]).
    pub(super) fn refined(&mut self, fix: Fix, result: Option<Refined>) -> Action {
        let found = Cheapest {
            heading_try: fix.heading_try(),
            per_reading: result.map_or(i64::MAX, |r| r.per_reading),
            again: false,
        };
        let cheapest = match self.cheapest {
            // the cheapest, found again to be reported
            Some(c) if c.again => return self.answer(fix),
            Some(c) if c.per_reading <= found.per_reading => c,
            _ => found,
        };
        self.cheapest = Some(cheapest);
        // a fit that explains the readings is the cheapest: those before
        // it all fit poorly
        if !result.is_some_and(|r| r.poor()) || found.heading_try >= LAST_TRY_ON || self.elapsed > SEARCH_ON_TICKS {
            return self.report_cheapest(fix);
        }
        self.search_on(found.heading_try.saturating_add(1))
    }

    /// The search going on past a poor fit has an answer: the next place
    /// to refine, or the cheapest fit so far reported. Called from the
    /// tick, not from [`Survey::searched`]: the search that goes on is not
    /// on the robot's stack under another.
    pub(super) fn searched_on(&mut self, result: Result<Fix, Failure>, cheapest: Cheapest) -> Action {
        match result {
            Ok(fix) if cheapest.again || fix.heading_try() <= LAST_TRY_ON => self.enter(Phase::Searched(fix)),
            Err(e) if cheapest.again => Action::Done(Err(e)),
            // no more places within the steps searched on
            _ => {
                self.cheapest = Some(Cheapest { again: true, ..cheapest });
                self.search_on(cheapest.heading_try)
            }
        }
    }

    /// The cheapest fit reported: `fix` when it is, else found again.
    fn report_cheapest(&mut self, fix: Fix) -> Action {
        match self.cheapest {
            Some(c) if c.heading_try != fix.heading_try() => {
                self.cheapest = Some(Cheapest { again: true, ..c });
                self.search_on(c.heading_try)
            }
            _ => self.answer(fix),
        }
    }

    /// The refined answer `fix` (the cheapest fit): reported, or, when it
    /// fits poorly ([`config::refine::SECOND_LOOK_FIT`]) on the first
    /// look, a second look from elsewhere instead (see the module docs).
    fn answer(&mut self, fix: Fix) -> Action {
        let poor = self.cheapest.is_some_and(|c| worth_a_second_look(c.per_reading));
        if poor && !self.second_look {
            self.look_again();
            return Action::LookAgain;
        }
        Action::Done(Ok(fix))
    }
}

#[cfg(test)]
#[allow(clippy::restriction)] // test code: a panic fails the test
mod tests {
    use super::*;
    use crate::math::Length;
    use std::vec::Vec;

    /// A survey with views at `headings` (degrees), each reading 300 mm
    /// ahead and 200 mm to the right.
    fn surveyed(headings: &[f64]) -> Survey {
        let mut s = Survey::new();
        for (slot, &deg) in s.views.iter_mut().zip(headings) {
            let (d, r) = (Length::from_mm(300), Length::from_mm(200));
            *slot = Readings { heading: Angle::from_degrees_f64(deg), front: Some(d), right: Some(r) };
        }
        s.count = headings.len();
        s
    }

    fn degrees(views: impl Iterator<Item = Readings>) -> Vec<f64> {
        views.map(|v| (f64::from(v.heading.to_millidegrees()) / 100.0).round() / 10.0).collect()
    }

    /// A view the next one repeats (a blocked turn between them) does not
    /// count among the last views the search reads, and the search reads
    /// the later of the two only; a turn the compass shows past
    /// `REPEAT_DEG` is a view of its own.
    #[test]
    fn a_repeated_view_is_searched_once() {
        let step = config::refine::REPEAT_DEG;
        let s = surveyed(&[0.0, 45.0, 90.0, 135.0, 135.0 + step - 0.5]);
        assert_eq!(s.searched_views().len(), 5);
        assert_eq!(degrees(unrepeated(s.searched_views())), [0.0, 45.0, 90.0, 135.0 + step - 0.5]);
        let s = surveyed(&[0.0, 45.0, 90.0, 135.0, 135.0 + step + 0.5]);
        assert_eq!(degrees(unrepeated(s.searched_views())), [45.0, 90.0, 135.0, 135.0 + step + 0.5]);
    }

    /// A search whose views leave no room to turn either way is the last:
    /// its answer stands (a search of the same views again found the same,
    /// and ran power-ups out of time), and the room's log says so. With
    /// room, the answer asks for another view.
    #[test]
    fn with_no_room_to_turn_the_search_is_not_repeated() {
        for (front, answer) in [(30, Action::Done(Err(Failure::NothingFits))), (600, Action::Stand)] {
            let mut s = surveyed(&[0.0, 45.0, 90.0, 135.0]);
            for v in s.views.iter_mut().take(4) {
                v.front = Some(Length::from_mm(front));
                v.right = Some(Length::from_mm(600));
            }
            // the last views searched found nothing, and then the last few
            s.few = true;
            assert_eq!(s.searched(Err(Failure::NothingFits)), answer, "front {front} mm");
            assert_eq!(s.room().cut_short, front == 30);
            assert_eq!(matches!(s.phase, Phase::Turn), front == 600);
        }
    }

    /// A first look whose answer fits poorly (more than
    /// `SECOND_LOOK_FIT` a reading) is not the answer: the procedure
    /// begins again, its drive to make room first, and says so; the second
    /// look's answer is the answer however it fits, and a first look that
    /// fits is the answer at once. A new procedure may look twice again.
    #[test]
    fn a_poor_fit_looks_again_from_elsewhere_once() {
        use crate::model::locate::locate;
        use crate::model::measurement::{expected_lidar, Arena, LidarId};
        use crate::model::Pose;
        let arena = Arena::DEFAULT;
        let views: Vec<Readings> = [10.0, 55.0, 100.0, 145.0]
            .map(|deg| {
                let pose = Pose::from_mm(380, 240, Angle::from_degrees_f64(deg));
                let read = |id| expected_lidar(&arena, &pose, id);
                Readings { heading: pose.theta, front: read(LidarId::Front), right: read(LidarId::Right) }
            })
            .to_vec();
        let fix = locate(&arena, &views).expect("exact views fit");
        let costing = |per_reading: f64| {
            let per_reading = (per_reading * f64::from(1u32 << 24)) as i64;
            Some(Cheapest { heading_try: fix.heading_try(), per_reading, again: false })
        };
        let poor = config::refine::SECOND_LOOK_FIT + 0.1;
        let mut s = surveyed(&[10.0, 55.0, 100.0, 145.0]);
        s.cheapest = costing(poor);
        assert_eq!(s.answer(fix), Action::LookAgain);
        assert!(s.views().is_empty() && !s.positioned && matches!(s.phase, Phase::View));
        s.cheapest = costing(poor);
        assert_eq!(s.answer(fix), Action::Done(Ok(fix)), "the second look answers");
        s.restart();
        s.cheapest = costing(poor);
        assert_eq!(s.answer(fix), Action::LookAgain, "a new procedure");
        let mut s = surveyed(&[10.0, 55.0, 100.0, 145.0]);
        s.cheapest = costing(config::refine::SECOND_LOOK_FIT - 0.1);
        assert_eq!(s.answer(fix), Action::Done(Ok(fix)), "a fit within the limit");
    }

    /// Without the refinement the search reads every view, repeats too.
    #[test]
    fn without_the_refinement_every_view_is_searched() {
        let mut s = surveyed(&[0.0, 45.0, 90.0, 135.0, 135.0, 180.0]);
        s.set_refine(false);
        assert_eq!(s.searched_views().len(), 6);
    }
}
