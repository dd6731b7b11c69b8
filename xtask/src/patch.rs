//! The registry crates `cargo fw-image` rewrites before building, taken at
//! the versions Cargo.lock pins from cargo's registry sources, and written
//! under `target/image/crates/` (the project keeps no copy):
//!
//! - xtensa-lx and xtensa-lx-rt: their inline assembly becomes calls to
//!   `xtensa/asm/` ([`crate::rewrite`]);
//! - esp8266-hal-proc-macros: `#[ram]` puts each function in its own
//!   `.rwtext.<name>.<hash>` section instead of one shared `.rwtext`, where
//!   rustc's object writer fails on the literal fixups.
use std::fs;
use std::path::{Path, PathBuf};

use crate::rewrite;

/// How a crate is rewritten.
#[derive(Clone, Copy)]
enum How {
    /// Inline assembly to calls; the assembly symbols start with this.
    AsmToCalls(&'static str),
    /// The `#[ram]` attribute macro, one section per function.
    RamSections,
}

const CRATES: [(&str, How); 3] = [
    ("xtensa-lx", How::AsmToCalls("xtensa_lx")),
    ("xtensa-lx-rt", How::AsmToCalls("xtensa_lx_rt")),
    ("esp8266-hal-proc-macros", How::RamSections),
];

/// A rewritten crate, for `[patch.crates-io]`.
pub struct Patched {
    pub name: &'static str,
    pub dir: PathBuf,
}

/// Rewrites the crates into `work/crates/` and says what it did.
pub fn prepare(lockfile: &Path, work: &Path) -> Result<Vec<Patched>, String> {
    let lock = fs::read_to_string(lockfile).map_err(|e| format!("{}: {e}", lockfile.display()))?;
    let mut patched = Vec::new();
    for (name, how) in CRATES {
        let version = locked_version(&lock, name).ok_or_else(|| format!("{name} is not in {}", lockfile.display()))?;
        let from = registry_source(name, &version)?;
        let dir = work.join("crates").join(format!("{name}-{version}"));
        if dir.exists() {
            fs::remove_dir_all(&dir).map_err(|e| format!("{}: {e}", dir.display()))?;
        }
        copy_dir(&from, &dir)?;
        let summary = match how {
            How::AsmToCalls(prefix) => rewrite_asm_crate(&dir, prefix)?,
            How::RamSections => rewrite_ram_macro(&dir)?,
        };
        println!("  {name} {version}: {summary}");
        patched.push(Patched { name, dir });
    }
    Ok(patched)
}

/// The version of `name` in a Cargo.lock (the first, if several).
fn locked_version(lock: &str, name: &str) -> Option<String> {
    let mut lines = lock.lines();
    while let Some(line) = lines.next() {
        if line == format!("name = \"{name}\"") {
            let version = lines.next()?.strip_prefix("version = \"")?.strip_suffix('"')?;
            return Some(version.to_string());
        }
    }
    None
}

/// Where cargo unpacked `name-version` (after `cargo fetch`).
fn registry_source(name: &str, version: &str) -> Result<PathBuf, String> {
    let cargo_home = std::env::var_os("CARGO_HOME")
        .map(PathBuf::from)
        .or_else(|| std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".cargo")))
        .ok_or("neither CARGO_HOME nor HOME is set")?;
    let src = cargo_home.join("registry").join("src");
    let entries = fs::read_dir(&src).map_err(|e| format!("{}: {e} (run `cargo fetch`)", src.display()))?;
    entries
        .filter_map(Result::ok)
        .map(|index| index.path().join(format!("{name}-{version}")))
        .find(|dir| dir.join("Cargo.toml").is_file())
        .ok_or_else(|| format!("{name} {version} is not under {} (run `cargo fetch`)", src.display()))
}

fn copy_dir(from: &Path, to: &Path) -> Result<(), String> {
    fs::create_dir_all(to).map_err(|e| format!("{}: {e}", to.display()))?;
    for entry in fs::read_dir(from).map_err(|e| format!("{}: {e}", from.display()))? {
        let entry = entry.map_err(|e| e.to_string())?;
        let target = to.join(entry.file_name());
        if entry.path().is_dir() {
            copy_dir(&entry.path(), &target)?;
        } else {
            fs::copy(entry.path(), &target).map_err(|e| format!("{}: {e}", target.display()))?;
        }
    }
    Ok(())
}

/// Every `.rs` file under `dir/src`, with its module path (`interrupt`,
/// `exception_esp8266`; empty for the crate root).
fn sources(dir: &Path) -> Result<Vec<(PathBuf, String)>, String> {
    let mut found = Vec::new();
    let mut stack = vec![dir.join("src")];
    while let Some(d) = stack.pop() {
        for entry in fs::read_dir(&d).map_err(|e| format!("{}: {e}", d.display()))? {
            let path = entry.map_err(|e| e.to_string())?.path();
            if path.is_dir() {
                stack.push(path);
            } else if path.extension().is_some_and(|e| e == "rs") {
                let rel = path.strip_prefix(dir.join("src")).map_err(|e| e.to_string())?;
                let module = rel.with_extension("").to_string_lossy().replace('/', "_");
                let module = if module == "lib" { String::new() } else { module };
                found.push((path, module));
            }
        }
    }
    found.sort();
    Ok(found)
}

fn rewrite_asm_crate(dir: &Path, prefix: &str) -> Result<String, String> {
    let (mut calls, mut naked, mut global) = (0, 0, 0);
    for (path, module) in sources(dir)? {
        let text = fs::read_to_string(&path).map_err(|e| format!("{}: {e}", path.display()))?;
        let symbol_prefix = if module.is_empty() { prefix.to_string() } else { format!("{prefix}_{module}") };
        let out = rewrite::rewrite_file(&text, &symbol_prefix).map_err(|e| format!("{}: {e}", path.display()))?;
        calls += out.calls.len();
        naked += out.removed_naked.len();
        global += out.removed_global_asm;
        fs::write(&path, out.text).map_err(|e| format!("{}: {e}", path.display()))?;
    }
    Ok(format!("{calls} functions call xtensa/asm/, {naked} #[naked] functions and {global} global_asm! removed"))
}

/// Inserted after the macro's check of a function: shadows the section
/// name it is about to use with one of this function's own.
const RAM_SECTION_PER_FUNCTION: &str = "
            // paperbot fw-image: a section per function, .rwtext.<name>.<hash>
            let section_name_text = &{
                use std::hash::{Hash, Hasher};
                let mut hasher = std::collections::hash_map::DefaultHasher::new();
                quote!(#function_item).to_string().hash(&mut hasher);
                format!(\"{}.{}.{:016x}\", section_name_text, function_item.sig.ident, hasher.finish())
            };";

fn rewrite_ram_macro(dir: &Path) -> Result<String, String> {
    const ANCHOR: &str = "check_ram_function(function_item);";
    let path = dir.join("src/lib.rs");
    let text = fs::read_to_string(&path).map_err(|e| format!("{}: {e}", path.display()))?;
    if text.matches(ANCHOR).count() != 1 {
        return Err(format!("{}: expected `{ANCHOR}` once (a new version of the macro?)", path.display()));
    }
    let text = text.replace(ANCHOR, &format!("{ANCHOR}{RAM_SECTION_PER_FUNCTION}"));
    fs::write(&path, text).map_err(|e| format!("{}: {e}", path.display()))?;
    Ok("#[ram] functions get a section each".into())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_locked_version_is_the_one_after_the_name() {
        let lock = "[[package]]\nname = \"xtensa-lx-rt\"\nversion = \"0.12.0\"\n\n[[package]]\nname = \"xtensa-lx\"\nversion = \"0.7.0\"\n";
        assert_eq!(locked_version(lock, "xtensa-lx").as_deref(), Some("0.7.0"));
        assert_eq!(locked_version(lock, "xtensa-lx-rt").as_deref(), Some("0.12.0"));
        assert_eq!(locked_version(lock, "xtensa"), None);
    }
}
