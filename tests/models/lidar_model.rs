//! The lidar model: the report's lines in the data's direction, and the
//! readings that mean no target.
use paperbot::config::lidar::{FRONT, MAX_READING_MM, MIN_DISTANCE_MM, RIGHT};
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
        assert_eq!(m.range(m.min_reading_mm - 1), Range::TooClose);
        assert!(matches!(m.range(m.min_reading_mm), Range::Target(_)));
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

/// A distance closer than the mounting allows is "too close", not a
/// measurement: the right lidar pushed past the east wall read 43-55 raw
/// (-16..-28 mm by its line); every lab reading of a target at the
/// reference point (0 mm) is still a measurement.
#[test]
fn distances_below_what_the_mounting_allows_are_too_close() {
    for raw in 43..=55 {
        assert_eq!(RIGHT.range(raw), Range::TooClose, "right {raw}");
    }
    for (m, file) in [(&FRONT, "tests/data/lab1/lidar_front.csv"), (&RIGHT, "tests/data/lab1/lidar_right.csv")] {
        // the first reading kept means at least MIN_DISTANCE_MM, the one below less
        let d = |r: u16| f64::from(m.slope_q16) / 65536.0 * f64::from(r) + m.intercept.to_mm_f64();
        assert!(d(m.min_reading_mm) >= MIN_DISTANCE_MM && d(m.min_reading_mm - 1) < MIN_DISTANCE_MM);
        let text = std::fs::read_to_string(file).unwrap();
        let mut at_zero = 0;
        for line in text.lines().skip(1) {
            let mut f = line.split(',');
            let actual: f64 = f.next().unwrap().parse().unwrap();
            let reading: u16 = f.next().unwrap().parse().unwrap();
            if actual == 0.0 {
                at_zero += 1;
                assert!(matches!(m.range(reading), Range::Target(_)), "{file}: reading {reading} at 0 mm");
            }
        }
        println!("{file}: {at_zero} readings at 0 mm, all kept; too close below {} raw", m.min_reading_mm);
        assert!(at_zero > 100);
    }
}
