//! embedded-hal-mock helpers shared by the driver tests.

use embedded_hal::i2c::{ErrorKind, NoAcknowledgeSource};
use embedded_hal_mock::eh1::i2c::Transaction as I2cT;

/// An address NACK, as a chip that is not there gives.
pub const NACK: ErrorKind = ErrorKind::NoAcknowledge(NoAcknowledgeSource::Address);

/// A failing transaction as the driver sends it: once, then once per retry
/// (`driver::bus::Retry`, `config::i2c::TRANSACTION_RETRIES`).
pub fn retried(t: I2cT) -> Vec<I2cT> {
    vec![t; usize::from(paperbot::config::i2c::TRANSACTION_RETRIES) + 1]
}
