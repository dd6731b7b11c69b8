//! Every number a user tunes, in one place, each with its unit and source.
//!
//! Sources: "report" is the lab report (`shared/seed/lab1-report.txt`),
//! "data" the lab's measurements (`tests/data/lab1/`), "PAPERBOT" the
//! project's fact sheet (`shared/docs/PAPERBOT.md`). Values are written in
//! the units people use (mm, degrees, rad/s) and converted to the fixed-point
//! types by `const fn`s at compile time: no float code reaches the robot.
//! To refit from new measurements: `cargo run --example fit -- <csv>` prints
//! constants ready to paste here.

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

/// The pose estimator (`model::estimator`): noise levels, gates and limits.
/// Units: lengths in mm, angles in degrees, converted at compile time.
pub mod estimator {
    use super::Length;

    /// Spread of a lidar's model output, mm: the readings' spread about their
    /// mean at a fixed distance is 1.6 mm and the fitted line misses the
    /// per-distance means by up to 1.4 mm (data `lidar_*.csv`: rms residual
    /// of the report's lines over all readings 1.86 mm front, 1.70 mm right).
    pub const LIDAR_SIGMA: Length = Length::from_mm_f64(2.0);
    /// Spread of the calibrated compass heading, degrees (data
    /// `magnetometer_heading.csv`, PAPERBOT: about 2.5 degrees).
    pub const COMPASS_SIGMA_DEG: f64 = 2.5;
    /// Relative spread of the car's speed going straight (std/mean of the
    /// timed runs of one command pair; data `servo_runs.csv`: rms over the
    /// pairs 1.9 % forward, 2.5 % backward; the larger is used).
    pub const SPEED_SPREAD: f64 = 0.025;
    /// Relative spread of the turn rate (data `servo_runs.csv`: rms over the
    /// pairs 2.6 % clockwise, 1.1 % counter-clockwise; the larger is used).
    pub const TURN_SPREAD: f64 = 0.026;
    /// A speed error holds for a whole run, not a tick: the estimator models
    /// it as a random walk whose variance over this distance equals the
    /// spread squared (the lab's timed run was 450 mm, data `servo_runs.csv`).
    pub const SPEED_CORRELATION_MM: f64 = 450.0;
    /// The same for turns, degrees of turning (one 90-degree turn: the
    /// drives the estimator is tested on turn by quarter turns).
    pub const TURN_CORRELATION_DEG: f64 = 90.0;
    /// A turn in place does not pivot exactly about the axle: the paper skid
    /// drags (PAPERBOT) and moves the pivot by this much, one sigma, mm. The
    /// estimator adds it as position noise across the car per angle turned
    /// (a random walk over `TURN_CORRELATION_DEG`), so after a turn it
    /// follows the lidars instead of gating them out. The simulator's pivot
    /// (`sim::PIVOT_BEHIND_AXLE_MM` and its spread) lies within it.
    pub const PIVOT_SIGMA_MM: f64 = 12.0;
    /// Extra position noise always added, mm^2 per second: keeps the
    /// covariance a margin away from singular (a turn's noise is rank one)
    /// and from collapsing while the robot stands still; 0.7 mm after a
    /// second, small against the lidars' 2 mm at 30 Hz.
    pub const POSITION_FLOOR_MM2_PER_S: f64 = 0.5;
    /// Extra heading noise always added, deg^2 per second (same reason;
    /// 0.2 degrees after a second).
    pub const HEADING_FLOOR_DEG2_PER_S: f64 = 0.05;
    /// Innovation gate, standard deviations: a reading further than this
    /// from its prediction is counted as an outlier and not used (3.5 sigma
    /// passes 99.95 % of good readings).
    pub const GATE_SIGMAS: f64 = 3.5;
    /// Lidar readings hitting their wall further than this from square on
    /// are not used (the VL53L0X's 25-degree cone makes oblique readings
    /// short; the linearisation also degrades), degrees.
    pub const MAX_INCIDENCE_DEG: f64 = 60.0;
    /// Lidar readings whose cone meets two walls at ranges closer than this
    /// are not used (which wall the reading came from is uncertain), mm. A
    /// side wall met at the cone's edge moves its nearest point by about
    /// 30 mm per degree of heading at the box's distances (160 mm from the
    /// wall, 17 degrees off its line), so a one-degree heading error can pick
    /// the wrong wall inside 30 mm, and a turn at a corner sweeps the
    /// cone's edge across a glancing wall: at 35 mm the realistic
    /// simulator's hours, from the power-up localization, took such a
    /// reading as the other wall's and jumped 22 mm (tests/realistic_hour.rs:
    /// worst 34.4 mm over 20 seeds; at 40 mm, 24.0 mm). Larger is not
    /// better: from 45 mm the real drive (tests/lab2_drive.rs) loses
    /// readings it needs and steps further than the wheels drive.
    pub const CORNER_MARGIN: Length = Length::from_mm_f64(40.0);
    /// Initial position uncertainty (one sigma), mm: the robot is put down by
    /// hand near its start pose.
    pub const INITIAL_SIGMA_MM: f64 = 100.0;
    /// Initial heading uncertainty (one sigma), degrees.
    pub const INITIAL_SIGMA_DEG: f64 = 20.0;
    /// Largest position or heading variance kept, mm^2 (heading as (256 mm
    /// x rad)^2, see the estimator): 256 mm (57 degrees) one sigma. Past it
    /// the row and column are scaled down, which keeps the covariance valid.
    pub const MAX_VARIANCE_MM2: f64 = 65536.0;
    /// Smallest variance kept, mm^2 (same units): 0.1 mm, 0.02 degrees.
    pub const MIN_VARIANCE_MM2: f64 = 0.01;
    /// Outliers in a row from one sensor after which the estimator takes the
    /// sensor's side, readings: it re-inflates the variances that sensor
    /// reads (compass: the heading's, to `MAX_VARIANCE_MM2`; a lidar: the
    /// position's, to `REACQUIRE_SIGMA_MM`), drops their correlations, and
    /// uses the reading with its innovation clipped to the gate (so the step
    /// stays within `GATE_SIGMAS` of the re-inflated covariance). Without it
    /// a wrong estimate further than the gate from the truth (a wheel held
    /// at a wall for 0.3 s of a turn: 41 degrees) rejects every true reading
    /// for ever. A good reading fails the 3.5-sigma gate with probability
    /// 5e-4, so ten in a row do not happen by chance, nor from the 1-10 % of
    /// corrupted transactions the fault tests inject; ten are 0.1 s of
    /// compass (100 Hz) and 0.33 s of one lidar (30 Hz). Single outliers
    /// stay rejected.
    pub const REACQUIRE_AFTER: u8 = 10;
    /// Position uncertainty a lidar's re-acquisition starts from (one sigma
    /// on each axis, uncorrelated; a larger variance already held is kept),
    /// mm. One re-acquisition moves the position at most `GATE_SIGMAS`
    /// times this (157 mm), so a lost estimate walks back to the lidars in
    /// bounded steps, one per run of `REACQUIRE_AFTER` outliers, instead of
    /// jumping across the box. The real robot's turns leave position errors
    /// of about 100 mm (issue 23): one step covers them. Measured
    /// (tests/estimator_no_teleport.rs, a robot standing 550 mm from where
    /// a settled estimate believes it): 4 re-acquisitions, 1.2 s until
    /// within 20 mm; at 30 mm, 6 steps of 105 mm and 1.5-1.8 s; at 60 mm,
    /// 3 steps of 210 mm and 0.9 s. The realistic simulated hour (worst
    /// 25.1 mm), the soak (90 % of errors below 20 mm) and the real drive's
    /// largest step (4.0-4.2 mm) do not change from 30 to 60 mm.
    pub const REACQUIRE_SIGMA_MM: f64 = 45.0;
    /// The estimate is kept within this distance outside the arena's walls,
    /// mm: the reference point is on the car, always inside the box, so a
    /// position further out is known wrong (dead reckoning while the body is
    /// held at a wall). 50 mm is more than three times the estimator's
    /// tracking error (15 mm rms), so a tracking estimate never meets it.
    pub const ARENA_MARGIN: Length = Length::from_mm_f64(50.0);
}

/// Localization (`model::locate`): where in the box the robot is, searched
/// at power-up and on `locate` from the compass and the two lidars.
pub mod locate {
    /// Grid step of the search, mm: 15,000 points in the team's box, each
    /// two lidar models (about 0.2 s on the lx106, lx106/BENCHMARKS.md).
    pub const GRID_MM: i32 = 5;
    /// A grid point explains a reading within this, mm: three lidar sigmas
    /// (`estimator::LIDAR_SIGMA`: 6 mm), half the grid's diagonal (3.5 mm),
    /// and what the compass's spread (2.5 degrees, `estimator::
    /// COMPASS_SIGMA_DEG`) moves an oblique beam's reading at typical
    /// ranges (a few mm).
    pub const TOLERANCE_MM: f64 = 12.0;
    /// Points that explain the readings spread over more than this on an
    /// axis: the fix is ambiguous (reported as such), mm. Two tolerances
    /// and a grid step over the span of one point's neighbourhood.
    pub const AMBIGUOUS_SPAN_MM: i32 = 60;
    /// A view taken after turns in place explains its readings within
    /// this more, mm: a real turn pivots about a point behind the axle
    /// (`sim::PIVOT_BEHIND_AXLE_MM`, 10 mm, spread 5 mm), which moves the
    /// reference point off the turn-in-place model by up to twice that
    /// (after a half turn: 20 mm, 30 mm at two sigmas).
    pub const TURN_TOLERANCE_MM: f64 = 20.0;
    /// With more readings than this over all views, the search lets one of
    /// them go unexplained when nothing explains them all (a glancing
    /// reading's spurious echo, `sim::SPURIOUS_SHARE`): the rest still pin
    /// the pose.
    pub const MIN_READINGS_FOR_OUTLIER: u32 = 3;
    /// When nothing fits at the compass's heading, the search tries headings
    /// this far apart, degrees (the compass's 2.5-degree spread, `estimator::
    /// COMPASS_SIGMA_DEG`) ...
    pub const HEADING_STEP_DEG: f64 = 2.5;
    /// ... up to this many each way (30 degrees: the real drive's compass,
    /// `tests/data/lab2/drive1.csv`, is fitted by no pose within 10 degrees
    /// of its first reading; the box is only roughly aligned with north).
    pub const HEADING_STEPS: u8 = 12;
    /// A reading whose beam would meet its wall past this incidence, at a
    /// point the search tries, says nothing about that point, degrees:
    /// glancing readings fail or come back as spurious echoes (the lab 2
    /// README; the simulator's `sim::GLANCING_DEG` onset, where half fail).
    pub const GLANCING_DEG: f64 = 75.0;
    /// Readings per lidar in a view, whose median the search takes: five
    /// lidar periods (0.17 s); the median takes the lidar's 1.6 mm spread
    /// to about 1 mm and drops a spurious echo or two.
    pub const LIDAR_READINGS: u8 = 5;
    /// Compass readings averaged: 0.2 s at 100 Hz; the compass's spread
    /// against the truth is mostly per heading, not per reading, so more
    /// would not help (data `magnetometer_heading.csv`).
    pub const COMPASS_READINGS: u8 = 20;
    /// A view's readings are taken for at most this long, ms; a lidar that
    /// gave fewer than `LIDAR_READINGS` by then gives the median of what it
    /// gave (none: no distance in that view). Five lidar periods and a
    /// half: room for a dropped reading or two.
    pub const VIEW_LIMIT_MS: u32 = 300;
    /// The robot localizes at power-up (the firmware and the simulator),
    /// turning in place: set false to start at the box's centre, unknown
    /// (`pose` or `locate` then).
    pub const AT_POWER_UP: bool = true;
    /// Views taken before the first search: two views can agree on a
    /// wrong pose far off (`tests/locate.rs`: 75 % right from two, 99.2 %
    /// from three).
    pub const MIN_VIEWS: usize = 3;
    /// The turn in place between views, degrees: two views at 45 degrees
    /// put the beams on walls of both axes from most of the box.
    pub const TURN_DEG: i32 = 45;
    /// Its rate, mrad/s: `goto`'s turn rate (`goto::TURN_MRAD_S`).
    pub const TURN_MRAD_S: i32 = super::goto::TURN_MRAD_S;
    /// The body stands this long after a turn before its view is taken,
    /// ms: the servos stop within a tick (data `servo_runs.csv`), and a
    /// lidar reading begun while turning (33 ms each) is over.
    pub const SETTLE_MS: u32 = 100;
    /// A turn the compass says moved less than this, degrees, was blocked
    /// (the body against a wall): the next turns go the other way.
    pub const BLOCKED_TURN_DEG: i32 = 20;
    /// Grid columns searched per loop tick (a column is 99 points of the
    /// team's box): two take up to 267,000 lx106 instructions (the worst
    /// slice of the search in lx106/BENCHMARKS.md), a third of the 10 ms
    /// tick at 80 MHz and one instruction a cycle (half at 1.5 cycles),
    /// which leaves the tick's own work room; a pass over the box takes 77
    /// ticks (0.8 s).
    pub const COLUMNS_PER_TICK: u32 = 2;
    /// The whole procedure's time limit, ms: eight views (5 s) and a
    /// search that tries every heading (50 passes, 39 s).
    pub const TIME_LIMIT_MS: u32 = 60_000;
}

/// The simulated robot (`sim`, host only; f64 is fine: nothing here reaches
/// the robot). Noise levels from the lab's data where it has them.
pub mod sim {
    /// Lidar noise (one sigma), mm: the spread of the lab's repeated
    /// readings at fixed distances (data `lidar_*.csv`, about 1.6 mm).
    pub const LIDAR_NOISE_MM: f64 = 1.6;
    /// Compass heading noise (one sigma), degrees: the spread of the lab's
    /// check against a printed compass (data `magnetometer_heading.csv`,
    /// PAPERBOT: about 2.5 degrees).
    pub const COMPASS_NOISE_DEG: f64 = 2.5;
    /// Straight speed noise per loop tick (one sigma), fraction of the
    /// speed: white noise on top of the fitted lines (averages to about 1%
    /// over a one-second run; the lab's runs spread by a few percent, data
    /// `servo_runs.csv`, most of which the lines absorb).
    pub const SPEED_NOISE: f64 = 0.10;
    /// Turn rate noise per loop tick (one sigma), fraction of the rate.
    pub const TURN_NOISE: f64 = 0.10;
    /// Horizontal earth field after calibration, ASA-adjusted counts:
    /// about 24 uT at UCLA (NOAA WMM) at 0.15 uT per count.
    pub const FIELD_HORIZONTAL_COUNTS: f64 = 160.0;
    /// Vertical (down) earth field, counts: about 38 uT at UCLA (NOAA WMM).
    pub const FIELD_DOWN_COUNTS: f64 = 253.0;
    /// Where the default run starts, mm and degrees: the first corner of
    /// the built-in laps (`sim::script::default_script`), 170 mm from the
    /// south and west walls, where the front lidar's cone meets the wall
    /// ahead before the side wall.
    pub const START_X_MM: f64 = 170.0;
    pub const START_Y_MM: f64 = 170.0;
    pub const START_HEADING_DEG: f64 = 0.0;
    /// Half the car's width at the wheels, mm (the 85 mm axle): a wheel
    /// that would pass a wall is a collision.
    pub const HALF_TRACK_MM: f64 = 42.5;

    // The realistic simulator's effects (`sim::realism`; each an option of
    // `simulate`).

    /// Trial-to-trial spread of the speed, one sigma, fraction, per motion
    /// (forward, backward, clockwise, counter-clockwise): each motion runs at
    /// its line's speed times one factor drawn for it. Data `servo_runs.csv`:
    /// the rms over the five command pairs of the ten timed runs' relative
    /// spread, 1.9 %, 2.5 %, 2.6 %, 1.1 %.
    pub const SPEED_SPREAD: [f64; 4] = [0.019, 0.025, 0.026, 0.011];
    /// A turn in place pivots about a point this far behind the axle's
    /// midpoint on average, mm: the paper skid drags ~70 mm behind the axle
    /// (PAPERBOT) and holds the tail back. Not measured (the lab timed turns
    /// only); 10 mm, a seventh of the way to the skid, is an assumption.
    pub const PIVOT_BEHIND_AXLE_MM: f64 = 10.0;
    /// Spread of that point from turn to turn, one sigma, mm (assumed, as
    /// the mean: the skid's grip changes with the paper and the floor).
    pub const PIVOT_SPREAD_MM: f64 = 5.0;
    /// The lidar's cone, full angle, degrees: the sensor's (`lidar::CONE_DEG`).
    pub const LIDAR_CONE_DEG: f64 = super::lidar::CONE_DEG;
    /// Readings start failing past this incidence of the beam's axis on the
    /// wall, degrees, all fail at 90 (the lab 2 README: glancing readings
    /// fail; the lab measured square on only, so the onset is assumed).
    pub const GLANCING_DEG: f64 = 60.0;
    /// Of the failed readings, the share that is a spurious echo (0.3 to 1.5
    /// times the true distance) rather than "no target" (assumed).
    pub const SPURIOUS_SHARE: f64 = 0.3;
    /// Compass disturbance: amplitude of the heading error that varies over
    /// the floor, degrees (assumed: within the lab's 2.5-degree spread
    /// against a printed compass, data `magnetometer_heading.csv`).
    pub const COMPASS_DISTURBANCE_DEG: f64 = 2.0;
    /// Wavelength of that pattern over the floor, mm (about the box's length).
    pub const COMPASS_DISTURBANCE_WAVELENGTH_MM: f64 = 800.0;
}

/// The teleop tool (`examples/teleop.rs`, `host::teleop`; host only).
pub mod teleop {
    use super::timing::DEADMAN_MS;

    /// How often a held motion command is sent again, ms: a quarter of the
    /// deadman, so three refreshes in a row may be lost or late (USB serial
    /// adds a few ms) before the robot stops.
    pub const REFRESH_MS: u32 = DEADMAN_MS / 4;
    const _: () = assert!(REFRESH_MS > 0 && REFRESH_MS * 2 < DEADMAN_MS);
    /// Speed levels of the drive keys, spread evenly over each motion's
    /// measured range (`config::actuators`: both wheels' lines hold there).
    pub const SPEED_LEVELS: usize = 5;
    /// The level at start (0 = slowest): the middle of the measured range.
    pub const START_LEVEL: usize = SPEED_LEVELS / 2;
    const _: () = assert!(SPEED_LEVELS >= 2 && START_LEVEL < SPEED_LEVELS);
    /// Telemetry rate the tool asks for while recording, Hz: a row every
    /// 20 ms catches every lidar reading (one per 33 ms timing budget; a
    /// row carries only the newest reading) and half the compass's 100 Hz;
    /// about 5.5 kB/s of rows (110 bytes each), half the UART's 11.5 kB/s.
    pub const RECORD_TELEMETRY_HZ: u16 = 50;
    const _: () = assert!(RECORD_TELEMETRY_HZ <= super::serial::MAX_TELEMETRY_HZ);
    /// No telemetry row for this long marks the link stale on the screen, ms.
    pub const STALE_LINK_MS: u32 = 1_000;
    /// Screen refresh period of the terminal UI, ms (20 frames a second).
    pub const FRAME_MS: u32 = 50;
    /// Messages (`#` lines) kept on the screen.
    pub const MESSAGES_SHOWN: usize = 8;
    /// How long the line mode waits for the answer to its first `rate 0`,
    /// dropping the rows the robot streamed before, ms: the answer comes
    /// within a tick or two; a robot still booting may take longer, and the
    /// run then goes on without it.
    pub const ANSWER_WAIT_MS: u32 = 1_000;
}

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
