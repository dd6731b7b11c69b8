//! The firmware's functions, their calls and their stack frames, read from
//! the linked ELF's disassembly (`xtensa-lx106-elf-objdump -d`): what the
//! reach checks of [`crate::elf`] and the stack depth of [`crate::stack`]
//! walk.
//!
//! The lx106 uses the CALL0 ABI: `a1` is the stack pointer, a call is
//! `call0` (direct) or `callx0` (through a register; LLVM calls most
//! functions so, the target loaded with `l32r` just before), and a function
//! makes its frame by lowering `a1`: LLVM writes `addi a8, a1, -N; mov.n a1,
//! a8`, or for larger frames `movi a8, -N` (and `addmi`), `add.n a8, a1,
//! a8; mov.n a1, a8`; our assembly `addmi a1, a1, -256`. The reading follows
//! what each register holds through those instructions, in address order.
use std::collections::{BTreeMap, BTreeSet};
use std::ops::Range;
use std::path::Path;
use std::process::Command;

use object::{Object, ObjectSection, ObjectSymbol, SymbolKind};

use crate::image::XT_OBJDUMP;

/// The firmware's functions with their calls and frames.
pub struct Functions {
    pub by_start: BTreeMap<u32, Function>,
}

pub struct Function {
    pub name: String,
    pub calls: Vec<Call>,
    /// Bytes the function lowers the stack pointer by: the sum of every
    /// lowering its code makes, an upper bound of its frame (LLVM lowers it
    /// once, in the prologue).
    pub frame: u32,
    /// Where the code sets the stack pointer to a value the reading cannot
    /// follow (neither the stack pointer plus a known amount nor a value
    /// loaded back from memory).
    pub lost_sp: Option<u32>,
}

/// What a register holds, as the disassembly shows it.
#[derive(Clone, Copy)]
enum Reg {
    /// A constant: a literal loaded with l32r, or movi.
    Const(u32),
    /// The address of an entry of a table at that address (addx4).
    TableSlot(u32),
    /// An entry loaded from that table.
    TableEntry(u32),
    /// The stack pointer at the function's entry plus this many bytes.
    Sp(i64),
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Call {
    To(u32),
    /// An indirect call whose target the disassembly does not show.
    Unknown(u32),
}

/// The stack pointer.
const SP: &str = "a1";
/// What a call leaves unchanged (CALL0 ABI: a12..a15 are callee-saved, and
/// the stack pointer); a0 and a2..a11 hold whatever the callee left.
const CALLEE_SAVED: [&str; 5] = [SP, "a12", "a13", "a14", "a15"];

impl Functions {
    pub fn read(file: &object::File, path: &Path) -> Result<Self, String> {
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

    /// The calls and frame of each function in `extents` (start -> end,
    /// name), from `objdump -d --no-show-raw-insn` text; `word` reads the
    /// image.
    pub fn from_disassembly(
        text: &str,
        extents: &BTreeMap<u32, (u32, String)>,
        word: impl Fn(u32) -> Option<u32>,
    ) -> Self {
        let mut by_start: BTreeMap<u32, Function> = BTreeMap::new();
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
                regs.insert(SP.to_string(), Reg::Sp(0));
            }
            let body = start..*end;
            let function = by_start.entry(start).or_insert_with(|| Function {
                name: name.clone(),
                calls: Vec::new(),
                frame: 0,
                lost_sp: None,
            });
            let ops: Vec<&str> = operands.split(',').map(|o| o.split_whitespace().next().unwrap_or("")).collect();
            let op = |i: usize| ops.get(i).copied().unwrap_or("");
            let sp_before = regs.get(SP).copied();
            match mnemonic {
                "call0" | "j" => {
                    if let Some(target) = parse_hex(op(0)) {
                        // a jump inside the function is a branch, not a call
                        if mnemonic == "call0" || !body.contains(&target) {
                            function.calls.push(Call::To(target));
                        }
                    }
                }
                "callx0" | "jx" => match regs.get(op(0)).copied() {
                    Some(Reg::Const(target)) => function.calls.push(Call::To(target)),
                    // a switch: every entry of the table jumps inside the function
                    Some(Reg::TableEntry(table)) if mnemonic == "jx" && table_within(&word, table, &body) => {}
                    _ => function.calls.push(Call::Unknown(addr)),
                },
                "l32r" => set(&mut regs, op(0), parse_hex(op(1)).and_then(&word).map(Reg::Const)),
                "movi" | "movi.n" => set(&mut regs, op(0), parse_imm(op(1)).map(|v| Reg::Const(v as u32))),
                "addi" | "addi.n" | "addmi" => {
                    let value = match (regs.get(op(1)).copied(), parse_imm(op(2))) {
                        (Some(Reg::Sp(k)), Some(imm)) => Some(Reg::Sp(k + imm)),
                        (Some(Reg::Const(c)), Some(imm)) => Some(Reg::Const(c.wrapping_add(imm as u32))),
                        _ => None,
                    };
                    set(&mut regs, op(0), value);
                }
                "add" | "add.n" | "sub" => {
                    let sign = if mnemonic == "sub" { -1 } else { 1 };
                    let value = match (regs.get(op(1)).copied(), regs.get(op(2)).copied()) {
                        (Some(Reg::Sp(k)), Some(Reg::Const(c))) => Some(Reg::Sp(k + sign * i64::from(c as i32))),
                        (Some(Reg::Const(c)), Some(Reg::Sp(k))) if sign > 0 => Some(Reg::Sp(k + i64::from(c as i32))),
                        (Some(Reg::Const(a)), Some(Reg::Const(b))) => {
                            Some(Reg::Const(if sign > 0 { a.wrapping_add(b) } else { a.wrapping_sub(b) }))
                        }
                        _ => None,
                    };
                    set(&mut regs, op(0), value);
                }
                "mov" | "mov.n" => {
                    let value = regs.get(op(1)).copied();
                    set(&mut regs, op(0), value);
                }
                "or" if op(1) == op(2) => {
                    let value = regs.get(op(1)).copied();
                    set(&mut regs, op(0), value);
                }
                "addx4" => match regs.get(op(2)).copied() {
                    Some(Reg::Const(table)) => set(&mut regs, op(0), Some(Reg::TableSlot(table))),
                    _ => set(&mut regs, op(0), None),
                },
                "l32i" | "l32i.n" => match regs.get(op(1)).copied() {
                    Some(Reg::TableSlot(table)) if op(2) == "0" => set(&mut regs, op(0), Some(Reg::TableEntry(table))),
                    _ => set(&mut regs, op(0), None),
                },
                _ => {
                    if writes_first_operand(mnemonic) {
                        set(&mut regs, op(0), None);
                    }
                }
            }
            if mnemonic.starts_with("call") {
                regs.retain(|r, _| CALLEE_SAVED.contains(&r.as_str()));
            }
            if op(0) == SP && writes_first_operand(mnemonic) {
                let before = match sp_before {
                    Some(Reg::Sp(k)) => k,
                    _ => 0,
                };
                match regs.get(SP) {
                    Some(Reg::Sp(after)) => {
                        function.frame = function.frame.saturating_add(u32::try_from(before - after).unwrap_or(0));
                    }
                    // a stack pointer loaded back from memory (our exception
                    // handlers' return): taken as the entry's
                    _ if mnemonic.starts_with("l32i") => {}
                    _ => _ = function.lost_sp.get_or_insert(addr),
                }
                if !matches!(regs.get(SP), Some(Reg::Sp(_))) {
                    regs.insert(SP.to_string(), Reg::Sp(0));
                }
            }
        }
        Self { by_start }
    }

    /// The start of the function named `name`.
    pub fn start_of(&self, name: &str) -> Result<u32, String> {
        self.by_start
            .iter()
            .find(|(_, f)| f.name == name)
            .map(|(a, _)| *a)
            .ok_or_else(|| format!("{name} not found in the firmware"))
    }

    /// Every function reachable from `entry`, by address; an error for a
    /// call whose target cannot be followed.
    pub fn reach_from(&self, entry: &str) -> Result<BTreeMap<u32, String>, String> {
        let start = self.start_of(entry)?;
        let mut reached = BTreeMap::new();
        let mut todo = vec![start];
        let mut seen = BTreeSet::new();
        while let Some(addr) = todo.pop() {
            if !seen.insert(addr) {
                continue;
            }
            let Some(function) = self.by_start.get(&addr) else {
                // no function starts there: ROM (no symbols) or a bad target
                reached.insert(addr, format!("{addr:#010x}"));
                continue;
            };
            reached.insert(addr, function.name.clone());
            for call in &function.calls {
                match *call {
                    Call::To(target) => todo.push(target),
                    Call::Unknown(at) => {
                        return Err(format!(
                            "{} makes an indirect call at {at:#010x} that the check cannot follow",
                            function.name
                        ))
                    }
                }
            }
        }
        Ok(reached)
    }
}

fn set(regs: &mut BTreeMap<String, Reg>, reg: &str, value: Option<Reg>) {
    match value {
        Some(v) => _ = regs.insert(reg.to_string(), v),
        None => _ = regs.remove(reg),
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
pub fn parse_instruction(line: &str) -> Option<(u32, &str, &str)> {
    let (addr, rest) = line.trim_start().split_once(':')?;
    let addr = parse_hex(addr)?;
    let mut parts = rest.trim().splitn(2, char::is_whitespace);
    let mnemonic = parts.next().filter(|m| !m.is_empty())?;
    Some((addr, mnemonic, parts.next().unwrap_or("").trim()))
}

fn parse_hex(text: &str) -> Option<u32> {
    u32::from_str_radix(text, 16).ok()
}

/// An immediate as objdump writes it: decimal (`-64`) or, for `addmi` and
/// large `movi`s, hexadecimal of the 32-bit value (`0xfffff600` = -2560).
fn parse_imm(text: &str) -> Option<i64> {
    match text.strip_prefix("0x") {
        Some(hex) => u32::from_str_radix(hex, 16).ok().map(|v| i64::from(v as i32)),
        None => text.parse().ok(),
    }
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
            (0x4010_000c, 0xFFFF_FF50), // literal: -176
        ]);
        let text = format!("{isr}\n40100200:\tret.n\n40210000:\tret.n\n");
        Functions::from_disassembly(&text, &extents, |a| words.get(&a).copied())
    }

    fn reach(f: &Functions) -> Result<Vec<String>, String> {
        f.reach_from("isr").map(|r| r.into_values().collect())
    }

    fn frame(isr: &str) -> (u32, Option<u32>) {
        let f = sample(isr);
        let isr = &f.by_start[&0x4010_0100];
        (isr.frame, isr.lost_sp)
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
    fn a_call_clobbers_the_caller_saved_registers() {
        // a8 held helper's address before the first call, not after it
        let f = sample(
            "40100100:\tl32r\ta8, 40100000 <x>\n40100103:\tl32r\ta12, 40100004 <y>\n40100106:\tcallx0\ta8\n40100109:\tcallx0\ta12\n4010010c:\tcallx0\ta8",
        );
        let calls = &f.by_start[&0x4010_0100].calls;
        assert_eq!(calls, &[Call::To(0x4010_0200), Call::To(0x4021_0000), Call::Unknown(0x4010_010c)]);
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

    /// The prologues and epilogues of the image's own code, as
    /// `cargo fw-image`'s ELF has them.
    #[test]
    fn frames_are_read_from_the_prologues() {
        // LLVM, a small frame (__level_1_interrupt)
        let small = "40100100:\taddi\ta8, a1, -16\n40100103:\tmov.n\ta1, a8\n40100105:\ts32i.n\ta0, a1, 0\n40100107:\taddi\ta8, a1, 16\n4010010a:\tmov.n\ta1, a8\n4010010c:\tret.n";
        assert_eq!(frame(small), (16, None));
        // LLVM, a large one: movi and addmi, then add.n (2,368 bytes)
        let large = "40100100:\tmovi\ta8, 192\n40100103:\taddmi\ta8, a8, 0xfffff600\n40100106:\tadd.n\ta8, a1, a8\n40100108:\tmov.n\ta1, a8\n4010010a:\tmovi.n\ta8, 64\n4010010c:\taddmi\ta8, a8, 0x900\n4010010f:\tadd.n\ta8, a1, a8\n40100111:\tmov.n\ta1, a8\n40100113:\tret.n";
        assert_eq!(frame(large), (2_368, None));
        // a literal's amount (-176), and an epilogue's increase is not a frame
        let literal = "40100100:\tl32r\ta9, 4010000c <x>\n40100103:\tadd.n\ta8, a1, a9\n40100105:\tmov.n\ta1, a8\n40100107:\taddi\ta8, a1, 127\n4010010a:\tmov.n\ta1, a8";
        assert_eq!(frame(literal), (176, None));
        // our assembly's exception entry: addmi on a1 itself, sp loaded back
        let naked = "40100100:\tmov.n\ta0, a1\n40100102:\taddmi\ta1, a1, 0xffffff00\n40100105:\ts32i.n\ta0, a1, 12\n40100107:\tl32i.n\ta1, a1, 12\n40100109:\trfe";
        assert_eq!(frame(naked), (256, None));
    }

    #[test]
    fn two_lowerings_add_up() {
        // a second prologue after an epilogue (not LLVM's shape): both count
        let twice = "40100100:\taddi\ta8, a1, -32\n40100103:\tmov.n\ta1, a8\n40100105:\taddi\ta8, a1, 32\n40100108:\tmov.n\ta1, a8\n4010010a:\tret.n\n4010010c:\taddi\ta8, a1, -48\n4010010f:\tmov.n\ta1, a8";
        assert_eq!(frame(twice), (80, None));
    }

    #[test]
    fn a_stack_pointer_the_reading_cannot_follow_is_reported() {
        // a1 from a register whose value is unknown (a call's result)
        let lost = "40100100:\tl32r\ta8, 40100000 <x>\n40100103:\tcallx0\ta8\n40100106:\tsub\ta8, a1, a2\n40100109:\tmov.n\ta1, a8";
        assert_eq!(frame(lost), (0, Some(0x4010_0109)));
        // a1 moved by a register that a call clobbered
        let clobbered = "40100100:\tmovi\ta9, -64\n40100103:\tcall0\t40100200 <helper>\n40100106:\tadd.n\ta1, a1, a9";
        assert_eq!(frame(clobbered), (0, Some(0x4010_0106)));
    }
}
