//! The settings record (`control::settings`) from arbitrary flash
//! contents: any bytes decode to a record or to a refusal with its reason,
//! never a panic; a record that decodes encodes back to exactly the same
//! words (nothing is taken that `encode` would not write); and the store
//! over two sectors of such contents loads the newer valid one. The same
//! bytes in a kept log's slot give a log whose every row reads, or a
//! refusal.
#![no_main]

use libfuzzer_sys::fuzz_target;
use paperbot::control::settings::kept_log::LOG_WORDS;
use paperbot::control::settings::{decode, encode, FlashSettings, MemoryFlash, Record, SettingsStore, RECORD_WORDS};

fn record(bytes: &[u8]) -> Record {
    words::<RECORD_WORDS>(bytes)
}

/// Words from the bytes (little-endian; missing words erased).
fn words<const N: usize>(bytes: &[u8]) -> [u32; N] {
    let mut r = [u32::MAX; N];
    for (w, chunk) in r.iter_mut().zip(bytes.chunks(4)) {
        let mut b = [0xFF; 4];
        b[..chunk.len()].copy_from_slice(chunk);
        *w = u32::from_le_bytes(b);
    }
    r
}

fuzz_target!(|data: &[u8]| {
    let (a, b) = data.split_at(data.len() / 2);
    let (ra, rb) = (record(a), record(b));
    for r in [&ra, &rb] {
        match decode(r) {
            Ok((settings, seq)) => assert_eq!(&encode(&settings, seq), r, "a decoded record re-encodes exactly"),
            Err(refusal) => assert!(!refusal.reason().is_empty()),
        }
    }
    let mut store = FlashSettings::new(MemoryFlash { sectors: [ra, rb], ..MemoryFlash::default() });
    let loaded = store.load().expect("the memory flash reads");
    let valid = [decode(&ra).ok(), decode(&rb).ok()];
    match (&valid, &loaded.newest) {
        ([None, None], None) => {}
        ([Some(x), None], Some(n)) | ([None, Some(x)], Some(n)) => assert_eq!(x, n),
        ([Some(x), Some(y)], Some(n)) => assert!(n == x || n == y),
        _ => panic!("loaded {:?} from {valid:?}", loaded.newest),
    }

    let mut logs = FlashSettings::new(MemoryFlash { logs: [words::<LOG_WORDS>(data), words(b)], ..MemoryFlash::default() });
    let found = logs.kept_logs().expect("the memory flash reads");
    if let Some(log) = found.newest {
        for i in 0..log.rows as usize {
            assert!(logs.kept_row(&log, i).expect("a kept row reads").is_some());
        }
        assert_eq!(logs.kept_row(&log, log.rows as usize), Ok(None));
    }
});
