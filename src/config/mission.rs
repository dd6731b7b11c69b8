//! Missions: commands stored on the robot and run without the cable
//! (`control::mission`).

/// Steps a mission holds at most. Each takes 12 bytes in the RAM copy
/// and in RTC memory (`board::esp8266::RtcMissionStore`, 512 bytes).
pub const MAX_STEPS: usize = 24;
/// Countdown after `mission start` before the first step, ms: time to
/// pull the cable and put the robot down.
pub const COUNTDOWN_MS: u32 = 10_000;
/// A running mission stops after this long whatever its steps, ms (its
/// own deadman: nobody is at the cable to stop it).
pub const TIME_LIMIT_MS: u32 = 300_000;
