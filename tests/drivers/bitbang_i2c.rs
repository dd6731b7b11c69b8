//! The board's bit-banged I2C master (`board::bitbang_i2c`) against the
//! simulator's wire (`sim::wire`, the one wire model, which the emulated
//! board drives too) cycle by cycle: register reads and writes, the
//! conditions and clocks on the wire, fast-mode timing, NACKs, clock
//! stretching, bus recovery, arbitration loss.

use crate::common;
use std::cell::RefCell;
use std::rc::Rc;

use common::wire::{check_timing, master_on, wire, Limits, RegisterChip, SharedWire};
use embedded_hal::i2c::{Error as _, ErrorKind, I2c, NoAcknowledgeSource, Operation};
use paperbot::board::bitbang_i2c::{BitBangI2c, Error, Timing};
use paperbot::config;
use paperbot::sim::wire::Condition;

const CPU_HZ: u64 = config::board::CPU_HZ as u64;

type Master = BitBangI2c<common::wire::Pins, common::wire::Clock>;

fn master(chips: &[Rc<RefCell<RegisterChip>>]) -> (Master, SharedWire) {
    let w = wire(chips);
    (master_on(&w, Timing::FAST), w)
}

fn assert_fast_mode(wire: &SharedWire) {
    let v = check_timing(wire.borrow().trace(), &Limits::fast_mode(CPU_HZ));
    assert!(v.is_empty(), "timing violations: {v:?}");
}

fn assert_idle(wire: &SharedWire) {
    let w = wire.borrow();
    assert_eq!(w.levels(), (true, true), "bus not idle");
    assert!(w.is_idle(), "a slave is mid-transfer");
}

fn conditions(wire: &SharedWire) -> Vec<Condition> {
    wire.borrow().conditions().iter().map(|c| c.1).collect()
}

#[test]
fn fast_mode_timing_constants() {
    // 80 MHz / 400 kHz = 200 cycles: low max(1.3 us = 104, 100), high >= 0.6 us.
    assert_eq!(Timing::FAST, Timing { low: 104, high_min: 48, period: 200, buf: 104, stretch_timeout: 80_000 });
    // 100 kHz: 800 cycles, low half of it.
    let t = Timing::new(80_000_000, 100_000, 1_000);
    assert_eq!((t.low, t.high_min, t.period), (400, 48, 800));
    // 1 MHz would break fast-mode minima: they win (104 + 48 > 80), the
    // bus runs slower than asked.
    let t = Timing::new(80_000_000, 1_000_000, 1_000);
    assert_eq!((t.low, t.high_min, t.period), (104, 48, 80));
}

#[test]
fn write_then_read_registers() {
    // (register, bytes written, then read back)
    let table: &[(u8, &[u8])] =
        &[(0x00, &[0xA5]), (0x10, &[0x01, 0x02, 0x03]), (0x8A, &[0xFF, 0x00, 0x55, 0xAA, 0x80, 0x7F]), (0xFF, &[0x42])];
    let chip = RegisterChip::new(0x29);
    let (mut i2c, bus) = master(std::slice::from_ref(&chip));
    i2c.init().unwrap();
    for &(reg, data) in table {
        let mut msg = vec![reg];
        msg.extend_from_slice(data);
        i2c.write(0x29, &msg).unwrap();
        let mut back = vec![0u8; data.len()];
        i2c.write_read(0x29, &[reg], &mut back).unwrap();
        assert_eq!(back, data, "reg {reg:#x}");
        let c = chip.borrow();
        for (k, &d) in data.iter().enumerate() {
            assert_eq!(c.regs[usize::from(reg.wrapping_add(k as u8))], d);
        }
    }
    assert_idle(&bus);
    assert_fast_mode(&bus);
}

#[test]
fn reads_what_the_slave_holds() {
    let s = RegisterChip::new(0x68);
    for (i, r) in s.borrow_mut().regs.iter_mut().enumerate() {
        *r = (i as u8).wrapping_mul(37) ^ 0x5C;
    }
    let want: Vec<u8> = (0x3Bu8..0x3B + 14).map(|i| i.wrapping_mul(37) ^ 0x5C).collect();
    let (mut i2c, bus) = master(&[s]);
    let mut buf = [0u8; 14];
    i2c.write_read(0x68, &[0x3B], &mut buf).unwrap();
    assert_eq!(buf.to_vec(), want);
    // START, repeated START, STOP
    assert_eq!(conditions(&bus), [Condition::Start, Condition::Start, Condition::Stop]);
    assert_idle(&bus);
    assert_fast_mode(&bus);
}

#[test]
fn transaction_groups_operations_by_direction() {
    let s = RegisterChip::new(0x0C);
    s.borrow_mut().regs[0x20..0x26].copy_from_slice(&[1, 2, 3, 4, 5, 6]);
    let (mut i2c, bus) = master(std::slice::from_ref(&s));
    let (mut a, mut b) = ([0u8; 2], [0u8; 4]);
    {
        let mut ops = [
            Operation::Write(&[0x20]),
            Operation::Write(&[]),
            Operation::Read(&mut a),
            Operation::Read(&mut b),
            Operation::Write(&[0x30, 9]),
        ];
        i2c.transaction(0x0C, &mut ops).unwrap();
    }
    assert_eq!((a, b), ([1, 2], [3, 4, 5, 6]));
    // write group, read group, write group: START, Sr, Sr, STOP
    assert_eq!(conditions(&bus), [Condition::Start, Condition::Start, Condition::Start, Condition::Stop]);
    assert_eq!(s.borrow().written(), [0x20, 0x30, 9]);
    assert_eq!(s.borrow().regs[0x30], 9);
    let bus = bus.borrow();
    // 3 address bytes + 3 written + 6 read, 9 clocks each; plus the SCL
    // rise of each repeated START and of the STOP
    assert_eq!(bus.scl_pulses(), 12 * 9 + 2 + 1);
}

#[test]
fn bus_runs_close_to_400_khz_and_never_faster() {
    let (mut i2c, bus) = master(&[RegisterChip::new(0x29)]);
    let mut buf = [0u8; 64];
    i2c.read(0x29, &mut buf).unwrap();
    let b = bus.borrow();
    let mut rises: Vec<u64> = b.trace().windows(2).filter(|w| !w[0].scl && w[1].scl).map(|w| w[1].t).collect();
    assert_eq!(rises.len(), 65 * 9 + 1);
    rises.pop(); // the STOP's
    let span = rises[rises.len() - 1] - rises[0];
    let hz = (rises.len() as u64 - 1) * CPU_HZ / span;
    assert!((395_000..=400_000).contains(&hz), "bus clock {hz} Hz");
    println!("simulated bus clock: {hz} Hz");
    drop(b);
    assert_fast_mode(&bus);
}

#[test]
fn address_nack_is_reported_and_the_bus_left_idle() {
    // no slave at 0x30; a slave at 0x29 that refuses
    for addr in [0x30u8, 0x29] {
        let (mut i2c, bus) = master(&[RegisterChip::new(0x29)]);
        bus.borrow_mut().set_nack(0x29, true);
        let e = i2c.write(addr, &[1, 2]).unwrap_err();
        assert_eq!(e, Error::NoAcknowledge(NoAcknowledgeSource::Address));
        assert_eq!(e.kind(), ErrorKind::NoAcknowledge(NoAcknowledgeSource::Address));
        assert_eq!(conditions(&bus).last(), Some(&Condition::Stop));
        assert_eq!(bus.borrow().scl_pulses(), 9 + 1, "STOP right after the address");
        assert_idle(&bus);
    }
}

#[test]
fn data_nack_is_reported() {
    let s = RegisterChip::new(0x29);
    let (mut i2c, bus) = master(std::slice::from_ref(&s));
    bus.borrow_mut().set_nack_data_after(0x29, Some(2)); // pointer + one byte
    let e = i2c.write(0x29, &[0x10, 0xAA, 0xBB, 0xCC]).unwrap_err();
    assert_eq!(e.kind(), ErrorKind::NoAcknowledge(NoAcknowledgeSource::Data));
    assert_eq!(s.borrow().written(), [0x10, 0xAA, 0xBB]);
    assert_eq!(bus.borrow().scl_pulses(), 4 * 9 + 1);
    assert_idle(&bus);
}

#[test]
fn clock_stretching_is_waited_for() {
    // stretch after every ACK: 0, 10 us, 500 us (all below the 1 ms timeout)
    for stretch_us in [0u64, 10, 500] {
        let s = RegisterChip::new(0x29);
        s.borrow_mut().regs[5] = 0x77;
        let (mut i2c, bus) = master(&[s]);
        bus.borrow_mut().set_stretch(0x29, stretch_us * 80);
        let mut buf = [0u8; 1];
        i2c.write_read(0x29, &[5], &mut buf).unwrap();
        assert_eq!(buf, [0x77]);
        assert_idle(&bus);
        // still no phase shorter than the fast-mode minima after a stretch
        assert_fast_mode(&bus);
    }
}

#[test]
fn endless_stretch_times_out_as_a_bus_error() {
    let (mut i2c, bus) = master(&[RegisterChip::new(0x29)]);
    bus.borrow_mut().set_stretch(0x29, 2_000 * 80); // 2 ms > 1 ms
    let t0 = bus.borrow().now();
    let e = i2c.write(0x29, &[1]).unwrap_err();
    assert_eq!(e, Error::ClockStretchTimeout);
    assert_eq!(e.kind(), ErrorKind::Bus);
    // gave up after the timeout, not before
    let waited = bus.borrow().now() - t0;
    assert!(waited >= u64::from(Timing::FAST.stretch_timeout), "{waited}");
}

#[test]
fn recovery_frees_a_slave_stuck_mid_read() {
    // The slave was sending these bytes when the master reset; SDA is low.
    for byte in [0x00u8, 0x01, 0x7F, 0x3C] {
        let s = RegisterChip::new(0x29);
        s.borrow_mut().regs[0] = 0x99;
        let (mut i2c, bus) = master(&[s]);
        bus.borrow_mut().stuck_mid_read(0x29, byte);
        assert_eq!(bus.borrow().levels(), (true, false), "SDA held low");
        i2c.init().unwrap();
        assert_idle(&bus);
        let pulses = bus.borrow().scl_pulses();
        assert!((1..=9).contains(&pulses), "{byte:#x}: {pulses} pulses");
        println!("stuck sending {byte:#04x}: freed by {pulses} clocks");
        // and the bus works afterwards
        let mut buf = [0u8; 1];
        i2c.write_read(0x29, &[0], &mut buf).unwrap();
        assert_eq!(buf, [0x99]);
    }
}

#[test]
fn start_recovers_a_stuck_bus_by_itself() {
    let s = RegisterChip::new(0x29);
    s.borrow_mut().regs[3] = 0x31;
    let (mut i2c, bus) = master(&[s]);
    bus.borrow_mut().stuck_mid_read(0x29, 0x00);
    let mut buf = [0u8; 1];
    i2c.write_read(0x29, &[3], &mut buf).unwrap();
    assert_eq!(buf, [0x31]);
    assert_idle(&bus);
}

#[test]
fn shorted_sda_is_a_bus_error_after_nine_clocks() {
    let (mut i2c, bus) = master(&[RegisterChip::new(0x29)]);
    bus.borrow_mut().set_sda_held(true);
    assert_eq!(i2c.init(), Err(Error::BusStuck));
    assert_eq!(bus.borrow().scl_pulses(), usize::from(config::i2c::RECOVERY_CLOCKS));
    let e = i2c.write(0x29, &[0]).unwrap_err();
    assert_eq!(e.kind(), ErrorKind::Bus);
}

#[test]
fn sda_pulled_low_by_someone_else_is_arbitration_loss() {
    // 0x7F is all ones: the master releases SDA for its first 7 bits; the
    // other driver pulls SDA low during the third bit.
    let (mut i2c, bus) = master(&[RegisterChip::new(0x29)]);
    {
        let mut b = bus.borrow_mut();
        let t = b.now();
        b.set_sda_low_window(Some((t + 2 * 200 + 150, t + 2 * 200 + 400)));
    }
    let e = i2c.write(0x7F, &[0]).unwrap_err();
    assert_eq!(e, Error::ArbitrationLoss);
    assert_eq!(e.kind(), ErrorKind::ArbitrationLoss);
    assert_idle(&bus);
}

#[test]
fn two_chips_share_the_bus() {
    let lidar = RegisterChip::new(0x29);
    lidar.borrow_mut().regs[0xC0] = 0xEE; // VL53L0X model id
    let mpu = RegisterChip::new(0x68);
    mpu.borrow_mut().regs[0x75] = 0x71; // MPU9250 WHO_AM_I
    let (mut i2c, _bus) = master(&[lidar.clone(), mpu.clone()]);
    let mut id = [0u8; 1];
    i2c.write_read(0x68, &[0x75], &mut id).unwrap();
    assert_eq!(id, [0x71]);
    i2c.write_read(0x29, &[0xC0], &mut id).unwrap();
    assert_eq!(id, [0xEE]);
    i2c.write(0x68, &[0x37, 0x02]).unwrap(); // INT_PIN_CFG: bypass on
    assert_eq!(mpu.borrow().regs[0x37], 0x02);
    assert_eq!(lidar.borrow().written(), [0xC0]);
}

#[test]
fn invalid_address_touches_nothing() {
    let (mut i2c, bus) = master(&[RegisterChip::new(0x29)]);
    let e = i2c.write(0x80, &[0]).unwrap_err();
    assert_eq!(e, Error::InvalidAddress);
    assert_eq!(e.kind(), ErrorKind::Other);
    assert_eq!(bus.borrow().trace().len(), 1);
}

#[test]
fn empty_transaction_and_empty_read() {
    let s = RegisterChip::new(0x29);
    s.borrow_mut().regs[0] = 0x12;
    let (mut i2c, bus) = master(&[s]);
    i2c.transaction(0x29, &mut []).unwrap();
    assert_eq!(bus.borrow().trace().len(), 1);
    // address-only write: a probe
    i2c.write(0x29, &[]).unwrap();
    assert_eq!(bus.borrow().scl_pulses(), 9 + 1);
    // an empty read still clocks (and NACKs) one byte
    i2c.read(0x29, &mut []).unwrap();
    assert_eq!(bus.borrow().scl_pulses(), 10 + 18 + 1);
    assert_idle(&bus);
}

#[test]
fn the_timing_check_catches_a_too_fast_master() {
    // A master told to run at 800 kHz with halved minima must be flagged:
    // proves check_timing (used above) can fail.
    let bus = wire(&[RegisterChip::new(0x29)]);
    let fast = Timing { low: 52, high_min: 24, period: 100, buf: 52, stretch_timeout: 80_000 };
    let mut i2c = master_on(&bus, fast);
    i2c.write(0x29, &[1, 2]).unwrap();
    let v = check_timing(bus.borrow().trace(), &Limits::fast_mode(CPU_HZ));
    assert!(v.iter().any(|m| m.starts_with("tLOW")), "{v:?}");
    assert!(v.iter().any(|m| m.starts_with("SCL period")), "{v:?}");
}
