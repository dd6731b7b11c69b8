//! A bit-banged I2C master over two open-drain GPIOs: embedded-hal 1.0
//! [`I2c`] with 7-bit addresses, fast mode (400 kHz), clock stretching,
//! arbitration/stuck-line detection and bus recovery.
//!
//! esp8266-hal has no I2C, and `bitbang-hal` paces its bits with the HAL's
//! 3.2 us timer ticks (about 150 kHz at best). This master paces every
//! phase against a free-running cycle counter ([`CycleClock`], CCOUNT on the
//! ESP8266) with *deadlines* measured from the last SCL edge, so the time the
//! code itself takes is absorbed in the wait instead of adding to it, and an
//! interrupt in the middle of a bit only stretches that phase (SCL is ours,
//! I2C tolerates any slow-down).
//!
//! # Timing (see [`Timing::FAST`])
//! At 80 MHz and 400 kHz a bit is 200 CPU cycles. Each phase is a deadline
//! against CCOUNT:
//! - SCL is released no earlier than tLOW (1.3 us = 104 cycles, or half the
//!   period if longer) after our SCL-low write;
//! - the high phase starts when SCL *reads* high (rise time and clock
//!   stretching included); SDA is sampled right then (it is stable for the
//!   whole high phase);
//! - SCL falls when both tHIGH (0.6 us = 48 cycles) since the rise and the
//!   200-cycle period since the previous planned fall have passed.
//!
//! The period is timed from deadline to deadline, so the bus runs at
//! 400 kHz as long as one bit's work fits in it, and never faster: each
//! fall is at least 200 cycles after the previous one.
//!
//! # Cycle budget per bit (lx106, code in IRAM or cache-hot flash)
//! Work per bit outside the waits: SDA store (or release), SCL release
//! store, a poll loop until SCL reads high (GPIO_IN load, bit test, CCOUNT
//! timeout check: ~7 instructions per iteration), one SDA load, the SCL-low
//! store and three CCOUNT reads; about 25-30 instructions and 4 GPIO
//! accesses. Along the critical path of one bit (fall -> low deadline ->
//! release -> seen high -> sample -> period deadline -> fall) that is
//! ~60 cycles even at a pessimistic 10 cycles per GPIO (DPORT) access,
//! against 200 available: 104 are spent in the tLOW wait, 48 are the tHIGH
//! floor, leaving ~50 cycles of slack before the code, not the deadlines,
//! sets the rate. The deadline loops poll CCOUNT in 3 instructions
//! (`rsr.ccount; sub; bltu`), so a deadline is overshot by at most ~3
//! cycles. The simulated-bus tests replay this with those costs and
//! measure the clock at >= 395 kHz, never above 400 kHz.
//!
//! # Errors and recovery
//! NACK of the address or of a written byte ends the transfer with a STOP
//! and `NoAcknowledge(Address | Data)`. SDA read low while we release it
//! (another driver on the line) is `ArbitrationLoss`; SCL held low beyond
//! [`config::i2c::CLOCK_STRETCH_TIMEOUT_US`] is [`Error::ClockStretchTimeout`]
//! (`ErrorKind::Bus`); SDA or SCL stuck low after recovery is
//! [`Error::BusStuck`] (`ErrorKind::Bus`). After any error the master sends a
//! STOP, and if the bus is still not idle it runs the recovery of UM10204
//! 3.1.16: up to nine SCL pulses, each ending in a STOP attempt, until the
//! slave releases SDA. [`BitBangI2c::init`] runs the same recovery first.

use embedded_hal::i2c::{ErrorKind, ErrorType, I2c, NoAcknowledgeSource, Operation, SevenBitAddress};

use crate::config;

/// Two open-drain lines that can be read back (an external or internal
/// pull-up makes a released line high unless someone holds it low).
pub trait I2cPins {
    /// Lets SCL go high (stops driving it).
    fn scl_release(&mut self);
    /// Drives SCL low.
    fn scl_low(&mut self);
    /// The level on the SCL line.
    fn scl_is_high(&mut self) -> bool;
    /// Lets SDA go high (stops driving it).
    fn sda_release(&mut self);
    /// Drives SDA low.
    fn sda_low(&mut self);
    /// The level on the SDA line.
    fn sda_is_high(&mut self) -> bool;
}

/// A free-running, wrapping cycle counter (CCOUNT on the lx106).
pub trait CycleClock {
    fn now(&mut self) -> u32;
}

/// Bus phases in CPU cycles.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub struct Timing {
    /// Shortest SCL low phase, counted from our SCL-low write.
    pub low: u32,
    /// Shortest SCL high phase, counted from SCL reading high (also used
    /// for tSU;STA, tHD;STA, tSU;STO, all 0.6 us in fast mode).
    pub high_min: u32,
    /// Shortest clock period, SCL fall to SCL fall: the bus rate.
    pub period: u32,
    /// Bus free time after a STOP (tBUF).
    pub buf: u32,
    /// Longest a slave may hold SCL low.
    pub stretch_timeout: u32,
}

/// `ns` nanoseconds in cycles of a `cpu_hz` clock, rounded up, saturating at
/// `u32::MAX` (shared with the board's CCOUNT delay).
pub(crate) const fn ns_to_cycles(ns: u32, cpu_hz: u32) -> u32 {
    // ceil(ns * cpu_hz / 1e9) in u64: < 2^32 * 2^32, exact, never saturates.
    let c = (ns as u64).saturating_mul(cpu_hz as u64).div_ceil(1_000_000_000);
    if c > u32::MAX as u64 {
        u32::MAX
    } else {
        c as u32
    }
}

const fn max(a: u32, b: u32) -> u32 {
    if a > b {
        a
    } else {
        b
    }
}

impl Timing {
    /// Phases for a `bus_hz` clock on a `cpu_hz` core, meeting the fast-mode
    /// minimum low/high/bus-free times of [`config::i2c`].
    pub const fn new(cpu_hz: u32, bus_hz: u32, stretch_timeout_us: u32) -> Self {
        let period = if bus_hz == 0 { u32::MAX } else { cpu_hz.div_ceil(bus_hz) };
        let low = max(ns_to_cycles(config::i2c::T_LOW_MIN_NS, cpu_hz), period / 2);
        let high_min = ns_to_cycles(config::i2c::T_HIGH_MIN_NS, cpu_hz);
        let buf = ns_to_cycles(config::i2c::T_BUF_MIN_NS, cpu_hz);
        let stretch_timeout = ns_to_cycles(stretch_timeout_us.saturating_mul(1_000), cpu_hz);
        Self { low, high_min, period, buf, stretch_timeout }
    }

    /// The robot's bus: [`config::i2c::FREQUENCY_HZ`] on the 80 MHz core.
    pub const FAST: Self =
        Self::new(config::board::CPU_HZ, config::i2c::FREQUENCY_HZ, config::i2c::CLOCK_STRETCH_TIMEOUT_US);
}

/// Why a transfer failed.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum Error {
    /// The slave did not acknowledge the address or a data byte.
    NoAcknowledge(NoAcknowledgeSource),
    /// SDA was low while we released it for a 1 bit or a repeated START.
    ArbitrationLoss,
    /// A slave held SCL low longer than the stretch timeout.
    ClockStretchTimeout,
    /// SDA or SCL stays low even after the recovery sequence.
    BusStuck,
    /// The address does not fit in 7 bits.
    InvalidAddress,
}

impl embedded_hal::i2c::Error for Error {
    fn kind(&self) -> ErrorKind {
        match *self {
            Error::NoAcknowledge(s) => ErrorKind::NoAcknowledge(s),
            Error::ArbitrationLoss => ErrorKind::ArbitrationLoss,
            Error::ClockStretchTimeout | Error::BusStuck => ErrorKind::Bus,
            Error::InvalidAddress => ErrorKind::Other,
        }
    }
}

/// The bit-banged master.
pub struct BitBangI2c<P, C> {
    pins: P,
    clock: C,
    timing: Timing,
    /// Cycle count just after SCL was last pulled low (tLOW counts from here).
    t_low: u32,
    /// Cycle count at which SCL was last due to fall (the period counts
    /// from here; the write itself comes a constant few cycles later).
    t_fall: u32,
}

impl<P: I2cPins, C: CycleClock> BitBangI2c<P, C> {
    /// Takes the lines; does not touch the bus (call [`Self::init`]).
    pub fn new(pins: P, clock: C, timing: Timing) -> Self {
        Self { pins, clock, timing, t_low: 0, t_fall: 0 }
    }

    /// Releases both lines and frees the bus (recovery + STOP), for power-up
    /// when a slave may have been left mid-byte by a reset of the master.
    pub fn init(&mut self) -> Result<(), Error> {
        self.recover()
    }

    /// Gives the lines and the clock back.
    pub fn release(self) -> (P, C) {
        (self.pins, self.clock)
    }

    pub fn timing(&self) -> Timing {
        self.timing
    }

    // bus timing: inlined into the bit loop, so its cost stays inside a clock phase
    #[inline(always)]
    fn wait(&mut self, since: u32, cycles: u32) {
        while self.clock.now().wrapping_sub(since) < cycles {}
    }

    /// Releases SCL and waits until it reads high (clock stretching, rise
    /// time). Returns the cycle count at which it was seen high.
    // bus timing: inlined into the bit loop, so its cost stays inside a clock phase
    #[inline(always)]
    fn scl_high(&mut self) -> Result<u32, Error> {
        self.pins.scl_release();
        let t0 = self.clock.now();
        loop {
            if self.pins.scl_is_high() {
                return Ok(self.clock.now());
            }
            if self.clock.now().wrapping_sub(t0) > self.timing.stretch_timeout {
                return Err(Error::ClockStretchTimeout);
            }
        }
    }

    /// Pulls SCL low now.
    // bus timing: inlined into the bit loop, so its cost stays inside a clock phase
    #[inline(always)]
    fn scl_low(&mut self) {
        self.t_fall = self.clock.now();
        self.pins.scl_low();
        self.t_low = self.clock.now();
    }

    /// Ends a high phase that began at `th`: waits for tHIGH and for the
    /// clock period since the last fall, then pulls SCL low. The fall is
    /// timed from the deadline, so the bus runs at `period` whatever the
    /// code in between costs (as long as it fits).
    // bus timing: inlined into the bit loop, so its cost stays inside a clock phase
    #[inline(always)]
    fn end_high(&mut self, th: u32) {
        loop {
            let n = self.clock.now();
            if n.wrapping_sub(th) >= self.timing.high_min && n.wrapping_sub(self.t_fall) >= self.timing.period {
                self.t_fall = n;
                break;
            }
        }
        self.pins.scl_low();
        self.t_low = self.clock.now();
    }

    /// START from an idle bus (both lines high).
    fn start(&mut self) -> Result<(), Error> {
        self.pins.sda_release();
        self.scl_high()?;
        if !self.pins.sda_is_high() {
            // A slave still holds SDA (reset mid-transfer): free it first.
            self.recover()?;
        }
        self.pins.sda_low();
        let t = self.clock.now();
        self.wait(t, self.timing.high_min); // tHD;STA
        self.scl_low();
        Ok(())
    }

    /// Repeated START, from the low phase after an ACK bit.
    fn repeated_start(&mut self) -> Result<(), Error> {
        self.pins.sda_release();
        self.wait(self.t_low, self.timing.low);
        let th = self.scl_high()?;
        self.wait(th, self.timing.high_min); // tSU;STA
        if !self.pins.sda_is_high() {
            return Err(Error::ArbitrationLoss);
        }
        self.pins.sda_low();
        let t = self.clock.now();
        self.wait(t, self.timing.high_min); // tHD;STA
        self.scl_low();
        Ok(())
    }

    /// STOP, from a low phase; then the bus-free time. Checks that SDA came up.
    fn stop(&mut self) -> Result<(), Error> {
        self.pins.sda_low();
        self.wait(self.t_low, self.timing.low);
        let th = self.scl_high()?;
        self.wait(th, self.timing.high_min); // tSU;STO
        self.pins.sda_release();
        let t = self.clock.now();
        self.wait(t, self.timing.buf); // tBUF
        if self.pins.sda_is_high() {
            Ok(())
        } else {
            Err(Error::BusStuck)
        }
    }

    // bus timing: inlined into the bit loop, so its cost stays inside a clock phase
    #[inline(always)]
    fn write_bit(&mut self, bit: bool) -> Result<(), Error> {
        if bit {
            self.pins.sda_release();
        } else {
            self.pins.sda_low();
        }
        self.wait(self.t_low, self.timing.low);
        let th = self.scl_high()?;
        // SDA is stable for the whole high phase (it only changes while SCL
        // is low), so it is sampled at once and the wait absorbs the read.
        let lost = bit && !self.pins.sda_is_high();
        self.end_high(th);
        if lost {
            Err(Error::ArbitrationLoss)
        } else {
            Ok(())
        }
    }

    // bus timing: inlined into the bit loop, so its cost stays inside a clock phase
    #[inline(always)]
    fn read_bit(&mut self) -> Result<bool, Error> {
        self.pins.sda_release();
        self.wait(self.t_low, self.timing.low);
        let th = self.scl_high()?;
        let bit = self.pins.sda_is_high();
        self.end_high(th);
        Ok(bit)
    }

    /// Sends a byte MSB first; true if the slave acknowledged it.
    fn write_byte(&mut self, byte: u8) -> Result<bool, Error> {
        for i in (0..8).rev() {
            self.write_bit(byte >> i & 1 == 1)?;
        }
        Ok(!self.read_bit()?)
    }

    /// Reads a byte MSB first and acknowledges it (`ack`) or not.
    fn read_byte(&mut self, ack: bool) -> Result<u8, Error> {
        let mut byte = 0u8;
        for _ in 0..8 {
            byte = byte << 1 | u8::from(self.read_bit()?);
        }
        self.write_bit(!ack)?;
        Ok(byte)
    }

    /// Frees a bus whose SDA a slave holds low (UM10204 3.1.16): up to
    /// [`config::i2c::RECOVERY_CLOCKS`] SCL pulses, each ending with a STOP
    /// attempt (SDA low during SCL low, released during SCL high), until SDA
    /// comes up. Also used at power-up; harmless on an idle bus (one STOP).
    pub fn recover(&mut self) -> Result<(), Error> {
        self.pins.sda_release();
        self.pins.scl_release();
        let t = self.clock.now();
        self.wait(t, self.timing.buf);
        // SCL must be free, or nothing can be done.
        self.scl_high().map_err(|_| Error::BusStuck)?;
        for _ in 0..config::i2c::RECOVERY_CLOCKS {
            self.scl_low();
            self.pins.sda_low();
            self.wait(self.t_low, self.timing.low);
            let th = self.scl_high().map_err(|_| Error::BusStuck)?;
            self.wait(th, self.timing.high_min);
            self.pins.sda_release(); // STOP if nobody else holds SDA
            let t = self.clock.now();
            self.wait(t, self.timing.buf);
            if self.pins.sda_is_high() {
                return Ok(());
            }
        }
        Err(Error::BusStuck)
    }

    /// After a failed transfer: STOP, or the full recovery if that fails.
    fn abort(&mut self) {
        if self.stop().is_err() {
            // Nothing more to do if this fails too: the next START will try again.
            let _ = self.recover();
        }
    }

    fn run(&mut self, address: u8, operations: &mut [Operation<'_>]) -> Result<(), Error> {
        if address > 0x7F {
            return Err(Error::InvalidAddress);
        }
        let any = !operations.is_empty();
        let mut first = true;
        let mut rest: &mut [Operation<'_>] = operations;
        while let Some(head) = rest.first() {
            // A group: the longest run of operations of the same direction,
            // sent under one address (embedded-hal 1.0 transaction contract).
            let is_read = matches!(head, Operation::Read(_));
            let len = rest.iter().position(|op| matches!(op, Operation::Read(_)) != is_read).unwrap_or(rest.len());
            // len <= rest.len(): the split always succeeds.
            let Some((group, tail)) = core::mem::take(&mut rest).split_at_mut_checked(len) else {
                break;
            };
            rest = tail;
            if first {
                self.start()?;
            } else {
                self.repeated_start()?;
            }
            first = false;
            if !self.write_byte(address << 1 | u8::from(is_read))? {
                return Err(Error::NoAcknowledge(NoAcknowledgeSource::Address));
            }
            if is_read {
                let total: usize = group.iter().map(|op| if let Operation::Read(b) = op { b.len() } else { 0 }).sum();
                if total == 0 {
                    // A read must clock one byte to NACK it.
                    self.read_byte(false)?;
                }
                let mut remaining = total;
                for op in group.iter_mut() {
                    if let Operation::Read(buf) = op {
                        for b in buf.iter_mut() {
                            remaining = remaining.saturating_sub(1);
                            // ACK all but the group's last byte
                            *b = self.read_byte(remaining > 0)?;
                        }
                    }
                }
            } else {
                for op in group.iter() {
                    if let Operation::Write(buf) = op {
                        for &b in buf.iter() {
                            if !self.write_byte(b)? {
                                return Err(Error::NoAcknowledge(NoAcknowledgeSource::Data));
                            }
                        }
                    }
                }
            }
        }
        if any {
            self.stop()?;
        }
        Ok(())
    }
}

impl<P, C> ErrorType for BitBangI2c<P, C> {
    type Error = Error;
}

impl<P: I2cPins, C: CycleClock> I2c<SevenBitAddress> for BitBangI2c<P, C> {
    fn transaction(&mut self, address: u8, operations: &mut [Operation<'_>]) -> Result<(), Self::Error> {
        let r = self.run(address, operations);
        if let Err(e) = r {
            if e != Error::InvalidAddress {
                self.abort();
            }
        }
        r
    }
}
