//! The bit-banged master against the wire-level simulated bus.

extern crate std;

use std::vec;
use std::vec::Vec;

use embedded_hal::i2c::{Error as _, ErrorKind, I2c, NoAcknowledgeSource, Operation};

use super::*;
use crate::board::sim_wire::{self, check_timing, Bus, Condition, Limits, RegSlave, SharedBus, SimClock, SimPins};

const CPU_HZ: u64 = config::board::CPU_HZ as u64;

fn master(slaves: Vec<RegSlave>) -> (BitBangI2c<SimPins, SimClock>, SharedBus) {
    let bus = sim_wire::shared(Bus::new(slaves));
    (BitBangI2c::new(SimPins(bus.clone()), SimClock(bus.clone()), Timing::FAST), bus)
}

fn assert_fast_mode(bus: &SharedBus) {
    let b = bus.borrow();
    let v = check_timing(&b.trace, &Limits::fast_mode(CPU_HZ));
    assert!(v.is_empty(), "timing violations: {v:?}");
}

fn assert_idle(bus: &SharedBus) {
    let b = bus.borrow();
    assert_eq!(b.levels(), (true, true), "bus not idle");
    assert!(b.slaves.iter().all(RegSlave::is_idle), "a slave is mid-transfer");
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
    let (mut i2c, bus) = master(vec![RegSlave::new(0x29)]);
    i2c.init().unwrap();
    for &(reg, data) in table {
        let mut msg = vec![reg];
        msg.extend_from_slice(data);
        i2c.write(0x29, &msg).unwrap();
        let mut back = vec![0u8; data.len()];
        i2c.write_read(0x29, &[reg], &mut back).unwrap();
        assert_eq!(back, data, "reg {reg:#x}");
        let b = bus.borrow();
        for (k, &d) in data.iter().enumerate() {
            assert_eq!(b.slaves[0].regs[usize::from(reg.wrapping_add(k as u8))], d);
        }
    }
    assert_idle(&bus);
    assert_fast_mode(&bus);
}

#[test]
fn reads_what_the_slave_holds() {
    let mut s = RegSlave::new(0x68);
    for (i, r) in s.regs.iter_mut().enumerate() {
        *r = (i as u8).wrapping_mul(37) ^ 0x5C;
    }
    let want: Vec<u8> = (0x3Bu8..0x3B + 14).map(|i| i.wrapping_mul(37) ^ 0x5C).collect();
    let (mut i2c, bus) = master(vec![s]);
    let mut buf = [0u8; 14];
    i2c.write_read(0x68, &[0x3B], &mut buf).unwrap();
    assert_eq!(buf.to_vec(), want);
    // START, repeated START, STOP
    let c: Vec<_> = bus.borrow().conditions.iter().map(|c| c.1).collect();
    assert_eq!(c, [Condition::Start, Condition::Start, Condition::Stop]);
    assert_idle(&bus);
    assert_fast_mode(&bus);
}

#[test]
fn transaction_groups_operations_by_direction() {
    let mut s = RegSlave::new(0x0C);
    s.regs[0x20..0x26].copy_from_slice(&[1, 2, 3, 4, 5, 6]);
    let (mut i2c, bus) = master(vec![s]);
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
    let bus = bus.borrow();
    let c: Vec<_> = bus.conditions.iter().map(|c| c.1).collect();
    // write group, read group, write group: START, Sr, Sr, STOP
    assert_eq!(c, [Condition::Start, Condition::Start, Condition::Start, Condition::Stop]);
    assert_eq!(bus.slaves[0].written, [0x20, 0x30, 9]);
    assert_eq!(bus.slaves[0].regs[0x30], 9);
    // 3 address bytes + 3 written + 6 read, 9 clocks each; plus the SCL
    // rise of each repeated START and of the STOP
    assert_eq!(bus.scl_pulses(), 12 * 9 + 2 + 1);
}

#[test]
fn bus_runs_close_to_400_khz_and_never_faster() {
    let (mut i2c, bus) = master(vec![RegSlave::new(0x29)]);
    let mut buf = [0u8; 64];
    i2c.read(0x29, &mut buf).unwrap();
    let b = bus.borrow();
    let mut rises: Vec<u64> = b.trace.windows(2).filter(|w| !w[0].scl && w[1].scl).map(|w| w[1].t).collect();
    assert_eq!(rises.len(), 65 * 9 + 1);
    rises.pop(); // the STOP's
    let span = rises[rises.len() - 1] - rises[0];
    let hz = (rises.len() as u64 - 1) * CPU_HZ / span;
    assert!((395_000..=400_000).contains(&hz), "bus clock {hz} Hz");
    std::println!("simulated bus clock: {hz} Hz");
    drop(b);
    assert_fast_mode(&bus);
}

#[test]
fn address_nack_is_reported_and_the_bus_left_idle() {
    // no slave at 0x30; a slave at 0x29 that refuses
    let mut refusing = RegSlave::new(0x29);
    refusing.nack_address = true;
    for addr in [0x30u8, 0x29] {
        let (mut i2c, bus) = master(vec![refusing.clone()]);
        let e = i2c.write(addr, &[1, 2]).unwrap_err();
        assert_eq!(e, Error::NoAcknowledge(NoAcknowledgeSource::Address));
        assert_eq!(e.kind(), ErrorKind::NoAcknowledge(NoAcknowledgeSource::Address));
        assert_eq!(bus.borrow().conditions.last().map(|c| c.1), Some(Condition::Stop));
        assert_eq!(bus.borrow().scl_pulses(), 9 + 1, "STOP right after the address");
        assert_idle(&bus);
    }
}

#[test]
fn data_nack_is_reported() {
    let mut s = RegSlave::new(0x29);
    s.nack_data_after = Some(2); // pointer + one byte
    let (mut i2c, bus) = master(vec![s]);
    let e = i2c.write(0x29, &[0x10, 0xAA, 0xBB, 0xCC]).unwrap_err();
    assert_eq!(e.kind(), ErrorKind::NoAcknowledge(NoAcknowledgeSource::Data));
    assert_eq!(bus.borrow().slaves[0].written, [0x10, 0xAA, 0xBB]);
    assert_eq!(bus.borrow().scl_pulses(), 4 * 9 + 1);
    assert_idle(&bus);
}

#[test]
fn clock_stretching_is_waited_for() {
    // stretch after every ACK: 0, 10 us, 500 us (all below the 1 ms timeout)
    for stretch_us in [0u64, 10, 500] {
        let mut s = RegSlave::new(0x29);
        s.stretch = stretch_us * 80;
        s.regs[5] = 0x77;
        let (mut i2c, bus) = master(vec![s]);
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
    let mut s = RegSlave::new(0x29);
    s.stretch = 2_000 * 80; // 2 ms > 1 ms
    let (mut i2c, bus) = master(vec![s]);
    let t0 = bus.borrow().now;
    let e = i2c.write(0x29, &[1]).unwrap_err();
    assert_eq!(e, Error::ClockStretchTimeout);
    assert_eq!(e.kind(), ErrorKind::Bus);
    // gave up after the timeout, not before
    let waited = bus.borrow().now - t0;
    assert!(waited >= u64::from(Timing::FAST.stretch_timeout), "{waited}");
}

#[test]
fn recovery_frees_a_slave_stuck_mid_read() {
    // The slave was sending these bytes when the master reset; SDA is low.
    for byte in [0x00u8, 0x01, 0x7F, 0x3C] {
        let mut s = RegSlave::new(0x29);
        s.stuck_mid_read(byte);
        s.regs[0] = 0x99;
        let (mut i2c, bus) = master(vec![s]);
        assert_eq!(bus.borrow().levels(), (true, false), "SDA held low");
        i2c.init().unwrap();
        assert_idle(&bus);
        let pulses = bus.borrow().scl_pulses();
        assert!((1..=9).contains(&pulses), "{byte:#x}: {pulses} pulses");
        // and the bus works afterwards
        let mut buf = [0u8; 1];
        i2c.write_read(0x29, &[0], &mut buf).unwrap();
        assert_eq!(buf, [0x99]);
    }
}

#[test]
fn start_recovers_a_stuck_bus_by_itself() {
    let mut s = RegSlave::new(0x29);
    s.stuck_mid_read(0x00);
    s.regs[3] = 0x31;
    let (mut i2c, bus) = master(vec![s]);
    let mut buf = [0u8; 1];
    i2c.write_read(0x29, &[3], &mut buf).unwrap();
    assert_eq!(buf, [0x31]);
    assert_idle(&bus);
}

#[test]
fn shorted_sda_is_a_bus_error_after_nine_clocks() {
    let (mut i2c, bus) = master(vec![RegSlave::new(0x29)]);
    bus.borrow_mut().sda_shorted = true;
    assert_eq!(i2c.init(), Err(Error::BusStuck));
    assert_eq!(bus.borrow().scl_pulses(), usize::from(config::i2c::RECOVERY_CLOCKS));
    let e = i2c.write(0x29, &[0]).unwrap_err();
    assert_eq!(e.kind(), ErrorKind::Bus);
}

#[test]
fn sda_pulled_low_by_someone_else_is_arbitration_loss() {
    // 0x7F is all ones: the master releases SDA for its first 7 bits; the
    // other driver pulls SDA low during the third bit.
    let (mut i2c, bus) = master(vec![RegSlave::new(0x29)]);
    {
        let mut b = bus.borrow_mut();
        let t = b.now;
        b.sda_low_window = Some((t + 2 * 200 + 150, t + 2 * 200 + 400));
    }
    let e = i2c.write(0x7F, &[0]).unwrap_err();
    assert_eq!(e, Error::ArbitrationLoss);
    assert_eq!(e.kind(), ErrorKind::ArbitrationLoss);
    assert_idle(&bus);
}

#[test]
fn two_chips_share_the_bus() {
    let mut lidar = RegSlave::new(0x29);
    lidar.regs[0xC0] = 0xEE; // VL53L0X model id
    let mut mpu = RegSlave::new(0x68);
    mpu.regs[0x75] = 0x71; // MPU9250 WHO_AM_I
    let (mut i2c, bus) = master(vec![lidar, mpu]);
    let mut id = [0u8; 1];
    i2c.write_read(0x68, &[0x75], &mut id).unwrap();
    assert_eq!(id, [0x71]);
    i2c.write_read(0x29, &[0xC0], &mut id).unwrap();
    assert_eq!(id, [0xEE]);
    i2c.write(0x68, &[0x37, 0x02]).unwrap(); // INT_PIN_CFG: bypass on
    let b = bus.borrow();
    assert_eq!(b.slaves[1].regs[0x37], 0x02);
    assert_eq!(b.slaves[0].written, [0xC0]);
}

#[test]
fn invalid_address_touches_nothing() {
    let (mut i2c, bus) = master(vec![RegSlave::new(0x29)]);
    let e = i2c.write(0x80, &[0]).unwrap_err();
    assert_eq!(e, Error::InvalidAddress);
    assert_eq!(e.kind(), ErrorKind::Other);
    assert_eq!(bus.borrow().trace.len(), 1);
}

#[test]
fn empty_transaction_and_empty_read() {
    let mut s = RegSlave::new(0x29);
    s.regs[0] = 0x12;
    let (mut i2c, bus) = master(vec![s]);
    i2c.transaction(0x29, &mut []).unwrap();
    assert_eq!(bus.borrow().trace.len(), 1);
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
    let bus = sim_wire::shared(Bus::new(vec![RegSlave::new(0x29)]));
    let fast = Timing { low: 52, high_min: 24, period: 100, buf: 52, stretch_timeout: 80_000 };
    let mut i2c = BitBangI2c::new(SimPins(bus.clone()), SimClock(bus.clone()), fast);
    i2c.write(0x29, &[1, 2]).unwrap();
    let v = check_timing(&bus.borrow().trace, &Limits::fast_mode(CPU_HZ));
    assert!(v.iter().any(|m| m.starts_with("tLOW")), "{v:?}");
    assert!(v.iter().any(|m| m.starts_with("SCL period")), "{v:?}");
}
