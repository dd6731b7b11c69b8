//! Every number a user tunes, in one place, each with its unit and source.
//!
//! Sources: "report" is the lab report (`shared/seed/lab1-report.txt`),
//! "data" the lab's measurements (`tests/data/lab1/`), "PAPERBOT" the
//! project's fact sheet (`shared/docs/PAPERBOT.md`). Values are written in
//! the units people use (mm, degrees, rad/s) and converted to the fixed-point
//! types by `const fn`s at compile time: no float code reaches the robot.
//! To refit from new measurements: `cargo run --example fit -- <csv>` prints
//! constants ready to paste here. The estimator's, the localization's, the
//! simulator's and the teleop tool's numbers are in files of their own
//! (`src/config/`), under the same `config::` paths.

use crate::math::{Angle, Length};

/// Robot geometry.
pub mod geometry {
    use super::*;
    use crate::model::lidar::LidarMount;

    /// Wheel radius: 20 mm (report 3.2 uses r = 0.02 m; its "200 mm
    /// diameter" is a typo).
    pub const WHEEL_RADIUS: Length = Length::from_mm_f64(20.0);
    /// Distance between the wheels: 85 mm (report 1).
    pub const AXLE_LENGTH: Length = Length::from_mm_f64(85.0);
    /// D: from the rotation axis (axle midpoint) to the car's reference
    /// point, mm. The report gives no number; the team's later estimator used
    /// 56 mm (PAPERBOT). Must stay below 128 mm (state update's Q24).
    pub const ROTATION_TO_REFERENCE: Length = Length::from_mm_f64(56.0);
    /// The paper skid drags about 70 mm behind the axle (report 1).
    pub const SKID_BEHIND_AXLE: Length = Length::from_mm_f64(70.0);

    /// Front lidar: 50 mm behind the reference point, looking forward
    /// (PAPERBOT, from the team's later estimator; lateral offset not
    /// recorded, taken as 0).
    pub const FRONT_LIDAR: LidarMount =
        LidarMount { forward: Length::from_mm_f64(-50.0), right: Length::ZERO, direction: Angle::ZERO };
    /// Right lidar: 53 mm left of the reference point, looking right
    /// (PAPERBOT, from the team's later estimator).
    pub const RIGHT_LIDAR: LidarMount =
        LidarMount { forward: Length::ZERO, right: Length::from_mm_f64(-53.0), direction: Angle::QUARTER_TURN };

    const _: () = assert!(ROTATION_TO_REFERENCE.0 >= 0 && ROTATION_TO_REFERENCE.0 < (128 << 16));
}

/// The servo actuator model: eight lines from command (0..180) to speed, and
/// the command ranges they were measured on (report 3.2, data
/// `servo_runs.csv`). Forward and backward lines give wheel speed in rad/s
/// (car speed = wheel speed * wheel radius); cw and ccw lines give the car's
/// turn rate in rad/s. Every line is a magnitude (see `model::actuator`).
pub mod actuators {
    use super::geometry::WHEEL_RADIUS;
    use crate::model::actuator::{ActuatorModel, MotionLines, Trim, WheelLine};

    /// Forward: left `y = 0.14 x - 8.205` on 103..112, right
    /// `y = -0.146 x + 15.85` on 57..66 (data says -0.146; the report printed
    /// `0.145 x - 15.85`, which is negative over the whole range).
    pub const FORWARD: MotionLines =
        MotionLines { left: WheelLine::new(0.14, -8.205, 103, 112), right: WheelLine::new(-0.146, 15.85, 57, 66) };
    /// Backward: left `y = -0.205 x + 19.77` on 58..70, right `y = 0.195 x - 13.95` on 99..111.
    pub const BACKWARD: MotionLines =
        MotionLines { left: WheelLine::new(-0.205, 19.77, 58, 70), right: WheelLine::new(0.195, -13.95, 99, 111) };
    /// Clockwise: left `y = 0.0862 x - 6.2423` on 100..111, right `y = 0.1431 x - 13.442` on 110..117.
    pub const CW: MotionLines = MotionLines {
        left: WheelLine::new(0.0862, -6.2423, 100, 111),
        right: WheelLine::new(0.1431, -13.442, 110, 117),
    };
    /// Counter-clockwise: left `y = -0.0908 x + 8.6171` on 60..71, right `y = -0.0344 x + 4.7604` on 43..70.
    pub const CCW: MotionLines =
        MotionLines { left: WheelLine::new(-0.0908, 8.6171, 60, 71), right: WheelLine::new(-0.0344, 4.7604, 43, 70) };

    /// Left servo trim in command steps (moves its stop point from 90).
    /// Tune on the robot with the `trim` command until the wheel stands still.
    pub const LEFT_TRIM: Trim = Trim::from_f64(0.0);
    /// Right servo trim in command steps.
    pub const RIGHT_TRIM: Trim = Trim::from_f64(0.0);

    pub const MODEL: ActuatorModel = ActuatorModel {
        forward: FORWARD,
        backward: BACKWARD,
        cw: CW,
        ccw: CCW,
        wheel_radius: WHEEL_RADIUS,
        left_trim: LEFT_TRIM,
        right_trim: RIGHT_TRIM,
    };
}

/// Servo pulses (FS90R continuous servos on 50 Hz PWM).
pub mod servo {
    /// Pulse width for command 0, us: the ESP8266 Arduino core's
    /// `Servo.write()` mapping of the lab's time (PAPERBOT).
    pub const PULSE_AT_0_US: u32 = 544;
    /// Pulse width for command 180, us (PAPERBOT).
    pub const PULSE_AT_180_US: u32 = 2400;
    /// Pulses are clamped to this window whatever the command and trim: the
    /// FS90R's rated 700..2300 us (FS90R datasheet).
    pub const SAFE_MIN_US: u32 = 700;
    pub const SAFE_MAX_US: u32 = 2300;
    /// Frame period: 20 ms (50 Hz servo frames).
    pub const FRAME_US: u32 = 20_000;
}

/// The two lidar lines (report 3.3, data `lidar_*.csv`), mapping a reading
/// (mm) to the distance from the car's reference point (mm).
pub mod lidar {
    use crate::model::lidar::LidarModel;

    /// The closest distance from the reference point a reading may mean,
    /// mm; a reading below it is "too close", not a measurement. The
    /// reference point is on the car, inside the box, and both lidars look
    /// across it (front: from 50 mm behind it, right: from 53 mm to its
    /// left; `geometry`), so a wall cannot be nearer than 0 mm along the
    /// beam; -6 mm leaves three lidar sigmas (`estimator::LIDAR_SIGMA`) for
    /// noise: the lab's readings of a target at 0 mm go down to -5.3 mm
    /// (data `lidar_*.csv`). This takes readings below 52 (front) and 66
    /// (right) as too close; the right lidar pushed past a wall read 43-55,
    /// which the former bound (20) turned into -16..-28 mm and the
    /// estimator accepted.
    pub const MIN_DISTANCE_MM: f64 = -6.0;
    /// Readings past this are beyond the VL53L0X's reliable range in its
    /// default mode (1.2 m, datasheet): reported as no target.
    pub const MAX_READING_MM: u16 = 1200;
    /// Front: `distance = 0.9849 reading - 56.2563` (report 3.3: the reading
    /// fitted on the true distance, inverted; `cargo run --example fit --
    /// tests/data/lab1/lidar_front.csv` gives 0.9849 / -56.2555 from the data).
    pub const FRONT: LidarModel = LidarModel::new(0.9849, -56.2563, MIN_DISTANCE_MM, MAX_READING_MM);
    /// Right: `distance = 0.9867 reading - 70.4578` (report 3.3; the fit
    /// gives 0.9867 / -70.4605).
    pub const RIGHT: LidarModel = LidarModel::new(0.9867, -70.4578, MIN_DISTANCE_MM, MAX_READING_MM);

    /// The VL53L0X's field of view, full cone angle, degrees (ST's
    /// datasheet: 25 degrees): it reads the nearest surface in the cone, so
    /// the estimator's measurement model takes the cone's direction nearest
    /// a wall's normal (`model::measurement`).
    pub const CONE_DEG: f64 = 25.0;
    /// Measurement timing budget, us (VL53L0X default 33 ms; at most one
    /// reading per 33 ms per lidar).
    pub const TIMING_BUDGET_US: u32 = 33_000;
    /// Wait after releasing XSHUT before talking to the chip, us (datasheet
    /// boot time 1.2 ms, with margin).
    pub const BOOT_TIME_US: u32 = 2_000;
    /// How long XSHUT is held low to reset a lidar, us (the datasheet gives
    /// no minimum; Adafruit's two-sensor example holds it 10 ms).
    pub const RESET_TIME_US: u32 = 10_000;
    /// Consecutive reads of one status register the bring-up may make while
    /// it waits for the chip (SPAD info, reference calibrations) before it
    /// gives up with a timeout: about 0.2 s at 100 us a read (three bytes at
    /// 400 kHz). The vl53l0x crate's own limits (10000 and 65535 reads)
    /// would block the robot for seconds.
    pub const INIT_POLL_LIMIT: u16 = 2_000;
}

/// The MPU9250's AK8963 magnetometer.
pub mod compass {
    use super::Angle;
    use crate::model::compass::{Axis, AxisMap, CompassModel, MagCalibration};

    /// Hard-iron biases x 79, y 35, z 2 counts; soft-iron scales x 0.679012,
    /// y 0.833333, z 3.055556 (report 2.4, Figure 4).
    pub const CALIBRATION: MagCalibration = MagCalibration::from_f64([79.0, 35.0, 2.0], [0.679012, 0.833333, 3.055556]);
    /// Declination at UCLA: 11 deg 56 min east (report 2.4; the course
    /// sketch's `11 + (56/60)` is 11 in integer arithmetic). 0 for a frame
    /// whose x is magnetic north.
    pub const DECLINATION: Angle = Angle::from_degrees_f64(11.0 + 56.0 / 60.0);
    /// The magnetometer's +x faced north when the car did (report 2.4), so
    /// its x is the car's front; the AK8963 frame is right-handed with z
    /// down, so its y is the car's right. (Its axes are not the
    /// accelerometer's: x and y swapped, z inverted.)
    pub const AXES: AxisMap = AxisMap { forward: Axis::X, right: Axis::Y };

    pub const MODEL: CompassModel = CompassModel { calibration: CALIBRATION, axes: AXES, declination: DECLINATION };

    /// Calibration sweep: samples to collect while turning in place.
    pub const CALIBRATION_SAMPLES: u16 = 1000;
    /// A sweep that has its samples but not its sectors keeps collecting up
    /// to this many more: two turns at the calibration turn rate (the first
    /// turn only builds the min/max box and counts about 9 sectors).
    pub const CALIBRATION_EXTRA_SAMPLES: u16 = 500;
    /// A sweep must visit this many of 12 30-degree sectors to be accepted.
    pub const CALIBRATION_MIN_SECTORS: u8 = 11;
    /// A calibration sample only marks a sector if its horizontal field,
    /// seen from the sweep's running centre, is at least this long (larger
    /// component), ASA-adjusted counts: 7.5 uT at 0.15 uT per count, a
    /// third of the horizontal field at UCLA (~24 uT, NOAA WMM), well above
    /// the AK8963's noise (a few counts), so a robot standing still visits
    /// no sectors.
    pub const CALIBRATION_MIN_RADIUS: i32 = 50;
    /// Turn rate of the calibration sweep (clockwise), mrad/s: inside the
    /// clockwise lines' common measured range (about 2.2..3.2 rad/s, data
    /// `servo_runs.csv`), so one turn takes 2.5 s, 250 samples at 100 Hz.
    pub const CALIBRATION_TURN_MRAD_S: i32 = 2_500;
    /// A sweep that has not collected its samples after this long per
    /// sample is abandoned (and the robot stops), ms: twice the AK8963's
    /// 10 ms period in continuous mode 2.
    pub const CALIBRATION_MS_PER_SAMPLE: u32 = 20;

    /// Wait after the MPU9250's device reset (PWR_MGMT_1 H_RESET), us: the
    /// register start-up time is 100 ms (MPU-9250 datasheet, table 6.2;
    /// the mpu9250 crate waits the same).
    pub const MPU_RESET_TIME_US: u32 = 100_000;
    /// Wait after each AK8963 mode change, us: at least 100 us in power-down
    /// before the next mode (AK8963 datasheet 6.3), with margin.
    pub const MODE_CHANGE_US: u32 = 200;
}

/// Wiring (PAPERBOT; NodeMCU label in brackets).
pub mod pins {
    /// Left servo signal (D1).
    pub const LEFT_SERVO_GPIO: u8 = 5;
    /// Right servo signal (D2).
    pub const RIGHT_SERVO_GPIO: u8 = 4;
    /// I2C data (D5).
    pub const SDA_GPIO: u8 = 14;
    /// I2C clock (D6).
    pub const SCL_GPIO: u8 = 12;
    /// Front lidar XSHUT (D3).
    pub const FRONT_XSHUT_GPIO: u8 = 0;
    /// Right lidar XSHUT (D4).
    pub const RIGHT_XSHUT_GPIO: u8 = 2;
    /// On-board LED (D0).
    pub const LED_GPIO: u8 = 16;
}

/// I2C bus and addresses (7-bit).
pub mod i2c {
    /// Both VL53L0X boot at 0x29 (datasheet).
    pub const LIDAR_DEFAULT_ADDR: u8 = 0x29;
    /// Front lidar after bring-up (the course sketch's 22, decimal).
    pub const FRONT_LIDAR_ADDR: u8 = 0x16;
    /// Right lidar after bring-up (the course sketch's 25, decimal).
    pub const RIGHT_LIDAR_ADDR: u8 = 0x19;
    /// MPU9250 (AD0 low).
    pub const MPU9250_ADDR: u8 = 0x68;
    /// AK8963 once the MPU9250 is in bypass mode.
    pub const AK8963_ADDR: u8 = 0x0C;
    /// Bus clock, Hz (fast mode).
    pub const FREQUENCY_HZ: u32 = 400_000;
    /// Longest a slave may stretch the clock before the transfer fails, us.
    pub const CLOCK_STRETCH_TIMEOUT_US: u32 = 1_000;
    /// Shortest SCL low phase, ns: fast mode tLOW >= 1.3 us (I2C spec
    /// UM10204 table 10). The bit-banged master makes the low phase at least
    /// this long and gives the rest of the bit period to the high phase.
    pub const T_LOW_MIN_NS: u32 = 1_300;
    /// Shortest SCL high phase, ns: fast mode tHIGH >= 0.6 us (UM10204 table 10).
    pub const T_HIGH_MIN_NS: u32 = 600;
    /// Bus-free time between a STOP and the next START, ns: fast mode
    /// tBUF >= 1.3 us (UM10204 table 10).
    pub const T_BUF_MIN_NS: u32 = 1_300;
    /// Clock pulses sent to free a slave that holds SDA low (UM10204 3.1.16:
    /// nine clocks, then STOP).
    pub const RECOVERY_CLOCKS: u8 = 9;
    /// Times a failed transaction is run again before the driver sees the
    /// error (`driver::bus::Retry`), count. Source: the fault runs
    /// (tests/faults_long.rs): a lidar bring-up is ~110 transactions, so
    /// without retries it got through a bus with 1 % faulty transactions
    /// about one try in three; with 2 retries a transaction fails only when
    /// three attempts in a row do (1e-6 at 1 %, 4e-4 at 10 % of which 3/4
    /// fail loudly), so a bring-up gets through a 10 % bus ~19 times in 20.
    /// Each retry costs one transaction (~0.1 ms at 400 kHz).
    pub const TRANSACTION_RETRIES: u8 = 2;
}

/// Timing of the control loop.
pub mod timing {
    /// Control loop rate, Hz.
    pub const LOOP_HZ: u32 = 100;
    /// Telemetry lines per second (0 = off).
    pub const TELEMETRY_HZ: u32 = 10;
    /// Stop when no command arrived for this long, ms.
    pub const DEADMAN_MS: u32 = 500;
    /// Wait before re-initialising a failed sensor, ms.
    pub const SENSOR_RETRY_MS: u32 = 1_000;
    /// A lidar reading older than this is stale, ms.
    pub const LIDAR_STALE_MS: u32 = 200;
    /// A sensor that delivers nothing for this long is taken as failed
    /// (counted as a timeout, re-initialised after `SENSOR_RETRY_MS`), ms:
    /// 15 lidar periods (33 ms) or 50 compass periods (10 ms at 100 Hz).
    pub const SENSOR_SILENT_MS: u32 = 500;
    /// Bus errors in a row before a sensor is taken down: one glitch (e.g.
    /// a servo's current surge on the bus) only costs that sample.
    pub const SENSOR_MAX_BUS_ERRORS: u8 = 3;
    /// Estimator corrections per tick at most (each ~1,350 lx106
    /// instructions, lx106/BENCHMARKS.md). Readings that arrive together wait
    /// a tick, lidars first (a 10 ms wait at 0.15 m/s is 1.5 mm, within the
    /// lidar's 1.6 mm spread), the compass when no lidar reading waits; this
    /// keeps a tick within its 3,000-instruction budget. 3 applies every
    /// reading in the tick it arrives.
    pub const MAX_CORRECTIONS_PER_TICK: u8 = 1;
}

/// Serial port.
pub mod serial {
    /// UART0 baud rate (8N1).
    pub const BAUD: u32 = 115_200;

    // The command protocol's limits (`control::protocol`). Each guards against
    // typos and line noise. The speed and rate limits are not what the servos
    // drive: that differs by direction and moves with the trims (no trim:
    // fwd 0.124..0.150 m/s, back 0.108..0.154, cw 2.377..3.300 rad/s, ccw
    // 2.353..3.169, from the fitted lines in `actuators`), so the control loop
    // drives a request outside it at the nearest it can and answers with that.

    /// Longest command line, bytes, without the terminator: the longest
    /// command (`servo 180.00 180.00 60.000`) is 26 bytes; 64 leaves room for
    /// spaces and long spellings.
    pub const MAX_LINE: usize = 64;
    /// Fastest `fwd`/`back` speed accepted, mm/s: twice the fastest the lab
    /// measured (0.149 m/s, data `servo_runs.csv`).
    pub const MAX_SPEED_MM_S: u32 = 300;
    /// Fastest `cw`/`ccw` turn rate accepted, mrad/s: about twice the fastest
    /// measured (3.20 rad/s, data `servo_runs.csv`).
    pub const MAX_TURN_MRAD_S: u32 = 6_000;
    /// Longest duration a motion command may ask for, ms (one minute: the
    /// arena is crossed in about 6 s).
    pub const MAX_DURATION_MS: u32 = 60_000;
    /// Largest servo trim accepted, 1/100 command step (10 steps: an FS90R's
    /// stop point drifts by a few steps).
    pub const MAX_TRIM_CENTI: u32 = 1_000;
    /// Largest |x| or |y| the `pose` command accepts, mm (the pose's
    /// `Length` view holds +-32.7 m).
    pub const MAX_POSE_MM: u32 = 30_000;
    /// Fewest magnetometer samples a calibration sweep may ask for: one turn
    /// at 3 rad/s takes 2.1 s, 210 samples at the AK8963's 100 Hz.
    pub const MIN_CAL_SAMPLES: u16 = 250;
    /// Most magnetometer samples a calibration sweep may ask for (100 s at 100 Hz).
    pub const MAX_CAL_SAMPLES: u16 = 10_000;
    /// Fastest telemetry rate, Hz: one row per loop tick. A typical row is
    /// about 100 bytes, 10 kB/s at 100 Hz against the UART's 11.5 kB/s
    /// (115200 baud, 10 bits a byte): rates near the maximum only fit short rows.
    pub const MAX_TELEMETRY_HZ: u16 = super::timing::LOOP_HZ as u16;
}

/// The ESP8266 itself: clocks, the servo timer and the watchdog (used by
/// `board`; the numbers are the chip's, from the ESP8266 Technical Reference).
pub mod board {
    /// CPU clock, Hz: the ESP8266 runs at 80 MHz after the HAL's PLL setup;
    /// CCOUNT counts CPU cycles.
    pub const CPU_HZ: u32 = 80_000_000;
    /// APB clock that feeds UART0 and FRC1, Hz (80 MHz, Technical Reference 11.3).
    pub const APB_HZ: u32 = 80_000_000;
    /// FRC1 prescaler for the servo pulses: 16, so one tick is 0.2 us
    /// (5 ticks per us) and the 23-bit counter spans 1.67 s.
    pub const FRC1_PRESCALER: u32 = 16;
    /// The FRC1 interrupt is raised this long before each servo edge; the
    /// handler then spins on CCOUNT to the exact cycle, so any interrupt latency below
    /// this does not move the edge, us. 20 us covers the vector entry and a
    /// flash-cache miss in another interrupt (a few us) with margin.
    pub const SERVO_EDGE_GUARD_US: u32 = 20;
    /// The right servo's pulse starts this long after the left one's, us:
    /// the pulses never overlap (max pulse 2300 us) and the two servos'
    /// current surges are apart.
    pub const SERVO_STAGGER_US: u32 = 2_600;
    /// Hardware watchdog timeout, ms: the loop (100 Hz) feeds it every tick.
    pub const WATCHDOG_MS: u32 = 1_680;
    /// LED heartbeat: half period while running normally, ms.
    pub const LED_BLINK_OK_MS: u32 = 500;
    /// LED half period while the robot is stopped by a fault, ms.
    pub const LED_BLINK_FAULT_MS: u32 = 100;
}

/// The test arena: a box, origin at a corner, x along the long side (north),
/// y along the short side (east), mm (PAPERBOT: the team's 762.5 x 495 mm box).
pub mod arena {
    use super::Length;
    pub const LENGTH_X: Length = Length::from_mm_f64(762.5);
    pub const WIDTH_Y: Length = Length::from_mm_f64(495.0);
}

pub mod estimator;
pub mod locate;
pub mod replay;
pub mod sim;
pub mod teleop;

/// Going places on the estimate (`goto`, `face`) and the wall stop
/// (`control::goto`, `control::tick`).
pub mod goto {
    /// The wall stop: a forward motion stops when the front lidar reads a
    /// target closer than this to the reference point (the car's nose), mm.
    /// The reading is up to one timing budget (33 ms, 5 mm at 0.15 m/s)
    /// old and the servos take a tick or two to stop (another 3 mm), so a
    /// wall square ahead is met at about 40 mm; a wall met at a slant is
    /// nearer to the nose's corners than to the beam (at 45 degrees the
    /// corner of the 85 mm-wide body is about 30 mm nearer).
    pub const WALL_STOP_MM: i32 = 50;
    /// `goto` arrives when the estimated reference point is this close to
    /// the target, mm: half the promised 20 mm, leaving the other half to
    /// the estimate's own error.
    pub const ARRIVE_MM: i32 = 8;
    /// `goto` and `face` turn in place until the heading is this close to
    /// the one wanted, millidegrees: a turn at `TURN_MRAD_S` moves 1.4
    /// degrees per loop tick, so stopping within 1 degree leaves the
    /// promised 3 degrees for the estimate's error.
    pub const TURN_TOLERANCE_MDEG: i32 = 1_000;
    /// While driving straight, a heading error past this (millidegrees)
    /// stops the leg and turns again (re-planning from the estimate).
    pub const STEER_TOLERANCE_MDEG: i32 = 4_000;
    /// Speed of `goto`'s straight legs, mm/s: inside what the servos drive
    /// both ways at no trim (fwd 124..150, back 108..154, `config::serial`).
    pub const SPEED_MM_S: i32 = 130;
    /// Turn rate of `goto`'s and `face`'s turns, mrad/s: the slow end of
    /// what the servos drive both ways (cw 2377..3300, ccw 2353..3169).
    pub const TURN_MRAD_S: i32 = 2_400;
    /// A target must be at least this far inside every wall, mm: the wall
    /// stop's distance plus the arrival tolerance, so a `goto` that ends
    /// facing the wall is not stopped short by the wall stop (and the
    /// wheels, 42.5 mm to each side, stay clear of a wall it drives along).
    pub const TARGET_WALL_MARGIN_MM: i32 = WALL_STOP_MM + 20;
    /// `goto` and `face` refuse to start (and stop) when the estimate's
    /// one-sigma position uncertainty is above this, mm: the promise is
    /// 20 mm. After `pose` it is 100 mm (`config::estimator`): a second of
    /// lidar readings standing still brings it under.
    pub const MAX_SIGMA_MM: i32 = 15;
    /// The same for the heading, millidegrees.
    pub const MAX_SIGMA_MDEG: i32 = 3_000;
    /// A `goto` stops when the front lidar sees something this much nearer
    /// than the target along the way (an obstacle), mm.
    pub const OBSTACLE_MARGIN_MM: i32 = 30;
    /// ... for at least this long, ms: more than two lidar periods (33 ms
    /// each), so one spurious echo (a glancing beam's, `sim::SPURIOUS_SHARE`)
    /// does not stop a `goto` (in the realistic simulator's hour of laps
    /// five did); 10 mm of driving at 0.15 m/s.
    pub const OBSTACLE_CONFIRM_MS: u32 = 70;
    /// Longest a `goto` or `face` may take, ms: the box's diagonal (0.9 m)
    /// at 0.13 m/s is 7 s, plus turns.
    pub const TIME_LIMIT_MS: u32 = 20_000;
}

/// Missions: commands stored on the robot and run without the cable
/// (`control::mission`).
pub mod mission {
    /// Steps a mission holds at most. Each takes 12 bytes in the RAM copy
    /// and in RTC memory (`board::esp8266::RtcMissionStore`, 512 bytes).
    pub const MAX_STEPS: usize = 24;
    /// Countdown after `mission start` before the first step, ms: time to
    /// pull the cable and put the robot down.
    pub const COUNTDOWN_MS: u32 = 10_000;
    /// A running mission stops after this long whatever its steps, ms (its
    /// own deadman: nobody is at the cable to stop it).
    pub const TIME_LIMIT_MS: u32 = 300_000;
}

/// The on-board log (`control::log`): telemetry rows kept in RAM during a
/// mission, dumped with `dump`.
pub mod log {
    /// Rows kept (a ring: when it is full the oldest row goes and is
    /// counted as dropped). 60 bytes each, in the firmware's DRAM budget
    /// (24 KiB, of which the rest of the firmware takes 8 KB): 200 rows
    /// are 12 KB, 50 s at 4 Hz.
    pub const ROWS: usize = 200;
    /// Rows per second at boot (`log <Hz>` changes it, 0 = off): a row
    /// every 250 ms is every 40 mm at 0.15 m/s.
    pub const HZ: u16 = 4;
    /// Rows written per loop tick while dumping: one row (about 110 bytes)
    /// every 10 ms is 11 kB/s, what the UART carries (115200 baud).
    pub const DUMP_ROWS_PER_TICK: u8 = 1;
}
