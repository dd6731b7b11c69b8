#!/usr/bin/env python3
"""Code bytes of an lx106 ELF by the module and function that own them.

    python3 tools/size_by_file.py ELF [BASE_ELF] [N]

Each instruction's bytes go to the innermost frame of its inline chain
(`addr2line -i -f`; the release profile keeps line info) that is a function
of the project or of a driver crate (vl53l0x, mpu9250, embedded-hal-bus):
an i64 `saturating_mul` from core::num or a heapless `String::push` inlined
into the estimator or the protocol counts for them. Code with no such frame
(runtime helpers, memcpy, core's own functions) goes to its outermost
function. With BASE_ELF, the base's figures are subtracted (size probe minus
the bare runtime). Literal pools (L32R constants) are not instructions: the
difference to `size`'s .text is them. Prints the modules, then the N (25)
largest functions.
"""
import re
import subprocess
import sys
from collections import Counter

OWN = re.compile(r"\b(paperbot|size_probe|core_probe|vl53l0x|mpu9250|embedded_hal_bus)::")


def module(fn):
    m = re.search(r"\b(paperbot|size_probe|core_probe|vl53l0x|mpu9250|embedded_hal_bus|compiler_builtins|core|heapless)((::[a-z_0-9]+)*)", fn)
    if not m:
        return "(runtime: " + fn[:40] + ")"
    parts = (m.group(1) + m.group(2)).split("::")
    depth = 4 if parts[:3] == ["paperbot", "control", "protocol"] else 3
    return "::".join(parts[:depth])


def owners(elf):
    sizes = {}
    out = subprocess.run(["xtensa-lx106-elf-objdump", "-d", elf], capture_output=True, text=True, check=True).stdout
    for line in out.splitlines():
        m = re.match(r"^\s*([0-9a-f]{8}):\t([0-9a-f]+)\s*\t", line)
        if m:
            sizes[m.group(1)] = len(m.group(2)) // 2
    res = subprocess.run(
        ["xtensa-lx106-elf-addr2line", "-a", "-i", "-f", "-C", "-e", elf],
        input="\n".join("0x" + a for a in sizes) + "\n",
        capture_output=True,
        text=True,
        check=True,
    ).stdout
    fns = Counter()
    block = []

    def flush():
        if not block:
            return
        addr = block[0][2:].rjust(8, "0")[-8:]
        names = block[1::2]
        own = next((f for f in names if OWN.search(f)), names[-1] if names else "?")
        fns[own] += sizes.get(addr, 0)

    for line in res.splitlines():
        if line.startswith("0x"):
            flush()
            block = [line]
        else:
            block.append(line.strip())
    flush()
    return fns


fns = owners(sys.argv[1])
if len(sys.argv) > 2:
    fns.subtract(owners(sys.argv[2]))
top = int(sys.argv[3]) if len(sys.argv) > 3 else 25
mods = Counter()
for f, n in fns.items():
    mods[module(f)] += n
total = sum(n for n in mods.values() if n > 0)
print(f"{total} bytes of instructions")
print()
print("| module (inlined core/heapless code counts for its caller) | bytes |")
print("| --- | ---: |")
for f, n in mods.most_common():
    if n >= 64:
        print(f"| `{f}` | {n} |")
print()
print("| function | bytes |")
print("| --- | ---: |")
for f, n in fns.most_common(top):
    f = re.sub(r"<[^<>]*(<[^<>]*(<[^<>]*>[^<>]*)*>[^<>]*)*>", "<..>", f) if len(f) > 100 else f
    print(f"| `{f[:110]}` | {n} |")
