//! One start's fit under way ([`Fit`]): Levenberg-Marquardt, a pass over
//! the rows (`rows.rs`) a slice at a time, each pass summing the start's
//! cost, the normal equations at its parameters (`solve.rs`), or the cost
//! of the step tried.

use super::rows::{param, Loss, Model, Params, HEADING, LEVER, PX, PY};
use super::solve::{self, Sums, DAMPING_MAX, DAMPING_MIN};
use super::{q24, End};
use crate::config::refine as cfg;
use crate::math::{div_i64, sin_cos, Angle};

/// A step that lowers the cost by less than this ends the start (Q24: a
/// thousandth of a sigma squared).
const CONVERGED: i64 = q24(0.5);

/// What a start's fit is summing over the readings.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
enum Stage {
    /// The start's cost.
    Start,
    /// The normal equations at the parameters.
    Normal,
    /// The cost of the step tried.
    Trial,
}

/// One start's fit under way.
#[derive(Clone, Copy, Debug)]
pub(super) struct Fit {
    p: Params,
    cost: i64,
    readings: u32,
    /// The step tried (from `sums`, at `p`).
    trial: Params,
    stage: Stage,
    /// The pass under way: its next row, and its sums so far.
    row: u16,
    pass_cost: i64,
    pass_readings: u32,
    sums: Sums,
    damping: i8,
    iterations: u8,
    tries: u8,
}

impl Fit {
    pub(super) fn new(p: Params) -> Fit {
        Fit {
            p,
            cost: i64::MAX,
            readings: 0,
            trial: p,
            stage: Stage::Start,
            row: 0,
            pass_cost: 0,
            pass_readings: 0,
            sums: Sums::ZERO,
            damping: -10,
            iterations: 0,
            tries: 0,
        }
    }

    /// The pass's next rows: true when it is done.
    pub(super) fn pass(&mut self, model: &Model) -> bool {
        let at = if self.stage == Stage::Trial { &self.trial } else { &self.p };
        let normal = self.stage == Stage::Normal;
        let (cost, readings, sums) = (&mut self.pass_cost, &mut self.pass_readings, &mut self.sums);
        let done = model.rows(at, normal, usize::from(self.row), cfg::ROWS_PER_STEP, |row| {
            if normal {
                sums.add(row);
            } else {
                *cost = cost.saturating_add(solve::cost(row));
                *readings = readings.saturating_add(u32::from(row.loss == Loss::Robust));
            }
        });
        self.row = self.row.saturating_add(cfg::ROWS_PER_STEP as u16);
        done
    }

    /// A pass is done: the next one. True when the start has ended.
    pub(super) fn next(&mut self, params: usize) -> bool {
        let (cost, readings) = (self.pass_cost, self.pass_readings);
        (self.row, self.pass_cost, self.pass_readings) = (0, 0, 0);
        match self.stage {
            Stage::Start => {
                (self.cost, self.readings) = (cost, readings);
                self.begin_normal();
                false
            }
            Stage::Normal => self.try_step(params),
            Stage::Trial if cost < self.cost => {
                let gain = self.cost.saturating_sub(cost);
                (self.p, self.cost, self.readings, self.tries) = (self.trial, cost, readings, 0);
                self.damping = self.damping.saturating_sub(2).max(DAMPING_MIN);
                self.iterations = self.iterations.saturating_add(1);
                if self.iterations >= cfg::MAX_ITERATIONS || gain < CONVERGED {
                    return true;
                }
                self.begin_normal();
                false
            }
            // the same normal equations, damped more
            Stage::Trial => self.failed() || self.try_step(params),
        }
    }

    fn begin_normal(&mut self) {
        self.sums = Sums::ZERO;
        self.stage = Stage::Normal;
    }

    /// A step from the normal equations: its cost's pass next. True when
    /// no step can be tried any more.
    fn try_step(&mut self, params: usize) -> bool {
        loop {
            if self.sums.step(&self.p, params, self.damping, &mut self.trial) {
                self.stage = Stage::Trial;
                return false;
            }
            if self.failed() {
                return true;
            }
        }
    }

    /// A failed try: more damping, or the start's end.
    fn failed(&mut self) -> bool {
        self.tries = self.tries.saturating_add(1);
        self.damping = self.damping.saturating_add(3).min(DAMPING_MAX);
        self.tries >= cfg::MAX_TRIES
    }

    /// Where it ended: the last view's pose and the cost with `margin`.
    pub(super) fn end(&self, views: usize, margin: i64) -> End {
        let get = |k: usize| param(&self.p, k);
        let theta = Angle(get(HEADING.saturating_add(views.saturating_sub(1))) as u32);
        let (s, c) = sin_cos(theta);
        let x = get(PX).saturating_add(get(LEVER).saturating_mul(i64::from(c)) >> 30);
        let y = get(PY).saturating_add(get(LEVER).saturating_mul(i64::from(s)) >> 30);
        let cost = self.cost.saturating_add(margin);
        End {
            cost,
            per_reading: div_i64(cost, i64::from(self.readings.max(1))).unwrap_or(i64::MAX).min(i64::from(i32::MAX))
                as i32,
            x_mm: whole_mm(x),
            y_mm: whole_mm(y),
            theta,
        }
    }
}

/// Q16 mm to whole mm, rounded, within `i16` (the box is a few hundred mm).
fn whole_mm(v: i64) -> i16 {
    (v.saturating_add(1 << 15) >> 16).clamp(i64::from(i16::MIN), i64::from(i16::MAX)) as i16
}
