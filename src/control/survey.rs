//! The survey: how the robot finds where it is, on `locate` (and `reset`)
//! and at power-up ([`config::locate::AT_POWER_UP`]): views taken standing, with turns in
//! place between them, and the search of the box for the poses that
//! explain them ([`crate::model::locate`]), a few hundred view scores per tick.
//!
//! 1. A view: the compass's heading, the mean of [`config::locate::COMPASS_READINGS`]
//!    readings, and each lidar's distance, the median of
//!    [`config::locate::LIDAR_READINGS`], taken standing (at most
//!    [`config::locate::VIEW_LIMIT_MS`]).
//!    Before the first, the body makes room to turn from the readings
//!    of a view taken standing ([`room::positioning_mm`]): it backs up
//!    from a wall ahead, or drives forward clear of one that may be right
//!    behind (ended early by a front reading nearer than it aims for,
//!    [`room::drive_ends`]), stands [`config::locate::SETTLE_MS`], and takes the first
//!    view there (the views are then joined by turns in place only, as the
//!    search assumes).
//! 2. A turn in place of [`config::locate::TURN_DEG`], clockwise first, ended
//!    when the compass shows it (`survey/turning.rs`), a settle of
//!    [`config::locate::SETTLE_MS`], and the next view. When the compass shows that a
//!    turn moved less than [`config::locate::BLOCKED_TURN_DEG`] (the body against a
//!    wall), the next turns go the other way. A turn must have room
//!    ([`room::room_to_turn`]) as the view taken at the edge of the swept
//!    ground that way shows; else it goes the other way, back over the
//!    swept ground and one step past its other edge in one turn; when
//!    neither way has room the views taken are all there are (the drive,
//!    the views kept and the turns: `survey/moving.rs`).
//! 3. From [`config::locate::MIN_VIEWS`] views on, the search after each view
//!    ([`config::locate::SCORES_PER_TICK`] view scores a tick): a fix that is not
//!    ambiguous and is certain enough for `goto`
//!    ([`crate::config::goto::MAX_SIGMA_MM`]) ends the procedure;
//!    otherwise (ambiguous, too uncertain, or nothing fits) another turn
//!    and view, up to [`MAX_VIEWS`], whose answer is taken as it is (an
//!    ambiguous fix says so); when neither way has room to turn, the
//!    search's answer is the last ([`RoomLog::cut_short`]:
//!    a search of the same views again finds the same). A fix of one
//!    place the search cannot vouch
//!    for ([`Fix::untrusted`]: reported uncertain) ends it too: more views
//!    each bring their own compass error.
//!    With the refinement on, a search reads the last
//!    [`config::refine::SEARCH_VIEWS`] views (a view the next one repeats,
//!    [`config::refine::REPEAT_DEG`], counted once: the later one read)
//!    and tries headings within
//!    [`config::refine::LAST_VIEWS_STEPS`] of the compass's; when nothing
//!    fits there, the views' compass errors differ more than the search
//!    allows, and from then on it reads the last
//!    [`config::refine::FEW_VIEWS`] views, at every heading.
//! 4. The fix refined with every reading of the last
//!    [`config::refine::REFINE_VIEWS`] views and the turns between them
//!    ([`crate::model::locate::refine`]; this and the searches:
//!    `survey/searching.rs`).
//!    A refined fit that explains the readings poorly
//!    ([`crate::model::locate::refine::Refined::poor`],
//!    [`config::refine::SEARCH_ON_LIMIT`])
//!    may rest on a wrong place: the search goes on at its next headings
//!    ([`config::refine::SEARCH_ON_STEPS`], for at most
//!    [`config::refine::SEARCH_ON_MS`] into the procedure), each place
//!    found is refined, and the cheapest fit is reported (found again by
//!    the search from its heading: the survey keeps its heading try and
//!    cost, not the fix).
//! 5. A refined answer that still fits poorly
//!    ([`config::refine::SECOND_LOOK_FIT`]: the refinement cannot vouch
//!    for any place) is not reported on the first look: the procedure
//!    looks again from elsewhere ([`Action::LookAgain`]), from step 1 with
//!    its drive to make room, and the second look's answer is the
//!    answer, whatever it fits (the first's place is behind the body by
//!    then).
//!
//! `tests/localization/locate.rs` measures this survey on the realistic simulator's
//! sensors (99.1 % right from random starts, the lab's world); `tests/localization/localize.rs` runs it
//! in the loop.
//!
//! The survey owns no hardware and no clock: the loop hands it the
//! readings ([`Survey::lidar`], [`Survey::heading`]) and calls
//! [`Survey::tick`] once per tick, which says whether to stand or turn,
//! or gives the answer. It keeps the lidars' readings taken while turning
//! between views too ([`Survey::turns`], issue #29), for refining the
//! search's fix.

use crate::config;
use crate::config::timing::LOOP_HZ;
use crate::math::{Angle, Length};
use crate::model::locate::refine::Refine;
use crate::model::locate::turns::Turn;
use crate::model::locate::{Fix, Readings, Search, MAX_VIEWS};
use crate::model::measurement::{Arena, LidarId};

mod answer;
mod moving;
pub mod room;
mod searching;
mod sweep;
mod turning;
mod view;
pub use answer::{Action, Failure};
pub use room::RoomLog;
use searching::Cheapest;
use sweep::Sweep;
use turning::Turning;
use view::ViewSums;
#[cfg(test)]
mod tests;

/// Where the procedure is.
// one phase at a time, inside the controller: no box (no allocator)
#[allow(clippy::large_enum_variant)]
#[derive(Clone, Debug)]
enum Phase {
    /// Taking a view's readings.
    View,
    /// Making room before the first view: this many ticks.
    Drive {
        forward: bool,
        ticks: u32,
    },
    Turn,
    Settle,
    Search(Search),
    /// A search to begin, from its heading try ([`Search::skip_to`]): begun
    /// by [`Survey::tick`] itself once the tick's work asked for it, not
    /// under that work's calls (a search is 0.6 kB: `cargo fw-image`'s
    /// stack check), and its failure to begin answered from there (no
    /// recursion through [`Survey::searched`]).
    Begin(u8),
    /// The search's answer, to be refined from the next tick.
    Searched(Fix),
    /// The search's fix refined with every reading
    /// ([`crate::model::locate::refine`]).
    Refine(Refine),
}

/// Loop ticks in `ms` (whole ticks, rounded down; const-evaluated).
const fn ticks(ms: u32) -> u32 {
    ms.saturating_mul(LOOP_HZ) / 1000
}

/// Ticks of one turn between views: the angle over the rate (urad per
/// degree over mrad/s is ms).
const TURN_TICKS: u32 = ticks((config::locate::TURN_DEG * 17_453 / config::locate::TURN_MRAD_S) as u32);
const SETTLE_TICKS: u32 = ticks(config::locate::SETTLE_MS);
const VIEW_TICKS: u32 = ticks(config::locate::VIEW_LIMIT_MS);
/// The blocked-turn threshold in angle LSB (2^32 per turn).
const BLOCKED: i32 = (config::locate::BLOCKED_TURN_DEG as i64 * (1 << 32) / 360) as i32;
const _: () = assert!(config::locate::MIN_VIEWS >= 1 && config::locate::MIN_VIEWS <= MAX_VIEWS && TURN_TICKS > 0);

/// The first `count` of `views`: the views taken ([`Survey::views`]).
fn taken(views: &[Readings], count: usize) -> &[Readings] {
    views.get(..count).unwrap_or(&[])
}

/// Of `turns`, those with a view after them when `count` views are taken
/// ([`Survey::turns`]).
fn between(turns: &[Turn], count: usize) -> &[Turn] {
    turns.get(..count.saturating_sub(1)).unwrap_or(turns)
}

/// The procedure (see the module docs).
#[derive(Clone, Debug)]
pub struct Survey {
    views: [Readings; MAX_VIEWS],
    count: usize,
    /// The turns begun, turn `j` just after view `j` was kept (every view
    /// but the first comes after one turn: the first after the drive
    /// that makes room); [`Survey::turns`] shows those with a view after.
    turns: heapless::Vec<Turn, { MAX_VIEWS - 1 }>,
    phase: Phase,
    /// Ticks spent in this phase.
    ticks: u32,
    clockwise: bool,
    view: ViewSums,
    /// The body has made its room before the first view.
    positioned: bool,
    sweep: Sweep,
    room: RoomLog,
    /// Where in its spot a lidar's range comes from, as the estimator has
    /// learned it (Q30; [`Search::with_spot_share`]).
    share: i32,
    /// The search's fix is refined with every reading
    /// ([`config::refine::ENABLED`], [`Survey::set_refine`]).
    refine: bool,
    /// The turn under way, as the compass shows it.
    turning: Turning,
    /// The search going on past poor fits: the cheapest so far.
    cheapest: Option<Cheapest>,
    /// Ticks since the procedure began.
    elapsed: u32,
    /// The search reads the last [`config::refine::FEW_VIEWS`] views only:
    /// a search of the last [`config::refine::SEARCH_VIEWS`] found nothing
    /// (for the rest of the procedure).
    few: bool,
    /// This is the procedure's second look, from elsewhere: the first
    /// answered with a poor fit ([`config::refine::SECOND_LOOK_FIT`]).
    second_look: bool,
}

impl Default for Survey {
    fn default() -> Self {
        Survey::new()
    }
}

impl Survey {
    /// Whether the search's fix is refined with every reading of the
    /// survey ([`crate::model::locate::refine`]); kept by
    /// [`Survey::restart`].
    pub fn set_refine(&mut self, on: bool) {
        self.refine = on;
    }

    /// The procedure's search reads each range `share` (Q30) of the way
    /// into its spot: the estimator's learned share (a new procedure reads
    /// the cone's nearest wall point, 0).
    pub fn set_spot_share(&mut self, share: i32) {
        self.share = share;
    }

    /// A procedure about to take its first view.
    pub const fn new() -> Survey {
        Survey {
            views: [Readings { heading: Angle::ZERO, front: None, right: None }; MAX_VIEWS],
            count: 0,
            turns: heapless::Vec::new(),
            phase: Phase::View,
            ticks: 0,
            clockwise: true,
            view: ViewSums {
                front: heapless::Vec::new(),
                right: heapless::Vec::new(),
                first_heading: None,
                heading_diffs: 0,
                headings: 0,
            },
            positioned: false,
            sweep: Sweep::START,
            room: RoomLog { moved_mm: 0, reversed: 0, squeezed: 0, cut_short: false },
            share: 0,
            refine: config::refine::ENABLED,
            turning: Turning::NONE,
            cheapest: None,
            elapsed: 0,
            few: false,
            second_look: false,
        }
    }

    /// Starts the procedure again, as [`Survey::new`] with the spot share
    /// kept. In place, for the robot's stack, which holds the controller:
    /// a survey assigned anew is built beside the old one (1.3 kB), and
    /// with it the deepest call (the firmware's run, the tick, end_locate,
    /// a `goto` that waited locating again) reached 14.9 kB below the
    /// stack's top, past the ROM's flash parameters 14.6 kB below it
    /// (`flashchip`, 0x3FFFC714, eagle.rom.addr.v6.ld; frames from
    /// `cargo fw-image`'s ELF); in place the deepest is 13.6 kB.
    pub fn restart(&mut self) {
        // every field named: a new one must be restarted too
        let Survey {
            views: _,
            count,
            turns,
            phase,
            ticks,
            clockwise,
            view,
            positioned,
            sweep,
            room,
            share: _,
            refine: _,
            turning,
            cheapest,
            elapsed,
            few,
            second_look,
        } = self;
        // (the views past `count` are not read)
        *count = 0;
        turns.clear();
        *phase = Phase::View;
        *ticks = 0;
        *clockwise = true;
        *view = ViewSums::default();
        *positioned = false;
        *sweep = Sweep::START;
        *room = RoomLog::default();
        *turning = Turning::NONE;
        *cheapest = None;
        *elapsed = 0;
        *few = false;
        *second_look = false;
    }

    /// A second look from elsewhere: the procedure begun again, its drive
    /// to make room first (the controller begins its time limit again on
    /// [`Action::LookAgain`]).
    fn look_again(&mut self) {
        self.restart();
        self.second_look = true;
    }

    /// The answer when the procedure's time ran out: the fix refined as
    /// far as it got, reported uncertain, while refining; else none.
    pub fn out_of_time(&self) -> Result<Fix, Failure> {
        match &self.phase {
            Phase::Searched(fix) => {
                let mut fix = *fix;
                fix.untrusted = true;
                Ok(fix)
            }
            Phase::Refine(refine) => {
                let mut fix = refine.refined_fix();
                fix.untrusted = true;
                Ok(fix)
            }
            _ => Err(Failure::OutOfTime),
        }
    }

    /// What the survey did to keep off the walls so far.
    pub fn room(&self) -> RoomLog {
        self.room
    }

    /// Views taken so far.
    pub fn views(&self) -> &[Readings] {
        taken(&self.views, self.count)
    }

    /// The turns between the views so far, with the lidars' readings
    /// taken on them: turn `j` between views `j` and `j + 1`
    /// ([`Survey::views`]), so one fewer than the views. A turn under way,
    /// or one whose view never came (the view had no heading, the survey
    /// was stopped), is not among them.
    pub fn turns(&self) -> &[Turn] {
        between(&self.turns, self.count)
    }

    /// A lidar's distance (the lidar model's output): kept while a view is
    /// being taken, up to [`config::locate::LIDAR_READINGS`]; while
    /// turning, by the turn, at the ticks the turn has run (handed in
    /// before this tick's [`Survey::tick`]: the body has turned that many
    /// ticks).
    pub fn lidar(&mut self, id: LidarId, d: Length) {
        match self.phase {
            Phase::View => {
                let distances = match id {
                    LidarId::Front => &mut self.view.front,
                    LidarId::Right => &mut self.view.right,
                };
                // a full view keeps its first readings
                let _ = distances.push(d);
            }
            Phase::Turn => {
                let tick = u16::try_from(self.ticks).unwrap_or(u16::MAX);
                if let Some(turn) = self.turns.last_mut() {
                    turn.push(id, tick, d);
                }
            }
            // a wall ahead nearer than the drive aims for: its ticks are up
            Phase::Drive { forward: true, ref mut ticks } if id == LidarId::Front && room::drive_ends(d) => *ticks = 0,
            _ => {}
        }
    }

    /// A compass heading; kept while a view is being taken, up to
    /// [`config::locate::COMPASS_READINGS`].
    pub fn heading(&mut self, h: Angle) {
        if matches!(self.phase, Phase::Turn) {
            return self.turning.heading(h);
        }
        let v = &mut self.view;
        if !matches!(self.phase, Phase::View) || v.headings >= config::locate::COMPASS_READINGS {
            return;
        }
        let first = *v.first_heading.get_or_insert(h);
        v.heading_diffs = v.heading_diffs.saturating_add(i64::from(h.diff(first)));
        v.headings = v.headings.saturating_add(1);
    }

    /// One loop tick: what the body does, or the answer.
    pub fn tick(&mut self, arena: &Arena) -> Action {
        let action = self.step(arena);
        // a search asked for begins here, under the tick alone
        match self.phase {
            Phase::Begin(heading_try) => self.begin(heading_try),
            _ => action,
        }
    }

    /// The tick's work but a search's beginning.
    fn step(&mut self, arena: &Arena) -> Action {
        self.ticks = self.ticks.saturating_add(1);
        self.elapsed = self.elapsed.saturating_add(1);
        if let Some(cheapest) = self.out_of_time_to_search_on() {
            return self.searched_on(Err(Failure::OutOfTime), cheapest);
        }
        match &mut self.phase {
            Phase::View if self.view.complete() || self.ticks > VIEW_TICKS => self.view_taken(),
            Phase::View => Action::Stand,
            Phase::Drive { ticks, .. } if self.ticks > *ticks => self.enter(Phase::Settle),
            Phase::Drive { forward, .. } => Action::Drive { forward: *forward },
            Phase::Turn if self.turning.over(self.ticks) => self.turned(),
            Phase::Turn => Action::Turn { clockwise: self.clockwise },
            Phase::Settle if self.ticks > SETTLE_TICKS => {
                self.view = ViewSums::default();
                self.enter(Phase::View)
            }
            Phase::Settle => Action::Stand,
            Phase::Search(search) => match (search.step(arena, config::locate::SCORES_PER_TICK), self.cheapest) {
                (None, _) => Action::Stand,
                (Some(result), Some(c)) => self.searched_on(result.map_err(Failure::from), c),
                (Some(result), None) => self.searched(result.map_err(Failure::from)),
            },
            // (not met: begun by the tick that asked for it)
            Phase::Begin(_) => Action::Stand,
            Phase::Searched(fix) => {
                let fix = *fix;
                self.refine(fix)
            }
            Phase::Refine(refine) => {
                // (the fields, not `views()` and `turns()`: the phase is borrowed)
                let (views, turns) = (taken(&self.views, self.count), between(&self.turns, self.count));
                match refine.step(arena, views, turns) {
                    None => Action::Stand,
                    Some(result) => {
                        let fix = refine.refined_fix();
                        self.refined(fix, result)
                    }
                }
            }
        }
    }

    fn enter(&mut self, phase: Phase) -> Action {
        self.phase = phase;
        self.ticks = 0;
        Action::Stand
    }
}
