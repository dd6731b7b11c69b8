//! The filter's constants, evaluated by the compiler from the config (no
//! float code reaches the robot), each in the fixed-point format its use
//! needs, with the bounds the arithmetic relies on asserted at build time.

use super::HEADING_LEVER_MM;
use crate::config::estimator as cfg;
use crate::config::geometry;

pub(super) const Q14: f64 = 16384.0;
pub(super) const TAU: f64 = core::f64::consts::TAU;
pub(super) const L: f64 = HEADING_LEVER_MM as f64;

const fn to_i32(x: f64) -> i32 {
    crate::math::round_f64(x) as i32
}
use crate::math::cos_f64;

/// Lidar variance, Q14 mm^2.
pub(super) const R_LIDAR: i32 =
    to_i32(cfg::LIDAR_SIGMA.0 as f64 / 65536.0 * (cfg::LIDAR_SIGMA.0 as f64 / 65536.0) * Q14);
/// Compass variance in (L rad)^2, Q14 mm^2.
pub(super) const R_COMPASS: i32 =
    to_i32((cfg::COMPASS_SIGMA_DEG * TAU / 360.0 * L) * (cfg::COMPASS_SIGMA_DEG * TAU / 360.0 * L) * Q14);
/// gate^2 in Q8.
pub(super) const GATE_SQ_Q8: i32 = to_i32(cfg::GATE_SIGMAS * cfg::GATE_SIGMAS * 256.0);
/// cos(max incidence), Q30.
pub(super) const MIN_NORMAL: i32 = to_i32(cos_f64(cfg::MAX_INCIDENCE_DEG * TAU / 360.0) * 1_073_741_824.0);
/// Straight: distance variance per mm driven (k^2 Lc), as a factor for
/// `mul_hi(|d| in Q24 mm, .)` giving Q14 mm^2: k^2 Lc 2^14 2^32 / 2^24.
pub(super) const K_DIST: i32 = to_i32(cfg::SPEED_SPREAD * cfg::SPEED_SPREAD * cfg::SPEED_CORRELATION_MM * Q14 * 256.0);
/// Straight: heading variance per mm driven, (k L / axle)^2 Lc, same scaling.
pub(super) const K_DRIFT: i32 = {
    let axle = geometry::AXLE_LENGTH.0 as f64 / 65536.0;
    let r = cfg::SPEED_SPREAD * L / axle;
    to_i32(r * r * cfg::SPEED_CORRELATION_MM * Q14 * 256.0)
};
/// Turn: heading variance (L rad)^2 Q14 per angle LSB turned, times 2^32
/// (for `mul_hi(|turn| in LSB, .)`): k^2 Lc_rad L^2 2^14 (2 pi / 2^32) 2^32.
pub(super) const K_TURN: i32 = {
    let lc = cfg::TURN_CORRELATION_DEG * TAU / 360.0;
    to_i32(cfg::TURN_SPREAD * cfg::TURN_SPREAD * lc * L * L * Q14 * TAU)
};
/// Turn: the position block's share, `K_TURN` plus the pivot's variance
/// across the car (sigma_pivot^2 Lc_rad per radian, the same scaling) over
/// `(D / L)^2`: the turn's noise vector `g` is `D / L` times the unit vector
/// across the car, so one `v g g^T` adds both.
pub(super) const K_TURN_POS: i32 = {
    let lc = cfg::TURN_CORRELATION_DEG * TAU / 360.0;
    let d_over_l = geometry::ROTATION_TO_REFERENCE.0 as f64 / 65536.0 / L;
    let pivot = cfg::PIVOT_SIGMA_MM * cfg::PIVOT_SIGMA_MM * lc * Q14 * TAU;
    to_i32(K_TURN as f64 + pivot / (d_over_l * d_over_l))
};
/// Floors per microsecond, Q14 mm^2 times 2^16.
pub(super) const FLOOR_POS: u32 = crate::math::round_f64(cfg::POSITION_FLOOR_MM2_PER_S * Q14 / 1e6 * 65_536.0) as u32;
pub(super) const FLOOR_HEADING: u32 = {
    let rad = TAU / 360.0;
    crate::math::round_f64(cfg::HEADING_FLOOR_DEG2_PER_S * rad * rad * L * L * Q14 / 1e6 * 65_536.0) as u32
};
/// D / L in Q31 (D < 128 mm by the config's assert, so D / L < 1/2).
pub(super) const D_OVER_L_Q31: i32 = to_i32(geometry::ROTATION_TO_REFERENCE.0 as f64 / 65536.0 / L * 2_147_483_648.0);
pub(super) const P_MAX: i32 = to_i32(cfg::MAX_VARIANCE_MM2 * Q14);
/// A lidar's re-acquisition's position variance, Q14 mm^2.
pub(super) const P_REACQUIRE: i32 = to_i32(cfg::REACQUIRE_SIGMA_MM * cfg::REACQUIRE_SIGMA_MM * Q14);
pub(super) const P_MIN: i32 = to_i32(cfg::MIN_VARIANCE_MM2 * Q14);
pub(super) const P0_POS: i32 = to_i32(cfg::INITIAL_SIGMA_MM * cfg::INITIAL_SIGMA_MM * Q14);
pub(super) const P0_HEADING: i32 = {
    let s = cfg::INITIAL_SIGMA_DEG * TAU / 360.0 * L;
    to_i32(s * s * Q14)
};
/// Angle LSB per (L rad) mm, 2^32 / (2 pi L), times 2^9: `mul_hi(K Q21, .)`
/// then times `nu` (Q16) and `>> 14` gives angle LSB (see `correct`).
pub(super) const LSB_PER_TILDE_MM_Q9: i32 = to_i32(4_294_967_296.0 / (TAU * L) * 512.0);
/// (L rad) mm in Q16 per angle LSB, times 2^32 (for `mul_hi`): 2 pi L 2^16 / 2^32 * 2^32.
pub(super) const TILDE_Q16_PER_LSB: i32 = to_i32(TAU * L * 65536.0);

const _: () = {
    assert!(R_LIDAR > 0 && R_COMPASS > 0 && R_COMPASS < (1 << 22));
    assert!(GATE_SQ_Q8 > 0 && GATE_SQ_Q8 < (1 << 12));
    // lidar R = R_LIDAR cos^2(incidence) >= R_LIDAR MIN_NORMAL^2 >= 2^12 (Q14 mm^2):
    // S >= R stays positive after `correct`'s scaling by 2^-9
    assert!((R_LIDAR as i64) * (MIN_NORMAL as i64) / (1 << 30) * (MIN_NORMAL as i64) / (1 << 30) >= (1 << 12));
    assert!(LSB_PER_TILDE_MM_Q9 > (1 << 30));
    // D / L < 1/4 (D < 64 mm): a turn's Jacobian entries stay below 1/2,
    // which `propagate`'s unsaturated products rely on
    assert!(D_OVER_L_Q31 >= 0 && D_OVER_L_Q31 < (1 << 29));
    assert!(MIN_NORMAL > (1 << 28) && MIN_NORMAL <= (1 << 30));
    assert!(P_MIN > 0 && P_MIN < P_MAX && P_MAX <= (1 << 30));
    assert!(P0_POS <= P_MAX && P0_HEADING <= P_MAX);
    assert!(P_REACQUIRE > P_MIN && P_REACQUIRE <= P_MAX);
    assert!(K_DIST > 0 && K_DRIFT > 0 && K_TURN > 0 && K_TURN_POS >= K_TURN && K_TURN_POS < (1 << 30));
    // floor * dt must fit u32 for dt <= 65535 us
    assert!((FLOOR_POS as u64) * 65_535 < (1 << 32) && (FLOOR_HEADING as u64) * 65_535 < (1 << 32));
};
