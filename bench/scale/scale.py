#!/usr/bin/python3
"""The whole pipeline at growing mesh sizes (issue 15): time and peak memory per stage and per
triangle, and whether each grows linearly (per-triangle cost within 1.3x per 4x triangles).

    /usr/bin/python3 bench/scale/scale.py [--build build] [--levels 0,2,3,4] [--repeat N]
        [--warm-memory GIB] [--out out-scale]

Meshes: Debian's armadillo (libcgal-demo, 52,000 triangles) midpoint-subdivided LEVEL times
(`ptc subdivide`): 52k, 832k, 3.3M and 13.3M triangles for levels 0, 2, 3 and 4. For each:
  subdivide   ptc subdivide (levels > 0)
  info        ptc info --json (load and mesh report)
  growth      ptc cluster --method growth (the manifest's stages: read, cluster, validate,
              metrics, write)
  contraction ptc cluster --method contraction
  trace       ptc trace MESH --clusters <growth> --frame 0 (1024x1024 primary rays)
  bench       ptc bench MESH --clusters <growth> --frames 0:2 (against Embree, 1024x1024)
Every command runs as a child; its wall time, peak resident memory and user and system CPU time
come from wait4's rusage, its stages from its manifest.json (timings_ms, peak_rss_mb). With
--repeat N every command but subdivide runs N times (the whole list, then again), and each figure
is the median of the N runs (every run's time is kept in the CSV, column ms_each_run; every run's
peak memory and CPU times in manifest.json's commands). Writes OUT/scale.csv (one row
per size, command and stage) and OUT/manifest.json (commands, machine, ptc build), prints a table:
per stage the per-triangle cost's growth per 4x triangles ('!' above 1.3x), and with levels 2 and
4 the issue's 13.3M rule, the 13.3M stage against 16 times its 832k time ('*' above 1.3x).
Needs about 4 GB of free disk at level 4 and 7.5 GB of memory for the contraction there.

--warm-memory GIB touches GIB GiB of anonymous memory (on huge pages) and frees it right before
every command. On a virtual machine whose host takes freed memory back (free page reporting), a
command gets memory the host still backs only up to what was freed in the last seconds; beyond
that every first touch waits for the host (docs/scale.md, "Fresh memory"). Without the warm-up a
832k command runs on memory its predecessor just freed and a 13.3M command mostly on memory the
host has to provide again, so the 13.3M rule compares the host's two states as much as the code.
The warm-up gives every command the same state. Default 0 (off: what a user's run gets).
"""
import argparse
import csv
import json
import math
import os
import platform
import shutil
import subprocess
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def run(cmd, log):
    """Runs cmd; returns (wall_s, peak_mb, user_s, sys_s). Exits on failure naming the log."""
    t0 = time.monotonic()
    with open(log, "wb") as out:
        p = subprocess.Popen(cmd, stdout=out, stderr=subprocess.STDOUT)
        _, status, ru = os.wait4(p.pid, 0)
    wall = time.monotonic() - t0
    p.returncode = os.waitstatus_to_exitcode(status)
    if p.returncode != 0:
        sys.exit(f"scale: {' '.join(cmd)} failed ({p.returncode}); see {log}")
    return wall, ru.ru_maxrss / 1024.0, ru.ru_utime, ru.ru_stime  # ru_maxrss is in KiB on Linux


WARM = """
import mmap, sys
n = int(float(sys.argv[1]) * (1 << 30))
m = mmap.mmap(-1, n, flags=mmap.MAP_PRIVATE | mmap.MAP_ANONYMOUS)
if hasattr(mmap, "MADV_HUGEPAGE"):
    m.madvise(mmap.MADV_HUGEPAGE)
chunk = b"\\1" * (64 << 20)
for off in range(0, n, len(chunk)):
    m[off:off + min(len(chunk), n - off)] = chunk[:min(len(chunk), n - off)]
"""


def warm_memory(gib):
    """Touches gib GiB of fresh anonymous memory (advised as huge pages, as ptc's large arrays are)
    in a child process, which frees it on exit: the kernel then holds that much freed memory the
    host still backs. (A child, so that this process's peak does not become the commands': a
    forked child inherits its parent's peak resident size in wait4's rusage.)"""
    if gib > 0:
        r = subprocess.run([sys.executable, "-c", WARM, str(gib)])
        if r.returncode != 0:
            sys.exit(f"scale: the warm-up of {gib:g} GiB failed (exit {r.returncode}); give a smaller --warm-memory")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--build", default=os.path.join(ROOT, "build"))
    ap.add_argument("--levels", default="0,2,3,4")
    ap.add_argument("--out", default="out-scale")
    ap.add_argument("--repeat", type=int, default=1, help="runs of every command but subdivide; figures are medians")
    ap.add_argument("--keep-meshes", action="store_true", help="keep the subdivided meshes in OUT/work")
    ap.add_argument("--warm-memory", type=float, default=0.0, metavar="GIB",
                    help="touch and free GIB GiB of memory right before every command (default 0: off)")
    a = ap.parse_args()
    if a.repeat < 1:
        ap.error("--repeat must be at least 1")
    ram_gib = os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES") / float(1 << 30)
    if not (math.isfinite(a.warm_memory) and 0 <= a.warm_memory < ram_gib):
        ap.error(f"--warm-memory must be from 0 to less than this machine's memory ({ram_gib:.1f} GiB), "
                 f"{a.warm_memory:g} given")
    ptc = os.path.join(a.build, "bin", "ptc")
    base = os.path.join(a.build, "data", "meshes", "armadillo.off")
    if not os.path.exists(ptc) or not os.path.exists(base):
        sys.exit(f"scale: needs {ptc} and {base} (./run.sh build)")
    levels = [int(x) for x in a.levels.split(",")]
    tmp = a.out + ".tmp"
    shutil.rmtree(tmp, ignore_errors=True)
    work = os.path.join(tmp, "work")
    os.makedirs(work)
    rows, commands = [], []

    runs = {}  # (level, command, stage) -> {"tris": T, "ms": [...], "peak_mb": [...], "sys_ms": [...]}

    def add(level, tris, command, stage, ms, peak_mb, sys_ms=""):
        r = runs.setdefault((level, command, stage), {"tris": tris, "ms": [], "peak_mb": [], "sys_ms": []})
        r["ms"].append(ms)
        r["peak_mb"].append(peak_mb)
        r["sys_ms"].append(sys_ms)

    for level in levels:
        d = os.path.join(work, f"L{level}")
        os.makedirs(d)
        mesh = base if level == 0 else os.path.join(d, "mesh.ply")
        steps = []
        if level > 0:
            steps.append(("subdivide", [ptc, "subdivide", base, "--levels", str(level), "--out", mesh], None))
        steps += [
            ("info", [ptc, "info", mesh, "--json"], None),
            ("growth", [ptc, "cluster", mesh, "--method", "growth", "--out", os.path.join(d, "growth")],
             os.path.join(d, "growth")),
            ("contraction", [ptc, "cluster", mesh, "--method", "contraction", "--out", os.path.join(d, "contraction")],
             os.path.join(d, "contraction")),
            ("trace", [ptc, "trace", mesh, "--clusters", os.path.join(d, "growth"), "--frame", "0", "--width", "1024",
                       "--height", "1024", "--out", os.path.join(d, "trace")], os.path.join(d, "trace")),
            ("bench", [ptc, "bench", mesh, "--clusters", os.path.join(d, "growth"), "--frames", "0:2", "--width", "1024",
                       "--height", "1024", "--out", os.path.join(d, "bench")], os.path.join(d, "bench")),
        ]
        tris = None
        # subdivide once, then the rest of the list --repeat times (round robin over the commands,
        # so that a slow phase of the machine spreads over all of them)
        order = [(0, st) for st in steps if st[0] == "subdivide"] + \
            [(k, st) for k in range(a.repeat) for st in steps if st[0] != "subdivide"]
        for k, (name, cmd, outdir) in order:
            print(f"== L{level} {name}" + (f" (run {k + 1}/{a.repeat})" if a.repeat > 1 else "") +
                  f": {' '.join(cmd)}", file=sys.stderr, flush=True)
            warm_memory(a.warm_memory)
            wall, peak, user, system = run(cmd, os.path.join(d, name + ".log"))
            if name == "info":
                tris = json.load(open(os.path.join(d, name + ".log")))["triangles"]
            commands.append({"level": level, "command": name, "run": k + 1, "argv": cmd, "wall_s": wall,
                             "peak_mb": peak, "user_s": user, "sys_s": system})
            if tris is None:  # subdivide runs before info: count from its output
                tris = 52000 * 4 ** level
            add(level, tris, name, "total", wall * 1e3, peak, system * 1e3)
            if outdir and os.path.exists(os.path.join(outdir, "manifest.json")):
                m = json.load(open(os.path.join(outdir, "manifest.json")))
                for stage, ms in m.get("timings_ms", {}).items():
                    if isinstance(ms, (int, float)):
                        add(level, tris, name, stage, ms, m.get("peak_rss_mb", {}).get(stage, ""))
        if not a.keep_meshes and level > 0:
            os.remove(mesh)

    # One row per size, command and stage: the median of its runs (every run's value kept).
    def median(xs):
        xs = sorted(x for x in xs if x != "")
        if not xs:
            return ""
        n = len(xs)
        return xs[n // 2] if n % 2 else 0.5 * (xs[n // 2 - 1] + xs[n // 2])

    for (level, command, stage), r in runs.items():
        ms, peak = median(r["ms"]), median(r["peak_mb"])
        rows.append({"level": level, "triangles": r["tris"], "command": command, "stage": stage, "ms": ms,
                     "peak_mb": peak, "ns_per_triangle": ms * 1e6 / r["tris"],
                     "bytes_per_triangle": peak * 1048576.0 / r["tris"] if peak else "",
                     "sys_ms": median(r["sys_ms"]), "runs": len(r["ms"]),
                     "ms_each_run": ";".join(f"{x:.1f}" for x in r["ms"])})
    # Growth of the per-triangle cost from one size to the next (4x triangles a level).
    by = {(r["command"], r["stage"], r["level"]): r for r in rows}
    for r in rows:
        prev = [l for l in levels if l < r["level"]]
        p = by.get((r["command"], r["stage"], prev[-1])) if prev else None
        r["per_triangle_growth"] = (r["ns_per_triangle"] / p["ns_per_triangle"]) ** (1.0 / (r["level"] - prev[-1])) \
            if p and p["ns_per_triangle"] > 0 else ""
    with open(os.path.join(tmp, "scale.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0].keys()))
        w.writeheader()
        w.writerows(rows)
    git = subprocess.run(["git", "-C", ROOT, "rev-parse", "HEAD"], capture_output=True, text=True).stdout.strip()
    manifest = {"schema": "ptc-scale/3", "argv": sys.argv, "levels": levels, "repeat": a.repeat,
                "warm_memory_gib": a.warm_memory, "commands": commands,
                "ptc_commit": git, "machine": {"cpu": platform.processor() or platform.machine(),
                                               "cores": os.cpu_count(), "kernel": platform.release()},
                "outputs": ["scale.csv"]}
    json.dump(manifest, open(os.path.join(tmp, "manifest.json"), "w"), indent=2)
    if not a.keep_meshes:
        shutil.rmtree(work)
    if os.path.exists(a.out):
        shutil.rmtree(a.out)
    os.rename(tmp, a.out)

    rule16 = 2 in levels and 4 in levels  # the 13.3M rule: within 1.3x of 16x the 832k time
    print(f"{'command':<12} {'stage':<20} " + " ".join(f"{'L' + str(l) + ' ms':>11} {'MB':>7}" for l in levels) +
          "  ns/tri growth per 4x" + ("   L4 / (16 x L2)" if rule16 else "") +
          (f"   (medians of {a.repeat} runs)" if a.repeat > 1 else "") +
          (f"   ({a.warm_memory:g} GiB warmed before each command)" if a.warm_memory > 0 else ""))
    keys = []
    for r in rows:
        if (r["command"], r["stage"]) not in keys:
            keys.append((r["command"], r["stage"]))
    command_order = ["subdivide", "info", "growth", "contraction", "trace", "bench"]
    keys.sort(key=lambda k: command_order.index(k[0]) if k[0] in command_order else len(command_order))  # stable
    for c, s in keys:
        cells, growth = [], []
        for l in levels:
            r = by.get((c, s, l))
            cells.append(f"{r['ms']:>11.1f} {r['peak_mb'] if r['peak_mb'] == '' else round(r['peak_mb']):>7}" if r else
                         f"{'-':>11} {'-':>7}")
            if r and r["per_triangle_growth"] != "":
                flag = r["per_triangle_growth"] > 1.3 and r["ms"] >= 20  # stages under 20 ms are noise
                growth.append(f"{r['per_triangle_growth']:.2f}" + ("!" if flag else ""))
        r2, r4 = by.get((c, s, 2)), by.get((c, s, 4))
        rule = ""
        if rule16 and r2 and r4 and r2["ms"] > 0:
            x = r4["ms"] / (16.0 * r2["ms"])
            rule = f"   {x:.2f}" + ("*" if x > 1.3 and r2["ms"] >= 20 else "")
        print(f"{c:<12} {s:<20} " + " ".join(cells) + "  " + " ".join(growth) + rule)
    print(f"wrote {a.out}/scale.csv, {a.out}/manifest.json ('!': a stage of 20 ms or more whose per-triangle cost "
          "grew more than 1.3x per 4x" + ("; '*': a 13.3M stage above 1.3 x 16 x its 832k time" if rule16 else "") +
          ")")


if __name__ == "__main__":
    main()
