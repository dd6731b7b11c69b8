//! The filter's constants, evaluated by the compiler from the config (no
//! float code reaches the robot), each in the fixed-point format its use
//! needs, with the bounds the arithmetic relies on asserted at build time
//! (the covariance is Q12 mm^2, see [`super::Covariance`]).

use super::HEADING_LEVER_MM;
use crate::config::estimator as cfg;
use crate::config::geometry;

/// One mm^2 in the covariance's format.
pub(super) const Q12: f64 = 4096.0;
pub(super) const TAU: f64 = core::f64::consts::TAU;
pub(super) const L: f64 = HEADING_LEVER_MM as f64;
const RAD_PER_DEG: f64 = TAU / 360.0;

const fn to_i32(x: f64) -> i32 {
    crate::math::round_f64(x) as i32
}
const fn to_u32(x: f64) -> u32 {
    crate::math::round_f64(x) as u32
}
use crate::math::cos_f64;

/// A one-sigma angle in degrees as a variance of `L dtheta`, Q12 mm^2.
const fn angle_var(deg: f64) -> f64 {
    let s = deg * RAD_PER_DEG * L;
    s * s * Q12
}
/// A one-sigma scale error as a variance of `L dscale`, Q12 mm^2.
const fn scale_var(sigma: f64) -> f64 {
    let s = sigma * L;
    s * s * Q12
}

/// Lidar variance square on, Q12 mm^2.
pub(super) const R_LIDAR: i32 = {
    let s = cfg::LIDAR_SIGMA.0 as f64 / 65536.0;
    to_i32(s * s * Q12)
};
/// The lidar's variance per `tan^2(incidence)`, Q12 mm^2 (see
/// `cfg::LIDAR_INCIDENCE_SIGMA_MM`): a correction's `R` is `R_LIDAR cos^2 +
/// R_INCIDENCE sin^2`, the variance `R_LIDAR + R_INCIDENCE tan^2` scaled by
/// `cos^2` as the innovation is (no division).
pub(super) const R_INCIDENCE: i32 = to_i32(cfg::LIDAR_INCIDENCE_SIGMA_MM * cfg::LIDAR_INCIDENCE_SIGMA_MM * Q12);
/// A lidar reading's corner sigma with a known heading, Q16 mm (see
/// `cfg::CORNER_SIGMA_FLOOR_MM`).
pub(super) const CORNER_FLOOR: crate::math::Length = crate::math::Length::from_mm_f64(cfg::CORNER_SIGMA_FLOOR_MM);
/// `P_tt r^2 / L^2` is the heading's variance times a range `r` squared
/// (Q12 mm^2 for `r` in mm): the division by `L^2` is this shift (`L` a
/// power of two).
pub(super) const CORNER_RANGE_SHIFT: u32 = 2 * HEADING_LEVER_MM.trailing_zeros();
const _: () = assert!(HEADING_LEVER_MM.count_ones() == 1);
/// How many corner sigmas apart the walls' ranges make a reading ambiguous.
pub(super) const CORNER_SIGMAS: i32 = to_i32(cfg::CORNER_SIGMAS);
/// Compass variance in (L rad)^2, Q12 mm^2.
pub(super) const R_COMPASS: i32 = to_i32(angle_var(cfg::COMPASS_SIGMA_DEG));
/// gate^2 in Q8.
pub(super) const GATE_SQ_Q8: i32 = to_i32(cfg::GATE_SIGMAS * cfg::GATE_SIGMAS * 256.0);
/// cos(max incidence), Q30.
pub(super) const MIN_NORMAL: i32 = to_i32(cos_f64(cfg::MAX_INCIDENCE_DEG * RAD_PER_DEG) * 1_073_741_824.0);
/// Straight: distance variance per mm driven (k^2 Lc), as a factor for
/// `mul_hi(|d| in Q24 mm, .)` giving Q12 mm^2: k^2 Lc 2^12 2^32 / 2^24.
pub(super) const K_DIST: i32 = to_i32(cfg::SPEED_SPREAD * cfg::SPEED_SPREAD * cfg::SPEED_CORRELATION_MM * Q12 * 256.0);
/// Straight: heading variance per mm driven, (k L / axle)^2 Lc, same scaling.
pub(super) const K_DRIFT: i32 = {
    let axle = geometry::AXLE_LENGTH.0 as f64 / 65536.0;
    let r = cfg::SPEED_SPREAD * L / axle;
    to_i32(r * r * cfg::SPEED_CORRELATION_MM * Q12 * 256.0)
};
/// Straight: the compass bias's variance per mm driven, same scaling.
pub(super) const K_BIAS_MM: i32 = to_i32(angle_var(1.0) * cfg::COMPASS_BIAS_WALK_DEG2_PER_MM * 256.0);
/// Turn: heading variance (L rad)^2 Q12 per angle LSB turned, times 2^32
/// (for `mul_hi(|turn| in LSB, .)`): k^2 Lc_rad L^2 2^12 (2 pi / 2^32) 2^32.
pub(super) const K_TURN: i32 = {
    let lc = cfg::TURN_CORRELATION_DEG * RAD_PER_DEG;
    to_i32(cfg::TURN_SPREAD * cfg::TURN_SPREAD * lc * L * L * Q12 * TAU)
};
/// Turn: the pivot's variance across the car per angle LSB turned, times
/// 2^32: sigma_pivot^2 Lc_rad per radian, same scaling.
const fn pivot_k(sigma_mm: f64) -> f64 {
    sigma_mm * sigma_mm * cfg::TURN_CORRELATION_DEG * RAD_PER_DEG * Q12 * TAU
}
pub(super) const K_PIVOT: i32 = to_i32(pivot_k(cfg::PIVOT_SIGMA_MM));
/// Per microsecond, times 2^16 (for `(k dt) >> 16`): the position and
/// heading floors, the scales' and the bias's random walks.
const fn per_us(var_q12_per_s: f64) -> u32 {
    to_u32(var_q12_per_s / 1e6 * 65_536.0)
}
pub(super) const FLOOR_POS: u32 = per_us(cfg::POSITION_FLOOR_MM2_PER_S * Q12);
pub(super) const FLOOR_HEADING: u32 = per_us(angle_var(1.0) * cfg::HEADING_FLOOR_DEG2_PER_S);
pub(super) const SCALE_WALK: u32 = per_us(scale_var(cfg::SCALE_WALK_PER_SQRT_S));
pub(super) const BIAS_WALK: u32 = per_us(angle_var(1.0) * cfg::COMPASS_BIAS_WALK_DEG2_PER_S);
/// D / L in Q31 (D < 128 mm by the config's assert, so D / L < 1/2).
pub(super) const D_OVER_L_Q31: i32 = to_i32(geometry::ROTATION_TO_REFERENCE.0 as f64 / 65536.0 / L * 2_147_483_648.0);
/// A secondary's share of the leader's speed-scale variance per distance
/// driven: `Lc / L^2` per mm as a factor for `mul_hi(|d| in Q24 mm, .)`
/// giving Q30 (`Lc / L^2 2^30 2^32 / 2^24`; see `light::Shared`).
pub(super) const SPEED_SHARE_Q30: i32 = to_i32(cfg::SPEED_CORRELATION_MM / (L * L) * 274_877_906_944.0);
/// The same for a turn: `Lc` in radians per radian turned, as a factor
/// for `mul_hi(|angle| in LSB, .)` giving Q27 (`Lc 2 pi 2^27`).
pub(super) const TURN_SHARE_Q27: i32 = to_i32(cfg::TURN_CORRELATION_DEG * RAD_PER_DEG * TAU * 134_217_728.0);
pub(super) const P_MAX: i32 = to_i32(cfg::MAX_VARIANCE_MM2 * Q12);
pub(super) const P_MIN: i32 = to_i32(cfg::MIN_VARIANCE_MM2 * Q12);
pub(super) const P0_POS: i32 = to_i32(cfg::INITIAL_SIGMA_MM * cfg::INITIAL_SIGMA_MM * Q12);
pub(super) const P0_HEADING: i32 = to_i32(angle_var(cfg::INITIAL_SIGMA_DEG));
pub(super) const P0_SPEED: i32 = to_i32(scale_var(cfg::SPEED_SCALE_SIGMA));
pub(super) const P0_TURN: i32 = to_i32(scale_var(cfg::TURN_SCALE_SIGMA));
pub(super) const P0_BIAS: i32 = to_i32(angle_var(cfg::COMPASS_BIAS_SIGMA_DEG));
pub(super) const P0_PIVOT: i32 = to_i32(cfg::PIVOT_STATE_SIGMA_MM * cfg::PIVOT_STATE_SIGMA_MM * Q12);
pub(super) const PIVOT_WALK: u32 = per_us(cfg::PIVOT_WALK_MM2_PER_S * Q12);
pub(super) const PIVOT_SAMPLE_VAR: i32 = to_i32(cfg::PIVOT_SAMPLE_SIGMA_MM * cfg::PIVOT_SAMPLE_SIGMA_MM * Q12);
pub(super) const PIVOT_SETTLE_US: u32 = cfg::PIVOT_SETTLE_MS * 1000;
/// The learned pivot's bounds, Q16 mm.
pub(super) const PIVOT_MIN_Q16: i32 = to_i32(cfg::PIVOT_MIN_MM * 65536.0);
pub(super) const PIVOT_MAX_Q16: i32 = to_i32(cfg::PIVOT_MAX_MM * 65536.0);
/// The lidar spot's learned share (`spot`): its start and variance, Q30;
/// its random walk per sample, Q30; a reading's least sample variance in
/// 1/64 mm^2.
pub(super) const SPOT_SHARE_START: i32 = to_i32(cfg::SPOT_SHARE_START * 1_073_741_824.0);
pub(super) const SPOT_START_VAR: i32 = to_i32(cfg::SPOT_SHARE_SIGMA * cfg::SPOT_SHARE_SIGMA * 1_073_741_824.0);
pub(super) const SPOT_WALK: i32 = to_i32(cfg::SPOT_WALK_PER_SAMPLE * cfg::SPOT_WALK_PER_SAMPLE * 1_073_741_824.0);
pub(super) const SPOT_SAMPLE_VAR: i32 = to_i32(cfg::SPOT_SAMPLE_SIGMA_MM * cfg::SPOT_SAMPLE_SIGMA_MM * 64.0);
/// The spreads that teach, 1/8 mm.
pub(super) const SPOT_MIN_SPREAD_Q3: i32 = to_i32(cfg::SPOT_MIN_SPREAD_MM * 8.0);
pub(super) const SPOT_MAX_SPREAD_Q3: i32 = to_i32(cfg::SPOT_MAX_SPREAD_MM * 8.0);
/// A lidar's local re-search: the new hypothesis's position variance.
pub(super) const P_RESEARCH: i32 = to_i32(cfg::RESEARCH_SIGMA_MM * cfg::RESEARCH_SIGMA_MM * Q12);
/// The scales' bounds and 1, Q29.
pub(super) const SCALE_ONE: i32 = 1 << 29;
pub(super) const SCALE_MIN: i32 = to_i32(cfg::SCALE_MIN * 536_870_912.0);
pub(super) const SCALE_MAX: i32 = to_i32(cfg::SCALE_MAX * 536_870_912.0);
/// The bias's bound, angle LSB.
pub(super) const BIAS_MAX_LSB: i32 = to_i32(cfg::COMPASS_BIAS_MAX_DEG / 360.0 * 4_294_967_296.0);
/// Angle LSB per (L rad) mm, 2^32 / (2 pi L), times 2^9: `mul_hi(K Q21, .)`
/// then times `nu` (Q16) and `>> 14` gives angle LSB (see `correct`).
pub(super) const LSB_PER_TILDE_MM_Q9: i32 = to_i32(4_294_967_296.0 / (TAU * L) * 512.0);
/// (L rad) mm in Q16 per angle LSB, times 2^32 (for `mul_hi`): 2 pi L 2^16 / 2^32 * 2^32.
pub(super) const TILDE_Q16_PER_LSB: i32 = to_i32(TAU * L * 65536.0);
/// Radians in Q28 per angle LSB, times 2^32: `mul_hi(angle, .)` is Q28.
pub(super) const RAD_Q28_PER_LSB: i32 = to_i32(TAU * 268_435_456.0);
/// The tracker's costs in Q8 (sums of normalised squared innovations).
pub(super) const OUTLIER_COST_Q8: i32 = to_i32(cfg::OUTLIER_COST * 256.0);
pub(super) const DOMINATE_Q8: i32 = to_i32(cfg::DOMINATE_COST * 256.0);
pub(super) const PRUNE_Q8: i32 = to_i32(cfg::PRUNE_COST * 256.0);
pub(super) const SPAWN_Q8: i32 = to_i32(cfg::SPAWN_COST * 256.0);
/// A position variance at which an unknown start counts as located, Q12 mm^2.
pub(super) const LOCATED_VAR: i32 = to_i32(cfg::LOCATED_SIGMA_MM * cfg::LOCATED_SIGMA_MM * Q12);
/// Travel (Q16 mm) a reading needs since its sensor's last counted one.
pub(super) const EVIDENCE_Q16: i32 = to_i32(cfg::EVIDENCE_TRAVEL_MM * 65536.0);
/// The evidence period, microseconds.
pub(super) const EVIDENCE_PERIOD_US: u32 = to_u32(cfg::EVIDENCE_PERIOD_S * 1e6);
/// Merging: mm Q16 and angle LSB.
pub(super) const MERGE_Q16: i32 = to_i32(cfg::MERGE_MM * 65536.0);
pub(super) const MERGE_LSB: i32 = to_i32(cfg::MERGE_DEG / 360.0 * 4_294_967_296.0);
/// The reported pose's catch-up (see `cfg::CATCH_UP_*`): Q16 per Q16 mm
/// moved, Q16 mm per microsecond times 2^8, and the caps in Q16 mm.
pub(super) const CATCH_UP_PER_MM_Q16: i32 = to_i32(cfg::CATCH_UP_PER_MM * 65536.0);
pub(super) const CATCH_UP_PER_US: u32 = to_u32(cfg::CATCH_UP_MM_PER_S * 65536.0 / 1e6 * 256.0);
pub(super) const CATCH_UP_MAX_Q16: i32 = to_i32(cfg::CATCH_UP_MAX_MM * 65536.0);
pub(super) const CATCH_UP_STANDING_Q16: i32 = to_i32(cfg::CATCH_UP_STANDING_MM * 65536.0);
pub(super) const AMBIGUOUS_GAP_Q16: i32 = to_i32(cfg::AMBIGUOUS_GAP_MM * 65536.0);

const _: () = {
    // Every measurement's noise is at most P_MAX (2^28): a correction's
    // S = H P H^T / 2^k + R / 2^k < 2^30 + 2^28 fits i32 for any k
    // (`update::innovation`). With the rescale the compass may be as bad as
    // 57 degrees one sigma (was 3.6): 20 degrees is asserted to fit.
    assert!(R_LIDAR > 0 && R_INCIDENCE > 0 && R_COMPASS > 0);
    assert!(R_LIDAR <= P_MAX && R_INCIDENCE <= P_MAX && R_COMPASS <= P_MAX);
    assert!(angle_var(20.0) <= P_MAX as f64);
    assert!(GATE_SQ_Q8 > 0 && GATE_SQ_Q8 < (1 << 12));
    // a lidar's R >= R_LIDAR cos^2 >= R_LIDAR MIN_NORMAL^2, and >> 8 (the
    // largest scaling, entries saturated at 2^31) still at least 1 LSB
    assert!((R_LIDAR as i64) * (MIN_NORMAL as i64) / (1 << 30) * (MIN_NORMAL as i64) / (1 << 30) >= (1 << 8));
    assert!(LSB_PER_TILDE_MM_Q9 > (1 << 30));
    // D / L < 1/4 (D < 64 mm): a turn's Jacobian entries stay below 1/2
    assert!(D_OVER_L_Q31 >= 0 && D_OVER_L_Q31 < (1 << 29));
    // the secondaries' shares fit their formats: a step drives at most
    // 65.5 mm (the speed's share below 1/2 in Q30) and turns at most 1.3
    // rad (the turn's below 4 in Q27; times a variance below 2^28, << 5
    // stays below 2^31)
    assert!(SPEED_SHARE_Q30 > 0 && (SPEED_SHARE_Q30 as f64) * 65.6 / 256.0 < (1u32 << 29) as f64);
    assert!(TURN_SHARE_Q27 > 0 && (TURN_SHARE_Q27 as f64) * 1.4 / TAU < (1u32 << 29) as f64);
    assert!(MIN_NORMAL > (1 << 26) && MIN_NORMAL <= (1 << 30));
    assert!(P_MIN > 0 && P_MIN < P_MAX && P_MAX <= (1 << 28));
    assert!(P0_POS <= P_MAX && P0_HEADING <= P_MAX && P0_SPEED <= P_MAX && P0_TURN <= P_MAX && P0_BIAS <= P_MAX);
    assert!(P_RESEARCH > P_MIN && P_RESEARCH <= P_MAX);
    assert!(P0_PIVOT > 0 && P0_PIVOT <= P_MAX && (PIVOT_WALK as u64) * 65_535 < (1 << 32));
    assert!(PIVOT_SAMPLE_VAR > 0 && PIVOT_SAMPLE_VAR <= P_MAX);
    // the share within [0, 1] and its variance at most 1 (Q30)
    assert!(SPOT_SHARE_START >= 0 && SPOT_SHARE_START <= (1 << 30));
    assert!(SPOT_START_VAR > 0 && SPOT_START_VAR <= (1 << 30) && SPOT_WALK >= 0 && SPOT_WALK < SPOT_START_VAR);
    // a reading's g below 2^11 and nu within 2 g: nu g, g^2 and nu^2
    // below 2^24, a batch's sums below 2^31
    assert!(SPOT_SAMPLE_VAR > 0 && SPOT_MIN_SPREAD_Q3 > 0 && SPOT_MAX_SPREAD_Q3 < (1 << 11));
    // the turn's lever D + pivot within (0, 256) mm: (D + pivot) / L below
    // 1 in Q31 (`pivot::lever_over_l`), the pivot Q16 << 7 being Q31 / L
    // for L = 256 mm; a step's Jacobian entries (D + p)/L times the sine's
    // change (below 0.2 rad a step) stay far below the shear's 1/2, G's
    // position entries below 1 (Q30)
    assert!(L == 256.0);
    assert!(PIVOT_MIN_Q16 < 0 && PIVOT_MAX_Q16 > 0);
    assert!(D_OVER_L_Q31 as i64 + ((PIVOT_MIN_Q16 as i64) << 7) > 0);
    assert!(D_OVER_L_Q31 as i64 + ((PIVOT_MAX_Q16 as i64) << 7) < (1 << 31) - (1 << 27));
    // a step's turn is below 2^30 LSB (TurnRate::MAX over Dt::MAX, 1.3 rad):
    // mul_hi by a factor below 2^31 gives below 2^29. The pivot's noise is
    // its own term: 45 mm one sigma (issue 29: the pivot 60 +- 20 mm behind
    // the axle) fits, where the old format stopped at 18 mm.
    assert!(K_DIST > 0 && K_DRIFT > 0 && K_TURN > 0 && K_PIVOT > 0 && K_BIAS_MM > 0);
    assert!(pivot_k(45.0) < 2_147_483_647.0);
    assert!(K_DIST < (1 << 24) && K_DRIFT < (1 << 24) && K_BIAS_MM < (1 << 28));
    // floor * dt must fit u32 for dt <= 65535 us
    assert!((FLOOR_POS as u64) * 65_535 < (1 << 32) && (FLOOR_HEADING as u64) * 65_535 < (1 << 32));
    assert!((SCALE_WALK as u64) * 65_535 < (1 << 32) && (BIAS_WALK as u64) * 65_535 < (1 << 32));
    assert!((CATCH_UP_PER_US as u64) * 65_535 < (1 << 32));
    assert!(SCALE_MIN > 0 && SCALE_MIN < SCALE_ONE && SCALE_MAX > SCALE_ONE);
    assert!(OUTLIER_COST_Q8 > GATE_SQ_Q8 && PRUNE_Q8 > DOMINATE_Q8 && PRUNE_Q8 < (1 << 20));
    assert!(CATCH_UP_STANDING_Q16 <= CATCH_UP_MAX_Q16 && CATCH_UP_PER_MM_Q16 < (1 << 16));
};
