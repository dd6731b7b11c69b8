//! The board's bit-banged I2C master on the simulator's wire
//! (`sim::wire`), cycle by cycle: the master's pins and its cycle counter
//! move the wire's clock by what each access costs on the lx106, so the
//! time the master's code takes shows up on the wire as on the chip; a
//! register-file chip to talk to; and the fast-mode timing check of a
//! recorded trace.

use std::cell::RefCell;
use std::rc::Rc;

use paperbot::board::bitbang_i2c::{BitBangI2c, CycleClock, I2cPins, Timing};
use paperbot::sim::bus::I2cTarget;
use paperbot::sim::wire::{Sample, Wire};

/// A chip with 256 byte registers and an auto-incrementing pointer (the
/// first written byte sets it), which records every write it is given.
pub struct RegisterChip {
    pub addr: u8,
    pub regs: [u8; 256],
    pub pointer: u8,
    /// Each transfer's written bytes (register byte first), in order.
    pub writes: Vec<Vec<u8>>,
}

impl RegisterChip {
    /// Registers all 0.
    pub fn new(addr: u8) -> Rc<RefCell<RegisterChip>> {
        Rc::new(RefCell::new(RegisterChip { addr, regs: [0; 256], pointer: 0, writes: Vec::new() }))
    }

    /// Register `i` holds `i * 7 ^ 0x5a`.
    pub fn patterned(addr: u8) -> Rc<RefCell<RegisterChip>> {
        let chip = RegisterChip::new(addr);
        for (i, r) in chip.borrow_mut().regs.iter_mut().enumerate() {
            *r = (i as u8).wrapping_mul(7) ^ 0x5a;
        }
        chip
    }

    /// Every byte written to it, in order.
    pub fn written(&self) -> Vec<u8> {
        self.writes.concat()
    }
}

impl I2cTarget for RegisterChip {
    fn acks(&self, addr: u8) -> bool {
        addr == self.addr
    }
    fn write(&mut self, _addr: u8, data: &[u8]) {
        self.writes.push(data.to_vec());
        if let Some((&reg, values)) = data.split_first() {
            self.pointer = reg;
            for &v in values {
                self.regs[usize::from(self.pointer)] = v;
                self.pointer = self.pointer.wrapping_add(1);
            }
        }
    }
    fn read(&mut self, _addr: u8, buf: &mut [u8]) {
        for b in buf {
            *b = self.regs[usize::from(self.pointer)];
            self.pointer = self.pointer.wrapping_add(1);
        }
    }
}

/// Simulated cost of each master action, in CPU cycles.
#[derive(Clone, Copy, Debug)]
pub struct Costs {
    /// One CCOUNT read plus the loop around it.
    pub clock_read: u64,
    pub pin_write: u64,
    pub pin_read: u64,
}

impl Costs {
    /// Pessimistic lx106 figures: CCOUNT poll loop 3 instructions; a GPIO
    /// store or load over the DPORT bus taken as 10 cycles.
    pub const LX106: Self = Self { clock_read: 3, pin_write: 10, pin_read: 10 };
}

/// A handle on the shared wire.
pub type SharedWire = Rc<RefCell<Wire>>;

/// The master's two open-drain pins on the wire (true: released).
pub struct Pins {
    pub wire: SharedWire,
    pub costs: Costs,
    scl: bool,
    sda: bool,
}

impl Pins {
    fn drive(&mut self, scl: bool, sda: bool) {
        (self.scl, self.sda) = (scl, sda);
        let mut w = self.wire.borrow_mut();
        w.advance(self.costs.pin_write);
        w.set_master(scl, sda);
    }

    fn read(&mut self) -> (bool, bool) {
        let mut w = self.wire.borrow_mut();
        w.advance(self.costs.pin_read);
        w.levels()
    }
}

impl I2cPins for Pins {
    fn scl_release(&mut self) {
        self.drive(true, self.sda);
    }
    fn scl_low(&mut self) {
        self.drive(false, self.sda);
    }
    fn scl_is_high(&mut self) -> bool {
        self.read().0
    }
    fn sda_release(&mut self) {
        self.drive(self.scl, true);
    }
    fn sda_low(&mut self) {
        self.drive(self.scl, false);
    }
    fn sda_is_high(&mut self) -> bool {
        self.read().1
    }
}

/// The simulated CPU's cycle counter: the wire's clock (wraps like CCOUNT).
pub struct Clock {
    pub wire: SharedWire,
    pub costs: Costs,
}

impl CycleClock for Clock {
    fn now(&mut self) -> u32 {
        let mut w = self.wire.borrow_mut();
        w.advance(self.costs.clock_read);
        w.now() as u32
    }
}

/// A wire with `chips` on it, recording from the start.
pub fn wire(chips: &[Rc<RefCell<RegisterChip>>]) -> SharedWire {
    let targets = chips.iter().map(|c| c.clone() as Rc<RefCell<dyn I2cTarget>>).collect();
    let mut w = Wire::new(targets);
    w.record();
    Rc::new(RefCell::new(w))
}

/// A master on `wire` with `timing`, at lx106 costs (not initialised).
pub fn master_on(wire: &SharedWire, timing: Timing) -> BitBangI2c<Pins, Clock> {
    let pins = Pins { wire: wire.clone(), costs: Costs::LX106, scl: true, sda: true };
    BitBangI2c::new(pins, Clock { wire: wire.clone(), costs: Costs::LX106 }, timing)
}

/// Minimum fast-mode times (UM10204 table 10) in cycles of `cpu_hz`.
#[derive(Clone, Copy, Debug)]
pub struct Limits {
    pub low: u64,
    pub high: u64,
    pub su_sta: u64,
    pub hd_sta: u64,
    pub su_sto: u64,
    pub buf: u64,
    /// Shortest SCL period (fall to fall), i.e. the highest clock rate.
    pub period: u64,
}

impl Limits {
    pub fn fast_mode(cpu_hz: u64) -> Self {
        let c = |ns: u64| (ns * cpu_hz).div_ceil(1_000_000_000);
        Self {
            low: c(1_300),
            high: c(600),
            su_sta: c(600),
            hd_sta: c(600),
            su_sto: c(600),
            buf: c(1_300),
            period: c(2_500),
        }
    }
}

/// Checks a trace against the limits; returns the violations found.
pub fn check_timing(trace: &[Sample], lim: &Limits) -> Vec<String> {
    let mut v = Vec::new();
    let mut last_scl_rise: Option<u64> = None;
    let mut last_scl_fall: Option<u64> = None;
    let mut last_start: Option<u64> = None;
    let mut last_stop: Option<u64> = None;
    for w in trace.windows(2) {
        let (a, b) = (w[0], w[1]);
        if a.scl != b.scl {
            if b.scl {
                if let Some(f) = last_scl_fall {
                    if b.t - f < lim.low {
                        v.push(format!("tLOW {} < {} at {}", b.t - f, lim.low, b.t));
                    }
                }
                last_scl_rise = Some(b.t);
            } else {
                if let Some(r) = last_scl_rise {
                    if b.t - r < lim.high {
                        v.push(format!("tHIGH {} < {} at {}", b.t - r, lim.high, b.t));
                    }
                }
                if let Some(s) = last_start {
                    if s >= last_scl_rise.unwrap_or(0) && b.t - s < lim.hd_sta {
                        v.push(format!("tHD;STA {} < {} at {}", b.t - s, lim.hd_sta, b.t));
                    }
                }
                if let Some(f) = last_scl_fall {
                    if b.t - f < lim.period {
                        v.push(format!("SCL period {} < {} at {}", b.t - f, lim.period, b.t));
                    }
                }
                last_scl_fall = Some(b.t);
            }
        } else if a.sda != b.sda && b.scl {
            // SDA changed while SCL high: a START or a STOP
            let since_rise = last_scl_rise.map_or(u64::MAX, |r| b.t - r);
            if b.sda {
                if since_rise < lim.su_sto {
                    v.push(format!("tSU;STO {} < {} at {}", since_rise, lim.su_sto, b.t));
                }
                last_stop = Some(b.t);
            } else {
                if let Some(p) = last_stop {
                    if b.t - p < lim.buf && last_scl_rise.is_none_or(|r| r <= p) {
                        v.push(format!("tBUF {} < {} at {}", b.t - p, lim.buf, b.t));
                    }
                }
                if last_scl_rise.is_some_and(|r| last_stop.is_none_or(|p| r > p)) && since_rise < lim.su_sta {
                    v.push(format!("tSU;STA {} < {} at {}", since_rise, lim.su_sta, b.t));
                }
                last_start = Some(b.t);
            }
        }
    }
    v
}
