//! `cargo fw-emu`: the firmware image on the emulated ESP8266 (emu/).

pub fn main(_args: &[String]) -> Result<(), String> {
    Err("fw-emu: not built yet".into())
}
