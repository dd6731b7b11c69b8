//! Localization from no prior pose (`model::locate`): from random poses in
//! the box, with readings from the simulator's sensor models (the lab's
//! world: the lidars' cones, their noise and glancing failures, the
//! compass's noise and disturbance; the hard world: a robot drawn per start,
//! `sim::realism::Realism::HARD`), the search finds the pose; the places
//! it returns ([`Fix::clusters`]); and what refining its fix with every
//! reading of the survey would give (`refine.rs`).

use super::refine::{refine, TurnSamples, EVALUATIONS};
use crate::common;
use common::rng::{random_pose_in_box, Rng};
use paperbot::config;
use paperbot::control::survey::room::{positioning_mm, room_to_turn, Ahead};
use paperbot::math::{Angle, Length};
use paperbot::model::locate::refine::Refine;
use paperbot::model::locate::turns::Turn;
use paperbot::model::locate::{locate, locate_with_spot_share, Fix, Readings, Search, MAX_VIEWS};
use paperbot::model::measurement::Arena;
use paperbot::model::LidarModel;
use paperbot::sim::arena::Arena as SimArena;
use paperbot::sim::body::{advance, wrap_pi, Kinematics, MotionF64, PoseF64};
use paperbot::sim::drawn::Drawn;
use paperbot::sim::realism::{Realism, Trial};
use paperbot::sim::robot::{body_fits, lidar_truth};
use std::sync::atomic::Ordering;

/// The world a start is in: its realism and what the start drew from it.
pub(crate) struct World {
    pub(crate) realism: Realism,
    pub(crate) drawn: Drawn,
}

impl World {
    /// The lab's world (the compass pattern's phase drawn from `rng`).
    fn lab(rng: &mut Rng) -> World {
        World { realism: Realism::LAB, drawn: Drawn::draw(0, &Realism::LAB, rng.range_f64(0.0, std::f64::consts::TAU)) }
    }
    /// The lab's world with the hard world's thin beam (a range from the
    /// beam's axis, not the cone's nearest wall point).
    fn thin_beam(rng: &mut Rng) -> World {
        let realism = Realism { cone_deg: Realism::HARD.cone_deg, ..Realism::LAB };
        World { realism, drawn: Drawn::draw(0, &realism, rng.range_f64(0.0, std::f64::consts::TAU)) }
    }
    /// The hard world, a robot drawn for start `start`.
    fn hard(start: u64, rng: &mut Rng) -> World {
        let phase = rng.range_f64(0.0, std::f64::consts::TAU);
        World { realism: Realism::HARD, drawn: Drawn::draw(start, &Realism::HARD, phase) }
    }
}

/// One averaged lidar reading as the firmware sees it (the model output of
/// the mean of `n` raw readings), or `None` when the reading failed.
fn lidar(
    w: &World,
    p: &PoseF64,
    which: paperbot::model::measurement::LidarId,
    model: &LidarModel,
    rng: &mut Rng,
) -> Option<Length> {
    let n = config::locate::LIDAR_READINGS;
    let mean = if w.realism == Realism::LAB {
        // the lab's world: one draw of the geometry, the sensor's noise averaged
        let d = lidar_truth(&SimArena::default(), &w.realism, p, &which.mount(), rng)?;
        (0..n).map(|_| d + rng.gauss(config::sim::LIDAR_NOISE_MM)).sum::<f64>() / f64::from(n)
    } else {
        // the hard world: each reading its own (spurious echoes, mixed
        // returns, incidence noise), the median of those that came back,
        // as the firmware takes a view
        let mut got: Vec<f64> = vec![];
        for _ in 0..n {
            if let Some(d) = lidar_truth(&SimArena::default(), &w.realism, p, &which.mount(), rng) {
                got.push(d + rng.gauss(config::sim::LIDAR_NOISE_MM));
            }
        }
        got.sort_by(f64::total_cmp);
        *got.get(got.len().checked_sub(1)? / 2)?
    };
    let raw = model.reading_for(Length::from_mm_f64(mean))?;
    model.range(raw).distance()
}

/// One view as the firmware takes it at `truth`: the averaged compass
/// heading (the floor's disturbance at `phase`, the averaged noise) and the
/// two lidars.
fn view(w: &World, truth: &PoseF64, rng: &mut Rng) -> Readings {
    use paperbot::model::measurement::LidarId;
    let compass_err = w.drawn.compass_bias(&SimArena::default(), truth.x, truth.y, &w.realism)
        + rng.gauss(config::sim::COMPASS_NOISE_DEG / f64::from(config::locate::COMPASS_READINGS).sqrt()).to_radians();
    Readings {
        heading: Angle::from_radians_f64(truth.theta + compass_err),
        front: lidar(w, truth, LidarId::Front, &config::lidar::FRONT, rng),
        right: lidar(w, truth, LidarId::Right, &config::lidar::RIGHT, rng),
    }
}

/// A turn in place of about `degrees` (clockwise when positive) as the
/// realistic simulator drives it (`sim::robot::SimRobot::tick`): the loop's
/// ticks at the cw or ccw rate, the trial's speed factor, per-tick noise, a
/// pivot behind the axle, and the body held where it would leave the box;
/// in the hard world the run's turn factor and pivot too.
fn turn(w: &World, start: &PoseF64, degrees: f64, rng: &mut Rng) -> PoseF64 {
    turn_read(w, start, degrees, rng, None)
}

/// [`turn`], the lidars read while turning into `read` (the readings from
/// their own random stream: the turn's draws stay what they were).
fn turn_read(
    w: &World,
    start: &PoseF64,
    degrees: f64,
    rng: &mut Rng,
    mut read: Option<(&mut TurnSamples, &mut Rng)>,
) -> PoseF64 {
    let realism = w.realism;
    let arena = SimArena::default();
    let rate = 2.5f64.copysign(degrees); // rad/s, the `cw` of the lab's scripts
    let dt = 1.0 / f64::from(config::timing::LOOP_HZ);
    let ticks = (degrees.to_radians() / rate / dt).round() as u32;
    let motion = MotionF64::Turn(rate);
    let trial = Trial::NONE.for_motion(motion, &realism, rng);
    let d = config::geometry::ROTATION_TO_REFERENCE.to_mm_f64() + trial.pivot_behind_mm + w.drawn.pivot_offset_mm;
    let scale = w.drawn.turn_factor(degrees > 0.0, 0.0, &realism);
    let mut p = *start;
    for _ in 0..ticks {
        let rate = rate * scale * trial.speed_factor * (1.0 + rng.gauss(config::sim::TURN_NOISE));
        let next = advance(&p, MotionF64::Turn(rate), dt, Kinematics::Rigid, d);
        if body_fits(&arena, &realism, &next) {
            p = next;
        }
        if let Some((samples, rng)) = read.as_mut() {
            samples.tick(w, &p, ticks, degrees > 0.0, rng);
        }
    }
    p
}

/// A straight drive of about `mm` (back when negative) at the survey's
/// speed, the run's speed scale, the body held where it would leave the box.
fn drive(w: &World, start: &PoseF64, mm: f64, rng: &mut Rng) -> PoseF64 {
    let speed = f64::from(config::locate::POSITION_MM_S).copysign(mm);
    let dt = 1.0 / f64::from(config::timing::LOOP_HZ);
    let ticks = (mm.abs() / speed.abs() / dt).round() as u32;
    let mut p = *start;
    for _ in 0..ticks {
        let v = speed * w.drawn.speed_scale * (1.0 + rng.gauss(config::sim::SPEED_NOISE));
        let next = advance(&p, MotionF64::Straight(v), dt, Kinematics::Rigid, 0.0);
        if body_fits(&SimArena::default(), &w.realism, &next) {
            p = next;
        }
    }
    p
}

/// How a fix compares with the truth.
#[derive(Default)]
struct Tally {
    right: usize,
    ambiguous: usize,
    ambiguous_right: usize,
    /// The truth is one of the fix's clusters (30 mm, 5 degrees): a tracker
    /// seeded from them holds it.
    among_clusters: usize,
    /// Fixes with more than one cluster.
    several: usize,
    /// Within 30 mm whatever the heading.
    position_right: usize,
    /// Reported uncertain (one place, but the search cannot vouch for it).
    uncertain: usize,
    failed: usize,
    wrong_unflagged: Vec<(f64, f64, PoseF64)>,
}

/// Within 30 mm and 5 degrees: the "right".
fn close(got: &PoseF64, truth: &PoseF64) -> bool {
    got.distance(truth) <= 30.0 && got.heading_error(truth).to_degrees().abs() <= 5.0
}

impl Tally {
    fn add(&mut self, fix: Option<Fix>, truth: &PoseF64) {
        let Some(fix) = fix else {
            self.failed += 1;
            return;
        };
        let got = PoseF64::from_pose(&fix.pose);
        let right = close(&got, truth);
        self.right += usize::from(right);
        self.ambiguous += usize::from(fix.ambiguous);
        self.ambiguous_right += usize::from(fix.ambiguous && right);
        self.among_clusters +=
            usize::from(fix.clusters().iter().any(|c| close(&PoseF64::from_pose(&fix.pose_of(c)), truth)));
        self.several += usize::from(fix.clusters().len() > 1);
        self.position_right += usize::from(got.distance(truth) <= 30.0);
        self.uncertain += usize::from(fix.untrusted && !fix.ambiguous);
        if !right && !fix.ambiguous && !fix.untrusted {
            let sigma = fix.sigma_x.to_mm_f64().hypot(fix.sigma_y.to_mm_f64());
            self.wrong_unflagged.push((got.distance(truth), sigma, *truth));
        }
    }

    fn print(&self, what: &str, starts: usize) {
        println!(
            "{what}: {} of {starts} right (30 mm, 5 deg); {} reported ambiguous ({} of them right anyway); \
             {} reported uncertain; {} found nothing; {} wrong and not flagged; {} with several clusters; the truth among the clusters in {}; \
             {} within 30 mm whatever the heading",
            self.right,
            self.ambiguous,
            self.ambiguous_right,
            self.uncertain,
            self.failed,
            self.wrong_unflagged.len(),
            self.several,
            self.among_clusters,
            self.position_right,
        );
        for (d, sigma, t) in self.wrong_unflagged.iter().take(5) {
            println!("  wrong, not flagged: off {d:.0} mm (sigma {sigma:.0} mm) at {t:?}");
        }
    }
}

/// Why fixes are wrong: the heading only (the position within 30 mm), the
/// position only, or both; and the compass's bias at the views (its mean
/// over the views, and its spread between them: a common bias is what a
/// search over compass offsets would model, the spread is not).
#[derive(Default)]
struct Why {
    heading_only: usize,
    position_only: usize,
    both: usize,
    /// (mean |bias|, bias spread) over the right fixes and the wrong ones,
    /// degrees.
    right_bias: Vec<(f64, f64)>,
    wrong_bias: Vec<(f64, f64)>,
}

impl Why {
    fn add(&mut self, fix: Option<&Fix>, truth: &PoseF64, biases: &[f64]) {
        let Some(fix) = fix else { return };
        let got = PoseF64::from_pose(&fix.pose);
        let degs: Vec<f64> = biases.iter().map(|b| b.to_degrees()).collect();
        let mean = degs.iter().sum::<f64>() / degs.len() as f64;
        let spread = degs.iter().copied().fold(f64::MIN, f64::max) - degs.iter().copied().fold(f64::MAX, f64::min);
        let (pos, head) = (got.distance(truth) <= 30.0, got.heading_error(truth).to_degrees().abs() <= 5.0);
        match (pos, head) {
            (true, true) => self.right_bias.push((mean.abs(), spread)),
            (true, false) => self.heading_only += 1,
            (false, true) => self.position_only += 1,
            (false, false) => self.both += 1,
        }
        if !(pos && head) {
            self.wrong_bias.push((mean.abs(), spread));
        }
    }

    fn print(&self) {
        let avg = |v: &[(f64, f64)]| {
            let n = v.len().max(1) as f64;
            (v.iter().map(|b| b.0).sum::<f64>() / n, v.iter().map(|b| b.1).sum::<f64>() / n)
        };
        let (r, w) = (avg(&self.right_bias), avg(&self.wrong_bias));
        println!(
            "  fixes found but wrong: {} the heading only, {} the position only, {} both; the compass's bias at the \
             views (mean |bias|, spread between views): right fixes {:.1} / {:.1} deg, wrong {:.1} / {:.1} deg",
            self.heading_only, self.position_only, self.both, r.0, r.1, w.0, w.1
        );
    }
}

/// The procedure from `starts` random starts in the world `world` makes
/// for each: a view, then a turn of about 45 degrees clockwise and another
/// view (counter-clockwise when the compass says the turn did not happen),
/// at least `config::locate::MIN_VIEWS` (four: two can agree on a wrong
/// pose, and the turn's pivot is not known), and more while the fix is
/// ambiguous, up to MAX_VIEWS. The tallies after two views and at
/// the end.
fn procedure(starts: usize, world: impl Fn(u64, &mut Rng) -> World) -> (Tally, Tally) {
    procedure_reading_the_spot(starts, world, 0)
}

/// [`procedure`] with the search reading each range `share` (Q30) of the
/// way from the cone's nearest wall point to the beam's axis.
fn procedure_reading_the_spot(starts: usize, world: impl Fn(u64, &mut Rng) -> World, share: i32) -> (Tally, Tally) {
    procedure_refined(starts, world, share, None, None)
}

/// [`procedure_reading_the_spot`]; with `refined`, the survey makes room
/// to turn as the firmware's does (`control::survey::room`: a drive before
/// the first view, and a turn only where the last view shows room for it,
/// the other way if not, no more views if neither way has room), and each
/// fix is also refined with every reading of its survey, the turns' too
/// (`refine.rs`), and tallied there.
fn procedure_refined(
    starts: usize,
    world: impl Fn(u64, &mut Rng) -> World,
    share: i32,
    mut refined: Option<&mut Tally>,
    mut robot: Option<(&mut Tally, &mut u64)>,
) -> (Tally, Tally) {
    let mut rng = Rng::new(2315);
    let (mut two, mut done) = (Tally::default(), Tally::default());
    let mut views_used = [0usize; MAX_VIEWS + 1];
    let mut why = Why::default();
    for start in 0..starts {
        let mut truth = random_pose_in_box(&mut rng);
        let w = world(start as u64, &mut rng);
        let make_room = refined.is_some();
        if make_room {
            // room to turn before the first view (its own random stream)
            let mut room_rng = Rng::new(7_000 + start as u64);
            let first = view(&w, &truth, &mut room_rng);
            let mm = positioning_mm(first.front);
            truth = drive(&w, &truth, f64::from(mm), &mut room_rng);
        }
        let mut views = vec![view(&w, &truth, &mut rng)];
        let mut biases = vec![wrap_pi(views[0].heading.to_radians_f64() - truth.theta)];
        let mut degrees = 45.0;
        // the turns' readings, from a stream of their own
        let mut turns_rng = Rng::new(9_000 + start as u64);
        let mut turns = vec![];
        let fix = loop {
            if make_room {
                let last = views[views.len() - 1];
                let clockwise = degrees > 0.0;
                if !room_to_turn(&last, clockwise, Ahead::Square) {
                    if room_to_turn(&last, !clockwise, Ahead::Square) {
                        degrees = -degrees;
                    } else {
                        break locate_with_spot_share(&Arena::DEFAULT, &views, share).ok();
                    }
                }
            }
            let mut samples = TurnSamples::from(&truth);
            let read = refined.is_some().then_some((&mut samples, &mut turns_rng));
            truth = turn_read(&w, &truth, degrees, &mut rng, read);
            turns.push(samples);
            views.push(view(&w, &truth, &mut rng));
            biases.push(wrap_pi(views[views.len() - 1].heading.to_radians_f64() - truth.theta));
            // a body against a wall may not turn that way: the compass says
            // so, and the next turns go the other way
            if let [.., a, b] = views.as_slice() {
                if b.heading.wrapping_sub(a.heading).to_signed_millidegrees().abs() < 20_000 {
                    degrees = -degrees;
                }
            }
            let fix = locate_with_spot_share(&Arena::DEFAULT, &views, share).ok();
            if views.len() == 2 {
                two.add(fix, &truth);
            }
            if views.len() == MAX_VIEWS
                || (views.len() >= config::locate::MIN_VIEWS && fix.is_some_and(|f| !f.ambiguous))
            {
                break fix;
            }
        };
        views_used[views.len()] += 1;
        why.add(fix.as_ref(), &truth, &biases);
        if let Some(tally) = refined.as_deref_mut() {
            // the search's flags kept (its places apart), the refinement's added
            let better = fix.map(|mut f| {
                if let Some(r) = refine(&views, &turns, &f) {
                    f.pose = r.pose.to_pose();
                    f.untrusted |= !r.vouched;
                }
                f
            });
            tally.add(better, &truth);
        }
        if let Some((tally, passes)) = robot.as_mut() {
            // the robot's refinement (fixed point), from the same readings
            let turns: Vec<Turn> = turns.iter().map(TurnSamples::to_turn).collect();
            let better = fix.map(|f| {
                let mut r = Refine::new(f, &views, &turns);
                while r.step(&Arena::DEFAULT, &views, &turns).is_none() {
                    **passes += 1;
                }
                r.refined_fix()
            });
            tally.add(better, &truth);
        }
        done.add(fix, &truth);
    }
    println!("  views taken (views, starts): {:?}", views_used.iter().enumerate().skip(3).collect::<Vec<_>>());
    why.print();
    (two, done)
}

/// The lab's world: the bar the firmware's procedure was built to (95 %
/// right, at most 1 % wrong and not flagged). Measured: 991 right, 12
/// reported ambiguous, 4 uncertain, none wrong and not flagged (992, 9, 1
/// from three views before the search tried the turn's pivot off the
/// axle; 989, 14, 2 from three views with it).
#[test]
fn views_turned_in_place_find_the_pose() {
    let starts = 1_000;
    let (two, done) = procedure(starts, |_, rng| World::lab(rng));
    two.print("lab world: locate, two views 45 degrees apart", starts);
    done.print("lab world: locate, four views and more while ambiguous", starts);
    // Turning one way only leaves about 6 % ambiguous: a body against a
    // wall that cannot turn takes the same view again.
    assert!(done.right * 100 >= starts * 95, "{} of {starts}", done.right);
    assert!(done.wrong_unflagged.len() * 100 <= starts, "{} wrong fixes not flagged", done.wrong_unflagged.len());
}

/// A search that reads the ranges where the estimator learned they come
/// from (`Search::with_spot_share`): in the lab's world with the thin beam,
/// reading them as the axis's finds the pose from more starts than as the
/// cone's nearest point, and leaves no more wrong and not flagged.
/// Measured, 300 starts: 295 right and 2 wrong and not flagged reading
/// the axis; 249 and 23 reading the cone's nearest point, 245 of those
/// reported uncertain, most found by guessing the axis when nothing fit
/// (135, 20 and 30 finding nothing before that guess). (At power-up the share is not learned: in
/// the hard world, reading every range as the axis's took 158 of 200 starts
/// within 30 mm instead of 126, but 84 right instead of 75, the compass's
/// bias the heading's error, and 83 wrong and not flagged instead of 54.)
#[test]
fn a_search_reading_the_learned_spot_finds_the_pose_from_a_thin_beam() {
    let starts = 300;
    let (_, cone) = procedure_reading_the_spot(starts, |_, rng| World::thin_beam(rng), 0);
    let (_, axis) = procedure_reading_the_spot(starts, |_, rng| World::thin_beam(rng), 1 << 30);
    cone.print("thin beam, the search reading the cone's nearest point", starts);
    axis.print("thin beam, the search reading the axis (a learned share of 1)", starts);
    assert!(axis.right >= cone.right + starts / 20, "{} against {}", axis.right, cone.right);
    assert!(axis.wrong_unflagged.len() <= cone.wrong_unflagged.len());
}

/// The hard world (a robot drawn per start, `Realism::HARD`): issue #29's
/// bar is right >= 98 % and wrong and not flagged <= 0.2 %. Today's search
/// does not meet it. It tries the turn's pivot behind the axle at each
/// grid point (`config::locate::PIVOTS_BEHIND_AXLE_MM`), but takes each
/// view's heading from the compass, which the hard world biases by up to
/// 12 to 20 degrees and by 5 to 8 degrees between the views of one start
/// (at half the starts the last view's compass is more than 5 degrees off,
/// and the fix's heading is that view's). A fix found only at a heading
/// off the compass's, leaving two readings unexplained, or one on a
/// sliver of the box, or reading the beam's axis as a guess, is reported
/// uncertain (`Fix::untrusted`). Measured, 1,000 starts, four views and
/// more: 361 right, 6 reported ambiguous, 573 uncertain, 6 found nothing,
/// 255 wrong and not flagged (644 within 30 mm whatever the heading);
/// before the axis's guess 316, 5, 544, 13, 277 (607); from three views with the pivot at the
/// axle only (main before): 65 right, 825 wrong and not flagged, 140
/// within 30 mm. It prints why the fixes found are wrong (heading,
/// position, both) and the compass's bias at the views, its mean and its
/// spread between them (`HARD_STARTS=200` for fewer starts). Asserted: no
/// worse than measured; the bar is printed, advisory. Ignored for
/// its time (30 s in release):
/// `cargo test --release --test localization locate:: -- --ignored --nocapture`.
#[test]
#[ignore = "30 s in release; prints the hard world's figures (issue #29's bar not met yet)"]
fn views_turned_in_place_in_the_hard_world() {
    let starts = std::env::var("HARD_STARTS").ok().and_then(|s| s.parse().ok()).unwrap_or(1_000);
    let (two, done) = procedure(starts, World::hard);
    two.print("hard world: locate, two views 45 degrees apart", starts);
    done.print("hard world: locate, four views and more while ambiguous", starts);
    let bar = done.right * 100 >= starts * 98 && done.wrong_unflagged.len() * 1000 <= starts * 2;
    println!(
        "hard world: issue #29's bar (right >= 98 %, wrong and not flagged <= 0.2 %) {}",
        if bar { "met" } else { "NOT met (advisory)" }
    );
    assert!(done.right >= HARD_RIGHT, "{} of {starts}", done.right);
    assert!(
        done.wrong_unflagged.len() <= HARD_WRONG_UNFLAGGED,
        "{} wrong fixes not flagged",
        done.wrong_unflagged.len()
    );
}

/// The same surveys' fixes refined with every reading the survey saw, the
/// turns' too (`refine.rs`: one model of the turn about a fixed pivot, each
/// view's heading its own, the compass's bias a mixture of the lab's and a
/// disturbed floor's): an f64 reference for a step the firmware does not
/// take yet. The surveys make room to turn as the firmware's does
/// ([`procedure_refined`]); a refined fix keeps the search's flags and adds
/// the refinement's (`Refined::vouched`). Measured, 300 starts each: the
/// hard world 113 right and 59 wrong and not flagged from the search, 274
/// and 3 refined (1,000 starts: 368 and 170, 912 and 7; 785 reported
/// uncertain against 688; 969 within 30 mm whatever the heading); the
/// lab's 292 and 1, 294 and 0 (1,000: 984 and 2, 989 and 1). Without
/// making room the lab's refined fixes were worse than its search's (991
/// and 0, 985 and 9): turns blocked at a wall do not turn evenly.
/// Asserted: the refinement at least doubles the hard world's right
/// fixes and halves its wrong and not flagged, and the lab's are no worse.
/// It does not meet issue #29's bar (docs/simulator.md, "Refining the
/// fix"). Ignored for its time (45 s in release; `REFINE_STARTS` for more
/// or fewer starts).
#[test]
#[ignore = "a minute in release; prints what refining the fix with every reading would give"]
fn the_fix_refined_with_every_reading() {
    let starts = std::env::var("REFINE_STARTS").ok().and_then(|s| s.parse().ok()).unwrap_or(300);
    for (name, hard) in [("hard", true), ("lab", false)] {
        let mut refined = Tally::default();
        let world = |start: u64, rng: &mut Rng| if hard { World::hard(start, rng) } else { World::lab(rng) };
        let (mut robot, mut passes) = (Tally::default(), 0u64);
        let before = EVALUATIONS.load(Ordering::Relaxed);
        let (_, searched) = procedure_refined(starts, world, 0, Some(&mut refined), Some((&mut robot, &mut passes)));
        let per_fix = (EVALUATIONS.load(Ordering::Relaxed) - before) / starts.max(1) as u64;
        println!("{name} world: the refinement evaluated the lidar model {per_fix} times a start");
        println!("{name} world: the robot's refinement took {} passes a start", passes / starts.max(1) as u64);
        searched.print(&format!("{name} world: the search's fixes"), starts);
        refined.print(&format!("{name} world: the fixes refined with every reading"), starts);
        robot.print(&format!("{name} world: the fixes refined by the robot's fit (fixed point)"), starts);
        let (was_right, was_wrong) = (searched.right, searched.wrong_unflagged.len());
        // the reference and the robot's fit alike
        for tally in [&refined, &robot] {
            let (right, wrong) = (tally.right, tally.wrong_unflagged.len());
            if hard {
                assert!(
                    right >= 2 * was_right && 2 * wrong <= was_wrong,
                    "{right}, {wrong} against {was_right}, {was_wrong}"
                );
            } else {
                assert!(right >= was_right && wrong <= was_wrong, "{right}, {wrong} against {was_right}, {was_wrong}");
            }
        }
    }
}

/// Measured in the hard world, 1,000 starts (the test holds these levels).
const HARD_RIGHT: usize = 361;
const HARD_WRONG_UNFLAGGED: usize = 255;

#[test]
fn the_search_finds_the_pose_from_random_starts() {
    let mut rng = Rng::new(23);
    let starts = 1_000;
    let mut one = Tally::default();
    for _ in 0..starts {
        let truth = random_pose_in_box(&mut rng);
        let w = World::lab(&mut rng);
        let r = view(&w, &truth, &mut rng);
        one.add(locate(&Arena::DEFAULT, &[r]).ok(), &truth);
    }
    one.print("locate, one view", starts);
    // One snapshot (a heading and two ranges) is right from half the
    // starts (498 of 1,000; 369 before a point had to explain a reading and
    // the fix became the heaviest cluster): half the poses have both cones
    // on walls of one axis, and a reading that would be glancing at a point
    // says nothing about it (`config::locate::GLANCING_DEG`), so those fixes
    // are reported ambiguous (turning in place for more views, above,
    // settles them). What this asserts is that level and that wrong fixes
    // are almost always flagged.
    assert!(one.right * 100 >= starts * 45, "{} of {starts}", one.right);
    assert!(one.wrong_unflagged.len() * 100 <= starts * 3, "{} wrong fixes not flagged", one.wrong_unflagged.len());
}

/// Three views of a random start in the lab's world, turned 45 degrees
/// in place between them, the compass `off_deg` off.
fn three_lab_views(rng: &mut Rng, off_deg: f64) -> Vec<Readings> {
    let mut truth = random_pose_in_box(rng);
    let w = World::lab(rng);
    let mut views = vec![view(&w, &truth, rng)];
    for _ in 0..2 {
        truth = turn(&w, &truth, 45.0, rng);
        views.push(view(&w, &truth, rng));
    }
    for v in &mut views {
        v.heading = v.heading.wrapping_add(Angle::from_degrees_f64(off_deg));
    }
    views
}

/// The robot spreads the search over its ticks ([`Search::step`], a few
/// hundred view scores at a time): the same answer as the search run to the end,
/// from starts where the compass's heading fits and where it does not.
#[test]
fn the_search_a_slice_at_a_time_gives_the_same_fix() {
    let mut rng = Rng::new(7);
    let mut steps_seen = Vec::new();
    for start in 0..40 {
        // a compass 20 degrees off: passes at other headings
        let views = three_lab_views(&mut rng, if start % 4 == 0 { 20.0 } else { 0.0 });
        let whole = locate(&Arena::DEFAULT, &views);
        let mut search = Search::new(&views).unwrap();
        let mut steps = 0;
        let stepped = loop {
            steps += 1;
            if let Some(r) = search.step(&Arena::DEFAULT, 200) {
                break r;
            }
        };
        assert_eq!(stepped, whole, "start {start}");
        steps_seen.push(steps);
    }
    steps_seen.sort();
    println!("steps of 200 view scores: fewest {}, most {}", steps_seen[0], steps_seen[39]);
    // a pass over the box's 15,147 points scores each at least once
    assert!(steps_seen[39] > 2 * 76, "some searches needed several passes");
}

/// A search from a fix's own heading try finds that fix again, and one
/// from the next try finds another at a later try or nothing
/// (`Search::skip_to`: the survey searches on past a poor fit and finds
/// the cheapest again to report it); one that stops short of the fix's
/// heading (`Search::up_to`) finds nothing. Starts whose compass is 20 degrees
/// off, so fixes come at later tries too.
#[test]
fn a_search_from_a_fixs_heading_try_finds_it_again() {
    let mut rng = Rng::new(7);
    let (mut later, mut again) = (0, 0);
    for start in 0..30 {
        let views = three_lab_views(&mut rng, 20.0);
        let run_up_to = |heading_try: u8, steps: u8| {
            let mut search = Search::new(&views).unwrap();
            search.skip_to(heading_try);
            search.up_to(steps);
            search.finish(&Arena::DEFAULT)
        };
        let run = |heading_try: u8| run_up_to(heading_try, config::locate::HEADING_STEPS);
        let Ok(fix) = locate(&Arena::DEFAULT, &views) else { continue };
        let k = fix.heading_try();
        later += usize::from(k > 0);
        if k > 0 {
            // the headings before the fix's found nothing: up to them, nothing fits
            let before = (k - 1) / 2;
            assert_eq!(run_up_to(0, before), Err(paperbot::model::locate::LocateError::NothingFits), "start {start}");
        }
        assert_eq!(run(k), Ok(fix), "start {start}");
        again += 1;
        if let Ok(next) = run(k + 1) {
            assert!(next.heading_try() > k, "start {start}: {} after {k}", next.heading_try());
        }
    }
    assert!(again >= 25 && later >= 4, "{again} fixes, {later} at later tries");
}

/// A grid point where every reading would be glancing explains none of
/// them: no fit. A front reading farther than any wall of the box, at a
/// heading where the beam glances along the north wall from points near
/// it: before this rule those points fitted (their only reading said
/// nothing), now nothing does.
#[test]
fn a_point_whose_readings_all_glance_is_no_fit() {
    let r = Readings { heading: Angle::from_degrees_f64(80.0), front: Some(Length::from_mm(2_000)), right: None };
    assert_eq!(locate(&Arena::DEFAULT, &[r]), Err(paperbot::model::locate::LocateError::NothingFits));
    // the same heading with a reading the box explains still finds it
    let truth = PoseF64::new(380.0, 100.0, 80f64.to_radians());
    let front = paperbot::model::measurement::expected_lidar(
        &Arena::DEFAULT,
        &truth.to_pose(),
        paperbot::model::measurement::LidarId::Front,
    );
    let fix = locate(&Arena::DEFAULT, &[Readings { front, ..r }]).unwrap();
    assert!(fix.points > 0);
}

/// Places apart are clusters, heaviest first, the fix the heaviest (never
/// the mean of places apart) and flagged ambiguous; one place is one
/// cluster with all the weight, the fix as before. From 1,000 one-view
/// starts in the lab's world (one view leaves many places).
#[test]
fn places_apart_are_weighted_clusters_and_the_fix_is_never_their_mean() {
    let mut rng = Rng::new(23);
    let (mut several, mut one) = (0, 0);
    for _ in 0..1_000 {
        let truth = random_pose_in_box(&mut rng);
        let w = World::lab(&mut rng);
        let Ok(fix) = locate(&Arena::DEFAULT, &[view(&w, &truth, &mut rng)]) else { continue };
        let c = fix.clusters();
        assert!(!c.is_empty() && c.len() <= paperbot::model::locate::MAX_CLUSTERS);
        assert_eq!(fix.pose, fix.pose_of(&c[0]), "the fix is the heaviest place");
        assert!(c.windows(2).all(|p| p[0].weight >= p[1].weight && p[0].points >= p[1].points));
        assert!(c.iter().map(|k| k.weight).sum::<u32>() <= 65_536 + c.len() as u32);
        assert!(c.iter().map(|k| k.points).sum::<u32>() <= fix.points);
        if c.len() == 1 {
            one += 1;
            assert!(c[0].weight >= 65_535 && c[0].points == fix.points);
            assert_eq!((c[0].sigma_x, c[0].sigma_y), (fix.sigma_x, fix.sigma_y));
            continue;
        }
        several += 1;
        assert!(fix.ambiguous, "several places are ambiguous");
        // the estimator starts with one hypothesis per place, none their mean
        let mut est = paperbot::model::estimator::Estimator::new(fix.pose);
        est.start_at(&fix);
        let held: Vec<_> = est.hypotheses().map(|(p, _)| p).collect();
        assert_eq!(held.len(), c.len().min(paperbot::config::estimator::MAX_HYPOTHESES), "{c:?}");
        assert!(c.iter().all(|k| held.contains(&fix.pose_of(k))) || c.len() > held.len(), "{held:?}");
        assert_ne!(est.tracking(), paperbot::model::estimator::Tracking::Located, "{c:?}");
        // places apart: no two together within the ambiguous span (else
        // they would be one place)
        let span = f64::from(config::locate::AMBIGUOUS_SPAN_MM);
        for (i, a) in c.iter().enumerate() {
            for b in &c[i + 1..] {
                let (pa, pb) = (PoseF64::from_pose(&fix.pose_of(a)), PoseF64::from_pose(&fix.pose_of(b)));
                assert!((pa.x - pb.x).abs().max((pa.y - pb.y).abs()) > span / 4.0, "{a:?} {b:?}");
            }
        }
    }
    println!("one view: {one} fixes of one place, {several} of several");
    assert!(several > 50 && one > 500, "{several} {one}");
}

/// A fix refined to a place other than the search's heaviest
/// (`Fix::refine_to`, the refinement's pose) reports that place: it is the
/// first and heaviest cluster, at the refined pose, and the estimator
/// started at the fix reports it (before, the located line printed the
/// refined pose while the estimator reported the search's heaviest place:
/// 11 of 1,000 hard power-ups 60 to 290 mm off). A vouched refinement
/// cuts the other places' weights by its rival gap; one not vouched keeps
/// them, so the estimator stays ambiguous.
#[test]
fn a_refined_fix_reports_the_refined_place() {
    use paperbot::model::estimator::{Estimator, Tracking};
    use paperbot::model::locate::RIVAL_BITS;
    let mut rng = Rng::new(23);
    let mut tried = 0;
    for _ in 0..200 {
        let truth = random_pose_in_box(&mut rng);
        let w = World::lab(&mut rng);
        let Ok(fix) = locate(&Arena::DEFAULT, &[view(&w, &truth, &mut rng)]) else { continue };
        let c = fix.clusters().to_vec();
        if c.len() < 2 {
            continue;
        }
        tried += 1;
        // the refinement's pose: 4 mm from the lightest place, 2 degrees turned
        let last = c.len() - 1;
        let at = PoseF64::from_pose(&fix.pose_of(&c[last]));
        let refined = PoseF64::new(at.x + 4.0, at.y, at.theta + 2f64.to_radians()).to_pose();
        for vouched in [false, true] {
            let mut f = fix;
            f.refine_to(refined, vouched);
            let k = f.clusters();
            assert_eq!(f.pose, refined);
            assert_eq!(f.pose_of(&k[0]), refined, "the refined place first: {k:?}");
            assert_eq!(k[0].weight, c[0].weight, "with the heaviest's weight");
            // the others in their order, weighed as the refinement says
            for (kept, was) in k[1..].iter().zip(&c[..last]) {
                assert_eq!((kept.x, kept.y), (was.x, was.y));
                let weight = if vouched { was.weight >> RIVAL_BITS } else { was.weight };
                assert_eq!(kept.weight, weight);
            }
            assert_eq!(f.untrusted, fix.untrusted || !vouched);
            let mut est = Estimator::new(fix.pose);
            est.start_at(&f);
            assert_eq!(est.pose(), refined, "the estimator reports the refined place");
            if !vouched {
                assert_ne!(est.tracking(), Tracking::Located);
            }
        }
    }
    assert!(tried > 10, "{tried} fixes of several places");
}
