//! The pulse scheduler against a model of the chip's timer and cycle
//! counter (`SimChip`): exact widths whatever the handler's latency below
//! the guard, no drift over frames, a late edge counted, new widths only
//! at a frame's start, an off channel low, the plan's intervals summing to
//! the frame, the mailbox's clamp, the timer constants.

#![allow(clippy::restriction)] // test code: a panic fails the test

use super::*;
extern crate std;
use std::vec::Vec;

const CYCLES_PER_US_64: u64 = CYCLES_PER_US as u64;

/// The chip as the handler sees it: CCOUNT, FRC1 as a one-shot alarm
/// that counts on the 5 MHz tick grid, and the two pins. Time runs in
/// CPU cycles; every access costs cycles like on the chip (CCOUNT poll 3,
/// an FRC1 or GPIO register access taken as 10).
struct SimChip {
    now: u64,
    alarm_at: u64,
    pins: [bool; 2],
    edges: Vec<(u64, Channel, bool)>,
}

impl SimChip {
    fn new() -> Self {
        Self { now: 0, alarm_at: 0, pins: [false; 2], edges: Vec::new() }
    }
}

impl PulseTimer for SimChip {
    fn cycles(&mut self) -> u32 {
        self.now += 3;
        self.now as u32
    }
    fn load(&mut self, ticks: u32) {
        self.now += 10;
        assert!(ticks > 0 && ticks <= FRC1_MAX);
        // the counter decrements on the free-running tick grid
        let tick = u64::from(CYCLES_PER_TICK);
        self.alarm_at = (self.now / tick + u64::from(ticks)) * tick;
    }
    fn set_pin(&mut self, channel: Channel, high: bool) {
        self.now += 10;
        let i = match channel {
            Channel::Left => 0,
            Channel::Right => 1,
        };
        if self.pins[i] != high {
            self.pins[i] = high;
            self.edges.push((self.now, channel, high));
        }
    }
}

/// xorshift, for repeatable pseudo-random latencies.
struct Rng(u32);
impl Rng {
    fn next(&mut self) -> u32 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 17;
        self.0 ^= self.0 << 5;
        self.0
    }
}

/// Runs `alarms` interrupts, each entered `latency(i)` cycles after its
/// alarm, with `widths(i)` published before alarm i.
fn run(
    alarms: usize,
    mut latency: impl FnMut(usize) -> u64,
    mut widths: impl FnMut(usize) -> Option<(u16, u16)>,
) -> (SimChip, PulseScheduler) {
    let mut hw = SimChip::new();
    let mailbox = PulseMailbox::new();
    let mut s = PulseScheduler::new();
    s.start(&mut hw);
    for i in 0..alarms {
        if let Some((l, r)) = widths(i) {
            mailbox.publish(PulseWidthUs(l), PulseWidthUs(r));
        }
        assert!(hw.alarm_at >= hw.now, "alarm in the past");
        hw.now = hw.alarm_at + latency(i);
        s.on_alarm(&mut hw, &mailbox);
    }
    (hw, s)
}

/// (rise, fall) cycle pairs for one channel.
fn pulses(hw: &SimChip, ch: Channel) -> Vec<(u64, u64)> {
    let e: Vec<_> = hw.edges.iter().filter(|e| e.1 == ch).collect();
    e.chunks(2)
        .filter(|p| p.len() == 2)
        .map(|p| {
            assert!(p[0].2 && !p[1].2, "edges alternate");
            (p[0].0, p[1].0)
        })
        .collect()
}

/// Edge error allowed: one CCOUNT poll (the pin write follows the first
/// poll that sees the edge's cycle).
const TOLERANCE_CYCLES: i64 = 3;

#[test]
fn widths_are_exact_whatever_the_latency_below_the_guard() {
    let guard_cycles = u64::from(GUARD_CYCLES);
    // Table: (left us, right us, latency pattern)
    let table: &[(u16, u16, u64)] =
        &[(1500, 1500, 0), (700, 2300, 1), (2300, 700, 2), (1200, 1800, 3), (544, 2400, 2), (1000, 2000, 3)];
    for &(l, r, pattern) in table {
        let mut rng = Rng(0x1234_5678 + pattern as u32);
        let latency = |_| match pattern {
            0 => 0,
            1 => guard_cycles - 40,
            _ => u64::from(rng.next()) % (guard_cycles - 40),
        };
        let (hw, s) = run(4 * 50, latency, |i| (i == 0).then_some((l, r)));
        assert_eq!(s.late_edges(), 0);
        let (lw, rw) = (PulseWidthUs::safe(l.into()), PulseWidthUs::safe(r.into()));
        for (ch, w) in [(Channel::Left, lw), (Channel::Right, rw)] {
            let p = pulses(&hw, ch);
            assert_eq!(p.len(), 50, "{ch:?}");
            for &(rise, fall) in &p {
                let err = (fall - rise) as i64 - i64::from(w.0) * CYCLES_PER_US as i64;
                assert!(err.abs() <= TOLERANCE_CYCLES, "{l}/{r} p{pattern} {ch:?}: err {err} cycles");
            }
            // frames: rise to rise = 20 ms within the same tolerance
            for w2 in p.windows(2) {
                let err = (w2[1].0 - w2[0].0) as i64 - i64::from(config::servo::FRAME_US) * CYCLES_PER_US as i64;
                assert!(err.abs() <= TOLERANCE_CYCLES, "frame err {err}");
            }
        }
        // stagger: right rises S after left
        let (pl, pr) = (pulses(&hw, Channel::Left), pulses(&hw, Channel::Right));
        for (a, b) in pl.iter().zip(&pr) {
            let err = (b.0 - a.0) as i64 - i64::from(config::board::SERVO_STAGGER_US) * CYCLES_PER_US as i64;
            assert!(err.abs() <= TOLERANCE_CYCLES, "stagger err {err}");
        }
    }
}

#[test]
fn no_drift_over_many_frames() {
    // 500 frames = 10 s: the frame grid stays put (errors do not add up).
    let mut rng = Rng(99);
    let (hw, _) = run(4 * 500, |_| u64::from(rng.next() % 1_500), |i| (i == 0).then_some((1500, 1500)));
    let p = pulses(&hw, Channel::Left);
    let first = p[0].0 as i64;
    let last = p[p.len() - 1].0 as i64;
    let want = (p.len() as i64 - 1) * i64::from(config::servo::FRAME_US) * CYCLES_PER_US as i64;
    assert!((last - first - want).abs() <= TOLERANCE_CYCLES, "drift {}", last - first - want);
}

#[test]
fn a_late_rising_edge_keeps_its_width_and_is_counted() {
    let guard_cycles = u64::from(GUARD_CYCLES);
    // The 9th alarm (frame 2's left rise) comes 50 us late.
    let (hw, s) = run(
        4 * 4,
        |i| if i == 8 { guard_cycles + 50 * CYCLES_PER_US_64 } else { 0 },
        |i| (i == 0).then_some((1300, 1700)),
    );
    assert_eq!(s.late_edges(), 1);
    for &(rise, fall) in &pulses(&hw, Channel::Left) {
        let err = (fall - rise) as i64 - 1300 * CYCLES_PER_US as i64;
        assert!(err.abs() <= TOLERANCE_CYCLES, "err {err}");
    }
}

#[test]
fn new_widths_apply_at_the_next_frame_start_never_mid_frame() {
    // Alarm 1 (left fall) and 3 (right fall): publish between the edges
    // of frame 0; frame 0 keeps 1000/1000, frame 1 gets 2000/1800.
    let (hw, _) = run(
        4 * 3,
        |_| 0,
        |i| match i {
            0 => Some((1000, 1000)),
            1 => Some((2000, 1800)),
            _ => None,
        },
    );
    let want = [(1000, 1000), (2000, 1800), (2000, 1800)];
    let (pl, pr) = (pulses(&hw, Channel::Left), pulses(&hw, Channel::Right));
    for (f, &(l, r)) in want.iter().enumerate() {
        for (p, w) in [(pl[f], l), (pr[f], r)] {
            let err = (p.1 - p.0) as i64 - w * CYCLES_PER_US as i64;
            assert!(err.abs() <= TOLERANCE_CYCLES, "frame {f}: err {err}");
        }
    }
}

#[test]
fn off_channel_stays_low_and_the_other_keeps_its_timing() {
    let (hw, s) = run(4 * 5, |_| 0, |i| (i == 0).then_some((0, 1500)));
    assert!(pulses(&hw, Channel::Left).is_empty());
    assert!(hw.edges.iter().all(|e| e.1 == Channel::Right));
    let pr = pulses(&hw, Channel::Right);
    assert_eq!(pr.len(), 5);
    for w in pr.windows(2) {
        let err = (w[1].0 - w[0].0) as i64 - i64::from(config::servo::FRAME_US) * CYCLES_PER_US as i64;
        assert!(err.abs() <= TOLERANCE_CYCLES);
    }
    assert_eq!(s.frames(), 5);
}

#[test]
fn plan_intervals_sum_to_the_frame_for_every_width() {
    let widths = [0u16, 1, 544, 699, 700, 1500, 2300, 2301, 2400, u16::MAX];
    for &l in &widths {
        for &r in &widths {
            let plan = FramePlan::new(PulseWidthUs(l), PulseWidthUs(r));
            let phases = [Phase::LeftRise, Phase::LeftFall, Phase::RightRise, Phase::RightFall];
            let sum: u32 = phases.iter().map(|&p| plan.edge(p).interval).sum();
            assert_eq!(sum, FRAME_CYCLES);
            for &p in &phases {
                assert!(plan.edge(p).interval >= (config::board::SERVO_EDGE_GUARD_US + HANDLER_US) * CYCLES_PER_US);
            }
            let lw = plan.edge(Phase::LeftRise).interval;
            if l != 0 {
                assert_eq!(lw, u32::from(PulseWidthUs::safe(l.into()).0) * 80);
            }
        }
    }
}

#[test]
fn mailbox_clamps_and_round_trips() {
    let m = PulseMailbox::new();
    assert_eq!(m.latest(), (PulseWidthUs::OFF, PulseWidthUs::OFF));
    let table = [((1500, 1200), (1500, 1200)), ((544, 2400), (700, 2300)), ((0, 65535), (0, 2300)), ((1, 0), (700, 0))];
    for ((l, r), (wl, wr)) in table {
        let mut out = ServoPulses::new(&m);
        out.set_widths(PulseWidthUs(l), PulseWidthUs(r));
        assert_eq!(m.latest(), (PulseWidthUs(wl), PulseWidthUs(wr)));
    }
}

#[test]
fn timer_constants() {
    assert_eq!(CYCLES_PER_US, 80);
    assert_eq!(CYCLES_PER_TICK, 16);
    assert_eq!(GUARD_CYCLES, 1_600);
    assert_eq!(FRAME_CYCLES, 1_600_000);
}

#[test]
fn alarm_comes_before_the_edge_within_the_guard() {
    // Each interrupt starts (latency 0) between 0 and GUARD_CYCLES before
    // its edge: never after it, never more than the guard + a tick early.
    let mut hw = SimChip::new();
    let mailbox = PulseMailbox::new();
    mailbox.publish(PulseWidthUs(1500), PulseWidthUs(900));
    let mut s = PulseScheduler::new();
    s.start(&mut hw);
    for _ in 0..40 {
        hw.now = hw.alarm_at;
        let entry = hw.now;
        let n = hw.edges.len();
        s.on_alarm(&mut hw, &mailbox);
        let lead = hw.edges.get(n).map(|e| e.0 - entry);
        if let Some(lead) = lead {
            let g = u64::from(GUARD_CYCLES);
            assert!(lead >= g - 20 && lead <= g + u64::from(CYCLES_PER_TICK) + 20, "lead {lead}");
        }
    }
    assert_eq!(s.late_edges(), 0);
}
