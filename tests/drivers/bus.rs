//! The shared-bus pieces: the embedded-hal 0.2 adapter for the mpu9250
//! crate, the error classes, the poll guard, and the simulated bus's fault
//! injection and routing.

use std::cell::RefCell;

use embedded_hal::i2c::{ErrorKind, I2c, NoAcknowledgeSource};
use embedded_hal_02::blocking::i2c::{Read as _, Write as _, WriteRead as _};
use embedded_hal_bus::i2c::RefCellDevice;
use embedded_hal_mock::eh1::i2c::{Mock as I2cMock, Transaction as I2cT};
use paperbot::config;
use paperbot::driver::bus::{classify, Eh0Compat, GuardError, PollGuard, RegisterCheck, Retry};
use paperbot::driver::SensorError;
use paperbot::sim::bus::{Fault, LoggedOp, SimBus, SimBusError};
use paperbot::sim::sensors::SimSensors;

#[test]
fn eh0_adapter_forwards_each_call_unchanged() {
    let mut mock = I2cMock::new(&[
        I2cT::write(0x68, vec![0x6B, 0x80]),
        I2cT::write_read(0x68, vec![0x75], vec![0x71]),
        I2cT::read(0x0C, vec![1, 2]),
        I2cT::write(0x68, vec![0x37, 0x02]).with_error(ErrorKind::Bus),
    ]);
    let mut eh0 = Eh0Compat(&mut mock);
    eh0.write(0x68, &[0x6B, 0x80]).unwrap();
    let mut who = [0u8; 1];
    eh0.write_read(0x68, &[0x75], &mut who).unwrap();
    assert_eq!(who, [0x71]);
    let mut two = [0u8; 2];
    eh0.read(0x0C, &mut two).unwrap();
    assert_eq!(two, [1, 2]);
    assert!(eh0.write(0x68, &[0x37, 0x02]).is_err());
    mock.done();
}

#[test]
fn error_classes() {
    let cases = [
        (ErrorKind::NoAcknowledge(NoAcknowledgeSource::Address), SensorError::Missing),
        (ErrorKind::NoAcknowledge(NoAcknowledgeSource::Data), SensorError::Bus),
        (ErrorKind::NoAcknowledge(NoAcknowledgeSource::Unknown), SensorError::Bus),
        (ErrorKind::Bus, SensorError::Bus),
        (ErrorKind::ArbitrationLoss, SensorError::Bus),
        (ErrorKind::Overrun, SensorError::Bus),
        (ErrorKind::Other, SensorError::Bus),
    ];
    for (kind, want) in cases {
        // embedded-hal-mock reports an I2C error as ErrorKind itself.
        assert_eq!(classify(&kind), want, "{kind:?}");
    }
    assert_eq!(GuardError::<ErrorKind>::PollLimit.sensor_error(), SensorError::Timeout);
    assert_eq!(GuardError::<ErrorKind>::Implausible.sensor_error(), SensorError::Bus);
    assert_eq!(classify(&SimBusError::AddressNack(0x29)), SensorError::Missing);
    assert_eq!(classify(&SimBusError::SdaStuck), SensorError::Bus);
    assert_eq!(classify(&SimBusError::Timeout), SensorError::Bus);
}

struct RejectFf;
impl RegisterCheck for RejectFf {
    fn plausible(&mut self, _reg: u8, data: &[u8]) -> bool {
        !data.contains(&0xFF)
    }
}

#[test]
fn poll_guard_limits_consecutive_polls_and_refuses_implausible_values() {
    let poll = |v: u8| I2cT::write_read(0x29, vec![0x13], vec![v]);
    let mut mock = I2cMock::new(&[
        poll(0),
        poll(0),
        poll(0),
        // a different transfer resets the count
        I2cT::write_read(0x29, vec![0x00, 0x01], vec![0]),
        poll(0),
        poll(0),
        poll(0),
        // the fourth consecutive poll is refused without a transfer
        I2cT::write_read(0x29, vec![0x50], vec![0xFF]),
        I2cT::write_read(0x29, vec![0x50], vec![0x06]).with_error(ErrorKind::Bus),
    ]);
    let mut g = PollGuard::new(&mut mock, RejectFf, 3);
    let mut b = [0u8; 1];
    for _ in 0..3 {
        g.write_read(0x29, &[0x13], &mut b).unwrap();
    }
    g.write_read(0x29, &[0x00, 0x01], &mut b).unwrap();
    for _ in 0..3 {
        g.write_read(0x29, &[0x13], &mut b).unwrap();
    }
    assert_eq!(g.write_read(0x29, &[0x13], &mut b), Err(GuardError::PollLimit));
    assert_eq!(g.write_read(0x29, &[0x50], &mut b), Err(GuardError::Implausible));
    assert_eq!(g.write_read(0x29, &[0x50], &mut b), Err(GuardError::Bus(ErrorKind::Bus)));
    mock.done();
}

#[test]
fn sim_bus_faults_hit_the_numbered_transaction_only() {
    let sim = SimSensors::new();
    sim.clock.advance_ms(2);
    sim.right.borrow_mut().set_present(false);
    let mut bus = sim.bus.clone();
    bus.set_logging(true);
    let mut id = [0u8; 1];
    let base = bus.transactions();
    bus.inject(base + 1, Fault::Nack);
    bus.inject(base + 2, Fault::Corrupt(0x0F));
    bus.inject(base + 3, Fault::Timeout);
    bus.inject(base + 4, Fault::SdaStuck);
    assert_eq!(bus.write_read(0x29, &[0xC0], &mut id), Ok(()));
    assert_eq!(id, [0xEE]);
    assert_eq!(bus.write_read(0x29, &[0xC0], &mut id), Err(SimBusError::AddressNack(0x29)));
    assert_eq!(bus.write_read(0x29, &[0xC0], &mut id), Ok(()));
    assert_eq!(id, [0xE1], "corrupted");
    assert_eq!(bus.write_read(0x29, &[0xC0], &mut id), Err(SimBusError::Timeout));
    assert_eq!(bus.write_read(0x29, &[0xC0], &mut id), Err(SimBusError::SdaStuck));
    assert_eq!(bus.write_read(0x29, &[0xC0], &mut id), Ok(()));
    assert_eq!(id, [0xEE]);
    // Nobody at an empty address; a persistent NACK.
    assert_eq!(bus.write(0x50, &[0]), Err(SimBusError::AddressNack(0x50)));
    bus.set_nack_address(0x29, true);
    assert_eq!(bus.write_read(0x29, &[0xC0], &mut id), Err(SimBusError::AddressNack(0x29)));
    bus.set_nack_address(0x29, false);
    let log = bus.log();
    assert_eq!(log.len(), 8);
    assert_eq!(log[0].ops, vec![LoggedOp::Write(vec![0xC0]), LoggedOp::Read(vec![0xEE])]);
    assert_eq!(log[1].result, Err(SimBusError::AddressNack(0x29)));
}

#[test]
fn the_ak8963_is_only_on_the_bus_in_bypass_mode() {
    let sim = SimSensors::new();
    let mut bus = sim.bus.clone();
    let mut wia = [0u8; 1];
    assert_eq!(bus.write_read(0x0C, &[0x00], &mut wia), Err(SimBusError::AddressNack(0x0C)));
    bus.write(0x68, &[0x37, 0x02]).unwrap();
    bus.write_read(0x0C, &[0x00], &mut wia).unwrap();
    assert_eq!(wia, [0x48]);
    // The MPU's own I2C master on: bypass has no effect.
    bus.write(0x68, &[0x6A, 0x20]).unwrap();
    assert_eq!(bus.write_read(0x0C, &[0x00], &mut wia), Err(SimBusError::AddressNack(0x0C)));
    // A device reset clears bypass.
    bus.write(0x68, &[0x6A, 0x00]).unwrap();
    bus.write(0x68, &[0x6B, 0x80]).unwrap();
    assert!(!sim.mpu.borrow().bypass());
    assert_eq!(sim.mpu.borrow().resets(), 1);
}

#[test]
fn the_fake_ak8963_follows_its_datasheet() {
    let sim = SimSensors::new();
    let mut bus = sim.bus.clone();
    bus.write(0x68, &[0x37, 0x02]).unwrap();
    let mut asa = [0u8; 3];
    // Fuse ROM only readable in fuse-ROM mode.
    bus.write_read(0x0C, &[0x10], &mut asa).unwrap();
    assert_eq!(asa, [0, 0, 0]);
    bus.write(0x0C, &[0x0A, 0x0F]).unwrap();
    bus.write_read(0x0C, &[0x10], &mut asa).unwrap();
    assert_eq!(asa, sim.mpu.borrow().ak.asa());
    // Fuse ROM -> continuous without power-down in between: ignored.
    bus.write(0x0C, &[0x0A, 0x16]).unwrap();
    assert_eq!(sim.mpu.borrow().ak.mode_violations(), 1);
    bus.write(0x0C, &[0x0A, 0x00]).unwrap();
    bus.write(0x0C, &[0x0A, 0x06]).unwrap(); // 14-bit, 100 Hz
    sim.mpu.borrow_mut().ak.set_field([400, -800, 1200]);
    let mut st1 = [0u8; 1];
    bus.write_read(0x0C, &[0x02], &mut st1).unwrap();
    assert_eq!(st1, [0], "no sample before 10 ms");
    sim.clock.advance_ms(10);
    bus.write_read(0x0C, &[0x02], &mut st1).unwrap();
    assert_eq!(st1, [1]);
    let mut d = [0u8; 7];
    bus.write_read(0x0C, &[0x03], &mut d).unwrap();
    assert_eq!(i16::from_le_bytes([d[0], d[1]]), 100, "14-bit: a quarter");
    assert_eq!(d[6] & 0x10, 0, "BITM clear in 14-bit mode");
    bus.write_read(0x0C, &[0x02], &mut st1).unwrap();
    assert_eq!(st1, [0], "ST2 read clears DRDY");
    // Two samples unread: data overrun.
    sim.clock.advance_ms(10);
    bus.write_read(0x0C, &[0x02], &mut st1).unwrap();
    sim.clock.advance_ms(10);
    bus.write_read(0x0C, &[0x02], &mut st1).unwrap();
    assert_eq!(st1, [0x03]);
    // Overflow by field size.
    sim.mpu.borrow_mut().ak.set_field([20000, 10000, 5000]);
    sim.clock.advance_ms(10);
    bus.write_read(0x0C, &[0x02], &mut st1).unwrap();
    bus.write_read(0x0C, &[0x03], &mut d).unwrap();
    assert_eq!(d[6] & 0x08, 0x08);
}

#[test]
fn refcell_devices_share_one_sim_bus() {
    let sim = SimSensors::new();
    sim.clock.advance_ms(2);
    sim.right.borrow_mut().set_present(false);
    let cell = RefCell::new(sim.bus.clone());
    let mut a = RefCellDevice::new(&cell);
    let mut b = RefCellDevice::new(&cell);
    let mut id = [0u8; 1];
    a.write_read(0x29, &[0xC0], &mut id).unwrap();
    b.write_read(0x68, &[0x75], &mut id).unwrap();
    assert_eq!(id, [0x71]);
    assert_eq!(sim.bus.transactions(), 2);
    let _unused: SimBus = cell.into_inner();
}

#[test]
fn retry_runs_a_failed_transaction_again_up_to_its_limit() {
    let n = usize::from(config::i2c::TRANSACTION_RETRIES);
    assert!(n >= 1);
    let nack = ErrorKind::NoAcknowledge(NoAcknowledgeSource::Address);
    // each method: n failures then a success (same arguments every time),
    // then n + 1 failures: the last error comes back
    let mut script = Vec::new();
    script.extend(vec![I2cT::write_read(0x29, vec![0x13], vec![0]).with_error(ErrorKind::Bus); n]);
    script.push(I2cT::write_read(0x29, vec![0x13], vec![0x07]));
    script.extend(vec![I2cT::write(0x16, vec![0x0B, 0x01]).with_error(nack); n]);
    script.push(I2cT::write(0x16, vec![0x0B, 0x01]));
    script.extend(vec![I2cT::read(0x0C, vec![0, 0]).with_error(ErrorKind::ArbitrationLoss); n]);
    script.push(I2cT::read(0x0C, vec![5, 6]));
    script.extend(vec![I2cT::write(0x16, vec![0x0B, 0x01]).with_error(nack); n + 1]);
    // the excepted register: one attempt only
    script.push(I2cT::write(0x29, vec![0x8A, 0x16]).with_error(ErrorKind::Other));
    script.push(I2cT::write(0x29, vec![0x8B, 0x16]));
    let mut mock = I2cMock::new(&script);
    let mut bus = Retry::with_config(&mut mock).except_writes_to(0x8A);
    let mut status = [0u8; 1];
    bus.write_read(0x29, &[0x13], &mut status).unwrap();
    assert_eq!(status, [0x07]);
    bus.write(0x16, &[0x0B, 0x01]).unwrap();
    let mut two = [0u8; 2];
    bus.read(0x0C, &mut two).unwrap();
    assert_eq!(two, [5, 6]);
    assert_eq!(bus.write(0x16, &[0x0B, 0x01]), Err(nack));
    assert_eq!(bus.retried(), 4 * n as u32);
    assert_eq!(bus.write(0x29, &[0x8A, 0x16]), Err(ErrorKind::Other));
    bus.write(0x29, &[0x8B, 0x16]).unwrap();
    assert_eq!(bus.retried(), 4 * n as u32);
    mock.done();
}

#[test]
fn retry_zero_is_a_pass_through() {
    let mut mock = I2cMock::new(&[I2cT::write(0x16, vec![1]).with_error(ErrorKind::Bus), I2cT::write(0x16, vec![2])]);
    let mut bus = Retry::new(&mut mock, 0);
    assert_eq!(bus.write(0x16, &[1]), Err(ErrorKind::Bus));
    bus.write(0x16, &[2]).unwrap();
    assert_eq!(bus.retried(), 0);
    mock.done();
}

#[test]
fn sim_bus_one_shot_stuck_sda_clears_after_its_transaction_and_failures_are_counted() {
    // as the board's master frees the bus (nine clocks) after a failure
    let mut bus = SimBus::new();
    let base = bus.transactions();
    bus.inject(base, Fault::SdaStuck);
    assert_eq!(bus.write(0x29, &[0]), Err(SimBusError::SdaStuck));
    assert_eq!(bus.write(0x29, &[0]), Err(SimBusError::AddressNack(0x29)), "bus free again: nobody there");
    assert_eq!(bus.failures(), 2);
    // the persistent one holds until released
    bus.set_sda_stuck(true);
    for _ in 0..3 {
        assert_eq!(bus.write(0x29, &[0]), Err(SimBusError::SdaStuck));
    }
    bus.set_sda_stuck(false);
    assert_eq!(bus.write(0x29, &[0]), Err(SimBusError::AddressNack(0x29)));
    assert_eq!(bus.failures(), 6);
}
