//! The arena on the host: the one [`Arena`] type (`model::measurement`,
//! the box the firmware's estimator knows), seen in f64 mm, with ray
//! casting to its walls (host only). Its origin is at a corner, x along the
//! long side (north), y along the short side (east).

use crate::math::Length;
pub use crate::model::measurement::Arena;

impl Arena {
    /// A box `[0, length_x] x [0, width_y]`, mm (to the model's 2^-16 mm).
    pub fn from_mm_f64(length_x: f64, width_y: f64) -> Arena {
        Arena { length_x: Length::from_mm_f64(length_x), width_y: Length::from_mm_f64(width_y) }
    }

    /// Extent along x (north), mm.
    pub fn length_x_mm(&self) -> f64 {
        self.length_x.to_mm_f64()
    }

    /// Extent along y (east), mm.
    pub fn width_y_mm(&self) -> f64 {
        self.width_y.to_mm_f64()
    }

    /// True when (x, y) is inside the box (walls included).
    pub fn contains(&self, x: f64, y: f64) -> bool {
        (0.0..=self.length_x_mm()).contains(&x) && (0.0..=self.width_y_mm()).contains(&y)
    }

    /// Distance from (x, y) to the nearest wall, mm (negative outside).
    pub fn clearance(&self, x: f64, y: f64) -> f64 {
        x.min(self.length_x_mm() - x).min(y).min(self.width_y_mm() - y)
    }

    /// Distance along the ray from (x, y) in direction `heading` (radians,
    /// clockwise from north: direction `(cos, sin)` in (x, y)) to the first
    /// wall it meets, mm; `None` if it meets none (a ray from outside that
    /// misses the box). A ray from inside always hits.
    pub fn ray_cast(&self, x: f64, y: f64, heading: f64) -> Option<f64> {
        let (dy, dx) = heading.sin_cos();
        let (length_x, width_y) = (self.length_x_mm(), self.width_y_mm());
        // from inside (walls included) only the walls ahead count, so a ray
        // leaving a wall or a corner is not stopped by it at distance 0
        let inside = self.contains(x, y);
        let ahead = |wall: f64, pos: f64, dir: f64| !inside || (wall - pos) * dir > 0.0;
        let mut best: Option<f64> = None;
        let mut consider = |t: f64, other: f64, lo: f64, hi: f64| {
            // tolerance for hits exactly on a corner
            if t >= 0.0 && other >= lo - 1e-9 && other <= hi + 1e-9 && best.is_none_or(|b| t < b) {
                best = Some(t);
            }
        };
        if dx != 0.0 {
            for wall in [0.0, length_x].into_iter().filter(|&w| ahead(w, x, dx)) {
                let t = (wall - x) / dx;
                consider(t, y + t * dy, 0.0, width_y);
            }
        }
        if dy != 0.0 {
            for wall in [0.0, width_y].into_iter().filter(|&w| ahead(w, y, dy)) {
                let t = (wall - y) / dy;
                consider(t, x + t * dx, 0.0, length_x);
            }
        }
        best
    }
}
