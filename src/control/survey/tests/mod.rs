//! The survey's room to turn, on exact scripts: readings handed in as the
//! loop would, the actions it answers.

#![allow(clippy::restriction)] // test code: a panic fails the test

use super::room::{left_clear, positioning_mm, reach_mm, room_to_turn, Ahead};
use super::*;
use crate::math::Angle;
use crate::model::locate::turns::TurnSample;

mod turns;

const ARENA: Arena = Arena::DEFAULT;

/// Feeds one view's readings (every lidar and compass reading the same)
/// and ticks until the survey acts; returns that action.
fn view(s: &mut Survey, heading_deg: u32, front: Option<i32>, right: Option<i32>) -> Action {
    let h = Angle((u64::from(heading_deg) * (1 << 32) / 360) as u32);
    for _ in 0..config::locate::COMPASS_READINGS {
        s.heading(h);
    }
    for _ in 0..config::locate::LIDAR_READINGS {
        if let Some(f) = front {
            s.lidar(LidarId::Front, Length::from_mm(f));
        }
        if let Some(r) = right {
            s.lidar(LidarId::Right, Length::from_mm(r));
        }
    }
    s.tick(&ARENA)
}

/// Ticks until the action is not `what`; returns how many ticks were `what`
/// and the next action.
fn run(s: &mut Survey, what: Action) -> (u32, Action) {
    let mut n = 0;
    loop {
        let a = s.tick(&ARENA);
        if a != what {
            return (n, a);
        }
        n += 1;
        assert!(n < 100_000, "stuck at {what:?}, {} views", s.views().len());
    }
}

/// Past a drive's ticks: standing for the settle.
fn to_next_view(s: &mut Survey, what: Action) -> u32 {
    let (n, a) = run(s, what);
    assert_eq!(a, Action::Stand);
    n
}

/// The compass's heading after `ticks` ticks of a turn that way from
/// `from` at `percent` of the turn line's rate ([`config::locate::TURN_DEG`]
/// in [`TURN_TICKS`]).
fn turned_to(from: Angle, clockwise: bool, percent: u64, ticks: u16) -> Angle {
    let step = ((config::locate::TURN_DEG as u64) << 32) / 360;
    let moved = Angle((step * percent * u64::from(ticks) / 100 / u64::from(TURN_TICKS)) as u32);
    if clockwise {
        from.wrapping_add(moved)
    } else {
        from.wrapping_sub(moved)
    }
}

/// Through a turn under way (the survey entered it on its last tick), the
/// compass reading before each tick where the body has turned at
/// `percent` of the turn line's rate from the last view: the ticks it
/// turned, until it stands.
fn turn(s: &mut Survey, clockwise: bool, percent: u64) -> u32 {
    let from = s.views().last().expect("a turn follows a view").heading;
    let mut tick: u16 = 0;
    loop {
        s.heading(turned_to(from, clockwise, percent, tick));
        match s.tick(&ARENA) {
            Action::Turn { clockwise: way } => assert_eq!(way, clockwise),
            Action::Stand => return u32::from(tick),
            a => panic!("{a:?} while turning"),
        }
        tick += 1;
    }
}

/// The front reading the drive before the first view aims for: what a
/// turn wants ahead (108 mm, a wall at a slant) and the slack.
fn aim() -> i32 {
    108 + config::locate::POSITION_SLACK_MM
}

#[test]
fn the_reach_is_the_swept_radius_about_the_skid_and_the_margin() {
    // the centre 126 mm behind the nose, at the skid: the front corners,
    // sqrt(126^2 + 53^2) = 136.7 mm, and 20 mm
    assert_eq!(reach_mm(), 136 + 20);
}

#[test]
fn positioning_backs_up_from_a_wall_ahead_and_drives_forward_from_one_behind() {
    let aim = aim();
    assert_eq!(positioning_mm(Some(Length::from_mm(100))), 100 - aim);
    assert_eq!(positioning_mm(Some(Length::from_mm(20))), -config::locate::MAX_BACK_UP_MM);
    // forward the whole reach (a wall may touch the skid, at the centre) ...
    assert_eq!(positioning_mm(Some(Length::from_mm(400))), reach_mm());
    // ... but not past the aim
    assert_eq!(positioning_mm(Some(Length::from_mm(aim + 30))), 30);
    assert_eq!(positioning_mm(Some(Length::from_mm(aim))), 0);
    assert_eq!(positioning_mm(None), 0);
}

#[test]
fn a_turn_needs_room_ahead_and_clockwise_on_the_right() {
    let reach = reach_mm();
    let v = |front: Option<i32>, right: Option<i32>| Readings {
        heading: Angle::ZERO,
        front: front.map(Length::from_mm),
        right: right.map(Length::from_mm),
    };
    assert!(room_to_turn(&v(Some(reach), Some(reach)), true, Ahead::Slanted));
    assert!(!room_to_turn(&v(Some(reach), Some(reach - 1)), true, Ahead::Slanted));
    assert!(room_to_turn(&v(Some(reach), Some(reach - 1)), false, Ahead::Slanted), "the left is not seen");
    // ahead: half as much again from the centre, 126 mm behind the nose
    let front = reach * 3 / 2 - 126;
    assert_eq!(front, 108);
    assert!(room_to_turn(&v(Some(front), Some(400)), false, Ahead::Slanted));
    assert!(!room_to_turn(&v(Some(front - 1), Some(400)), false, Ahead::Slanted));
    assert!(!room_to_turn(&v(Some(front - 1), Some(400)), true, Ahead::Slanted));
    assert!(room_to_turn(&v(None, None), true, Ahead::Slanted), "a missing reading shows no wall");
    // a wall square ahead: the reach from the centre
    assert!(room_to_turn(&v(Some(reach - 126), Some(400)), true, Ahead::Square));
    assert!(!room_to_turn(&v(Some(reach - 127), Some(400)), true, Ahead::Square));
}

/// The left of a view is what earlier views saw in its direction: a right
/// reading taken facing the other way, or a front reading taken facing
/// left, within 45 degrees (the front's from the reference point, the
/// turning centre behind it).
#[test]
fn the_left_is_clear_unless_an_earlier_view_saw_a_wall_there() {
    let reach = reach_mm();
    let behind = config::locate::TURN_CENTRE_BEHIND_REFERENCE.to_mm();
    let v = |deg: i32, front: Option<i32>, right: Option<i32>| Readings {
        heading: Angle::from_millidegrees(deg * 1000),
        front: front.map(Length::from_mm),
        right: right.map(Length::from_mm),
    };
    // facing north (0), the left is west (270): seen by the right lidar
    // facing south (180), or the front facing west
    assert!(left_clear(&[], Angle::ZERO), "nothing seen, nothing refused");
    assert!(left_clear(&[v(180, Some(50), Some(reach))], Angle::ZERO));
    assert!(!left_clear(&[v(180, Some(400), Some(reach - 1))], Angle::ZERO));
    assert!(!left_clear(&[v(180 - 45, Some(400), Some(reach - 1))], Angle::ZERO), "45 degrees off is near");
    assert!(left_clear(&[v(180 - 46, Some(400), Some(reach - 1))], Angle::ZERO), "46 degrees off is not");
    assert!(left_clear(&[v(270, Some(reach - behind), Some(50))], Angle::ZERO));
    assert!(!left_clear(&[v(270, Some(reach - behind - 1), Some(400))], Angle::ZERO));
    assert!(left_clear(&[v(180, None, None), v(270, None, Some(50))], Angle::ZERO), "no reading shows no wall");
    // the same views say nothing of the left when facing south
    assert!(left_clear(&[v(180, Some(400), Some(reach - 1))], Angle::HALF_TURN));
}

/// On a script, the negative check of the left: three views clockwise
/// from north, then facing 135 degrees a wall near the nose: no turn on
/// clockwise, so back over the swept ground and one step past the first
/// view, whose left (270) this view's right lidar (225) reads. Room there:
/// the turn back; a wall within the reach: neither way has room (before
/// `room::left_clear`, the turn back swung the nose into it).
#[test]
fn a_wall_an_earlier_view_saw_on_the_left_stops_the_turn_back() {
    let reach = reach_mm();
    for (right, turns_back) in [(reach, true), (reach - 1, false)] {
        let mut s = Survey::new();
        // readings no pose in the box gives: the search's answer is no fix,
        // and the survey turns on
        for (deg, mm) in [(0, None), (45, Some(500)), (90, Some(500))] {
            assert_eq!(view(&mut s, deg, mm, mm), Action::Stand);
            assert_eq!(run(&mut s, Action::Stand).1, Action::Turn { clockwise: true });
            turn(&mut s, true, 100);
            settle(&mut s);
        }
        assert_eq!(view(&mut s, 135, Some(60), Some(right)), Action::Stand);
        let (_, next) = run(&mut s, Action::Stand);
        if turns_back {
            assert_eq!(next, Action::Turn { clockwise: false });
        } else {
            assert!(matches!(next, Action::Done(_)), "{next:?}");
            assert!(s.room().cut_short);
        }
    }
}

/// Through the settle after a drive or a turn: standing, then ready for a view.
fn settle(s: &mut Survey) {
    for _ in 0..=SETTLE_TICKS {
        assert_eq!(s.tick(&ARENA), Action::Stand);
    }
}

/// The drive before the first view: the readings standing, the drive's
/// ticks; then standing for the first view.
fn positioned(s: &mut Survey, front: i32, right: i32) -> (i32, u32) {
    assert_eq!(view(s, 0, Some(front), Some(right)), Action::Stand);
    assert!(s.views().is_empty(), "the positioning view is not one of the search's");
    let mm = s.room().moved_mm;
    let ticks = to_next_view(s, Action::Drive { forward: mm > 0 });
    settle(s);
    (mm, ticks)
}

#[test]
fn a_wall_ahead_backs_the_body_up_before_the_first_view() {
    let mut s = Survey::new();
    let (mm, ticks) = positioned(&mut s, 100, 300);
    let back = 108 + config::locate::POSITION_SLACK_MM - 100;
    assert_eq!(mm, -back);
    // 28 mm at 130 mm/s: 215 ms, 21 ticks
    assert_eq!(ticks, ticks_of(back));
    assert_eq!(view(&mut s, 0, Some(reach_mm()), Some(300)), Action::Stand);
    assert_eq!(s.views().len(), 1);
    assert_eq!(run(&mut s, Action::Stand).1, Action::Turn { clockwise: true });
    assert_eq!(s.room(), RoomLog { moved_mm: -back, reversed: 0, squeezed: 0, cut_short: false });
}

/// Whole ticks of a drive of `mm` at the survey's speed.
fn ticks_of(mm: i32) -> u32 {
    (mm.unsigned_abs() * 1000 / config::locate::POSITION_MM_S as u32) * LOOP_HZ / 1000
}

#[test]
fn room_ahead_drives_forward_clear_of_a_wall_behind() {
    let mut s = Survey::new();
    let (mm, ticks) = positioned(&mut s, 400, 300);
    assert_eq!(mm, reach_mm());
    assert_eq!(ticks, ticks_of(mm));
    // a front reading nearer than the aim while driving ends the drive
    // (one at the aim does not); backing up, the front reading is nearer
    // anyway, and the drive goes on
    for (forward_mm, front, ends) in [(400, aim() - 1, true), (400, aim(), false), (100, 20, false)] {
        let mut s = Survey::new();
        assert_eq!(view(&mut s, 0, Some(forward_mm), Some(300)), Action::Stand);
        let forward = s.room().moved_mm > 0;
        for _ in 0..3 {
            assert_eq!(s.tick(&ARENA), Action::Drive { forward });
        }
        s.lidar(LidarId::Front, Length::from_mm(front));
        let next = s.tick(&ARENA);
        assert_eq!(next == Action::Stand, ends, "{forward_mm} mm, then {front} mm: {next:?}");
    }
    // already at the aim: no drive, that view is the first
    let mut s = Survey::new();
    assert_eq!(view(&mut s, 0, Some(aim()), Some(300)), Action::Stand);
    assert_eq!((s.views().len(), s.room().moved_mm), (1, 0));
    assert_eq!(run(&mut s, Action::Stand).1, Action::Turn { clockwise: true });
}

#[test]
fn no_room_on_the_right_turns_counterclockwise() {
    let mut s = Survey::new();
    positioned(&mut s, 300, 100);
    assert_eq!(view(&mut s, 0, Some(reach_mm()), Some(100)), Action::Stand);
    assert_eq!(run(&mut s, Action::Stand).1, Action::Turn { clockwise: false });
    assert_eq!(s.room().reversed, 1);
}

#[test]
fn a_wall_ahead_after_a_turn_turns_back_over_swept_ground_and_past_it() {
    let mut s = Survey::new();
    assert_eq!(view(&mut s, 0, Some(aim()), Some(300)), Action::Stand);
    assert_eq!(run(&mut s, Action::Stand).1, Action::Turn { clockwise: true });
    assert_eq!(turn(&mut s, true, 100), TURN_TICKS);
    settle(&mut s);
    // the nose now 60 mm from a wall: no turn on into new ground, but back
    // over the swept ground and one step past the first view (whose front
    // showed room), in one turn
    assert_eq!(view(&mut s, 45, Some(60), Some(300)), Action::Stand);
    assert_eq!(run(&mut s, Action::Stand).1, Action::Turn { clockwise: false });
    assert_eq!(turn(&mut s, false, 100), 2 * TURN_TICKS);
    settle(&mut s);
    assert_eq!(s.room(), RoomLog { moved_mm: 0, reversed: 1, squeezed: 0, cut_short: false });
    // on counterclockwise one step at a time, while there is room ahead
    assert_eq!(view(&mut s, 315, Some(aim()), Some(300)), Action::Stand);
    assert_eq!(run(&mut s, Action::Stand).1, Action::Turn { clockwise: false });
    assert_eq!(turn(&mut s, false, 100), TURN_TICKS);
}

#[test]
fn no_room_either_way_takes_the_views_there_are() {
    let mut s = Survey::new();
    positioned(&mut s, 20, 300);
    // after backing up the wall ahead still reads near: no turn either way
    assert_eq!(view(&mut s, 0, Some(20), Some(100)), Action::Stand);
    assert!(s.room().cut_short);
    let (_, end) = run(&mut s, Action::Stand);
    assert!(matches!(end, Action::Done(_)), "{end:?}");
    assert_eq!(s.views().len(), 1);
}

#[test]
fn before_the_search_has_its_views_a_wall_square_ahead_is_room_enough() {
    let mut s = Survey::new();
    positioned(&mut s, 100, 300);
    // no room for a slanted wall ahead, nor on the right: counterclockwise,
    // as long as a wall square ahead clears
    assert_eq!(view(&mut s, 0, Some(100), Some(100)), Action::Stand);
    assert_eq!(run(&mut s, Action::Stand).1, Action::Turn { clockwise: false });
    assert_eq!((s.room().reversed, s.room().squeezed, s.room().cut_short), (1, 1, false));
}

/// The negative check: without the room check a view with a wall near on
/// the right turns clockwise anyway (the old survey) -- here it must not.
#[test]
fn the_room_check_is_what_turns_away_from_the_wall() {
    let reach = reach_mm();
    for (right, clockwise) in [(reach, true), (reach - 1, false)] {
        let mut s = Survey::new();
        assert_eq!(view(&mut s, 0, Some(aim()), Some(right)), Action::Stand);
        assert_eq!(run(&mut s, Action::Stand).1, Action::Turn { clockwise }, "right {right}");
    }
}
