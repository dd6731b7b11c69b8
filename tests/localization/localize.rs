//! Localization as the robot does it (`control::survey` in the loop), on
//! the realistic simulator: the robot powers up at a random pose in the
//! box, not knowing where it is, takes its views turning in place, and
//! starts its estimate at the fix. The bar (the right pose, 30 mm
//! and 5 degrees, from 95 % of random starts), wrong fixes flagged, the
//! estimate certain enough for `goto` a second later, and what it costs in
//! time. Measured (lab's world): 989 of 1,000 right, 17 reported
//! ambiguous or uncertain, none wrong and not flagged, 985 steerable; 4.3 s median, 5.9 s
//! at the 95th percentile (before the survey made room to turn,
//! `control::survey::room`: 991, 14, 1, 991; 3.3 s, 7.1 s) (`cargo test --release --test localization localize:: --
//! --nocapture` prints the figures). The hard world's (issue #29): see
//! `the_robot_finds_itself_in_the_hard_world`.

use crate::common;
use common::rng::{random_pose_in_box, Rng};
use paperbot::sim::body::PoseF64;
use paperbot::sim::realism::Realism;
use paperbot::sim::robot::{SimConfig, SimRobot};

/// How one power-up went.
struct Run {
    /// The `# located` or `# locate failed` line.
    line: String,
    seconds: f64,
    off_mm: f64,
    off_deg: f64,
    /// A second later, the estimate is certain enough for `goto`.
    steerable: bool,
    /// The first look fit poorly: the procedure said it looked again.
    looked_again: bool,
}

impl Run {
    /// Within 30 mm and 5 degrees of the truth (issue #29's right fix).
    fn right(&self) -> bool {
        self.off_mm <= 30.0 && self.off_deg <= 5.0
    }

    /// Located, and right: `what` names the power-up when not.
    fn assert_located_right(&self, what: impl std::fmt::Display) {
        assert!(self.line.starts_with("# located "), "{what}: {}", self.line);
        assert!(self.right(), "{what}: {} off {:.1} mm {:.1} deg", self.line, self.off_mm, self.off_deg);
    }
}

/// Powers up at `start` and runs until the procedure ends (at most two
/// looks' time limits and a second).
fn power_up(start: PoseF64, seed: u64, realism: Realism, refine: bool) -> Run {
    let mut robot = SimRobot::new(SimConfig { start, seed, realism, refine, ..SimConfig::default() });
    assert_eq!(robot.take_output(), ["# ok locate"]);
    robot.send("rate 0");
    let limit_ticks = (paperbot::config::locate::LONGEST_MS + 1_000) / 10;
    let mut looked_again = false;
    for _ in 0..limit_ticks {
        robot.tick();
        let out = robot.take_output();
        looked_again |= out.iter().any(|l| l.starts_with("# looking again from elsewhere"));
        if let Some(line) = out.into_iter().find(|l| l.starts_with("# locate")) {
            let s = robot.sample();
            for _ in 0..100 {
                robot.tick();
            }
            let sigma = robot.controller().estimator().sigma();
            let limit = f64::from(paperbot::config::goto::MAX_SIGMA_MM);
            return Run {
                line,
                seconds: s.t_us as f64 * 1e-6,
                off_mm: s.truth.distance(&s.estimate),
                off_deg: s.estimate.heading_error(&s.truth).to_degrees().abs(),
                steerable: sigma.x.to_mm_f64() <= limit && sigma.y.to_mm_f64() <= limit,
                looked_again,
            };
        }
    }
    panic!("no answer from the localization at {start:?}");
}

/// A set of 1,000 power-ups: where the starts are drawn from, and the
/// first run's seed (each run's world, `sim::drawn`, and noise).
#[derive(Clone, Copy)]
struct Set {
    starts_seed: u64,
    first_seed: u64,
}

/// The set every figure and test here was measured on, and the
/// localization's constants chosen by.
const TUNED: Set = Set { starts_seed: 1523, first_seed: 0 };
/// Two sets nothing was chosen by: what a new robot's power-ups would
/// measure (`the_robot_finds_itself_in_the_hard_world`).
const HELD_OUT: [Set; 2] = [Set { starts_seed: 6151, first_seed: 5_000 }, Set { starts_seed: 9209, first_seed: 9_000 }];
/// Two sets never used to choose anything, not even to keep or drop a
/// change tried (sets C and D of docs/simulator.md).
const FRESH: [Set; 2] = [Set { starts_seed: 3331, first_seed: 13_000 }, Set { starts_seed: 4447, first_seed: 17_000 }];

/// The tally of 1,000 power-ups in `realism`, the fixes refined or not
/// (`config::refine`): (right, ambiguous, failed, wrong and not flagged,
/// steerable).
fn power_ups(name: &str, realism: Realism, refine: bool) -> (usize, usize, usize, usize, usize) {
    power_ups_of(TUNED, name, realism, refine)
}

/// [`power_ups`] of `set`.
fn power_ups_of(set: Set, name: &str, realism: Realism, refine: bool) -> (usize, usize, usize, usize, usize) {
    let mut rng = Rng::new(set.starts_seed);
    let starts = 1_000;
    let (mut right, mut ambiguous, mut failed, mut steerable) = (0, 0, 0, 0);
    let mut wrong_unflagged = vec![];
    let mut seconds = vec![];
    for i in 0..starts {
        let start = random_pose_in_box(&mut rng);
        let run = power_up(start, set.first_seed + i, realism, refine);
        seconds.push(run.seconds);
        steerable += usize::from(run.steerable);
        if !run.line.starts_with("# located ") {
            failed += 1;
            continue;
        }
        let flagged = run.line.contains("ambiguous") || run.line.contains("uncertain");
        let ok = run.right();
        right += usize::from(ok);
        ambiguous += usize::from(flagged);
        if !ok && !flagged {
            wrong_unflagged.push((run.off_mm, run.line, (i, start)));
        }
    }
    seconds.sort_by(f64::total_cmp);
    println!(
        "{name} world, power-up localization{}{}: {right} of {starts} right (30 mm, 5 deg); {ambiguous} reported ambiguous or uncertain; \
         {failed} failed; {} wrong and not flagged; {steerable} certain enough for goto a second later; time median {:.1} s, 95th percentile {:.1} s, worst {:.1} s",
        if refine { ", refined" } else { "" },
        if set.first_seed == TUNED.first_seed { String::new() } else { format!(", held-out seeds from {}", set.first_seed) },
        wrong_unflagged.len(),
        seconds[starts as usize / 2],
        seconds[starts as usize * 95 / 100],
        seconds[starts as usize - 1],
    );
    for (off, line, start) in wrong_unflagged.iter().take(10) {
        println!("  wrong, not flagged: off {off:.0} mm: {line} (truth {start:?})");
    }
    (right, ambiguous, failed, wrong_unflagged.len(), steerable)
}

#[test]
fn the_robot_finds_itself_at_power_up_from_random_starts() {
    let starts = 1_000;
    let (right, _, _, wrong_unflagged, steerable) = power_ups("lab", Realism::LAB, false);
    assert!(right * 100 >= starts * 95, "{right} of {starts}");
    assert!(steerable * 100 >= starts * 90, "{steerable} of {starts} certain enough for goto");
    assert!(wrong_unflagged * 100 <= starts, "{wrong_unflagged} wrong fixes not flagged");
}

/// With the refinement on (`SimConfig::refine`, `config::refine::ENABLED`),
/// power-ups in the lab's world end located near the truth: 20 starts,
/// every one within 30 mm and 5 degrees (the 1,000 of the ignored test
/// below: 983 right).
#[test]
fn a_refined_power_up_finds_the_pose() {
    let mut rng = Rng::new(77);
    for i in 0..20 {
        let start = random_pose_in_box(&mut rng);
        power_up(start, 500 + i, Realism::LAB, true).assert_located_right(format_args!("{start:?}"));
    }
}

/// Issue #29's bar in the hard world: right >= 98 %, wrong and not flagged
/// <= 0.2 %. Not met by today's search (see tests/localization/locate.rs's hard-world
/// test for why); measured: `HARD_POWER_UP`. Asserted: no worse than
/// that; the bar is printed, advisory. And the same power-ups with the
/// fix refined with every reading (`config::refine::ENABLED`, on by
/// default): measured `HARD_REFINED`; asserted: no worse than that, at
/// least twice the right fixes and at most half the wrong and not flagged,
/// the two held-out sets no worse than `HARD_HELD_OUT` and the two fresh
/// ones than `HARD_FRESH` (1,000 power-ups each that no constant was
/// chosen by; the five sets pooled are printed), and the lab's 1,000 refined
/// within the lab's bar. Ignored for its time (three minutes in release):
/// `cargo test --release --test localization localize:: -- --ignored --nocapture`.
#[test]
#[ignore = "minutes: the hard world's failing searches try every heading; prints issue #29's figures"]
fn the_robot_finds_itself_in_the_hard_world() {
    let starts = 1_000;
    let (right, _, _, wrong_unflagged, _) = power_ups("hard", Realism::HARD, false);
    let (refined_right, _, _, refined_wrong, _) = power_ups("hard", Realism::HARD, true);
    print_bar("", right, wrong_unflagged);
    print_bar(", refined", refined_right, refined_wrong);
    let (floor_right, ceiling_wrong) = HARD_POWER_UP;
    assert!(right >= floor_right, "{right} of {starts}");
    assert!(wrong_unflagged <= ceiling_wrong, "{wrong_unflagged} wrong fixes not flagged");
    assert!(refined_right >= 2 * right && 2 * refined_wrong <= wrong_unflagged, "{refined_right}, {refined_wrong}");
    let (refined_floor, refined_ceiling) = HARD_REFINED;
    assert!(refined_right >= refined_floor && refined_wrong <= refined_ceiling, "{refined_right}, {refined_wrong}");
    // the held-out and fresh sets: what the constants chosen on the tuned
    // set give where nothing was chosen (two at a time: a minute each)
    let others: Vec<(Set, (usize, usize))> =
        HELD_OUT.into_iter().zip(HARD_HELD_OUT).chain(FRESH.into_iter().zip(HARD_FRESH)).collect();
    let tallies: Vec<(usize, usize)> = std::thread::scope(|scope| {
        let runs: Vec<_> = others
            .chunks(2)
            .map(|pair| {
                scope.spawn(move || {
                    pair.iter()
                        .map(|(set, _)| power_ups_of(*set, "hard", Realism::HARD, true))
                        .map(|t| (t.0, t.3))
                        .collect::<Vec<_>>()
                })
            })
            .collect();
        runs.into_iter().flat_map(|r| r.join().expect("a set's power-ups")).collect()
    });
    let (mut pooled_right, mut pooled_wrong) = (refined_right, refined_wrong);
    for ((set, (floor, ceiling)), &(right, wrong)) in others.iter().zip(&tallies) {
        print_bar(&format!(", refined, seeds from {} (chose nothing)", set.first_seed), right, wrong);
        assert!(right >= *floor && wrong <= *ceiling, "the set from seed {}: {right}, {wrong}", set.first_seed);
        (pooled_right, pooled_wrong) = (pooled_right + right, pooled_wrong + wrong);
    }
    print_pooled(pooled_right, pooled_wrong, starts * (1 + others.len()));
    // the lab's world refined: its bar (`the_robot_finds_itself_at_power_up_
    // from_random_starts`); measured 991 right and 1 wrong and not flagged
    // (992 and 0 before the compass's bend) against 986 and 0 unrefined
    let (lab_right, _, _, lab_wrong, _) = power_ups("lab", Realism::LAB, true);
    assert!(lab_right * 100 >= starts * 95 && lab_wrong * 100 <= starts, "{lab_right}, {lab_wrong}");
}

/// Prints whether `right` and `wrong` (not flagged) of 1,000 hard
/// power-ups meet issue #29's bar (advisory: `HARD_REFINED` and
/// `HARD_HELD_OUT` are what is asserted).
fn print_bar(what: &str, right: usize, wrong: usize) {
    let bar = right * 100 >= 1_000 * 98 && wrong * 1000 <= 1_000 * 2;
    println!(
        "hard world{what}: issue #29's bar (right >= 98 %, wrong and not flagged <= 0.2 %) {}",
        if bar { "met" } else { "NOT met (advisory)" }
    );
}

/// Prints the five sets' power-ups pooled (`right` and `wrong` and not
/// flagged of `starts`) with the right share's 95 % interval (Wilson's
/// score interval): one set's count moves by about 5 of 1,000 with any
/// change to the survey (its chaotic runs), so whether issue #29's bar
/// lies inside the interval says more than one set meeting it or not.
fn print_pooled(right: usize, wrong: usize, starts: usize) {
    let (n, z) = (starts as f64, 1.96);
    let p = right as f64 / n;
    let centre = (p + z * z / (2.0 * n)) / (1.0 + z * z / n);
    let half = z / (1.0 + z * z / n) * (p * (1.0 - p) / n + z * z / (4.0 * n * n)).sqrt();
    println!(
        "hard world, refined, {starts} power-ups pooled over the sets: {right} right ({:.2} %, 95 % interval {:.2} to {:.2} %), \
         {wrong} wrong and not flagged ({:.2} %)",
        100.0 * p,
        100.0 * (centre - half),
        100.0 * (centre + half),
        100.0 * wrong as f64 / n
    );
}

/// A refined fit that explains the readings poorly (more than
/// `config::refine::SEARCH_ON_LIMIT` a reading) makes the survey search on
/// at the next headings, and the cheapest fit is reported
/// (`config::refine::SEARCH_ON_STEPS`). Four hard power-ups of the 1,000
/// (`the_robot_finds_itself_in_the_hard_world`) where the search's place at
/// the compass's heading was wrong: each is located within 30 mm and 5
/// degrees now; before, each was reported uncertain 110 to 400 mm off.
/// And held-out set A's start 797, whose search's only place was 214 mm
/// off, refined to 1.97 a reading and vouched for (under
/// `config::refine::FIT_LIMIT`, which searching on took as its limit
/// before): it was located 288 mm off and not flagged; searching on finds
/// the true place, where the fit costs 1.42.
#[test]
fn a_poor_fit_makes_the_search_go_on() {
    power_ups_are_right(Realism::HARD, &[45, 112, 594, 629]);
    power_ups_of_are_right(HELD_OUT[0], Realism::HARD, &[797]);
}

/// A survey whose answer fits poorly (more than
/// `config::refine::SECOND_LOOK_FIT` a reading) looks again from
/// elsewhere: a second survey, begun with its drive to make room, answers
/// instead. Set A's starts 97, 107, 194, 205 and 222 were located 38 to
/// 371 mm off, reported uncertain at 2.5 to 3.6 a reading: each says it
/// looks again and is located within 30 mm and 5 degrees now. Start 107
/// answers 140 s after power-up: its second look has a time limit of its
/// own (with one limit for both, it ran out of time).
#[test]
fn a_poor_fit_looks_again_from_elsewhere() {
    for (i, run) in power_ups_at(HELD_OUT[0], Realism::HARD, &[97, 107, 194, 205, 222]) {
        assert!(run.looked_again, "start {i}: {}", run.line);
        run.assert_located_right(format_args!("start {i}"));
    }
}

/// The power-ups `starts` of the 1,000 in `realism`'s world (the `TUNED`
/// set's starts and seeds) are each located within 30 mm and 5 degrees,
/// refined.
fn power_ups_are_right(realism: Realism, starts: &[usize]) {
    power_ups_of_are_right(TUNED, realism, starts);
}

/// [`power_ups_are_right`] for the power-ups of `set`.
fn power_ups_of_are_right(set: Set, realism: Realism, starts: &[usize]) {
    for (i, run) in power_ups_at(set, realism, starts) {
        run.assert_located_right(format_args!("start {i}"));
    }
}

/// The refined power-ups `starts` of `set`'s 1,000, each with its index.
fn power_ups_at(set: Set, realism: Realism, starts: &[usize]) -> Vec<(usize, Run)> {
    let mut rng = Rng::new(set.starts_seed);
    let poses: Vec<PoseF64> = (0..1_000).map(|_| random_pose_in_box(&mut rng)).collect();
    starts.iter().map(|&i| (i, power_up(poses[i], set.first_seed + i as u64, realism, true))).collect()
}

/// A search of the last views (`config::refine::SEARCH_VIEWS`) that finds
/// nothing within `config::refine::LAST_VIEWS_STEPS` of the compass's
/// heading gives way to a search of the last `config::refine::FEW_VIEWS`,
/// refined with more (their compass errors differ by more than the search
/// allows).
/// Three hard power-ups of the 1,000 that ran out of time before, trying
/// every heading with all the views, each searched again with each new
/// view: each is located within 30 mm and 5 degrees now.
#[test]
fn views_that_fit_nowhere_together_are_searched_a_few_at_a_time() {
    power_ups_are_right(Realism::HARD, &[308, 370, 972]);
}

/// With the refinement on, a search reads the last
/// `config::refine::SEARCH_VIEWS` views (the refinement weighs more): a
/// search of every view costs more with each. Five hard power-ups of the
/// 1,000 that ran out of time before, searching five to eight views for
/// 30 to 90 s each (or, start 832, found a place 237 mm off at the limit):
/// each is located within 30 mm and 5 degrees now.
#[test]
fn a_search_reads_the_last_views() {
    power_ups_are_right(Realism::HARD, &[105, 299, 832, 848, 909]);
}

/// The refinement weighs the last `config::refine::REFINE_VIEWS` views: its
/// one pivot does not follow the skid's pivot from turn to turn. The lab's
/// start 919 takes eight views; weighing them all, its heading was refined
/// 5 degrees off, and not flagged: it is located within 30 mm and 5
/// degrees now.
#[test]
fn the_refinement_weighs_the_last_views() {
    power_ups_are_right(Realism::LAB, &[919]);
}

/// A view the next one repeats (the turn between them blocked by a wall,
/// `config::refine::REPEAT_DEG`) counts once among the last views a search
/// reads, and the search reads the later one. A hard power-up of the
/// 1,000 whose last turn was blocked: searching the repeat and three views
/// before it, it was located 152 mm off; it is located within 30 mm and 5
/// degrees now. (Starts 96 and 973 were mended so too, and became heading
/// misses of 5.4 and 5.1 degrees with a far pivot's wider view prior,
/// since replaced by the floor's bend, `config::refine::FIELD_SIGMA_DEG`.)
#[test]
fn a_view_a_blocked_turn_repeats_is_searched_once() {
    power_ups_are_right(Realism::HARD, &[627]);
}

/// Measured in the hard world, 1,000 power-ups with the fix refined: (right,
/// wrong and not flagged): the tuned set (`TUNED`). Also 813 reported
/// ambiguous or uncertain (the search's flags kept, the refinement's
/// added), 0 failed, 825 certain enough for goto a second later; time
/// median 16.6 s, 95th percentile 76.5 s, the longest 146 s (two looks).
/// (979 and 2, 814 flagged, 826 steerable, 74.9 s, before a poor fit
/// looked again from elsewhere, `config::refine::SECOND_LOOK_FIT`;
/// 980 and 1, 821 flagged, 845
/// steerable, 15.8 s, 73.1 s, before each turn's pivot moved in the
/// refinement's model, `config::refine::PIVOT_MOVE_SIGMA_MM`, its rows
/// 24 a tick; 979 and 1, 817 steerable,
/// 15.6 s, before the drive that makes room ended at a wall ahead,
/// `control::survey::room::drive_ends`; 980 and 2, 762 flagged, 822
/// steerable, 13.5 and 36.4 s, before a fit dearer than
/// `config::refine::SEARCH_ON_LIMIT`, not `FIT_LIMIT`, made the search go
/// on: the power-ups whose right fit costs more search on for a minute;
/// 974 and 6, 814 steerable,
/// 36.1 s, before the compass's bias bent across the pivot's circle,
/// `config::refine::FIELD_SIGMA_DEG`, chosen by the held-out sets, in
/// place of a far pivot's wider view prior; 979 and 1, 825 steerable,
/// 39.1 s, before that wider prior;
/// 42.1 s before a search with no room to turn after it was the
/// last, not repeated: `control::survey`'s searching.rs; the one wrong
/// and not flagged then, start 985, 11 mm off with its
/// heading 6.3 degrees off, vouched for by the refinement. 976 and 1,
/// 762 flagged, 95th percentile 42.9 s, before a view the next repeats
/// counted once among the views searched, `config::refine::REPEAT_DEG`;
/// 972 and 0,
/// 797 flagged, 4 failed, 95th percentile 51.6 s, before a search read the
/// last `config::refine::SEARCH_VIEWS` views and the refinement weighed
/// the last `REFINE_VIEWS`; 968 and 0, 9 failed, before a search of all the views that
/// found nothing within `config::refine::LAST_VIEWS_STEPS` gave way to the
/// last `FEW_VIEWS`; 959 and 0, 814 steerable, 95th percentile 38.4 s, before a poor
/// refined fit made the search go on, `config::refine::SEARCH_ON_STEPS`;
/// 948 and 0 before the refined place was the one reported,
/// `Fix::refine_to`: the estimator reported the search's heaviest place
/// while the line printed the refined pose; 939 and 0, 18 failed, with a 60 s time limit,
/// `config::locate::TIME_LIMIT_MS`; 933 and 2, 808
/// flagged, before the simulated chip measured over its budget and the
/// firmware read each reading a reading's age before its tick,
/// `config::lidar::READING_AGE_US`; 924 and 5, 723
/// flagged, before a turn between views ended when the compass showed its
/// angle, `control::survey`'s turning.rs: timed by the lab's turn line, a
/// turn overshot or fell short where each direction turns off it; 893
/// and 17, 745 flagged, before each lidar's reading in a turn kept its own tick,
/// `model::locate::turns::TurnSample`: a pair's second reading sat up to
/// a lidar period early; 831 and 19, 796 flagged, before the refinement's readings
/// spread with their range, its glancing ones said nothing and each view's
/// compass took the compass's own spread: `config::refine::
/// INCIDENCE_SPREAD`, `MAX_INCIDENCE_DEG`, `VIEW_MIX`; 823 and 18 before
/// the survey asked its earlier views about the left, `control::survey::
/// room::left_clear`.)
const HARD_REFINED: (usize, usize) = (984, 2);

/// Measured on the held-out sets (`HELD_OUT`), refined: (right, wrong and
/// not flagged); also 1 and 1 failed (out of time), 824 and 806
/// flagged, 810 and 829 steerable, time median 17.7 and 16.6 s, 95th
/// percentile 78.6 and 77.1 s (970 / 2 and 981 / 1, 1 and 1 failed,
/// 76.3 and 75.9 s, before a poor fit looked again from elsewhere,
/// `config::refine::SECOND_LOOK_FIT`; 967 / 3 and 976 / 1, 829 flagged on set
/// A, 17.0 s, before each turn's pivot moved in the refinement's model,
/// `config::refine::PIVOT_MOVE_SIGMA_MM`; 971 / 2
/// and 982 / 1, 3 and 1 failed, 17.1 and 15.8 s, before the drive that
/// makes room ended at a wall ahead; 966 / 5 and 977 / 2, 767 and 755 flagged, 38.2 and
/// 32.7 s, before a fit dearer than `config::refine::SEARCH_ON_LIMIT`
/// made the search go on; 959 / 5 and 974 / 3, 37.7 and
/// 32.5 s, before the compass's bend, `config::refine::FIELD_SIGMA_DEG`,
/// chosen on both; 954 / 7 and 967 / 3, 43.0 and 33.1 s, before a far
/// pivot's wider view prior, chosen on set A and confirmed on B, since
/// replaced by the bend; 953, 4 failed, 47.0 s, and
/// 35.7 s before a search with no room to turn after it was the last,
/// not repeated: set A's start 861 searched its four views for 86 s,
/// found them ambiguous, had no room to turn and began the same search
/// again). The tuned set's figures are partly the choosing: every
/// constant of the survey and the refinement before the bend was kept or
/// dropped by its count there (and its starts were the ones studied),
/// and these sets measure what the same firmware does on power-ups
/// little of it was chosen by: 98.0 and 98.3 % right, 0.2 and 0.1 % wrong
/// and not flagged; the two fresh sets never used to choose: `FRESH`,
/// `HARD_FRESH`. (Before the far pivot's wider view prior: the tuned set's
/// starts with the held-out seeds measured 973 and 974;
/// `config::refine::REPEAT_DEG`'s repeats
/// counted once: 953 and 967 against 954 and 966 without (the three
/// starts it mends are the tuned set's).)
/// Asserted: no worse than that.
const HARD_HELD_OUT: [(usize, usize); 2] = [(980, 2), (983, 1)];

/// Measured on the fresh sets (`FRESH`), refined: (right, wrong and not
/// flagged); also 0 and 2 failed (980 / 1 and 978 / 0 before a poor fit
/// looked again from elsewhere, `config::refine::SECOND_LOOK_FIT`).
/// Pooled with the tuned and held-out sets: 4,907 of 5,000 right,
/// 98.14 % (95 % interval 97.73 to 98.48 %), 6 wrong and not flagged
/// (0.12 %); 4,888 (97.76 %) before. Asserted: no worse than that.
const HARD_FRESH: [(usize, usize); 2] = [(982, 1), (978, 0)];

/// Measured in the hard world, 1,000 power-ups unrefined: (right, wrong
/// and not flagged). Also: 789 reported ambiguous or uncertain, 8 failed
/// (nothing fits, or out of time), 842 certain enough for goto a second
/// later; time median 10.3 s, 95th percentile 31.0 s. 30 s in release.
/// (383 right, 788 flagged, 818 steerable, 10.5 s, before the drive that
/// makes room ended at a wall ahead, `control::survey::room::drive_ends`;
/// 9 failed, 95th percentile 32.1 s, before a search with no room to
/// turn after it was the last, not repeated; 378 right, 18 failed, with a 60 s time limit. Before the chip's measurement window and the reading's age: 372 right,
/// 119 wrong and not flagged. Before a turn between views ended when the compass showed its angle:
/// 340 right, 171 wrong and not flagged, 711 ambiguous or uncertain, 19
/// failed, median 10.1 s. Before the survey asked its earlier views about the left, which cuts
/// more surveys short, `control::survey::room::left_clear`: 347 right, 149
/// wrong and not flagged, 732 ambiguous or uncertain, 26 failed, median
/// 10.6 s. Before the search guessed the beam's axis at the compass's heading when
/// nothing fits the cone's nearest point: 302 right, 149 wrong and not
/// flagged, 665 ambiguous or uncertain, 93 failed, 812 steerable, 95th
/// percentile 60.1 s, the time limit. Before the survey made room to turn: 294 right, 252 wrong and not
/// flagged, 532 ambiguous or uncertain, 73 failed, 891 steerable, median
/// 7.5 s. With the pivot at the axle only: 43 right, 759 wrong and not
/// flagged, 198 failed, median 8.4 s.)
const HARD_POWER_UP: (usize, usize) = (372, 118);

/// After the fix the estimator tracks: a `goto` from the located pose gets
/// where it was sent (on the truth), and `reset` finds the robot again
/// after it was carried elsewhere.
#[test]
fn after_the_fix_goto_works_and_reset_relocates() {
    let start = PoseF64::new(300.0, 250.0, 0.5);
    let mut robot = SimRobot::new(SimConfig { start, seed: 5, ..SimConfig::default() });
    robot.send("rate 0");
    for _ in 0..1_000 {
        robot.tick();
    }
    let lines = robot.take_output();
    assert!(lines.iter().any(|l| l.starts_with("# located ")), "{lines:?}");
    robot.send("goto 500 300");
    for _ in 0..800 {
        robot.tick();
    }
    let t = robot.truth();
    assert!((t.x - 500.0).hypot(t.y - 300.0) <= 20.0, "the goto ended at {t:?}: {:?}", robot.take_output());
    // carried to the other end of the box, turned
    robot.set_truth(PoseF64::new(650.0, 120.0, 4.0));
    robot.take_output();
    robot.send("reset");
    for _ in 0..1_000 {
        robot.tick();
    }
    let lines = robot.take_output();
    assert!(lines.iter().any(|l| l.starts_with("# located ")), "{lines:?}");
    let s = robot.sample();
    assert!(s.truth.distance(&s.estimate) <= 30.0, "{lines:?} {s:?}");
}

/// A `goto` on an estimate too uncertain to steer by finds the pose first,
/// then goes; in a mission too (the cable pulled: nobody to type `pose`).
#[test]
fn a_goto_when_lost_locates_first_then_goes() {
    let start = PoseF64::new(300.0, 250.0, 0.5);
    let mut robot = SimRobot::new(SimConfig { start, seed: 5, locate_at_power_up: false, ..SimConfig::default() });
    robot.send("rate 0");
    // told a wrong pose: 100 mm uncertain, and 200 mm off
    robot.send("pose 500 150 30");
    robot.send("goto 200 300");
    let mut lines = robot.take_output();
    assert_eq!(lines[2], "# estimate too uncertain to steer by: locating first", "{lines:?}");
    for _ in 0..2_000 {
        robot.tick();
        lines.extend(robot.take_output());
    }
    let located = lines.iter().position(|l| l.starts_with("# located ")).expect("a fix");
    assert_eq!(lines[located + 1], "# ok goto 200 300", "{lines:?}");
    assert!(lines.iter().any(|l| l.starts_with("# done at")), "{lines:?}");
    let t = robot.truth();
    assert!((t.x - 200.0).hypot(t.y - 300.0) <= 20.0, "ended at {t:?}");
}

/// The loop hands the survey the lidars' readings while it turns between
/// views (issue #29): each turn of a power-up keeps, at the tick of the
/// turn each came, every reading the loop took while the body turned (the
/// same readings handed to a `Turn` directly, ended after the ticks the
/// loop drove the turn), and the turns kept stay one fewer than the views.
#[test]
fn the_survey_keeps_the_readings_the_loop_takes_while_turning() {
    use paperbot::config::locate::{TURN_DEG, TURN_MRAD_S};
    use paperbot::config::timing::LOOP_HZ;
    use paperbot::model::lidar::Range;
    use paperbot::model::locate::turns::Turn;
    use paperbot::model::measurement::LidarId;
    use paperbot::model::Motion;
    // a step's ticks: 45 degrees at 2.4 rad/s, 327 ms
    let step_ticks = (TURN_DEG * 17_453 / TURN_MRAD_S) as u32 * LOOP_HZ / 1000;
    assert_eq!(step_ticks, 32);

    let mut robot = SimRobot::new(SimConfig::default());
    robot.send("rate 0");
    let sampled =
        |r: &SimRobot| (r.controller().front_health().last_sample_us(), r.controller().right_health().last_sample_us());
    let mut last = sampled(&robot);
    // the turn under way as the loop drove it: its way, the ticks it has
    // turned, the readings (lidar, tick of the turn, distance)
    type Reading = (LidarId, u16, paperbot::math::Length);
    let mut under_way: Option<(bool, u16, Vec<Reading>)> = None;
    let mut expected: Vec<Turn> = vec![];
    let mut most = 0;
    for _ in 0..3_000 {
        robot.tick();
        if robot.take_output().iter().any(|l| l.starts_with("# locate")) {
            break;
        }
        let c = robot.controller();
        // this tick's new readings, handed to the survey before its tick
        let now = sampled(&robot);
        let fresh =
            [(now.0 != last.0, LidarId::Front, c.last_front()), (now.1 != last.1, LidarId::Right, c.last_right())]
                .into_iter()
                .filter_map(|(new, id, s)| match s?.range {
                    Range::Target(d) if new => Some((id, d)),
                    _ => None,
                });
        last = now;
        match (c.applied().motion, &mut under_way) {
            // a tick the survey turned: the readings came at the ticks it
            // had turned before
            (Motion::Turn(rate), turn) => {
                let (_, ticks, readings) = turn.get_or_insert((rate.to_mrad_s() > 0, 0, vec![]));
                readings.extend(fresh.map(|(id, d)| (id, *ticks, d)));
                *ticks += 1;
            }
            // the tick after the turn's last: its readings came at the end
            (_, turn @ Some(_)) => {
                let (clockwise, ticks, mut readings) = turn.take().unwrap();
                readings.extend(fresh.map(|(id, d)| (id, ticks, d)));
                // (a turn ends when the compass shows its steps: the
                // nearest whole number of the line's ticks)
                let steps = (u32::from(ticks) + step_ticks / 2) / step_ticks;
                let mut t = Turn::new(clockwise, steps.max(1) as u8);
                for (id, tick, d) in readings {
                    t.push(id, tick, d);
                }
                t.end(ticks);
                expected.push(t);
            }
            _ => {}
        }
        let survey = c.survey();
        assert_eq!(survey.turns().len() + 1, survey.views().len().max(1));
        assert_eq!(survey.turns(), &expected[..survey.turns().len()]);
        most = most.max(survey.turns().len());
    }
    assert!(most >= 3, "{most} turns kept");
    // one step each, ended by the compass within 15 % of the line's ticks
    // (the lab world turns on its line, each trial off it by the lab's
    // spread, its compass off by a couple of degrees), about a pair every
    // 3.3 ticks (10 each here)
    for t in &expected {
        let ticks = u32::from(t.ticks);
        assert!(ticks * 100 >= step_ticks * 85 && ticks * 100 <= step_ticks * 115, "{ticks} ticks");
        assert!((8..=12).contains(&t.samples().len()), "{t:?}");
    }
}
