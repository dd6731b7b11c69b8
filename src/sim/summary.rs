//! The closing summary of a simulated run, as `simulate` and the emulated
//! image on the simulated robot (`cargo fw-emu --sim`) both print it: the
//! true, estimated and dead-reckoned poses at the end, the errors at the end
//! and over the run, and the firmware's fault counters.

use std::fmt;

use super::body::PoseF64;
use crate::control::protocol::FaultCounters;

/// One comparison over the run: the truth and what the firmware believed.
#[derive(Clone, Copy, Debug)]
pub struct Compared {
    pub truth: PoseF64,
    pub estimate: PoseF64,
    pub dead_reckoned: PoseF64,
}

/// The run's summary; its `Display` is the closing lines.
pub struct Summary<'a> {
    /// The poses at the end.
    pub end: Compared,
    /// The samples the rms errors are taken over.
    pub samples: &'a [Compared],
    /// Ticks the body was held by a wall.
    pub collisions: u32,
    pub faults: FaultCounters,
}

impl Summary<'_> {
    /// The rms of `err` between the truth and `of` over the samples.
    fn rms(&self, err: impl Fn(&PoseF64, &PoseF64) -> f64, of: impl Fn(&Compared) -> PoseF64) -> f64 {
        let n = self.samples.len().max(1) as f64;
        (self.samples.iter().map(|s| err(&s.truth, &of(s)).powi(2)).sum::<f64>() / n).sqrt()
    }
}

impl fmt::Display for Summary<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let Compared { truth: t, estimate: e, dead_reckoned: d } = self.end;
        for (name, p) in [("true     ", t), ("estimate ", e), ("dead reck", d)] {
            writeln!(f, "  {name} x {:8.1} mm  y {:8.1} mm  heading {:6.1} deg", p.x, p.y, p.theta.to_degrees())?;
        }
        writeln!(
            f,
            "  estimate error at the end {:.1} mm, {:.1} deg (dead reckoning {:.1} mm); wall collisions: {} ticks",
            t.distance(&e),
            t.heading_error(&e).to_degrees(),
            t.distance(&d),
            self.collisions,
        )?;
        let mm = |a: &PoseF64, b: &PoseF64| a.distance(b);
        let deg = |a: &PoseF64, b: &PoseF64| a.heading_error(b).to_degrees();
        writeln!(
            f,
            "  estimate error over the run (rms) {:.1} mm, {:.1} deg (dead reckoning {:.1} mm, {:.1} deg)",
            self.rms(mm, |s| s.estimate),
            self.rms(deg, |s| s.estimate),
            self.rms(mm, |s| s.dead_reckoned),
            self.rms(deg, |s| s.dead_reckoned),
        )?;
        let c = &self.faults;
        writeln!(
            f,
            "  faults: bus {}, timeout {}, missing {}, bad sample {}, outliers {}, overruns {}",
            c.bus, c.timeout, c.missing, c.bad_sample, c.rejected_outliers, c.overruns
        )
    }
}
