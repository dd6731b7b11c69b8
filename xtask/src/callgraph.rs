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
//! a8; mov.n a1, a8`; our assembly `addmi a1, a1, -256`. Each function is
//! read by a dataflow over its branches (`flow`): what each register and
//! each word of its frame holds before each instruction, on every path.
use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;
use std::process::Command;

use object::{Object, ObjectSection, ObjectSymbol, SymbolKind};

use crate::image::XT_OBJDUMP;

mod flow;
pub use flow::parse_imm;

/// The firmware's functions with their calls and frames.
pub struct Functions {
    pub by_start: BTreeMap<u32, Function>,
}

pub struct Function {
    pub name: String,
    pub calls: Vec<Call>,
    /// Bytes the function's frame takes: the most the stack pointer stands
    /// below its value at the entry, on any path through the function.
    pub frame: u32,
    /// Where the code sets the stack pointer to a value the reading cannot
    /// follow (neither the stack pointer plus a known amount nor a value
    /// loaded back from memory).
    pub lost_sp: Option<u32>,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Call {
    To(u32),
    /// An indirect call whose target the disassembly does not show.
    Unknown(u32),
}

impl Functions {
    pub fn read(file: &object::File, path: &Path) -> Result<Self, String> {
        // Function extents from the symbol table; where a symbol has no
        // size (assembly without .size), up to the next symbol or the end
        // of its section.
        let mut starts: Vec<(u32, u32, u32, String)> = file
            .symbols()
            .filter(|s| s.kind() == SymbolKind::Text && s.is_definition())
            .filter_map(|s| {
                let addr = u32::try_from(s.address()).ok()?;
                let size = u32::try_from(s.size()).ok()?;
                let section = file.section_by_index(s.section_index()?).ok()?;
                let section_end = u32::try_from(section.address() + section.size()).ok()?;
                Some((addr, size, section_end, format!("{:#}", rustc_demangle::demangle(s.name().ok()?))))
            })
            .collect();
        starts.sort_by_key(|s| s.0);
        starts.dedup_by_key(|s| s.0);
        let mut extents: BTreeMap<u32, (u32, String)> = BTreeMap::new();
        for (i, (addr, size, section_end, name)) in starts.iter().enumerate() {
            let next = starts.get(i + 1).map_or(u32::MAX, |s| s.0).min(*section_end);
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
        let mut code: BTreeMap<u32, Vec<(u32, &str, &str)>> = BTreeMap::new();
        for line in text.lines() {
            let Some((addr, mnemonic, operands)) = parse_instruction(line) else { continue };
            let Some((&start, (end, _))) = extents.range(..=addr).next_back() else { continue };
            if addr < *end {
                // (past the end: a literal pool or padding between functions)
                code.entry(start).or_default().push((addr, mnemonic, operands));
            }
        }
        let by_start = code
            .into_iter()
            .map(|(start, insns)| {
                let (end, name) = &extents[&start];
                (start, flow::read(name, &(start..*end), &insns, &word))
            })
            .collect();
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

/// `40100230:\taddi\ta1, a1, -16` -> (address, mnemonic, operands).
pub fn parse_instruction(line: &str) -> Option<(u32, &str, &str)> {
    let (addr, rest) = line.trim_start().split_once(':')?;
    let addr = parse_hex(addr)?;
    let mut parts = rest.trim().splitn(2, char::is_whitespace);
    let mnemonic = parts.next().filter(|m| !m.is_empty())?;
    Some((addr, mnemonic, parts.next().unwrap_or("").trim()))
}

pub(crate) fn parse_hex(text: &str) -> Option<u32> {
    u32::from_str_radix(text, 16).ok()
}

/// Stores, branches, jumps and special-register writes read their first
/// operand; the other instructions with a register first write it.
pub(crate) fn writes_first_operand(mnemonic: &str) -> bool {
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
    fn the_frame_holds_on_a_path_past_an_early_return() {
        // an early epilogue and return, then code a branch reaches with
        // the frame still made: its own epilogue, no second frame
        let early = "40100100:\taddi\ta8, a1, -32\n40100103:\tmov.n\ta1, a8\n40100105:\tbnez.n\ta2, 40100110 <isr+0x10>\n40100107:\taddi\ta8, a1, 32\n4010010a:\tmov.n\ta1, a8\n4010010c:\tret.n\n40100110:\tl32r\ta8, 40100000 <x>\n40100113:\tcallx0\ta8\n40100116:\taddi\ta8, a1, 32\n40100119:\tmov.n\ta1, a8\n4010011b:\tret.n";
        assert_eq!(frame(early), (32, None));
        assert_eq!(sample(early).by_start[&0x4010_0100].calls, [Call::To(0x4010_0200)]);
        // code no path reaches is read knowing nothing: a frame made there
        // cannot be measured
        let unreached = "40100100:\tret.n\n40100102:\taddi\ta8, a1, -48\n40100105:\tmov.n\ta1, a8";
        assert_eq!(frame(unreached), (0, Some(0x4010_0105)));
    }

    #[test]
    fn where_two_paths_meet_a_call_goes_to_either_constant() {
        // a8 is helper on one path, in_flash on the other (with_cache_off's
        // SPIRead or SPIWrite): both are called
        let either = "40100100:\tl32r\ta8, 40100000 <x>\n40100103:\tbeqz.n\ta2, 40100108 <isr+0x8>\n40100105:\tl32r\ta8, 40100004 <y>\n40100108:\tcallx0\ta8";
        assert_eq!(sample(either).by_start[&0x4010_0100].calls, [Call::To(0x4010_0200), Call::To(0x4021_0000)]);
        // unknown on one of the paths: unknown
        let unknown = "40100100:\tl32r\ta8, 40100000 <x>\n40100103:\tbeqz.n\ta2, 40100108 <isr+0x8>\n40100105:\tl32i.n\ta8, a2, 0\n40100108:\tcallx0\ta8";
        assert_eq!(sample(unknown).by_start[&0x4010_0100].calls, [Call::Unknown(0x4010_0108)]);
    }

    #[test]
    fn a_callee_spilled_to_the_frame_is_followed() {
        // spilled, a call clobbers a9, loaded back and called
        let spilled = "40100100:\taddi\ta8, a1, -16\n40100103:\tmov.n\ta1, a8\n40100105:\tl32r\ta9, 40100000 <x>\n40100108:\ts32i.n\ta9, a1, 4\n4010010a:\tcall0\t40210000 <in_flash>\n4010010d:\tl32i.n\ta8, a1, 4\n4010010f:\tcallx0\ta8";
        assert_eq!(sample(spilled).by_start[&0x4010_0100].calls, [Call::To(0x4021_0000), Call::To(0x4010_0200)]);
        // the slot overwritten (a narrower store) before the load: unknown
        let spoiled = "40100100:\taddi\ta8, a1, -16\n40100103:\tmov.n\ta1, a8\n40100105:\tl32r\ta9, 40100000 <x>\n40100108:\ts32i.n\ta9, a1, 4\n4010010a:\ts8i\ta2, a1, 6\n4010010d:\tl32i.n\ta8, a1, 4\n4010010f:\tcallx0\ta8";
        assert_eq!(sample(spoiled).by_start[&0x4010_0100].calls, [Call::Unknown(0x4010_010f)]);
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
