//! What the estimator tells its users: what a correction did with a
//! reading, how sure it is of the pose, its counts, its sigmas.

use crate::math::Angle;

/// What a correction did with a reading (the best hypothesis's outcome).
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
pub enum Update {
    /// Used to correct the pose.
    Accepted,
    /// Too far from its prediction (innovation gate): counted, not used.
    Outlier,
    /// The geometry makes the reading useless: the beam meets its wall too
    /// obliquely or passes near a corner. Counted, not used.
    Unusable,
}

impl Tracking {
    /// One word for `status` and telemetry: `located`, `ambiguous`, `unknown`.
    pub fn word(self) -> &'static str {
        match self {
            Tracking::Located => "located",
            Tracking::Ambiguous => "ambiguous",
            Tracking::Unknown => "unknown",
        }
    }

    /// The state a [`Self::word`] names.
    pub fn from_word(word: &str) -> Option<Tracking> {
        [Tracking::Located, Tracking::Ambiguous, Tracking::Unknown].into_iter().find(|t| t.word() == word)
    }
}

impl Update {
    pub fn is_accepted(self) -> bool {
        self == Update::Accepted
    }
}

/// How sure the estimator is of where the robot is (for control,
/// telemetry and `status`).
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
pub enum Tracking {
    /// One hypothesis dominates: the reported pose follows it.
    Located,
    /// Several hypotheses, none dominating: the reported pose holds (it
    /// only dead-reckons); `goto` waits or localizes. Also while one
    /// dominates but the reported pose, which never jumps, is still more
    /// than [`AMBIGUOUS_GAP_MM`](crate::config::estimator::AMBIGUOUS_GAP_MM) from it (catching up as the robot moves).
    Ambiguous,
    /// Started from a typed pose with the config's initial uncertainty,
    /// not yet narrowed to [`LOCATED_SIGMA_MM`](crate::config::estimator::LOCATED_SIGMA_MM).
    Unknown,
}

/// Counts of what became of one sensor's readings (saturating).
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug, Default)]
pub struct SensorStats {
    pub accepted: u32,
    pub outliers: u32,
    pub unusable: u32,
    /// Local re-searches this sensor's disagreements started.
    pub researched: u32,
}

impl SensorStats {
    pub(super) fn count(&mut self, u: Update) {
        let c = match u {
            Update::Accepted => &mut self.accepted,
            Update::Outlier => &mut self.outliers,
            Update::Unusable => &mut self.unusable,
        };
        *c = c.saturating_add(1);
    }
    /// All readings seen.
    pub fn total(&self) -> u32 {
        self.accepted.saturating_add(self.outliers).saturating_add(self.unusable)
    }
}

/// Per-sensor counts, hypotheses spawned, and how often the covariance
/// needed repair.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug, Default)]
pub struct EstimatorStats {
    pub front: SensorStats,
    pub right: SensorStats,
    pub compass: SensorStats,
    /// Hypotheses started by local re-searches.
    pub spawned: u32,
    /// Times a covariance broke `P_ij^2 <= P_ii P_jj` (by rounding, at a
    /// correlation of 1) and was clamped back, or a gain overflowed.
    pub repairs: u32,
}

/// The covariance's diagonal in the units people read (for telemetry):
/// one-sigma position in mm (Q16, a [`crate::math::Length`]'s bits) and heading as an [`Angle`].
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug, Default)]
pub struct PoseSigma {
    pub x: crate::math::Length,
    pub y: crate::math::Length,
    pub theta: Angle,
}
