//! The checks `cargo fw-image` makes on the linked firmware; each failure
//! fails the build:
//!
//! - the entry point is esp8266-hal's reset routine, in IRAM (the ROM jumps
//!   there with the flash cache off: it enables the cache and the PLL, then
//!   runs xtensa-lx-rt's `Reset`);
//! - no undefined symbol but `DefaultHandler` (memory.x's EXTERN, never called);
//! - the exception vectors where the lx106 takes them;
//! - everything reachable from the level-1 interrupt entry in IRAM or ROM:
//!   flash is mapped through a cache the flash routines switch off, so
//!   code an interrupt reaches must not be there;
//! - everything reachable from the flash routines' caller (which turns the
//!   flash cache off around the ROM's SPIRead/SPIWrite/SPIEraseSector) in
//!   IRAM or ROM, for the same reason;
//! - the memory budget;
//! - the flash-mapped code ends before the settings sectors
//!   (`src/config/settings.rs`, included here as it is).
use std::collections::{BTreeMap, BTreeSet};
use std::fmt::Write as _;
use std::ops::Range;
use std::path::Path;
use std::process::Command;

use object::{Object, ObjectSection, ObjectSymbol, SectionFlags, SymbolKind};

use crate::image::XT_OBJDUMP;

/// The ESP8266's address map (Espressif, ESP8266 Technical Reference, the
/// memory map): instruction RAM, data RAM, the mask ROM and the window
/// through which the flash is mapped.
const IRAM: Range<u32> = 0x4010_0000..0x4010_8000;
const DRAM: Range<u32> = 0x3FFE_8000..0x4000_0000;
const ROM: Range<u32> = 0x4000_0000..0x4001_0000;
const FLASH: Range<u32> = 0x4020_0000..0x4030_0000;

/// The firmware's flash map (`config::settings`): the one file, compiled
/// here too, so the check and the firmware agree.
#[allow(dead_code)]
#[path = "../../src/config/settings.rs"]
mod settings;

/// Flash offset 0 is mapped at the start of [`FLASH`] (memory.x: flash code
/// at 0x40210000 is written at offset 0x10000).
const FLASH_MAP_BASE: u32 = FLASH.start;

/// Where the lx106 takes its exceptions, from VECBASE = 0x40100000 (the
/// core's configuration, core-isa.h: XCHAL_*_VECOFS; exception.x).
const VECTORS: [(&str, u32); 5] = [
    ("_DebugExceptionVector", 0x4010_0010),
    ("_NMIExceptionVector", 0x4010_0020),
    ("_KernelExceptionVector", 0x4010_0030),
    ("_UserExceptionVector", 0x4010_0050),
    ("_DoubleExceptionVector", 0x4010_0070),
];

/// esp8266-hal's reset routine (`ESP8266Reset`, `#[ram]`): the ELF's entry
/// (memory.x's ENTRY), which the boot image's header hands the ROM.
const RESET_ROUTINE: &str = "ESP8266Reset";

/// What the interrupt-reach check walks from: the level-1 interrupt
/// handler the user vector's code calls (esp8266-hal's dispatcher).
const INTERRUPT_ENTRY: &str = "__level_1_interrupt";
/// The vector code on the way there, which must be in IRAM too.
const INTERRUPT_PATH: [&str; 4] =
    ["_UserExceptionVector", "__default_naked_exception", "save_context", "restore_context"];

/// The function that calls the ROM's flash routines with the cache off
/// (src/board/rom_flash.rs).
const CACHE_OFF_ENTRY: &str = "paperbot::board::rom_flash::with_cache_off";

/// The budgets (bytes): a quarter of IRAM, of the user's DRAM and of the
/// 1 MiB flash window, leaving room to grow and for the stack.
const BUDGETS: [(&str, u32, u32); 3] = [
    ("IRAM (vectors, RAM code)", 8 * 1024, 32 * 1024),
    ("DRAM (rodata, data, bss)", 24 * 1024, 80 * 1024),
    ("flash code", 256 * 1024, 1024 * 1024 - 64 * 1024),
];

/// Runs every check; the report says what each found.
pub fn check(path: &Path) -> Result<String, String> {
    let data = std::fs::read(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let file = object::File::parse(&*data).map_err(|e| format!("{}: {e}", path.display()))?;
    let mut report = String::new();
    let mut failures = Vec::new();

    let undefined = undefined_symbols(&file);
    if undefined.is_empty() {
        let _ = writeln!(report, "  undefined symbols: none but DefaultHandler");
    } else {
        failures.push(format!("undefined symbols: {}", undefined.join(", ")));
    }

    let symbols = symbol_addresses(&file);
    match check_entry(file.entry(), symbols.get(RESET_ROUTINE).copied()) {
        Ok(line) => {
            let _ = writeln!(report, "  {line}");
        }
        Err(e) => failures.push(e),
    }
    for (name, want) in VECTORS {
        match symbols.get(name) {
            Some(&at) if at == want => {}
            Some(&at) => failures.push(format!("{name} at {at:#010x}, the lx106 takes it at {want:#010x}")),
            None => failures.push(format!("{name} missing")),
        }
    }
    let _ = writeln!(report, "  exception vectors: debug +0x10, NMI +0x20, kernel +0x30, user +0x50, double +0x70");

    let functions = Functions::read(&file, path)?;
    match functions.reach_from(INTERRUPT_ENTRY) {
        Ok(reached) => {
            let mut outside: Vec<String> = Vec::new();
            for &name in INTERRUPT_PATH.iter() {
                if !symbols.get(name).is_some_and(|a| IRAM.contains(a)) {
                    outside.push(name.to_string());
                }
            }
            for (addr, name) in &reached {
                if !(IRAM.contains(addr) || ROM.contains(addr)) {
                    outside.push(format!("{name} at {addr:#010x}"));
                }
            }
            if outside.is_empty() {
                let _ = writeln!(
                    report,
                    "  interrupt code: {} functions reachable from {INTERRUPT_ENTRY}, all in IRAM or ROM:",
                    reached.len()
                );
                for (addr, name) in &reached {
                    let _ = writeln!(report, "    {addr:#010x} {name}");
                }
            } else {
                failures
                    .push(format!("reachable from {INTERRUPT_ENTRY} but not in IRAM or ROM: {}", outside.join(", ")));
            }
        }
        Err(e) => failures.push(e),
    }

    match functions.reach_from(CACHE_OFF_ENTRY) {
        Ok(reached) => {
            let outside: Vec<String> = reached
                .iter()
                .filter(|(addr, _)| !(IRAM.contains(addr) || ROM.contains(addr)))
                .map(|(addr, name)| format!("{name} at {addr:#010x}"))
                .collect();
            if outside.is_empty() {
                let names: Vec<&str> = reached.values().map(String::as_str).collect();
                let _ = writeln!(report, "  cache-off code: {} in IRAM or ROM", names.join(", "));
            } else {
                failures.push(format!(
                    "reachable from {CACHE_OFF_ENTRY} (the flash cache off) but not in IRAM or ROM: {}",
                    outside.join(", ")
                ));
            }
        }
        Err(e) => failures.push(e),
    }

    let used = usage(&file);
    let _ = writeln!(report, "  memory            used      budget     chip");
    for ((what, budget, chip), used) in BUDGETS.iter().zip(used) {
        let mark = if used <= *budget { "" } else { "  OVER BUDGET" };
        let _ = writeln!(report, "  {what:<26} {used:>7} B  {budget:>7} B  {chip:>7} B{mark}");
        if used > *budget {
            failures.push(format!("{what}: {used} B over the budget of {budget} B"));
        }
    }

    match check_flash_end(flash_end(&file)) {
        Ok(line) => {
            let _ = writeln!(report, "  {line}");
        }
        Err(e) => failures.push(e),
    }

    if failures.is_empty() {
        Ok(report)
    } else {
        Err(format!("{report}the firmware image fails its checks:\n  - {}", failures.join("\n  - ")))
    }
}

/// The entry must be [`RESET_ROUTINE`]'s address, in IRAM: the ROM calls it
/// before anything has enabled the flash cache.
fn check_entry(entry: u64, reset: Option<u32>) -> Result<String, String> {
    let Some(reset) = reset else {
        return Err(format!("{RESET_ROUTINE} (esp8266-hal's reset routine) not found"));
    };
    if entry != u64::from(reset) {
        return Err(format!("entry point {entry:#010x} is not {RESET_ROUTINE} ({reset:#010x})"));
    }
    if !IRAM.contains(&reset) {
        return Err(format!("entry point {RESET_ROUTINE} at {reset:#010x} is not in IRAM"));
    }
    Ok(format!("entry point: {entry:#010x} = {RESET_ROUTINE} (esp8266-hal's reset routine), in IRAM"))
}

fn undefined_symbols(file: &object::File) -> Vec<String> {
    let mut names: Vec<String> = file
        .symbols()
        .filter(|s| s.is_undefined())
        .filter_map(|s| s.name().ok().map(str::to_string))
        .filter(|n| !n.is_empty() && n != "DefaultHandler")
        .collect();
    names.sort();
    names.dedup();
    names
}

fn symbol_addresses<'a>(file: &'a object::File) -> BTreeMap<&'a str, u32> {
    file.symbols()
        .filter(|s| !s.is_undefined())
        .filter_map(|s| Some((s.name().ok()?, u32::try_from(s.address()).ok()?)))
        .collect()
}

/// Bytes of IRAM, DRAM and flash the loaded sections take.
fn usage(file: &object::File) -> [u32; 3] {
    let mut used = [0u32; 3];
    for section in file.sections() {
        let alloc = matches!(section.flags(), SectionFlags::Elf { sh_flags } if sh_flags & u64::from(object::elf::SHF_ALLOC) != 0);
        let (Ok(addr), Ok(size)) = (u32::try_from(section.address()), u32::try_from(section.size())) else { continue };
        if !alloc || size == 0 {
            continue;
        }
        let region = [&IRAM, &DRAM, &FLASH].iter().position(|r| r.contains(&addr));
        if let Some(i) = region {
            used[i] = used[i].saturating_add(size);
        }
    }
    used
}

/// The end of the flash-mapped sections, as a flash offset.
fn flash_end(file: &object::File) -> u32 {
    let mut end = 0u32;
    for section in file.sections() {
        let (Ok(addr), Ok(size)) = (u32::try_from(section.address()), u32::try_from(section.size())) else { continue };
        if FLASH.contains(&addr) {
            end = end.max(addr.saturating_add(size).saturating_sub(FLASH_MAP_BASE));
        }
    }
    end
}

/// The image must end before the kept log's slots and the settings
/// record's sectors (the lowest of them: `FIRST_SECTOR`).
fn check_flash_end(end: u32) -> Result<String, String> {
    let first = settings::FIRST_SECTOR;
    if end <= first {
        Ok(format!(
            "flash code ends at offset {end:#08x}, before the log's slots {:#08x} and {:#08x} and the settings sectors {:#08x} and {:#08x} (config::settings)",
            settings::LOG_SLOTS[0],
            settings::LOG_SLOTS[1],
            settings::SECTORS[0],
            settings::SECTORS[1]
        ))
    } else {
        Err(format!("flash code ends at offset {end:#08x}, over the log's and settings' sectors from {first:#08x}"))
    }
}

/// The firmware's functions with their calls, from the disassembly.
struct Functions {
    /// Start address -> (name, calls: callee addresses).
    by_start: BTreeMap<u32, (String, Vec<Call>)>,
}

/// What a register holds, as the disassembly shows it.
enum Reg {
    /// A literal loaded with l32r.
    Const(u32),
    /// The address of an entry of a table at that address (addx4).
    TableSlot(u32),
    /// An entry loaded from that table.
    TableEntry(u32),
}

#[derive(Clone, Copy)]
enum Call {
    To(u32),
    /// An indirect call whose target the disassembly does not show.
    Unknown(u32),
}

impl Functions {
    fn read(file: &object::File, path: &Path) -> Result<Self, String> {
        // Function extents from the symbol table; where a symbol has no
        // size (assembly without .size), up to the next symbol.
        let mut starts: Vec<(u32, u32, String)> = file
            .symbols()
            .filter(|s| s.kind() == SymbolKind::Text && s.is_definition())
            .filter_map(|s| {
                let addr = u32::try_from(s.address()).ok()?;
                let size = u32::try_from(s.size()).ok()?;
                Some((addr, size, format!("{:#}", rustc_demangle::demangle(s.name().ok()?))))
            })
            .collect();
        starts.sort_by_key(|s| s.0);
        starts.dedup_by_key(|s| s.0);
        let mut extents: BTreeMap<u32, (u32, String)> = BTreeMap::new();
        for (i, (addr, size, name)) in starts.iter().enumerate() {
            let next = starts.get(i + 1).map_or(u32::MAX, |s| s.0);
            let end = if *size > 0 { addr.saturating_add(*size).min(next) } else { next };
            extents.insert(*addr, (end, name.clone()));
        }

        let out = Command::new(XT_OBJDUMP)
            .args(["-d", "--no-show-raw-insn"])
            .arg(path)
            .output()
            .map_err(|e| format!("{XT_OBJDUMP}: {e}"))?;
        if !out.status.success() {
            return Err(format!("{XT_OBJDUMP} -d failed"));
        }
        let words = Words { file };
        Ok(Self::from_disassembly(&String::from_utf8_lossy(&out.stdout), &extents, |a| words.at(a)))
    }

    /// The calls of each function in `extents` (start -> end, name), from
    /// `objdump -d --no-show-raw-insn` text; `word` reads the image.
    fn from_disassembly(text: &str, extents: &BTreeMap<u32, (u32, String)>, word: impl Fn(u32) -> Option<u32>) -> Self {
        let mut by_start: BTreeMap<u32, (String, Vec<Call>)> = BTreeMap::new();
        // what each register holds, as far as the function's code since
        // its start shows
        let mut regs: BTreeMap<String, Reg> = BTreeMap::new();
        let mut current: Option<u32> = None;
        for line in text.lines() {
            let Some((addr, mnemonic, operands)) = parse_instruction(line) else { continue };
            let Some((&start, (end, name))) = extents.range(..=addr).next_back() else { continue };
            if addr >= *end {
                continue; // a literal pool or padding between functions
            }
            if current != Some(start) {
                current = Some(start);
                regs.clear();
            }
            let body = start..*end;
            let calls = &mut by_start.entry(start).or_insert_with(|| (name.clone(), Vec::new())).1;
            let ops: Vec<&str> = operands.split(',').map(|o| o.split_whitespace().next().unwrap_or("")).collect();
            let op = |i: usize| ops.get(i).copied().unwrap_or("");
            match mnemonic {
                "call0" | "j" => {
                    if let Some(target) = parse_hex(op(0)) {
                        // a jump inside the function is a branch, not a call
                        if mnemonic == "call0" || !body.contains(&target) {
                            calls.push(Call::To(target));
                        }
                    }
                }
                "callx0" | "jx" => match regs.get(op(0)) {
                    Some(Reg::Const(target)) => calls.push(Call::To(*target)),
                    // a switch: every entry of the table jumps inside the function
                    Some(Reg::TableEntry(table)) if mnemonic == "jx" && table_within(&word, *table, &body) => {}
                    _ => calls.push(Call::Unknown(addr)),
                },
                "l32r" => match parse_hex(op(1)).and_then(&word) {
                    Some(value) => _ = regs.insert(op(0).to_string(), Reg::Const(value)),
                    None => _ = regs.remove(op(0)),
                },
                "addx4" => match regs.get(op(2)) {
                    Some(Reg::Const(table)) => _ = regs.insert(op(0).to_string(), Reg::TableSlot(*table)),
                    _ => _ = regs.remove(op(0)),
                },
                "l32i" | "l32i.n" => match regs.get(op(1)) {
                    Some(Reg::TableSlot(table)) if op(2) == "0" => {
                        _ = regs.insert(op(0).to_string(), Reg::TableEntry(*table))
                    }
                    _ => _ = regs.remove(op(0)),
                },
                _ => {
                    if writes_first_operand(mnemonic) {
                        regs.remove(op(0));
                    }
                }
            }
        }
        Self { by_start }
    }

    /// Every function reachable from `entry`, by address; an error for a
    /// call whose target cannot be followed.
    fn reach_from(&self, entry: &str) -> Result<BTreeMap<u32, String>, String> {
        let start = self
            .by_start
            .iter()
            .find(|(_, (name, _))| name == entry)
            .map(|(a, _)| *a)
            .ok_or_else(|| format!("{entry} not found in the firmware"))?;
        let mut reached = BTreeMap::new();
        let mut todo = vec![start];
        let mut seen = BTreeSet::new();
        while let Some(addr) = todo.pop() {
            if !seen.insert(addr) {
                continue;
            }
            let Some((name, calls)) = self.by_start.get(&addr) else {
                // no function starts there: ROM (no symbols) or a bad target
                reached.insert(addr, format!("{addr:#010x}"));
                continue;
            };
            reached.insert(addr, name.clone());
            for call in calls {
                match *call {
                    Call::To(target) => todo.push(target),
                    Call::Unknown(at) => {
                        return Err(format!("{name} makes an indirect call at {at:#010x} that the check cannot follow"))
                    }
                }
            }
        }
        Ok(reached)
    }
}

/// Reads 32-bit words (literal pool entries) from the loaded sections.
struct Words<'a, 'd> {
    file: &'a object::File<'d>,
}

impl Words<'_, '_> {
    fn at(&self, addr: u32) -> Option<u32> {
        let section =
            self.file.sections().find(|s| (s.address()..s.address() + s.size()).contains(&u64::from(addr)))?;
        let data = section.data().ok()?;
        let offset = usize::try_from(u64::from(addr) - section.address()).ok()?;
        let bytes: [u8; 4] = data.get(offset..offset + 4)?.try_into().ok()?;
        Some(u32::from_le_bytes(bytes))
    }
}

/// Whether the jump table at `table` holds addresses inside `body`: its
/// entries, read until the first that is not, must be at least one.
fn table_within(word: impl Fn(u32) -> Option<u32>, table: u32, body: &Range<u32>) -> bool {
    let entries = (0u32..)
        .map_while(|i| word(table.checked_add(i.checked_mul(4)?)?))
        .take_while(|target| body.contains(target))
        .count();
    entries > 0
}

/// `40100230:\taddi\ta1, a1, -16` -> (address, mnemonic, operands).
fn parse_instruction(line: &str) -> Option<(u32, &str, &str)> {
    let (addr, rest) = line.trim_start().split_once(':')?;
    let addr = parse_hex(addr)?;
    let mut parts = rest.trim().splitn(2, char::is_whitespace);
    let mnemonic = parts.next().filter(|m| !m.is_empty())?;
    Some((addr, mnemonic, parts.next().unwrap_or("").trim()))
}

fn parse_hex(text: &str) -> Option<u32> {
    u32::from_str_radix(text, 16).ok()
}

/// Stores, branches, jumps and special-register writes read their first
/// operand; the other instructions with a register first write it.
fn writes_first_operand(mnemonic: &str) -> bool {
    let m = mnemonic.trim_end_matches(".n");
    let reads = m.starts_with('b')
        || matches!(m, "s8i" | "s16i" | "s32i" | "s32e" | "s32ri" | "s32c1i" | "wsr" | "wur" | "j" | "jx" | "ret")
        || m.starts_with("wsr.")
        || m.starts_with("call");
    !reads
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn instructions_parse_with_their_operands() {
        assert_eq!(parse_instruction("40100230:\taddi\ta1, a1, -16"), Some((0x4010_0230, "addi", "a1, a1, -16")));
        assert_eq!(
            parse_instruction("40100244:\tl32r\ta0, 40100100 <foo+0x4>"),
            Some((0x4010_0244, "l32r", "a0, 40100100 <foo+0x4>"))
        );
        assert_eq!(parse_instruction("40100250:\tret.n"), Some((0x4010_0250, "ret.n", "")));
        assert_eq!(parse_instruction("Disassembly of section .text:"), None);
    }

    /// Two functions in IRAM, one in flash, a jump table in DRAM.
    fn sample(isr: &str) -> Functions {
        let extents = BTreeMap::from([
            (0x4010_0100, (0x4010_0140, "isr".to_string())),
            (0x4010_0200, (0x4010_0210, "helper".to_string())),
            (0x4021_0000, (0x4021_0010, "in_flash".to_string())),
        ]);
        let words = BTreeMap::from([
            (0x4010_0000u32, 0x4010_0200u32), // literal: helper
            (0x4010_0004, 0x4021_0000),       // literal: in_flash
            (0x4010_0008, 0x3FFE_8000),       // literal: the jump table
            (0x3FFE_8000, 0x4010_0110),       // table entries, inside isr
            (0x3FFE_8004, 0x4010_0120),
        ]);
        let text = format!("{isr}\n40100200:\tret.n\n40210000:\tret.n\n");
        Functions::from_disassembly(&text, &extents, |a| words.get(&a).copied())
    }

    fn reach(f: &Functions) -> Result<Vec<String>, String> {
        f.reach_from("isr").map(|r| r.into_values().collect())
    }

    #[test]
    fn calls_through_literals_are_followed() {
        let f = sample("40100100:\tl32r\ta0, 40100000 <x>\n40100103:\tcallx0\ta0\n40100106:\tret.n");
        assert_eq!(reach(&f).unwrap(), ["isr", "helper"]);
        let f = sample("40100100:\tl32r\ta0, 40100004 <x>\n40100103:\tcallx0\ta0");
        assert_eq!(reach(&f).unwrap(), ["isr", "in_flash"]);
    }

    #[test]
    fn a_call_through_an_overwritten_register_cannot_be_followed() {
        let f = sample("40100100:\tl32r\ta0, 40100000 <x>\n40100103:\tl32i.n\ta0, a1, 0\n40100105:\tcallx0\ta0");
        assert!(reach(&f).unwrap_err().contains("indirect call at 0x40100105"));
    }

    #[test]
    fn a_switch_through_a_jump_table_stays_in_the_function() {
        let switch = "40100100:\tl32r\ta7, 40100008 <x>\n40100103:\taddx4\ta10, a10, a7\n40100106:\tl32i.n\ta10, a10, 0\n40100108:\tjx\ta10";
        assert_eq!(reach(&sample(switch)).unwrap(), ["isr"]);
        let not_a_table = "40100100:\tl32r\ta7, 40100000 <x>\n40100103:\taddx4\ta10, a10, a7\n40100106:\tl32i.n\ta10, a10, 0\n40100108:\tjx\ta10";
        assert!(reach(&sample(not_a_table)).is_err());
    }

    #[test]
    fn a_tail_jump_out_of_the_function_is_a_call() {
        let f = sample("40100100:\tj\t40210000 <in_flash>\n40100103:\tj\t40100100 <isr>");
        assert_eq!(reach(&f).unwrap(), ["isr", "in_flash"]);
    }

    #[test]
    fn stores_and_branches_do_not_overwrite_their_first_register() {
        assert!(!writes_first_operand("s32i.n"));
        assert!(!writes_first_operand("beqz"));
        assert!(!writes_first_operand("wsr.intenable"));
        assert!(writes_first_operand("l32i.n"));
        assert!(writes_first_operand("mov.n"));
        assert!(writes_first_operand("addi"));
    }

    #[test]
    fn the_image_must_end_before_the_logs_and_the_settings_sectors() {
        let ok = check_flash_end(0x2_0000).unwrap();
        assert!(
            ok.contains("before the log's slots 0x3f3000 and 0x3f6000 and the settings sectors 0x3f9000 and 0x3fa000")
        );
        assert!(check_flash_end(0x3F_3000).is_ok());
        assert!(check_flash_end(0x3F_3001).unwrap_err().contains("over the log's and settings' sectors from 0x3f3000"));
    }

    #[test]
    fn the_entry_must_be_the_reset_routine_in_iram() {
        assert!(check_entry(0x4010_01b4, Some(0x4010_01b4)).unwrap().contains("in IRAM"));
        assert!(check_entry(0x4021_0000, Some(0x4010_01b4)).unwrap_err().contains("is not ESP8266Reset"));
        assert!(check_entry(0x4021_0000, Some(0x4021_0000)).unwrap_err().contains("not in IRAM"));
        assert!(check_entry(0x4010_01b4, None).unwrap_err().contains("not found"));
    }
}
