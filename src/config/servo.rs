//! Servo pulses (FS90R continuous servos on 50 Hz PWM).

/// Pulse width for command 0, us: the ESP8266 Arduino core's
/// `Servo.write()` mapping of the lab's time (fact sheet).
pub const PULSE_AT_0_US: u32 = 544;
/// Pulse width for command 180, us (fact sheet).
pub const PULSE_AT_180_US: u32 = 2400;
/// Pulses are clamped to this window whatever the command and trim: the
/// FS90R's rated 700..2300 us (FS90R datasheet). Shortest pulse, us.
pub const SAFE_MIN_US: u32 = 700;
/// Longest pulse, us (FS90R datasheet).
pub const SAFE_MAX_US: u32 = 2300;
/// Frame period, us: 20 ms (the 50 Hz servo frames of the fact sheet's
/// Arduino mapping).
pub const FRAME_US: u32 = 20_000;
