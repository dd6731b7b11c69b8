//! The deepest the firmware's stack can go, read from the linked image,
//! against the room the ROM leaves it.
//!
//! The firmware runs on the stack the ROM hands it: SP starts just below
//! the top of DRAM and grows down over the ROM's own data, where the
//! parameters of the flash chip lie that the ROM's `SPIRead`, `SPIWrite`
//! and `SPIEraseSector` read (the firmware calls them for its settings and
//! its kept log). A deeper stack overwrites them, and the next flash write
//! goes wherever the damaged parameters say. Nothing on the chip would
//! notice, and the emulated board's ROM routines do not read them.
//!
//! The bound is static: every function's frame ([`crate::callgraph`]), the
//! deepest chain of calls from the reset entry, plus the deepest chain from
//! the level-1 interrupt's vector on top of it (an interrupt can arrive at
//! any point of that chain), plus the ROM routines' own frames
//! ([`ROM_ROUTINES`]). What the reading of calls cannot show is named here,
//! each with its reason: calls through trait objects ([`DYN_CALLS`],
//! [`FMT_DEPTH`]), functions that call themselves ([`RECURSION`]), and the
//! ways to a reset the walk stops at ([`TERMINAL`]). Any other call it
//! cannot follow, cycle of calls, or stack pointer it cannot follow fails
//! the check: the bound would not be one.
//!
//! The ROM data between the stack's top and its flash parameters (its UART
//! state `UartDev` at 0x3FFFDE10, its AES tables from 0x3FFFCCF0,
//! `eagle.rom.addr.v6.ld`) lies under the firmware's deepest stack: the
//! firmware uses none of it (its own UART driver, no ROM AES).
use std::collections::BTreeMap;
use std::fmt::Write as _;

use crate::callgraph::{Call, Functions};

mod deeper;
pub use deeper::refuses_deeper;

/// Where SP stands when the image's entry runs: the ROM's `_start` sets SP
/// to 0x40000000, the top of DRAM, and calls `main`, which makes a 16-byte
/// frame and calls the image's entry from it (the ESP8266 mask ROM's
/// disassembly, esp-open-bootrom's `bootrom.s`: `_start` at 0x4000042c,
/// `main` at 0x40000fec, `addi sp, sp, -16`, the entry's `callx0` at
/// 0x400010fd; the addresses as Espressif's `eagle.rom.addr.v6.ld` names
/// them). memory.x's `_stack_end_cpu0` and the emulated board's ROM
/// (emu/rom/reset.S) use the same value.
pub const STACK_TOP: u32 = 0x3FFF_FFF0;

/// `flashchip` (`eagle.rom.addr.v6.ld`, ESP8266 NONOS SDK): a pointer to
/// the flash chip's parameters, which the ROM's SPI routines load first
/// (`l32r a2, 0x3fffc714; l32i a2, a2, 0` in `SPIRead`, bootrom.s); the
/// NONOS SDK's `spi_flash.h` declares it a pointer to `SpiFlashChip` in the
/// ROM's RAM.
pub const FLASHCHIP: u32 = 0x3FFF_C714;
/// The table it points to, which the ROM puts right after the pointer
/// (public notes on the ROM: a bootloader's rom.h, a 24-byte table "pointed
/// to by a pointer at 3FFFC714", by default "the next 6 words"; P.
/// Finlayson, "ESP8266 16MB Flash Handling", 2016: the structure at
/// 0x3fffc718): `SpiFlashChip`, six `uint32`: deviceId, chip_size,
/// block_size, sector_size, page_size, status_mask (`spi_flash.h`).
pub const FLASHCHIP_TABLE: u32 = FLASHCHIP + 4;
/// `sizeof(SpiFlashChip)`.
pub const SPI_FLASH_CHIP_BYTES: u32 = 6 * 4;
/// The lowest address the stack may reach: just above the table.
pub const STACK_FLOOR: u32 = FLASHCHIP_TABLE + SPI_FLASH_CHIP_BYTES;

/// The margin below which the depth may not come to the floor, bytes
/// (`config::board`, included here as it is).
#[allow(dead_code)]
#[path = "../../src/config/board.rs"]
mod board;

/// The ROM routines the image calls (rom-functions.x, at their ROM
/// addresses) and the most stack each takes, bytes: the sum of the frames
/// along its deepest chain of calls in the ROM's disassembly (esp-open-
/// bootrom's `bootrom.s`: `addi sp, sp, -N`, or `movi a6, N; sub sp, sp, a6`
/// in the 64-bit divisions). memcpy, memmove, memset and memcmp make no
/// frame and call nothing.
pub const ROM_ROUTINES: [(&str, u32, u32); 11] = [
    ("memcpy", 0x4000_df48, 0),
    ("memmove", 0x4000_e04c, 0),
    ("memset", 0x4000_e190, 0),
    ("memcmp", 0x4000_dea8, 0),
    // 48, then __umulsidi3's 32
    ("__muldi3", 0x4000_0650, 80),
    // 192, then __umulsidi3's 32 (its __udivsi3 and __umodsi3 make none)
    ("__udivdi3", 0x4000_d310, 224),
    // 176, then __umulsidi3's 32
    ("__umoddi3", 0x4000_d770, 208),
    // 240, then __umulsidi3's 32
    ("__divdi3", 0x4000_ce60, 272),
    // 16, SPI_read_data 16, Wait_SPI_Idle 16 (SPI_read_status none)
    ("SPIRead", 0x4000_4b1c, 48),
    // 48, SPI_page_program 32, SPI_write_enable 16, Wait_SPI_Idle 16
    ("SPIWrite", 0x4000_4a4c, 112),
    // 16, SPI_write_enable or SPI_sector_erase 16, Wait_SPI_Idle 16
    ("SPIEraseSector", 0x4000_4a00, 48),
];

/// What the check walks from: the reset entry (esp8266-hal's
/// `ESP8266Reset`, the ELF's entry), and on top of its deepest point the
/// user exception vector, where the lx106 takes level-1 interrupts
/// (exception.x). While a level-1 interrupt is handled PS.EXCM is set, so
/// no second one nests in it; an exception there is a double exception,
/// whose handler panics. The NMI, debug and kernel vectors' handlers panic
/// too (exception.x: `__default_exception`): see [`TERMINAL`].
pub const THREAD_ENTRY: &str = "ESP8266Reset";
pub const INTERRUPT_ENTRY: &str = "_UserExceptionVector";

/// Where the walk stops: the ways to a reset. `halt` (src/board/halt.rs)
/// stops the servo pulses, prints why and resets through the watchdog, and
/// the panic handler goes there (every panic through `panic_fmt`). No flash
/// routine runs after them, and the ROM sets up its flash parameters
/// again at the reset, so their stack may go deeper; it is not bounded
/// here (core::fmt formats through trait objects, recursively).
pub const TERMINAL: [&str; 2] = ["paperbot::board::halt::halt", "core::panicking::panic_fmt"];

/// Calls through a trait object that the disassembly cannot follow (the
/// method's address comes from a vtable through the callers' data): the
/// function that makes them, and the trait method called. Such a call goes
/// to one of the image's implementations of that method (a vtable holds
/// its trait's methods), each of which the walk follows. Any other call
/// the reading cannot follow fails the check.
pub const DYN_CALLS: [(&str, &str); 1] = [(
    "<paperbot::control::protocol::number::Cursor>::flush",
    " as paperbot::control::protocol::number::TextOut>::put_ascii",
)];

/// Functions that call themselves, and how many times one may be on a chain
/// at once (src/control/protocol/command.rs); any other cycle of calls
/// fails the check.
/// - `format_command` formats a mission step's command in the `mission
///   add` line, and a step's command is never a mission command
///   (`Step::command`, src/control/mission.rs): twice.
/// - `parse` parses what follows `mission add` as a command line of its
///   own, which may start with `mission add` again: each level takes 12
///   bytes (`mission add `) of a line of at most [`MAX_LINE`] bytes.
/// - the survey's `search`, `searched` and `turn` (src/control/survey.rs):
///   a failed search asks for another turn, and a turn with no room left
///   sets `cut_short` and searches, whose failure then ends the survey
///   (`last_view`): `turn` once on a chain, the other two twice.
pub const RECURSION: [(&str, usize); 5] = [
    ("paperbot::control::protocol::command::format_command", 2),
    ("paperbot::control::protocol::command::parse", 1 + (MAX_LINE + 1) / "mission add ".len()),
    ("<paperbot::control::survey::Survey>::search", 2),
    ("<paperbot::control::survey::Survey>::searched", 2),
    ("<paperbot::control::survey::Survey>::turn", 1),
];

/// `config::serial::MAX_LINE`, the longest command line (a test reads it
/// from src/config/serial.rs).
pub const MAX_LINE: usize = 64;

/// core::fmt, the other user of trait objects: `Formatter` writes through
/// `&mut dyn Write`, `Arguments` call `<T as Display>::fmt` and the like
/// through function pointers, the debug builders hold `&dyn Debug`. An
/// indirect call the reading cannot follow in a function of core::fmt or in
/// an implementation of one of its traits goes to one of the image's
/// implementations of core::fmt's traits (the names `<T as core::fmt::..>`).
/// Formatting recurses as deep as the values formatted nest (a `Debug`
/// formats its fields through `&dyn Debug`), which the calls do not show:
/// the walk follows chains of at most this many core::fmt functions. The
/// firmware formats on its own paths only the bring-up lines
/// (src/bin/firmware.rs: `Result`s of sensor and bus errors, about ten
/// core::fmt calls deep).
pub const FMT_DEPTH: u32 = 16;

/// A function of core::fmt or an implementation of one of its traits.
fn is_fmt(name: &str) -> bool {
    name.starts_with("core::fmt::") || name.starts_with("<core::fmt::") || name.contains(" as core::fmt::")
}

/// An implementation of one of core::fmt's traits: what its trait objects
/// may call.
fn is_fmt_impl(name: &str) -> bool {
    name.starts_with('<') && name.contains(" as core::fmt::")
}

/// One chain of calls, the deepest from its start: each function with its
/// frame, bytes.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Chain {
    pub depth: u32,
    pub frames: Vec<(String, u32)>,
}

/// The deepest chain from `entry`; an error for a call the reading cannot
/// follow, a stack pointer it cannot follow, a call into the ROM whose
/// stack use is not known, or a cycle of calls.
pub fn deepest(functions: &Functions, entry: &str) -> Result<Chain, String> {
    let start = functions.start_of(entry)?;
    let mut walk = Walk { functions, done: BTreeMap::new(), open: Vec::new(), cuts: 0 };
    walk.from(start, FMT_DEPTH)
}

struct Walk<'a> {
    functions: &'a Functions,
    /// the deepest chain from each function already walked, by the number
    /// of core::fmt functions the chain may still pass through
    done: BTreeMap<(u32, u32), Chain>,
    /// the functions on the way to the one being walked
    open: Vec<u32>,
    /// how many times a recursion was cut at its bound ([`RECURSION`])
    cuts: usize,
}

impl Walk<'_> {
    /// The deepest chain from `addr`, passing through at most `fmt_left`
    /// functions of core::fmt.
    fn from(&mut self, addr: u32, fmt_left: u32) -> Result<Chain, String> {
        let Some(function) = self.functions.by_start.get(&addr) else {
            return match ROM_ROUTINES.iter().find(|r| r.1 == addr) {
                Some(&(name, _, depth)) => Ok(Chain { depth, frames: vec![(format!("{name} (ROM)"), depth)] }),
                None => Err(format!(
                    "{} calls {addr:#010x}, where no function of the image or known ROM routine starts",
                    self.name(self.open.last().copied())
                )),
            };
        };
        if TERMINAL.contains(&function.name.as_str()) {
            return Ok(Chain { depth: 0, frames: vec![(format!("{} (not followed: a reset)", function.name), 0)] });
        }
        if let Some(at) = function.lost_sp {
            return Err(format!(
                "{} sets the stack pointer at {at:#010x} to a value the check cannot follow",
                function.name
            ));
        }
        // a recursive function's chain depends on how often it is open:
        // walked each time
        let recursion = RECURSION.iter().find(|(name, _)| *name == function.name).map(|&(_, times)| times);
        if recursion.is_none() {
            if let Some(chain) = self.done.get(&(addr, fmt_left)) {
                return Ok(chain.clone());
            }
        }
        let fmt = is_fmt(&function.name);
        if fmt && fmt_left == 0 {
            // past FMT_DEPTH: not followed
            return Ok(Chain::default());
        }
        if let Some(from) = self.open.iter().position(|&a| a == addr) {
            let open = self.open.iter().filter(|&&a| a == addr).count();
            match recursion {
                // as often as RECURSION says it recurses: not deeper
                Some(times) if open >= times => {
                    self.cuts += 1;
                    return Ok(Chain::default());
                }
                Some(_) => {}
                None if fmt => {}
                None => return Err(format!("a cycle of calls (recursion): {} -> {}", self.way(from), function.name)),
            }
        }
        self.open.push(addr);
        let cuts = self.cuts;
        let below = if fmt { fmt_left - 1 } else { fmt_left };
        let mut deepest = Chain::default();
        for call in &function.calls {
            let targets = match *call {
                Call::To(target) => vec![target],
                Call::Unknown(at) => self.dyn_targets(&function.name, at)?,
            };
            for target in targets {
                let chain = self.from(target, below)?;
                if chain.depth > deepest.depth || deepest.frames.is_empty() {
                    deepest = chain;
                }
            }
        }
        self.open.pop();
        let mut frames = vec![(function.name.clone(), function.frame)];
        frames.extend(deepest.frames);
        let chain = Chain { depth: function.frame.saturating_add(deepest.depth), frames };
        // (a chain a recursion was cut in depends on what was open)
        if recursion.is_none() && self.cuts == cuts {
            self.done.insert((addr, fmt_left), chain.clone());
        }
        Ok(chain)
    }

    /// The implementations a call through a trait object may reach
    /// ([`DYN_CALLS`], and core::fmt's: [`FMT_DEPTH`]).
    fn dyn_targets(&self, caller: &str, at: u32) -> Result<Vec<u32>, String> {
        let method = DYN_CALLS.iter().find(|(name, _)| *name == caller).map(|(_, m)| *m);
        let reaches = |name: &str| match method {
            Some(m) => name.starts_with('<') && name.ends_with(m),
            None => is_fmt_impl(name),
        };
        if method.is_none() && !is_fmt(caller) {
            return Err(format!(
                "{caller} makes an indirect call at {at:#010x} whose target the check cannot see (reached by {})",
                self.way(0)
            ));
        }
        let targets: Vec<u32> =
            self.functions.by_start.iter().filter(|(_, f)| reaches(&f.name)).map(|(&a, _)| a).collect();
        if targets.is_empty() {
            return Err(format!(
                "{caller} calls through a trait object at {at:#010x}, and the image has no method it may reach"
            ));
        }
        Ok(targets)
    }

    fn name(&self, addr: Option<u32>) -> &str {
        addr.and_then(|a| self.functions.by_start.get(&a)).map_or("the entry", |f| f.name.as_str())
    }

    /// The way from the entry, from the `from`th function on.
    fn way(&self, from: usize) -> String {
        let names: Vec<&str> = self.open[from.min(self.open.len())..].iter().map(|&a| self.name(Some(a))).collect();
        names.join(" -> ")
    }
}

/// The check: the deepest chain from the reset entry, the interrupt's on
/// top, against the room from [`STACK_TOP`] down to [`STACK_FLOOR`] less
/// the margin. The report names both chains, frame by frame.
pub fn check(functions: &Functions) -> Result<String, String> {
    let thread = deepest(functions, THREAD_ENTRY)?;
    let interrupt = deepest(functions, INTERRUPT_ENTRY)?;
    judge(&thread, &interrupt, budget())
}

/// The static bound of the image at `elf`, bytes: the reset entry's
/// deepest chain and the interrupt's on top (for `cargo fw-emu --sim-test`,
/// which holds the board's low-water mark against it).
pub fn worst_case(elf: &std::path::Path) -> Result<u32, String> {
    let data = std::fs::read(elf).map_err(|e| format!("{}: {e}", elf.display()))?;
    let file = object::File::parse(&*data).map_err(|e| format!("{}: {e}", elf.display()))?;
    let functions = Functions::read(&file, elf)?;
    Ok(deepest(&functions, THREAD_ENTRY)?.depth + deepest(&functions, INTERRUPT_ENTRY)?.depth)
}

/// The bytes the stack may take: from its top down to the floor, less the
/// margin.
pub fn budget() -> u32 {
    STACK_TOP - STACK_FLOOR - board::STACK_MARGIN_BYTES
}

fn judge(thread: &Chain, interrupt: &Chain, budget: u32) -> Result<String, String> {
    let depth = thread.depth.saturating_add(interrupt.depth);
    let mut report = String::new();
    let _ = writeln!(
        report,
        "  stack: worst case {depth} B ({} B from {THREAD_ENTRY}, {} B from {INTERRUPT_ENTRY} on top), budget {budget} B",
        thread.depth, interrupt.depth
    );
    let _ = writeln!(
        report,
        "    (SP {STACK_TOP:#010x} down to the ROM's flash parameters, flashchip at {FLASHCHIP:#010x} and its table up to {STACK_FLOOR:#010x}: {} B, less a margin of {} B)",
        STACK_TOP - STACK_FLOOR,
        board::STACK_MARGIN_BYTES
    );
    for (what, chain) in [("the deepest path", thread), ("then the interrupt's", interrupt)] {
        let _ = writeln!(report, "    {what}:");
        for (name, frame) in &chain.frames {
            let _ = writeln!(report, "      {frame:>6} B  {name}");
        }
    }
    if depth <= budget {
        Ok(report)
    } else {
        Err(format!(
            "{report}stack: {depth} B is over the budget of {budget} B: it reaches {:#010x}, {} B above the ROM's flash parameters (the margin is {} B)",
            STACK_TOP - depth.min(STACK_TOP),
            i64::from(STACK_TOP) - i64::from(depth) - i64::from(STACK_FLOOR),
            board::STACK_MARGIN_BYTES
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A small image: the reset entry calls `run` (a 2 KiB frame, as LLVM
    /// makes large ones), which calls `tick` and `idle` and the ROM's
    /// SPIWrite; the user vector's handler makes the 256-byte exception
    /// frame and calls the interrupt.
    const IMAGE: &str = "\
40100100:\taddi\ta8, a1, -16
40100103:\tmov.n\ta1, a8
40100105:\tl32r\ta8, 40100000 <x>
40100108:\tcallx0\ta8
40100200:\tmovi\ta8, 0
40100203:\taddmi\ta8, a8, 0xfffff800
40100206:\tadd.n\ta8, a1, a8
40100208:\tmov.n\ta1, a8
4010020a:\tl32r\ta9, 40100004 <x>
4010020d:\ts32i\ta9, a1, 0x104
40100210:\tcall0\t40100300 <idle>
40100213:\tl32i\ta8, a1, 0x104
40100216:\tcallx0\ta8
40100219:\tl32r\ta8, 40100008 <x>
4010021c:\tcallx0\ta8
4010021f:\tj\t4010020a <run+0xa>
40100300:\taddi\ta8, a1, -32
40100303:\tmov.n\ta1, a8
40100305:\taddi\ta8, a1, 32
40100308:\tmov.n\ta1, a8
4010030a:\tret.n
40100400:\taddi\ta8, a1, -96
40100403:\tmov.n\ta1, a8
40100405:\taddi\ta8, a1, 96
40100408:\tmov.n\ta1, a8
4010040a:\tret.n
40100500:\tcall0\t40100510 <handler>
40100510:\tmov.n\ta0, a1
40100512:\taddmi\ta1, a1, 0xffffff00
40100515:\tcall0\t40100300 <idle>
40100518:\tl32i\ta1, a1, 12
4010051b:\trfe
";

    fn image(text: &str) -> Functions {
        let names = [
            (0x4010_0100, THREAD_ENTRY),
            (0x4010_0200, "run"),
            (0x4010_0300, "idle"),
            (0x4010_0400, "tick"),
            (0x4010_0500, INTERRUPT_ENTRY),
            (0x4010_0510, "handler"),
        ];
        let extents = names.iter().map(|&(a, n)| (a, (a + 0x100, n.to_string()))).collect();
        let words = BTreeMap::from([
            (0x4010_0000u32, 0x4010_0200u32), // run
            (0x4010_0004, 0x4010_0400),       // tick
            (0x4010_0008, 0x4000_4a4c),       // SPIWrite, in the ROM
        ]);
        Functions::from_disassembly(text, &extents, |a| words.get(&a).copied())
    }

    fn names(chain: &Chain) -> Vec<(&str, u32)> {
        chain.frames.iter().map(|(n, f)| (n.as_str(), *f)).collect()
    }

    #[test]
    fn the_deepest_chain_adds_the_frames_on_its_way() {
        let f = image(IMAGE);
        let thread = deepest(&f, THREAD_ENTRY).unwrap();
        // run calls idle (32), tick (96: its address spilled to the frame
        // across idle's call and loaded back) and the ROM's SPIWrite (112)
        let run = &f.by_start[&0x4010_0200].calls;
        assert_eq!(run, &[Call::To(0x4010_0300), Call::To(0x4010_0400), Call::To(0x4000_4a4c)]);
        assert_eq!(names(&thread), [(THREAD_ENTRY, 16), ("run", 2048), ("SPIWrite (ROM)", 112)]);
        assert_eq!(thread.depth, 16 + 2048 + 112);
        let interrupt = deepest(&f, INTERRUPT_ENTRY).unwrap();
        assert_eq!(names(&interrupt), [(INTERRUPT_ENTRY, 0), ("handler", 256), ("idle", 32)]);
    }

    #[test]
    fn the_check_fails_past_the_budget() {
        let f = image(IMAGE);
        let (thread, interrupt) = (deepest(&f, THREAD_ENTRY).unwrap(), deepest(&f, INTERRUPT_ENTRY).unwrap());
        let depth = 16 + 2048 + 112 + 256 + 32;
        let ok = judge(&thread, &interrupt, depth).unwrap();
        assert!(ok.contains(&format!("worst case {depth} B")), "{ok}");
        assert!(ok.contains("      2048 B  run"), "{ok}");
        let over = judge(&thread, &interrupt, depth - 1).unwrap_err();
        assert!(over.contains(&format!("stack: {depth} B is over the budget of {} B", depth - 1)), "{over}");
    }

    #[test]
    fn the_budget_runs_from_the_top_to_the_rom_flash_parameters_less_the_margin() {
        // SpiFlashChip's table ends 4 + 24 bytes above flashchip
        assert_eq!(STACK_FLOOR, 0x3FFF_C730);
        assert_eq!(budget(), 0x3FFF_FFF0 - 0x3FFF_C730 - board::STACK_MARGIN_BYTES);
    }

    #[test]
    fn a_call_the_reading_cannot_follow_fails() {
        // run calls through a register loaded from memory it does not know
        let text = IMAGE.replace("40100213:\tl32i\ta8, a1, 0x104", "40100213:\tl32i\ta8, a2, 0");
        let err = deepest(&image(&text), THREAD_ENTRY).unwrap_err();
        assert!(err.contains("run makes an indirect call at 0x40100216 whose target the check cannot see"), "{err}");
        assert!(err.contains(&format!("reached by {THREAD_ENTRY} -> run")), "{err}");
    }

    #[test]
    fn a_call_into_the_rom_at_an_unknown_routine_fails() {
        let text = IMAGE.replace("40100008 <x>", "4010000c <x>");
        let f = {
            let names =
                [(0x4010_0100, THREAD_ENTRY), (0x4010_0200, "run"), (0x4010_0300, "idle"), (0x4010_0400, "tick")];
            let extents = names.iter().map(|&(a, n)| (a, (a + 0x100, n.to_string()))).collect();
            let words = BTreeMap::from([
                (0x4010_0000u32, 0x4010_0200u32),
                (0x4010_0004, 0x4010_0400),
                (0x4010_000c, 0x4000_2000), // somewhere in the ROM
            ]);
            Functions::from_disassembly(&text, &extents, |a| words.get(&a).copied())
        };
        let err = deepest(&f, THREAD_ENTRY).unwrap_err();
        assert!(
            err.contains("run calls 0x40002000, where no function of the image or known ROM routine starts"),
            "{err}"
        );
    }

    #[test]
    fn recursion_fails_unless_bounded() {
        // tick goes back to run (a tail call)
        let text = IMAGE.replace("4010040a:\tret.n", "4010040a:\tj\t40100200 <run>");
        let err = deepest(&image(&text), THREAD_ENTRY).unwrap_err();
        assert!(err.contains("a cycle of calls (recursion): run -> tick -> run"), "{err}");
    }

    #[test]
    fn a_bounded_recursion_is_walked_as_often_as_its_bound() {
        // the entry calls format_command (64 B), which calls itself
        let text = "40100100:\tcall0\t40100200 <f>\n40100200:\taddi\ta8, a1, -64\n40100203:\tmov.n\ta1, a8\n40100205:\tcall0\t40100200 <f>\n40100208:\taddi\ta8, a1, 64\n4010020b:\tmov.n\ta1, a8\n4010020d:\tret.n\n";
        let (name, times) = RECURSION[0];
        let extents = BTreeMap::from([
            (0x4010_0100, (0x4010_0200, THREAD_ENTRY.to_string())),
            (0x4010_0200, (0x4010_0300, name.to_string())),
        ]);
        let f = Functions::from_disassembly(text, &extents, |_| None);
        let chain = deepest(&f, THREAD_ENTRY).unwrap();
        assert_eq!(chain.depth, 64 * u32::try_from(times).unwrap());
        assert_eq!(chain.frames.iter().filter(|(n, _)| n == name).count(), times);
    }

    #[test]
    fn a_stack_pointer_the_reading_cannot_follow_fails() {
        let text = IMAGE.replace("40100300:\taddi\ta8, a1, -32", "40100300:\tsub\ta8, a1, a2");
        let err = deepest(&image(&text), THREAD_ENTRY).unwrap_err();
        assert!(err.contains("idle sets the stack pointer at 0x40100303"), "{err}");
    }

    #[test]
    fn halt_and_panic_are_not_followed() {
        assert_eq!(TERMINAL, ["paperbot::board::halt::halt", "core::panicking::panic_fmt"]);
    }

    #[test]
    fn the_parse_recursion_bound_follows_the_longest_command_line() {
        let serial = std::fs::read_to_string(crate::image::repo_root().join("src/config/serial.rs")).unwrap();
        assert!(serial.contains(&format!("pub const MAX_LINE: usize = {MAX_LINE};")), "config::serial::MAX_LINE moved");
        // 64 bytes hold five `mission add ` and an empty rest: six parses
        assert_eq!(RECURSION[1].1, 6);
    }
}
