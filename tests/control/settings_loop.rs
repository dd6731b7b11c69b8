//! `save`, `settings` and `forget` on the control loop of the simulated
//! robot, across power-cycles (a new robot on the same flash): the saved
//! trims, calibration, declination and mission are back with the boot line
//! that says so; a damaged record, one of another version, or a save cut
//! short by a power cut gives the older record or the config, with the
//! reason; a save is refused while the robot moves and changes nothing.

use crate::common;
use paperbot::config;
use paperbot::config::settings::VERSION;
use paperbot::control::settings::{encode, MemoryFlash, Settings, RECORD_WORDS};
use paperbot::control::tick::Source;
use paperbot::driver::MagCalibrate;
use paperbot::math::Angle;
use paperbot::model::compass::MagCalibration;
use paperbot::model::Trim;
use paperbot::sim::robot::{SimConfig, SimRobot};

fn cfg() -> SimConfig {
    SimConfig { locate_at_power_up: false, ..SimConfig::default() }
}

/// Sends `line` and returns the answer lines (a few ticks for them).
fn ask(robot: &mut SimRobot, line: &str) -> Vec<String> {
    robot.take_output();
    robot.send(line);
    for _ in 0..3 {
        robot.tick();
    }
    robot.take_output().into_iter().filter(|l| !l.starts_with("t_ms") && l.starts_with('#')).collect()
}

/// The robot powered off and on again with its flash.
fn power_cycle(robot: &mut SimRobot) -> (SimRobot, Vec<String>) {
    let flash = robot.flash();
    let mut next = SimRobot::with_flash(cfg(), flash);
    let boot = next.take_output();
    (next, boot)
}

fn trims(robot: &SimRobot) -> (Trim, Trim) {
    let m = robot.controller().model();
    (m.left_trim, m.right_trim)
}

#[test]
fn saved_settings_are_back_after_a_power_cycle() {
    let mut robot = SimRobot::new(cfg());
    ask(&mut robot, "trim left 1.5");
    ask(&mut robot, "trim right -0.75");
    let cal = MagCalibration { bias: [70, 30, 5], scale_q16: [40_000, 50_000, 190_000] };
    robot.controller_mut().compass().set_calibration(cal);
    robot.controller_mut().compass().set_declination(Angle::from_millidegrees(12_500));
    ask(&mut robot, "mission add fwd 0.13 1");
    ask(&mut robot, "mission add goto 300 200");
    let saved = ask(&mut robot, "save");
    assert_eq!(saved[0], "# ok save");
    assert!(saved[1].starts_with("# saved: record 1 at 0x3f9000, paused "), "{saved:?}");

    let (mut again, boot) = power_cycle(&mut robot);
    assert_eq!(boot, ["# settings from flash, record 1: trims, compass, declination, mission of 2 steps"]);
    assert_eq!(trims(&again), (Trim(384), Trim(-192)));
    assert_eq!(again.controller_mut().compass().calibration(), cal);
    assert_eq!(again.controller_mut().compass().declination(), Angle::from_millidegrees(12_500));
    assert_eq!(again.controller().mission().len(), 2);
    assert_eq!(again.controller().sources().trims, Source::Flash);
    let listed = ask(&mut again, "settings");
    assert_eq!(listed[1], "# trims (flash): left 1.50 right -0.75");
    assert_eq!(listed[2], "# compass (flash): bias 70 30 5 scale 0.610352 0.762939 2.899170");
    assert_eq!(listed[3], "# declination (flash): 12.500");
    assert_eq!(listed[4], "# mission (flash): 2 steps");
    // a change is marked until saved again, into the other sector
    assert_eq!(ask(&mut again, "trim l 2"), ["# ok trim left 2.00", "# not saved: save to keep it"]);
    assert_eq!(again.controller().sources().trims, Source::Changed);
    assert!(ask(&mut again, "save")[1].starts_with("# saved: record 2 at 0x3fa000"));
    let (third, boot) = power_cycle(&mut again);
    assert!(boot[0].starts_with("# settings from flash, record 2"), "{boot:?}");
    assert_eq!(trims(&third).0, Trim(512));
}

#[test]
fn blank_flash_boots_on_the_config() {
    let (robot, boot) = power_cycle(&mut SimRobot::new(cfg()));
    assert_eq!(boot, ["# settings: config (none in flash)"]);
    assert_eq!(trims(&robot), (config::actuators::LEFT_TRIM, config::actuators::RIGHT_TRIM));
    assert_eq!(robot.controller().sources().calibration, Source::Config);
}

#[test]
fn a_damaged_record_is_ignored_with_the_reason_and_the_config_used() {
    let mut robot = SimRobot::new(cfg());
    ask(&mut robot, "trim left 3");
    ask(&mut robot, "save");
    let mut flash = robot.flash();
    flash.sectors[0][5] ^= 1 << 9; // one bit of a bias
    let mut robot = SimRobot::with_flash(cfg(), flash);
    assert_eq!(
        robot.take_output(),
        ["# settings at 0x3f9000 ignored: CRC mismatch", "# settings: config (none in flash)"]
    );
    assert_eq!(trims(&robot).0, config::actuators::LEFT_TRIM, "nothing half-applied");
    assert_eq!(robot.controller_mut().compass().calibration(), config::compass::CALIBRATION);
}

#[test]
fn a_record_of_another_version_is_ignored_and_the_older_one_used() {
    let mut flash = MemoryFlash::default();
    let mut older = Settings::from_config();
    older.left_trim = Trim(100);
    flash.sectors[0] = encode(&older, 4);
    let mut v2 = encode(&Settings::from_config(), 5);
    v2[1] = VERSION + 1;
    v2[RECORD_WORDS - 1] = common::crc32(&v2[..RECORD_WORDS - 1]);
    flash.sectors[1] = v2;
    let mut robot = SimRobot::with_flash(cfg(), flash);
    assert_eq!(
        robot.take_output(),
        [
            "# settings at 0x3fa000 ignored: version 2 not 1",
            "# settings from flash, record 4: trims, compass, declination, mission of 0 steps",
        ]
    );
    assert_eq!(trims(&robot).0, Trim(100));
}

#[test]
fn a_power_cut_during_a_save_keeps_the_older_record() {
    let mut robot = SimRobot::new(cfg());
    ask(&mut robot, "trim left 1");
    ask(&mut robot, "save");
    ask(&mut robot, "trim left 2");
    // the power lasts for the erase and 40 words of the record
    robot.controller_mut().settings_store().flash.power_left = Some(41);
    assert_eq!(ask(&mut robot, "save"), ["# err not saved: flash timeout"]);
    let mut flash = robot.flash();
    flash.power_left = None;
    let mut again = SimRobot::with_flash(cfg(), flash);
    assert_eq!(
        again.take_output(),
        [
            "# settings at 0x3fa000 ignored: save cut short",
            "# settings from flash, record 1: trims, compass, declination, mission of 0 steps",
        ]
    );
    assert_eq!(trims(&again).0, Trim(256));
}

#[test]
fn save_and_forget_are_refused_while_the_robot_moves() {
    let mut robot = SimRobot::new(cfg());
    ask(&mut robot, "trim left 1");
    ask(&mut robot, "fwd 0.13");
    let before = robot.flash();
    assert_eq!(ask(&mut robot, "save"), ["# err moving: stop first (flash pauses the loop)"]);
    assert_eq!(ask(&mut robot, "forget"), ["# err moving: stop first (flash pauses the loop)"]);
    assert_eq!(robot.flash(), before, "flash untouched");
    assert_eq!(robot.controller().mode().word(), "drive", "the drive goes on");
}

#[test]
fn forget_erases_the_record_and_brings_the_config_back() {
    let mut robot = SimRobot::new(cfg());
    ask(&mut robot, "trim left 1");
    ask(&mut robot, "mission add wait 1");
    ask(&mut robot, "save");
    let answer = ask(&mut robot, "forget");
    assert_eq!(answer[0], "# ok forget");
    assert!(answer[1].starts_with("# flash erased, config in use, paused "), "{answer:?}");
    assert_eq!(trims(&robot).0, config::actuators::LEFT_TRIM);
    assert_eq!(robot.controller().mission().len(), 1, "the mission stays in RAM");
    assert_eq!(robot.controller().sources().mission, Source::Changed);
    assert_eq!(robot.flash(), MemoryFlash::default());
    let (_, boot) = power_cycle(&mut robot);
    assert_eq!(boot, ["# settings: config (none in flash)"]);
}
