#!/usr/bin/env python3
"""Where a measured stretch of lx106 code spends its instructions.

    python3 tools/profile.py ELF TRACE [N]

TRACE is QEMU's `-singlestep -d exec,nochain` log of ELF (one line per
executed instruction, see tools/profile.sh). Only the instructions between
the return from `icount_start` and the call of `icount_read` count (the
stretch that rt::measure brackets). Prints, per function, the instructions
executed inside it (self) and inside it or anything it called (inclusive),
and how often it was called; call0/callx0 push, reaching the return address
pops (the lx106 uses the call0 ABI).
"""
import re
import subprocess
import sys
from bisect import bisect_right
from collections import Counter

elf, trace = sys.argv[1], sys.argv[2]
top = int(sys.argv[3]) if len(sys.argv) > 3 else 30
objdump = "xtensa-lx106-elf-objdump"

# address -> (mnemonic, size); function starts
insn = {}
starts = []
names = {}
cur = None
for line in subprocess.run([objdump, "-d", "-C", elf], capture_output=True, text=True, check=True).stdout.splitlines():
    m = re.match(r"^([0-9a-f]{8}) <(.*)>:$", line)
    if m:
        a = int(m.group(1), 16)
        starts.append(a)
        names[a] = m.group(2)
        continue
    m = re.match(r"^([0-9a-f]{8}):\t([0-9a-f]+)\s*\t(\S+)", line)
    if m:
        insn[int(m.group(1), 16)] = (m.group(3), len(m.group(2)) // 2)
starts.sort()


def func(pc):
    i = bisect_right(starts, pc) - 1
    return names[starts[i]] if i >= 0 else "?"


def short(name):
    name = re.sub(r"paperbot_lx106::scripts::(Script\w+|NullSink)", r"\1", name)
    name = re.sub(r"<paperbot::control::tick::Controller<[^>]*>>", "Controller", name)
    name = name.replace("paperbot::", "")
    return name[:110]


sym = {v: k for k, v in names.items()}
start_fn, read_fn = sym.get("icount_start"), sym.get("icount_read")
pcs = []
for line in open(trace):
    m = re.match(r"Trace \d+: \S+ \[[0-9a-f]+/([0-9a-f]+)/", line)
    if m:
        pcs.append(int(m.group(1), 16))

# the measured stretch: after icount_start returns, until icount_read is entered
try:
    s = pcs.index(start_fn)
    while func(pcs[s]) == "icount_start":
        s += 1
    e = pcs.index(read_fn, s)
except ValueError:
    sys.exit("profile.py: no icount_start ... icount_read stretch in the trace")
stretch = pcs[s:e]

self_c, incl, calls, edges = Counter(), Counter(), Counter(), Counter()
stack = [(func(stretch[0]), None)]
prev = None
for pc in stretch:
    if prev is not None:
        mn, size = insn.get(prev, ("?", 3))
        if mn in ("call0", "callx0"):
            edges[(stack[-1][0], func(pc))] += 1
            stack.append((func(pc), prev + size))
            calls[func(pc)] += 1
        else:
            # pop every frame whose return address we reached
            for k in range(len(stack) - 1, 0, -1):
                if stack[k][1] == pc:
                    del stack[k:]
                    break
    f = func(pc)
    self_c[f] += 1
    for g in {fr[0] for fr in stack} | {f}:
        incl[g] += 1
    prev = pc

print(f"{len(stretch)} instructions in the measured stretch")
print()
print("| function | inclusive | self | calls |")
print("| --- | ---: | ---: | ---: |")
for f, n in incl.most_common(top):
    print(f"| `{short(f)}` | {n} | {self_c[f]} | {calls[f]} |")

# the runtime helpers (no multiply-high, no divide on the lx106): who calls them
helpers = [f for f in incl if f.startswith("__") or f == "memcpy" or f == "memset"]
if helpers:
    print()
    print("| runtime helper | called from | calls | instructions (at its average) |")
    print("| --- | --- | ---: | ---: |")
    for h in sorted(helpers, key=lambda f: -incl[f]):
        avg = incl[h] / max(calls[h], 1)
        for (caller, callee), n in edges.most_common():
            if callee == h:
                print(f"| `{h}` | `{short(caller)}` | {n} | {round(n * avg)} |")

