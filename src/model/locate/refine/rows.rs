//! The survey's model, one row at a time: each reading's residual in its
//! sigmas and how it moves with the parameters (closed form: the beam's
//! own derivatives,
//! [`Beam::heading_lever`](crate::model::measurement::Beam::heading_lever),
//! as the estimator's update takes them, chained through the pivot and the
//! lever; a lidar's row: `rows/lidar.rs`).
//!
//! # The parameters ([`Params`])
//! The body turns about a pivot `P`; the reference point sits at a lever
//! `D` from it, at `P + D (cos t, sin t)` with `t` the heading, at the
//! last view. Each turn `j` (between views `j` and `j + 1`) swings it at a
//! lever of its own, `D + e_j` (the pivot moves: the skid's grip), so a
//! reading before the turn sits `e_j (u(t) - u(t_j+1))` from there, `u`
//! the heading's unit vector (the moves' chords, [`Model::chords`]).
//! Each view has its own heading `t_i`; the compass
//! reads `t_i + b + (D / 100 mm) (g_x cos t_i + g_y sin t_i)`: a bias `b`
//! at the pivot, and a floor that bends the field, its bias changing by
//! `g` every 100 mm the compass (at the reference point) moves from the
//! pivot, give or take a little a view;
//! each way's turns run at one rate (angle per tick); a turn's readings sit
//! at headings between its two views', in proportion to its ticks.
//!
//! # Units
//! A parameter is stored in its fixed-point LSB ([`unit()`]: a position,
//! the lever or a move in Q16 mm, an angle in [`Angle`] LSB, a rate in angle LSB a
//! tick) and stepped in its unit (1 mm, 1 mrad, [`RATE_UNIT`]). A residual
//! is Q12 sigmas, a row's derivatives Q12 sigmas a unit.

use super::Share;
use crate::config::estimator as est;
use crate::config::refine as cfg;
use crate::math::{div_i64, mul_wide, quotient, sin_cos, Angle, Length};
use crate::model::locate::turns::Turn;
use crate::model::locate::Readings;
use crate::model::measurement::{Arena, LidarId};

mod lidar;

/// The parameters' places: the pivot, the lever, the compass's bias, each
/// way's turn a tick (both positive), the field's bend along x and along y
/// (the bias's change over [`FIELD_SPAN`]), then the views' headings.
pub const PX: usize = 0;
pub const PY: usize = 1;
pub const LEVER: usize = 2;
pub const BIAS: usize = 3;
pub const CW: usize = 4;
pub const CCW: usize = 5;
pub const FIELD_X: usize = 6;
pub const FIELD_Y: usize = 7;
pub const HEADING: usize = 8;
/// Views the model weighs at most (the refinement passes it the last
/// ones).
pub const FIT_VIEWS: usize = cfg::REFINE_VIEWS;
/// Each turn's pivot move, after the views' headings: turn `j` (between
/// views `j` and `j + 1`) pivots that much farther from the reference
/// point than the lever.
pub const MOVE: usize = HEADING + FIT_VIEWS;
/// Parameters at most.
pub const MAX_PARAMS: usize = MOVE + FIT_VIEWS - 1;

/// The parameters in their LSB, an angle's wrapping (`i32`: the fit's two
/// sets of them are on the robot's stack, `cargo fw-image`).
pub type Params = [i32; MAX_PARAMS];

/// Parameter `k` of `p` (0 past the parameters).
pub fn param(p: &Params, k: usize) -> i64 {
    p.get(k).map_or(0, |&v| i64::from(v))
}

/// One mrad in angle LSB.
pub const MRAD: i64 = Angle::from_radians_f64(0.001).0 as i64;
/// A rate's unit: one mrad over a 32-tick turn (a quarter turn's
/// 33 ticks at `goto::TURN_MRAD_S`), angle LSB a tick.
pub const RATE_UNIT: i64 = MRAD / 32;
const MM: i64 = 1 << 16;
/// Parameter `k`'s unit in its LSB.
pub fn unit(k: usize) -> i64 {
    // (compares, not a `match`: LLVM made the match a table in .rodata,
    // the robot's DRAM, 24 bytes more in `cargo fw-image`)
    if k <= LEVER || k >= MOVE {
        MM
    } else if k == CW || k == CCW {
        RATE_UNIT
    } else {
        MRAD
    }
}

/// Q12: a residual's and a derivative's scale (sigmas).
pub const ONE_SIGMA: i64 = 1 << 12;
/// The bounded loss's scale (Q12).
pub const ROBUST: i64 = (cfg::ROBUST_SIGMAS * ONE_SIGMA as f64) as i64;
/// Residuals are held within this (2^12 sigmas: squares stay far from
/// i64's bound).
const R_MAX: i64 = 1 << 24;

/// `2^40 / sigma` for a sigma in `lsb` units: a value in those units times
/// it, `>> 28`, is Q12 sigmas.
const fn inv(sigma_lsb: f64) -> i64 {
    ((1u64 << 40) as f64 / sigma_lsb) as i64
}
const fn deg(d: f64) -> f64 {
    Angle::from_degrees_f64(d).0 as f64
}

/// A max-mixture prior: the inverse sigmas of its narrow and wide parts
/// and what the wide part costs over the narrow one at zero (Q24), twice
/// `ln((wide / narrow) (share / (1 - share)))`.
#[derive(Clone, Copy)]
struct Mixture {
    narrow: i64,
    wide: i64,
    extra: i64,
}

const fn mixture((share, narrow, wide): (f64, f64, f64)) -> Mixture {
    let extra = 2.0 * crate::math::ln_f64(wide / narrow * share / (1.0 - share));
    Mixture { narrow: inv(deg(narrow)), wide: inv(deg(wide)), extra: (extra * (ONE_SIGMA * ONE_SIGMA) as f64) as i64 }
}

const BIAS_PRIOR: Mixture = mixture(cfg::BIAS_MIX);
const VIEW_PRIOR: Mixture = mixture(cfg::VIEW_MIX);
const TURN_INV: i64 = inv(deg(cfg::TURN_SIGMA_DEG));
const FIELD_INV: i64 = inv(deg(cfg::FIELD_SIGMA_DEG));
const MOVE_INV: i64 = inv(cfg::PIVOT_MOVE_SIGMA_MM * 65536.0);
/// The distance the field's bend is the bias's change over
/// ([`cfg::FIELD_SIGMA_DEG`]'s), Q16 mm.
pub const FIELD_SPAN: i64 = 100 * MM;
/// The lever's prior: the pivot anywhere the estimator allows
/// (`PIVOT_MIN_MM` to `PIVOT_MAX_MM` behind the axle), its mean and a
/// third of the range as one sigma.
const LEVER_MEAN: i64 = Length::from_mm_f64(
    crate::config::geometry::ROTATION_TO_REFERENCE.0 as f64 / 65536.0 + (est::PIVOT_MIN_MM + est::PIVOT_MAX_MM) / 2.0,
)
.0 as i64;
const LEVER_INV: i64 = inv((est::PIVOT_MAX_MM - est::PIVOT_MIN_MM) / 3.0 * 65536.0);
const Q30: i64 = 1 << 30;
/// An angle LSB in rad, Q46 (an angle times it `>> 16` is Q30 rad).
const RAD_Q30: i64 = (Q30 as f64 * 65536.0 / Angle::from_radians_f64(1.0).0 as f64) as i64;
/// `2^46 / FIELD_SPAN`: a lever (Q16 mm) times it `>> 16` is Q30 spans.
const PER_SPAN: i64 = (Q30 << 16) / FIELD_SPAN;
/// 1/1000 in Q30: a derivative per rad to one per mrad.
const PER_MRAD: i64 = Q30 / 1000;

/// How long before its tick a reading describes the body, ticks, Q16
/// (`config::lidar::READING_AGE_US`): a turn's reading sits that much
/// earlier in it.
const READING_AGE: u64 =
    crate::config::lidar::READING_AGE_US as u64 * crate::config::timing::LOOP_HZ as u64 * (1 << 16) / 1_000_000;

/// How a row counts in the cost.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum Loss {
    /// A reading (or a turn): bounded ([`ROBUST`]).
    Robust,
    /// A prior: its square, plus a constant (Q24) when the wide part of a
    /// mixture explains it.
    Square(i64),
}

/// One residual (Q12 sigmas) and its derivatives (Q12 sigmas a unit) by
/// the parameters they are not zero for.
#[derive(Clone, Copy, Debug)]
pub struct Row {
    pub r: i32,
    cols: [(u8, i32); 9],
    len: u8,
    pub loss: Loss,
}

impl Row {
    fn new(r: i64, loss: Loss) -> Row {
        Row { r: clamp(r), cols: [(0, 0); 9], len: 0, loss }
    }

    fn with(mut self, k: usize, d: i64) -> Row {
        if let Some(slot) = self.cols.get_mut(usize::from(self.len)) {
            *slot = (k as u8, clamp(d));
            self.len = self.len.saturating_add(1);
        }
        self
    }

    /// Its derivatives: (parameter, Q12 sigmas a unit).
    pub fn cols(&self) -> &[(u8, i32)] {
        self.cols.get(..usize::from(self.len)).unwrap_or(&[])
    }
}

/// Each view's heading as a unit vector (cos, sin; Q30), once a call of
/// [`Model::rows`].
type Units = [(i32, i32); FIT_VIEWS];

// out of line: inlined into the loop's tick, `sin_cos`'s quadrant became
// a jump table `cargo fw-image`'s stack check could not follow
#[inline(never)]
fn headings(p: &Params) -> Units {
    let mut units = [(0, 0); FIT_VIEWS];
    for (i, u) in units.iter_mut().enumerate() {
        let (s, c) = sin_cos(Angle(param(p, HEADING.saturating_add(i)) as u32));
        *u = (c, s);
    }
    units
}

/// Within [`R_MAX`], as an `i32`.
fn clamp(v: i64) -> i32 {
    v.clamp(-R_MAX, R_MAX) as i32
}

/// `a b >> s` for factors within `i32` (a residual's or a derivative's
/// scaling: `mul_wide`'s 25 lx106 instructions, where a saturating i64
/// product is about 290; the pass over the readings is the fit's cost).
fn mul_shr(a: i64, b: i64, s: u32) -> i64 {
    let fit = |v: i64| v.clamp(i64::from(i32::MIN), i64::from(i32::MAX)) as i32;
    mul_wide(fit(a), fit(b)) >> s
}

/// Which rows a pass's slice makes: the `from`-th to before the `end`-th.
struct Slice {
    index: usize,
    from: usize,
    end: usize,
}

impl Slice {
    /// The next row is in the slice (counted either way).
    fn take(&mut self) -> bool {
        let take = self.index >= self.from && self.index < self.end;
        self.index = self.index.saturating_add(1);
        take
    }
}

/// Where a reading's heading comes from: one view's, or a turn's two
/// views' weighed by how far through the turn it came (Q16).
#[derive(Clone, Copy)]
struct At {
    theta: i64,
    from: (usize, i64),
    to: (usize, i64),
    /// The turns whose whole chord the body still has ahead (from this
    /// one on), and the turn under way (its chord from `theta` on).
    ahead: usize,
    turning: Option<usize>,
}

/// The survey's readings, and the start's fixed choices.
pub struct Model<'a> {
    pub arena: &'a Arena,
    pub views: &'a [Readings],
    pub turns: &'a [Turn],
    pub share: Share,
    /// The search's place for the last view (Q16 mm) and `2^40 / sigma`.
    pub near: (i64, i64, i64),
}

impl Model<'_> {
    /// Parameters in use: the views' headings after the common ones.
    pub fn params(&self) -> usize {
        let views = self.views.len().min(FIT_VIEWS);
        if views > 1 {
            MOVE.saturating_add(views - 1)
        } else {
            HEADING.saturating_add(views)
        }
    }

    /// The rows at `p` from the `from`-th, `count` of them at most, in
    /// order: the views (lidars, compass), the turns (the turn itself, its
    /// readings), then the priors; the derivatives only when asked for
    /// (the cost needs none). True when the last row was among them.
    pub fn rows(&self, p: &Params, derivatives: bool, from: usize, count: usize, mut f: impl FnMut(&Row)) -> bool {
        // a row is made only when its index is in the slice
        let mut slice = Slice { index: 0, from, end: from.saturating_add(count) };
        let get = |k: usize| param(p, k);
        let views = self.views.get(..FIT_VIEWS).unwrap_or(self.views);
        let units = headings(p);
        for (i, v) in views.iter().enumerate() {
            let k = HEADING.saturating_add(i);
            let at = At { theta: get(k), from: (k, 1 << 16), to: (k, 0), ahead: i, turning: None };
            for (id, z) in [(LidarId::Front, v.front), (LidarId::Right, v.right)] {
                if let Some(z) = z {
                    if slice.take() {
                        f(&self.lidar(p, &units, at, id, z, derivatives));
                    }
                }
            }
            if slice.take() {
                f(&self.compass(p, k, v.heading));
            }
        }
        for (j, t) in self.turns.iter().enumerate().take(views.len().saturating_sub(1)) {
            let (from, to) = (HEADING.saturating_add(j), HEADING.saturating_add(j).saturating_add(1));
            // the turn from `a` to `b`, the angle between them wrapped
            let a = get(from);
            let b = a.saturating_add(i64::from((get(to) as i32).wrapping_sub(get(from) as i32)));
            let ticks = i64::from(t.ticks);
            // a reading's share of the turn: its tick over the turn's, Q16
            let per_tick = quotient(1, u64::from(t.ticks.max(1)), 32);
            if ticks > 0 && slice.take() {
                let (rate, way) = if t.clockwise { (get(CW), 1) } else { (get(CCW).saturating_neg(), -1) };
                let miss = b.saturating_sub(a).saturating_sub(rate.saturating_mul(ticks));
                let d = mul_shr(MRAD, TURN_INV, 28);
                let dr = mul_shr(ticks.saturating_mul(RATE_UNIT), TURN_INV, 28).saturating_mul(-way);
                let rate_col = if t.clockwise { CW } else { CCW };
                f(&Row::new(mul_shr(miss, TURN_INV, 28), Loss::Robust).with(to, d).with(from, -d).with(rate_col, dr));
            }
            for s in t.samples() {
                for id in [LidarId::Front, LidarId::Right] {
                    if let Some((tick, z)) = s.reading(id) {
                        if slice.take() {
                            let when = (u64::from(tick) << 16).saturating_sub(READING_AGE);
                            let done = (when.saturating_mul(per_tick) >> 32).min(1 << 16) as i64;
                            let theta = a.saturating_add(mul_shr(b.saturating_sub(a), done, 16));
                            let at = At {
                                theta,
                                from: (from, (1 << 16) - done),
                                to: (to, done),
                                ahead: j.saturating_add(1),
                                turning: Some(j),
                            };
                            f(&self.lidar(p, &units, at, id, z, derivatives));
                        }
                    }
                }
            }
        }
        if slice.take() {
            let bias = i64::from(Angle(get(BIAS) as u32).diff(Angle::ZERO));
            f(&mixed(bias, BIAS_PRIOR, &[BIAS], 1));
        }
        // the field's bend, each way
        for k in [FIELD_X, FIELD_Y] {
            if slice.take() {
                f(&gaussian(k, get(k), FIELD_INV));
            }
        }
        if slice.take() {
            f(&gaussian(LEVER, get(LEVER).saturating_sub(LEVER_MEAN), LEVER_INV));
        }
        for j in 0..views.len().saturating_sub(1) {
            if slice.take() {
                let k = MOVE.saturating_add(j);
                f(&gaussian(k, get(k), MOVE_INV));
            }
        }
        let last = HEADING.saturating_add(views.len().saturating_sub(1));
        for on_x in [true, false] {
            if slice.take() {
                f(&self.near(p, last, on_x));
            }
        }
        slice.index <= slice.end
    }

    /// The prior that the last view stays near the search's place: along
    /// x, or along y.
    fn near(&self, p: &Params, last: usize, on_x: bool) -> Row {
        let get = |k: usize| param(p, k);
        let (s, c) = sin_cos(Angle(get(last) as u32));
        let (s, c) = (i64::from(s), i64::from(c));
        let d = get(LEVER);
        let (nx, ny, inv) = self.near;
        let per = |v: i64| mul_shr(v, inv, 28);
        let (start, toward, swing, at, col) =
            if on_x { (get(PX), c, mul_shr(d, -s, 30), nx, PX) } else { (get(PY), s, mul_shr(d, c, 30), ny, PY) };
        let place = start.saturating_add(mul_shr(d, toward, 30));
        Row::new(per(place.saturating_sub(at)), Loss::Square(0))
            .with(col, per(MM))
            .with(LEVER, per(toward >> 14))
            .with(last, per(mul_shr(swing, PER_MRAD, 30)))
    }

    /// View `k`'s compass reading `read`: the view's heading, the bias at
    /// the pivot, and the field's bend out to the reference point.
    // out of line: inlined into the pass, the Xtensa backend could not
    // spill a register in its frame (lx106/run.sh's build)
    #[inline(never)]
    fn compass(&self, p: &Params, k: usize, read: Angle) -> Row {
        let get = |k: usize| param(p, k);
        let (s, c) = sin_cos(Angle(get(k) as u32));
        let (s, c) = (i64::from(s), i64::from(c));
        let (gx, gy) = (get(FIELD_X), get(FIELD_Y));
        // the lever in field spans (Q30), the bend along the heading and
        // across it (angle LSB a span)
        let spans = mul_shr(get(LEVER), PER_SPAN, 16);
        let along = mul_shr(gx, c, 30).saturating_add(mul_shr(gy, s, 30));
        let across = mul_shr(gy, c, 30).saturating_sub(mul_shr(gx, s, 30));
        let field = mul_shr(along, spans, 30);
        let predicted = get(k).saturating_add(get(BIAS)).saturating_add(field);
        let miss = i64::from(read.diff(Angle(predicted as u32)));
        let row = mixed(miss, VIEW_PRIOR, &[BIAS], -1);
        // the row's derivative by the bias (Q12 sigmas a mrad); the others
        // move the predicted reading by their share of a mrad
        let per = row.cols().first().map_or(0, |&(_, d)| i64::from(d));
        let turning = mul_shr(mul_shr(across, spans, 30), RAD_Q30, 16);
        let per_mm = div_i64(per.saturating_mul(along), MRAD.saturating_mul(FIELD_SPAN / MM)).unwrap_or(0);
        row.with(k, per.saturating_add(mul_shr(per, turning, 30)))
            .with(FIELD_X, mul_shr(mul_shr(per, c, 30), spans, 30))
            .with(FIELD_Y, mul_shr(mul_shr(per, s, 30), spans, 30))
            .with(LEVER, per_mm)
    }
}

/// A Gaussian prior's row: parameter `k` off its mean by `miss` (its
/// LSB), one sigma `2^40 / inv` LSB.
fn gaussian(k: usize, miss: i64, inv: i64) -> Row {
    Row::new(mul_shr(miss, inv, 28), Loss::Square(0)).with(k, mul_shr(unit(k), inv, 28))
}

/// A max-mixture prior's row for `miss` (angle LSB) in the parameters
/// `cols`, each moving it by `sign` mrad a unit: the part that explains
/// it better.
fn mixed(miss: i64, m: Mixture, cols: &[usize], sign: i64) -> Row {
    let narrow = mul_shr(miss, m.narrow, 28);
    let wide = mul_shr(miss, m.wide, 28);
    let (r, inv, extra) = if narrow.saturating_mul(narrow) <= wide.saturating_mul(wide).saturating_add(m.extra) {
        (narrow, m.narrow, 0)
    } else {
        (wide, m.wide, m.extra)
    };
    let d = mul_shr(MRAD, inv, 28).saturating_mul(sign);
    cols.iter().fold(Row::new(r, Loss::Square(extra)), |row, &k| row.with(k, d))
}
