#!/usr/bin/env bash
# Builds the project's ESP8266 board (emu/esp8266*.[ch]) into Debian's QEMU 7.2
# (an xtensa-only qemu-system-xtensa) and the board's ROM (emu/rom/), and
# prints the directory that holds both:
#
#   ${XDG_CACHE_HOME:-$HOME/.cache}/paperbot/emu-<hash of emu/'s sources>/
#       qemu-system-xtensa   rom.elf   probe-<mode>.elf (test images)
#
# Cached: a second run with unchanged sources prints the directory at once.
# The QEMU source tree and its build directory stay in the cache too, so an
# edit to the board rebuilds one file (seconds); the first build compiles
# QEMU's xtensa target (about 5 minutes on 2 cores).
#
# Needs: root or sudo for apt-get on a fresh machine (packages below; a
# deb-src entry for the machine's own Debian suites is added when missing).
# Progress goes to stderr, the result directory alone to stdout.
set -euo pipefail

emu_dir=$(cd "$(dirname "$0")" && pwd)
cache=${XDG_CACHE_HOME:-$HOME/.cache}/paperbot
say() { echo "build-qemu: $*" >&2; }

# Every file that goes into the binaries, and this script.
sources_hash() {
    (cd "$emu_dir" && find . -type f ! -name '*.md' -print0 | LC_ALL=C sort -z |
        xargs -0 sha256sum) | sha256sum | cut -c1-16
}

out=$cache/emu-$(sources_hash)
# The test images (emu/test/probe.c), one per mode.
probe_modes=(wdt gpio0-low no-pll ram narrow-iram narrow-flash)

if [ -x "$out/qemu-system-xtensa" ] && [ -f "$out/rom.elf" ] && [ -f "$out/probe-narrow-flash.elf" ]; then
    echo "$out"
    exit 0
fi

as_root() { if [ "$(id -u)" = 0 ]; then "$@"; else sudo "$@"; fi; }

# ---- packages ----------------------------------------------------------------
build_packages=(dpkg-dev meson ninja-build libglib2.0-dev libpixman-1-dev flex bison
    pkg-config python3-venv gcc-xtensa-lx106 binutils-xtensa-lx106)

install_missing_packages() {
    local missing=() p
    for p in "${build_packages[@]}"; do
        dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q 'install ok installed' ||
            missing+=("$p")
    done
    if [ ${#missing[@]} -gt 0 ]; then
        say "installing ${missing[*]}"
        as_root apt-get update -qq
        as_root env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq "${missing[@]}" >&2
    fi
}

# A deb-src twin of every deb822 "Types: deb" stanza (Debian 12's layout),
# or of every one-line "deb" entry, unless some deb-src entry exists.
add_deb_src() {
    if grep -rqsE '^(Types:.*deb-src|deb-src )' /etc/apt/sources.list /etc/apt/sources.list.d/; then
        return
    fi
    say "adding deb-src entries for the machine's suites"
    local f=/etc/apt/sources.list.d/paperbot-deb-src
    if ls /etc/apt/sources.list.d/*.sources >/dev/null 2>&1; then
        awk 'BEGIN { RS = ""; ORS = "\n\n" }
             /(^|\n)Types:[^\n]*deb([^-]|$)/ && !/deb-src/ {
                 sub(/Types:[^\n]*/, "Types: deb-src"); print }' \
            /etc/apt/sources.list.d/*.sources | as_root tee "$f.sources" >/dev/null
    else
        sed -n 's/^deb \(.*\)$/deb-src \1/p' /etc/apt/sources.list | as_root tee "$f.list" >/dev/null
    fi
    as_root apt-get update -qq
}

# ---- QEMU source (Debian's 7.2, with Debian's patches) --------------------------
qemu_src=$cache/qemu-7.2-src

fetch_qemu_source() {
    [ -f "$qemu_src/.complete" ] && return
    add_deb_src
    say "fetching Debian's QEMU source (apt-get source qemu)"
    rm -rf "$qemu_src" "$cache/qemu-download"
    mkdir -p "$cache/qemu-download"
    (cd "$cache/qemu-download" && apt-get source -qq qemu >&2)
    local dir
    dir=$(find "$cache/qemu-download" -maxdepth 1 -type d -name 'qemu-7.2*' | head -n1)
    [ -n "$dir" ] || { say "apt-get source gave no qemu-7.2 tree (is the suite bookworm?)"; exit 1; }
    mv "$dir" "$qemu_src"
    rm -rf "$cache/qemu-download"
    touch "$qemu_src/.complete"
}

# The board's glue: its Kconfig symbol, on by default, and its files in meson.
add_line_once() { # file line
    grep -qxF "$2" "$1" || printf '%s\n' "$2" >>"$1"
}

# The board's files (esp8266*.c, esp8266*.h), as installed in hw/xtensa/.
board_files() { # c|h
    (cd "$emu_dir" && LC_ALL=C ls -- esp8266*."$1")
}

# The board's lines in hw/xtensa/meson.build, one per C file, written afresh
# (the lines for other files removed); the file is rewritten only when they
# change, so meson reconfigures only then.
set_meson_files() { # file.c...
    local meson=$qemu_src/hw/xtensa/meson.build f
    {
        grep -vF "'CONFIG_XTENSA_ESP8266'" "$meson" || true
        for f in "$@"; do
            printf "xtensa_ss.add(when: 'CONFIG_XTENSA_ESP8266', if_true: files('%s'))\n" "$f"
        done
    } >"$meson.new"
    if cmp -s "$meson.new" "$meson"; then rm "$meson.new"; else mv "$meson.new" "$meson"; fi
}

# The QEMU tree is shared by the builds of every checkout, whose boards may
# have other files: each build lists its own files in meson and removes the
# board's files it does not have.
install_board_sources() {
    local dir=$qemu_src/hw/xtensa f
    set_meson_files $(board_files c)
    if ! grep -q '^config XTENSA_ESP8266$' "$qemu_src/hw/xtensa/Kconfig"; then
        printf '\nconfig XTENSA_ESP8266\n    bool\n' >>"$qemu_src/hw/xtensa/Kconfig"
    fi
    add_line_once "$qemu_src/configs/devices/xtensa-softmmu/default.mak" "CONFIG_XTENSA_ESP8266=y"
    for f in "$dir"/esp8266*.[ch]; do
        if [ -e "$f" ] && [ ! -e "$emu_dir/$(basename "$f")" ]; then rm "$f"; fi
    done
    # copy only when changed, so ninja rebuilds only what changed
    for f in $(board_files c) $(board_files h); do
        cmp -s "$emu_dir/$f" "$dir/$f" || cp "$emu_dir/$f" "$dir/$f"
    done
}

# The one change to QEMU's own code (emu/qemu-narrow-load.patch): the
# board's LoadStoreError for 8- and 16-bit loads from IRAM and flash, which
# the translator must check. Off for every other machine, so the shared
# tree stays good for checkouts without it; applied once.
patch_qemu() {
    local f=$qemu_src/target/xtensa/translate.c
    grep -q "the narrow-load check branches before the load" "$f" && return
    say "patching target/xtensa/translate.c (emu/qemu-narrow-load.patch)"
    patch -d "$qemu_src" -p1 -N -s <"$emu_dir/qemu-narrow-load.patch" >&2
}

build_qemu() {
    local build=$qemu_src/build
    if [ ! -f "$build/build.ninja" ]; then
        say "configuring QEMU (xtensa-softmmu only)"
        mkdir -p "$build"
        (cd "$build" && ../configure --target-list=xtensa-softmmu \
            --without-default-features --without-default-devices \
            --disable-docs --disable-werror --disable-install-blobs >&2)
    fi
    say "building qemu-system-xtensa"
    ninja -C "$build" qemu-system-xtensa >&2
}

# ---- the ROM -------------------------------------------------------------------
build_rom() { # out.elf
    xtensa-lx106-elf-gcc -Os -nostdlib -ffreestanding -fno-builtin -fno-tree-loop-distribute-patterns -Wall -Werror \
        -T "$emu_dir/rom/rom.ld" -Wl,--gc-sections -Wl,-Map="$1.map" \
        -o "$1" "$emu_dir/rom/reset.S" "$emu_dir/rom/boot.c" "$emu_dir/rom/routines.c" "$emu_dir/rom/flash.c"
    if xtensa-lx106-elf-nm -u "$1" | grep -q .; then
        say "rom.elf has undefined symbols:"; xtensa-lx106-elf-nm -u "$1" >&2; exit 1
    fi
}

# The test images (cargo fw-emu --self-test wraps each in a boot image).
build_test_images() { # out-dir
    local m
    for m in "${probe_modes[@]}"; do
        xtensa-lx106-elf-gcc -Os -nostdlib -ffreestanding -fno-builtin -Wall -Werror \
            -DPROBE_$(echo "$m" | tr a-z- A-Z_) -T "$emu_dir/test/probe.ld" \
            -o "$1/probe-$m.elf" "$emu_dir/test/probe.c"
    done
}

install_missing_packages
fetch_qemu_source
install_board_sources
patch_qemu
build_qemu
tmp=$(mktemp -d "$cache/emu-tmp.XXXXXX")
build_rom "$tmp/rom.elf"
build_test_images "$tmp"
cp "$qemu_src/build/qemu-system-xtensa" "$tmp/"
rm -rf "$out"
mv "$tmp" "$out"
# builds of older sources, unused for a month
find "$cache" -maxdepth 1 -name 'emu-*' ! -name "$(basename "$out")" -mtime +30 -exec rm -rf {} +
say "built $out"
echo "$out"
