//! The `replay` tool's judgement of a replayed estimate (host only,
//! `host::replay_stats`).

/// An estimate that accepts fewer than this share of its usable lidar
/// readings is reported lost: the estimator refuses most of what the sensors say
/// (issue #29). Half: a tracking estimate accepts nearly all (the lab's
/// simulated runs: 99 %), one off by more than its gate accepts few.
pub const LOST_ACCEPTED_SHARE: f64 = 0.5;
/// ... or whose lidar readings disagree with it by more than this on
/// average, in lidar sigmas (the mean normalised innovation,
/// `host::replay_stats`): the real drive replayed from its own
/// localization disagrees by 2 to 3 (`tests/estimator/lab2_drive.rs`), an estimate
/// 30 mm off along a beam square to its wall by 15 (30 mm over the 2 mm
/// sigma, `estimator::LIDAR_SIGMA`); the estimator, started confident at a wrong
/// pose, still accepts most readings (70 %) while they disagree by 24 (right)
/// to 155 (front).
pub const LOST_MEAN_INNOVATION: f64 = 15.0;
