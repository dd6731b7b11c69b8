//! What a simulated run draws once from its seed ([`Drawn`]): the hard
//! world's turn-rate factors and their drift, its speed scale, its pivot,
//! the compass bias's pattern over the floor and its excursions near the
//! walls (host only, f64). With the lab's or the ideal [`Realism`] every
//! draw is neutral (factors of 1, no offset, no wall excursion).
//!
//! The draws come from a stream of their own (the seed scrambled with a
//! constant), so the lab's world draws exactly what it drew before the hard
//! world existed: its runs, and the figures measured on them, stay.

use super::arena::Arena;
use super::noise::Rng;
use super::realism::{compass_disturbance, Realism};

/// Scrambles the seed for the draws' own stream.
const STREAM: u64 = 0x4841_5244_574f_524c; // "HARDWORL"

/// A run's draws (see the module docs).
#[derive(Clone, Copy, PartialEq, Debug)]
pub struct Drawn {
    /// Turn-rate factor, clockwise and counter-clockwise, before drift.
    pub turn_scale: [f64; 2],
    /// Each direction's drift phase, radians.
    turn_drift_phase: [f64; 2],
    /// Straight speed factor.
    pub speed_scale: f64,
    /// Added to [`Realism::pivot_behind_mm`] for the run, mm.
    pub pivot_offset_mm: f64,
    /// The floor pattern's phase (drawn from the run's main stream, as
    /// the lab's world always did).
    pub compass_phase: f64,
    /// The wall excursion's phase along the walls, radians.
    wall_phase: f64,
}

impl Drawn {
    /// Nothing drawn: the lab's lines, no floor pattern phase.
    pub const NONE: Drawn = Drawn {
        turn_scale: [1.0; 2],
        turn_drift_phase: [0.0; 2],
        speed_scale: 1.0,
        pivot_offset_mm: 0.0,
        compass_phase: 0.0,
        wall_phase: 0.0,
    };

    /// The draws of the run with `seed` in the world `r`; `compass_phase`
    /// is the floor pattern's (drawn by the caller from its main stream).
    pub fn draw(seed: u64, r: &Realism, compass_phase: f64) -> Drawn {
        let mut rng = Rng::new(seed ^ STREAM);
        let (lo, hi) = r.turn_scale;
        let tau = core::f64::consts::TAU;
        Drawn {
            turn_scale: [rng.range_f64(lo, hi), rng.range_f64(lo, hi)],
            turn_drift_phase: [rng.range_f64(0.0, tau), rng.range_f64(0.0, tau)],
            speed_scale: 1.0 + rng.range_f64(-r.speed_scale, r.speed_scale),
            pivot_offset_mm: rng.range_f64(-r.pivot_run_mm, r.pivot_run_mm),
            compass_phase,
            wall_phase: rng.range_f64(0.0, tau),
        }
    }

    /// The turn-rate factor `t_s` seconds into the run: the direction's
    /// draw, drifting by [`Realism::turn_drift`] of itself over
    /// [`Realism::turn_drift_period_s`], kept within
    /// [`Realism::turn_scale`].
    pub fn turn_factor(&self, clockwise: bool, t_s: f64, r: &Realism) -> f64 {
        let i = usize::from(!clockwise);
        let (base, phase) = (self.turn_scale[i], self.turn_drift_phase[i]);
        if r.turn_drift == 0.0 || r.turn_drift_period_s <= 0.0 {
            return base;
        }
        let wave = (core::f64::consts::TAU * t_s / r.turn_drift_period_s + phase).sin();
        (base * (1.0 + r.turn_drift * wave)).clamp(r.turn_scale.0, r.turn_scale.1)
    }

    /// The compass's heading error at (x, y) mm, radians: the floor's
    /// smooth pattern ([`compass_disturbance`]) and, within a few
    /// [`Realism::compass_wall_decay_mm`] of a wall, an excursion that
    /// brings it up to [`Realism::compass_wall_deg`] (its sign and size
    /// varying along the walls).
    pub fn compass_bias(&self, arena: &Arena, x: f64, y: f64, r: &Realism) -> f64 {
        let floor = compass_disturbance(x, y, r, self.compass_phase);
        let extra = (r.compass_wall_deg - r.compass_disturbance_deg).max(0.0);
        if extra == 0.0 || r.compass_wall_decay_mm <= 0.0 {
            return floor;
        }
        let near = (-arena.clearance(x, y).max(0.0) / r.compass_wall_decay_mm).exp();
        // where along the walls: the perimeter's coordinate of the nearest
        // wall point (one pattern running round the box)
        let (lx, wy) = (arena.length_x_mm(), arena.width_y_mm());
        let along = [(x, y), (wy - y, wy + x), (lx - x, wy + lx + (wy - y)), (y, 2.0 * wy + lx + (lx - x))]
            .iter()
            .min_by(|a, b| a.0.total_cmp(&b.0))
            .map_or(0.0, |w| w.1);
        let k = core::f64::consts::TAU / r.compass_wall_wavelength_mm.max(1.0);
        floor + extra.to_radians() * near * (k * along + self.wall_phase).sin()
    }
}
