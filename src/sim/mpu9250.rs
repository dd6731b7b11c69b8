//! A register-level fake MPU9250 with its AK8963 magnetometer.
//!
//! Its registers are the driver's map (`driver::compass::{mpu, ak}`).
//!
//! MPU9250 (at 0x68): WHO_AM_I (0x71), PWR_MGMT_1 with device reset
//! (H_RESET, which also clears bypass), PWR_MGMT_2, USER_CTRL, INT_PIN_CFG.
//! With INT_PIN_CFG BYPASS_EN set and the I2C master off (USER_CTRL
//! I2C_MST_EN clear) the AK8963 answers at 0x0C.
//!
//! AK8963: WIA (0x48), ST1 (DRDY, DOR), data registers (little-endian), ST2
//! (HOFL, BITM; reading it ends a read and clears DRDY), CNTL1 modes (power
//! down, single, continuous 8 Hz and 100 Hz, fuse ROM; 14- or 16-bit), CNTL2
//! soft reset, and the fuse ROM (ASA, readable in fuse-ROM mode only, 0
//! otherwise). A mode change that skips power-down is ignored (the datasheet
//! requires power-down between modes) and counted in
//! [`FakeAk8963::mode_violations`]. Samples appear on the simulated clock
//! (every 10 ms at 100 Hz).
//!
//! Truth from outside: [`FakeAk8963::set_field`] (raw counts in the chip's
//! axes as a 16-bit reading, before ASA), [`FakeAk8963::set_field_adjusted`]
//! (ASA-adjusted counts: the raw value is derived from the chip's ASA), and
//! [`FakeAk8963::set_overflow`].

use std::cell::RefCell;
use std::rc::Rc;

use super::bus::{I2cTarget, SimClock};
use crate::config::i2c::{AK8963_ADDR as AK_ADDR, MPU9250_ADDR as MPU_ADDR};
use crate::driver::compass::{ak, mpu};

/// |X| + |Y| + |Z| at or above this (16-bit counts, 4912 uT at 0.15 uT per
/// count) sets HOFL (AK8963 datasheet 6.4.3.2).
pub const OVERFLOW_SUM: i32 = 32_747;

/// What INFO reads (device information for AKM's use; any value).
const AK_INFO: u8 = 0x9A;
const PWR_MGMT_1: usize = mpu::PWR_MGMT_1 as usize;
const USER_CTRL: usize = mpu::USER_CTRL as usize;
const INT_PIN_CFG: usize = mpu::INT_PIN_CFG as usize;
const WHO_AM_I: usize = mpu::WHO_AM_I as usize;

/// The AK8963 inside the package.
pub struct FakeAk8963 {
    clock: SimClock,
    ptr: u8,
    cntl1: u8,
    asa: [u8; 3],
    field: [i16; 3],
    overflow: bool,
    st1: u8,
    data: [u8; 6],
    st2: u8,
    next_sample_ns: u64,
    mode_violations: u32,
    samples: u32,
}

impl FakeAk8963 {
    fn new(clock: SimClock) -> Self {
        FakeAk8963 {
            clock,
            ptr: 0,
            cntl1: 0,
            asa: [0xB0, 0xB2, 0xA6],
            field: [0; 3],
            overflow: false,
            st1: 0,
            data: [0; 6],
            st2: 0,
            next_sample_ns: 0,
            mode_violations: 0,
            samples: 0,
        }
    }

    /// The raw reading the chip makes from now on (16-bit counts, chip
    /// axes, before ASA; a 14-bit mode reports a quarter of it).
    pub fn set_field(&mut self, raw: [i16; 3]) {
        self.field = raw;
    }
    /// The field in ASA-adjusted counts (what a driver gets after applying
    /// the ASA): the chip reports `adjusted * 256 / (asa + 128)`.
    pub fn set_field_adjusted(&mut self, adjusted: [i32; 3]) {
        for ((f, a), asa) in self.field.iter_mut().zip(adjusted).zip(self.asa) {
            let den = i64::from(asa) + 128;
            let num = i64::from(a) * 256;
            let q = (2 * num + if num >= 0 { den } else { -den }) / (2 * den);
            *f = q.clamp(i64::from(i16::MIN), i64::from(i16::MAX)) as i16;
        }
    }
    pub fn field(&self) -> [i16; 3] {
        self.field
    }
    /// Forces the overflow flag (HOFL) on every sample while set.
    pub fn set_overflow(&mut self, overflow: bool) {
        self.overflow = overflow;
    }
    /// The fuse ROM's sensitivity adjustment.
    pub fn set_asa(&mut self, asa: [u8; 3]) {
        self.asa = asa;
    }
    pub fn asa(&self) -> [u8; 3] {
        self.asa
    }
    /// CNTL1 as the chip holds it.
    pub fn cntl1(&self) -> u8 {
        self.cntl1
    }
    /// Mode changes that skipped power-down (ignored by the chip).
    pub fn mode_violations(&self) -> u32 {
        self.mode_violations
    }
    /// Samples measured so far.
    pub fn samples(&self) -> u32 {
        self.samples
    }

    fn period_ns(&self) -> Option<u64> {
        match self.cntl1 & ak::MODE_MASK {
            ak::MODE_CONT1_8HZ => Some(125_000_000),  // 8 Hz
            ak::MODE_CONT2_100HZ => Some(10_000_000), // 100 Hz
            _ => None,
        }
    }

    fn update(&mut self) {
        let Some(period) = self.period_ns() else { return };
        let now = self.clock.now_ns();
        if now >= self.next_sample_ns {
            self.measure();
            let behind = (now - self.next_sample_ns) / period;
            self.next_sample_ns += (behind + 1) * period;
        }
    }

    fn measure(&mut self) {
        let bit16 = self.cntl1 & ak::BIT_16 != 0;
        let sum: i32 = self.field.iter().map(|v| i32::from(*v).abs()).sum();
        let hofl = self.overflow || sum >= OVERFLOW_SUM;
        for (i, v) in self.field.iter().enumerate() {
            let out = if bit16 { *v } else { *v / 4 };
            let [lo, hi] = out.to_le_bytes();
            self.data[2 * i] = lo;
            self.data[2 * i + 1] = hi;
        }
        if self.st1 & ak::DRDY != 0 {
            self.st1 |= ak::DOR; // the previous sample was never read
        }
        self.st1 |= ak::DRDY;
        self.st2 = (if hofl { ak::HOFL } else { 0 }) | (if bit16 { ak::BITM } else { 0 });
        self.samples += 1;
    }

    fn reg_read(&mut self, r: u8) -> u8 {
        match r {
            ak::WIA => ak::DEVICE_ID,
            ak::INFO => AK_INFO,
            ak::ST1 => {
                self.update();
                self.st1
            }
            ak::HXL..=ak::HZH => self.data[usize::from(r - ak::HXL)],
            ak::ST2 => {
                // reading ST2 ends the data read
                self.st1 = 0;
                self.st2
            }
            ak::CNTL1 => self.cntl1,
            ak::ASAX..=ak::ASAZ if self.cntl1 & ak::MODE_MASK == ak::MODE_FUSE_ROM => {
                self.asa[usize::from(r - ak::ASAX)]
            }
            _ => 0,
        }
    }

    fn reg_write(&mut self, r: u8, v: u8) {
        match r {
            ak::CNTL1 => {
                let (old, new) = (self.cntl1 & ak::MODE_MASK, v & ak::MODE_MASK);
                if old != ak::MODE_POWER_DOWN && new != ak::MODE_POWER_DOWN && old != new {
                    self.mode_violations += 1;
                    return;
                }
                self.cntl1 = v & (ak::BIT_16 | ak::MODE_MASK);
                if new == ak::MODE_SINGLE {
                    self.measure();
                    self.cntl1 &= ak::BIT_16; // single measurement, then power-down
                } else if let Some(p) = self.period_ns() {
                    self.next_sample_ns = self.clock.now_ns() + p;
                }
            }
            ak::CNTL2 if v & ak::SRST != 0 => {
                self.cntl1 = 0;
                self.st1 = 0;
                self.st2 = 0;
            }
            _ => {}
        }
    }
}

/// The MPU9250 (see the module docs). Share it as [`Mpu9250Handle`].
pub struct FakeMpu9250 {
    regs: [u8; 128],
    ptr: u8,
    present: bool,
    who_am_i: u8,
    resets: u32,
    pub ak: FakeAk8963,
}

/// A shared handle on a fake MPU9250.
pub type Mpu9250Handle = Rc<RefCell<FakeMpu9250>>;

impl FakeMpu9250 {
    pub fn new(clock: SimClock) -> Self {
        let mut m = FakeMpu9250 {
            regs: [0; 128],
            ptr: 0,
            present: true,
            who_am_i: mpu::MPU9250_ID,
            resets: 0,
            ak: FakeAk8963::new(clock),
        };
        m.reset();
        m
    }

    pub fn shared(clock: SimClock) -> Mpu9250Handle {
        Rc::new(RefCell::new(Self::new(clock)))
    }

    fn reset(&mut self) {
        self.regs = [0; 128];
        self.regs[PWR_MGMT_1] = mpu::CLKSEL_AUTO;
        self.regs[WHO_AM_I] = self.who_am_i;
    }

    /// True when the AK8963 is on the host bus.
    pub fn bypass(&self) -> bool {
        self.regs[INT_PIN_CFG] & mpu::BYPASS_EN != 0 && self.regs[USER_CTRL] & mpu::I2C_MST_EN == 0
    }
    /// Device resets so far.
    pub fn resets(&self) -> u32 {
        self.resets
    }
    /// A register as the chip holds it.
    pub fn register(&self, reg: u8) -> u8 {
        self.regs.get(usize::from(reg)).copied().unwrap_or(0)
    }
    /// Another identity (e.g. 0x70, an MPU6500 without magnetometer).
    pub fn set_who_am_i(&mut self, id: u8) {
        self.who_am_i = id;
        self.regs[WHO_AM_I] = id;
    }
    /// Unplugs (false) or plugs back in (true: a power cycle).
    pub fn set_present(&mut self, present: bool) {
        if present && !self.present {
            self.reset();
            let clock = self.ak.clock.clone();
            let asa = self.ak.asa;
            let field = self.ak.field;
            self.ak = FakeAk8963::new(clock);
            self.ak.asa = asa;
            self.ak.field = field;
        }
        self.present = present;
    }

    fn reg_write(&mut self, r: u8, v: u8) {
        let Some(slot) = self.regs.get_mut(usize::from(r)) else { return };
        if usize::from(r) == WHO_AM_I {
            return;
        }
        *slot = v;
        if usize::from(r) == PWR_MGMT_1 && v & mpu::H_RESET != 0 {
            self.resets += 1;
            self.reset();
        }
    }
}

impl I2cTarget for FakeMpu9250 {
    fn acks(&self, addr: u8) -> bool {
        self.present && (addr == MPU_ADDR || (addr == AK_ADDR && self.bypass()))
    }

    fn write(&mut self, addr: u8, data: &[u8]) {
        let Some((&reg, values)) = data.split_first() else { return };
        if addr == AK_ADDR {
            self.ak.ptr = reg;
            for &v in values {
                let r = self.ak.ptr;
                self.ak.reg_write(r, v);
                self.ak.ptr = self.ak.ptr.wrapping_add(1);
            }
        } else {
            self.ptr = reg;
            for &v in values {
                let r = self.ptr;
                self.reg_write(r, v);
                self.ptr = self.ptr.wrapping_add(1);
            }
        }
    }

    fn read(&mut self, addr: u8, buf: &mut [u8]) {
        for b in buf.iter_mut() {
            if addr == AK_ADDR {
                let r = self.ak.ptr;
                *b = self.ak.reg_read(r);
                self.ak.ptr = self.ak.ptr.wrapping_add(1);
            } else {
                *b = self.regs.get(usize::from(self.ptr)).copied().unwrap_or(0);
                self.ptr = self.ptr.wrapping_add(1);
            }
        }
    }
}
