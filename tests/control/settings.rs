//! The settings record in flash (`control::settings`): its encoding, what
//! `decode` refuses (an erased sector, any flipped bit, another version,
//! values out of range), and the two sectors written by turns: the newer
//! valid record wins, a power cut at any point of a save leaves the older
//! one, sequence numbers wrap, `forget` erases both, and the flash double
//! keeps NOR semantics (a write only clears bits).

use crate::common;
use paperbot::config::settings::{SECTORS, VERSION};
use paperbot::control::mission::{Mission, Step};
use paperbot::control::settings::{
    check, decode, encode, Flash, FlashError, FlashSettings, MemoryFlash, Refusal, Settings, SettingsStore,
    RECORD_WORDS,
};
use paperbot::math::{Angle, Speed};
use paperbot::model::compass::MagCalibration;
use paperbot::model::{Motion, Trim};

/// Settings unlike the config's in every field.
fn learned() -> Settings {
    let mut mission = Mission::new();
    for s in [
        Step::Pose { x_mm: -1200, y_mm: 300, heading: Angle::from_millidegrees(90_000) },
        Step::Drive { motion: Motion::Straight(Speed::from_mm_s(130)), duration_ms: 2_500 },
        Step::Goto { x_mm: 300, y_mm: -200 },
    ] {
        mission.push(s).unwrap();
    }
    Settings {
        left_trim: Trim(-512),
        right_trim: Trim(2560),
        calibration: MagCalibration { bias: [-81, 36, -3], scale_q16: [44_000, 55_000, 200_000] },
        declination: Angle::from_millidegrees(11_933),
        mission,
    }
}

/// `r` with its CRC recomputed (a record that another firmware might have
/// written correctly).
fn resealed(mut r: [u32; RECORD_WORDS]) -> [u32; RECORD_WORDS] {
    let crc = common::crc32(&r[..RECORD_WORDS - 1]);
    r[RECORD_WORDS - 1] = crc;
    r
}

#[test]
fn a_record_survives_its_encoding() {
    let s = learned();
    let r = encode(&s, 7);
    assert_eq!(r[0], 0x5042_5354, "magic PBST");
    assert_eq!(r[1], VERSION);
    assert_eq!(r[2], 7);
    assert_eq!(r[RECORD_WORDS - 1], common::crc32(&r[..RECORD_WORDS - 1]), "CRC-32 ISO-HDLC of the LE bytes");
    assert_eq!(decode(&r), Ok((s, 7)));
    let config = Settings::from_config();
    assert_eq!(decode(&encode(&config, u32::MAX)), Ok((config, u32::MAX)));
}

#[test]
fn every_flipped_bit_is_refused() {
    let r = encode(&learned(), 3);
    for i in 0..RECORD_WORDS {
        for bit in 0..32 {
            let mut bad = r;
            bad[i] ^= 1 << bit;
            let refusal = decode(&bad).unwrap_err();
            let expected = match i {
                0 => Refusal::NotARecord,
                1 => Refusal::OtherVersion(VERSION ^ 1 << bit),
                _ => Refusal::Damaged,
            };
            assert_eq!(refusal, expected, "word {i} bit {bit}");
        }
    }
}

#[test]
fn erased_garbage_and_other_versions_are_refused_with_their_reason() {
    assert_eq!(decode(&[u32::MAX; RECORD_WORDS]), Err(Refusal::Blank));
    assert_eq!(decode(&[0; RECORD_WORDS]), Err(Refusal::NotARecord));
    let mut v2 = encode(&learned(), 1);
    v2[1] = VERSION + 1;
    let v2 = resealed(v2);
    assert_eq!(decode(&v2), Err(Refusal::OtherVersion(VERSION + 1)));
    assert_eq!(Refusal::OtherVersion(2).reason(), "version");
}

#[test]
fn values_out_of_range_are_refused_even_with_a_good_crc() {
    // trims beyond the protocol's +-10 steps
    let mut r = encode(&learned(), 1);
    r[3] = u32::from(Trim(10 * 256 + 1).0 as u16);
    assert_eq!(decode(&resealed(r)), Err(Refusal::OutOfRange));
    // a zero soft-iron scale
    let mut r = encode(&learned(), 1);
    r[8] = 0;
    assert_eq!(decode(&resealed(r)), Err(Refusal::OutOfRange));
    // a mission that is not one (its own checksum broken)
    let mut r = encode(&learned(), 1);
    r[12] ^= 1;
    assert_eq!(decode(&resealed(r)), Err(Refusal::OutOfRange));
    // the trims at the limit are fine
    let mut s = learned();
    s.left_trim = Trim(-2560);
    assert!(decode(&encode(&s, 1)).is_ok());
}

fn store() -> FlashSettings<MemoryFlash> {
    FlashSettings::new(MemoryFlash::default())
}

#[test]
fn blank_flash_loads_nothing_and_says_both_sectors_are_erased() {
    let loaded = store().load().unwrap();
    assert_eq!(loaded.newest, None);
    assert_eq!(loaded.refused, [Some(Refusal::Blank), Some(Refusal::Blank)]);
}

#[test]
fn saves_alternate_sectors_and_the_newest_wins() {
    let mut st = store();
    let mut s = learned();
    let first = st.save(&s).unwrap();
    assert_eq!((first.sector, first.sequence), (SECTORS[0], 1));
    s.left_trim = Trim(100);
    let second = st.save(&s).unwrap();
    assert_eq!((second.sector, second.sequence), (SECTORS[1], 2));
    s.left_trim = Trim(200);
    let third = st.save(&s).unwrap();
    assert_eq!((third.sector, third.sequence), (SECTORS[0], 3));
    let loaded = st.load().unwrap();
    assert_eq!(loaded.newest, Some((s, 3)));
    assert_eq!(loaded.refused, [None, None]);
}

#[test]
fn a_power_cut_anywhere_in_a_save_keeps_the_older_record() {
    let older = learned();
    let mut newer = learned();
    newer.right_trim = Trim(-77);
    // the erase is one operation, each word written another
    for ops in 0..=(1 + RECORD_WORDS as u32) {
        let mut st = store();
        st.save(&older).unwrap();
        st.flash.power_left = Some(ops);
        let result = st.save(&newer);
        st.flash.power_left = None; // power back: a new boot
        let loaded = st.load().unwrap();
        if ops <= RECORD_WORDS as u32 {
            assert_eq!(result.unwrap_err(), FlashError::Timeout, "cut after {ops} operations");
            assert_eq!(loaded.newest, Some((older.clone(), 1)), "cut after {ops} operations");
            // erased until a word is written, then cut short (the magic
            // word goes last)
            let torn = if ops <= 1 { Refusal::Blank } else { Refusal::Unfinished };
            assert_eq!(loaded.refused[1], Some(torn), "cut after {ops} operations");
        } else {
            assert!(result.is_ok());
            assert_eq!(loaded.newest, Some((newer.clone(), 2)));
        }
    }
}

#[test]
fn a_damaged_newest_record_gives_the_older_one() {
    let mut st = store();
    let older = learned();
    st.save(&older).unwrap();
    let mut newer = learned();
    newer.left_trim = Trim(9);
    st.save(&newer).unwrap();
    st.flash.sectors[1][20] &= !0x100; // a bit lost in the newer
    let loaded = st.load().unwrap();
    assert_eq!(loaded.newest, Some((older.clone(), 1)));
    assert_eq!(loaded.refused, [None, Some(Refusal::Damaged)]);
    // the next save replaces the damaged one, not the good one
    let saved = st.save(&newer).unwrap();
    assert_eq!((saved.sector, saved.sequence), (SECTORS[1], 2));
}

#[test]
fn sequence_numbers_wrap() {
    let mut st = store();
    let mut s = learned();
    st.flash.sectors[0] = encode(&s, u32::MAX);
    s.left_trim = Trim(1);
    let saved = st.save(&s).unwrap();
    assert_eq!((saved.sector, saved.sequence), (SECTORS[1], 0));
    assert_eq!(st.load().unwrap().newest, Some((s, 0)));
}

#[test]
fn forget_erases_both_sectors() {
    let mut st = store();
    st.save(&learned()).unwrap();
    st.save(&learned()).unwrap();
    st.forget().unwrap();
    let loaded = st.load().unwrap();
    assert_eq!(loaded.newest, None);
    assert_eq!(loaded.refused, [Some(Refusal::Blank); 2]);
}

#[test]
fn the_flash_double_is_nor_flash() {
    let mut f = MemoryFlash::default();
    let a = SECTORS[0];
    f.write(a, &[0xF0F0_F0F0]).unwrap();
    f.write(a, &[0x0FFF_FFFF]).unwrap(); // cannot set bits again
    let mut w = [0];
    f.read(a, &mut w).unwrap();
    assert_eq!(w, [0x00F0_F0F0]);
    f.erase_sector(a).unwrap();
    f.read(a, &mut w).unwrap();
    assert_eq!(w, [u32::MAX]);
    // unaligned, not a sector start, outside the settings sectors
    assert_eq!(f.write(a + 2, &[0]), Err(FlashError::Error));
    assert_eq!(f.erase_sector(a + 4), Err(FlashError::Error));
    assert_eq!(f.read(0x1000, &mut w), Err(FlashError::Error));
    // a record written over an old one without an erase is damaged
    f.erase_sector(a).unwrap();
    let mut st = FlashSettings::new(f);
    st.save(&learned()).unwrap();
    let mut other = learned();
    other.left_trim = Trim(3);
    st.flash.write(SECTORS[0], &encode(&other, 5)).unwrap();
    assert!(check(&st.flash.sectors[0]).is_err());
}

#[test]
fn the_fuzz_seed_holds_two_valid_records() {
    // fuzz/seeds/settings_decode/two_records: the config's values with
    // sequence 1 and 2 (so the fuzzer starts from records that decode)
    let bytes = std::fs::read(concat!(env!("CARGO_MANIFEST_DIR"), "/fuzz/seeds/settings_decode/two_records")).unwrap();
    let words: Vec<u32> = bytes.chunks(4).map(|c| u32::from_le_bytes(c.try_into().unwrap())).collect();
    let first: [u32; RECORD_WORDS] = words[..RECORD_WORDS].try_into().unwrap();
    let second: [u32; RECORD_WORDS] = words[RECORD_WORDS..].try_into().unwrap();
    assert_eq!(decode(&first).unwrap().0.left_trim, Trim(256));
    assert_eq!(decode(&second).unwrap().1, 2);
}

#[test]
fn a_board_without_flash_has_a_zero_sized_store_that_refuses() {
    use paperbot::control::settings::NoFlash;
    assert_eq!(std::mem::size_of::<FlashSettings<NoFlash>>(), 0);
    let mut st = FlashSettings::new(NoFlash);
    assert_eq!(st.load(), Err(FlashError::Error));
    assert_eq!(st.save(&learned()), Err(FlashError::Error));
}
