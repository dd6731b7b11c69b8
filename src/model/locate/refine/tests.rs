//! The refinement on surveys whose readings the model explains exactly
//! (the arena model's own ranges: `measurement::expected_lidar`), and on
//! ones it cannot explain. The realistic simulator's figures, beside the
//! f64 reference's, are `tests/localization/locate.rs`'s.

#![allow(clippy::restriction)] // test code: a panic fails the test

use super::solve::{cholesky_solve, lower, TRIANGLE};
use super::*;
use crate::math::Length;
use crate::model::locate::locate;
use crate::model::measurement::{expected_lidar, LidarId};
use std::vec;
use std::vec::Vec;

const ARENA: Arena = Arena::DEFAULT;
/// [`crate::config::lidar::READING_AGE_US`] in loop ticks.
const AGE_TICKS: f64 =
    crate::config::lidar::READING_AGE_US as f64 * crate::config::timing::LOOP_HZ as f64 / 1_000_000.0;

/// The body's reference point at heading `deg` about the pivot (mm) at a
/// lever of `lever` mm.
fn pose_at(pivot: (f64, f64), lever: f64, deg: f64) -> Pose {
    let t = deg.to_radians();
    let (x, y) = (pivot.0 + lever * t.cos(), pivot.1 + lever * t.sin());
    Pose::new(Coord::from_mm_f64(x), Coord::from_mm_f64(y), Angle::from_degrees_f64(deg))
}

/// A survey of `headings` (degrees) about `pivot`, the compass off by
/// `bias` degrees, each turn 33 ticks with a reading pair every third;
/// `spoil` changes each turn reading (mm).
fn survey(pivot: (f64, f64), lever: f64, headings: &[f64], bias: f64, spoil: f64) -> (Vec<Readings>, Vec<Turn>) {
    survey_paired(pivot, lever, headings, bias, spoil, 0)
}

/// [`survey`], each turn's right lidar reading `right_after` ticks after
/// the front one (the two range on their own clocks). A reading at a tick
/// is of the body [`crate::config::lidar::READING_AGE_US`] earlier (the
/// chip's measurement, the loop's poll).
fn survey_paired(
    pivot: (f64, f64),
    lever: f64,
    headings: &[f64],
    bias: f64,
    spoil: f64,
    right_after: u16,
) -> (Vec<Readings>, Vec<Turn>) {
    let levers = vec![lever; headings.len().saturating_sub(1).max(1)];
    survey_pivoting(pivot, &levers, headings, bias, spoil, right_after)
}

/// Turn `j`'s lever: `levers[j]`, the last one's past the turns.
fn lever_of(levers: &[f64], j: usize) -> f64 {
    levers.get(j).or(levers.last()).copied().unwrap_or(0.0)
}

/// Each view's pivot when turn `j` swings the reference point `levers[j]`
/// about a pivot that far behind it, the first about `pivot`.
fn pivots(pivot: (f64, f64), levers: &[f64], headings: &[f64]) -> Vec<(f64, f64)> {
    let mut pivots = vec![pivot];
    for (j, w) in headings.windows(2).enumerate() {
        let reference = pose_at(pivots[j], lever_of(levers, j), w[1]);
        let (next, t) = (lever_of(levers, j + 1), w[1].to_radians());
        pivots.push((reference.x.to_mm_f64() - next * t.cos(), reference.y.to_mm_f64() - next * t.sin()));
    }
    pivots
}

/// [`survey_paired`] with each turn about its own pivot: turn `j` swings
/// the reference point `levers[j]` about a pivot that far behind it (the
/// first about `pivot`), so the pivot moves between turns as the lever
/// changes.
fn survey_pivoting(
    pivot: (f64, f64),
    levers: &[f64],
    headings: &[f64],
    bias: f64,
    spoil: f64,
    right_after: u16,
) -> (Vec<Readings>, Vec<Turn>) {
    let read = |p: &Pose, id| expected_lidar(&ARENA, p, id);
    let pivots = pivots(pivot, levers, headings);
    let views: Vec<Readings> = headings
        .iter()
        .enumerate()
        .map(|(i, &h)| {
            let p = pose_at(pivots[i], lever_of(levers, i), h);
            Readings {
                heading: Angle::from_degrees_f64(h + bias),
                front: read(&p, LidarId::Front),
                right: read(&p, LidarId::Right),
            }
        })
        .collect();
    let turns = headings
        .windows(2)
        .enumerate()
        .map(|(j, w)| {
            let mut t = Turn::new(w[1] > w[0], 1);
            for tick in (3..30u16).step_by(3) {
                for (id, tick) in [(LidarId::Front, tick), (LidarId::Right, tick + right_after)] {
                    let h = w[0] + (w[1] - w[0]) * (f64::from(tick) - AGE_TICKS) / 33.0;
                    let p = pose_at(pivots[j], levers[j], h);
                    if let Some(d) = read(&p, id) {
                        t.push(id, tick, Length::from_mm_f64(d.to_mm_f64() + spoil));
                    }
                }
            }
            t.end(33);
            t
        })
        .collect();
    (views, turns)
}

fn refine_all(fix: &Fix, views: &[Readings], turns: &[Turn]) -> (Refined, u32) {
    let mut r = Refine::new(*fix, views, turns);
    for passes in 1..20_000 {
        if let Some(done) = r.step(&ARENA, views, turns) {
            let refined = done.expect("a refined pose");
            // the fix takes the refined pose, and the flag
            let fix = r.refined_fix();
            assert_eq!((fix.pose, fix.untrusted), (refined.pose, !refined.vouched));
            return (refined, passes);
        }
    }
    panic!("the refinement did not end");
}

fn off(got: &Pose, want: &Pose) -> (f64, f64) {
    let d = (got.x.to_mm_f64() - want.x.to_mm_f64()).hypot(got.y.to_mm_f64() - want.y.to_mm_f64());
    (d, f64::from(got.theta.diff(want.theta)) * 360.0 / 4_294_967_296.0)
}

#[test]
fn a_survey_the_model_explains_refines_to_its_pose() {
    // the hard world's lever (60 mm behind the axle), the compass 4
    // degrees off at every view: the search's heading is 4 degrees out
    let (pivot, lever) = ((380.0, 240.0), 116.0);
    let headings = [10.0, 55.0, 100.0, 145.0];
    let (views, turns) = survey(pivot, lever, &headings, 4.0, 0.0);
    let fix = locate(&ARENA, &views).expect("the search finds a place");
    let truth = pose_at(pivot, lever, 145.0);
    let (refined, passes) = refine_all(&fix, &views, &turns);
    let (d, deg) = off(&refined.pose, &truth);
    std::println!(
        "refined {d:.1} mm and {deg:.2} degrees off in {passes} passes (the search {:?})",
        off(&fix.pose, &truth)
    );
    assert!(d < 3.0 && deg.abs() < 0.5, "{d} mm, {deg} degrees");
    assert!(refined.vouched, "{refined:?}");
}

/// A pivot that moves from turn to turn (the skid's grip: the hard
/// world's lever give or take 5 mm a turn, `sim::PIVOT_SPREAD_MM`; here
/// 108, 124 and 116 mm) is the model's: at the survey's own poses, each
/// turn's lever apart from the last as its move, every reading's row is
/// within a quarter of a sigma (measured 0.20; the model's own floor, one
/// lever for every turn, 0.16); with the moves left out, a reading misses
/// by more than a sigma (measured 1.33).
#[test]
fn a_pivot_that_moves_each_turn_is_the_models() {
    let headings = [10.0, 55.0, 100.0, 145.0];
    let (pivot, levers) = ((380.0, 240.0), [108.0, 124.0, 116.0]);
    let (views, turns) = survey_pivoting(pivot, &levers, &headings, 4.0, 0.0, 0);
    let model = rows::Model { arena: &ARENA, views: &views, turns: &turns, share: Share::Nearest, near: (0, 0, 0) };
    let last = pivots(pivot, &levers, &headings)[3];
    let mut p: Params = [0; MAX_PARAMS];
    (p[PX], p[PY], p[LEVER]) =
        (Length::from_mm_f64(last.0).0, Length::from_mm_f64(last.1).0, Length::from_mm_f64(levers[2]).0);
    for (i, h) in headings.iter().enumerate() {
        p[HEADING + i] = Angle::from_degrees_f64(*h).0 as i32;
    }
    // each turn 45 degrees in its 33 ticks
    let rate = Angle::from_degrees_f64(45.0 / 33.0).0 as i32;
    (p[rows::CW], p[rows::CCW]) = (rate, rate);
    let worst = |p: &Params| {
        let mut worst = 0.0f64;
        model.rows(p, true, 0, 1_000, |row| {
            if row.loss == rows::Loss::Robust && !row.cols().is_empty() {
                worst = worst.max(f64::from(row.r).abs() / rows::ONE_SIGMA as f64);
            }
        });
        worst
    };
    let without = worst(&p);
    for j in 0..2 {
        p[rows::MOVE + j] = Length::from_mm_f64(levers[j] - levers[2]).0;
    }
    let with = worst(&p);
    std::println!("the worst reading's row: {with:.3} sigmas; without the moves {without:.2}");
    assert!(with < 0.25 && without > 1.0, "{with}, {without}");
}

#[test]
fn each_reading_of_a_turn_sits_at_its_own_tick() {
    // the right lidar reads three ticks after the front (4.1 degrees of
    // these turns): explained when each reading takes its own tick's
    // heading (0.5 mm, 0.2 degrees, 0.07 sigmas squared a reading); at its
    // pair's first tick 5.2 mm, 0.5 degrees and 0.31
    let (pivot, lever) = ((380.0, 240.0), 116.0);
    let headings = [10.0, 55.0, 100.0, 145.0];
    let (views, turns) = survey_paired(pivot, lever, &headings, 4.0, 0.0, 3);
    assert_eq!(turns[0].samples()[0].reading(LidarId::Right).map(|r| r.0), Some(6));
    let fix = locate(&ARENA, &views).expect("the search finds a place");
    let (refined, _) = refine_all(&fix, &views, &turns);
    let (d, deg) = off(&refined.pose, &pose_at(pivot, lever, 145.0));
    assert!(d < 2.0 && deg.abs() < 0.35, "{d} mm, {deg} degrees");
    assert!(refined.vouched && refined.per_reading < q24(0.15), "{refined:?}");
}

#[test]
fn readings_no_pose_explains_are_not_vouched_for() {
    // every turn's reading 60 mm long (something else than the walls, or
    // a lidar's model far off): the fit cannot explain them
    let (pivot, lever) = ((380.0, 240.0), 116.0);
    let (views, turns) = survey(pivot, lever, &[10.0, 55.0, 100.0, 145.0], 0.0, 60.0);
    let fix = locate(&ARENA, &views).expect("the views alone fit");
    let (refined, _) = refine_all(&fix, &views, &turns);
    assert!(!refined.vouched, "{refined:?}");
    assert!(refined.per_reading > FIT_LIMIT);
}

#[test]
fn compass_rates_take_each_ways_median_and_skip_blocked_turns() {
    let view = |deg: f64| Readings { heading: Angle::from_degrees_f64(deg), front: None, right: None };
    let views = [view(0.0), view(45.0), view(95.0), view(96.0), view(50.0)];
    let turn = |cw: bool, ticks: u16| {
        let mut t = Turn::new(cw, 1);
        t.end(ticks);
        t
    };
    let turns = [turn(true, 30), turn(true, 40), turn(true, 30), turn(false, 23)];
    let (cw, ccw) = compass_rates(&views, &turns);
    let lsb = |deg: f64, ticks: f64| Angle::from_degrees_f64(deg).0 as f64 / ticks;
    // 45 / 30 and 50 / 40: the median of two is the upper; 1 degree is blocked
    assert!((cw as f64 - lsb(45.0, 30.0)).abs() < 2.0, "{cw}");
    assert!((ccw as f64 - lsb(46.0, 23.0)).abs() < 2.0, "{ccw}");
}

#[test]
fn cholesky_solves_a_positive_definite_system() {
    let one = 1i32 << 24;
    let mut m = [0i32; TRIANGLE];
    // [[4, 2, 0], [2, 3, 1], [0, 1, 2]] y = [2, 1, -1] (Q24; b Q12)
    let a = [[4, 2, 0], [2, 3, 1], [0, 1, 2]];
    for (k, row) in a.iter().enumerate() {
        for (l, v) in row.iter().enumerate().take(k + 1) {
            m[lower(k, l)] = v * one;
        }
    }
    let mut b = [0i32; MAX_PARAMS];
    b[..3].copy_from_slice(&[2 << 12, 1 << 12, -(1 << 12)]);
    cholesky_solve(&mut m, &mut b, 3).expect("solved");
    // exact: y = (1/3, 1/3, -2/3)
    for (got, want) in b.iter().zip([1.0 / 3.0, 1.0 / 3.0, -2.0 / 3.0]) {
        assert!((*got as f64 / 4096.0 - want).abs() < 1e-3, "{b:?}");
    }
    // not positive definite
    let mut m = [0i32; TRIANGLE];
    m[0] = -one;
    assert!(cholesky_solve(&mut m, &mut [0; MAX_PARAMS], 1).is_none());
}

#[test]
fn the_config_logarithm_is_the_logarithm() {
    for x in [0.5, 1.0, 2.0, 9.333, 11.2, 50.0] {
        assert!((crate::math::ln_f64(x) - x.ln()).abs() < 1e-9, "{x}");
    }
}

/// The front lidar's row of a one-view survey at (x, y) mm facing `deg`
/// (the reference point on the pivot), reading `z_mm`.
fn front_row(x: f64, y: f64, deg: f64, z_mm: f64) -> rows::Row {
    let views =
        [Readings { heading: Angle::from_degrees_f64(deg), front: Some(Length::from_mm_f64(z_mm)), right: None }];
    let model = rows::Model { arena: &ARENA, views: &views, turns: &[], share: Share::Axis, near: (0, 0, NEAR_INV) };
    let mut p: Params = [0; MAX_PARAMS];
    (p[PX], p[PY]) = (Length::from_mm_f64(x).0, Length::from_mm_f64(y).0);
    p[HEADING] = Angle::from_degrees_f64(deg).0 as i32;
    let mut first = None;
    model.rows(&p, true, 0, 1, |row| first = Some(*row));
    first.expect("the front reading's row")
}

/// A reading's spread off square grows with its range
/// (`config::refine::INCIDENCE_SPREAD`): at 45 degrees on the east wall,
/// one of 400 mm is half as sure as one of 200 (its derivatives, in its
/// sigmas, half: sqrt(2^2 + 20^2) mm against sqrt(2^2 + 10^2)); past the
/// incidence limit (`config::refine::MAX_INCIDENCE_DEG`) a reading costs
/// one sigma and moves nothing, just inside it a row as any.
#[test]
fn a_readings_sigma_grows_with_range_and_glancing_readings_say_nothing() {
    let d_px = |row: &rows::Row| row.cols().iter().find(|c| usize::from(c.0) == PX).map(|c| f64::from(c.1).abs());
    let (near, far) = (front_row(562.5, 50.0, 45.0, 200.0), front_row(562.5, 50.0, 45.0, 400.0));
    let ratio = d_px(&near).unwrap() / d_px(&far).unwrap();
    let want = (4.0f64 + 20.0 * 20.0).sqrt() / (4.0f64 + 10.0 * 10.0).sqrt();
    assert!((ratio - want).abs() < 0.03 * want, "{ratio} against {want}");
    // the east wall 62.5 mm ahead along x: 65 degrees off square, then 55
    let glancing = front_row(700.0, 50.0, 65.0, 150.0);
    assert_eq!((glancing.r, glancing.cols().len()), (rows::ONE_SIGMA as i32, 0));
    let inside = front_row(700.0, 50.0, 55.0, 110.0);
    assert!(d_px(&inside).is_some_and(|d| d > 0.0), "{inside:?}");
}

/// A compass the floor bends (its bias 6 degrees more every 100 mm east
/// of the pivot, on top of 4 everywhere: views 14 degrees apart in their
/// errors about the hard world's 116 mm lever) is explained by the bend
/// (`config::refine::FIELD_SIGMA_DEG`): within 0.3 degrees and 0.15
/// sigmas squared a reading (measured 0.19 and 0.11; with the bend's
/// sigma near zero, no bend, 0.39 and 0.20).
#[test]
fn a_compass_the_floor_bends_is_explained_by_the_bend() {
    let (pivot, lever) = ((380.0, 240.0), 116.0);
    let headings = [10.0, 55.0, 100.0, 145.0, 190.0];
    let (mut views, turns) = survey(pivot, lever, &headings, 4.0, 0.0);
    for (v, h) in views.iter_mut().zip(headings) {
        let bend = 6.0 * lever / 100.0 * h.to_radians().cos();
        v.heading = v.heading.wrapping_add(Angle::from_degrees_f64(bend));
    }
    let fix = locate(&ARENA, &views).expect("the search finds a place");
    let (refined, _) = refine_all(&fix, &views, &turns);
    let (d, deg) = off(&refined.pose, &pose_at(pivot, lever, 190.0));
    std::println!("{d:.1} mm, {deg:.2} degrees, {:.3} a reading", refined.per_reading as f64 / q24(1.0) as f64);
    assert!(d < 3.0 && deg.abs() < 0.3, "{d} mm, {deg} degrees");
    assert!(refined.vouched && refined.per_reading < q24(0.15), "{refined:?}");
}

/// A view's compass row moves with the parameters as its closed-form
/// derivatives say: each parameter stepped a unit either way (a mrad, a
/// mm) changes the residual by its derivative (Q12 sigmas a unit), to a
/// hundredth.
#[test]
fn a_compass_rows_derivatives_are_its_differences() {
    let views = [Readings { heading: Angle::from_degrees_f64(40.0), front: None, right: None }];
    let model = rows::Model { arena: &ARENA, views: &views, turns: &[], share: Share::Axis, near: (0, 0, NEAR_INV) };
    let mut p: Params = [0; MAX_PARAMS];
    let deg = |d: f64| Angle::from_degrees_f64(d).0 as i32;
    (p[HEADING], p[BIAS], p[rows::FIELD_X], p[rows::FIELD_Y]) = (deg(30.0), deg(3.0), deg(4.0), deg(-2.0));
    p[LEVER] = Length::from_mm_f64(116.0).0;
    let row = |p: &Params| {
        let mut first = None;
        model.rows(p, true, 0, 1, |row| first = Some(*row));
        first.expect("the compass's row")
    };
    let at = row(&p);
    for k in [HEADING, BIAS, rows::FIELD_X, rows::FIELD_Y, LEVER] {
        let step = |sign: i32| {
            let mut q = p;
            q[k] += sign * rows::unit(k) as i32;
            f64::from(row(&q).r)
        };
        let difference = (step(1) - step(-1)) / 2.0;
        let derivative = at.cols().iter().find(|c| usize::from(c.0) == k).map_or(0.0, |c| f64::from(c.1));
        assert!((difference - derivative).abs() <= 0.01 * difference.abs() + 1.0, "{k}: {difference} {derivative}");
        assert!(difference.abs() > 1.0, "{k} moves the row");
    }
}
