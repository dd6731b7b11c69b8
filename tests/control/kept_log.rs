//! The on-board log kept in flash at a mission's end (`control::settings::
//! kept_log`): the rows read back exactly; two slots by turns, the newer
//! wins; a power cut after any of a keep's operations leaves the older
//! log; a damaged log is refused. On the simulated robot: a mission's log
//! is kept once it ends, `dump` after a power-cycle sends it (the same
//! rows the RAM held), a newer mission's log in RAM wins over it, a
//! damaged one is named, and nothing is written while the wheels turn.

use paperbot::config;
use paperbot::config::settings::LOG_SLOTS;
use paperbot::control::log::{RingLog, RowLog};
use paperbot::control::protocol::{telemetry_header, FaultCounters, TelemetryRow};
use paperbot::control::settings::kept_log::HEAD_WORDS;
use paperbot::control::settings::{FlashError, FlashSettings, MemoryFlash, Refusal, SettingsStore};
use paperbot::model::estimator::Tracking;
use paperbot::model::MotionKind;
use paperbot::sim::robot::{SimConfig, SimRobot};

fn row(t_ms: u32) -> TelemetryRow {
    let k = t_ms as i32;
    TelemetryRow {
        t_ms,
        x_dmm: 1_000 + k,
        y_dmm: -k,
        heading_mdeg: (t_ms * 7) % 360_000,
        motion: MotionKind::Forward,
        v_mm_s: 130,
        w_mrad_s: 0,
        left_cmd_centi: 9_500,
        right_cmd_centi: 8_500,
        front_raw_mm: Some(300),
        front_dmm: (t_ms % 2 == 0).then_some(-k),
        right_raw_mm: None,
        right_dmm: None,
        mag_raw: Some([k as i16, -7, 300]),
        mag_field: Some([-66, 4, 300]),
        compass_mdeg: Some(12_000),
        faults: FaultCounters { bus: 1, overruns: t_ms, ..FaultCounters::default() },
        tracking: Tracking::Located,
    }
}

/// A ring of `n` rows, 100 ms apart.
fn log_of(n: u32) -> RingLog<{ config::log::ROWS }> {
    let mut log = RingLog::new();
    for i in 0..n {
        log.push(&row(i * 100));
    }
    log
}

fn rows_of(store: &mut FlashSettings<MemoryFlash>) -> Vec<TelemetryRow> {
    let log = store.kept_logs().unwrap().newest.expect("a kept log");
    (0..).map_while(|i| store.kept_row(&log, i).unwrap()).collect()
}

#[test]
fn a_kept_log_reads_back_row_for_row_and_the_slots_take_turns() {
    let mut store = FlashSettings::new(MemoryFlash::default());
    assert_eq!(store.kept_logs().unwrap().newest, None);
    let first = log_of(7);
    let kept = store.keep_log(&first, 4).unwrap();
    assert_eq!((kept.sector, kept.sequence), (LOG_SLOTS[0], 1));
    let found = store.kept_logs().unwrap();
    let log = found.newest.unwrap();
    assert_eq!((log.rows, log.hz, log.dropped, found.refused), (7, 4, 0, [None, Some(Refusal::Blank)]));
    assert_eq!(rows_of(&mut store), (0..7).map(|i| first.row(i).unwrap()).collect::<Vec<_>>());

    // a full ring that dropped rows, into the other slot; then the first again
    let mut full = log_of(config::log::ROWS as u32 + 30);
    full.push(&row(99_999));
    let kept = store.keep_log(&full, 20).unwrap();
    assert_eq!((kept.sector, kept.sequence), (LOG_SLOTS[1], 2));
    let log = store.kept_logs().unwrap().newest.unwrap();
    assert_eq!((log.rows as usize, log.hz, log.dropped), (config::log::ROWS, 20, 31));
    let back = rows_of(&mut store);
    assert_eq!(back.len(), config::log::ROWS);
    assert_eq!((back[0].t_ms, back.last().unwrap().t_ms), (3_100, 99_999));
    assert_eq!(store.keep_log(&first, 4).unwrap().sector, LOG_SLOTS[0]);
    assert_eq!(store.kept_logs().unwrap().newest.unwrap().sequence, 3);
}

#[test]
fn a_power_cut_after_any_operation_of_a_keep_leaves_the_older_log() {
    let mut store = FlashSettings::new(MemoryFlash::default());
    store.keep_log(&log_of(5), 4).unwrap();
    let older = rows_of(&mut store);
    let newer = log_of(9);
    // the erase of three sectors, then one word at a time
    let ops = 3 + HEAD_WORDS as u32 + 9 * 15;
    for power in 0..ops {
        let mut cut = store.flash.clone();
        cut.power_left = Some(power);
        let mut s = FlashSettings::new(cut);
        assert_eq!(s.keep_log(&newer, 4), Err(FlashError::Timeout), "power for {power} operations");
        s.flash.power_left = None;
        let found = s.kept_logs().unwrap();
        assert_eq!(found.newest.map(|l| (l.slot, l.sequence)), Some((LOG_SLOTS[0], 1)), "power {power}");
        assert_eq!(rows_of(&mut s), older, "power {power}");
        let torn = found.refused[1];
        assert!(matches!(torn, Some(Refusal::Blank | Refusal::Unfinished)), "power {power}: {torn:?}");
    }
    let mut whole = store.flash.clone();
    whole.power_left = Some(ops);
    assert!(FlashSettings::new(whole).keep_log(&newer, 4).is_ok(), "{ops} operations are a whole keep");
}

#[test]
fn a_damaged_or_foreign_log_is_refused_with_its_reason() {
    let mut store = FlashSettings::new(MemoryFlash::default());
    store.keep_log(&log_of(5), 4).unwrap();
    let clean = store.flash.clone();
    for (word, bit, refusal) in [
        (HEAD_WORDS + 20, 3, Refusal::Damaged), // a row's word
        (3, 0, Refusal::Damaged),               // the row count
        (1, 1, Refusal::OtherVersion(3)),       // the version
        (0, 4, Refusal::NotARecord),            // the magic word
    ] {
        let mut flash = clean.clone();
        flash.logs[0][word] ^= 1 << bit;
        let found = FlashSettings::new(flash).kept_logs().unwrap();
        assert_eq!((found.newest, found.refused[0]), (None, Some(refusal)), "word {word} bit {bit}");
    }
    let mut many = clean;
    many.logs[0][3] = config::log::ROWS as u32 + 1;
    assert_eq!(FlashSettings::new(many).kept_logs().unwrap().refused[0], Some(Refusal::OutOfRange));
}

fn cfg() -> SimConfig {
    SimConfig { locate_at_power_up: false, ..SimConfig::default() }
}

/// Ticks until a line starts with one of `ends` (at most `seconds`): the
/// `#` lines so far.
fn until(r: &mut SimRobot, ends: &[&str], seconds: u32) -> Vec<String> {
    let mut lines = Vec::new();
    for _ in 0..seconds * config::timing::LOOP_HZ {
        r.tick();
        let new = r.take_output();
        let done = new.iter().any(|l| ends.iter().any(|e| l.starts_with(e)));
        lines.extend(new.into_iter().filter(|l| l.starts_with('#')));
        if done {
            break;
        }
    }
    lines
}

/// `dump`: its summary line and its rows (as text).
fn dump(r: &mut SimRobot) -> (Vec<String>, Vec<String>) {
    r.take_output();
    r.send("dump");
    let mut all = Vec::new();
    for _ in 0..3 * config::log::ROWS {
        r.tick();
        all.extend(r.take_output());
        if all.iter().any(|l| l == "# log end") {
            break;
        }
    }
    let (notes, rows) = all.into_iter().partition(|l| l.starts_with('#') || l.starts_with("t_ms"));
    (notes, rows)
}

/// A mission of a short drive with its log at 10 Hz, to its end.
fn mission(r: &mut SimRobot) -> Vec<String> {
    for l in ["mission clear", "mission add wait 0.5", "mission add fwd 0.13 1", "log 10", "mission start"] {
        r.send(l);
    }
    until(r, &["# kept the log", "# err"], 30)
}

#[test]
fn a_missions_log_is_kept_and_dumped_after_a_power_cycle() {
    let mut r = SimRobot::new(cfg());
    let lines = mission(&mut r);
    let kept = lines.last().unwrap();
    let held = r.controller().log().len();
    assert!(held >= 14, "{held} rows");
    assert!(
        kept.starts_with(&format!("# kept the log in flash: {held} rows, log 1 at 0x3f3000, paused ")),
        "{lines:?}"
    );
    let done = lines.iter().position(|l| l.starts_with("# mission done")).unwrap();
    assert_eq!(done + 1, lines.len() - 1, "kept right after the mission: {lines:?}");
    let (notes, in_ram) = dump(&mut r);
    assert_eq!(notes[1], format!("# log {held} rows at 10 Hz, 0 dropped (oldest first)"));

    let mut again = SimRobot::with_flash(cfg(), r.flash());
    assert_eq!(again.controller().log().len(), 0);
    let (notes, from_flash) = dump(&mut again);
    assert_eq!(notes[1], format!("# log {held} rows at 10 Hz, 0 dropped (oldest first), kept in flash, log 1"));
    assert_eq!(notes.last().map(String::as_str), Some("# log end"));
    assert_eq!(from_flash, in_ram, "the same rows, byte for byte");

    // a new mission: its log in RAM is the newer one, and kept in the other slot
    let lines = mission(&mut again);
    assert!(lines.last().unwrap().contains("log 2 at 0x3f6000"), "{lines:?}");
    let (notes, _) = dump(&mut again);
    assert!(!notes[1].contains("flash"), "{}", notes[1]);
}

#[test]
fn a_damaged_kept_log_is_named_and_not_sent() {
    let mut r = SimRobot::new(cfg());
    mission(&mut r);
    let mut flash = r.flash();
    flash.logs[0][HEAD_WORDS + 3] ^= 1;
    let mut again = SimRobot::with_flash(cfg(), flash);
    let (notes, rows) = dump(&mut again);
    assert_eq!(
        notes,
        [
            "# ok dump",
            "# kept log at 0x3f3000 ignored: CRC mismatch",
            "# log 0 rows at 4 Hz, 0 dropped (oldest first)",
            telemetry_header(),
            "# log end",
        ]
    );
    assert!(rows.is_empty());
}

#[test]
fn nothing_is_written_while_the_wheels_turn() {
    let mut r = SimRobot::new(cfg());
    for l in ["mission clear", "mission add fwd 0.13 5", "log 10", "mission start"] {
        r.send(l);
    }
    until(&mut r, &["# mission 1"], 30);
    // a byte aborts the mission, and the command it starts drives on
    r.send("fwd 0.13 1");
    let before = r.flash();
    let lines = until(&mut r, &["# kept the log", "# done"], 1);
    assert!(lines.iter().any(|l| l.starts_with("# err mission")), "{lines:?}");
    assert!(!lines.iter().any(|l| l.starts_with("# kept")), "{lines:?}");
    assert_eq!(r.flash(), before, "flash untouched while driving");
    let lines = until(&mut r, &["# kept the log"], 3);
    assert!(lines.last().unwrap().starts_with("# kept the log in flash: "), "{lines:?}");
    assert_eq!(r.controller().mode().word(), "idle");
}
