//! The robot's three sensor chips on one simulated bus, ready for the
//! drivers: what the simulator and the tests build on.
//!
//! ```
//! use paperbot::driver::{HeadingSensor, RangeSensor};
//! use paperbot::sim::sensors::SimSensors;
//!
//! let sim = SimSensors::new();
//! let (mut front, mut right, mut compass) = sim.drivers();
//! assert!(paperbot::driver::lidar::bring_up(&mut front, &mut right).all_ok());
//! compass.reinit().unwrap();
//! sim.front.borrow_mut().set_distance_mm(300);
//! sim.clock.advance_ms(40); // one lidar period, four magnetometer periods
//! let d = front.poll().unwrap();
//! assert_eq!(d.raw_mm, 300);
//! assert!(compass.poll().is_ok());
//! ```

use super::bus::{SimBus, SimClock, SimDelay};
use super::mpu9250::{FakeMpu9250, Mpu9250Handle};
use super::vl53l0x::{FakeVl53l0x, Vl53l0xHandle, XshutPin};
use crate::driver::compass::Compass;
use crate::driver::lidar::Lidar;

/// A lidar driver on the simulated bus.
pub type SimLidar = Lidar<SimBus, XshutPin, SimDelay>;
/// The compass driver on the simulated bus.
pub type SimCompass = Compass<SimBus, SimDelay>;

/// The clock, the bus and the three fake chips (handles: set their truth,
/// inject faults, look inside).
#[derive(Clone)]
pub struct SimSensors {
    pub clock: SimClock,
    pub bus: SimBus,
    pub front: Vl53l0xHandle,
    pub right: Vl53l0xHandle,
    pub mpu: Mpu9250Handle,
}

impl Default for SimSensors {
    fn default() -> Self {
        Self::new()
    }
}

impl SimSensors {
    /// Three chips at power-up (both lidars awake at 0x29).
    pub fn new() -> Self {
        let clock = SimClock::new();
        let bus = SimBus::new();
        let front = FakeVl53l0x::shared(clock.clone());
        let right = FakeVl53l0x::shared(clock.clone());
        let mpu = FakeMpu9250::shared(clock.clone());
        bus.attach(front.clone());
        bus.attach(right.clone());
        bus.attach(mpu.clone());
        SimSensors { clock, bus, front, right, mpu }
    }

    pub fn front_xshut(&self) -> XshutPin {
        XshutPin(self.front.clone())
    }

    pub fn right_xshut(&self) -> XshutPin {
        XshutPin(self.right.clone())
    }

    pub fn delay(&self) -> SimDelay {
        self.clock.delay()
    }

    /// The drivers with the configured addresses and models, not yet
    /// brought up: front lidar, right lidar, compass.
    pub fn drivers(&self) -> (SimLidar, SimLidar, SimCompass) {
        (
            Lidar::front(self.bus.clone(), self.front_xshut(), self.delay()),
            Lidar::right(self.bus.clone(), self.right_xshut(), self.delay()),
            Compass::with_config(self.bus.clone(), self.delay()),
        )
    }
}
