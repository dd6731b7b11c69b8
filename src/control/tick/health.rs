//! Sensor health: polling a sensor only while it is up, counting its
//! faults, taking it down and re-initialising it after a back-off.

use super::clock::{ms_to_us, reached, Stamp};
use super::{Controller, Hardware};
use crate::config;
use crate::driver::{HeadingSensor, LidarSample, RangeSensor, SensorError};
use crate::model::Range;

/// One sensor's health.
#[derive(Clone, Copy, PartialEq, Eq, Debug, Default)]
pub struct SensorHealth {
    /// False while the sensor is failed and waiting to be re-initialised.
    pub up: bool,
    /// The last error seen (cleared by nothing: for `status`).
    pub last_error: Option<SensorError>,
    /// Successful re-initialisations since boot.
    pub reinits: u32,
    /// Bus errors in a row (a single glitch does not take a sensor down).
    consecutive_bus_errors: u8,
    /// When a failed sensor is tried again.
    retry_at_us: Stamp,
    /// When the sensor last delivered.
    last_sample_us: Stamp,
}

impl SensorHealth {
    pub(super) fn new() -> SensorHealth {
        SensorHealth { up: true, ..SensorHealth::default() }
    }

    /// When the sensor last delivered a sample (any: "too close" and "no
    /// target" too), loop clock us.
    pub fn last_sample_us(&self) -> Stamp {
        self.last_sample_us
    }
}

/// Which sensor (for the shared fault handling).
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub(super) enum Which {
    Front,
    Right,
    Compass,
}

impl<H: Hardware> Controller<H> {
    /// True when a sensor is up, to be polled. A sensor that is down is
    /// re-initialised when its back-off is over and no other sensor was
    /// re-initialised in this tick (a bring-up blocks the loop, so one per
    /// tick keeps a tick's cost to one bring-up); it is polled from the
    /// next tick on.
    pub(super) fn ready(&mut self, which: Which, now: Stamp) -> bool {
        let health = self.health(which);
        if health.up {
            return true;
        }
        if !reached(now, health.retry_at_us) || self.reinit_ran {
            return false;
        }
        self.reinit_ran = true;
        let result = match which {
            Which::Front => self.front.reinit(),
            Which::Right => self.right.reinit(),
            Which::Compass => self.compass.reinit(),
        };
        match result {
            Ok(()) => {
                let h = self.health_mut(which);
                h.up = true;
                h.reinits = h.reinits.saturating_add(1);
                h.consecutive_bus_errors = 0;
                h.last_sample_us = now;
            }
            Err(e) => self.fail(which, e, now),
        }
        false
    }

    /// Keeps what a lidar's poll gave (`which` is `Front` or `Right`).
    // tick bar: a call here costs ~100 instructions
    #[inline(always)]
    pub(super) fn lidar_polled(&mut self, which: Which, polled: nb::Result<LidarSample, SensorError>, now: Stamp) {
        let s = match polled {
            Ok(s) => s,
            Err(e) => return self.missed(which, e, now),
        };
        self.sampled(which, now);
        let (fresh, last, pending, log_bit) = if which == Which::Front {
            (&mut self.fresh_front, &mut self.last_front, &mut self.pending_front, super::untethered::LOG_FRONT)
        } else {
            (&mut self.fresh_right, &mut self.last_right, &mut self.pending_right, super::untethered::LOG_RIGHT)
        };
        self.log_fresh |= log_bit;
        *fresh = true;
        *last = Some(s);
        if let Range::Target(d) = s.range {
            *pending = Some(d);
        }
    }

    /// A sensor delivered a sample at `now`.
    pub(super) fn sampled(&mut self, which: Which, now: Stamp) {
        let h = self.health_mut(which);
        h.last_sample_us = now;
        h.consecutive_bus_errors = 0;
    }

    /// A poll gave no sample: nothing new yet (a timeout once the sensor
    /// has been silent too long), or an error.
    pub(super) fn missed(&mut self, which: Which, e: nb::Error<SensorError>, now: Stamp) {
        match e {
            nb::Error::WouldBlock => {
                let silent = now.wrapping_sub(self.health(which).last_sample_us);
                if silent >= ms_to_us(config::timing::SENSOR_SILENT_MS) {
                    self.fail(which, SensorError::Timeout, now);
                }
            }
            nb::Error::Other(e) => self.fail(which, e, now),
        }
    }

    /// Counts a fault; takes the sensor down unless it was a dropped sample
    /// or one of too few bus errors in a row. A NACK of its address
    /// (`Missing`) from a sensor that is up, i.e. while polling a chip that
    /// was working, counts like a bus error: on a noisy bus a corrupted
    /// address byte is NACKed too, and a chip that is really gone is found
    /// after `SENSOR_MAX_BUS_ERRORS` polls (30 ms) anyway. At a
    /// re-initialisation a NACK means what it says: the sensor stays down.
    pub(super) fn fail(&mut self, which: Which, e: SensorError, now: Stamp) {
        let f = &mut self.faults;
        let counter = match e {
            SensorError::Bus => &mut f.bus,
            SensorError::Timeout => &mut f.timeout,
            SensorError::Missing | SensorError::NotReady => &mut f.missing,
            SensorError::BadSample => &mut f.bad_sample,
        };
        *counter = counter.saturating_add(1);
        let h = self.health_mut(which);
        h.last_error = Some(e);
        let down = match e {
            SensorError::BadSample => false,
            SensorError::Bus | SensorError::Missing if h.up => {
                h.consecutive_bus_errors = h.consecutive_bus_errors.saturating_add(1);
                h.consecutive_bus_errors >= config::timing::SENSOR_MAX_BUS_ERRORS
            }
            _ => true,
        };
        if down || !h.up {
            h.up = false;
            h.retry_at_us = now.wrapping_add(ms_to_us(config::timing::SENSOR_RETRY_MS));
        }
    }

    /// The sensor is up and delivered within `config::timing::LIDAR_STALE_MS`.
    pub(super) fn is_fresh(&self, which: Which, now: Stamp) -> bool {
        let h = self.health(which);
        h.up && now.wrapping_sub(h.last_sample_us) < ms_to_us(config::timing::LIDAR_STALE_MS)
    }

    pub(super) fn health(&self, which: Which) -> &SensorHealth {
        match which {
            Which::Front => &self.health_front,
            Which::Right => &self.health_right,
            Which::Compass => &self.health_compass,
        }
    }
    pub(super) fn health_mut(&mut self, which: Which) -> &mut SensorHealth {
        match which {
            Which::Front => &mut self.health_front,
            Which::Right => &mut self.health_right,
            Which::Compass => &mut self.health_compass,
        }
    }
}
