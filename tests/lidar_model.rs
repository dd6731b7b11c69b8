//! The lidar model: the report's lines in the data's direction, and the
//! readings that mean no target.
use paperbot::config::lidar::{FRONT, MAX_READING_MM, MIN_READING_MM, RIGHT};
use paperbot::math::Length;
use paperbot::model::lidar::Range;

#[test]
fn readings_map_through_the_fitted_lines() {
    // (model, reading, expected mm from the report's equation)
    let table = [
        (&FRONT, 57u16, 0.9849 * 57.0 - 56.2563),
        (&FRONT, 300, 0.9849 * 300.0 - 56.2563),
        (&FRONT, 1200, 0.9849 * 1200.0 - 56.2563),
        (&RIGHT, 72, 0.9867 * 72.0 - 70.4578),
        (&RIGHT, 500, 0.9867 * 500.0 - 70.4578),
    ];
    for (m, reading, want) in table {
        let d = m.range(reading).distance().expect("a target");
        // the slope is Q16: at most 2^-17 * 1200 mm = 0.01 mm off the printed line
        assert!((d.to_mm_f64() - want).abs() < 0.01, "{reading}: {} vs {want}", d.to_mm_f64());
    }
}

#[test]
fn out_of_range_readings_are_not_distances() {
    for m in [&FRONT, &RIGHT] {
        assert_eq!(m.range(8190), Range::NoTarget);
        assert_eq!(m.range(8191), Range::NoTarget);
        assert_eq!(m.range(u16::MAX), Range::NoTarget);
        assert_eq!(m.range(MAX_READING_MM + 1), Range::NoTarget);
        assert_eq!(m.range(MIN_READING_MM - 1), Range::TooClose);
        assert_eq!(m.range(0), Range::TooClose);
        assert!(matches!(m.range(MAX_READING_MM), Range::Target(_)));
    }
}

#[test]
fn reading_for_inverts_the_model() {
    for m in [&FRONT, &RIGHT] {
        for mm in [0, 10, 100, 400, 700] {
            let r = m.reading_for(Length::from_mm(mm)).unwrap();
            let back = m.range(r).distance().unwrap().to_mm_f64();
            assert!((back - f64::from(mm)).abs() <= 0.6, "{mm} -> {r} -> {back}");
        }
    }
}
