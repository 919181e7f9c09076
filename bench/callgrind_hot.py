#!/usr/bin/python3
"""The hottest straight-line runs of instructions of one function, from a callgrind profile.

This host's guest has no hardware counters, so `perf stat` cannot say how many instructions a
ray costs; callgrind counts them exactly (docs/tracing.md, "Compiler artefacts in the walks").
Record with per-instruction counts, then list the runs:

    valgrind --tool=callgrind --dump-instr=yes --collect-atstart=no \\
        --toggle-collect='*trace_packet<false>*' --callgrind-out-file=cg.out \\
        build/bin/ptc bench cloth-sphere-128 --threads 1 --frames 0:1 --packets --no-shadows \\
        --width 512 --height 512 --out D
    /usr/bin/python3 bench/callgrind_hot.py cg.out 'trace_packet<false>' --top 20

A run is a stretch of consecutive instructions executed the same number of times (a basic block,
or part of one). Each line: the run's addresses, its length, how often it ran, its instructions
and their share of the function's, and its first instruction (objdump of the binary named in the
profile, or --binary).
"""
import argparse
import collections
import re
import subprocess
import sys


def fail(msg):
    print(f"callgrind_hot.py: {msg}", file=sys.stderr)
    sys.exit(1)


def read_costs(path, pattern):
    """Instruction counts by address for the functions whose name contains `pattern`, and the
    object file they belong to. Callgrind names a function once ("fn=(id) name") and refers to it
    by id after that; addresses may be relative to the previous line ("+n", "-n", "*")."""
    try:
        lines = open(path, encoding="utf-8", errors="replace").read().split("\n")
    except OSError as e:
        fail(f"{path}: {e.strerror}")
    if not lines or not lines[0].startswith("# callgrind format"):
        fail(f"{path}: not a callgrind profile (first line: {lines[0][:40]!r})")
    if not any(l.startswith("positions:") and "instr" in l for l in lines[:40]):
        fail(f"{path}: no per-instruction counts; record with --dump-instr=yes")
    names, objects = {}, {}
    for l in lines:
        m = re.match(r"^c?(fn|ob)=\((\d+)\)\s*(.*)$", l)
        if m and m.group(3):
            (names if m.group(1) == "fn" else objects)[m.group(2)] = m.group(3)
    costs = collections.Counter()
    inside, last, after_call, obj, fn_obj = False, 0, False, None, None
    for l in lines:
        if l.startswith("ob="):
            m = re.match(r"^ob=\((\d+)\)", l)
            obj = objects.get(m.group(1)) if m else None
            continue
        if l.startswith("fn="):
            m = re.match(r"^fn=\((\d+)\)", l)
            inside = bool(m) and pattern in names.get(m.group(1), "")
            if inside:
                fn_obj = obj
            continue
        if l.startswith("calls="):
            after_call = True  # the next cost line is the call's inclusive cost
            continue
        m = re.match(r"^(0x[0-9a-f]+|\+\d+|-\d+|\*)\s+\S+(?:\s+(\d+))?$", l.strip())
        if not m:
            continue
        a = m.group(1)
        last = int(a, 16) if a.startswith("0x") else last + int(a[1:]) if a[0] == "+" else \
            last - int(a[1:]) if a[0] == "-" else last
        if after_call:
            after_call = False
            continue
        if inside and m.group(2):
            costs[last] += int(m.group(2))
    if not costs:
        fail(f"{path}: no instruction of a function whose name contains {pattern!r} was counted")
    return costs, fn_obj


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("profile", help="callgrind output file (recorded with --dump-instr=yes)")
    ap.add_argument("function", help="part of the function's name, e.g. 'trace_packet<false>'")
    ap.add_argument("--top", type=int, default=25, help="runs to list (default 25)")
    ap.add_argument("--binary", help="the object to disassemble (default: the one the profile names)")
    a = ap.parse_args()
    if a.top < 1:
        ap.error("--top must be at least 1")
    costs, obj = read_costs(a.profile, a.function)
    binary = a.binary or obj
    if not binary:
        fail(f"{a.profile}: the profile names no object for {a.function!r}; give --binary")
    lo, hi = min(costs), max(costs)
    try:
        dis = subprocess.run(["objdump", "-d", "--no-show-raw-insn", f"--start-address={lo}",
                              f"--stop-address={hi + 16}", binary], capture_output=True, text=True, check=True).stdout
    except (OSError, subprocess.CalledProcessError) as e:
        fail(f"{binary}: objdump failed ({e})")
    starts = {int(m.group(1), 16) for m in re.finditer(r"^\s*([0-9a-f]+):", dis, re.M)}
    stray = sum(c for addr, c in costs.items() if addr not in starts)
    if stray > 0.001 * sum(costs.values()):
        fail(f"{binary}: {stray:,} of the counted instructions fall between its instructions; it is not the "
             "binary that was profiled (rebuilt since?)")
    runs, cur = [], None
    for l in dis.split("\n"):
        m = re.match(r"\s*([0-9a-f]+):\s*(.*)", l)
        if not m:
            continue
        addr, c = int(m.group(1), 16), costs.get(int(m.group(1), 16), 0)
        if cur and c == cur["count"] and c > 0:
            cur["n"] += 1
            cur["end"] = addr
            continue
        if cur:
            runs.append(cur)
        cur = {"start": addr, "end": addr, "count": c, "n": 1, "first": m.group(2)[:60]} if c > 0 else None
    if cur:
        runs.append(cur)
    total = sum(costs.values())
    print(f"{a.function}: {total:,} instructions counted ({binary})")
    print(f"{'addresses':>17} {'length':>6} {'executed':>11} {'instructions':>14} {'share':>6}  first instruction")
    for r in sorted(runs, key=lambda r: -r["count"] * r["n"])[:a.top]:
        ir = r["count"] * r["n"]
        print(f"{r['start']:x}-{r['end']:x} {r['n']:6d} {r['count']:11,d} {ir:14,d} {100 * ir / total:5.1f}%  {r['first']}")


if __name__ == "__main__":
    main()
