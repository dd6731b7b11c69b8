//! A simulated I2C bus (embedded-hal 1.0 [`I2c`]) that routes each
//! transaction to the fake chip answering at its address, with a simulated
//! clock and fault injection.
//!
//! [`SimBus`] is a cheap handle (`Rc`): clone it for every driver (or put
//! one in a `RefCell` and share it with `embedded_hal_bus`'s
//! `RefCellDevice`, as the robot does) and keep one in the test to inject
//! faults and read the transaction log. Fake chips are attached as
//! `Rc<RefCell<_>>` so the test (or the simulator) keeps a handle on each to
//! set its "truth" (a distance, a field) while the drivers own the bus.
//!
//! Faults ([`Fault`]): one-shot at a given transaction number
//! ([`SimBus::inject`]), or persistent: an address that never answers
//! ([`SimBus::set_nack_address`]), SDA held low by a stuck slave
//! ([`SimBus::set_sda_stuck`]). Chips can also disappear and come back
//! (their own `set_present`).
//!
//! A one-shot [`Fault::SdaStuck`] is a slave that held SDA through one
//! transaction and let go when the master freed the bus afterwards: the
//! board's bit-banged master sends STOP, or nine clocks and STOP, after
//! every failed transfer (UM10204 3.1.16, `board::bitbang_i2c`), so the next
//! transaction finds an idle bus. The simulated bus behaves the same: the
//! fault clears by itself after its transaction. A slave that keeps SDA low
//! through the recovery is the persistent [`SimBus::set_sda_stuck`].

use std::cell::{Cell, RefCell};
use std::rc::Rc;
use std::vec::Vec;

use embedded_hal::delay::DelayNs;
use embedded_hal::i2c::{ErrorKind, ErrorType, I2c, NoAcknowledgeSource, Operation};

/// Simulated time in nanoseconds, shared by the bus's chips and delays.
#[derive(Clone, Default, Debug)]
pub struct SimClock(Rc<Cell<u64>>);

impl SimClock {
    pub fn new() -> Self {
        Self::default()
    }
    pub fn now_ns(&self) -> u64 {
        self.0.get()
    }
    pub fn advance_ns(&self, ns: u64) {
        self.0.set(self.0.get().saturating_add(ns));
    }
    pub fn advance_us(&self, us: u64) {
        self.advance_ns(us.saturating_mul(1000));
    }
    pub fn advance_ms(&self, ms: u64) {
        self.advance_ns(ms.saturating_mul(1_000_000));
    }
    /// A delay that moves this clock forward.
    pub fn delay(&self) -> SimDelay {
        SimDelay { clock: self.clone() }
    }
}

/// An embedded-hal 1.0 delay that advances a [`SimClock`] instead of waiting.
#[derive(Clone, Debug)]
pub struct SimDelay {
    pub clock: SimClock,
}

impl DelayNs for SimDelay {
    fn delay_ns(&mut self, ns: u32) {
        self.clock.advance_ns(u64::from(ns));
    }
}

/// A chip on the simulated bus. One transaction is a START, then write and
/// read operations, each at the same address; the chip keeps its register
/// pointer between them.
pub trait I2cTarget {
    /// True if the chip acknowledges `addr` now.
    fn acks(&self, addr: u8) -> bool;
    /// Bytes written to `addr` (the first one is usually a register).
    fn write(&mut self, addr: u8, data: &[u8]);
    /// Bytes read from `addr`.
    fn read(&mut self, addr: u8, buf: &mut [u8]);
}

/// Why a simulated transaction failed.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum SimBusError {
    /// Nobody acknowledged the address.
    AddressNack(u8),
    /// A slave stretched the clock past the master's limit.
    Timeout,
    /// SDA is held low: the master cannot make a START.
    SdaStuck,
    /// Two chips answered the same address (their bytes would mix on the
    /// wire); counted in [`SimBus::collisions`].
    Collision(u8),
}

impl embedded_hal::i2c::Error for SimBusError {
    fn kind(&self) -> ErrorKind {
        match self {
            SimBusError::AddressNack(_) => ErrorKind::NoAcknowledge(NoAcknowledgeSource::Address),
            SimBusError::Timeout => ErrorKind::Other,
            SimBusError::SdaStuck | SimBusError::Collision(_) => ErrorKind::Bus,
        }
    }
}

/// A one-shot fault for one transaction.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum Fault {
    /// The address is not acknowledged; the chip sees nothing.
    Nack,
    /// Clock-stretch timeout after the writes reached the chip; reads are
    /// not done.
    Timeout,
    /// The transfer succeeds but every byte read is XORed with the mask.
    Corrupt(u8),
    /// SDA stuck for this one transaction.
    SdaStuck,
}

/// One logged operation.
#[derive(Clone, PartialEq, Eq, Debug)]
pub enum LoggedOp {
    Write(Vec<u8>),
    Read(Vec<u8>),
}

/// One logged transaction.
#[derive(Clone, PartialEq, Eq, Debug)]
pub struct LoggedTxn {
    /// Transaction number (from 0, counting failed ones).
    pub index: u32,
    pub addr: u8,
    pub ops: Vec<LoggedOp>,
    pub result: Result<(), SimBusError>,
}

struct BusState {
    targets: Vec<Rc<RefCell<dyn I2cTarget>>>,
    count: u32,
    failures: u32,
    faults: Vec<(u32, Fault)>,
    nack_addrs: Vec<u8>,
    sda_stuck: bool,
    collisions: u32,
    logging: bool,
    log: Vec<LoggedTxn>,
}

/// The simulated bus (a shared handle; see the module docs).
#[derive(Clone)]
pub struct SimBus(Rc<RefCell<BusState>>);

impl Default for SimBus {
    fn default() -> Self {
        Self::new()
    }
}

impl SimBus {
    pub fn new() -> Self {
        SimBus(Rc::new(RefCell::new(BusState {
            targets: Vec::new(),
            count: 0,
            failures: 0,
            faults: Vec::new(),
            nack_addrs: Vec::new(),
            sda_stuck: false,
            collisions: 0,
            logging: false,
            log: Vec::new(),
        })))
    }

    /// Puts a chip on the bus.
    pub fn attach<T: I2cTarget + 'static>(&self, chip: Rc<RefCell<T>>) {
        self.0.borrow_mut().targets.push(chip);
    }

    /// Transactions so far (including failed ones).
    pub fn transactions(&self) -> u32 {
        self.0.borrow().count
    }

    /// Transactions that failed (returned an error) so far.
    pub fn failures(&self) -> u32 {
        self.0.borrow().failures
    }

    /// Transactions that two chips answered at once.
    pub fn collisions(&self) -> u32 {
        self.0.borrow().collisions
    }

    /// Makes transaction number `at` (counted from the bus's creation) fail.
    pub fn inject(&self, at: u32, fault: Fault) {
        self.0.borrow_mut().faults.push((at, fault));
    }

    /// Makes the next transaction fail.
    pub fn inject_next(&self, fault: Fault) {
        let at = self.transactions();
        self.inject(at, fault);
    }

    /// Drops every pending one-shot fault.
    pub fn clear_faults(&self) {
        self.0.borrow_mut().faults.clear();
    }

    /// While set, nobody acknowledges `addr`.
    pub fn set_nack_address(&self, addr: u8, nack: bool) {
        let mut s = self.0.borrow_mut();
        s.nack_addrs.retain(|a| *a != addr);
        if nack {
            s.nack_addrs.push(addr);
        }
    }

    /// While set, SDA is held low and every transaction fails.
    pub fn set_sda_stuck(&self, stuck: bool) {
        self.0.borrow_mut().sda_stuck = stuck;
    }

    /// Turns the transaction log on or off (off by default: long
    /// simulations would fill memory).
    pub fn set_logging(&self, on: bool) {
        self.0.borrow_mut().logging = on;
    }

    /// The logged transactions so far.
    pub fn log(&self) -> Vec<LoggedTxn> {
        self.0.borrow().log.clone()
    }

    pub fn clear_log(&self) {
        self.0.borrow_mut().log.clear();
    }

    fn run(&self, address: u8, operations: &mut [Operation<'_>]) -> Result<(), SimBusError> {
        let (fault, target) = {
            let mut s = self.0.borrow_mut();
            let index = s.count;
            s.count = s.count.wrapping_add(1);
            let fault = s.faults.iter().position(|(at, _)| *at == index).map(|i| s.faults.swap_remove(i).1);
            if s.sda_stuck {
                return Err(SimBusError::SdaStuck);
            }
            let mut answering = s.targets.iter().filter(|t| t.borrow().acks(address));
            let first = answering.next().cloned();
            let second = answering.next().is_some();
            if second {
                s.collisions += 1;
                return Err(SimBusError::Collision(address));
            }
            let target = if s.nack_addrs.contains(&address) { None } else { first };
            (fault, target)
        };
        match fault {
            Some(Fault::Nack) => return Err(SimBusError::AddressNack(address)),
            Some(Fault::SdaStuck) => return Err(SimBusError::SdaStuck),
            _ => {}
        }
        let Some(target) = target else {
            return Err(SimBusError::AddressNack(address));
        };
        let mut chip = target.borrow_mut();
        for op in operations.iter_mut() {
            match op {
                Operation::Write(data) => chip.write(address, data),
                Operation::Read(buf) => {
                    if fault == Some(Fault::Timeout) {
                        return Err(SimBusError::Timeout);
                    }
                    chip.read(address, buf);
                    if let Some(Fault::Corrupt(mask)) = fault {
                        buf.iter_mut().for_each(|b| *b ^= mask);
                    }
                }
            }
        }
        if fault == Some(Fault::Timeout) {
            return Err(SimBusError::Timeout);
        }
        Ok(())
    }
}

impl ErrorType for SimBus {
    type Error = SimBusError;
}

impl I2c for SimBus {
    fn transaction(&mut self, address: u8, operations: &mut [Operation<'_>]) -> Result<(), Self::Error> {
        let index = self.transactions();
        let result = self.run(address, operations);
        let mut s = self.0.borrow_mut();
        if result.is_err() {
            s.failures = s.failures.wrapping_add(1);
        }
        if s.logging {
            let ops = operations
                .iter()
                .map(|op| match op {
                    Operation::Write(d) => LoggedOp::Write(d.to_vec()),
                    Operation::Read(b) => LoggedOp::Read(b.to_vec()),
                })
                .collect();
            s.log.push(LoggedTxn { index, addr: address, ops, result });
        }
        result
    }
}
