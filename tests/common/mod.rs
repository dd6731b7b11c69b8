//! Helpers shared by the integration tests. Each test binary uses a subset.
#![allow(dead_code, unused_imports)]

pub mod estimator;
pub mod longrun;
pub mod reading_age;
pub mod rng;

/// A lab data file from tests/data/lab1/.
pub fn lab1(name: &str) -> String {
    let path = format!("{}/tests/data/lab1/{name}", env!("CARGO_MANIFEST_DIR"));
    std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{path}: {e}"))
}
pub mod i2c;
pub mod mpu9250;
pub mod reference;
pub mod vl53l0x_script;
pub mod wire;

/// The bias and scale numbers of a `CALIBRATION` line as the robot prints
/// it (`MagCalibration::from_f64([bx, by, bz], [sx, sy, sz])`).
pub fn parse_calibration_line(line: &str) -> ([f64; 3], [f64; 3]) {
    let inner = line.split("from_f64(").nth(1).unwrap_or_else(|| panic!("no from_f64( in {line}"));
    let nums: Vec<f64> = inner
        .split(|c: char| !(c.is_ascii_digit() || c == '.' || c == '-'))
        .filter(|s| s.contains('.'))
        .map(|s| s.parse().unwrap())
        .collect();
    assert_eq!(nums.len(), 6, "{line}");
    ([nums[0], nums[1], nums[2]], [nums[3], nums[4], nums[5]])
}

/// CRC-32 (ISO-HDLC, the settings record's) written out bitwise, independent
/// of the crate the firmware uses: to check a record, or write one another
/// firmware might have.
pub fn crc32(words: &[u32]) -> u32 {
    let mut crc = u32::MAX;
    for b in words.iter().flat_map(|w| w.to_le_bytes()) {
        crc ^= u32::from(b);
        for _ in 0..8 {
            crc = if crc & 1 != 0 { (crc >> 1) ^ 0xEDB8_8320 } else { crc >> 1 };
        }
    }
    !crc
}
