//! The magnetometer calibration sweep (`cal`), the state of
//! [`Mode::Calibrate`]: it turns in place while the compass's raw samples
//! feed a [`MagCalibrator`]; when it has them (or its time is up) the new
//! calibration is applied and printed as the config line to paste.

use super::clock::Timer;
use super::mode::Sweep;
use super::settings::{Source, NOT_SAVED};
use super::{Controller, Hardware, LineSink, Mode};
use crate::config;
use crate::control::protocol::number::push_str;
use crate::control::protocol::response::{format_calibration_report, format_config_line};
use crate::control::protocol::Response;
use crate::driver::MagCalibrate;
use crate::math::TurnRate;
use crate::model::compass::{CalibrationError, MagCalibration, MagCalibrator};
use crate::model::Motion;

impl<H: Hardware> Controller<H> {
    /// Starts a sweep of `samples` samples (`cal`).
    pub(super) fn begin_sweep(&mut self, samples: u16) {
        let calibrator = MagCalibrator::new(
            self.compass.driver.asa(),
            config::compass::AXES,
            samples,
            config::compass::CALIBRATION_MIN_SECTORS,
            config::compass::CALIBRATION_MIN_RADIUS,
        );
        let turn = Motion::Turn(TurnRate::from_mrad_s(config::compass::CALIBRATION_TURN_MRAD_S));
        // max_samples <= u16::MAX: the product fits in u32 (asserted at MAX_SPAN_MS)
        let limit_ms = u32::from(calibrator.max_samples()) * config::compass::CALIBRATION_MS_PER_SAMPLE;
        self.mode = Mode::Calibrate {
            drive: self.model.drive(turn),
            timer: Timer::new(Some(limit_ms)),
            sweep: Sweep::new(calibrator),
        };
    }

    /// Ends the running sweep with its result (its samples are in, or its
    /// time is up).
    pub(super) fn finish_sweep(&mut self, sink: &mut impl LineSink) {
        let result = match &self.mode {
            Mode::Calibrate { sweep, .. } => Some(sweep.calibrator().result()),
            _ => None,
        };
        self.end_calibration(result, sink);
    }

    /// Ends a calibration sweep: applies and prints a good result, reports
    /// a bad one (`None`: abandoned for another command). The robot stops.
    pub(super) fn end_calibration(
        &mut self,
        result: Option<Result<MagCalibration, CalibrationError>>,
        sink: &mut impl LineSink,
    ) {
        let (samples, sectors) = match &self.mode {
            Mode::Calibrate { sweep, .. } => (sweep.calibrator().samples(), sweep.calibrator().sectors()),
            _ => (0, 0),
        };
        if matches!(self.mode, Mode::Calibrate { .. }) {
            self.mode = Mode::Idle;
        }
        if let Some(Ok(cal)) = result {
            self.compass.driver.set_calibration(cal);
        }
        // Integer formatting (no core::fmt on the robot), straight into the
        // output line: every text here is printable ASCII, as `Response::Note`
        // and `Fail` would leave it. A line that does not fit is cut short,
        // which MAX_OUT_LINE makes impossible here.
        self.out.clear();
        if format_calibration_report(&mut self.out, result, samples, sectors).is_ok() {
            sink.write_line(&self.out);
        }
        if let Some(Ok(cal)) = result {
            self.out.clear();
            if push_str(&mut self.out, "# ").and_then(|()| format_config_line(&mut self.out, &cal)).is_ok() {
                sink.write_line(&self.out);
            }
            self.sources.calibration = Source::Changed;
            self.respond(&Response::Note(NOT_SAVED), sink);
        }
    }
}
