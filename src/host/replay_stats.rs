//! How a replayed estimate agrees with its lidar readings (`replay`'s
//! closing lines, issue #29): the share of the readings the estimator
//! accepted, the mean normalised innovation, and whether the estimate is
//! lost: it refuses most of its readings
//! ([`crate::config::replay::LOST_ACCEPTED_SHARE`]), or they disagree with
//! it by far more than their noise on average
//! ([`crate::config::replay::LOST_MEAN_INNOVATION`]).
//!
//! The normalised innovation of a reading is its distance (the lidar
//! model's output) less what the arena model says the lidar reads from the
//! prior pose, in units of the lidar's sigma
//! ([`crate::config::estimator::LIDAR_SIGMA`]). The prior is the previous
//! row's estimate moved by that row's commands' motion over the time
//! between the rows, as the estimator predicts it. The estimator's own
//! uncertainty is not in it (the replay hands out poses only), so it reads
//! high while the estimate is uncertain: about 1 for an estimate on its
//! track, tens for one off by tens of mm.

use crate::config;
use crate::math::Dt;
use crate::model::estimator::replay::{Estimate, Sample};
use crate::model::estimator::{EstimatorStats, SensorStats};
use crate::model::lidar::Range;
use crate::model::measurement::{expected_lidar, Arena, LidarId};
use crate::model::state::step;

/// One lidar's agreement with the estimate.
#[derive(Clone, Copy, PartialEq, Debug, Default)]
pub struct LidarAgreement {
    /// Readings the estimator accepted, and those it weighed (accepted or
    /// refused as outliers; "no target" and "too close" readings are
    /// neither), its counts.
    pub accepted: u32,
    pub readings: u32,
    /// Mean of |normalised innovation| over the readings with a prior and
    /// a modelled wall (see the module docs), and how many that was.
    pub mean_normalised: f64,
    pub innovations: u32,
}

impl LidarAgreement {
    fn from_stats(s: &SensorStats) -> LidarAgreement {
        LidarAgreement {
            accepted: s.accepted,
            readings: s.accepted.saturating_add(s.outliers),
            ..LidarAgreement::default()
        }
    }
}

/// Both lidars' agreement.
#[derive(Clone, Copy, PartialEq, Debug, Default)]
pub struct Agreement {
    pub front: LidarAgreement,
    pub right: LidarAgreement,
}

impl Agreement {
    /// The share of all lidar readings accepted (1 with none).
    pub fn accepted_share(&self) -> f64 {
        let readings = self.front.readings + self.right.readings;
        if readings == 0 {
            return 1.0;
        }
        f64::from(self.front.accepted + self.right.accepted) / f64::from(readings)
    }

    /// The mean normalised innovation over both lidars (0 with none).
    pub fn mean_normalised(&self) -> f64 {
        let n = self.front.innovations + self.right.innovations;
        if n == 0 {
            return 0.0;
        }
        let sum = self.front.mean_normalised * f64::from(self.front.innovations)
            + self.right.mean_normalised * f64::from(self.right.innovations);
        sum / f64::from(n)
    }

    /// The estimator refuses most of its readings, or they disagree with
    /// it far beyond their noise: the estimate is lost.
    pub fn lost(&self) -> bool {
        self.accepted_share() < config::replay::LOST_ACCEPTED_SHARE
            || self.mean_normalised() > config::replay::LOST_MEAN_INNOVATION
    }
}

/// The agreement of `estimates` (one per row of `samples`, from
/// `replay::replay`) with the rows' lidar readings; `stats` are the
/// replay's counts.
pub fn agreement(samples: &[Sample], estimates: &[Estimate], stats: &EstimatorStats, arena: &Arena) -> Agreement {
    let mut out =
        Agreement { front: LidarAgreement::from_stats(&stats.front), right: LidarAgreement::from_stats(&stats.right) };
    let sigma = config::estimator::LIDAR_SIGMA.to_mm_f64();
    let tick_us = 1_000_000 / config::timing::LOOP_HZ;
    let mut sums = [0.0f64; 2];
    for (rows, est) in samples.windows(2).zip(estimates.windows(2)) {
        let (before, now) = (&rows[0], &rows[1]);
        // the prior: the previous estimate moved as the estimator predicts
        let motion = config::actuators::MODEL.motion_from_commands(before.left, before.right);
        let mut prior = est[0].pose;
        let mut us = u64::from(now.t_ms.saturating_sub(before.t_ms)) * 1000;
        while us > 0 {
            let chunk = us.min(u64::from(tick_us));
            prior = step(&prior, motion, Dt::from_micros_saturating(chunk as u32));
            us -= chunk;
        }
        for (i, which, raw, model) in [
            (0, LidarId::Front, now.front_mm, &config::lidar::FRONT),
            (1, LidarId::Right, now.right_mm, &config::lidar::RIGHT),
        ] {
            let Some(Range::Target(z)) = raw.map(|r| model.range(r)) else { continue };
            let Some(expected) = expected_lidar(arena, &prior, which) else { continue };
            sums[i] += ((z.to_mm_f64() - expected.to_mm_f64()) / sigma).abs();
            let a = if i == 0 { &mut out.front } else { &mut out.right };
            a.innovations += 1;
        }
    }
    for (a, sum) in [(&mut out.front, sums[0]), (&mut out.right, sums[1])] {
        a.mean_normalised = if a.innovations == 0 { 0.0 } else { sum / f64::from(a.innovations) };
    }
    out
}
