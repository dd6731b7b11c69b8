//! The settings record (`control::settings`) from arbitrary flash
//! contents: any bytes decode to a record or to a refusal with its reason,
//! never a panic; a record that decodes encodes back to exactly the same
//! words (nothing is taken that `encode` would not write); and the store
//! over two sectors of such contents loads the newer valid one.
#![no_main]

use libfuzzer_sys::fuzz_target;
use paperbot::control::settings::{decode, encode, FlashSettings, MemoryFlash, Record, SettingsStore, RECORD_WORDS};

/// A record from the bytes (little-endian words; missing words erased).
fn record(bytes: &[u8]) -> Record {
    let mut r = [u32::MAX; RECORD_WORDS];
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
    let mut store = FlashSettings::new(MemoryFlash { sectors: [ra, rb], power_left: None });
    let loaded = store.load().expect("the memory flash reads");
    let valid = [decode(&ra).ok(), decode(&rb).ok()];
    match (&valid, &loaded.newest) {
        ([None, None], None) => {}
        ([Some(x), None], Some(n)) | ([None, Some(x)], Some(n)) => assert_eq!(x, n),
        ([Some(x), Some(y)], Some(n)) => assert!(n == x || n == y),
        _ => panic!("loaded {:?} from {valid:?}", loaded.newest),
    }
});
