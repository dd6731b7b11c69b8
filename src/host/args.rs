//! Option values the host tools (`simulate`, `replay`) share, parsed one way:
//! `--arena LxW` (mm, x north by y east: `800x500`; `800,500` is also taken)
//! and `--start X,Y,DEG` (mm, mm, degrees clockwise from north). Errors name
//! the option and what it wants.

use std::format;
use std::string::String;
use std::vec::Vec;

/// The largest arena side, mm: the protocol's and the estimator's pose
/// limit (`pose`: |x|, |y| <= 30000).
pub const MAX_ARENA_SIDE_MM: f64 = 30_000.0;

/// A finite number.
pub fn number(option: &str, s: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(v),
        _ => Err(format!("{option}: {s:?} is not a number")),
    }
}

/// `LxW` (or `L,W`): the arena's length along x and width along y, mm, each
/// in 1..=30000.
pub fn arena(s: &str) -> Result<(f64, f64), String> {
    let want = "--arena wants LxW in mm, e.g. 762.5x495";
    let (l, w) = s.split_once(['x', 'X', ',']).ok_or(want)?;
    let (l, w) = (number("--arena", l)?, number("--arena", w)?);
    if !(1.0..=MAX_ARENA_SIDE_MM).contains(&l) || !(1.0..=MAX_ARENA_SIDE_MM).contains(&w) {
        return Err(format!("--arena {s}: each side must be 1..30000 mm"));
    }
    Ok((l, w))
}

/// `X,Y,DEG`: a pose inside the arena `length_x` by `width_y` (walls
/// included), heading in degrees clockwise from north.
pub fn start(s: &str, length_x: f64, width_y: f64) -> Result<(f64, f64, f64), String> {
    let v: Vec<&str> = s.split(',').collect();
    let [x, y, deg] = v.as_slice() else { return Err(format!("--start wants X,Y,DEG (mm, mm, degrees), got {s:?}")) };
    let (x, y, deg) = (number("--start", x)?, number("--start", y)?, number("--start", deg)?);
    if !(0.0..=length_x).contains(&x) || !(0.0..=width_y).contains(&y) {
        return Err(format!(
            "--start {s}: ({x}, {y}) mm is outside the {length_x} x {width_y} mm arena (x 0..{length_x}, y 0..{width_y})"
        ));
    }
    Ok((x, y, deg))
}
