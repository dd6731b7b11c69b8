//! The magnetometer calibration sweep: a synthetic turn through a field
//! distorted by the report's hard and soft iron gives the report's numbers
//! back for the two horizontal axes and keeps z's from the config; a sweep
//! short of sectors keeps collecting up to its cap; incomplete sweeps are
//! rejected; the config line round-trips.

use crate::common;
use paperbot::config;
use paperbot::model::compass::{CalStatus, CalibrationError, ConfigLine, MagCalibrator};
use paperbot::model::compass::{MagCalibration, MagCounts};

/// Half-ranges (counts) that the report's scales imply for a 150-count
/// field: scale_i = mean(h) / h_i, so h_i = 150 / scale_i.
fn half_ranges() -> [f64; 3] {
    let s = [0.679012, 0.833333, 3.055556];
    [150.0 / s[0], 150.0 / s[1], 150.0 / s[2]]
}

/// Raw counts (ASA 128, so raw = adjusted) at turn angle `t` (radians).
fn sample(t: f64) -> MagCounts {
    let h = half_ranges();
    let b = [79.0, 35.0, 2.0];
    MagCounts {
        x: (b[0] + h[0] * t.cos()).round() as i16,
        y: (b[1] + h[1] * t.sin()).round() as i16,
        // the car rocks on its skid as it turns
        z: (b[2] + h[2] * (t + 0.3).sin()).round() as i16,
    }
}

fn sweep(turns: f64, n: u16) -> MagCalibrator {
    let mut cal = MagCalibrator::with_config([128; 3]);
    for k in 0..n {
        let t = turns * std::f64::consts::TAU * f64::from(k) / f64::from(n);
        let status = cal.feed(sample(t));
        let done = (k + 1 >= config::compass::CALIBRATION_SAMPLES
            && cal.sectors() >= config::compass::CALIBRATION_MIN_SECTORS)
            || k + 1 >= cal.max_samples();
        assert_eq!(status, if done { CalStatus::Done } else { CalStatus::Collecting(k + 1) }, "sample {k}");
    }
    cal
}

#[test]
fn the_first_turn_only_builds_the_box() {
    // Sectors are seen from the running centre of the min/max box, which
    // only settles once the turn has passed every extreme: over the first
    // turn the vector sweeps 90..360 degrees (9 sectors), so a sweep must
    // be longer than one turn.
    assert_eq!(sweep(1.0, config::compass::CALIBRATION_SAMPLES).sectors(), 9);
    assert_eq!(sweep(1.25, config::compass::CALIBRATION_SAMPLES).sectors(), 12);
}

#[test]
fn a_sweep_recovers_the_reports_calibration() {
    let n = config::compass::CALIBRATION_SAMPLES;
    let cal = sweep(2.0, n);
    assert_eq!(cal.sectors(), 12);
    let got = cal.result().unwrap();
    assert_eq!(got.bias, [79, 35, 2]);
    let report = config::compass::CALIBRATION;
    assert_eq!(got.scale_q16[2], report.scale_q16[2], "z is kept");
    for i in 0..2 {
        let rel = f64::from(got.scale_q16[i] - report.scale_q16[i]) / f64::from(report.scale_q16[i]);
        // Ranges are whole counts: within 0.5 % of the report's scales.
        assert!(rel.abs() < 0.005, "axis {i}: {} vs {}", got.scale_q16[i], report.scale_q16[i]);
    }
}

#[test]
fn asa_is_applied_before_the_sweep() {
    // A chip with ASA 0 on x reads half the field: the bias comes out in
    // adjusted counts, like the config's.
    let mut cal = MagCalibrator::new([0, 128, 128], config::compass::AXES, 400, 11, 10);
    for k in 0..400 {
        let t = 2.0 * std::f64::consts::TAU * f64::from(k) / 400.0;
        let s = sample(t);
        cal.feed(MagCounts { x: s.x.wrapping_mul(2), ..s });
    }
    assert_eq!(cal.result().unwrap().bias[0], 79);
}

#[test]
fn half_a_turn_is_rejected() {
    let cal = sweep(0.5, config::compass::CALIBRATION_SAMPLES);
    assert!(cal.sectors() <= 7, "{}", cal.sectors());
    assert!(matches!(cal.result(), Err(CalibrationError::SweepIncomplete { need: 11, .. })));
}

#[test]
fn standing_still_with_noise_visits_no_sector() {
    let mut cal = MagCalibrator::with_config([128; 3]);
    let mut seed = 1u32;
    for _ in 0..config::compass::CALIBRATION_SAMPLES {
        seed = seed.wrapping_mul(1_103_515_245).wrapping_add(12345);
        let n = |s: u32| ((s >> 16) % 7) as i16 - 3;
        cal.feed(MagCounts { x: 200 + n(seed), y: -30 + n(seed >> 3), z: 5 + n(seed >> 6) });
    }
    assert_eq!(cal.sectors(), 0);
    assert_eq!(cal.result(), Err(CalibrationError::SweepIncomplete { sectors: 0, need: 11 }));
}

#[test]
fn too_few_samples_and_flat_axes_are_rejected() {
    let mut cal = MagCalibrator::with_config([128; 3]);
    cal.feed(sample(0.0));
    assert_eq!(cal.result(), Err(CalibrationError::NotEnoughSamples { have: 1, need: 1000 }));
    // x never changes: no scale can be computed for it.
    let mut flat = MagCalibrator::new([128; 3], config::compass::AXES, 360, 0, 10);
    for k in 0..360 {
        let s = sample(2.0 * std::f64::consts::TAU * f64::from(k) / 360.0);
        flat.feed(MagCounts { x: 7, ..s });
    }
    assert_eq!(flat.result(), Err(CalibrationError::Degenerate { axis: 0 }));
}

/// On a flat floor a turn leaves z where it is: the sweep measures x and y
/// and keeps z's bias and scale from the config.
#[test]
fn a_flat_turn_keeps_z_from_the_config() {
    let mut flat = MagCalibrator::new([128; 3], config::compass::AXES, 360, 11, 10);
    for k in 0..360 {
        let s = sample(2.0 * std::f64::consts::TAU * f64::from(k) / 360.0);
        flat.feed(MagCounts { z: 7, ..s });
    }
    assert_eq!(paperbot::model::compass::calibration::VERTICAL, 2);
    let got = flat.result().unwrap();
    let cfg = config::compass::CALIBRATION;
    assert_eq!((got.bias[2], got.scale_q16[2]), (cfg.bias[2], cfg.scale_q16[2]));
    assert_eq!(&got.bias[..2], &[79, 35]);
    // the report's proportion holds: 1/s_x + 1/s_y + 1/s_z = 3
    let inv: f64 = got.scale_q16.iter().map(|&q| 65536.0 / f64::from(q)).sum();
    assert!((inv - 3.0).abs() < 0.005, "{inv}");
}

/// A sweep with its samples but short of sectors keeps collecting up to
/// its cap: one turn's worth of samples ends once the second turn has
/// covered the circle; a robot that never turns ends at the cap.
#[test]
fn a_sweep_short_of_sectors_collects_up_to_its_cap() {
    let per_turn = 250u16;
    let mut cal = MagCalibrator::new([128; 3], config::compass::AXES, per_turn, 11, 10);
    assert_eq!(cal.max_samples(), per_turn + config::compass::CALIBRATION_EXTRA_SAMPLES);
    let mut k = 0u16;
    while cal.feed(sample(std::f64::consts::TAU * f64::from(k) / f64::from(per_turn))) != CalStatus::Done {
        k += 1;
    }
    assert!(k > per_turn && k < 2 * per_turn, "done after {k} samples");
    assert!(cal.sectors() >= 11);
    assert_eq!(&cal.result().unwrap().bias[..2], &[79, 35]);

    let mut still = MagCalibrator::new([128; 3], config::compass::AXES, per_turn, 11, 10);
    let mut n = 0u16;
    while still.feed(sample(0.0)) != CalStatus::Done {
        n += 1;
    }
    assert_eq!(n + 1, still.max_samples());
    assert_eq!(still.result(), Err(CalibrationError::SweepIncomplete { sectors: 0, need: 11 }));
}

#[test]
fn samples_after_the_sweep_are_ignored() {
    let mut cal = sweep(2.0, config::compass::CALIBRATION_SAMPLES);
    let before = cal.result().unwrap();
    assert_eq!(cal.feed(MagCounts { x: 30000, y: 30000, z: 30000 }), CalStatus::Done);
    assert_eq!(cal.result().unwrap(), before);
    assert_eq!(cal.samples(), config::compass::CALIBRATION_SAMPLES);
}

#[test]
fn the_config_line_reproduces_the_report_constant_and_round_trips() {
    // The report's scales as the Q16 values the robot uses (0.679012 is
    // 44499.3 / 65536, stored as 44499 = 0.679016...).
    let line = ConfigLine(&config::compass::CALIBRATION).to_string();
    assert_eq!(
        line,
        "pub const CALIBRATION: MagCalibration = MagCalibration::from_f64([79.0, 35.0, 2.0], [0.679016, 0.833328, 3.055557]);"
    );
    // Any calibration survives print -> from_f64.
    for cal in [
        config::compass::CALIBRATION,
        sweep(2.0, 1000).result().unwrap(),
        MagCalibration { bias: [-5, 0, 123], scale_q16: [1, 65536, 9_999_999] },
    ] {
        let line = ConfigLine(&cal).to_string();
        let (bias, scale) = common::parse_calibration_line(&line);
        let back = MagCalibration::from_f64(bias, scale);
        assert_eq!(back, cal, "{line}");
    }
}

/// The bias is `(max + min) / 2` rounded half away from zero, for every
/// sign and parity of the sum (the extremes come from two samples; ASA 128
/// leaves the counts as they are).
#[test]
fn biases_round_half_away_from_zero() {
    // (min, max) per case, and the bias the report's rule gives
    let cases: [((i16, i16), i32); 8] = [
        ((-3, 6), 2),          // 1.5 -> 2
        ((-6, 3), -2),         // -1.5 -> -2
        ((-4, 6), 1),          // 1
        ((-6, 4), -1),         // -1
        ((-5, 6), 1),          // 0.5 -> 1
        ((-6, 5), -1),         // -0.5 -> -1
        ((-32768, 32767), -1), // -0.5 -> -1, the widest the chip gives
        ((100, 301), 201),     // 200.5 -> 201
    ];
    for ((lo, hi), want) in cases {
        let exact = (f64::from(lo) + f64::from(hi)) / 2.0;
        assert_eq!(exact.abs().round().copysign(exact) as i32, want, "the table: {lo}..{hi}");
        let mut cal = MagCalibrator::new([128; 3], config::compass::AXES, 2, 0, i32::MAX);
        cal.feed(MagCounts { x: lo, y: lo, z: lo });
        assert_eq!(cal.feed(MagCounts { x: hi, y: hi, z: hi }), CalStatus::Done);
        let kept_z = config::compass::CALIBRATION.bias[2];
        assert_eq!(cal.result().map(|c| c.bias), Ok([want, want, kept_z]), "{lo}..{hi}");
    }
}
