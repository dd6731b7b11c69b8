//! The simulator's I2C wire (`sim::wire`, what the emulated board's pins
//! drive) against the firmware's own bit-banged master: the master's edges
//! become the transactions a register-file chip sees, byte for byte, and
//! the wire's faults reach the master as the errors it reports.

use crate::common;
use std::cell::RefCell;
use std::rc::Rc;

use common::wire::{master_on, wire, RegisterChip, SharedWire};
use embedded_hal::i2c::{ErrorKind, I2c, NoAcknowledgeSource};
use paperbot::board::bitbang_i2c::{BitBangI2c, Error, Timing};

/// The robot's master on a wire with `chips` (register `i` holds
/// `i * 7 ^ 0x5a`), initialised.
fn bus(chips: &[Rc<RefCell<RegisterChip>>]) -> (BitBangI2c<common::wire::Pins, common::wire::Clock>, SharedWire) {
    let w = wire(chips);
    let mut i2c = master_on(&w, Timing::FAST);
    i2c.init().unwrap();
    (i2c, w)
}

#[test]
fn a_register_read_gives_the_chip_s_bytes_in_order() {
    let chip = RegisterChip::patterned(0x29);
    let (mut i2c, wire) = bus(std::slice::from_ref(&chip));
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
    let chip = RegisterChip::patterned(0x29);
    let (mut i2c, _) = bus(std::slice::from_ref(&chip));
    i2c.write(0x29, &[0x8a, 0x16]).unwrap();
    i2c.write(0x29, &[0x20, 1, 2, 3]).unwrap();
    let c = chip.borrow();
    assert_eq!(c.writes, vec![vec![0x8a, 0x16], vec![0x20, 1, 2, 3]]);
    assert_eq!((c.regs[0x8a], c.regs[0x20], c.regs[0x22]), (0x16, 1, 3));
}

#[test]
fn only_the_addressed_chip_answers() {
    let (front, compass) = (RegisterChip::patterned(0x16), RegisterChip::patterned(0x0c));
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
    let chip = RegisterChip::patterned(0x68);
    let (mut i2c, wire) = bus(std::slice::from_ref(&chip));
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
