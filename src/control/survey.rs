//! The survey: how the robot finds where it is, on `locate` (and `reset`)
//! and at power-up ([`config::locate::AT_POWER_UP`]): views taken standing, with turns in
//! place between them, and the search of the box for the poses that
//! explain them ([`crate::model::locate`]), a few hundred view scores per tick.
//!
//! 1. A view: the compass's heading, the mean of [`config::locate::COMPASS_READINGS`]
//!    readings, and each lidar's distance, the median of
//!    [`config::locate::LIDAR_READINGS`], taken standing (at most
//!    [`config::locate::VIEW_LIMIT_MS`]).
//! 2. A turn in place of [`config::locate::TURN_DEG`], clockwise first, a settle of
//!    [`config::locate::SETTLE_MS`], and the next view. When the compass shows that a
//!    turn moved less than [`config::locate::BLOCKED_TURN_DEG`] (the body against a
//!    wall), the next turns go the other way.
//! 3. From [`config::locate::MIN_VIEWS`] views on, the search after each view
//!    ([`config::locate::SCORES_PER_TICK`] view scores a tick): a fix that is not
//!    ambiguous and is certain enough for `goto`
//!    ([`crate::config::goto::MAX_SIGMA_MM`]) ends the procedure;
//!    otherwise (ambiguous, too uncertain, or nothing fits) another turn
//!    and view, up to [`MAX_VIEWS`], whose answer is taken as it is (an
//!    ambiguous fix says so). A fix of one place the search cannot vouch
//!    for ([`Fix::untrusted`]: reported uncertain) ends it too: more views
//!    each bring their own compass error.
//!
//! `tests/localization/locate.rs` measures this survey on the realistic simulator's
//! sensors (99.1 % right from random starts, the lab's world); `tests/localization/localize.rs` runs it
//! in the loop.
//!
//! The survey owns no hardware and no clock: the loop hands it the
//! readings ([`Survey::lidar`], [`Survey::heading`]) and calls
//! [`Survey::tick`] once per tick, which says whether to stand or turn,
//! or gives the answer.

use crate::config;
use crate::config::timing::LOOP_HZ;
use crate::control::goto::position_steerable;
use crate::math::{div_i64, Angle, Length};
use crate::model::locate::{Fix, LocateError, Readings, Search, MAX_VIEWS};
use crate::model::measurement::{Arena, LidarId};

/// Why there is no fix.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum Failure {
    /// The compass gave no heading for a view.
    NoHeading,
    /// Neither lidar gave a distance in any view.
    NoRange,
    /// No pose in the box explains the views (an obstacle, another box).
    NothingFits,
    /// [`config::locate::TIME_LIMIT_MS`] ran out.
    OutOfTime,
    /// A command came (it runs instead).
    Interrupted,
}

impl Failure {
    /// The reason in words, for the `# locate failed` line.
    pub fn text(self) -> &'static str {
        match self {
            Failure::NoHeading => "no compass heading",
            Failure::NoRange => "no lidar distance",
            Failure::NothingFits => "no pose in the box explains the readings",
            Failure::OutOfTime => "out of time",
            Failure::Interrupted => "interrupted by a command",
        }
    }
}

impl From<LocateError> for Failure {
    fn from(e: LocateError) -> Failure {
        match e {
            LocateError::NoReading => Failure::NoRange,
            LocateError::NothingFits => Failure::NothingFits,
        }
    }
}

/// What the body does this tick, or the procedure's answer.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum Action {
    Stand,
    /// Turn in place at [`config::locate::TURN_MRAD_S`].
    Turn {
        clockwise: bool,
    },
    Done(Result<Fix, Failure>),
}

/// Where the procedure is.
// one phase at a time, inside the controller: no box (no allocator)
#[allow(clippy::large_enum_variant)]
#[derive(Clone, Debug)]
enum Phase {
    /// Taking a view's readings.
    View,
    Turn,
    Settle,
    Search(Search),
}

/// One lidar's distances in a view.
type Distances = heapless::Vec<Length, { config::locate::LIDAR_READINGS as usize }>;

/// A view's readings as they come.
#[derive(Clone, Default, Debug)]
struct ViewSums {
    front: Distances,
    right: Distances,
    /// The first heading, and the sum of the others' differences from it
    /// (a mean that does not wrap at north).
    first_heading: Option<Angle>,
    heading_diffs: i64,
    headings: u8,
}

impl ViewSums {
    fn complete(&self) -> bool {
        self.front.is_full() && self.right.is_full() && self.headings >= config::locate::COMPASS_READINGS
    }

    /// The view: the lidars' medians (a glancing beam's spurious echo
    /// among them does not move it) and the compass's mean (`None`: no
    /// compass heading).
    fn readings(&mut self) -> Option<Readings> {
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

/// The procedure (see the module docs).
#[derive(Clone, Debug)]
pub struct Survey {
    views: [Readings; MAX_VIEWS],
    count: usize,
    phase: Phase,
    /// Ticks spent in this phase.
    ticks: u32,
    clockwise: bool,
    view: ViewSums,
}

impl Default for Survey {
    fn default() -> Self {
        Survey::new()
    }
}

impl Survey {
    /// A procedure about to take its first view.
    pub const fn new() -> Survey {
        Survey {
            views: [Readings { heading: Angle::ZERO, front: None, right: None }; MAX_VIEWS],
            count: 0,
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
        }
    }

    /// Views taken so far.
    pub fn views(&self) -> &[Readings] {
        self.views.get(..self.count).unwrap_or(&[])
    }

    /// A lidar's distance (the lidar model's output); kept while a view is
    /// being taken, up to [`config::locate::LIDAR_READINGS`].
    pub fn lidar(&mut self, id: LidarId, d: Length) {
        let distances = match id {
            LidarId::Front => &mut self.view.front,
            LidarId::Right => &mut self.view.right,
        };
        if matches!(self.phase, Phase::View) {
            // a full view keeps its first readings
            let _ = distances.push(d);
        }
    }

    /// A compass heading; kept while a view is being taken, up to
    /// [`config::locate::COMPASS_READINGS`].
    pub fn heading(&mut self, h: Angle) {
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
        self.ticks = self.ticks.saturating_add(1);
        match &mut self.phase {
            Phase::View if self.view.complete() || self.ticks > VIEW_TICKS => self.view_taken(),
            Phase::View => Action::Stand,
            Phase::Turn if self.ticks > TURN_TICKS => self.enter(Phase::Settle),
            Phase::Turn => Action::Turn { clockwise: self.clockwise },
            Phase::Settle if self.ticks > SETTLE_TICKS => {
                self.view = ViewSums::default();
                self.enter(Phase::View)
            }
            Phase::Settle => Action::Stand,
            Phase::Search(search) => match search.step(arena, config::locate::SCORES_PER_TICK) {
                None => Action::Stand,
                Some(result) => self.searched(result.map_err(Failure::from)),
            },
        }
    }

    /// A view is in: kept, then a search or another turn.
    fn view_taken(&mut self) -> Action {
        let Some(r) = self.view.readings() else {
            return Action::Done(Err(Failure::NoHeading));
        };
        if let Some(previous) = self.views().last() {
            if r.heading.diff(previous.heading).saturating_abs() < BLOCKED {
                self.clockwise = !self.clockwise;
            }
        }
        if let Some(slot) = self.views.get_mut(self.count) {
            *slot = r;
            self.count = self.count.saturating_add(1);
        }
        if self.count < config::locate::MIN_VIEWS {
            return self.enter(Phase::Turn);
        }
        match Search::new(self.views()) {
            Ok(search) => self.enter(Phase::Search(search)),
            Err(e) => self.searched(Err(e.into())),
        }
    }

    /// A search's answer: the end, or another view.
    fn searched(&mut self, result: Result<Fix, Failure>) -> Action {
        let last_view = self.count >= MAX_VIEWS;
        match result {
            // (the fix's heading is the compass's, within goto's limit)
            Ok(fix) if (!fix.ambiguous && position_steerable(fix.sigma_x, fix.sigma_y, 1)) || last_view => {
                Action::Done(Ok(fix))
            }
            Err(e) if last_view => Action::Done(Err(e)),
            _ => self.enter(Phase::Turn),
        }
    }

    fn enter(&mut self, phase: Phase) -> Action {
        self.phase = phase;
        self.ticks = 0;
        Action::Stand
    }
}
