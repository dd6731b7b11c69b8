//! What the loop shows: its clock, pose, mode, counters and drivers, and
//! the `status` answer.

use super::clock::whole_ms;
use super::{Controller, Hardware, Mode, SensorHealth};
use crate::control::protocol::number::div_rem_1000;
use crate::control::protocol::{FaultCounters, Status};
use crate::driver::{CompassSample, LidarSample};
use crate::model::estimator::Estimator;
use crate::model::{ActuatorModel, Drive, Pose};

impl<H: Hardware> Controller<H> {
    /// Loop clock in ms (wraps after 49 days: the truncation is intended).
    pub fn t_ms(&self) -> u32 {
        whole_ms(self.clock.us)
    }
    /// Loop clock, us since the first tick.
    pub fn clock_us(&self) -> u64 {
        self.clock.us
    }
    /// The pose the telemetry reports: the estimator's.
    pub fn pose(&self) -> Pose {
        self.estimator.pose()
    }
    /// The dead-reckoned pose (the state update alone, from the last `pose`
    /// or fix; host builds only).
    #[cfg(feature = "std")]
    pub fn dead_reckoned(&self) -> Pose {
        self.dead
    }
    pub fn estimator(&self) -> &Estimator {
        &self.estimator
    }
    pub fn mode(&self) -> Mode {
        self.mode
    }
    /// The localization's survey (its views so far while locating).
    pub fn survey(&self) -> &crate::control::survey::Survey {
        &self.localizing.survey
    }
    /// The servo commands and motion set at the last tick.
    pub fn applied(&self) -> Drive {
        self.applied
    }
    pub fn model(&self) -> &ActuatorModel {
        &self.model
    }
    pub fn faults(&self) -> FaultCounters {
        self.faults
    }
    pub fn telemetry_hz(&self) -> u16 {
        self.reports.telemetry.hz
    }
    pub fn ticks(&self) -> u64 {
        self.clock.ticks
    }
    pub fn front_health(&self) -> SensorHealth {
        self.front.health
    }
    pub fn right_health(&self) -> SensorHealth {
        self.right.health
    }
    pub fn compass_health(&self) -> SensorHealth {
        self.compass.health
    }
    pub fn last_front(&self) -> Option<LidarSample> {
        self.front.latest
    }
    pub fn last_right(&self) -> Option<LidarSample> {
        self.right.latest
    }
    pub fn last_compass(&self) -> Option<CompassSample> {
        self.compass.latest
    }
    /// The drivers, e.g. for a simulator that reads the servo commands or
    /// sets a fake chip's truth.
    pub fn front(&mut self) -> &mut H::Front {
        &mut self.front.driver
    }
    pub fn right(&mut self) -> &mut H::Right {
        &mut self.right.driver
    }
    pub fn compass(&mut self) -> &mut H::Compass {
        &mut self.compass.driver
    }
    pub fn servos(&mut self) -> &mut H::Servos {
        &mut self.servos
    }

    /// What `status` reports.
    pub fn status(&self) -> Status {
        let now = self.clock.now();
        let remaining_ms = self.mode.timer().and_then(|t| t.remaining_us(now)).map(|us| div_rem_1000(us).0);
        Status {
            t_ms: self.t_ms(),
            mode: self.mode.word(),
            motion: self.applied.motion,
            remaining_ms,
            pose: self.estimator.pose(),
            tracking: self.estimator.tracking(),
            left_cmd: self.applied.left,
            right_cmd: self.applied.right,
            left_trim: self.model.left_trim,
            right_trim: self.model.right_trim,
            rate_hz: self.reports.telemetry.hz,
            front_ok: self.front.health.up,
            right_ok: self.right.health.up,
            compass_ok: self.compass.health.up,
            faults: self.faults,
        }
    }
}
