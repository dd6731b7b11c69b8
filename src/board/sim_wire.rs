//! A wire-level simulated I2C bus, to test the bit-banged master edge by edge.
//!
//! The master's two open-drain lines, any number of [`RegSlave`]s and a
//! cycle clock share one [`Bus`]: a line is high unless someone pulls it low.
//! Every master pin access and clock read costs simulated CPU cycles
//! ([`Costs`]), so the time the master's code takes shows up on the wire like
//! on the chip. Slaves see the edges (START, STOP, SCL rise/fall) and behave
//! like a register-file chip (first written byte = register pointer,
//! auto-increment): they ACK or NACK, stretch the clock after ACKs, and can be
//! left mid-read driving SDA low (the case bus recovery is for). Every level
//! change is traced with its time for timing checks ([`check_timing`]).

extern crate std;

use core::cell::RefCell;
use std::rc::Rc;
use std::vec::Vec;

use super::bitbang_i2c::{CycleClock, I2cPins};

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

/// Line levels after a change, at cycle `t`.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub struct Sample {
    pub t: u64,
    pub scl: bool,
    pub sda: bool,
}

/// Bus conditions seen on the wire.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum Condition {
    Start,
    Stop,
}

#[derive(Clone, Copy, PartialEq, Eq, Debug)]
enum St {
    Idle,
    Addr,
    AddrAck { read: bool },
    Rx,
    RxAck,
    Tx { byte: u8, bit: u8 },
    TxAck,
}

/// A register-file slave (like the VL53L0X / MPU9250 register interface).
#[derive(Clone, Debug)]
pub struct RegSlave {
    pub address: u8,
    pub regs: [u8; 256],
    pub pointer: u8,
    /// Do not acknowledge the address.
    pub nack_address: bool,
    /// Acknowledge only this many written bytes per transfer (pointer included).
    pub nack_data_after: Option<usize>,
    /// Hold SCL low this many cycles after every ACK clock.
    pub stretch: u64,
    /// Bytes written to it (pointer bytes included), in order.
    pub written: Vec<u8>,
    st: St,
    shift: u8,
    nbits: u8,
    first_data: bool,
    rx_in_transfer: usize,
    master_acked: bool,
    drive_sda_low: bool,
    hold_scl_until: u64,
}

impl RegSlave {
    pub fn new(address: u8) -> Self {
        Self {
            address,
            regs: [0; 256],
            pointer: 0,
            nack_address: false,
            nack_data_after: None,
            stretch: 0,
            written: Vec::new(),
            st: St::Idle,
            shift: 0,
            nbits: 0,
            first_data: false,
            rx_in_transfer: 0,
            master_acked: false,
            drive_sda_low: false,
            hold_scl_until: 0,
        }
    }

    /// Leaves the slave in the middle of sending `byte` (bit 7 on SDA), as
    /// if the master had been reset during a read.
    pub fn stuck_mid_read(&mut self, byte: u8) {
        self.st = St::Tx { byte, bit: 7 };
        self.drive_sda_low = byte & 0x80 == 0;
    }

    pub fn is_idle(&self) -> bool {
        self.st == St::Idle && !self.drive_sda_low
    }

    fn on_start(&mut self) {
        self.st = St::Addr;
        self.shift = 0;
        self.nbits = 0;
        self.drive_sda_low = false;
    }

    fn on_stop(&mut self) {
        self.st = St::Idle;
        self.drive_sda_low = false;
    }

    fn on_rise(&mut self, sda: bool) {
        match self.st {
            St::Addr | St::Rx => {
                self.shift = self.shift << 1 | u8::from(sda);
                self.nbits += 1;
            }
            St::TxAck => self.master_acked = !sda,
            _ => {}
        }
    }

    fn present(&mut self, byte: u8, bit: u8) {
        self.st = St::Tx { byte, bit };
        self.drive_sda_low = byte >> bit & 1 == 0;
    }

    fn next_tx_byte(&mut self) -> u8 {
        let b = self.regs[usize::from(self.pointer)];
        self.pointer = self.pointer.wrapping_add(1);
        b
    }

    fn on_fall(&mut self, now: u64) {
        match self.st {
            St::Addr if self.nbits == 8 => {
                if self.shift >> 1 == self.address && !self.nack_address {
                    self.drive_sda_low = true;
                    self.st = St::AddrAck { read: self.shift & 1 == 1 };
                } else {
                    self.st = St::Idle;
                }
            }
            St::Rx if self.nbits == 8 => {
                let byte = self.shift;
                self.written.push(byte);
                self.rx_in_transfer += 1;
                if self.first_data {
                    self.pointer = byte;
                    self.first_data = false;
                } else {
                    self.regs[usize::from(self.pointer)] = byte;
                    self.pointer = self.pointer.wrapping_add(1);
                }
                self.drive_sda_low = self.nack_data_after.is_none_or(|n| self.rx_in_transfer <= n);
                self.st = St::RxAck;
            }
            St::AddrAck { read } => {
                self.drive_sda_low = false;
                self.hold_scl_until = now + self.stretch;
                if read {
                    let b = self.next_tx_byte();
                    self.present(b, 7);
                } else {
                    self.st = St::Rx;
                    self.nbits = 0;
                    self.shift = 0;
                    self.first_data = true;
                    self.rx_in_transfer = 0;
                }
            }
            St::RxAck => {
                self.drive_sda_low = false;
                self.hold_scl_until = now + self.stretch;
                self.st = St::Rx;
                self.nbits = 0;
                self.shift = 0;
            }
            St::Tx { byte, bit } => {
                if bit == 0 {
                    self.drive_sda_low = false;
                    self.st = St::TxAck;
                } else {
                    self.present(byte, bit - 1);
                }
            }
            St::TxAck => {
                if self.master_acked {
                    self.hold_scl_until = now + self.stretch;
                    let b = self.next_tx_byte();
                    self.present(b, 7);
                } else {
                    self.st = St::Idle;
                }
            }
            _ => {}
        }
    }
}

/// The shared wire.
#[derive(Debug)]
pub struct Bus {
    /// Simulated time, CPU cycles.
    pub now: u64,
    pub costs: Costs,
    pub slaves: Vec<RegSlave>,
    /// Level changes, in order (the first entry is the idle bus at t = 0).
    pub trace: Vec<Sample>,
    pub conditions: Vec<(u64, Condition)>,
    /// SDA shorted to ground (a dead chip): nothing frees it.
    pub sda_shorted: bool,
    /// Another driver pulls SDA low during this window of cycles.
    pub sda_low_window: Option<(u64, u64)>,
    m_scl_low: bool,
    m_sda_low: bool,
    scl: bool,
    sda: bool,
}

impl Bus {
    pub fn new(slaves: Vec<RegSlave>) -> Self {
        Self {
            now: 0,
            costs: Costs::LX106,
            slaves,
            trace: std::vec![Sample { t: 0, scl: true, sda: true }],
            conditions: Vec::new(),
            sda_shorted: false,
            sda_low_window: None,
            m_scl_low: false,
            m_sda_low: false,
            scl: true,
            sda: true,
        }
    }

    /// The wire levels now (SCL, SDA).
    pub fn levels(&self) -> (bool, bool) {
        let scl = !self.m_scl_low && self.slaves.iter().all(|s| s.hold_scl_until <= self.now);
        let forced = self.sda_low_window.is_some_and(|(a, b)| self.now >= a && self.now < b);
        let sda = !self.m_sda_low && !self.sda_shorted && !forced && !self.slaves.iter().any(|s| s.drive_sda_low);
        (scl, sda)
    }

    /// Delivers every pending edge to the slaves until the wire is stable.
    fn settle(&mut self) {
        loop {
            let (scl, sda) = self.levels();
            let now = self.now;
            if scl != self.scl {
                self.scl = scl;
                self.trace.push(Sample { t: now, scl, sda: self.sda });
                let sda_now = self.sda;
                for s in &mut self.slaves {
                    if scl {
                        s.on_rise(sda_now);
                    } else {
                        s.on_fall(now);
                    }
                }
            } else if sda != self.sda {
                self.sda = sda;
                self.trace.push(Sample { t: now, scl, sda });
                if scl {
                    let c = if sda { Condition::Stop } else { Condition::Start };
                    self.conditions.push((now, c));
                    for s in &mut self.slaves {
                        if sda {
                            s.on_stop();
                        } else {
                            s.on_start();
                        }
                    }
                }
            } else {
                return;
            }
        }
    }

    fn advance(&mut self, cycles: u64) {
        self.now += cycles;
        self.settle();
    }

    /// SCL clock pulses (rising edges) seen on the wire.
    pub fn scl_pulses(&self) -> usize {
        self.trace.windows(2).filter(|w| !w[0].scl && w[1].scl).count()
    }
}

/// A handle on the shared bus.
pub type SharedBus = Rc<RefCell<Bus>>;

pub fn shared(bus: Bus) -> SharedBus {
    Rc::new(RefCell::new(bus))
}

/// The master's two pins on the simulated wire.
pub struct SimPins(pub SharedBus);

impl SimPins {
    fn write(&mut self, f: impl FnOnce(&mut Bus)) {
        let mut b = self.0.borrow_mut();
        let c = b.costs.pin_write;
        b.advance(c);
        f(&mut b);
        b.settle();
    }

    fn read(&mut self) -> (bool, bool) {
        let mut b = self.0.borrow_mut();
        let c = b.costs.pin_read;
        b.advance(c);
        b.levels()
    }
}

impl I2cPins for SimPins {
    fn scl_release(&mut self) {
        self.write(|b| b.m_scl_low = false);
    }
    fn scl_low(&mut self) {
        self.write(|b| b.m_scl_low = true);
    }
    fn scl_is_high(&mut self) -> bool {
        self.read().0
    }
    fn sda_release(&mut self) {
        self.write(|b| b.m_sda_low = false);
    }
    fn sda_low(&mut self) {
        self.write(|b| b.m_sda_low = true);
    }
    fn sda_is_high(&mut self) -> bool {
        self.read().1
    }
}

/// The cycle counter of the simulated CPU (wraps like CCOUNT).
pub struct SimClock(pub SharedBus);

impl CycleClock for SimClock {
    fn now(&mut self) -> u32 {
        let mut b = self.0.borrow_mut();
        let c = b.costs.clock_read;
        b.advance(c);
        b.now as u32
    }
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
pub fn check_timing(trace: &[Sample], lim: &Limits) -> Vec<std::string::String> {
    use std::format;
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
