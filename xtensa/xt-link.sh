#!/usr/bin/env bash
# Linker wrapper for the xtensa-esp8266-none-elf custom target, shared by
# the firmware image (`cargo fw-image`) and lx106/.
#
# WHY: rustc nightly 1.97 (LLVM 22.1) emits broken Xtensa *objects*: its
# integrated assembler puts each function's L32R literal pool at the end of
# the *previous* function's section at an unaligned offset (the ELF
# streamer's startLiteralSection() never switches to the .literal section),
# so GNU ld fails with "dangerous relocation: l32r: misaligned literal
# target".  The *assembly* LLVM prints is fine, and GNU as puts the literals
# into aligned .literal.* sections.
#
# HOW: the final crate (fat LTO, 1 codegen unit => one module holding all
# Rust code incl. core and libm) and compiler_builtins (never LTO'd) are
# built with `--emit=asm,link` (Cargo.toml, profile rustflags).  This wrapper
# assembles <crate>-<hash>.s and compiler_builtins-<hash>.s with GNU as,
# substitutes them for rustc's broken .rcgu.o / compiler_builtins rlib, and
# runs xtensa-lx106-elf-gcc as the real linker.
set -euo pipefail
GCC="${XT_CC:-xtensa-lx106-elf-gcc}"
OBJCOPY="${XT_OBJCOPY:-xtensa-lx106-elf-objcopy}"
AR="${XT_AR:-xtensa-lx106-elf-ar}"

# Before GNU as (binutils 2.40, xtensa) sees LLVM's assembly:
#  - .cfi_* directives go ("CFI is not supported for this target"; only the
#    debuggers' .debug_frame is lost);
#  - DWARF `.file N "dir" "name"` (two-string form) becomes "dir/name";
#  - literal-fix.awk moves each literal pool after its function's
#    `.section` line (LLVM prints it before).
# Several binaries of one package link in parallel and share the
# compiler_builtins object: every file is written under a unique temporary
# name and renamed into place, so a concurrent link never reads a
# half-written one.
#
# `--no-target-align`: GNU as would align branch targets to fetch words
# (fill bytes after jumps, wide forms of narrow instructions); LLVM's own
# Xtensa assembler, which the esp toolchain's build uses, does not. Without
# it both builds hold the same code; instruction counts do not change.
GAS_FLAGS=(-Wa,--no-target-align)
assemble() { # $1 = LLVM .s, $2 = output .o
  if [[ -f "$2" && "$2" -nt "$1" ]]; then return 0; fi
  local tmp="$2.$$"
  sed -e '/^[[:space:]]*\.cfi_/d' \
      -e 's|^\([[:space:]]*\.file[[:space:]]\{1,\}[0-9]\{1,\}[[:space:]]\{1,\}\)"\([^"]*\)"[[:space:]]\{1,\}"\([^"]*\)"|\1"\2/\3"|' \
      "$1" | awk -f "$(dirname "$0")/literal-fix.awk" > "$tmp.s"
  "$GCC" -c "${GAS_FLAGS[@]}" -x assembler "$tmp.s" -o "$tmp.o"
  # Embedded LLVM bitcode (.llvmbc/.llvmcmd, from embed-bitcode) makes
  # binutils' LLVM plugin claim the object, and ar/nm/ld then see no symbols.
  "$OBJCOPY" --remove-section=.llvmbc --remove-section=.llvmcmd "$tmp.o" "$tmp.clean.o"
  mv -f "$tmp.s" "${2%.o}.s"
  mv -f "$tmp.clean.o" "$2"
  rm -f "$tmp.o"
}

args=()
# expand @response files (rustc uses them only for very long command lines)
for a in "$@"; do
  if [[ "$a" == @* && -f "${a#@}" ]]; then
    while IFS= read -r line || [[ -n "$line" ]]; do args+=("$line"); done < "${a#@}"
  else
    args+=("$a")
  fi
done

out=""
for ((i = 0; i < ${#args[@]}; i++)); do
  if [[ "${args[$i]}" == "-o" ]]; then out="${args[$((i + 1))]}"; fi
done
[[ -n "$out" ]] || { echo "xt-link: no -o in linker args" >&2; exit 1; }

asm="$out.s"
if [[ ! -f "$asm" ]]; then
  echo "xt-link: $asm not found; the crate must be built with --emit=asm,link, lto=\"fat\", codegen-units=1 (see Cargo.toml)" >&2
  exit 1
fi
assemble "$asm" "$out.gas.o"

stem="$(basename "$out")."
new=()
replaced=0
# The repository's own .cargo/config.toml (a parent directory's: cargo merges
# it) adds `-nostartfiles -Wl,-Tlink.x` for the firmware; build.rs passes
# the same for this crate. GNU ld refuses a linker script given twice, so
# keep the first of each.
declare -A seen_script=()
seen_nostart=0
for a in "${args[@]}"; do
  base="$(basename -- "$a")"
  script=""
  case "$a" in -Wl,-T*) script="${a#-Wl,-T}" ;; -T?*) script="${a#-T}" ;; esac
  if [[ -n "$script" ]]; then
    [[ -n "${seen_script[$script]:-}" ]] && continue
    seen_script[$script]=1
  fi
  if [[ "$a" == -nostartfiles ]]; then
    (( seen_nostart )) && continue
    seen_nostart=1
  fi
  if [[ "$a" == *.rcgu.o && "$base" == "$stem"* ]]; then
    if (( replaced )); then
      echo "xt-link: more than one codegen unit ($a); set codegen-units = 1 and lto = \"fat\"" >&2
      exit 1
    fi
    new+=("$out.gas.o"); replaced=1
  elif [[ "$base" == libcompiler_builtins-*.rlib ]]; then
    cb="${base#lib}"; cb="$(dirname -- "$a")/${cb%.rlib}"
    if [[ ! -f "$cb.s" ]]; then
      echo "xt-link: $cb.s not found; compiler_builtins needs --emit=asm,link (Cargo.toml profile.*.package.compiler_builtins)" >&2
      exit 1
    fi
    assemble "$cb.s" "$cb.gas.o"
    # as an archive so that only referenced members are considered
    if [[ ! -f "$cb.gas.a" || "$cb.gas.a" -ot "$cb.gas.o" ]]; then
      "$AR" rcs "$cb.gas.a.$$" "$cb.gas.o" && mv -f "$cb.gas.a.$$" "$cb.gas.a"
    fi
    new+=("$cb.gas.a")
  else
    new+=("$a")
  fi
done
(( replaced )) || { echo "xt-link: no $stem*.rcgu.o object among linker args" >&2; exit 1; }

# a linker map next to each binary (<bin>-<hash>.map): run.sh reads it
new+=("-Wl,-Map=$out.map")
if [[ -n "${XT_LINK_VERBOSE:-}" ]]; then echo "xt-link: $GCC ${new[*]}" >&2; fi
exec "$GCC" "${new[@]}"
