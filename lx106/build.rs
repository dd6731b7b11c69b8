// Assembles asm/start.S and compiles csrc/*.c with xtensa-lx106-elf-gcc via
// the `cc` crate (C pre-linked with picolibc libm and GCC's libgcc
// soft-float, see BENCHMARKS.md "C float baseline"), and passes the linker
// script and link libraries.
use std::env;
use std::path::{Path, PathBuf};
use std::process::Command;

fn run(mut cmd: Command) -> String {
    let o = cmd.output().unwrap_or_else(|e| panic!("{cmd:?}: {e}"));
    assert!(o.status.success(), "{cmd:?} failed:\n{}", String::from_utf8_lossy(&o.stderr));
    String::from_utf8_lossy(&o.stdout).into_owned()
}

/// GCC's libgcc/config/xtensa sources, which are not part of this project:
/// fetch-libgcc-src.sh takes them from Debian's gcc-12-source (the source of
/// gcc-xtensa-lx106) into a cache directory on first use and prints that
/// directory.  Its messages (only when it fetches) go to this script's stderr
/// (shown by `cargo build -vv`; cargo would replay cargo:warning lines on
/// every later build); on failure they are the panic message.
fn libgcc_src(manifest: &Path) -> PathBuf {
    let script = manifest.join("fetch-libgcc-src.sh");
    let o = Command::new("bash").arg(&script).output().unwrap_or_else(|e| panic!("bash {}: {e}", script.display()));
    let msg = String::from_utf8_lossy(&o.stderr);
    if !o.status.success() {
        panic!("GCC libgcc Xtensa sources missing; {} failed:\n{msg}", script.display());
    }
    eprint!("{msg}");
    let dir = PathBuf::from(String::from_utf8_lossy(&o.stdout).trim());
    for f in ["lib1funcs.S", "ieee754-sf.S", "ieee754-df.S", "t-xtensa"] {
        // absolute path: a deleted/changed cache file re-runs this script
        println!("cargo:rerun-if-changed={}", dir.join(f).display());
    }
    dir
}

/// LIB1ASMFUNCS from libgcc/config/xtensa/t-xtensa: the functions that
/// libgcc assembles from lib1funcs.S, one object each (_mulsi3 ... _rsqrtdf2).
fn lib1asmfuncs(t_xtensa: &Path) -> Vec<String> {
    let text = std::fs::read_to_string(t_xtensa).unwrap_or_else(|e| panic!("{}: {e}", t_xtensa.display()));
    let text = text.replace("\\\n", " ");
    let funcs: Vec<String> = text
        .lines()
        .filter_map(|l| l.trim().strip_prefix("LIB1ASMFUNCS"))
        .filter_map(|l| {
            let l = l.trim_start();
            l.strip_prefix('=').or(l.strip_prefix("+="))
        })
        .flat_map(|l| l.split_whitespace().map(String::from))
        .collect();
    assert!(
        !funcs.is_empty() && funcs.iter().all(|f| f.starts_with('_')),
        "no LIB1ASMFUNCS list in {}",
        t_xtensa.display()
    );
    funcs
}

/// lx106 core configuration (xtensa-config.h) that Debian's gcc-xtensa-lx106
/// built its libgcc with; it installs it with the plugin headers.
fn xtensa_config_dir(gcc: &str) -> PathBuf {
    let out = run({
        let mut c = Command::new(gcc);
        c.arg("-print-file-name=plugin");
        c
    });
    let dir = PathBuf::from(out.trim()).join("include");
    let h = dir.join("xtensa-config.h");
    assert!(
        h.is_file(),
        "{} not found (it comes with Debian's gcc-xtensa-lx106): \
             apt-get install gcc-xtensa-lx106 binutils-xtensa-lx106",
        h.display()
    );
    println!("cargo:rerun-if-changed={}", h.display());
    dir
}

/// Assembles lib1funcs.S (GCC's Xtensa libgcc1 + ieee754-sf.S/ieee754-df.S)
/// from `src` once per LIB1ASMFUNCS entry with the same flags as libgcc's
/// Makefile and Debian's lx106 xtensa-config.h (`-I config`); returns the
/// archive.
fn build_libgcc1(gcc: &str, ar: &str, src: &Path, config: &Path, out: &Path) -> PathBuf {
    let mut objs = Vec::new();
    for f in lib1asmfuncs(&src.join("t-xtensa")) {
        let o = out.join(format!("libgcc{f}.o"));
        let mut cmd = Command::new(gcc);
        cmd.args(["-g", "-O2", "-mlongcalls", "-I"])
            .arg(config)
            .arg(format!("-DL{f}"))
            .args(["-x", "assembler-with-cpp", "-c"])
            .arg(src.join("lib1funcs.S"))
            .arg("-o")
            .arg(&o);
        run(cmd);
        objs.push(o);
    }
    let lib = out.join("libgcc1_xtensa.a");
    let _ = std::fs::remove_file(&lib);
    let mut cmd = Command::new(ar);
    cmd.arg("rcs").arg(&lib).args(&objs);
    run(cmd);
    lib
}

fn main() {
    if env::var("CARGO_CFG_TARGET_ARCH").as_deref() != Ok("xtensa") {
        panic!(
            "paperbot-lx106 builds only for xtensa-esp8266-none-elf: run cargo from the \
                project directory so .cargo/config.toml applies (cargo reads config \
                from the current directory, not from --manifest-path)"
        );
    }
    let manifest = PathBuf::from(env::var("CARGO_MANIFEST_DIR").unwrap());
    for f in ["link.x", "../rom-functions.x", "asm/start.S", "csrc/step_c.c", "build.rs", "fetch-libgcc-src.sh"] {
        println!("cargo:rerun-if-changed={f}");
    }
    for v in ["XT_CC", "XT_LIBGCC_CACHE", "XDG_CACHE_HOME", "HOME"] {
        println!("cargo:rerun-if-env-changed={v}");
    }
    let gcc = env::var("XT_CC").unwrap_or_else(|_| "xtensa-lx106-elf-gcc".into());
    let ar = env::var("XT_AR").unwrap_or_else(|_| "xtensa-lx106-elf-ar".into());
    // first, so that a missing piece is the first error reported
    let gcc_src = libgcc_src(&manifest);
    let xtensa_config = xtensa_config_dir(&gcc);

    cc::Build::new().compiler(&gcc).archiver(&ar).file("asm/start.S").compile("xtstart");

    // picolibc-xtensa-lx106-elf installs under /usr/lib/xtensa-lx106-elf,
    // which Debian's gcc-xtensa-lx106 does not search: give full paths.
    let pico_dir = env::var("PICOLIBC_DIR").unwrap_or_else(|_| "/usr/lib/xtensa-lx106-elf".into());
    let pico = format!("{pico_dir}/lib");
    let out = PathBuf::from(env::var("OUT_DIR").unwrap());
    let objs = cc::Build::new()
        .compiler(&gcc)
        .archiver(&ar)
        .file("csrc/step_c.c")
        .opt_level(2)
        // cc adds -fno-omit-frame-pointer when the profile has debug info;
        // that changes C codegen, so turn it off for a fair comparison.
        .force_frame_pointer(false)
        .flag(format!("--specs={pico_dir}/picolibc.specs"))
        .compile_intermediates();
    // Pre-link the C code with picolibc's libm/libc (ld -r) so that its
    // sinf/cosf are picolibc's.  Otherwise the final link resolves them to
    // the weak sinf/cosf that Rust's compiler_builtins also exports (it is
    // searched first), silently turning the "C version" into C + Rust libm.
    // The same ld -r binds the C code's soft-float calls (__addsf3, __mulsf3,
    // ...) to GCC's libgcc routines (what ESP8266 firmware runs: mask ROM +
    // toolchain libgcc) instead of compiler_builtins'.
    let libgcc1 = build_libgcc1(&gcc, &ar, &gcc_src, &xtensa_config, &out);
    let ld = env::var("XT_LD").unwrap_or_else(|_| "xtensa-lx106-elf-ld".into());
    let nm = env::var("XT_NM").unwrap_or_else(|_| "xtensa-lx106-elf-nm".into());
    let objcopy = env::var("XT_OBJCOPY").unwrap_or_else(|_| "xtensa-lx106-elf-objcopy".into());
    let prelinked = out.join("stepc_prelinked.o");
    let mut cmd = Command::new(&ld);
    cmd.arg("-r")
        .arg("-o")
        .arg(&prelinked)
        .args(&objs)
        .arg(format!("-L{pico}"))
        .args(["--start-group", "-lm", "-lc"])
        .arg(&libgcc1)
        .arg("--end-group");
    run(cmd);
    // Nothing may be left for the final link to resolve from Rust's
    // compiler_builtins / libm (e.g. __muldi3, __udivdi3: ROM routines
    // built from libgcc2.c, not in lib1funcs.S).
    let mut cmd = Command::new(&nm);
    cmd.arg("-u").arg(&prelinked);
    let undef = run(cmd);
    assert!(undef.trim().is_empty(), "C code needs symbols outside picolibc + libgcc lib1funcs:\n{undef}");
    // Rename the libgcc routines in the pre-linked object, __addsf3 ->
    // __libgcc_addsf3 etc. (definitions and the C code's references alike),
    // so they cannot clash with compiler_builtins' __addsf3, which the Rust
    // code keeps using.  src/main.rs calls a few directly for comparison.
    let mut cmd = Command::new(&nm);
    cmd.args(["-g", "--defined-only", "--format=just-symbols"]).arg(&libgcc1);
    let map: String =
        run(cmd).lines().filter(|l| l.starts_with("__")).map(|l| format!("{l} __libgcc_{}\n", &l[2..])).collect();
    let map_file = out.join("libgcc_rename.txt");
    std::fs::write(&map_file, map).unwrap();
    let mut cmd = Command::new(&objcopy);
    cmd.arg(format!("--redefine-syms={}", map_file.display())).arg(&prelinked);
    run(cmd);
    let lib = out.join("libstepc.a");
    let _ = std::fs::remove_file(&lib);
    let mut cmd = Command::new(&ar);
    cmd.arg("rcs").arg(&lib).arg(&prelinked);
    run(cmd);
    println!("cargo:rustc-link-search=native={}", out.display());
    println!("cargo:rustc-link-lib=static=stepc");

    println!("cargo:rustc-link-search=native={}", manifest.display());
    println!("cargo:rustc-link-arg=-nostartfiles");
    println!("cargo:rustc-link-arg=-Tlink.x");
    // The size probes (linked, never run) take memcpy, memset, __muldi3 and
    // the 64-bit division helpers from the ESP8266's ROM as the robot's link
    // does (../rom-functions.x,
    // INCLUDEd by the firmware's memory.x), so their figures count what the
    // robot's flash holds. The binaries QEMU runs have no ROM: they keep
    // compiler_builtins' versions.
    for bin in ["core-probe", "size-probe", "size-base"] {
        println!("cargo:rustc-link-arg-bin={bin}=-Wl,-T../rom-functions.x");
    }
    // whatever is still undefined: picolibc libc, then libgcc.  NOTE Debian's
    // lx106 libgcc lacks the soft-float/int helpers that live in the
    // ESP8266 mask ROM (__addsf3, __mulsf3, __muldi3, __udivsi3, ...); for
    // the Rust code those come from Rust's compiler_builtins (see xt-link.sh),
    // for the C code from GCC's lib1funcs.S (above).
    println!("cargo:rustc-link-arg=-L{pico}");
    println!("cargo:rustc-link-arg=-Wl,--start-group");
    println!("cargo:rustc-link-arg=-lc");
    println!("cargo:rustc-link-arg=-lgcc");
    println!("cargo:rustc-link-arg=-Wl,--end-group");
}
