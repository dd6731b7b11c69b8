//! `control::goto`'s tests: the planner on the exact kinematics.

#![allow(clippy::restriction)] // test code: a panic fails the test

use super::*;
use crate::math::Dt;
use crate::model::step;
use std::vec::Vec;

fn pose(x: f64, y: f64, deg: f64) -> Pose {
    Pose::new(crate::math::Coord::from_mm_f64(x), crate::math::Coord::from_mm_f64(y), Angle::from_degrees_f64(deg))
}

/// Runs the planner on the exact kinematics (`model::step`, 10 ms
/// ticks, turns about the axle, planned so) and returns the pose it stops
/// at and the ticks it took.
fn drive(start: Pose, target: Target) -> (Pose, u32) {
    let mut nav = Nav::new(target);
    let mut p = start;
    for n in 0..5_000 {
        match nav.step(&p, config::geometry::ROTATION_TO_REFERENCE, &Arena::DEFAULT) {
            NavStep::Arrived => return (p, n),
            NavStep::Drive { motion, .. } => p = step(&p, motion, Dt::from_micros_saturating(10_000)),
        }
    }
    panic!("no arrival from {start:?} to {target:?}");
}

#[test]
fn goto_arrives_from_every_side_and_heading() {
    let target = Target::Point { x_mm: 400, y_mm: 250 };
    for (x, y) in [(150.0, 100.0), (650.0, 400.0), (400.0, 100.0), (390.0, 240.0), (420.0, 280.0), (400.0, 250.0)] {
        for deg in [0.0, 45.0, 90.0, 179.0, 200.0, 315.0] {
            let (p, ticks) = drive(pose(x, y, deg), target);
            let miss = (p.x.to_mm_f64() - 400.0).hypot(p.y.to_mm_f64() - 250.0);
            // within the tolerance; a goto that drove there ends with the
            // target abeam (exact kinematics: 4.4 mm at most, 3.7 without
            // the drives that make room for a turn near a wall)
            let bound = if ticks > 50 { 4.5 } else { f64::from(config::goto::ARRIVE_MM) + 0.1 };
            assert!(miss <= bound, "from ({x}, {y}, {deg}): {miss:.1} mm off after {ticks} ticks");
        }
    }
}

#[test]
fn face_stops_within_its_tolerance_turning_the_short_way() {
    for (from, to) in [(0.0, 90.0), (90.0, 0.0), (350.0, 10.0), (10.0, 350.0), (0.0, 179.0), (30.0, 30.5)] {
        let (p, ticks) = drive(pose(300.0, 200.0, from), Target::Heading(Angle::from_degrees_f64(to)));
        let off = (p.theta.diff(Angle::from_degrees_f64(to)) as f64 / 4_294_967_296.0 * 360.0).abs();
        assert!(off <= 1.0, "{from} -> {to}: {off:.2} degrees off");
        // the short way round at 2.4 rad/s (1.375 degrees a tick)
        let mut turn = (to - from + 360.0) % 360.0;
        if turn > 180.0 {
            turn = 360.0 - turn;
        }
        assert!(f64::from(ticks) <= turn / 1.375 + 1.0, "{from} -> {to}: {ticks} ticks");
    }
}

#[test]
fn targets_near_a_wall_or_outside_are_refused() {
    let arena = Arena::DEFAULT; // 762.5 x 495
    let m = config::goto::TARGET_WALL_MARGIN_MM;
    assert_eq!(check_target(Target::Point { x_mm: m, y_mm: m }, &arena), Ok(()));
    assert_eq!(check_target(Target::Point { x_mm: 762 - m, y_mm: 495 - m }, &arena), Ok(()));
    for (x, y) in [(m - 1, 200), (200, m - 1), (763 - m, 200), (200, 496 - m), (-100, 200), (2000, 200)] {
        assert_eq!(check_target(Target::Point { x_mm: x, y_mm: y }, &arena), Err(Refusal::TooNearWall), "{x} {y}");
    }
    assert_eq!(check_target(Target::Heading(Angle::ZERO), &arena), Ok(()));
}

/// The turning centre the planner assumes (config), mm behind the
/// reference point.
fn planned_centre_mm() -> f64 {
    config::goto::TURN_CENTRE_BEHIND_REFERENCE.to_mm_f64()
}

/// How a goto on the exact kinematics went.
struct Run {
    end: Pose,
    /// Smallest distance of a body corner inside a wall over the run, mm
    /// (negative: it crossed one).
    clearance_mm: f64,
    /// Times it began driving to make room for a turn.
    room_legs: u32,
}

/// The body's corners (the rectangle of `config::geometry`: the reference
/// point to the skid, `BODY_HALF_WIDTH` to each side) at pose `(x, y,
/// th)`, mm and radians.
fn corners(x: f64, y: f64, th: f64) -> [(f64, f64); 4] {
    let g = |l: crate::math::Length| l.to_mm_f64();
    let back = g(config::geometry::ROTATION_TO_REFERENCE) + g(config::geometry::SKID_BEHIND_AXLE);
    let w = g(config::geometry::BODY_HALF_WIDTH);
    let (s, c) = th.sin_cos();
    // forward (c, s), right (-s, c)
    [(0.0, w), (0.0, -w), (-back, w), (-back, -w)].map(|(f, r)| (x + f * c - r * s, y + f * s + r * c))
}

/// Clearance of the body's corners to the box's walls, mm.
fn body_clearance(arena: &Arena, x: f64, y: f64, th: f64) -> f64 {
    let (lx, wy) = (arena.length_x.to_mm_f64(), arena.width_y.to_mm_f64());
    corners(x, y, th).iter().map(|&(cx, cy)| cx.min(lx - cx).min(cy).min(wy - cy)).fold(f64::MAX, f64::min)
}

/// A goto on the exact kinematics in the default box whose turns pivot
/// `true_centre_mm` behind the reference point, planned with the config's
/// centre; the planner is told `told` as its box (a far larger one turns
/// the room check off). Ticks of 10 ms, at most the goto's time limit.
fn run(start: (f64, f64, f64), target: (i32, i32), true_centre_mm: f64, told: &Arena) -> Option<Run> {
    let arena = Arena::DEFAULT;
    let (mut x, mut y, mut th) = (start.0, start.1, start.2.to_radians());
    let mut nav = Nav::new(Target::Point { x_mm: target.0, y_mm: target.1 });
    let mut out = Run { end: pose(x, y, start.2), clearance_mm: body_clearance(&arena, x, y, th), room_legs: 0 };
    let dt = 0.01;
    for _ in 0..config::goto::TIME_LIMIT_MS / 10 {
        let p = Pose::new(
            crate::math::Coord::from_mm_f64(x),
            crate::math::Coord::from_mm_f64(y),
            Angle::from_radians_f64(th),
        );
        let before = nav.leg;
        let motion = match nav.step(&p, config::goto::TURN_CENTRE_BEHIND_REFERENCE, told) {
            NavStep::Arrived => return Some(Run { end: p, ..out }),
            NavStep::Drive { motion, .. } => motion,
        };
        if nav.leg == Leg::Room && before != Leg::Room {
            out.room_legs += 1;
        }
        match motion {
            Motion::Straight(v) => {
                let d = v.to_mps_f64() * 1000.0 * dt;
                (x, y) = (x + d * th.cos(), y + d * th.sin());
            }
            Motion::Turn(w) => {
                // about the centre `true_centre_mm` behind the reference point
                let c = true_centre_mm;
                let (cx, cy) = (x - c * th.cos(), y - c * th.sin());
                th += w.to_rad_s_f64() * dt;
                (x, y) = (cx + c * th.cos(), cy + c * th.sin());
            }
            Motion::Stop => {}
        }
        out.clearance_mm = out.clearance_mm.min(body_clearance(&arena, x, y, th));
    }
    None
}

/// Starts near each wall and in each corner: the reference point 90 and
/// 150 mm from a wall at its middle, 150 mm from both in a corner, at
/// every 30 degrees of heading whose body is inside the box by 5 mm (at
/// 150 mm the skid end may face the wall). (From 110 mm in a corner,
/// facing a wall with the target behind, the turn where it stands, the
/// short way, sweeps the nose into the side wall: docs/simulator.md.)
fn starts_near_walls() -> Vec<(f64, f64, f64)> {
    let (lx, wy) = (Arena::DEFAULT.length_x.to_mm_f64(), Arena::DEFAULT.width_y.to_mm_f64());
    let mut out = Vec::new();
    let corner = 150.0;
    let mut places =
        std::vec![(corner, corner), (corner, wy - corner), (lx - corner, corner), (lx - corner, wy - corner)];
    for side in [90.0, 150.0] {
        places.extend([(side, wy / 2.0), (lx - side, wy / 2.0), (lx / 2.0, side), (lx / 2.0, wy - side)]);
    }
    for (x, y) in places {
        for k in 0..12 {
            let deg = f64::from(k) * 30.0;
            if body_clearance(&Arena::DEFAULT, x, y, deg.to_radians()) >= 5.0 {
                out.push((x, y, deg));
            }
        }
    }
    out
}

/// Targets across the box: its middle, and near its corners (100 mm from
/// two walls: 30 mm more than the nearest a target may be).
const TARGETS: [(i32, i32); 5] = [(381, 247), (100, 100), (662, 100), (100, 395), (662, 395)];

#[test]
fn turns_far_behind_the_axle_clear_the_walls_and_arrive() {
    let starts = starts_near_walls();
    assert!(starts.len() >= 80, "{} starts", starts.len());
    // the planned pivot, and the hard world's farthest (80 mm behind the axle)
    let d = config::geometry::ROTATION_TO_REFERENCE.to_mm_f64();
    let (mut rooms, mut worst) = (0, f64::MAX);
    for true_centre in [planned_centre_mm(), d + 80.0] {
        for &start in &starts {
            for target in TARGETS {
                let Some(r) = run(start, target, true_centre, &Arena::DEFAULT) else {
                    panic!("{start:?} -> {target:?} (centre {true_centre} mm): no arrival in the time limit");
                };
                let miss = (r.end.x.to_mm_f64() - f64::from(target.0)).hypot(r.end.y.to_mm_f64() - f64::from(target.1));
                assert!(miss <= f64::from(config::goto::ARRIVE_MM) + 0.1, "{start:?} -> {target:?}: {miss:.1} mm off");
                assert!(
                    r.clearance_mm >= 0.0,
                    "{start:?} -> {target:?}: a corner {:.1} mm past a wall",
                    -r.clearance_mm
                );
                // no see-saw between making room and turning
                assert!(r.room_legs <= 2, "{start:?} -> {target:?}: {} room legs", r.room_legs);
                rooms += r.room_legs;
                worst = worst.min(r.clearance_mm);
            }
        }
    }
    // the room check did the work: many starts needed room
    assert!(rooms >= 50, "{rooms} room legs");
    assert!(worst < 25.0, "closest {worst:.1} mm: the starts are not near the walls");
}

#[test]
fn without_the_room_check_the_same_turns_cross_walls() {
    // told a box far larger than the real one, the planner sees room everywhere
    let vast = Arena { length_x: crate::math::Length::from_mm(30_000), width_y: crate::math::Length::from_mm(30_000) };
    let mut crossed = 0;
    for &start in &starts_near_walls() {
        for target in TARGETS {
            if let Some(r) = run(start, target, planned_centre_mm(), &vast) {
                if r.clearance_mm < 0.0 {
                    crossed += 1;
                }
            }
        }
    }
    assert!(crossed >= 20, "only {crossed} runs crossed a wall");
}
