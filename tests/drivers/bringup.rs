//! Full bring-up of the three chips on one simulated bus, and readings that
//! come out right end to end (distance through the lidar model, heading
//! through the compass model).

use core::cell::RefCell;

use embedded_hal_bus::i2c::RefCellDevice;
use paperbot::config;
use paperbot::driver::compass::Compass;
use paperbot::driver::lidar::{bring_up, Lidar};
use paperbot::driver::{HeadingSensor, MagCalibrate, RangeSensor, SensorError};
use paperbot::model::lidar::Range;
use paperbot::sim::bus::SimBus;
use paperbot::sim::sensors::SimSensors;

#[test]
fn both_lidars_move_to_their_addresses_without_collisions() {
    let sim = SimSensors::new();
    let (mut front, mut right, _) = sim.drivers();
    // At power-up both chips are awake at 0x29.
    sim.clock.advance_ms(2);
    assert_eq!(sim.front.borrow().address(), 0x29);
    assert_eq!(sim.right.borrow().address(), 0x29);
    let status = bring_up(&mut front, &mut right);
    assert_eq!(status.front, Ok(()));
    assert_eq!(status.right, Ok(()));
    assert_eq!(sim.front.borrow().address(), config::i2c::FRONT_LIDAR_ADDR);
    assert_eq!(sim.right.borrow().address(), config::i2c::RIGHT_LIDAR_ADDR);
    assert!(sim.front.borrow().is_ranging() && sim.right.borrow().is_ranging());
    assert_eq!(sim.bus.collisions(), 0);
}

#[test]
fn starting_one_lidar_while_the_other_is_awake_at_0x29_collides() {
    // What the XSHUT dance prevents: without it both chips answer 0x29.
    let sim = SimSensors::new();
    let (mut front, _right, _) = sim.drivers();
    sim.clock.advance_ms(2);
    assert_eq!(front.reinit(), Err(SensorError::Bus));
    assert!(sim.bus.collisions() > 0);
    assert!(!sim.front.borrow().is_powered(), "a failed lidar is held in reset");
}

#[test]
fn readings_go_through_the_lidar_models() {
    let sim = SimSensors::new();
    let (mut front, mut right, _) = sim.drivers();
    assert!(bring_up(&mut front, &mut right).all_ok());
    // Nothing before the first measurement period has passed.
    assert_eq!(front.poll(), Err(nb::Error::WouldBlock));
    let cases: [(u16, u16); 4] = [(300, 250), (57, 1000), (1100, 71), (8190, 8190)];
    for (f_mm, r_mm) in cases {
        sim.front.borrow_mut().set_distance_mm(f_mm);
        sim.right.borrow_mut().set_distance_mm(r_mm);
        sim.clock.advance_ms(34);
        let fs = front.poll().unwrap();
        let rs = right.poll().unwrap();
        assert_eq!((fs.raw_mm, rs.raw_mm), (f_mm, r_mm));
        assert_eq!(fs.range, config::lidar::FRONT.range(f_mm));
        assert_eq!(rs.range, config::lidar::RIGHT.range(r_mm));
        // f64 reference of the report's lines.
        for (s, mm, slope, icpt) in [(fs, f_mm, 0.9849, -56.2563), (rs, r_mm, 0.9867, -70.4578)] {
            match s.range {
                Range::Target(d) => assert!((d.to_mm_f64() - (slope * f64::from(mm) + icpt)).abs() < 0.01),
                Range::NoTarget => assert!(mm > config::lidar::MAX_READING_MM),
                Range::TooClose => assert!(slope * f64::from(mm) + icpt < config::lidar::MIN_DISTANCE_MM),
            }
        }
        // Read once: the next one waits for the next period.
        assert_eq!(front.poll(), Err(nb::Error::WouldBlock));
    }
}

/// The chip ranges over its whole period, back to back (ST's datasheet
/// DocID029104, "Ranging modes"; UM2039: the timing budget is one
/// measurement's time): a result reports the distance set nearest the
/// middle of its measurement (`sim::vl53l0x`), not the one in effect when
/// it is ready, which a chip that latched at that instant would report
/// (the negative check: 700 below).
#[test]
fn a_reading_is_of_the_middle_of_its_measurement() {
    use paperbot::sim::vl53l0x::DEFAULT_PERIOD_NS;
    let sim = SimSensors::new();
    let (mut front, mut right, _) = sim.drivers();
    assert!(bring_up(&mut front, &mut right).all_ok());
    // a result comes: it was due within the last ms
    sim.front.borrow_mut().set_distance_mm(300);
    while front.poll() == Err(nb::Error::WouldBlock) {
        sim.clock.advance_ms(1);
    }
    // over the next measurement (due a period later, its middle half a
    // period before that, 15.5 to 16.5 ms from here): 300 until 5 ms,
    // 480 from 15 ms (500 set first at that instant, then a hand over it:
    // the last set counts), 700 from 28 ms
    let period_ms = DEFAULT_PERIOD_NS / 1_000_000;
    let mut elapsed_ms = 0;
    for (at_ms, mm) in [(5, 300), (15, 500), (15, 480), (28, 700)] {
        sim.clock.advance_ms(at_ms - elapsed_ms);
        elapsed_ms = at_ms;
        sim.front.borrow_mut().set_distance_mm(mm);
    }
    sim.clock.advance_ms(period_ms + 1 - elapsed_ms);
    assert_eq!(front.poll().unwrap().raw_mm, 480);
    assert_eq!(sim.front.borrow().distance_mm(), 700, "in effect when the result came");
}

/// Heading the model should give for a car heading `h` (degrees, clockwise
/// from true north), f64 reference: magnetic heading `h - declination`, the
/// horizontal field seen from the car is (cos m, -sin m) in (forward,
/// right), and the chip's raw value is that field through the inverse of
/// the calibration.
fn raw_field_for(h_deg: f64, magnitude: f64) -> [i32; 3] {
    let cal = config::compass::CALIBRATION;
    let decl = config::compass::DECLINATION.to_radians_f64();
    let m = h_deg.to_radians() - decl;
    let corrected = [magnitude * m.cos(), -magnitude * m.sin(), 40.0];
    let mut adj = [0i32; 3];
    for i in 0..3 {
        let scale = f64::from(cal.scale_q16[i]) / 65536.0;
        adj[i] = (corrected[i] / scale + f64::from(cal.bias[i])).round() as i32;
    }
    adj
}

#[test]
fn compass_headings_go_through_the_compass_model() {
    let sim = SimSensors::new();
    let (_, _, mut compass) = sim.drivers();
    compass.reinit().unwrap();
    assert!(sim.mpu.borrow().bypass());
    assert_eq!(compass.asa(), sim.mpu.borrow().ak.asa());
    assert_eq!(sim.mpu.borrow().ak.cntl1(), 0x16, "continuous 100 Hz, 16 bit");
    assert_eq!(sim.mpu.borrow().ak.mode_violations(), 0);
    let mut worst = 0.0f64;
    for k in 0..72 {
        let h = f64::from(k) * 5.0;
        sim.mpu.borrow_mut().ak.set_field_adjusted(raw_field_for(h, 200.0));
        sim.clock.advance_ms(10);
        let s = compass.poll().unwrap();
        let got = f64::from(s.heading.to_millidegrees()) / 1000.0;
        let err = ((got - h + 540.0) % 360.0 - 180.0).abs();
        worst = worst.max(err);
        assert_eq!(s.field, config::compass::MODEL.correct(s.raw, compass.asa()));
    }
    // Rounding of the raw counts (field of 200 counts): well under a degree.
    assert!(worst < 0.6, "worst heading error {worst} deg");
}

#[test]
fn all_three_chips_share_one_bus_through_refcell_devices() {
    let sim = SimSensors::new();
    let bus = RefCell::new(sim.bus.clone());
    let mut front = Lidar::front(RefCellDevice::new(&bus), sim.front_xshut(), sim.delay());
    let mut right = Lidar::right(RefCellDevice::new(&bus), sim.right_xshut(), sim.delay());
    let mut compass = Compass::with_config(RefCellDevice::new(&bus), sim.delay());
    assert!(bring_up(&mut front, &mut right).all_ok());
    compass.reinit().unwrap();
    sim.front.borrow_mut().set_distance_mm(400);
    sim.right.borrow_mut().set_distance_mm(200);
    sim.mpu.borrow_mut().ak.set_field_adjusted(raw_field_for(90.0, 200.0));
    sim.clock.advance_ms(40);
    assert_eq!(front.poll().unwrap().raw_mm, 400);
    assert_eq!(right.poll().unwrap().raw_mm, 200);
    let h = compass.poll().unwrap().heading.to_millidegrees();
    assert!((89_400..=90_600).contains(&h), "{h}");
}

#[test]
fn the_simulated_bus_alone_is_an_i2c_for_each_driver() {
    // SimBus handles are clones of one bus: the way the simulator wires it.
    let bus = SimBus::new();
    assert_eq!(bus.transactions(), 0);
    let sim = SimSensors::new();
    let (mut front, mut right, mut compass) = sim.drivers();
    assert!(bring_up(&mut front, &mut right).all_ok());
    compass.reinit().unwrap();
    assert!(sim.bus.transactions() > 100);
}
