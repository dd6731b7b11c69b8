//! The survey's turns between views on exact scripts (issue #29): the
//! compass ends them, and each keeps the lidars' readings taken on it.

#![allow(clippy::restriction)] // test code: a panic fails the test

use super::*;

/// Through a turn under way (the survey entered it on its last tick), as
/// the loop hands the readings in, before each tick: the compass where
/// the body has turned at `percent` of the turn line's rate ([`turn`]),
/// the right lidar's on the turn's ticks 0, 3, 6, ... (400 mm and the
/// tick) and the front's on 2, 5, 8, ... (200 mm and the tick), a lidar's
/// period being 3.3 ticks. Ticks until the survey stands; returns the
/// ticks it turned and the turn as it should be kept: the same readings
/// handed to a [`Turn`] of `steps` directly, ended after those ticks.
fn turn_reading(s: &mut Survey, clockwise: bool, steps: u8, percent: u64) -> (u32, Turn) {
    let mut kept = Turn::new(clockwise, steps);
    let from = s.views().last().expect("a turn follows a view").heading;
    // the ticks the turn has run: 0 before its first
    let mut tick: u16 = 0;
    loop {
        s.heading(turned_to(from, clockwise, percent, tick));
        for (due, id, mm) in [(tick % 3 == 0, LidarId::Right, 400), (tick % 3 == 2, LidarId::Front, 200)] {
            if due {
                let d = Length::from_mm(mm + i32::from(tick));
                s.lidar(id, d);
                kept.push(id, tick, d);
            }
        }
        match s.tick(&ARENA) {
            Action::Turn { clockwise: way } => assert_eq!(way, clockwise),
            Action::Stand => {
                kept.end(tick);
                return (u32::from(tick), kept);
            }
            a => panic!("{a:?} while turning"),
        }
        tick += 1;
    }
}

/// The same readings, standing through the settle after a turn: no turn
/// keeps them.
fn settle_reading(s: &mut Survey) {
    for _ in 0..=SETTLE_TICKS {
        s.lidar(LidarId::Front, Length::from_mm(999));
        s.lidar(LidarId::Right, Length::from_mm(999));
        assert_eq!(s.tick(&ARENA), Action::Stand);
    }
}

/// Runs the survey to its answer as the loop would in open ground: before
/// each tick the compass reads where the turns have taken the body (a
/// turn's [`config::locate::TURN_DEG`] over its [`TURN_TICKS`]), each
/// lidar 400 mm while the body turns (room to turn everywhere), and
/// `standing` (`None`: nothing) while it stands. Every tick the turns
/// kept are one fewer than the views.
fn to_the_end(s: &mut Survey, mut heading: Angle, standing: Option<i32>) -> Result<Fix, Failure> {
    let per_tick = Angle((((config::locate::TURN_DEG as u64) << 32) / 360 / u64::from(TURN_TICKS)) as u32);
    let mut turning = false;
    for _ in 0..100_000 {
        s.heading(heading);
        if let Some(mm) = if turning { Some(400) } else { standing } {
            s.lidar(LidarId::Front, Length::from_mm(mm));
            s.lidar(LidarId::Right, Length::from_mm(mm));
        }
        let a = s.tick(&ARENA);
        assert_eq!(s.turns().len() + 1, s.views().len().max(1), "{a:?}");
        turning = matches!(a, Action::Turn { .. });
        match a {
            Action::Turn { clockwise: true } => heading = heading.wrapping_add(per_tick),
            Action::Turn { clockwise: false } => heading = heading.wrapping_sub(per_tick),
            Action::Done(result) => return result,
            _ => {}
        }
    }
    panic!("no answer");
}

#[test]
fn the_turns_between_views_keep_the_readings_taken_on_them() {
    let mut s = Survey::new();
    // view 0, then a turn clockwise
    assert_eq!(view(&mut s, 0, Some(aim()), Some(300)), Action::Stand);
    assert!(s.turns().is_empty());
    let (ticks, first) = turn_reading(&mut s, true, 1, 100);
    // the tick that began the turn stood (it took the view), the turn's
    // TURN_TICKS ticks turned, and the tick after them stood again and
    // ended it: the turn ran the ticks that turned, TURN_TICKS (45 degrees
    // at 2.4 rad/s is 327 ms, 32 whole ticks), its readings at 0 to 32
    assert_eq!((ticks, TURN_TICKS), (32, 32));
    assert!(s.turns().is_empty(), "a turn is kept once the view after it is");
    settle_reading(&mut s);
    // a wall ahead: back counterclockwise over the swept ground and past
    // it, two steps in one turn
    assert_eq!(view(&mut s, 45, Some(60), Some(300)), Action::Stand);
    assert_eq!(s.turns(), core::slice::from_ref(&first));
    let (ticks, second) = turn_reading(&mut s, false, 2, 100);
    assert_eq!(ticks, 2 * TURN_TICKS);
    settle_reading(&mut s);
    assert_eq!(view(&mut s, 315, Some(aim()), Some(300)), Action::Stand);
    let (ticks, third) = turn_reading(&mut s, false, 1, 100);
    assert_eq!(ticks, TURN_TICKS);
    settle_reading(&mut s);
    assert_eq!(view(&mut s, 270, Some(aim()), Some(300)), Action::Stand);
    assert_eq!(s.room().reversed, 1);
    assert_eq!(s.views().len(), config::locate::MIN_VIEWS);
    assert_eq!(s.turns(), [first, second, third]);

    let t = s.turns();
    assert_eq!(
        t.iter().map(|t| (t.clockwise, t.ticks)).collect::<std::vec::Vec<_>>(),
        [(true, 32), (false, 64), (false, 32)]
    );
    // the one-step turn: a pair every 3 ticks, the right lidar's reading
    // and the front's 2 ticks later; the last front reading came on the
    // tick that ended the turn (32), before the survey's tick
    let ticks_of = |t: &Turn| t.samples().iter().map(|s| s.first_tick()).collect::<std::vec::Vec<_>>();
    assert_eq!(ticks_of(&t[0]), (0..=30).step_by(3).collect::<std::vec::Vec<u16>>());
    assert_eq!(t[0].samples()[10], TurnSample { front_tick: 32, front_mm: 232, right_tick: 30, right_mm: 430 });
    // the two-step turn: every second pair, spread over all of it
    assert_eq!(ticks_of(&t[1]), (0..=60).step_by(6).collect::<std::vec::Vec<u16>>());
    assert_eq!(t[1].samples()[1], TurnSample { front_tick: 8, front_mm: 208, right_tick: 6, right_mm: 406 });

    // on to the answer (the search's, of these four views: a fix it
    // cannot vouch for, which ends the survey): the turns stay one fewer
    // than the views
    let fix = to_the_end(&mut s, Angle::from_degrees_f64(270.0), Some(400)).expect("a fix");
    assert!(fix.untrusted);
    assert_eq!((s.views().len(), s.turns().len()), (4, 3));
}

#[test]
fn a_survey_of_all_its_views_keeps_a_turn_between_each_two() {
    // no lidar distance standing (the lidars read only while turning):
    // no search, a turn and a view after each view, to the last
    let mut s = Survey::new();
    assert_eq!(to_the_end(&mut s, Angle::ZERO, None), Err(Failure::NoRange));
    let (views, turns) = (s.views().len(), s.turns());
    assert_eq!(views, MAX_VIEWS);
    assert_eq!(turns.len(), views - 1);
    // one step clockwise a turn, a pair of readings each tick it turned
    // (handed in on the ticks after those), the first twelve kept
    for t in turns {
        assert_eq!((t.clockwise, t.ticks, t.samples().len()), (true, 32, 12));
        assert_eq!(
            t.samples().first(),
            Some(&TurnSample { front_tick: 1, front_mm: 400, right_tick: 1, right_mm: 400 })
        );
    }
}

/// A turn's ticks at `percent` of the turn line's rate: the first tick
/// past its `steps` of [`config::locate::TURN_DEG`] on the compass.
fn ticks_at(steps: u32, percent: u32) -> u32 {
    (steps * TURN_TICKS * 100).div_ceil(percent)
}

#[test]
fn a_turn_ends_when_the_compass_shows_its_angle() {
    // issue #29's hard world turns each way at 0.6 to 1.8 times the line
    for (percent, ticks) in [(100, 32), (180, 18), (60, 54)] {
        assert_eq!(ticks_at(1, percent), ticks);
        let mut s = Survey::new();
        assert_eq!(view(&mut s, 0, Some(aim()), Some(300)), Action::Stand);
        assert_eq!(turn_reading(&mut s, true, 1, u64::from(percent)).0, ticks, "{percent} %");
        settle_reading(&mut s);
        assert_eq!(view(&mut s, 45, Some(aim()), Some(300)), Action::Stand);
        let kept = &s.turns()[0];
        assert_eq!(kept.ticks, ticks as u16);
        // readings every 3 ticks, up to the turn's twelve
        assert_eq!(kept.samples().len(), (ticks as usize / 3 + 1).min(12), "{percent} %");
    }
    // a reversed turn goes back over the swept ground by the compass too
    let mut s = Survey::new();
    assert_eq!(view(&mut s, 0, Some(aim()), Some(300)), Action::Stand);
    assert_eq!(turn_reading(&mut s, true, 1, 60).0, ticks_at(1, 60));
    settle_reading(&mut s);
    assert_eq!(view(&mut s, 45, Some(60), Some(300)), Action::Stand);
    assert_eq!(turn_reading(&mut s, false, 2, 180).0, ticks_at(2, 180));
}

#[test]
fn a_blocked_turn_is_kept_without_its_readings_and_a_survey_cut_short_keeps_its_turns() {
    let mut s = Survey::new();
    // the search's answer as it is (refined, this one's poor fit would
    // look again from elsewhere, beginning anew: searching.rs's
    // `a_poor_fit_looks_again_from_elsewhere_once`)
    s.set_refine(false);
    assert_eq!(view(&mut s, 0, Some(aim()), Some(300)), Action::Stand);
    // the compass shows no turn (blocked): the turn ends when a step's
    // ticks on the turn line showed less than BLOCKED_TURN_DEG
    let (ticks, mut turn) = turn_reading(&mut s, true, 1, 0);
    assert_eq!(ticks, TURN_TICKS - 1);
    settle_reading(&mut s);
    // and the nose 20 mm from a wall: no room either way, the survey ends
    // with the views it has
    assert_eq!(view(&mut s, 0, Some(20), Some(100)), Action::Stand);
    assert!(s.room().cut_short);
    assert!(matches!(run(&mut s, Action::Stand).1, Action::Done(_)));
    assert_eq!(s.views().len(), 2);
    // the turn is kept, its readings forgotten (the refinement would read
    // them at headings the body never turned to)
    assert!(!turn.samples().is_empty());
    turn.forget();
    assert_eq!(s.turns(), [turn]);
    assert_eq!((s.turns()[0].clockwise, s.turns()[0].ticks), (true, TURN_TICKS as u16 - 1));
}

#[test]
fn a_turn_too_slow_for_its_limit_ends_there_without_its_readings() {
    let limit = TURN_TICKS * config::locate::TURN_LIMIT_PERCENT / 100;
    assert_eq!(limit, 64);
    for (percent, ticks, kept) in [(72, 45, true), (48, limit, false)] {
        let mut s = Survey::new();
        assert_eq!(view(&mut s, 0, Some(aim()), Some(300)), Action::Stand);
        // (at 48 %, 21 degrees a step's ticks: not stalled)
        assert_eq!(turn_reading(&mut s, true, 1, percent).0, ticks, "{percent} %");
        settle_reading(&mut s);
        assert_eq!(view(&mut s, 45, Some(aim()), Some(300)), Action::Stand);
        assert_eq!(!s.turns()[0].samples().is_empty(), kept, "{percent} %");
    }
}

#[test]
fn a_turn_whose_view_fails_is_not_among_the_turns() {
    let mut s = Survey::new();
    assert_eq!(view(&mut s, 0, Some(aim()), Some(300)), Action::Stand);
    turn_reading(&mut s, true, 1, 100);
    settle_reading(&mut s);
    // the view after it: the lidars read, the compass gives nothing
    let mut end = Action::Stand;
    for _ in 0..=VIEW_TICKS {
        s.lidar(LidarId::Front, Length::from_mm(300));
        end = s.tick(&ARENA);
    }
    assert_eq!(end, Action::Done(Err(Failure::NoHeading)));
    assert_eq!((s.views().len(), s.turns().len()), (1, 0));
}

/// Three views and two turns, one of them back over the swept ground:
/// the views, the turns and the room log after them.
fn three_views(s: &mut Survey) -> (std::vec::Vec<Readings>, std::vec::Vec<Turn>, RoomLog) {
    assert_eq!(view(s, 0, Some(aim()), Some(300)), Action::Stand);
    turn_reading(s, true, 1, 100);
    settle_reading(s);
    assert_eq!(view(s, 45, Some(60), Some(300)), Action::Stand);
    turn_reading(s, false, 2, 100);
    settle_reading(s);
    assert_eq!(view(s, 315, Some(aim()), Some(300)), Action::Stand);
    (s.views().to_vec(), s.turns().to_vec(), s.room())
}

#[test]
fn a_restarted_survey_goes_as_a_new_one() {
    let mut new = Survey::new();
    let fresh = three_views(&mut new);
    assert_eq!(fresh.1.len(), 2);
    // restarted after its views, and in the middle of a turn
    let mut s = Survey::new();
    three_views(&mut s);
    for _ in 0..5 {
        assert!(matches!(s.tick(&ARENA), Action::Turn { .. }));
    }
    s.restart();
    assert!(s.views().is_empty() && s.turns().is_empty());
    assert_eq!(three_views(&mut s), fresh);
}
