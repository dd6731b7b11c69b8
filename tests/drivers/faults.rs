//! Fault injection on the simulated bus: every transaction of every
//! bring-up fails in turn; a single failure is absorbed by the transaction
//! retry (`driver::bus::Retry`), one more failure in a row than it retries
//! gives an error, never a panic (overflow checks are on in test builds),
//! and a later bring-up works. Chips that disappear and come back, a stuck
//! bus, a missing chip.

use paperbot::config;
use paperbot::driver::lidar::bring_up;
use paperbot::driver::{HeadingSensor, MagCalibrate, RangeSensor, SensorError};
use paperbot::sim::bus::{Fault, LoggedOp};
use paperbot::sim::sensors::SimSensors;

const FAILING: [Fault; 3] = [Fault::Nack, Fault::Timeout, Fault::SdaStuck];
const CORRUPTING: [Fault; 3] = [Fault::Corrupt(0xFF), Fault::Corrupt(0x80), Fault::Corrupt(0x01)];
/// Attempts per transaction: the first and its retries.
const ATTEMPTS: u32 = config::i2c::TRANSACTION_RETRIES as u32 + 1;

/// Makes transactions `at..at + n` fail with `fault`.
fn inject_run(sim: &SimSensors, at: u32, n: u32, fault: Fault) {
    for k in 0..n {
        sim.bus.inject(at + k, fault);
    }
}

/// Transactions a clean bring-up of both lidars takes.
fn lidar_bring_up_len() -> u32 {
    let sim = SimSensors::new();
    let (mut f, mut r, _) = sim.drivers();
    assert!(bring_up(&mut f, &mut r).all_ok());
    sim.bus.transactions()
}

fn compass_bring_up_len() -> u32 {
    let sim = SimSensors::new();
    let (_, _, mut c) = sim.drivers();
    c.reinit().unwrap();
    sim.bus.transactions()
}

/// Both lidars give the fake's distances.
fn lidars_read_right(sim: &SimSensors, f: &mut impl RangeSensor, r: &mut impl RangeSensor) {
    sim.front.borrow_mut().set_distance_mm(321);
    sim.right.borrow_mut().set_distance_mm(123);
    sim.clock.advance_ms(70);
    assert_eq!(f.poll().unwrap().raw_mm, 321);
    assert_eq!(r.poll().unwrap().raw_mm, 123);
}

#[test]
fn every_lidar_bring_up_transaction_failing_once_is_retried() {
    let n = lidar_bring_up_len();
    for at in 0..n {
        for fault in FAILING {
            let sim = SimSensors::new();
            let (mut f, mut r, _) = sim.drivers();
            inject_run(&sim, at, ATTEMPTS - 1, fault);
            sim.bus.set_logging(true);
            let status = bring_up(&mut f, &mut r);
            // the address change is not retried (not idempotent: the chip
            // may have moved): the lidar is brought up again from a reset
            let log = sim.bus.log();
            let txn = log.iter().find(|t| t.index == at).unwrap();
            let moves = matches!(txn.ops.as_slice(), [LoggedOp::Write(w)] if w.first() == Some(&0x8A));
            if moves {
                assert!(!status.all_ok(), "{at} {fault:?}");
                if status.front.is_err() {
                    f.reinit().unwrap();
                } else {
                    r.reinit().unwrap();
                }
                lidars_read_right(&sim, &mut f, &mut r);
                continue;
            }
            assert!(status.all_ok(), "transaction {at} failing with {fault:?}: {status:?}");
            assert_eq!(sim.bus.transactions(), n + ATTEMPTS - 1, "one more transaction per failure");
            assert_eq!(sim.bus.collisions(), 0);
            lidars_read_right(&sim, &mut f, &mut r);
        }
    }
}

#[test]
fn every_lidar_bring_up_transaction_failing_every_retry_gives_an_error_and_a_retry_works() {
    let n = lidar_bring_up_len();
    assert!(n > 200, "{n}");
    for at in 0..n {
        for fault in FAILING {
            let sim = SimSensors::new();
            let (mut f, mut r, _) = sim.drivers();
            inject_run(&sim, at, ATTEMPTS, fault);
            let status = bring_up(&mut f, &mut r);
            assert!(!status.all_ok(), "transaction {at} failing with {fault:?} went unnoticed");
            // Exactly one of them failed; it is held in reset, the other runs.
            assert!(status.front.is_ok() != status.right.is_ok(), "{at} {fault:?} {status:?}");
            assert_eq!(sim.front.borrow().is_powered(), status.front.is_ok());
            assert_eq!(sim.right.borrow().is_powered(), status.right.is_ok());
            if status.front.is_err() {
                f.reinit().unwrap();
            } else {
                r.reinit().unwrap();
            }
            assert_eq!(sim.bus.collisions(), 0);
            lidars_read_right(&sim, &mut f, &mut r);
        }
    }
}

#[test]
fn corrupted_lidar_bring_up_transfers_never_panic_and_a_retry_works() {
    let n = lidar_bring_up_len();
    for at in 0..n {
        for fault in CORRUPTING {
            let sim = SimSensors::new();
            let (mut f, mut r, _) = sim.drivers();
            sim.bus.inject(at, fault);
            let status = bring_up(&mut f, &mut r);
            // A corrupted byte may or may not be noticed; a retry of both
            // puts everything right either way.
            let _ = status;
            f.reinit().unwrap();
            r.reinit().unwrap();
            lidars_read_right(&sim, &mut f, &mut r);
        }
    }
}

#[test]
fn every_compass_bring_up_transaction_failing_once_is_retried() {
    let n = compass_bring_up_len();
    for at in 0..n {
        for fault in FAILING {
            let sim = SimSensors::new();
            let (_, _, mut c) = sim.drivers();
            inject_run(&sim, at, ATTEMPTS - 1, fault);
            assert_eq!(c.reinit(), Ok(()), "transaction {at} failing with {fault:?}");
            assert_eq!(sim.bus.transactions(), n + ATTEMPTS - 1);
            assert_eq!(c.asa(), sim.mpu.borrow().ak.asa());
        }
    }
}

#[test]
fn every_compass_bring_up_transaction_failing_every_retry_gives_an_error_and_a_retry_works() {
    let n = compass_bring_up_len();
    assert_eq!(n, 13, "who, reset, 4 MPU writes, WIA, 4 mode changes, ASA twice");
    for at in 0..n {
        for fault in FAILING.into_iter().chain(CORRUPTING) {
            let sim = SimSensors::new();
            let (_, _, mut c) = sim.drivers();
            match fault {
                Fault::Corrupt(_) => sim.bus.inject(at, fault),
                _ => inject_run(&sim, at, ATTEMPTS, fault),
            }
            let first = c.reinit();
            if matches!(fault, Fault::Corrupt(_)) {
                // A corrupted identity, ASA or register value: noticed
                // (identity, the ASA read twice) or harmless (a write's
                // reply). Never a wrong ASA in use.
                if first.is_ok() {
                    assert_eq!(c.asa(), sim.mpu.borrow().ak.asa(), "{at} {fault:?}");
                }
            } else {
                assert!(first.is_err(), "transaction {at} failing with {fault:?} went unnoticed");
                assert_eq!(c.poll(), Err(nb::Error::Other(SensorError::NotReady)));
            }
            c.reinit().unwrap();
            assert_eq!(c.asa(), sim.mpu.borrow().ak.asa());
            sim.mpu.borrow_mut().ak.set_field([100, -50, 30]);
            sim.clock.advance_ms(10);
            assert_eq!(c.poll().unwrap().raw.x, 100);
        }
    }
}

#[test]
fn a_lidar_that_disappears_is_missing_until_reinitialised() {
    let sim = SimSensors::new();
    let (mut f, mut r, _) = sim.drivers();
    assert!(bring_up(&mut f, &mut r).all_ok());
    sim.front.borrow_mut().set_present(false);
    sim.clock.advance_ms(40);
    assert_eq!(f.poll(), Err(nb::Error::Other(SensorError::Missing)));
    assert_eq!(f.reinit(), Err(SensorError::Missing));
    // Back (a power cycle: at 0x29 again), still missing at its address.
    sim.front.borrow_mut().set_present(true);
    sim.clock.advance_ms(40);
    assert_eq!(f.poll(), Err(nb::Error::Other(SensorError::NotReady)), "the failed reinit left it down");
    f.reinit().unwrap();
    assert_eq!(sim.front.borrow().address(), config::i2c::FRONT_LIDAR_ADDR);
    lidars_read_right(&sim, &mut f, &mut r);
}

#[test]
fn a_power_cycled_lidar_is_found_again_by_reinit() {
    let sim = SimSensors::new();
    let (mut f, mut r, _) = sim.drivers();
    assert!(bring_up(&mut f, &mut r).all_ok());
    // Brown-out: the chip is back at 0x29 while the driver still thinks it
    // runs at its own address.
    sim.right.borrow_mut().set_present(false);
    sim.right.borrow_mut().set_present(true);
    sim.clock.advance_ms(40);
    assert_eq!(r.poll(), Err(nb::Error::Other(SensorError::Missing)));
    r.reinit().unwrap();
    lidars_read_right(&sim, &mut f, &mut r);
}

#[test]
fn a_compass_that_disappears_is_missing_until_reinitialised() {
    let sim = SimSensors::new();
    let (_, _, mut c) = sim.drivers();
    c.reinit().unwrap();
    sim.mpu.borrow_mut().set_present(false);
    sim.clock.advance_ms(10);
    assert_eq!(c.poll(), Err(nb::Error::Other(SensorError::Missing)));
    assert_eq!(c.reinit(), Err(SensorError::Missing));
    sim.mpu.borrow_mut().set_present(true);
    // Power-cycled: bypass is off, the AK8963 is not on the bus.
    assert_eq!(c.poll(), Err(nb::Error::Other(SensorError::NotReady)));
    c.reinit().unwrap();
    sim.mpu.borrow_mut().ak.set_field([10, 20, 30]);
    sim.clock.advance_ms(10);
    assert_eq!(c.poll().unwrap().raw.y, 20);
}

#[test]
fn a_stuck_bus_is_a_bus_error_and_reads_resume_when_it_frees() {
    let sim = SimSensors::new();
    let (mut f, mut r, mut c) = sim.drivers();
    assert!(bring_up(&mut f, &mut r).all_ok());
    c.reinit().unwrap();
    sim.bus.set_sda_stuck(true);
    sim.clock.advance_ms(40);
    assert_eq!(f.poll(), Err(nb::Error::Other(SensorError::Bus)));
    assert_eq!(r.poll(), Err(nb::Error::Other(SensorError::Bus)));
    assert_eq!(c.poll(), Err(nb::Error::Other(SensorError::Bus)));
    sim.bus.set_sda_stuck(false);
    lidars_read_right(&sim, &mut f, &mut r);
    assert!(c.poll().is_ok());
}

#[test]
fn missing_or_wrong_chips_are_reported_as_missing() {
    let sim = SimSensors::new();
    let (mut f, mut r, mut c) = sim.drivers();
    sim.front.borrow_mut().set_present(false);
    let status = bring_up(&mut f, &mut r);
    assert_eq!(status.front, Err(SensorError::Missing));
    assert_eq!(status.right, Ok(()));
    sim.bus.set_nack_address(config::i2c::MPU9250_ADDR, true);
    assert_eq!(c.reinit(), Err(SensorError::Missing));
    sim.bus.set_nack_address(config::i2c::MPU9250_ADDR, false);
    // An MPU6500 (no magnetometer) answers 0x70.
    sim.mpu.borrow_mut().set_who_am_i(0x70);
    assert_eq!(c.reinit(), Err(SensorError::Missing));
    sim.mpu.borrow_mut().set_who_am_i(0x71);
    c.reinit().unwrap();
}

#[test]
fn a_dropped_result_register_read_loses_one_reading_only() {
    let sim = SimSensors::new();
    let (mut f, mut r, _) = sim.drivers();
    assert!(bring_up(&mut f, &mut r).all_ok());
    sim.clock.advance_ms(34);
    // status read ok, range read fails every attempt: the result stays pending.
    let t = sim.bus.transactions();
    inject_run(&sim, t + 1, ATTEMPTS, Fault::Timeout);
    assert_eq!(f.poll(), Err(nb::Error::Other(SensorError::Bus)));
    sim.front.borrow_mut().set_distance_mm(8191);
    assert_eq!(f.poll().unwrap().raw_mm, 8190, "the pending result, not a new one");
}

#[test]
fn a_failed_poll_transaction_is_retried_and_the_reading_delivered() {
    let sim = SimSensors::new();
    let (mut f, mut r, mut c) = sim.drivers();
    assert!(bring_up(&mut f, &mut r).all_ok());
    c.reinit().unwrap();
    sim.front.borrow_mut().set_distance_mm(444);
    sim.mpu.borrow_mut().ak.set_field([7, 8, 9]);
    sim.clock.advance_ms(34);
    // each of the lidar's three transfers (status, range, interrupt clear),
    // then the compass's two (ST1, data and ST2), failing all but the last
    // attempt
    for step in 0..3 {
        for fault in FAILING {
            let t = sim.bus.transactions();
            inject_run(&sim, t + step, ATTEMPTS - 1, fault);
            assert_eq!(f.poll().map(|s| s.raw_mm), Ok(444), "lidar step {step} {fault:?}");
            assert_eq!(sim.bus.transactions(), t + 3 + ATTEMPTS - 1);
            sim.clock.advance_ms(34);
        }
    }
    for step in 0..2 {
        for fault in FAILING {
            let t = sim.bus.transactions();
            inject_run(&sim, t + step, ATTEMPTS - 1, fault);
            assert_eq!(c.poll().map(|s| s.raw.y), Ok(8), "compass step {step} {fault:?}");
            assert_eq!(sim.bus.transactions(), t + 2 + ATTEMPTS - 1);
            sim.clock.advance_ms(10);
        }
    }
}
