//! Servo driver: the Arduino `Servo.write()` mapping with sub-microsecond
//! arithmetic, the safe clamp, trims at stop, and the pair behind the
//! board's `PulseOutput`.

use std::cell::RefCell;
use std::rc::Rc;

use paperbot::config;
use paperbot::driver::servo::{pulse_ns, pulse_width, ServoPair};
use paperbot::driver::servo::{PulseOutput, PulseWidthUs};
use paperbot::driver::Servos;
use paperbot::model::{ServoCmd, Trim};

/// f64 reference: 544 us at 0, 2400 us at 180, linear.
fn reference_ns(cmd: f64) -> f64 {
    let (a, b) = (f64::from(config::servo::PULSE_AT_0_US), f64::from(config::servo::PULSE_AT_180_US));
    (a + (b - a) * cmd / 180.0) * 1000.0
}

#[test]
fn pulse_widths_follow_the_arduino_mapping_to_the_nanosecond() {
    for q8 in 0..=(180u32 << 8) {
        let cmd = ServoCmd::from_q8(q8);
        let got = f64::from(pulse_ns(cmd));
        assert!((got - reference_ns(cmd.to_f64())).abs() <= 0.5 + 1e-6, "{q8}: {got}");
    }
}

#[test]
fn table_of_whole_commands() {
    // (command, unclamped ns, width sent in us)
    let table: [(u8, u32, u16); 7] = [
        (0, 544_000, 700),  // clamped up to the FS90R's safe minimum
        (17, 719_289, 719), // first whole command inside the window
        (45, 1_008_000, 1008),
        (90, 1_472_000, 1472), // stop
        (135, 1_936_000, 1936),
        (170, 2_296_889, 2297),
        (180, 2_400_000, 2300), // clamped down to the safe maximum
    ];
    for (cmd, ns, us) in table {
        assert_eq!(pulse_ns(ServoCmd::from_int(cmd)), ns, "{cmd}");
        assert_eq!(pulse_width(ServoCmd::from_int(cmd)), PulseWidthUs(us), "{cmd}");
    }
}

#[test]
fn fractional_commands_move_the_pulse_below_a_microsecond() {
    // 1/256 step = 40.3 ns.
    let a = pulse_ns(ServoCmd::from_q8(90 << 8));
    let b = pulse_ns(ServoCmd::from_q8((90 << 8) + 1));
    assert_eq!(b - a, 40);
    assert_eq!(pulse_ns(ServoCmd::from_f64(90.5)), 1_477_156);
}

#[derive(Clone, Default)]
struct Recorder(Rc<RefCell<Vec<(u16, u16)>>>);
impl PulseOutput for Recorder {
    fn set_widths(&mut self, l: PulseWidthUs, r: PulseWidthUs) {
        self.0.borrow_mut().push((l.0, r.0));
    }
}

#[test]
fn the_pair_sends_both_widths_and_stops_at_its_trimmed_neutral() {
    let out = Recorder::default();
    let mut servos = ServoPair::new(out.clone(), Trim::from_f64(1.5), Trim::from_f64(-2.0));
    assert!(out.0.borrow().is_empty(), "nothing sent before the first command");
    servos.set(ServoCmd::from_int(108), ServoCmd::from_int(60));
    assert_eq!(servos.commands(), (ServoCmd::from_int(108), ServoCmd::from_int(60)));
    servos.stop();
    assert_eq!(servos.neutral(), (ServoCmd::from_f64(91.5), ServoCmd::from_f64(88.0)));
    servos.set_trims(Trim::ZERO, Trim::ZERO);
    servos.stop();
    let sent = out.0.borrow().clone();
    assert_eq!(sent, vec![(1658, 1163), (1487, 1451), (1472, 1472)]);
}

#[test]
fn the_configured_pair_stops_at_the_configured_trims() {
    let out = Recorder::default();
    let mut servos = ServoPair::with_config(out.clone());
    servos.stop();
    let (l, r) = servos.neutral();
    assert_eq!(l, ServoCmd::NEUTRAL.trimmed(config::actuators::LEFT_TRIM));
    assert_eq!(r, ServoCmd::NEUTRAL.trimmed(config::actuators::RIGHT_TRIM));
    assert_eq!(out.0.borrow().last(), Some(&(pulse_width(l).0, pulse_width(r).0)));
}
