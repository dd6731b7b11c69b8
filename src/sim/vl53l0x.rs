//! A register-level fake VL53L0X: as much of the chip as the `vl53l0x`
//! crate's initialisation and our continuous reads touch.
//!
//! Modelled: identity registers (0xC0 = 0xEE), the page register (0xFF) and
//! the paged registers behind it (stop variable at page 1 0x91, the SPAD
//! info handshake at page 7 0x83/0x92), the timing registers with the
//! chip's defaults, the address change (0x8A), the XSHUT pin (low: off and
//! reset to 0x29; high: answers after the 1.2 ms boot time of the
//! datasheet), single-shot and reference-calibration starts (SYSRANGE_START
//! bit 0), continuous back-to-back ranging (one result per measurement
//! period of simulated time), the interrupt status and clear, and the range
//! result (0x1E, big-endian mm). The truth comes from outside:
//! [`FakeVl53l0x::set_distance_mm`] (what the chip reports, 8190 = no
//! target).
//!
//! A continuous result is measured over its whole period, not at the
//! instant it is ready: ST's datasheet (DocID029104, "Ranging modes":
//! back-to-back ranging starts the next measurement as soon as one
//! ends) and its API manual (UM2039: the timing budget is the time one
//! range measurement takes, 33 ms by default). So a result reports the
//! distance set nearest the middle of its measurement, half a period
//! before it is due (`FakeVl53l0x::distance_at`): a sensor on a turning
//! body reads where it pointed about 17 ms earlier, 2.3 degrees at the
//! survey's turn rate. Single-shot starts report at once.

use std::cell::RefCell;
use std::collections::{BTreeMap, VecDeque};
use std::rc::Rc;

use embedded_hal::digital::{ErrorType, OutputPin};

use super::bus::{I2cTarget, SimClock};

/// Boot time after XSHUT goes high, ns (datasheet tBOOT 1.2 ms).
pub const BOOT_NS: u64 = 1_200_000;
/// Default measurement period in continuous back-to-back mode, ns (the
/// default 33 ms timing budget).
pub const DEFAULT_PERIOD_NS: u64 = 33_000_000;
/// The boot address.
pub const DEFAULT_ADDR: u8 = 0x29;
/// Reads of page 7 register 0x83 before the SPAD info is ready.
const SPAD_BUSY_READS: u8 = 3;
/// SPAD info (page 7, 0x92): 5 reference SPADs, aperture type.
const SPAD_INFO: u8 = 0x85;
/// Stop variable (page 1, 0x91).
const STOP_VARIABLE: u8 = 0x3C;

#[derive(Clone, Copy, PartialEq, Eq, Debug)]
enum Mode {
    Idle,
    Continuous,
}

/// The fake chip (see the module docs). Share it as [`Vl53l0xHandle`].
pub struct FakeVl53l0x {
    clock: SimClock,
    addr: u8,
    /// XSHUT high.
    powered: bool,
    /// Plugged in (a test can pull it out).
    present: bool,
    ready_at_ns: u64,
    page: u8,
    page0: [u8; 256],
    paged: BTreeMap<(u8, u8), u8>,
    ptr: u8,
    distance_mm: u16,
    /// The distances set over the last few periods, oldest first, and
    /// when (ns): a continuous result reports the one set nearest the
    /// middle of its measurement.
    history: VecDeque<(u64, u16)>,
    mode: Mode,
    period_ns: u64,
    next_result_ns: u64,
    int_status: u8,
    spad_busy: u8,
    /// Results latched so far.
    results: u32,
}

/// A shared handle on a fake lidar.
pub type Vl53l0xHandle = Rc<RefCell<FakeVl53l0x>>;

impl FakeVl53l0x {
    /// A chip with XSHUT pulled high (as on the board at power-up): awake
    /// at 0x29 once the boot time has passed.
    pub fn new(clock: SimClock) -> Self {
        let now = clock.now_ns();
        let mut chip = FakeVl53l0x {
            clock,
            addr: DEFAULT_ADDR,
            powered: true,
            present: true,
            ready_at_ns: now + BOOT_NS,
            page: 0,
            page0: [0; 256],
            paged: BTreeMap::new(),
            ptr: 0,
            distance_mm: 8190,
            history: VecDeque::new(),
            mode: Mode::Idle,
            period_ns: DEFAULT_PERIOD_NS,
            next_result_ns: 0,
            int_status: 0,
            spad_busy: 0,
            results: 0,
        };
        chip.reset_registers();
        chip
    }

    /// A shared handle.
    pub fn shared(clock: SimClock) -> Vl53l0xHandle {
        Rc::new(RefCell::new(Self::new(clock)))
    }

    fn reset_registers(&mut self) {
        self.addr = DEFAULT_ADDR;
        self.page = 0;
        self.page0 = [0; 256];
        self.paged.clear();
        self.ptr = 0;
        self.mode = Mode::Idle;
        self.int_status = 0;
        self.spad_busy = 0;
        let defaults: [(u8, u8); 13] = [
            (0x01, 0xFF), // SYSTEM_SEQUENCE_CONFIG
            (0x46, 0x25), // MSRC_CONFIG_TIMEOUT_MACROP
            (0x50, 0x06), // PRE_RANGE_CONFIG_VCSEL_PERIOD: 14 PCLK
            (0x51, 0x00), // PRE_RANGE_CONFIG_TIMEOUT_MACROP_HI
            (0x52, 0x96),
            (0x70, 0x04), // FINAL_RANGE_CONFIG_VCSEL_PERIOD: 10 PCLK
            (0x71, 0x02), // FINAL_RANGE_CONFIG_TIMEOUT_MACROP_HI
            (0x72, 0x6B),
            (0x84, 0x11), // GPIO_HV_MUX_ACTIVE_HIGH
            (0x8A, DEFAULT_ADDR),
            (0xC0, 0xEE), // identification: model ID
            (0xC1, 0xAA), // module type
            (0xC2, 0x10), // revision ID
        ];
        for (r, v) in defaults {
            self.page0[usize::from(r)] = v;
        }
        // GLOBAL_CONFIG_SPAD_ENABLES_REF_0..5: every SPAD good.
        for r in 0xB0..=0xB5 {
            self.page0[r] = 0xFF;
        }
    }

    /// What the chip measures from now on, mm (8190: no target).
    pub fn set_distance_mm(&mut self, mm: u16) {
        let now = self.clock.now_ns();
        // what was set more than two periods ago no measurement reads
        let keep_from = now.saturating_sub(2 * self.period_ns);
        while self.history.len() > 1 && self.history.get(1).is_some_and(|&(t, _)| t <= keep_from) {
            self.history.pop_front();
        }
        if self.history.is_empty() {
            // the distance before: in effect since the start
            self.history.push_back((0, self.distance_mm));
        }
        match self.history.back_mut() {
            // set again at the same instant (a hand over the wall): the
            // last one set is what the chip sees
            Some((t, set)) if *t == now => *set = mm,
            _ => self.history.push_back((now, mm)),
        }
        self.distance_mm = mm;
    }

    /// The distance set nearest the time `t_ns` (see the module docs).
    fn distance_at(&self, t_ns: u64) -> u16 {
        self.history.iter().min_by_key(|&&(t, _)| t.abs_diff(t_ns)).map_or(self.distance_mm, |&(_, mm)| mm)
    }
    pub fn distance_mm(&self) -> u16 {
        self.distance_mm
    }
    /// Nothing in range (the chip reports 8190).
    pub fn set_no_target(&mut self) {
        self.set_distance_mm(8190);
    }
    /// The measurement period in continuous mode, ns.
    pub fn set_period_ns(&mut self, ns: u64) {
        self.period_ns = ns.max(1);
    }
    /// The address the chip answers at.
    pub fn address(&self) -> u8 {
        self.addr
    }
    pub fn is_powered(&self) -> bool {
        self.powered
    }
    pub fn is_ranging(&self) -> bool {
        self.mode == Mode::Continuous
    }
    /// Results measured so far.
    pub fn results(&self) -> u32 {
        self.results
    }
    /// A page-0 register as the chip holds it.
    pub fn register(&self, reg: u8) -> u8 {
        self.page0[usize::from(reg)]
    }
    /// Unplugs (false) or plugs back in (true, a power cycle: back at 0x29
    /// after the boot time if XSHUT is high).
    pub fn set_present(&mut self, present: bool) {
        if present && !self.present {
            self.power_cycle();
        }
        self.present = present;
    }
    /// XSHUT level (what [`XshutPin`] drives).
    pub fn set_xshut(&mut self, high: bool) {
        if high && !self.powered {
            self.powered = true;
            self.power_cycle();
        } else if !high {
            self.powered = false;
            self.reset_registers();
        }
    }

    fn power_cycle(&mut self) {
        self.reset_registers();
        self.ready_at_ns = self.clock.now_ns() + BOOT_NS;
    }

    fn awake(&self) -> bool {
        self.present && self.powered && self.clock.now_ns() >= self.ready_at_ns
    }

    /// Latches a result if one is due.
    fn update(&mut self) {
        if self.mode != Mode::Continuous {
            return;
        }
        let now = self.clock.now_ns();
        if now >= self.next_result_ns {
            // the newest result due, measured over the period before it
            let behind = (now - self.next_result_ns) / self.period_ns;
            let due = self.next_result_ns + behind * self.period_ns;
            let mm = self.distance_at(due.saturating_sub(self.period_ns / 2));
            self.latch(mm);
            // Next result one period after the last one due (catch up).
            self.next_result_ns = due + self.period_ns;
        }
    }

    fn latch(&mut self, mm: u16) {
        let [hi, lo] = mm.to_be_bytes();
        self.page0[0x14] = 0x0B; // RESULT_RANGE_STATUS: range valid
        self.page0[0x1E] = hi;
        self.page0[0x1F] = lo;
        self.int_status = 0x04; // new sample ready
        self.results += 1;
    }

    fn reg_read(&mut self, r: u8) -> u8 {
        if r == 0xFF {
            return self.page;
        }
        if self.page != 0 {
            return match (self.page, r) {
                (7, 0x83) if self.spad_busy > 0 => {
                    self.spad_busy -= 1;
                    if self.spad_busy == 0 {
                        0x10
                    } else {
                        0x00
                    }
                }
                (7, 0x92) => SPAD_INFO,
                (1, 0x91) => STOP_VARIABLE,
                _ => self.paged.get(&(self.page, r)).copied().unwrap_or(0),
            };
        }
        match r {
            0x00 => self.page0[0] & !0x01, // start bit clears itself
            0x13 => {
                self.update();
                self.int_status
            }
            0x8A => self.addr,
            _ => self.page0[usize::from(r)],
        }
    }

    fn reg_write(&mut self, r: u8, v: u8) {
        if r == 0xFF {
            self.page = v;
            return;
        }
        if self.page != 0 {
            if (self.page, r, v) == (7, 0x83, 0x00) && self.paged.get(&(7, 0x94)) == Some(&0x6B) {
                self.spad_busy = SPAD_BUSY_READS;
            }
            self.paged.insert((self.page, r), v);
            return;
        }
        match r {
            0x00 => {
                self.page0[0] = v;
                if v & 0x01 != 0 {
                    // single shot or reference calibration: done at once
                    self.mode = Mode::Idle;
                    self.latch(self.distance_mm);
                } else if v & 0x06 != 0 {
                    self.mode = Mode::Continuous;
                    self.next_result_ns = self.clock.now_ns() + self.period_ns;
                } else {
                    self.mode = Mode::Idle;
                }
            }
            0x0B => {
                if v & 0x01 != 0 {
                    self.int_status = 0;
                }
            }
            0x8A => self.addr = v & 0x7F,
            _ => self.page0[usize::from(r)] = v,
        }
    }
}

impl I2cTarget for FakeVl53l0x {
    fn acks(&self, addr: u8) -> bool {
        self.awake() && addr == self.addr
    }

    fn write(&mut self, _addr: u8, data: &[u8]) {
        let Some((&reg, values)) = data.split_first() else { return };
        self.ptr = reg;
        for &v in values {
            let r = self.ptr;
            self.reg_write(r, v);
            self.ptr = self.ptr.wrapping_add(1);
        }
    }

    fn read(&mut self, _addr: u8, buf: &mut [u8]) {
        for b in buf.iter_mut() {
            let r = self.ptr;
            *b = self.reg_read(r);
            self.ptr = self.ptr.wrapping_add(1);
        }
    }
}

/// The lidar's XSHUT pin (embedded-hal 1.0 `OutputPin`), wired to a fake.
#[derive(Clone)]
pub struct XshutPin(pub Vl53l0xHandle);

impl ErrorType for XshutPin {
    type Error = core::convert::Infallible;
}

impl OutputPin for XshutPin {
    fn set_low(&mut self) -> Result<(), Self::Error> {
        self.0.borrow_mut().set_xshut(false);
        Ok(())
    }
    fn set_high(&mut self) -> Result<(), Self::Error> {
        self.0.borrow_mut().set_xshut(true);
        Ok(())
    }
}
