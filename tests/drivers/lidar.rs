//! The lidar driver against embedded-hal-mock scripts: the exact bring-up
//! with the XSHUT transitions and waits, the address change, range reads,
//! and every error path. Every mock ends with `.done()`.

use crate::common;
use std::cell::RefCell;
use std::rc::Rc;

use common::i2c::{retried, NACK};
use common::vl53l0x_script::{
    address_change_index, bring_up_script, done, new_front_lidar, read_script, waits, Kind, BRING_UP,
};
use embedded_hal::digital::{ErrorType as PinErrorType, OutputPin};
use embedded_hal::i2c::{ErrorKind, ErrorType, I2c, NoAcknowledgeSource, Operation};
use embedded_hal_mock::eh1::delay::CheckedDelay;
use embedded_hal_mock::eh1::digital::{Mock as PinMock, State, Transaction as PinT};
use embedded_hal_mock::eh1::i2c::{Mock as I2cMock, Transaction as I2cT};
use paperbot::config::{self, i2c::FRONT_LIDAR_ADDR as FRONT, i2c::RIGHT_LIDAR_ADDR as RIGHT};
use paperbot::driver::lidar::{bring_up, Lidar};
use paperbot::driver::{LidarSample, RangeSensor, SensorError};
use paperbot::model::lidar::Range;

/// Shared event log: pin edges and bus transfers in the order they happen.
type Log = Rc<RefCell<Vec<String>>>;

struct RecPin(PinMock, &'static str, Log);
impl PinErrorType for RecPin {
    type Error = <PinMock as PinErrorType>::Error;
}
impl OutputPin for RecPin {
    fn set_low(&mut self) -> Result<(), Self::Error> {
        self.2.borrow_mut().push(format!("{} low", self.1));
        self.0.set_low()
    }
    fn set_high(&mut self) -> Result<(), Self::Error> {
        self.2.borrow_mut().push(format!("{} high", self.1));
        self.0.set_high()
    }
}

struct RecI2c(I2cMock, Log);
impl ErrorType for RecI2c {
    type Error = <I2cMock as ErrorType>::Error;
}
impl I2c for RecI2c {
    fn write(&mut self, a: u8, w: &[u8]) -> Result<(), Self::Error> {
        self.1.borrow_mut().push(format!("i2c {a:#04x} {w:02x?}"));
        self.0.write(a, w)
    }
    fn write_read(&mut self, a: u8, w: &[u8], r: &mut [u8]) -> Result<(), Self::Error> {
        self.1.borrow_mut().push(format!("i2c {a:#04x} {w:02x?}"));
        self.0.write_read(a, w, r)
    }
    fn read(&mut self, a: u8, r: &mut [u8]) -> Result<(), Self::Error> {
        self.0.read(a, r)
    }
    fn transaction(&mut self, a: u8, ops: &mut [Operation<'_>]) -> Result<(), Self::Error> {
        self.0.transaction(a, ops)
    }
}

#[test]
fn pair_bring_up_holds_the_right_lidar_in_reset_until_the_front_one_has_moved() {
    let log: Log = Rc::default();
    let i2c = I2cMock::new(&[bring_up_script(FRONT), bring_up_script(RIGHT)].concat());
    let pins = [State::Low, State::Low, State::High].map(PinT::set);
    let mut front = Lidar::front(
        RecI2c(i2c.clone(), log.clone()),
        RecPin(PinMock::new(&pins), "front", log.clone()),
        CheckedDelay::new(&waits()),
    );
    let mut right = Lidar::right(
        RecI2c(i2c.clone(), log.clone()),
        RecPin(PinMock::new(&pins), "right", log.clone()),
        CheckedDelay::new(&waits()),
    );
    let status = bring_up(&mut front, &mut right);
    assert_eq!((status.front, status.right), (Ok(()), Ok(())));
    assert!(front.is_running() && right.is_running());

    let log = log.borrow();
    let pos = |e: &str| log.iter().position(|l| l == e).unwrap_or_else(|| panic!("no {e:?} in {log:#?}"));
    let last = |e: &str| log.iter().rposition(|l| l == e).unwrap();
    let first_i2c = log.iter().position(|l| l.starts_with("i2c")).unwrap();
    let front_moves = pos(&format!("i2c 0x29 [8a, {FRONT:02x}]"));
    let right_moves = pos(&format!("i2c 0x29 [8a, {RIGHT:02x}]"));
    // Both in reset before anything talks on the bus, front released first.
    assert!(pos("front low") < first_i2c && pos("right low") < first_i2c);
    assert!(last("front high") < first_i2c);
    // The right one stays in reset until the front one has left 0x29...
    assert!(front_moves < last("right high"));
    // ...and only then does anyone talk to 0x29 again.
    let at_boot_addr: Vec<usize> =
        log.iter().enumerate().filter(|(_, l)| l.starts_with("i2c 0x29")).map(|(i, _)| i).collect();
    assert!(at_boot_addr.iter().all(|&i| i <= front_moves || i > last("right high")));
    assert!(right_moves > last("right high"));
    drop(log);

    let (mut i1, RecPin(mut p1, ..), mut d1) = front.release();
    let (_, RecPin(mut p2, ..), mut d2) = right.release();
    i1.0.done();
    p1.done();
    p2.done();
    d1.done();
    d2.done();
}

/// A front lidar brought up on a mock, with `then` scripted after.
#[test]
fn reinit_is_reset_boot_wait_init_and_address_change() {
    // The whole of `running_front`: XSHUT low, 10 ms, high, 2 ms, the crate's
    // init at 0x29, the move, then budget and start at the new address.
    let (lidar, _) = new_front_lidar(&[]);
    assert_eq!(BRING_UP.get(address_change_index()).map(|s| s.write), Some(&[0x8A, 0x16][..]));
    assert!(BRING_UP[..address_change_index()].iter().all(|s| s.at == common::vl53l0x_script::At::Boot));
    assert!(BRING_UP[address_change_index() + 1..].iter().all(|s| s.at == common::vl53l0x_script::At::New));
    // Last steps: continuous back-to-back start.
    assert_eq!(BRING_UP.last().map(|s| (s.kind, s.write)), Some((Kind::Set, &[0x00, 0x02][..])));
    done(lidar);
}

#[test]
fn range_reads_go_through_the_model() {
    let script = [
        read_script(FRONT, 0x04, 300),
        vec![I2cT::write_read(FRONT, vec![0x13], vec![0x00])],
        read_script(FRONT, 0x04, 8190),
        read_script(FRONT, 0x07, 10),
    ]
    .concat();
    let (mut lidar, _) = new_front_lidar(&script);
    assert_eq!(lidar.poll(), Ok(LidarSample { raw_mm: 300, range: config::lidar::FRONT.range(300) }));
    match config::lidar::FRONT.range(300) {
        Range::Target(d) => assert!((d.to_mm_f64() - (0.9849 * 300.0 - 56.2563)).abs() < 0.01),
        other => panic!("{other:?}"),
    }
    assert_eq!(lidar.poll(), Err(nb::Error::WouldBlock));
    assert_eq!(lidar.poll().map(|s| s.range), Ok(Range::NoTarget));
    assert_eq!(lidar.poll().map(|s| s.range), Ok(Range::TooClose));
    done(lidar);
}

#[test]
fn read_errors_are_typed() {
    let cases: [(usize, ErrorKind, SensorError); 4] = [
        (0, NACK, SensorError::Missing),
        (0, ErrorKind::Bus, SensorError::Bus),
        (1, ErrorKind::ArbitrationLoss, SensorError::Bus),
        (2, ErrorKind::NoAcknowledge(NoAcknowledgeSource::Data), SensorError::Bus),
    ];
    for (step, kind, want) in cases {
        let mut script = read_script(FRONT, 0x04, 500);
        script.truncate(step + 1);
        let failing = script.pop().unwrap().with_error(kind);
        script.extend(retried(failing));
        let (mut lidar, _) = new_front_lidar(&script);
        assert_eq!(lidar.poll(), Err(nb::Error::Other(want)), "step {step} {kind:?}");
        done(lidar);
    }
}

#[test]
fn a_lidar_not_brought_up_is_not_ready_and_touches_nothing() {
    let i2c = I2cMock::new(&[]);
    let mut lidar = Lidar::front(i2c, PinMock::new(&[]), CheckedDelay::new(&[]));
    assert_eq!(lidar.poll(), Err(nb::Error::Other(SensorError::NotReady)));
    done(lidar);
}

/// Bring-up scripts that fail at `step` (with `kind`, or with the given
/// reply), and what the driver must say. The lidar is left in reset.
fn failing_bring_up(step: usize, fail: Vec<I2cT>, want: SensorError) {
    let mut script = bring_up_script(FRONT);
    script.truncate(step);
    script.extend(fail);
    let i2c = I2cMock::new(&script);
    let pin = PinMock::new(&[PinT::set(State::Low), PinT::set(State::High), PinT::set(State::Low)]);
    let mut lidar = Lidar::front(i2c, pin, CheckedDelay::new(&waits()));
    assert_eq!(lidar.reinit(), Err(want), "step {step}");
    assert!(!lidar.is_running());
    assert_eq!(lidar.poll(), Err(nb::Error::Other(SensorError::NotReady)));
    done(lidar);
}

#[test]
fn bring_up_errors_are_typed_and_leave_the_lidar_in_reset() {
    // No chip at 0x29.
    failing_bring_up(0, retried(I2cT::write_read(0x29, vec![0xC0], vec![0]).with_error(NACK)), SensorError::Missing);
    // Something else at 0x29.
    failing_bring_up(0, vec![I2cT::write_read(0x29, vec![0xC0], vec![0x42])], SensorError::Missing);
    // A bus error in the middle of the tuning table.
    failing_bring_up(40, retried(bring_up_script(FRONT).remove(40).with_error(ErrorKind::Bus)), SensorError::Bus);
    // The address change not acknowledged: not retried (the chip may have
    // moved), the bring-up fails at once.
    let i = address_change_index();
    failing_bring_up(i, vec![I2cT::write(0x29, vec![0x8A, FRONT]).with_error(ErrorKind::Bus)], SensorError::Bus);
    // The chip gone right after the move.
    failing_bring_up(i + 1, retried(bring_up_script(FRONT).remove(i + 1).with_error(NACK)), SensorError::Missing);
}

/// Index of the step that polls the SPAD info (page 7, 0x83) until ready.
fn spad_poll_index() -> usize {
    BRING_UP.iter().position(|s| s.kind == Kind::Set && s.write == [0x83, 0x00]).unwrap() + 1
}

#[test]
fn a_chip_that_never_gets_ready_times_out_after_the_poll_limit() {
    let i = spad_poll_index();
    // The SPAD handshake polls 0x83 until it reads nonzero.
    assert_eq!((BRING_UP[i].kind, BRING_UP[i].write), (Kind::Read, &[0x83][..]));
    let mut script = bring_up_script(FRONT);
    script.truncate(i);
    let limit = usize::from(config::lidar::INIT_POLL_LIMIT);
    script.extend((0..limit).map(|_| I2cT::write_read(0x29, vec![0x83], vec![0x00])));
    let pin = PinMock::new(&[PinT::set(State::Low), PinT::set(State::High), PinT::set(State::Low)]);
    let mut lidar = Lidar::front(I2cMock::new(&script), pin, CheckedDelay::new(&waits()));
    assert_eq!(lidar.reinit(), Err(SensorError::Timeout));
    done(lidar);
}

#[test]
fn implausible_timing_registers_are_refused_before_the_crate_does_arithmetic_on_them() {
    // The crate computes (v + 1) << 1 in u8 and divides by a product of it
    // (VCSEL period), adds 1 to a u8 (MSRC timeout), and subtracts the
    // pre-range timeout from the final-range one: each bad value would be a
    // panic (debug) or a division by zero (release) inside the crate.
    let bad: [(u8, Vec<u8>); 6] = [
        (0x70, vec![0x7F]),
        (0x70, vec![0xFF]),
        (0x50, vec![0x00]),
        (0x46, vec![0xFF]),
        (0x51, vec![0x10, 0xFF]),
        (0x71, vec![0x00, 0x01]),
    ];
    for (reg, value) in bad {
        let i = BRING_UP.iter().position(|s| s.kind == Kind::Read && s.write == [reg]).unwrap();
        failing_bring_up(i, retried(I2cT::write_read(0x29, vec![reg], value.clone())), SensorError::Bus);
    }
}
