//! Servo pulses from the FRC1 timer interrupt: the scheduling arithmetic and
//! the loop-to-interrupt handoff, independent of the chip.
//!
//! # Frame
//! Every 20 ms frame ([`config::servo::FRAME_US`]) has four edges, each
//! driven by one FRC1 interrupt:
//!
//! ```text
//! t = 0            left pin high        (widths for the frame latched here)
//! t = wL           left pin low
//! t = S            right pin high       (S = config::board::SERVO_STAGGER_US)
//! t = S + wR       right pin low
//! t = FRAME        next frame
//! ```
//!
//! # Latency independence
//! Edge times are absolute CCOUNT values (the lx106's free-running 80 MHz
//! cycle counter): each edge is exactly its interval after the previous
//! *planned* edge, so errors never accumulate. FRC1 (a 23-bit down counter
//! at 80 MHz / 16) only raises the interrupt [`GUARD_CYCLES`] *before* an
//! edge; the handler then spins on CCOUNT until the edge's cycle and only
//! then writes the pin. Any interrupt latency below the guard therefore moves
//! no edge: an edge lands within one CCOUNT poll (a few cycles, < 0.1 us) of
//! its planned cycle. The FRC1 alarm itself may be off by a tick or two (it
//! is programmed by writing `FRC1_LOAD`, which restarts the counter); that
//! only eats into the guard.
//!
//! If the latency ever exceeds the guard (interrupts masked for > 20 us), the
//! edge is late; the schedule re-anchors on the real edge, so a late rising
//! edge still gives an exact pulse width (a late falling edge lengthens that
//! one pulse by its lateness). Such edges are counted in
//! [`PulseScheduler::late_edges`].
//!
//! # Handoff without CAS
//! The ESP8266 has no compare-and-swap (atomics are load/store only). Both
//! widths fit in one `AtomicU32` ([`PulseMailbox`]): the loop stores the pair
//! with one store, the interrupt loads it with one load at the start of each
//! frame, so the pair is never torn and a frame never mixes old and new
//! widths. One writer (the loop) and one reader (the ISR): no read-modify-write
//! is ever needed.
//!
//! # Interface to the servo driver
//! The driver maps commands to [`PulseWidthUs`] and hands both to a
//! [`PulseOutput`] (implemented by [`ServoPulses`], a handle on the mailbox).
//! Widths are clamped to [`config::servo::SAFE_MIN_US`]..=`SAFE_MAX_US` on the
//! way in and again when the frame is latched; [`PulseWidthUs::OFF`] (0)
//! keeps that pin low (no pulses: the FS90R stands still).

use core::sync::atomic::{AtomicU32, Ordering};

use crate::config;
use crate::driver::servo::{PulseOutput, PulseWidthUs};

/// CPU cycles (CCOUNT counts) per microsecond: 80.
pub const CYCLES_PER_US: u32 = config::board::CPU_HZ / 1_000_000;
/// CPU cycles per FRC1 tick: the timer runs at APB / prescaler = 5 MHz, 16 cycles.
pub const CYCLES_PER_TICK: u32 = config::board::CPU_HZ / (config::board::APB_HZ / config::board::FRC1_PRESCALER);
/// The FRC1 counter is 23 bits wide.
pub const FRC1_MAX: u32 = (1 << 23) - 1;
/// The alarm comes this many cycles before its edge.
pub const GUARD_CYCLES: u32 = config::board::SERVO_EDGE_GUARD_US * CYCLES_PER_US;
/// The longest pulse, cycles.
pub const MAX_WIDTH_CYCLES: u32 = config::servo::SAFE_MAX_US * CYCLES_PER_US;
/// One frame, cycles.
pub const FRAME_CYCLES: u32 = config::servo::FRAME_US * CYCLES_PER_US;
/// Rising edge of the right pulse after the left one, cycles.
pub const STAGGER_CYCLES: u32 = config::board::SERVO_STAGGER_US * CYCLES_PER_US;
/// Smallest value ever written to FRC1_LOAD (1 tick): a late schedule fires
/// as soon as possible.
pub const MIN_LOAD_TICKS: u32 = 1;
/// Delay from [`PulseScheduler::start`] to the first edge, cycles (1 ms).
pub const START_DELAY_CYCLES: u32 = 1_000 * CYCLES_PER_US;
/// An edge made more than this after its planned cycle counts as late (the
/// interrupt came after the guard), cycles: two CCOUNT polls of slack.
pub const LATE_SLACK_CYCLES: u32 = 16;
/// Worst-case time the handler needs after an edge before the next alarm
/// may come (entry + spin exit + bookkeeping, a few us in IRAM), us; only
/// used to check the configuration below.
pub const HANDLER_US: u32 = 30;

// Whole cycles per tick and per us, and every interval between edges leaves
// room for the guard and one handler run.
const _: () = {
    assert!(CYCLES_PER_US * 1_000_000 == config::board::CPU_HZ);
    assert!(CYCLES_PER_TICK * (config::board::APB_HZ / config::board::FRC1_PRESCALER) == config::board::CPU_HZ);
    assert!(config::servo::SAFE_MIN_US <= config::servo::SAFE_MAX_US);
    assert!(config::servo::SAFE_MAX_US <= u16::MAX as u32);
    let need = config::board::SERVO_EDGE_GUARD_US + HANDLER_US;
    // left rise -> left fall, right rise -> right fall
    assert!(config::servo::SAFE_MIN_US >= need);
    // left fall -> right rise
    assert!(config::board::SERVO_STAGGER_US >= config::servo::SAFE_MAX_US + need);
    // right fall -> next frame's left rise
    assert!(config::servo::FRAME_US >= config::board::SERVO_STAGGER_US + config::servo::SAFE_MAX_US + need);
    // the longest wait fits in FRC1, and every cycle difference in an i32
    assert!(FRAME_CYCLES / CYCLES_PER_TICK <= FRC1_MAX);
    assert!(FRAME_CYCLES < i32::MAX as u32);
    assert!(START_DELAY_CYCLES > GUARD_CYCLES);
};

/// A width in CPU cycles after clamping (0 for OFF), at most
/// [`MAX_WIDTH_CYCLES`].
// IRAM: part of the FRC1 interrupt handler (see `on_alarm`)
#[inline(always)]
const fn width_cycles(w: PulseWidthUs) -> u32 {
    // <= SAFE_MAX_US * 80 (asserted to fit above): exact, never saturates.
    (PulseWidthUs::safe(w.0 as u32).0 as u32).saturating_mul(CYCLES_PER_US)
}

/// The loop-to-interrupt mailbox: both widths in one 32-bit word (left in
/// the high half), written with a single store and read with a single load.
pub struct PulseMailbox {
    word: AtomicU32,
}

impl PulseMailbox {
    /// Both servos off.
    pub const fn new() -> Self {
        Self { word: AtomicU32::new(0) }
    }

    /// Publishes both widths (clamped) in one store. Called by the loop.
    pub fn publish(&self, left: PulseWidthUs, right: PulseWidthUs) {
        let l = PulseWidthUs::safe(u32::from(left.0)).0;
        let r = PulseWidthUs::safe(u32::from(right.0)).0;
        self.word.store(u32::from(l) << 16 | u32::from(r), Ordering::Release);
    }

    /// The newest pair (left, right) in one load. Called by the interrupt.
    // IRAM: part of the FRC1 interrupt handler (see `on_alarm`)
    #[inline(always)]
    pub fn latest(&self) -> (PulseWidthUs, PulseWidthUs) {
        let w = self.word.load(Ordering::Acquire);
        (PulseWidthUs((w >> 16) as u16), PulseWidthUs(w as u16))
    }
}

impl Default for PulseMailbox {
    fn default() -> Self {
        Self::new()
    }
}

/// The loop's handle on the mailbox.
pub struct ServoPulses<'a> {
    mailbox: &'a PulseMailbox,
}

impl<'a> ServoPulses<'a> {
    pub const fn new(mailbox: &'a PulseMailbox) -> Self {
        Self { mailbox }
    }
}

impl PulseOutput for ServoPulses<'_> {
    fn set_widths(&mut self, left: PulseWidthUs, right: PulseWidthUs) {
        self.mailbox.publish(left, right);
    }
}

/// Which servo pin an edge is on.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum Channel {
    Left,
    Right,
}

/// The four edges of a frame, in order.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum Phase {
    LeftRise,
    LeftFall,
    RightRise,
    RightFall,
}

impl Phase {
    // IRAM: part of the FRC1 interrupt handler (see `on_alarm`)
    #[inline(always)]
    const fn next(self) -> Self {
        match self {
            Phase::LeftRise => Phase::LeftFall,
            Phase::LeftFall => Phase::RightRise,
            Phase::RightRise => Phase::RightFall,
            Phase::RightFall => Phase::LeftRise,
        }
    }
}

/// One planned edge: which pin, which level, and the time to the next edge.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub struct PlannedEdge {
    pub channel: Channel,
    pub high: bool,
    /// Cycles from this edge to the next one.
    pub interval: u32,
}

/// The widths of one frame, in cycles (0 = off), latched at its first edge.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub struct FramePlan {
    left: u32,
    right: u32,
}

impl FramePlan {
    // IRAM: part of the FRC1 interrupt handler (see `on_alarm`)
    #[inline(always)]
    pub const fn new(left: PulseWidthUs, right: PulseWidthUs) -> Self {
        Self { left: width_cycles(left), right: width_cycles(right) }
    }

    /// The edge of `phase`. An OFF channel gets its "fall" at the shortest
    /// width with both edges low, so the frame keeps its shape.
    /// Intervals: each >= SAFE_MIN_US or >= STAGGER - SAFE_MAX, and they sum
    /// to FRAME_CYCLES.
    // IRAM: part of the FRC1 interrupt handler (see `on_alarm`)
    #[inline(always)]
    pub const fn edge(&self, phase: Phase) -> PlannedEdge {
        const MIN: u32 = config::servo::SAFE_MIN_US * CYCLES_PER_US;
        // Both widths come from `PulseWidthUs::cycles` (or are 0), so
        // l, r <= MAX_WIDTH_CYCLES; the config asserts STAGGER >= SAFE_MAX +
        // guard and FRAME >= STAGGER + SAFE_MAX + guard, so the subtractions
        // below are exact and never saturate.
        let l = if self.left == 0 { MIN } else { self.left };
        let r = if self.right == 0 { MIN } else { self.right };
        match phase {
            Phase::LeftRise => PlannedEdge { channel: Channel::Left, high: self.left != 0, interval: l },
            Phase::LeftFall => {
                PlannedEdge { channel: Channel::Left, high: false, interval: STAGGER_CYCLES.saturating_sub(l) }
            }
            Phase::RightRise => PlannedEdge { channel: Channel::Right, high: self.right != 0, interval: r },
            Phase::RightFall => PlannedEdge {
                channel: Channel::Right,
                high: false,
                interval: (FRAME_CYCLES - STAGGER_CYCLES).saturating_sub(r),
            },
        }
    }
}

/// What the interrupt handler needs from the chip.
pub trait PulseTimer {
    /// CCOUNT: the free-running CPU cycle counter (wraps every 53 s).
    fn cycles(&mut self) -> u32;
    /// Writes FRC1_LOAD: the counter restarts from `ticks` at once and
    /// raises the interrupt when it reaches zero.
    fn load(&mut self, ticks: u32);
    fn set_pin(&mut self, channel: Channel, high: bool);
}

/// The interrupt side: which edge comes next and when. Owned by the FRC1
/// handler alone.
#[derive(Debug)]
pub struct PulseScheduler {
    phase: Phase,
    plan: FramePlan,
    /// CCOUNT of the next edge.
    target: u32,
    late_edges: u32,
    frames: u32,
}

impl PulseScheduler {
    pub const fn new() -> Self {
        Self { phase: Phase::LeftRise, plan: FramePlan { left: 0, right: 0 }, target: 0, late_edges: 0, frames: 0 }
    }

    /// Pins low and the first alarm armed; the first frame starts
    /// [`START_DELAY_CYCLES`] from now.
    pub fn start<T: PulseTimer>(&mut self, hw: &mut T) {
        hw.set_pin(Channel::Left, false);
        hw.set_pin(Channel::Right, false);
        self.phase = Phase::LeftRise;
        self.target = hw.cycles().wrapping_add(START_DELAY_CYCLES);
        hw.load((START_DELAY_CYCLES - GUARD_CYCLES) / CYCLES_PER_TICK);
    }

    /// The FRC1 interrupt: makes the due edge at its exact cycle and arms the
    /// alarm for the next one. Inlined, with everything it calls, so the
    /// whole handler sits in IRAM (`#[ram]` places only the handler itself).
    // IRAM: inlined into the `#[ram]` handler
    #[inline(always)]
    pub fn on_alarm<T: PulseTimer>(&mut self, hw: &mut T, mailbox: &PulseMailbox) {
        if self.phase == Phase::LeftRise {
            let (l, r) = mailbox.latest();
            self.plan = FramePlan::new(l, r);
            self.frames = self.frames.wrapping_add(1);
        }
        let edge = self.plan.edge(self.phase);
        // Spin to the edge's cycle. Differences are taken as i32: the target
        // is never more than one frame (1.6e6 cycles) away.
        let mut late = hw.cycles().wrapping_sub(self.target) as i32;
        while late < 0 {
            late = hw.cycles().wrapping_sub(self.target) as i32;
        }
        hw.set_pin(edge.channel, edge.high);
        // late >= 0 here.
        let late = late as u32;
        if late > LATE_SLACK_CYCLES {
            // The interrupt came after the guard: re-anchor on the real edge.
            self.late_edges = self.late_edges.wrapping_add(1);
            self.target = self.target.wrapping_add(late);
        }
        self.target = self.target.wrapping_add(edge.interval);
        // Alarm GUARD_CYCLES before the next edge (rounded down to a tick:
        // early, never late).
        let until_alarm = self.target.wrapping_sub(GUARD_CYCLES).wrapping_sub(hw.cycles()) as i32;
        let ticks = if until_alarm > 0 { until_alarm as u32 / CYCLES_PER_TICK } else { 0 };
        hw.load(ticks.clamp(MIN_LOAD_TICKS, FRC1_MAX));
        self.phase = self.phase.next();
    }

    /// Edges made later than [`LATE_SLACK_CYCLES`] after their cycle
    /// (interrupt latency above the guard).
    pub const fn late_edges(&self) -> u32 {
        self.late_edges
    }

    /// Frames started.
    pub const fn frames(&self) -> u32 {
        self.frames
    }

    pub const fn phase(&self) -> Phase {
        self.phase
    }
}

impl Default for PulseScheduler {
    fn default() -> Self {
        Self::new()
    }
}

#[cfg(test)]
mod tests;
