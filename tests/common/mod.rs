//! Helpers shared by the integration tests. Each test binary uses a subset.
#![allow(dead_code, unused_imports)]

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
