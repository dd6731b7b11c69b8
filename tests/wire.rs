//! The simulator's I2C wire (`sim::wire`, what the emulated board's pins
//! drive) against the firmware's own bit-banged master: the master's edges
//! become the transactions a register-file chip sees, byte for byte, and
//! the wire's faults reach the master as the errors it reports.
use std::cell::RefCell;
use std::rc::Rc;

use embedded_hal::i2c::{ErrorKind, I2c, NoAcknowledgeSource};
use paperbot::board::bitbang_i2c::{BitBangI2c, CycleClock, Error, I2cPins, Timing};
use paperbot::sim::bus::I2cTarget;
use paperbot::sim::wire::Wire;

/// A chip with 256 byte registers and an auto-incrementing pointer, which
/// records every write it is given.
struct RegisterChip {
    addr: u8,
    regs: [u8; 256],
    pointer: u8,
    writes: Vec<Vec<u8>>,
}

impl RegisterChip {
    fn new(addr: u8) -> Rc<RefCell<RegisterChip>> {
        let mut regs = [0; 256];
        for (i, r) in regs.iter_mut().enumerate() {
            *r = (i as u8).wrapping_mul(7) ^ 0x5a;
        }
        Rc::new(RefCell::new(RegisterChip { addr, regs, pointer: 0, writes: Vec::new() }))
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

/// The master's two pins, wired to the simulated wire.
struct Pins {
    wire: Rc<RefCell<Wire>>,
    scl: bool,
    sda: bool,
}

impl Pins {
    fn drive(&mut self) {
        self.wire.borrow_mut().set_master(self.scl, self.sda);
    }
}

impl I2cPins for Pins {
    fn scl_release(&mut self) {
        self.scl = true;
        self.drive();
    }
    fn scl_low(&mut self) {
        self.scl = false;
        self.drive();
    }
    fn scl_is_high(&mut self) -> bool {
        self.wire.borrow().levels().0
    }
    fn sda_release(&mut self) {
        self.sda = true;
        self.drive();
    }
    fn sda_low(&mut self) {
        self.sda = false;
        self.drive();
    }
    fn sda_is_high(&mut self) -> bool {
        self.wire.borrow().levels().1
    }
}

/// A cycle counter that moves on by a few cycles at every look.
struct Ticking(u32);

impl CycleClock for Ticking {
    fn now(&mut self) -> u32 {
        self.0 = self.0.wrapping_add(7);
        self.0
    }
}

fn bus(chips: &[Rc<RefCell<RegisterChip>>]) -> (BitBangI2c<Pins, Ticking>, Rc<RefCell<Wire>>) {
    let targets = chips.iter().map(|c| c.clone() as Rc<RefCell<dyn I2cTarget>>).collect();
    let wire = Rc::new(RefCell::new(Wire::new(targets)));
    let pins = Pins { wire: wire.clone(), scl: true, sda: true };
    let mut i2c = BitBangI2c::new(pins, Ticking(0), Timing::FAST);
    i2c.init().unwrap();
    (i2c, wire)
}

#[test]
fn a_register_read_gives_the_chip_s_bytes_in_order() {
    let chip = RegisterChip::new(0x29);
    let (mut i2c, wire) = bus(&[chip.clone()]);
    let mut buf = [0u8; 4];
    i2c.write_read(0x29, &[0x10], &mut buf).unwrap();
    let want: Vec<u8> = (0x10..0x14u8).map(|i| i.wrapping_mul(7) ^ 0x5a).collect();
    assert_eq!(buf.to_vec(), want);
    assert_eq!(chip.borrow().writes, vec![vec![0x10]]);
    assert_eq!(chip.borrow().pointer, 0x14);
    assert_eq!(wire.borrow().addressed(), (2, 0));
}

#[test]
fn written_bytes_reach_the_chip_at_the_stop() {
    let chip = RegisterChip::new(0x29);
    let (mut i2c, _) = bus(&[chip.clone()]);
    i2c.write(0x29, &[0x8a, 0x16]).unwrap();
    i2c.write(0x29, &[0x20, 1, 2, 3]).unwrap();
    let c = chip.borrow();
    assert_eq!(c.writes, vec![vec![0x8a, 0x16], vec![0x20, 1, 2, 3]]);
    assert_eq!((c.regs[0x8a], c.regs[0x20], c.regs[0x22]), (0x16, 1, 3));
}

#[test]
fn only_the_addressed_chip_answers() {
    let (front, compass) = (RegisterChip::new(0x16), RegisterChip::new(0x0c));
    let (mut i2c, _) = bus(&[front.clone(), compass.clone()]);
    let mut b = [0u8; 1];
    i2c.write_read(0x0c, &[0x03], &mut b).unwrap();
    assert_eq!(b[0], 3u8.wrapping_mul(7) ^ 0x5a);
    assert!(front.borrow().writes.is_empty());
    assert_eq!(compass.borrow().writes, vec![vec![0x03]]);
    assert_eq!(i2c.write(0x29, &[0]), Err(Error::NoAcknowledge(NoAcknowledgeSource::Address)));
}

#[test]
fn an_injected_nack_and_a_held_sda_are_the_master_s_errors() {
    let chip = RegisterChip::new(0x68);
    let (mut i2c, wire) = bus(&[chip.clone()]);
    wire.borrow_mut().set_nack(0x68, true);
    let mut b = [0u8; 2];
    let e = i2c.write_read(0x68, &[0x75], &mut b).unwrap_err();
    assert_eq!(embedded_hal::i2c::Error::kind(&e), ErrorKind::NoAcknowledge(NoAcknowledgeSource::Address));
    assert_eq!(wire.borrow().addressed(), (1, 1));
    wire.borrow_mut().set_nack(0x68, false);

    wire.borrow_mut().set_sda_held(true);
    assert!(i2c.write_read(0x68, &[0x75], &mut b).is_err());
    wire.borrow_mut().set_sda_held(false);
    i2c.write_read(0x68, &[0x75], &mut b).unwrap();
    assert_eq!(b, [0x75u8.wrapping_mul(7) ^ 0x5a, 0x76u8.wrapping_mul(7) ^ 0x5a]);
}
