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
//!   a missing chip, anything else on the wire is a bus error.

use embedded_hal::i2c::{ErrorKind, ErrorType, I2c, NoAcknowledgeSource, Operation};
use embedded_hal_02::blocking::i2c as i2c02;

use super::SensorError;

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
