//! The exact bus transcript of one VL53L0X bring-up by `driver::lidar`
//! (the vl53l0x 1.0.1 crate's initialisation, then our address change,
//! timing budget and start of continuous ranging), for embedded-hal-mock
//! scripts. Recorded once from the register-level fake (`sim::vl53l0x`) and
//! checked by hand against the crate's source
//! (`VL53L0x::with_address` -> `init_hardware`, `set_address`,
//! `set_measurement_timing_budget`, `start_continuous(0)`); replies are the
//! fake's register values. A change in the crate or in our sequence breaks
//! the mock tests that replay it.
//!
//! The crate writes registers with `write_read(addr, [reg, value], [_])`
//! (a write followed by a one-byte read whose value it ignores): those are
//! [`Kind::Set`] steps, replied with zeros (one byte; six for the SPAD
//! map, whose write the crate pairs with a six-byte read).

use embedded_hal_mock::eh1::delay::{CheckedDelay, Transaction as DelayT};
use embedded_hal_mock::eh1::digital::{Mock as PinMock, State, Transaction as PinT};
use embedded_hal_mock::eh1::i2c::{Mock as I2cMock, Transaction};
use paperbot::config::i2c::FRONT_LIDAR_ADDR;
use paperbot::driver::lidar::Lidar;
use paperbot::driver::RangeSensor;

/// Which address a step goes to.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum At {
    /// The boot address 0x29.
    Boot,
    /// The lidar's own address (after the move).
    New,
}
use At::{Boot as B, New as N};

#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum Kind {
    /// `write_read([reg], reply)`: a register read.
    Read,
    /// `write_read([reg, value..], [_])`: the crate's register write.
    Set,
    /// A plain `write` (the address change).
    Write,
}
use Kind::*;

#[derive(Clone, Copy, Debug)]
pub struct Step {
    pub at: At,
    pub kind: Kind,
    pub write: &'static [u8],
    pub reply: &'static [u8],
}

/// One lidar's bring-up after XSHUT is released.
pub const BRING_UP: &[Step] = &[
    Step { at: B, kind: Read, write: &[0xC0], reply: &[0xEE] },
    Step { at: B, kind: Read, write: &[0x89], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0x89, 0x01], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0x88, 0x00], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0x80, 0x01], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0xFF, 0x01], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0x00, 0x00], reply: &[0x00] },
    Step { at: B, kind: Read, write: &[0x91], reply: &[0x3C] },
    Step { at: B, kind: Set, write: &[0x00, 0x01], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0xFF, 0x00], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0x80, 0x00], reply: &[0x00] },
    Step { at: B, kind: Read, write: &[0x60], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0x60, 0x12], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0x44, 0x00, 0x20], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0x01, 0xFF], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0x80, 0x01], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0xFF, 0x01], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0x00, 0x00], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0xFF, 0x06], reply: &[0x00] },
    Step { at: B, kind: Read, write: &[0x83], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0x83, 0x04], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0xFF, 0x07], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0x81, 0x01], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0x80, 0x01], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0x94, 0x6B], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0x83, 0x00], reply: &[0x00] },
    Step { at: B, kind: Read, write: &[0x83], reply: &[0x00] },
    Step { at: B, kind: Read, write: &[0x83], reply: &[0x00] },
    Step { at: B, kind: Read, write: &[0x83], reply: &[0x10] },
    Step { at: B, kind: Set, write: &[0x83, 0x01], reply: &[0x00] },
    Step { at: B, kind: Read, write: &[0x92], reply: &[0x85] },
    Step { at: B, kind: Set, write: &[0x81, 0x00], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0xFF, 0x06], reply: &[0x00] },
    Step { at: B, kind: Read, write: &[0x83], reply: &[0x04] },
    Step { at: B, kind: Set, write: &[0x83, 0x00], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0xFF, 0x01], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0x00, 0x01], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0xFF, 0x00], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0x80, 0x00], reply: &[0x00] },
    Step { at: B, kind: Read, write: &[0xB0], reply: &[0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF] },
    Step { at: B, kind: Set, write: &[0xFF, 0x01], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0x4F, 0x00], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0x4E, 0x2C], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0xFF, 0x00], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0xB6, 0xB4], reply: &[0x00] },
    Step {
        at: B,
        kind: Set,
        write: &[0xB0, 0x00, 0xF0, 0x01, 0x00, 0x00, 0x00],
        reply: &[0x00, 0x00, 0x00, 0x00, 0x00, 0x00],
    },
    Step { at: B, kind: Set, write: &[0xFF, 0x01], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0x00, 0x00], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0xFF, 0x00], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0x09, 0x00], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0x10, 0x00], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0x11, 0x00], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0x24, 0x01], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0x25, 0xFF], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0x75, 0x00], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0xFF, 0x01], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0x4E, 0x2C], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0x48, 0x00], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0x30, 0x20], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0xFF, 0x00], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0x30, 0x09], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0x54, 0x00], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0x31, 0x04], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0x32, 0x03], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0x40, 0x83], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0x46, 0x25], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0x60, 0x00], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0x27, 0x00], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0x50, 0x06], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0x51, 0x00], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0x52, 0x96], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0x56, 0x08], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0x57, 0x30], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0x61, 0x00], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0x62, 0x00], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0x64, 0x00], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0x65, 0x00], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0x66, 0xA0], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0xFF, 0x01], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0x22, 0x32], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0x47, 0x14], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0x49, 0xFF], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0x4A, 0x00], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0xFF, 0x00], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0x7A, 0x0A], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0x7B, 0x00], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0x78, 0x21], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0xFF, 0x01], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0x23, 0x34], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0x42, 0x00], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0x44, 0xFF], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0x45, 0x26], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0x46, 0x05], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0x40, 0x40], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0x0E, 0x06], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0x20, 0x1A], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0x43, 0x40], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0xFF, 0x00], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0x34, 0x03], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0x35, 0x44], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0xFF, 0x01], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0x31, 0x04], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0x4B, 0x09], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0x4C, 0x05], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0x4D, 0x04], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0xFF, 0x00], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0x44, 0x00], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0x45, 0x20], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0x47, 0x08], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0x48, 0x28], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0x67, 0x00], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0x70, 0x04], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0x71, 0x01], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0x72, 0xFE], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0x76, 0x00], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0x77, 0x00], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0xFF, 0x01], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0x0D, 0x01], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0xFF, 0x00], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0x80, 0x01], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0x01, 0xF8], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0xFF, 0x01], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0x8E, 0x01], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0x00, 0x01], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0xFF, 0x00], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0x80, 0x00], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0x0A, 0x04], reply: &[0x00] },
    Step { at: B, kind: Read, write: &[0x84], reply: &[0x11] },
    Step { at: B, kind: Set, write: &[0x84, 0x01], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0x0B, 0x01], reply: &[0x00] },
    Step { at: B, kind: Read, write: &[0x01], reply: &[0xF8] },
    Step { at: B, kind: Read, write: &[0x51], reply: &[0x00, 0x96] },
    Step { at: B, kind: Read, write: &[0x71], reply: &[0x01, 0xFE] },
    Step { at: B, kind: Read, write: &[0x50], reply: &[0x06] },
    Step { at: B, kind: Read, write: &[0x46], reply: &[0x25] },
    Step { at: B, kind: Read, write: &[0x70], reply: &[0x04] },
    Step { at: B, kind: Set, write: &[0x01, 0xE8], reply: &[0x00] },
    Step { at: B, kind: Read, write: &[0x01], reply: &[0xE8] },
    Step { at: B, kind: Read, write: &[0x51], reply: &[0x00, 0x96] },
    Step { at: B, kind: Read, write: &[0x71], reply: &[0x01, 0xFE] },
    Step { at: B, kind: Read, write: &[0x50], reply: &[0x06] },
    Step { at: B, kind: Read, write: &[0x46], reply: &[0x25] },
    Step { at: B, kind: Read, write: &[0x70], reply: &[0x04] },
    Step { at: B, kind: Set, write: &[0x71, 0x02, 0x98], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0x01, 0x01], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0x00, 0x41], reply: &[0x00] },
    Step { at: B, kind: Read, write: &[0x13], reply: &[0x04] },
    Step { at: B, kind: Set, write: &[0x0B, 0x01], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0x00, 0x00], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0x01, 0x02], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0x00, 0x01], reply: &[0x00] },
    Step { at: B, kind: Read, write: &[0x13], reply: &[0x04] },
    Step { at: B, kind: Set, write: &[0x0B, 0x01], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0x00, 0x00], reply: &[0x00] },
    Step { at: B, kind: Set, write: &[0x01, 0xE8], reply: &[0x00] },
    Step { at: B, kind: Write, write: &[0x8A, 0x16], reply: &[] },
    Step { at: N, kind: Read, write: &[0x01], reply: &[0xE8] },
    Step { at: N, kind: Read, write: &[0x51], reply: &[0x00, 0x96] },
    Step { at: N, kind: Read, write: &[0x71], reply: &[0x02, 0x98] },
    Step { at: N, kind: Read, write: &[0x50], reply: &[0x06] },
    Step { at: N, kind: Read, write: &[0x46], reply: &[0x25] },
    Step { at: N, kind: Read, write: &[0x70], reply: &[0x04] },
    Step { at: N, kind: Set, write: &[0x71, 0x02, 0x92], reply: &[0x00] },
    Step { at: N, kind: Set, write: &[0x80, 0x01], reply: &[0x00] },
    Step { at: N, kind: Set, write: &[0xFF, 0x01], reply: &[0x00] },
    Step { at: N, kind: Set, write: &[0x00, 0x00], reply: &[0x00] },
    Step { at: N, kind: Set, write: &[0x91, 0x3C], reply: &[0x00] },
    Step { at: N, kind: Set, write: &[0x00, 0x01], reply: &[0x00] },
    Step { at: N, kind: Set, write: &[0xFF, 0x00], reply: &[0x00] },
    Step { at: N, kind: Set, write: &[0x80, 0x00], reply: &[0x00] },
    Step { at: N, kind: Set, write: &[0x00, 0x02], reply: &[0x00] },
];

/// Index of the address change (`0x8A <- new address`) in [`BRING_UP`].
pub fn address_change_index() -> usize {
    BRING_UP.iter().position(|s| s.kind == Write && s.write.first() == Some(&0x8A)).unwrap_or(usize::MAX)
}

/// [`BRING_UP`] as mock transactions, for a lidar moving to `new_addr`.
/// The address change writes `new_addr`.
pub fn bring_up_script(new_addr: u8) -> Vec<Transaction> {
    BRING_UP
        .iter()
        .map(|s| {
            let addr = match s.at {
                At::Boot => 0x29,
                At::New => new_addr,
            };
            match s.kind {
                Read => Transaction::write_read(addr, s.write.to_vec(), s.reply.to_vec()),
                Set => Transaction::write_read(addr, s.write.to_vec(), s.reply.to_vec()),
                Write if s.write.first() == Some(&0x8A) => Transaction::write(addr, vec![0x8A, new_addr]),
                Write => Transaction::write(addr, s.write.to_vec()),
            }
        })
        .collect()
}

/// Registers of a range read (the vl53l0x crate's names).
pub const RESULT_INTERRUPT_STATUS: u8 = 0x13;
/// `RESULT_RANGE_STATUS + 10`: the range in mm, big-endian.
pub const RESULT_RANGE_MM: u8 = 0x1E;
pub const SYSTEM_INTERRUPT_CLEAR: u8 = 0x0B;

/// One range read at `addr`: the interrupt status, the range, the clear.
pub fn read_script(addr: u8, status: u8, mm: u16) -> Vec<Transaction> {
    vec![
        Transaction::write_read(addr, vec![RESULT_INTERRUPT_STATUS], vec![status]),
        Transaction::write_read(addr, vec![RESULT_RANGE_MM], mm.to_be_bytes().to_vec()),
        Transaction::write(addr, vec![SYSTEM_INTERRUPT_CLEAR, 0x01]),
    ]
}

/// The bring-up's waits: XSHUT low, then the chip's boot.
pub fn waits() -> Vec<DelayT> {
    use paperbot::config::lidar::{BOOT_TIME_US, RESET_TIME_US};
    vec![DelayT::delay_us(RESET_TIME_US), DelayT::delay_us(BOOT_TIME_US)]
}

/// The front lidar brought up over mocks that then expect `then`; also
/// returns a handle on the I2C mock.
pub fn new_front_lidar(then: &[Transaction]) -> (Lidar<I2cMock, PinMock, CheckedDelay>, I2cMock) {
    let i2c = I2cMock::new(&[bring_up_script(FRONT_LIDAR_ADDR), then.to_vec()].concat());
    let pin = PinMock::new(&[PinT::set(State::Low), PinT::set(State::High)]);
    let mut lidar = Lidar::front(i2c.clone(), pin, CheckedDelay::new(&waits()));
    lidar.reinit().unwrap();
    (lidar, i2c)
}

/// Checks that every expected transfer, pin edge and wait happened.
pub fn done(lidar: Lidar<I2cMock, PinMock, CheckedDelay>) {
    let (mut i2c, mut pin, mut delay) = lidar.release();
    i2c.done();
    pin.done();
    delay.done();
}
