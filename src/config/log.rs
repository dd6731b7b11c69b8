//! The on-board log (`control::log`): telemetry rows kept in RAM during a
//! mission, dumped with `dump`.

/// Rows kept (a ring: when it is full the oldest row goes and is
/// counted as dropped). 60 bytes each, in the firmware's DRAM budget
/// (24 KiB, of which the rest of the firmware takes about 12.7 KB): 196
/// rows are 11,760 B, 49 s at 4 Hz (200 until issue #29's `goto` that
/// waits for a localization took two rows' 120 B, and its refinement of
/// the localization's fix, `model::locate::refine`, two more: its code's
/// constant tables, 152 B of .rodata).
pub const ROWS: usize = 196;
/// Rows per second at boot (`log <Hz>` changes it, 0 = off): a row
/// every 250 ms is every 40 mm at 0.15 m/s.
pub const HZ: u16 = 4;
/// Rows written per loop tick while dumping: one row (about 110 bytes)
/// every 10 ms is 11 kB/s, what the UART carries (115200 baud).
pub const DUMP_ROWS_PER_TICK: u8 = 1;
