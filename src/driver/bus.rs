//! One physical I2C bus for three chips and two embedded-hal versions.
//!
//! The board's bit-banged master implements embedded-hal 1.0 [`I2c`]. The
//! `vl53l0x` crate (1.0.1) speaks embedded-hal 1.0; the `mpu9250` crate
//! (0.25) speaks embedded-hal 0.2's `blocking::i2c`.
//!
//! Choices, and why:
//! - **Sharing**: `embedded_hal_bus::i2c::RefCellDevice` (re-exported as
//!   [`SharedI2c`]). The ESP8266 has one core and the bus is only used from
//!   the main loop (never from an interrupt), so a `RefCell` is all the
//!   locking needed: no critical sections, no atomics (the lx106 has no
//!   compare-and-swap anyway). A re-entrant borrow cannot happen in this
//!   single-threaded loop; if it ever did, `RefCellDevice` would panic, so
//!   every driver here takes the bus only for the duration of one call.
//! - **eh0 for the mpu9250 crate**: [`Eh0Compat`], a ten-line adapter from
//!   any eh1 [`I2c`] to embedded-hal 0.2's `Write`, `WriteRead` and `Read`.
//!   `embedded-hal-compat` would do the same, but it is a whole crate (with
//!   both HAL versions and their pin/serial traits) for three one-line
//!   trait impls; ours has no dependency and no `unsafe`.
//! - **Error classes**: [`classify`] maps any eh1 bus error onto the
//!   driver's [`SensorError`] by its [`ErrorKind`]: a NACK of the address is
//!   a missing chip, anything else on the wire is a bus error. (The control
//!   loop counts a NACK while polling a chip that was working like a bus
//!   error: a glitch, see `control::tick`.)
//! - **Transient faults**: [`Retry`] runs a failed transaction again, up to
//!   [`config::i2c::TRANSACTION_RETRIES`] times, before the driver sees the
//!   error. The board's master has already freed the bus after the failure
//!   (STOP, or nine clocks for a stuck SDA: `board::bitbang_i2c`), so the
//!   retry starts on an idle bus. A retry repeats the whole transaction, so
//!   it is only used where every transaction is idempotent; every one the
//!   drivers here issue is (see [`Retry`]).

use embedded_hal::i2c::{ErrorKind, ErrorType, I2c, NoAcknowledgeSource, Operation};
use embedded_hal_02::blocking::i2c as i2c02;

use super::SensorError;
use crate::config;

/// A driver's handle on the shared bus (embedded-hal-bus 0.3, see the
/// module docs). Create one per driver from the same `RefCell`:
/// `SharedI2c::new(&bus_cell)`.
pub type SharedI2c<'a, B> = embedded_hal_bus::i2c::RefCellDevice<'a, B>;

/// Maps a bus error to a sensor error: a NACK of the address means nobody
/// answered (the chip is missing, held in reset, or at another address);
/// every other failure is a bus error.
pub fn classify<E: embedded_hal::i2c::Error>(e: &E) -> SensorError {
    match e.kind() {
        ErrorKind::NoAcknowledge(NoAcknowledgeSource::Address) => SensorError::Missing,
        _ => SensorError::Bus,
    }
}

/// Adapts an embedded-hal 1.0 [`I2c`] to embedded-hal 0.2's blocking
/// `Write`, `WriteRead` and `Read` (for the `mpu9250` crate). Wrap a
/// `&mut` to keep ownership: `Eh0Compat(&mut i2c)`.
#[derive(Debug)]
pub struct Eh0Compat<T>(pub T);

impl<T: I2c> i2c02::Write for Eh0Compat<T> {
    type Error = T::Error;
    fn write(&mut self, address: u8, bytes: &[u8]) -> Result<(), Self::Error> {
        self.0.write(address, bytes)
    }
}

impl<T: I2c> i2c02::WriteRead for Eh0Compat<T> {
    type Error = T::Error;
    fn write_read(&mut self, address: u8, bytes: &[u8], buffer: &mut [u8]) -> Result<(), Self::Error> {
        self.0.write_read(address, bytes, buffer)
    }
}

impl<T: I2c> i2c02::Read for Eh0Compat<T> {
    type Error = T::Error;
    fn read(&mut self, address: u8, buffer: &mut [u8]) -> Result<(), Self::Error> {
        self.0.read(address, buffer)
    }
}

/// Why a guarded transaction failed (see [`PollGuard`]).
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum GuardError<E> {
    /// The bus itself failed.
    Bus(E),
    /// A register read back a value the chip cannot hold (a corrupted
    /// transfer); it was not passed on.
    Implausible,
    /// The same register was polled more often than allowed.
    PollLimit,
}

impl<E: embedded_hal::i2c::Error> embedded_hal::i2c::Error for GuardError<E> {
    fn kind(&self) -> ErrorKind {
        match self {
            GuardError::Bus(e) => e.kind(),
            GuardError::Implausible | GuardError::PollLimit => ErrorKind::Other,
        }
    }
}

impl<E: embedded_hal::i2c::Error> GuardError<E> {
    /// The sensor error this stands for.
    pub fn sensor_error(&self) -> SensorError {
        match self {
            GuardError::Bus(e) => classify(e),
            GuardError::Implausible => SensorError::Bus,
            GuardError::PollLimit => SensorError::Timeout,
        }
    }
}

/// Checks the values a chip reads back before a third-party driver sees
/// them (may keep state, e.g. to compare two registers read in turn).
pub trait RegisterCheck {
    /// True if `data`, read from register `reg`, can be passed on.
    fn plausible(&mut self, reg: u8, data: &[u8]) -> bool;
}

/// An [`I2c`] wrapper for a third-party driver that (a) turns register
/// values the chip cannot hold into an error before the driver sees them,
/// and (b) ends busy-wait loops early: after `poll_limit` consecutive
/// identical register reads it fails with [`GuardError::PollLimit`].
///
/// Why: the `vl53l0x` crate does unchecked `u8`/`u16` arithmetic on register
/// values (an overflow panic in debug builds and a division by zero in
/// release builds for a corrupted VCSEL period), and polls up to 65535
/// times (seconds on a bit-banged bus) for a chip that never gets ready.
pub struct PollGuard<T, C> {
    inner: T,
    check: C,
    poll_limit: u16,
    last_reg: Option<u8>,
    repeats: u16,
}

impl<T: I2c, C: RegisterCheck> PollGuard<T, C> {
    pub fn new(inner: T, check: C, poll_limit: u16) -> Self {
        PollGuard { inner, check, poll_limit, last_reg: None, repeats: 0 }
    }

    fn note_read(&mut self, reg: u8) -> Result<(), GuardError<T::Error>> {
        if self.last_reg == Some(reg) {
            self.repeats = self.repeats.saturating_add(1);
            if self.repeats >= self.poll_limit {
                return Err(GuardError::PollLimit);
            }
        } else {
            self.last_reg = Some(reg);
            self.repeats = 0;
        }
        Ok(())
    }
}

impl<T: I2c, C> ErrorType for PollGuard<T, C> {
    type Error = GuardError<T::Error>;
}

impl<T: I2c, C: RegisterCheck> PollGuard<T, C> {
    /// Before a transfer: a register read (`[reg]` written, then read) is
    /// counted, anything else resets the count.
    fn before(&mut self, reg: Option<u8>) -> Result<(), GuardError<T::Error>> {
        match reg {
            Some(r) => self.note_read(r),
            None => {
                self.last_reg = None;
                self.repeats = 0;
                Ok(())
            }
        }
    }

    fn after(&mut self, reg: Option<u8>, data: &[u8]) -> Result<(), GuardError<T::Error>> {
        match reg {
            Some(r) if !self.check.plausible(r, data) => Err(GuardError::Implausible),
            _ => Ok(()),
        }
    }
}

/// Each method forwards to the same method of the inner bus (so a mock
/// sees exactly the driver's calls).
impl<T: I2c, C: RegisterCheck> I2c for PollGuard<T, C> {
    fn read(&mut self, address: u8, read: &mut [u8]) -> Result<(), Self::Error> {
        self.before(None)?;
        self.inner.read(address, read).map_err(GuardError::Bus)
    }

    fn write(&mut self, address: u8, write: &[u8]) -> Result<(), Self::Error> {
        self.before(None)?;
        self.inner.write(address, write).map_err(GuardError::Bus)
    }

    fn write_read(&mut self, address: u8, write: &[u8], read: &mut [u8]) -> Result<(), Self::Error> {
        let reg = match write {
            [r] => Some(*r),
            _ => None,
        };
        self.before(reg)?;
        self.inner.write_read(address, write, read).map_err(GuardError::Bus)?;
        self.after(reg, read)
    }

    fn transaction(&mut self, address: u8, operations: &mut [Operation<'_>]) -> Result<(), Self::Error> {
        let reg = match operations {
            [Operation::Write([r]), Operation::Read(_)] => Some(*r),
            _ => None,
        };
        self.before(reg)?;
        self.inner.transaction(address, operations).map_err(GuardError::Bus)?;
        match &*operations {
            [_, Operation::Read(buf)] => self.after(reg, buf),
            _ => Ok(()),
        }
    }
}

/// An [`I2c`] wrapper that runs a failed transaction again, up to `retries`
/// more times, and returns the last error if every attempt failed. Each
/// attempt is the same method on the inner bus with the same arguments, so
/// the chip sees the transaction again from its START (write buffers are
/// sent again, read buffers refilled).
///
/// Only for idempotent transactions: doing one twice must leave the chip as
/// doing it once. That holds for everything the drivers here send:
/// - register writes (`[reg, value...]`) set the same value again;
/// - register reads (`[reg]` then a read) re-set the register pointer first;
/// - the reads with a side effect are ones whose repetition is harmless:
///   the AK8963's data read (HXL..ST2) releases the data lock and clears
///   DRDY, and a second read gets the same (or the next whole) sample; the
///   VL53L0X's result registers are cleared by a separate write
///   (SYSTEM_INTERRUPT_CLEAR), not by reading them, and its status read
///   (RESULT_INTERRUPT_STATUS) clears nothing. No driver here reads a
///   clear-on-read register (e.g. the MPU9250's INT_STATUS) or a FIFO,
///   where a retry would lose data: keep such reads outside a `Retry`.
///
/// One write is not idempotent: the VL53L0X's address change
/// (I2C_SLAVE_DEVICE_ADDRESS). If it reaches the chip and the transfer
/// fails after it (a clock-stretch timeout), the chip has moved, and the
/// same write to the old address is NACKed. [`Retry::except_writes_to`]
/// leaves writes to such a register alone: their failure goes straight to
/// the driver (the bring-up fails and is tried again from a reset).
///
/// Every error kind is retried, an address NACK too: on a noisy bus a
/// corrupted address byte is NACKed like an absent chip. An absent chip
/// costs `retries` more transactions before the error comes back.
///
/// Wrap a `&mut` to keep ownership: `Retry::new(&mut i2c, n)`.
#[derive(Debug)]
pub struct Retry<I> {
    inner: I,
    retries: u8,
    /// Writes to this register are not retried (see the type's docs).
    except: Option<u8>,
    /// Failed attempts that were retried (for tests and statistics).
    retried: u32,
}

impl<I: I2c> Retry<I> {
    /// `retries` more attempts after a failure (0: a plain pass-through).
    pub fn new(inner: I, retries: u8) -> Self {
        Retry { inner, retries, except: None, retried: 0 }
    }

    /// Does not retry a plain write whose first byte is `reg` (a register
    /// write that is not idempotent).
    pub fn except_writes_to(mut self, reg: u8) -> Self {
        self.except = Some(reg);
        self
    }

    /// With [`config::i2c::TRANSACTION_RETRIES`].
    pub fn with_config(inner: I) -> Self {
        Self::new(inner, config::i2c::TRANSACTION_RETRIES)
    }

    /// Failed attempts that were run again so far.
    pub fn retried(&self) -> u32 {
        self.retried
    }

    /// Gives the inner bus back.
    pub fn into_inner(self) -> I {
        self.inner
    }

    /// Runs `f` until it succeeds or `1 + retries` attempts have failed.
    fn attempt<R>(&mut self, mut f: impl FnMut(&mut I) -> Result<R, I::Error>) -> Result<R, I::Error> {
        let mut left = self.retries;
        loop {
            match f(&mut self.inner) {
                Ok(r) => return Ok(r),
                Err(e) if left == 0 => return Err(e),
                Err(_) => {
                    left = left.saturating_sub(1); // left > 0 here
                    self.retried = self.retried.saturating_add(1);
                }
            }
        }
    }
}

impl<I: I2c> ErrorType for Retry<I> {
    type Error = I::Error;
}

/// Each method retries the same method of the inner bus (so a mock sees
/// exactly the driver's calls, repeated after each failure).
impl<I: I2c> I2c for Retry<I> {
    fn read(&mut self, address: u8, read: &mut [u8]) -> Result<(), Self::Error> {
        self.attempt(|i| i.read(address, read))
    }

    fn write(&mut self, address: u8, write: &[u8]) -> Result<(), Self::Error> {
        if self.except.is_some() && write.first() == self.except.as_ref() {
            return self.inner.write(address, write);
        }
        self.attempt(|i| i.write(address, write))
    }

    fn write_read(&mut self, address: u8, write: &[u8], read: &mut [u8]) -> Result<(), Self::Error> {
        self.attempt(|i| i.write_read(address, write, read))
    }

    fn transaction(&mut self, address: u8, operations: &mut [Operation<'_>]) -> Result<(), Self::Error> {
        self.attempt(|i| i.transaction(address, operations))
    }
}
