//! `cargo fw-image`: the firmware for the ESP8266 built with upstream
//! nightly (the dated one named in `xtensa/nightly`), linked, checked, and
//! written as the images esptool flashes, with the module's flash
//! parameters in the boot image's header.
//!
//! 1. `cargo fetch`, then the registry crates with assembly rewritten
//!    ([`crate::patch`]) under `target/image/crates/`;
//! 2. `xtensa/asm/*.S` assembled with GNU as;
//! 3. `cargo +<xtensa/nightly> build` of `src/bin/firmware.rs` for
//!    `xtensa/xtensa-esp8266-none-elf.json` with the rewritten crates
//!    patched in, linked through `xtensa/xt-link.sh` (GNU as, the literal
//!    fix) with our `memory.x`, `exception.x` and `rom-functions.x`;
//! 4. the checks of [`crate::elf`] (entry point, undefined symbols,
//!    vectors, interrupt code in IRAM, the stack's depth, budgets), each
//!    failing the build, and the stack check's negative test (a deeper
//!    copy of the image it must refuse, [`crate::stack::refuses_deeper`]);
//! 5. esptool's `elf2image` with the flash parameters, and `image-info`,
//!    which must report them ([`crate::esptool`]).
use std::fs;
use std::path::{Path, PathBuf};
use std::process::Command;

use crate::esptool::FlashParams;
use crate::{elf, esptool, patch, stack};

const USAGE: &str = "\
usage: cargo fw-image [--clippy] [--flash-mode M] [--flash-freq F] [--flash-size S]

Builds src/bin/firmware.rs for the ESP8266 with the dated upstream nightly
named in xtensa/nightly and writes
  target/image/paperbot.elf          the linked firmware
  target/image/paperbot-0x00000.bin  the boot image (flash offset 0x00000)
  target/image/paperbot-0x10000.bin  the flash-mapped code (offset 0x10000)
then checks the ELF and prints the memory and stack budgets.

  --clippy        first run clippy (the panic lints) on the board code and
                  the firmware, for the same target, warnings as errors
  --flash-mode M  the flash mode the ROM boots with: qio, qout, dio, dout
                  (default dio: the NodeMCU's ESP-12E boots only with dio)
  --flash-freq F  the flash clock: 40m, 26m, 20m, 80m (default 40m)
  --flash-size S  the module's flash: 512KB, 1MB, 2MB, 4MB, ... (default
                  4MB, the ESP-12E's)
The three go into the boot image's header; esptool image-info must report
them, or the build fails.

Needs: rustup's nightly of xtensa/nightly with rust-src; Debian packages
gcc-xtensa-lx106 binutils-xtensa-lx106; python3 with venv (esptool comes
from PyPI).";

/// The tools the build calls, by name (PATH).
pub const XT_GCC: &str = "xtensa-lx106-elf-gcc";
pub const XT_OBJDUMP: &str = "xtensa-lx106-elf-objdump";

/// The dated nightly the image is built with (`xtensa/nightly`, one line:
/// the link wrapper and the literal fix are written for its output).
pub fn nightly(root: &Path) -> Result<String, String> {
    let path = root.join("xtensa/nightly");
    let text = fs::read_to_string(&path).map_err(|e| format!("{}: {e}", path.display()))?;
    let name = text.trim();
    if !name.starts_with("nightly-") || name.contains(char::is_whitespace) {
        return Err(format!("{}: '{name}' is not a dated nightly (nightly-YYYY-MM-DD)", path.display()));
    }
    Ok(name.to_string())
}

pub fn main(args: &[String]) -> Result<(), String> {
    let mut clippy = false;
    let mut flash = FlashParams::default();
    let mut it = args.iter();
    while let Some(arg) = it.next() {
        let mut value = || it.next().cloned().ok_or_else(|| format!("{arg} needs a value\n{USAGE}"));
        match arg.as_str() {
            "--clippy" => clippy = true,
            "--flash-mode" => flash.mode = value()?,
            "--flash-freq" => flash.freq = value()?,
            "--flash-size" => flash.size = value()?,
            "--help" | "-h" => {
                println!("{USAGE}");
                return Ok(());
            }
            other => return Err(format!("unknown option '{other}'\n{USAGE}")),
        }
    }
    flash.validate()?;
    let root = repo_root();
    let work = root.join("target/image");
    let nightly = nightly(&root)?;
    check_tools(&nightly)?;
    fs::create_dir_all(&work).map_err(|e| format!("{}: {e}", work.display()))?;

    println!("== registry crates with assembly, rewritten (target/image/crates/)");
    run(Command::new("cargo").args(["fetch", "--quiet"]).current_dir(&root))?;
    let patched = patch::prepare(&root.join("Cargo.lock"), &work)?;
    // The build's own lockfile: the repository's versions, to which cargo
    // adds the patched path crates (the repository's stays as it is).
    fs::copy(root.join("Cargo.lock"), work.join("Cargo.lock")).map_err(|e| format!("Cargo.lock: {e}"))?;

    println!("== our assembly (xtensa/asm/)");
    let objects = assemble(&root, &work)?;

    if clippy {
        println!("== clippy on the firmware and the board code (the panic lints)");
        run_cargo(nightly_cargo(&root, &work, &nightly, &patched, &objects, "clippy").args(["--", "-D", "warnings"]))?;
    }

    println!("== cargo +{nightly} build (firmware profile, xtensa-esp8266-none-elf)");
    run_cargo(&mut nightly_cargo(&root, &work, &nightly, &patched, &objects, "build"))?;
    let built = work.join("build/xtensa-esp8266-none-elf/firmware/firmware");
    let elf_path = work.join("paperbot.elf");
    fs::copy(&built, &elf_path).map_err(|e| format!("{}: {e}", built.display()))?;

    println!("== checks ({})", rel(&root, &elf_path));
    let report = elf::check(&elf_path)?;
    print!("{report}");
    println!("  {}", stack::refuses_deeper(&elf_path, &work.join("paperbot-deeper.elf"))?);

    println!("== esptool");
    esptool::write_images(&root, &elf_path, &work.join("paperbot-"), &flash)?;
    println!(
        "\nflash with:\n  esptool --chip esp8266 write-flash --flash-mode {} --flash-freq {} --flash-size {} \\\n    0x00000 target/image/paperbot-0x00000.bin 0x10000 target/image/paperbot-0x10000.bin",
        flash.mode, flash.freq, flash.size
    );
    Ok(())
}

/// `fw-check [ELF]`: the checks of [`crate::elf`] on an ELF already built
/// (`target/image/paperbot.elf` unless named), without building.
pub fn check_only(args: &[String]) -> Result<(), String> {
    let elf_path = match args {
        [] => repo_root().join("target/image/paperbot.elf"),
        [path] if !path.starts_with('-') => PathBuf::from(path),
        _ => return Err("usage: fw-check [ELF]".into()),
    };
    print!("{}", elf::check(&elf_path)?);
    let copy = elf_path.with_file_name("paperbot-deeper.elf");
    println!("  {}", stack::refuses_deeper(&elf_path, &copy)?);
    Ok(())
}

/// The repository (xtask/ is one level below it).
pub fn repo_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).parent().map(Path::to_path_buf).unwrap_or_default()
}

fn rel(root: &Path, path: &Path) -> String {
    path.strip_prefix(root).unwrap_or(path).display().to_string()
}

fn check_tools(nightly: &str) -> Result<(), String> {
    for tool in [XT_GCC, XT_OBJDUMP] {
        if Command::new(tool).arg("--version").output().is_err() {
            return Err(format!("{tool} not found: apt-get install gcc-xtensa-lx106 binutils-xtensa-lx106"));
        }
    }
    let sysroot = Command::new("rustc").arg(format!("+{nightly}")).args(["--print", "sysroot"]).output();
    let has_src = sysroot.ok().filter(|o| o.status.success()).is_some_and(|o| {
        Path::new(String::from_utf8_lossy(&o.stdout).trim()).join("lib/rustlib/src/rust/library/core").is_dir()
    });
    if !has_src {
        return Err(format!(
            "{nightly} with rust-src needed (xtensa/nightly): rustup toolchain install {nightly} --profile minimal --component rust-src,clippy"
        ));
    }
    Ok(())
}

/// Each `xtensa/asm/*.S` to an object in `work/asm/`.
fn assemble(root: &Path, work: &Path) -> Result<Vec<PathBuf>, String> {
    let src_dir = root.join("xtensa/asm");
    let out_dir = work.join("asm");
    fs::create_dir_all(&out_dir).map_err(|e| format!("{}: {e}", out_dir.display()))?;
    let mut sources: Vec<PathBuf> = fs::read_dir(&src_dir)
        .map_err(|e| format!("{}: {e}", src_dir.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|e| e == "S"))
        .collect();
    sources.sort();
    let mut objects = Vec::new();
    for src in sources {
        let obj = out_dir.join(src.file_stem().unwrap_or_default()).with_extension("o");
        run(Command::new(XT_GCC).args(["-c", "-x", "assembler-with-cpp"]).arg(&src).arg("-o").arg(&obj))?;
        println!("  {}", rel(root, &src));
        objects.push(obj);
    }
    Ok(objects)
}

/// `cargo +<nightly> <verb>` of the firmware with everything the image needs
/// passed on the command line, so that the repository's own files stay as
/// the esp toolchain reads them.
fn nightly_cargo(
    root: &Path,
    work: &Path,
    nightly: &str,
    patched: &[patch::Patched],
    objects: &[PathBuf],
    verb: &str,
) -> Command {
    let lock = work.join("Cargo.lock");
    let target = root.join("xtensa/xtensa-esp8266-none-elf.json");
    let link_args: Vec<String> = objects.iter().map(|o| format!("\"-C\", \"link-arg={}\"", o.display())).collect();

    let mut cmd = Command::new("cargo");
    cmd.current_dir(root); // GNU ld finds memory.x, exception.x, rom-functions.x here
    for var in ["RUSTUP_TOOLCHAIN", "RUSTC", "RUSTDOC", "RUSTC_WRAPPER", "RUSTFLAGS", "CARGO_TARGET_DIR", "CARGO"] {
        cmd.env_remove(var);
    }
    cmd.arg(format!("+{nightly}"))
        .args([verb, "-Zbuild-std=core", "-Zjson-target-spec", "-Zprofile-rustflags"])
        .args(["--profile", "firmware", "--features", "firmware", "--bin", "firmware"])
        .arg("--target")
        .arg(&target)
        .arg("--target-dir")
        .arg(work.join("build"));
    let mut config = vec![format!("resolver.lockfile-path=\"{}\"", lock.display())];
    // The firmware calls our assembly (xtensa/asm/) where the esp toolchain
    // would take inline `asm!` (src/board/esp8266.rs).
    let mut rustflags = vec!["\"--cfg\", \"paperbot_asm_objects\"".to_string()];
    if verb == "build" {
        // xt-link.sh assembles the LLVM assembly of the (fat-LTO, one
        // codegen unit) firmware and of compiler_builtins with GNU as.
        config.push("profile.firmware.package.paperbot.rustflags=[\"--emit=asm,link\"]".into());
        config.push("profile.firmware.package.compiler_builtins.rustflags=[\"--emit=asm,link\"]".into());
        config.push(format!("target.xtensa-esp8266-none-elf.linker=\"{}\"", root.join("xtensa/xt-link.sh").display()));
        rustflags.extend(link_args);
    }
    config.push(format!("target.xtensa-esp8266-none-elf.rustflags=[{}]", rustflags.join(", ")));
    for p in patched {
        config.push(format!("patch.crates-io.{}.path=\"{}\"", p.name, p.dir.display()));
        // path crates are linted like ours; these are not ours
        config.push(format!("profile.firmware.package.{}.rustflags=[\"--cap-lints\", \"allow\"]", p.name));
    }
    for c in config {
        cmd.arg("--config").arg(c);
    }
    cmd
}

/// Runs cargo with its messages passed through, but for the warning that
/// the patches are unused: -Zbuild-std resolves the standard library's own
/// workspace with the same `[patch]` table, where those crates are not.
fn run_cargo(cmd: &mut Command) -> Result<(), String> {
    use std::io::BufRead as _;
    let mut child = cmd.stderr(std::process::Stdio::piped()).spawn().map_err(|e| format!("cargo: {e}"))?;
    let mut skipping = false;
    if let Some(stderr) = child.stderr.take() {
        for line in std::io::BufReader::new(stderr).lines().map_while(Result::ok) {
            if line.starts_with("warning: patch `") && line.ends_with("was not used in the crate graph") {
                skipping = true;
                continue;
            }
            // the help text under those warnings is indented
            if skipping && (line.starts_with("help:") || line.starts_with("      ")) {
                continue;
            }
            skipping = false;
            eprintln!("{line}");
        }
    }
    let status = child.wait().map_err(|e| format!("cargo: {e}"))?;
    if status.success() {
        Ok(())
    } else {
        Err(format!("cargo {:?} failed ({status})", cmd.get_args().collect::<Vec<_>>()))
    }
}

/// Runs a command, its output passed through; an error if it fails.
pub fn run(cmd: &mut Command) -> Result<(), String> {
    let status = cmd.status().map_err(|e| format!("{:?}: {e}", cmd.get_program()))?;
    if status.success() {
        Ok(())
    } else {
        Err(format!("{:?} {:?} failed ({status})", cmd.get_program(), cmd.get_args().collect::<Vec<_>>()))
    }
}
