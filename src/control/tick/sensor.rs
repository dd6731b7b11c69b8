//! One sensor as the loop keeps it: its driver, its health (polled only
//! while up, faults counted, taken down and re-initialised after a
//! back-off), its newest sample and the reading waiting for the estimator.

use super::clock::{ms_to_us, reached, Stamp};
use crate::config;
use crate::control::protocol::FaultCounters;
use crate::driver::{CompassSample, LidarSample, SensorError};
use crate::math::{Angle, Length};
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
    fn new() -> SensorHealth {
        SensorHealth { up: true, ..SensorHealth::default() }
    }

    /// When the sensor last delivered a sample (any: "too close" and "no
    /// target" too), loop clock us.
    pub fn last_sample_us(&self) -> Stamp {
        self.last_sample_us
    }

    /// The sensor delivered a sample at `now`.
    fn sampled(&mut self, now: Stamp) {
        self.last_sample_us = now;
        self.consecutive_bus_errors = 0;
    }

    /// Counts a fault; takes the sensor down unless it was a dropped sample
    /// or one of too few bus errors in a row. A NACK of its address
    /// (`Missing`) from a sensor that is up, i.e. while polling a chip that
    /// was working, counts like a bus error: on a noisy bus a corrupted
    /// address byte is NACKed too, and a chip that is really gone is found
    /// after `SENSOR_MAX_BUS_ERRORS` polls (30 ms) anyway. At a
    /// re-initialisation a NACK means what it says: the sensor stays down.
    fn fail(&mut self, e: SensorError, now: Stamp, faults: &mut FaultCounters) {
        let counter = match e {
            SensorError::Bus => &mut faults.bus,
            SensorError::Timeout => &mut faults.timeout,
            SensorError::Missing | SensorError::NotReady => &mut faults.missing,
            SensorError::BadSample => &mut faults.bad_sample,
        };
        *counter = counter.saturating_add(1);
        self.last_error = Some(e);
        let down = match e {
            SensorError::BadSample => false,
            SensorError::Bus | SensorError::Missing if self.up => {
                self.consecutive_bus_errors = self.consecutive_bus_errors.saturating_add(1);
                self.consecutive_bus_errors >= config::timing::SENSOR_MAX_BUS_ERRORS
            }
            _ => true,
        };
        if down || !self.up {
            self.up = false;
            self.retry_at_us = now.wrapping_add(ms_to_us(config::timing::SENSOR_RETRY_MS));
        }
    }

    /// A poll gave no sample: nothing new yet (a timeout once the sensor
    /// has been silent too long), or an error.
    fn missed(&mut self, e: nb::Error<SensorError>, now: Stamp, faults: &mut FaultCounters) {
        match e {
            nb::Error::WouldBlock => {
                if now.wrapping_sub(self.last_sample_us) >= ms_to_us(config::timing::SENSOR_SILENT_MS) {
                    self.fail(SensorError::Timeout, now, faults);
                }
            }
            nb::Error::Other(e) => self.fail(e, now, faults),
        }
    }
}

/// What a sensor's sample gives the estimator (or a localization view).
// tick bar: the impls are inlined: a sample behind a reference that is
// not is copied with a `memcpy` call (opt-level "z")
pub(super) trait Sample {
    type Reading: Copy;
    /// The reading to correct with (`None`: nothing to correct with, as a
    /// lidar's "no target").
    fn reading(&self) -> Option<Self::Reading>;
    /// Keeps the sample as the newest.
    fn keep(&self, newest: &mut Option<Self>)
    where
        Self: Sized;
}

// tick bar: the samples' accessors inlined into `SensorSlot::polled` (on
// the bar's tick), as it is (lx106/BENCHMARKS.md, "Control tick")
impl Sample for LidarSample {
    type Reading = Length;
    #[inline(always)]
    fn reading(&self) -> Option<Length> {
        match self.range {
            Range::Target(d) => Some(d),
            _ => None,
        }
    }
    #[inline(always)]
    fn keep(&self, newest: &mut Option<Self>) {
        *newest = Some(*self);
    }
}

impl Sample for CompassSample {
    type Reading = Angle;
    #[inline(always)]
    fn reading(&self) -> Option<Angle> {
        Some(self.heading)
    }
    #[inline(always)]
    fn keep(&self, newest: &mut Option<Self>) {
        // tick bar: member by member (at opt-level "z" a copy of the
        // sample, or of its 12-byte `MagField`, is a `memcpy` call)
        let kept = newest.insert(CompassSample { raw: self.raw, field: Default::default(), heading: self.heading });
        kept.field.x = self.field.x;
        kept.field.y = self.field.y;
        kept.field.z = self.field.z;
    }
}

/// A sensor's slot in the loop: the driver `D`, its health, its newest
/// sample `S` and the reading waiting for its estimator correction.
pub(super) struct SensorSlot<D, S: Sample> {
    pub driver: D,
    pub health: SensorHealth,
    /// The newest sample (for telemetry, the wall stop and tests).
    pub latest: Option<S>,
    /// The reading waiting for its estimator correction (see
    /// `config::timing::MAX_CORRECTIONS_PER_TICK`), or for the view while
    /// localizing.
    pub pending: Option<S::Reading>,
    /// A sample came since the last telemetry row.
    pub unreported: bool,
    /// A sample came since the last on-board log row.
    pub unlogged: bool,
}

pub(super) type LidarSlot<D> = SensorSlot<D, LidarSample>;
pub(super) type CompassSlot<D> = SensorSlot<D, CompassSample>;

impl<D, S: Sample> SensorSlot<D, S> {
    pub fn new(driver: D) -> Self {
        SensorSlot {
            driver,
            health: SensorHealth::new(),
            latest: None,
            pending: None,
            unreported: false,
            unlogged: false,
        }
    }

    /// True when the sensor is up, to be polled. A sensor that is down is
    /// re-initialised (`reinit`) when its back-off is over and no other
    /// sensor was re-initialised in this tick (`reinit_ran`: a bring-up
    /// blocks the loop, so one per tick keeps a tick's cost to one
    /// bring-up); it is polled from the next tick on.
    pub fn ready(
        &mut self,
        now: Stamp,
        reinit_ran: &mut bool,
        faults: &mut FaultCounters,
        reinit: impl FnOnce(&mut D) -> Result<(), SensorError>,
    ) -> bool {
        let h = &mut self.health;
        if h.up {
            return true;
        }
        if !reached(now, h.retry_at_us) || *reinit_ran {
            return false;
        }
        *reinit_ran = true;
        match reinit(&mut self.driver) {
            Ok(()) => {
                h.up = true;
                h.reinits = h.reinits.saturating_add(1);
                h.consecutive_bus_errors = 0;
                h.last_sample_us = now;
            }
            Err(e) => h.fail(e, now, faults),
        }
        false
    }

    /// What a poll gave: a sample is kept (newest, unreported, unlogged)
    /// and its reading waits for the estimator; a miss is counted.
    // tick bar: inlined, the sample is not copied (a `memcpy` call at
    // opt-level "z")
    #[inline(always)]
    pub fn polled(&mut self, polled: nb::Result<S, SensorError>, now: Stamp, faults: &mut FaultCounters) -> Option<&S> {
        match polled {
            Ok(s) => {
                self.health.sampled(now);
                self.unreported = true;
                self.unlogged = true;
                if let Some(r) = s.reading() {
                    self.pending = Some(r);
                }
                s.keep(&mut self.latest);
                self.latest.as_ref()
            }
            Err(e) => {
                self.health.missed(e, now, faults);
                None
            }
        }
    }

    /// The sensor is up and delivered within `config::timing::LIDAR_STALE_MS`.
    pub fn is_fresh(&self, now: Stamp) -> bool {
        let h = &self.health;
        h.up && now.wrapping_sub(h.last_sample_us) < ms_to_us(config::timing::LIDAR_STALE_MS)
    }
}

impl<D> LidarSlot<D> {
    /// The distance it read lately, if it is fresh (too close to measure
    /// is 0).
    pub fn distance(&self, now: Stamp) -> Option<Length> {
        if !self.is_fresh(now) {
            return None;
        }
        match self.latest {
            Some(LidarSample { range: Range::Target(d), .. }) => Some(d),
            Some(LidarSample { range: Range::TooClose, .. }) => Some(Length::ZERO),
            _ => None,
        }
    }
}
