//! The stack check's negative test on the real image, run by `cargo
//! fw-image` after the check passes: a copy of the image whose largest frame
//! on the deepest path is made larger than the room left must fail the
//! check, deeper by exactly what was added. The copy differs in one byte:
//! the immediate of the `addmi` with which that function's prologue makes
//! its frame (RRI8: op0 = 2, r = 0xD, the third byte the immediate in units
//! of 256 bytes; Xtensa ISA, ADDMI).
use std::fs;
use std::path::Path;
use std::process::Command;

use object::{Object, ObjectSection};

use super::{budget, deepest, INTERRUPT_ENTRY, THREAD_ENTRY};
use crate::callgraph::{parse_instruction, Functions};
use crate::image::XT_OBJDUMP;

/// Writes the deeper copy of `elf` to `copy`, checks it, and says how it
/// failed; an error if it passes or fails otherwise.
pub fn refuses_deeper(elf: &Path, copy: &Path) -> Result<String, String> {
    let data = fs::read(elf).map_err(|e| format!("{}: {e}", elf.display()))?;
    let (depth, largest) = {
        let file = object::File::parse(&*data).map_err(|e| format!("{}: {e}", elf.display()))?;
        let functions = Functions::read(&file, elf)?;
        let thread = deepest(&functions, THREAD_ENTRY)?;
        let depth = thread.depth + deepest(&functions, INTERRUPT_ENTRY)?.depth;
        let largest = thread.frames.iter().max_by_key(|f| f.1).map(|f| f.0.clone()).unwrap_or_default();
        let start = functions.start_of(&largest)?;
        (depth, (largest, start))
    };
    let (name, start) = largest;
    let file = object::File::parse(&*data).map_err(|e| format!("{}: {e}", elf.display()))?;
    let (addr, imm) = prologue_addmi(elf, start).ok_or(format!("{name}: no addmi making its frame in its prologue"))?;
    let section = file
        .sections()
        .find(|s| (s.address()..s.address() + s.size()).contains(&u64::from(addr)))
        .ok_or(format!("{addr:#010x} is in no section"))?;
    let (offset, _) = section.file_range().ok_or(format!("{addr:#010x} is not in the file"))?;
    let at = usize::try_from(offset + u64::from(addr) - section.address()).map_err(|e| e.to_string())?;
    let bytes = data.get(at..at + 3).ok_or("the instruction is past the file's end")?;
    if bytes[0] & 0x0F != 2 || bytes[1] >> 4 != 0xD || i64::from(bytes[2] as i8) * 256 != imm {
        return Err(format!("{addr:#010x}: {bytes:02x?} is not the addmi objdump shows ({imm})"));
    }
    // more than the room left, in addmi's steps of 256 bytes
    let steps = budget().saturating_sub(depth) / 256 + 1;
    let patched = i8::try_from(i32::from(bytes[2] as i8) - i32::try_from(steps).unwrap_or(i32::MAX))
        .map_err(|_| format!("{name}'s frame cannot grow by {steps} x 256 B in one addmi"))?;
    let mut deeper = data.clone();
    deeper[at + 2] = patched as u8;
    fs::write(copy, &deeper).map_err(|e| format!("{}: {e}", copy.display()))?;

    let added = steps * 256;
    let want = format!("stack: {} B is over the budget", depth + added);
    match crate::elf::check(copy) {
        Ok(_) => Err(format!("{}: {name}'s frame {added} B larger passes the stack check", copy.display())),
        Err(e) if e.contains(&want) => Ok(format!(
            "stack check refuses a copy with {name}'s frame {added} B larger ({}): {} B over {} B",
            copy.file_name().and_then(|n| n.to_str()).unwrap_or(""),
            depth + added,
            budget()
        )),
        Err(e) => Err(format!(
            "{}: {name}'s frame {added} B larger fails otherwise than expected ({want}):\n{e}",
            copy.display()
        )),
    }
}

/// The first `addmi` with a negative immediate in the function at `start`
/// (its first 32 bytes), and that immediate.
fn prologue_addmi(elf: &Path, start: u32) -> Option<(u32, i64)> {
    let out = Command::new(XT_OBJDUMP)
        .args(["-d", "--no-show-raw-insn"])
        .arg(format!("--start-address={start:#x}"))
        .arg(format!("--stop-address={:#x}", start + 32))
        .arg(elf)
        .output()
        .ok()?;
    String::from_utf8_lossy(&out.stdout).lines().find_map(|line| {
        let (addr, mnemonic, operands) = parse_instruction(line)?;
        let imm = crate::callgraph::parse_imm(operands.rsplit(',').next()?.trim())?;
        (mnemonic == "addmi" && imm < 0).then_some((addr, imm))
    })
}
