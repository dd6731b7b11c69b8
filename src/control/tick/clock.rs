//! The loop's clock: the tick period, moments as the low 32 bits of the
//! 64-bit microsecond clock, and the timers of timed commands.

use crate::config;
use crate::control::protocol::number::div_rem_1000;
use crate::math::div_u64;

/// Loop period, us.
pub const TICK_US: u32 = 1_000_000 / config::timing::LOOP_HZ;
/// A tick later than this after the previous one counts as an overrun, us.
pub(super) const OVERRUN_US: u32 = TICK_US + TICK_US / 2;
const _: () = assert!(config::timing::LOOP_HZ >= 1 && config::timing::LOOP_HZ <= 1_000);

/// A moment on the loop clock, us: its low 32 bits, which wrap every 71.6
/// minutes. Timestamps and deadlines are compared by their wrapping
/// difference ([`reached`], `now.wrapping_sub(since)`), which is right for
/// any two moments less than [`MAX_SPAN_US`] apart: every span the loop
/// keeps is far shorter (asserted below), and every stored moment is
/// renewed or done with well within it (a deadline is checked every tick).
/// On the lx106 a 64-bit compare or saturating add is several instructions
/// and a 64-bit field two loads and stores, for each of the loop's
/// deadlines; the 64-bit clock itself stays for `t_ms` and
/// [`super::Controller::clock_us`].
pub(super) type Stamp = u32;

/// Longest span between two [`Stamp`]s that compare correctly, us (35.8 min).
const MAX_SPAN_US: u32 = i32::MAX as u32;
/// [`MAX_SPAN_US`] in whole ms.
const MAX_SPAN_MS: u32 = MAX_SPAN_US / 1_000;

/// ms to us, at most [`MAX_SPAN_US`].
pub(super) const fn ms_to_us(ms: u32) -> u32 {
    if ms > MAX_SPAN_MS {
        MAX_SPAN_US
    } else {
        ms.wrapping_mul(1_000) // <= MAX_SPAN_US
    }
}

/// `now` is at or past `deadline` (the two less than [`MAX_SPAN_US`] apart).
pub(super) fn reached(now: Stamp, deadline: Stamp) -> bool {
    now.wrapping_sub(deadline) <= MAX_SPAN_US
}

// Every span the loop keeps, ms, well under MAX_SPAN_MS: a timed command, a
// calibration sweep of any u16 sample count, the deadman, the sensor
// timings; a telemetry period is at most 1 s.
const _: () = {
    use config::{compass, serial, timing};
    assert!(serial::MAX_DURATION_MS <= MAX_SPAN_MS);
    assert!((u16::MAX as u64) * (compass::CALIBRATION_MS_PER_SAMPLE as u64) <= MAX_SPAN_MS as u64);
    assert!(timing::DEADMAN_MS <= MAX_SPAN_MS);
    assert!(timing::SENSOR_RETRY_MS <= MAX_SPAN_MS && timing::SENSOR_SILENT_MS <= MAX_SPAN_MS);
};

/// The loop's own clock, kept from the free-running, wrapping 32-bit
/// microsecond counter the tick is called with.
#[derive(Clone, Copy, PartialEq, Eq, Debug, Default)]
pub(super) struct LoopClock {
    /// us since the first tick.
    pub us: u64,
    /// The counter at the previous tick (`None` before the first).
    last_now_us: Option<u32>,
    /// Ticks so far.
    pub ticks: u64,
}

impl LoopClock {
    /// A tick at counter value `now_us`: the time since the previous tick,
    /// us (0 at the first).
    pub fn tick(&mut self, now_us: u32) -> u32 {
        let dt_us = match self.last_now_us {
            None => 0,
            Some(last) => now_us.wrapping_sub(last),
        };
        self.last_now_us = Some(now_us);
        self.us = self.us.saturating_add(u64::from(dt_us));
        self.ticks = self.ticks.saturating_add(1);
        dt_us
    }

    /// Now, as a [`Stamp`] (the low 32 bits).
    pub fn now(&self) -> Stamp {
        self.us as Stamp
    }
}

/// How long a mode runs: for `duration_us` from the first tick that drives
/// it (so a command runs for its whole duration whenever it arrives between
/// ticks), or, without a duration, until the deadman. A duration is at most
/// `MAX_SPAN_US`, 35.8 min (a longer one, only possible through [`super::Controller::handle`]
/// with a hand-made command, runs for that long).
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub struct Timer {
    duration_us: Option<u32>,
    pub(super) started_us: Option<Stamp>,
}

impl Timer {
    pub(super) fn new(duration_ms: Option<u32>) -> Timer {
        Timer { duration_us: duration_ms.map(ms_to_us), started_us: None }
    }
    /// Time left at `now`, us (`None` for an untimed mode).
    pub(super) fn remaining_us(&self, now: Stamp) -> Option<u32> {
        let d = self.duration_us?;
        Some(match self.started_us {
            None => d,
            Some(s) => d.saturating_sub(now.wrapping_sub(s)),
        })
    }
}

/// `(us / 1000) as u32` (mod 2^32) without a 64-bit division (a ~430
/// instruction call on the lx106): with `us = hi 2^32 + lo`, `lo = 1000 q +
/// r` and `2^32 = 1000 * 4_294_967 + 296`, `us / 1000 = 4_294_967 hi + q +
/// (296 hi + r) / 1000`.
pub(super) fn whole_ms(us: u64) -> u32 {
    const HI_MAX: u32 = (u32::MAX - 999) / 296; // const-evaluated: 296 hi + r fits
    let hi = (us >> 32) as u32; // < 2^32
    let (q, r) = div_rem_1000(us as u32); // the low 32 bits
    if hi == 0 {
        return q; // the first 71 minutes
    }
    if hi > HI_MAX {
        return div_u64(us, 1_000).map_or(0, |q| q as u32); // after 1,900 years
    }
    let (q2, _) = div_rem_1000(hi.wrapping_mul(296).wrapping_add(r)); // no wrap: hi <= HI_MAX
    hi.wrapping_mul(4_294_967).wrapping_add(q).wrapping_add(q2) // mod 2^32, as the cast
}

#[cfg(test)]
#[allow(clippy::restriction)] // test code: a panic fails the test
mod tests {
    use super::whole_ms;

    #[test]
    fn whole_ms_is_the_truncated_quotient() {
        let check = |us: u64| {
            assert_eq!(whole_ms(us), (us / 1000) as u32, "{us}");
        };
        let big = (u64::from(u32::MAX) + 1) * 1000; // the first us whose quotient does not fit u32
        for us in [0, 1, 999, 1000, u64::from(u32::MAX), 1 << 32, big - 1, big, u64::MAX, u64::MAX - 1] {
            check(us);
        }
        // around HI_MAX = (2^32 - 1000) / 296 = 14_510_021 and both ends of lo
        for hi in [1u64, 2, 295, 296, 1000, 14_510_020, 14_510_021, 14_510_022, u64::from(u32::MAX)] {
            for lo in [0u64, 1, 703, 704, 999, 1000, 123_456_789, u64::from(u32::MAX) - 1, u64::from(u32::MAX)] {
                check(hi << 32 | lo);
            }
        }
        let mut x: u64 = 0x9E37_79B9_7F4A_7C15;
        for _ in 0..200_000 {
            // xorshift64, shifted to cover every magnitude
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            check(x >> (x % 64));
        }
    }
}
