//! The I2C wire in front of the fake chips: a master's SCL/SDA levels, edge
//! by edge, turned into the transactions the chips ([`I2cTarget`]) answer,
//! and the level the chips put back on SDA. The emulated board's bit-banged
//! master drives it through the simulator link (`link.rs`).
//!
//! A chip acknowledges its address when [`I2cTarget::acks`] says so (and no
//! injected fault NACKs it), acknowledges every written byte, and takes the
//! written bytes (register first) at the repeated START or STOP that ends
//! them. Read bytes are fetched one at a time as the master clocks them,
//! each after the master's ACK of the previous one, so a chip's register
//! pointer moves exactly as on the real bus. The slaves change SDA only at
//! SCL's falling edge and at START/STOP, and never stretch SCL.
//!
//! Faults: addresses that are not acknowledged ([`Wire::set_nack`]), SDA
//! held low by a stuck slave ([`Wire::set_sda_held`]) or by another driver
//! for a while ([`Wire::set_sda_low_window`]), written bytes not
//! acknowledged past a count ([`Wire::set_nack_data_after`]), and a slave
//! left in the middle of a read ([`Wire::stuck_mid_read`]).
//!
//! Time, for the board's bit-banged master tested cycle by cycle
//! (`tests/drivers/bitbang_i2c.rs`): the owner moves the wire's clock
//! ([`Wire::advance`]; any unit, CPU cycles there); a slave may then stretch
//! the clock after each ACK ([`Wire::set_stretch`]), and the wire can
//! record every level change with its time and every START and STOP
//! ([`Wire::record`]) for timing checks. The emulated board's link uses
//! none of these: without them the wire has no time and never stretches.

use std::cell::RefCell;
use std::rc::Rc;
use std::vec::Vec;

use super::bus::I2cTarget;

#[derive(Clone, Copy, PartialEq, Eq, Debug)]
enum St {
    /// Not addressed: waiting for a START.
    Idle,
    Addr,
    AddrAck {
        read: bool,
    },
    Rx,
    RxAck,
    Tx {
        byte: u8,
        bit: u8,
    },
    TxAck {
        acked: bool,
    },
}

/// The wire and its slaves (see the module docs).
pub struct Wire {
    chips: Vec<Rc<RefCell<dyn I2cTarget>>>,
    master_scl: bool,
    master_sda: bool,
    scl: bool,
    sda: bool,
    st: St,
    shift: u8,
    nbits: u8,
    addr: u8,
    target: Option<usize>,
    written: Vec<u8>,
    slave_low: bool,
    held_low: bool,
    nack: Vec<u8>,
    addressed: u32,
    nacked: u32,
    /// The owner's clock (see the module docs).
    now: u64,
    /// SCL held low by the addressed slave until this time.
    hold_scl_until: u64,
    stretch: Vec<(u8, u64)>,
    nack_data_after: Vec<(u8, usize)>,
    sda_low_window: Option<(u64, u64)>,
    recording: bool,
    trace: Vec<Sample>,
    conditions: Vec<(u64, Condition)>,
}

/// The wire's levels after a change, at time `t`.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub struct Sample {
    pub t: u64,
    pub scl: bool,
    pub sda: bool,
}

/// A bus condition seen on the wire.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum Condition {
    Start,
    Stop,
}

impl Wire {
    pub fn new(chips: Vec<Rc<RefCell<dyn I2cTarget>>>) -> Wire {
        Wire {
            chips,
            master_scl: true,
            master_sda: true,
            scl: true,
            sda: true,
            st: St::Idle,
            shift: 0,
            nbits: 0,
            addr: 0,
            target: None,
            written: Vec::new(),
            slave_low: false,
            held_low: false,
            nack: Vec::new(),
            addressed: 0,
            nacked: 0,
            now: 0,
            hold_scl_until: 0,
            stretch: Vec::new(),
            nack_data_after: Vec::new(),
            sda_low_window: None,
            recording: false,
            trace: Vec::new(),
            conditions: Vec::new(),
        }
    }

    /// The master's lines (true: released); the slaves see every edge.
    pub fn set_master(&mut self, scl: bool, sda: bool) {
        self.master_scl = scl;
        self.master_sda = sda;
        self.settle();
    }

    /// True while a slave (or a fault) pulls SDA low.
    pub fn sda_pulled_low(&self) -> bool {
        let window = self.sda_low_window.is_some_and(|(from, to)| self.now >= from && self.now < to);
        self.slave_low || self.held_low || window
    }

    /// The wire's levels (SCL, SDA).
    pub fn levels(&self) -> (bool, bool) {
        (self.master_scl && self.hold_scl_until <= self.now, self.master_sda && !self.sda_pulled_low())
    }

    /// Moves the wire's clock on by `dt`; the slaves see what changes.
    pub fn advance(&mut self, dt: u64) {
        self.now += dt;
        self.settle();
    }

    /// The wire's clock.
    pub fn now(&self) -> u64 {
        self.now
    }

    /// While set, the slave at `addr` holds SCL low for `duration` after
    /// each ACK clock (address, written byte, and a read byte the master
    /// acknowledged).
    pub fn set_stretch(&mut self, addr: u8, duration: u64) {
        self.stretch.retain(|(a, _)| *a != addr);
        self.stretch.push((addr, duration));
    }

    /// While set, the slave at `addr` acknowledges only the first `n` bytes
    /// written in a transfer (the register byte included).
    pub fn set_nack_data_after(&mut self, addr: u8, n: Option<usize>) {
        self.nack_data_after.retain(|(a, _)| *a != addr);
        if let Some(n) = n {
            self.nack_data_after.push((addr, n));
        }
    }

    /// Another driver pulls SDA low over `[from, to)` of the wire's clock.
    pub fn set_sda_low_window(&mut self, window: Option<(u64, u64)>) {
        self.sda_low_window = window;
        self.settle();
    }

    /// Leaves the slave at `addr` in the middle of sending `byte`, bit 7 on
    /// SDA, as if the master had been reset during a read (what bus
    /// recovery is for). The wire is at that level already: no edge.
    pub fn stuck_mid_read(&mut self, addr: u8, byte: u8) {
        self.addr = addr;
        self.target = self.chips.iter().position(|c| c.borrow().acks(addr));
        self.present(byte, 7);
        self.sda = self.levels().1;
        self.push_sample();
    }

    /// True when no transfer is under way and no slave pulls SDA low.
    pub fn is_idle(&self) -> bool {
        self.st == St::Idle && !self.slave_low
    }

    /// From now on, records every level change and condition.
    pub fn record(&mut self) {
        self.recording = true;
        self.push_sample();
    }

    /// The recorded level changes (the first is the wire when recording
    /// began).
    pub fn trace(&self) -> &[Sample] {
        &self.trace
    }

    /// The recorded STARTs (repeated ones included) and STOPs.
    pub fn conditions(&self) -> &[(u64, Condition)] {
        &self.conditions
    }

    /// SCL clock pulses (rising edges) recorded.
    pub fn scl_pulses(&self) -> usize {
        self.trace.windows(2).filter(|w| matches!(w, [a, b] if !a.scl && b.scl)).count()
    }

    fn push_sample(&mut self) {
        if self.recording {
            self.trace.push(Sample { t: self.now, scl: self.scl, sda: self.sda });
        }
    }

    fn stretch_after_ack(&mut self) {
        let d = self.stretch.iter().find(|(a, _)| *a == self.addr).map_or(0, |(_, d)| *d);
        self.hold_scl_until = self.now + d;
    }

    /// While set, `addr` is not acknowledged.
    pub fn set_nack(&mut self, addr: u8, nack: bool) {
        self.nack.retain(|a| *a != addr);
        if nack {
            self.nack.push(addr);
        }
    }

    /// While set, a stuck slave holds SDA low.
    pub fn set_sda_held(&mut self, held: bool) {
        self.held_low = held;
        self.settle();
    }

    /// Address phases seen (acknowledged or not) and those not acknowledged.
    pub fn addressed(&self) -> (u32, u32) {
        (self.addressed, self.nacked)
    }

    fn settle(&mut self) {
        loop {
            let (scl, sda) = self.levels();
            if scl != self.scl {
                self.scl = scl;
                self.push_sample();
                if scl {
                    self.on_rise(self.sda);
                } else {
                    self.on_fall();
                }
            } else if sda != self.sda {
                self.sda = sda;
                self.push_sample();
                if scl {
                    if self.recording {
                        self.conditions.push((self.now, if sda { Condition::Stop } else { Condition::Start }));
                    }
                    self.deliver_write();
                    self.slave_low = false;
                    self.st = if sda { St::Idle } else { St::Addr };
                    self.shift = 0;
                    self.nbits = 0;
                }
            } else {
                return;
            }
        }
    }

    fn on_rise(&mut self, sda: bool) {
        match self.st {
            St::Addr | St::Rx => {
                self.shift = self.shift << 1 | u8::from(sda);
                self.nbits += 1;
            }
            St::TxAck { .. } => self.st = St::TxAck { acked: !sda },
            _ => {}
        }
    }

    fn on_fall(&mut self) {
        match self.st {
            St::Addr if self.nbits == 8 => self.address(),
            St::AddrAck { read } => {
                self.slave_low = false;
                self.stretch_after_ack();
                if read {
                    self.present_next();
                } else {
                    self.st = St::Rx;
                    self.nbits = 0;
                }
            }
            St::Rx if self.nbits == 8 => {
                self.written.push(self.shift);
                let n = self.written.len();
                self.slave_low = !self.nack_data_after.iter().any(|&(a, after)| a == self.addr && n > after);
                self.st = St::RxAck;
            }
            St::RxAck => {
                self.slave_low = false;
                self.stretch_after_ack();
                self.st = St::Rx;
                self.nbits = 0;
            }
            St::Tx { bit: 0, .. } => {
                self.slave_low = false;
                self.st = St::TxAck { acked: false };
            }
            St::Tx { byte, bit } => self.present(byte, bit - 1),
            St::TxAck { acked: true } => {
                self.stretch_after_ack();
                self.present_next();
            }
            St::TxAck { acked: false } => self.st = St::Idle,
            _ => {}
        }
    }

    /// The eighth address bit is in: acknowledge it, or go idle.
    fn address(&mut self) {
        let addr = self.shift >> 1;
        self.addressed += 1;
        let chip = if self.nack.contains(&addr) { None } else { self.chips.iter().position(|c| c.borrow().acks(addr)) };
        match chip {
            Some(i) => {
                self.addr = addr;
                self.target = Some(i);
                self.slave_low = true;
                self.st = St::AddrAck { read: self.shift & 1 == 1 };
            }
            None => {
                self.nacked += 1;
                self.target = None;
                self.st = St::Idle;
            }
        }
    }

    fn present_next(&mut self) {
        let mut b = [0xFF];
        if let Some(chip) = self.target.and_then(|i| self.chips.get(i)) {
            chip.borrow_mut().read(self.addr, &mut b);
        }
        self.present(b[0], 7);
    }

    fn present(&mut self, byte: u8, bit: u8) {
        self.st = St::Tx { byte, bit };
        self.slave_low = byte >> bit & 1 == 0;
    }

    fn deliver_write(&mut self) {
        if self.written.is_empty() {
            return;
        }
        if let Some(chip) = self.target.and_then(|i| self.chips.get(i)) {
            chip.borrow_mut().write(self.addr, &self.written);
        }
        self.written.clear();
    }
}
