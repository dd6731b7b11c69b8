#!/usr/bin/env bash
# Footprint of the paperbot core and of the whole firmware stack on the lx106.
#
#   bash lx106/size.sh                  # build the probes, print the figures
#   bash lx106/size.sh --no-build       # as run.sh step 5: the probes are built
#   SIZE_ROWS=40 bash lx106/size.sh     # more rows in the breakdowns
#
# Three release binaries, each linked alone from the same minimal runtime:
# - core-probe (src/bin/core_probe.rs): the core, i.e. math, the models, the
#   estimator, the control tick and the protocol, over trait doubles;
# - size-probe (src/bin/size_probe.rs): the firmware stack, i.e. the core
#   plus the drivers, the bit-banged I2C master, the shared bus, the sensor
#   crates and the servo pulse scheduler (everything but esp8266-hal's glue);
# - size-base (src/bin/size_base.rs): the runtime alone.
# All three link memcpy, memset, __muldi3 and the 64-bit division helpers at
# their ESP8266 ROM addresses (../rom-functions.x, as the firmware's memory.x
# does), so those are not in their .text; the binaries QEMU runs carry
# compiler_builtins' versions.
# Each figure is a probe minus size-base. Needs python3 for the breakdown
# (tools/size_by_file.py: instruction bytes by owning module and function).
set -euo pipefail
cd "$(dirname "$0")"
build=1
while (($#)); do
  case "$1" in
    --no-build) build=0 ;;
    *) echo "size.sh: unknown argument $1" >&2; exit 2 ;;
  esac
  shift
done
OUT=target/xtensa-esp8266-none-elf/release
if ((build)); then
  cargo "+$(cat ../xtensa/nightly)" build --release --bin core-probe --bin size-probe --bin size-base 2>&1 |
    grep -vE '^warning: profile package spec `compiler_builtins`' | tail -1
fi

sec() { # $1 = ELF, $2 = section: its size in bytes (0 if absent)
  xtensa-lx106-elf-size -A "$1" | awk -v s="$2" '$1 == s { print $2; f = 1 } END { if (!f) print 0 }'
}
d() { # $1 = probe, $2 = section: probe minus base
  echo $(( $(sec "$OUT/$1" "$2") - $(sec "$OUT/size-base" "$2") ))
}
row() { # $1 = label, $2 = probe
  printf '   | %s | %d | %d | %d |\n' "$1" "$(d "$2" .text)" "$(d "$2" .rodata)" "$(( $(d "$2" .data) + $(d "$2" .bss) ))"
}
echo "   | bytes (probe minus size-base) | .text (code + literals + runtime helpers) | .rodata (flash) | static RAM |"
echo "   | --- | ---: | ---: | ---: |"
row "core: math, models, estimator, tick, protocol (core-probe)" core-probe
row "firmware stack: the core + drivers, bus, I2C, servo pulses (size-probe)" size-probe

echo "   runtime helpers the core links (compiler_builtins):"
xtensa-lx106-elf-nm -S "$OUT/core-probe" |
  awk '$3 ~ /^[tTwW]$/ && $4 ~ /^__/ { printf "     %-12s 0x%s bytes\n", $4, $2; n++ } END { if (!n) print "     none" }' | sort -u
# ../rom-functions.x: what the robot calls in the ESP8266's ROM (not in .text)
echo "   ESP8266 ROM routines, linked at their addresses (../rom-functions.x; not in .text):"
xtensa-lx106-elf-nm "$OUT/core-probe" | awk '$2 == "A" && $3 !~ /^_/ || $2 == "A" && $3 ~ /^__[a-z]/ { printf "     %-12s at 0x%s\n", $3, $1 }' | sort -u
# Informational: core::panicking entry points linked from the stack's paths
np=$(xtensa-lx106-elf-objdump -d "$OUT/size-probe" | grep -cE 'l32r.*<[^>]*core9panicking' || true)
echo "   references to core::panicking from the firmware stack: $np"

if command -v python3 >/dev/null; then
  echo "   where the core's bytes go (instructions only; literal pools under _double_vector):"
  python3 tools/size_by_file.py "$OUT/core-probe" "$OUT/size-base" "${SIZE_ROWS:-25}" | sed 's/^/   /'
else
  echo "   (python3 missing: no breakdown)"
fi
