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
//! Faults: addresses that are not acknowledged ([`Wire::set_nack`]) and SDA
//! held low by a stuck slave ([`Wire::set_sda_held`]).

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
        self.slave_low || self.held_low
    }

    /// The wire's levels (SCL, SDA).
    pub fn levels(&self) -> (bool, bool) {
        (self.master_scl, self.master_sda && !self.sda_pulled_low())
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
                if scl {
                    self.on_rise(self.sda);
                } else {
                    self.on_fall();
                }
            } else if sda != self.sda {
                self.sda = sda;
                if scl {
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
                if read {
                    self.present_next();
                } else {
                    self.st = St::Rx;
                    self.nbits = 0;
                }
            }
            St::Rx if self.nbits == 8 => {
                self.written.push(self.shift);
                self.slave_low = true;
                self.st = St::RxAck;
            }
            St::RxAck => {
                self.slave_low = false;
                self.st = St::Rx;
                self.nbits = 0;
            }
            St::Tx { bit: 0, .. } => {
                self.slave_low = false;
                self.st = St::TxAck { acked: false };
            }
            St::Tx { byte, bit } => self.present(byte, bit - 1),
            St::TxAck { acked: true } => self.present_next(),
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
