//! The arena measurement model against f64 ray casting, and its wall
//! choice, corner test and innovation sign, table-driven.

use crate::common;
use common::estimator::{true_range, PoseF64, Rng};
use paperbot::config::geometry::{FRONT_LIDAR, RIGHT_LIDAR};
use paperbot::math::Length;
use paperbot::model::measurement::{expected_heading, expected_lidar, Arena, Beam, LidarId, Wall};

const LX: f64 = 762.5;
const WY: f64 = 495.0;

#[test]
fn expected_distances_match_f64_ray_casting() {
    let arena = Arena::DEFAULT;
    let mut rng = Rng::new(3);
    let mut worst: f64 = 0.0;
    for _ in 0..20_000 {
        let t =
            PoseF64 { x: 60.0 + 640.0 * rng.uniform(), y: 60.0 + 375.0 * rng.uniform(), theta: 7.0 * rng.uniform() };
        for (which, mount) in [(LidarId::Front, &FRONT_LIDAR), (LidarId::Right, &RIGHT_LIDAR)] {
            let want = true_range(t, mount, LX, WY);
            let beam = Beam::new(&arena, &t.to_pose(), mount);
            // a beam within 10 degrees of parallel to its wall is never used;
            // the division there amplifies the fixed-point rounding
            if beam.normal < (0.17 * (1u64 << 30) as f64) as i32 {
                continue;
            }
            let got = expected_lidar(&arena, &t.to_pose(), which).unwrap().to_mm_f64();
            worst = worst.max((got - want).abs());
            assert!((got - want).abs() < 0.01, "{t:?} {which:?}: {got} vs {want}");
        }
    }
    println!("largest difference from f64: {worst:.5} mm");
}

#[test]
fn walls_and_distances_for_the_four_headings() {
    // reference point at (200, 150); the mounts sit on their beams' lines
    // through it, so the expected output is the reference point's distance
    // to the wall along the beam.
    let arena = Arena::DEFAULT;
    let cases = [
        // heading, front wall, front mm, right wall, right mm
        (0.0, Wall::North, 562.5, Wall::East, 345.0),
        (90.0, Wall::East, 345.0, Wall::South, 200.0),
        (180.0, Wall::South, 200.0, Wall::West, 150.0),
        (270.0, Wall::West, 150.0, Wall::North, 562.5),
    ];
    for (deg, fw, fd, rw, rd) in cases {
        let pose = PoseF64 { x: 200.0, y: 150.0, theta: f64::to_radians(deg) }.to_pose();
        let f = Beam::new(&arena, &pose, &FRONT_LIDAR);
        let r = Beam::new(&arena, &pose, &RIGHT_LIDAR);
        assert_eq!((f.wall, r.wall), (fw, rw), "heading {deg}");
        assert!((f.expected_distance().unwrap().to_mm_f64() - fd).abs() < 0.001, "heading {deg}");
        assert!((r.expected_distance().unwrap().to_mm_f64() - rd).abs() < 0.001, "heading {deg}");
        assert_eq!(expected_heading(&pose), pose.theta);
    }
}

#[test]
fn the_mount_setback_is_what_the_lidar_model_subtracts() {
    // facing north 100 mm from the north wall: the front lidar (50 mm behind
    // the reference point) sees the wall 150 mm away; the model output is 100.
    let pose = PoseF64 { x: LX - 100.0, y: 200.0, theta: 0.0 };
    let from_mount = true_range(pose, &FRONT_LIDAR, LX, WY) - FRONT_LIDAR.forward.to_mm_f64();
    assert!((from_mount - 150.0).abs() < 1e-9);
    let got = expected_lidar(&Arena::DEFAULT, &pose.to_pose(), LidarId::Front).unwrap();
    assert!((got.to_mm_f64() - 100.0).abs() < 0.001);
}

#[test]
fn normal_miss_is_positive_for_long_readings_and_scaled_by_the_incidence() {
    let arena = Arena::DEFAULT;
    // 30 degrees off square to the north wall, 300 mm from it
    let pose = PoseF64 { x: LX - 300.0, y: 250.0, theta: f64::to_radians(30.0) }.to_pose();
    let beam = Beam::new(&arena, &pose, &FRONT_LIDAR);
    assert_eq!(beam.wall, Wall::North);
    let expected = beam.expected_distance().unwrap();
    // the lidar sits 50 mm behind the reference point; the nearest point in
    // its cone is 30 - 12.5 degrees off square
    let (cos30, cone) = (f64::cos(f64::to_radians(30.0)), f64::cos(f64::to_radians(17.5)));
    assert!((expected.to_mm_f64() - ((300.0 + 50.0 * cos30) / cone - 50.0)).abs() < 0.001);
    for (dz, want) in [(0.0, 0.0), (10.0, 10.0 * cone), (-10.0, -10.0 * cone)] {
        let z = Length::from_mm_f64(expected.to_mm_f64() + dz);
        assert!((beam.normal_miss(z).to_mm_f64() - want).abs() < 0.001, "{dz}");
    }
}

#[test]
fn corner_test_and_incidence_limit() {
    let arena = Arena::DEFAULT;
    // aimed straight at the north-east corner from (LX - 200, WY - 200): 45 degrees
    let at_corner = PoseF64 { x: LX - 200.0, y: WY - 200.0, theta: f64::to_radians(45.0) }.to_pose();
    let b = Beam::new(&arena, &at_corner, &FRONT_LIDAR);
    assert!(b.near_corner(Length::from_mm(25)));
    // 10 degrees off the corner: the nearest points in the cone on the two
    // walls are about 50 mm apart
    let off = PoseF64 { x: LX - 200.0, y: WY - 200.0, theta: f64::to_radians(35.0) }.to_pose();
    let b = Beam::new(&arena, &off, &FRONT_LIDAR);
    assert!(!b.near_corner(Length::from_mm(25)) && b.near_corner(Length::from_mm(60)));
    assert_eq!(b.wall, Wall::North);
    // square on: never near a corner, fully square
    let square = PoseF64 { x: 300.0, y: 200.0, theta: 0.0 }.to_pose();
    let b = Beam::new(&arena, &square, &FRONT_LIDAR);
    assert!(!b.near_corner(Length::from_mm(25)) && b.square_enough(1 << 30));
    // 61 degrees from square fails a 60-degree limit, 59 passes
    let cos60 = 1 << 29;
    for (deg, ok) in [(59.0, true), (61.0, false)] {
        let p = PoseF64 { x: LX - 100.0, y: 100.0, theta: f64::to_radians(deg) }.to_pose();
        let b = Beam::new(&arena, &p, &FRONT_LIDAR);
        assert_eq!(b.wall, Wall::North, "{deg}");
        assert_eq!(b.square_enough(cos60), ok, "{deg}");
    }
}

/// The f64 cone's nearest point on a wall: the range from the lidar at
/// (`mx`, `my`) looking along `dir` to the wall whose normal points along
/// `normal` at `distance` from the lidar, and the cosine of that ray's
/// incidence (the ray in the cone nearest the normal).
fn cone_point(dir: f64, normal: f64, distance: f64) -> (f64, f64) {
    let half = (paperbot::config::lidar::CONE_DEG / 2.0).to_radians();
    let off = (normal - dir + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU) - std::f64::consts::PI;
    let incidence = (off.abs() - half).max(0.0);
    (distance / incidence.cos(), incidence.cos())
}

/// `Beam::corner_reading` against f64 geometry, looking into the
/// north-east corner: the cone's nearest points on the two walls are `d`
/// apart; a heading error `e` moves them apart by `r e (tan a + tan b)`,
/// so the corner's variance for a heading variance times range squared
/// `hr2` is `floor^2 + hr2 / (cos a cos b)^2` (with `sin(a + b)` taken as
/// 1), and the reading is ambiguous when `d` is within `sigmas` of its
/// root. Cases within 3 % of the threshold are skipped (the fixed point's
/// rounding); the rest must agree exactly on ambiguity and within 1 % on
/// the variance.
#[test]
fn the_corner_variance_is_what_a_heading_error_moves_the_two_walls_apart() {
    let arena = Arena::DEFAULT;
    let max = paperbot::model::measurement::CORNER_MARGIN_MAX.to_mm_f64();
    let mut rng = Rng::new(29);
    let (floor, sigmas) = (5.0, 3);
    let (mut ambiguous, mut clear) = (0, 0);
    for _ in 0..20_000 {
        let t = PoseF64 {
            x: LX - 80.0 - 400.0 * rng.uniform(),
            y: WY - 80.0 - 300.0 * rng.uniform(),
            theta: (5.0 + 80.0 * rng.uniform()).to_radians(),
        };
        let hr = 40.0 * rng.uniform();
        let beam = Beam::new(&arena, &t.to_pose(), &FRONT_LIDAR);
        // the lidar (50 mm behind the reference point) and its two walls
        let (s, c) = t.theta.sin_cos();
        let (mx, my) = (t.x + FRONT_LIDAR.forward.to_mm_f64() * c, t.y + FRONT_LIDAR.forward.to_mm_f64() * s);
        let (rn, cn) = cone_point(t.theta, 0.0, LX - mx);
        let (re, ce) = cone_point(t.theta, std::f64::consts::FRAC_PI_2, WY - my);
        let apart = (rn - re).abs();
        let want = floor * floor + (hr / (cn * ce)).powi(2);
        let limit = (f64::from(sigmas) * want.sqrt()).min(max);
        if (apart - limit).abs() < 0.03 * limit {
            continue;
        }
        let got = beam.corner_reading(Length::ZERO, Length::from_mm_f64(floor), || (hr * hr * 4096.0) as i32, sigmas);
        let got = got.unwrap();
        let got = f64::from(got) / 4096.0;
        if apart < limit {
            let want = want.min(max * max);
            assert!((got - want).abs() <= 0.01 * want, "{t:?} hr {hr:.1}: {got:.1} mm^2 vs {want:.1}");
            ambiguous += 1;
        } else {
            assert_eq!(got, 0.0, "{t:?} hr {hr:.1}: {apart:.1} apart, limit {limit:.1}");
            clear += 1;
        }
    }
    println!("{ambiguous} ambiguous, {clear} clear");
    assert!(ambiguous > 1_000 && clear > 1_000);
}
