//! `cargo fw-image`: the firmware for the ESP8266, linked and checked.

pub fn main(_args: &[String]) -> Result<(), String> {
    Err("fw-image: not built yet".into())
}
