//! The test arena: a box, origin at a corner, x along the long side (north),
//! y along the short side (east), mm (fact sheet: the team's 762.5 x 495 mm box).

use super::Length;

/// Length along x (north), mm (fact sheet).
pub const LENGTH_X: Length = Length::from_mm_f64(762.5);
/// Width along y (east), mm (fact sheet).
pub const WIDTH_Y: Length = Length::from_mm_f64(495.0);
