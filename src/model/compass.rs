//! The magnetometer model (report section 2.4): factory sensitivity
//! adjustment (ASA), hard- and soft-iron correction, axis orientation and
//! declination, giving the heading clockwise from north. Integer only.

pub mod calibration;

use crate::math::{atan2, round_f64, sat_i32, Angle};

pub use calibration::{CalStatus, CalibrationError, ConfigLine, MagCalibrator};

/// Raw AK8963 counts, in the chip's own axes.
#[derive(Clone, Copy, PartialEq, Eq, Debug, Default)]
pub struct MagCounts {
    pub x: i16,
    pub y: i16,
    pub z: i16,
}

impl MagCounts {
    pub fn axis(&self, i: usize) -> i16 {
        match i {
            0 => self.x,
            1 => self.y,
            _ => self.z,
        }
    }
}

/// Corrected field in the chip's axes, in ASA-adjusted counts, soft-iron
/// scaled (Q0: whole counts; 0.15 uT per count at 16 bit).
#[derive(Clone, Copy, PartialEq, Eq, Debug, Default)]
pub struct MagField {
    pub x: i32,
    pub y: i32,
    pub z: i32,
}

impl MagField {
    pub fn axis(&self, i: usize) -> i32 {
        match i {
            0 => self.x,
            1 => self.y,
            _ => self.z,
        }
    }
}

/// One of the chip's axes, possibly negated.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub struct Axis {
    /// 0 = x, 1 = y, 2 = z of the AK8963.
    pub index: u8,
    pub negate: bool,
}

impl Axis {
    pub const X: Axis = Axis { index: 0, negate: false };
    pub const Y: Axis = Axis { index: 1, negate: false };
    pub const Z: Axis = Axis { index: 2, negate: false };
    pub const fn neg(self) -> Axis {
        Axis { index: self.index, negate: !self.negate }
    }
    fn pick(self, f: &MagField) -> i32 {
        let v = f.axis(usize::from(self.index));
        if self.negate {
            v.saturating_neg()
        } else {
            v
        }
    }
}

/// Which chip axes point to the car's front and to its right.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub struct AxisMap {
    pub forward: Axis,
    pub right: Axis,
}

/// Hard- and soft-iron calibration, per chip axis.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub struct MagCalibration {
    /// Hard-iron bias in ASA-adjusted counts.
    pub bias: [i32; 3],
    /// Soft-iron scale in Q16 (65536 = 1.0).
    pub scale_q16: [i32; 3],
}

impl MagCalibration {
    pub const IDENTITY: MagCalibration = MagCalibration { bias: [0; 3], scale_q16: [65536; 3] };
    pub const fn from_f64(bias: [f64; 3], scale: [f64; 3]) -> MagCalibration {
        MagCalibration {
            bias: [sat_i32(round_f64(bias[0])), sat_i32(round_f64(bias[1])), sat_i32(round_f64(bias[2]))],
            scale_q16: [
                sat_i32(round_f64(scale[0] * 65536.0)),
                sat_i32(round_f64(scale[1] * 65536.0)),
                sat_i32(round_f64(scale[2] * 65536.0)),
            ],
        }
    }
}

/// Factory sensitivity adjustment: `raw * ((asa - 128) / 256 + 1)`, i.e.
/// `raw * (asa + 128) / 256`, rounded. Exact in i32 for every raw and ASA.
pub fn apply_asa(raw: i16, asa: u8) -> i32 {
    (i32::from(raw) * (i32::from(asa) + 128) + 128) >> 8
}

/// The compass model: calibration, orientation and declination.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub struct CompassModel {
    pub calibration: MagCalibration,
    pub axes: AxisMap,
    /// Added to the magnetic heading (east positive).
    pub declination: Angle,
}

impl CompassModel {
    /// ASA, then hard iron, then soft iron, per chip axis.
    pub fn correct(&self, raw: MagCounts, asa: [u8; 3]) -> MagField {
        let c = &self.calibration;
        let one = |i: usize| {
            let adj = apply_asa(raw.axis(i), asa.get(i).copied().unwrap_or(128));
            let centred = adj - c.bias.get(i).copied().unwrap_or(0); // |.| < 2^17
            let scale = i64::from(c.scale_q16.get(i).copied().unwrap_or(65536));
            ((i64::from(centred) * scale) >> 16).clamp(-(1 << 24), 1 << 24) as i32
        };
        MagField { x: one(0), y: one(1), z: one(2) }
    }

    /// Heading clockwise from north, from a corrected field. With the car
    /// level, north seen from the car is `(cos h, -sin h)` in (forward,
    /// right), so `h = atan2(-right, forward)`; then plus declination.
    pub fn heading(&self, field: &MagField) -> Angle {
        let f = self.axes.forward.pick(field);
        let r = self.axes.right.pick(field);
        atan2(r.saturating_neg(), f).wrapping_add(self.declination)
    }

    /// Raw counts to heading.
    pub fn heading_from_raw(&self, raw: MagCounts, asa: [u8; 3]) -> Angle {
        self.heading(&self.correct(raw, asa))
    }
}
