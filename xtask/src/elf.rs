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
//! - the stack's worst-case depth within its budget, above the ROM's flash
//!   parameters ([`crate::stack`]);
//! - the memory budget;
//! - the flash-mapped code ends before the settings sectors
//!   (`src/config/settings.rs`, included here as it is).
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::ops::Range;
use std::path::Path;

use object::{Object, ObjectSection, ObjectSymbol, SectionFlags};

use crate::callgraph::Functions;
use crate::stack;

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

    match stack::check(&functions) {
        Ok(lines) => report.push_str(&lines),
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

#[cfg(test)]
mod tests {
    use super::*;

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
