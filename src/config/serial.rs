//! Serial port.

/// UART0 baud rate (8N1).
pub const BAUD: u32 = 115_200;

// The command protocol's limits (`control::protocol`). Each guards against
// typos and line noise. The speed and rate limits are not what the servos
// drive: that differs by direction and moves with the trims (no trim:
// fwd 0.124..0.150 m/s, back 0.108..0.154, cw 2.377..3.300 rad/s, ccw
// 2.353..3.169, from the fitted lines in `actuators`), so the control loop
// drives a request outside it at the nearest it can and answers with that.

/// Longest command line, bytes, without the terminator: the longest
/// command (`servo 180.00 180.00 60.000`) is 26 bytes; 64 leaves room for
/// spaces and long spellings.
pub const MAX_LINE: usize = 64;
/// Fastest `fwd`/`back` speed accepted, mm/s: twice the fastest the lab
/// measured (0.149 m/s, data `servo_runs.csv`).
pub const MAX_SPEED_MM_S: u32 = 300;
/// Fastest `cw`/`ccw` turn rate accepted, mrad/s: about twice the fastest
/// measured (3.20 rad/s, data `servo_runs.csv`).
pub const MAX_TURN_MRAD_S: u32 = 6_000;
/// Longest duration a motion command may ask for, ms (one minute: the
/// arena is crossed in about 6 s).
pub const MAX_DURATION_MS: u32 = 60_000;
/// Largest servo trim accepted, 1/100 command step (10 steps: an FS90R's
/// stop point drifts by a few steps).
pub const MAX_TRIM_CENTI: u32 = 1_000;
/// Largest |x| or |y| the `pose` command accepts, mm (the pose's
/// `Length` view holds +-32.7 m).
pub const MAX_POSE_MM: u32 = 30_000;
/// Fewest magnetometer samples a calibration sweep may ask for: one turn
/// at 3 rad/s takes 2.1 s, 210 samples at the AK8963's 100 Hz.
pub const MIN_CAL_SAMPLES: u16 = 250;
/// Most magnetometer samples a calibration sweep may ask for (100 s at 100 Hz).
pub const MAX_CAL_SAMPLES: u16 = 10_000;
/// Fastest telemetry rate, Hz: one row per loop tick. A typical row is
/// about 100 bytes, 10 kB/s at 100 Hz against the UART's 11.5 kB/s
/// (115200 baud, 10 bits a byte): rates near the maximum only fit short rows.
pub const MAX_TELEMETRY_HZ: u16 = super::timing::LOOP_HZ as u16;
