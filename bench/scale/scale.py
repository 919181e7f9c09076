#!/usr/bin/python3
"""The whole pipeline at growing mesh sizes (issue 15): time and peak memory per stage and per
triangle, and whether each grows linearly (per-triangle cost within 1.3x per 4x triangles).

    /usr/bin/python3 bench/scale/scale.py [--build build] [--levels 0,2,3,4] [--out out-scale]

Meshes: Debian's armadillo (libcgal-demo, 52,000 triangles) midpoint-subdivided LEVEL times
(`ptc subdivide`): 52k, 832k, 3.3M and 13.3M triangles for levels 0, 2, 3 and 4. For each:
  subdivide   ptc subdivide (levels > 0)
  info        ptc info --json (load and mesh report)
  growth      ptc cluster --method growth (the manifest's stages: read, cluster, validate,
              metrics, write)
  contraction ptc cluster --method contraction
  trace       ptc trace MESH --clusters <growth> --frame 0 (1024x1024 primary rays)
  bench       ptc bench MESH --clusters <growth> --frames 0:2 (against Embree, 1024x1024)
Every command runs as a child; its wall time and peak resident memory come from wait4's rusage,
its stages from its manifest.json (timings_ms, peak_rss_mb). Writes OUT/scale.csv (one row per
size, command and stage) and OUT/manifest.json (commands, machine, ptc build), prints a table.
Needs about 4 GB of free disk at level 4 and 7.5 GB of memory for the contraction there.
"""
import argparse
import csv
import json
import os
import platform
import shutil
import subprocess
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def run(cmd, log):
    """Runs cmd; returns (wall_s, peak_mb). Raises on failure with the command's stderr."""
    t0 = time.monotonic()
    with open(log, "wb") as out:
        p = subprocess.Popen(cmd, stdout=out, stderr=subprocess.STDOUT)
        _, status, ru = os.wait4(p.pid, 0)
    wall = time.monotonic() - t0
    p.returncode = os.waitstatus_to_exitcode(status)
    if p.returncode != 0:
        sys.exit(f"scale: {' '.join(cmd)} failed ({p.returncode}); see {log}")
    return wall, ru.ru_maxrss / 1024.0  # ru_maxrss is in KiB on Linux


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--build", default=os.path.join(ROOT, "build"))
    ap.add_argument("--levels", default="0,2,3,4")
    ap.add_argument("--out", default="out-scale")
    ap.add_argument("--keep-meshes", action="store_true", help="keep the subdivided meshes in OUT/work")
    a = ap.parse_args()
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

    def add(level, tris, command, stage, ms, peak_mb):
        rows.append({"level": level, "triangles": tris, "command": command, "stage": stage, "ms": ms,
                     "peak_mb": peak_mb, "ns_per_triangle": ms * 1e6 / tris,
                     "bytes_per_triangle": peak_mb * 1048576.0 / tris if peak_mb else ""})

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
        for name, cmd, outdir in steps:
            print(f"== L{level} {name}: {' '.join(cmd)}", file=sys.stderr, flush=True)
            wall, peak = run(cmd, os.path.join(d, name + ".log"))
            if name == "info":
                tris = json.load(open(os.path.join(d, name + ".log")))["triangles"]
            commands.append({"level": level, "command": name, "argv": cmd, "wall_s": wall, "peak_mb": peak})
            if tris is None:  # subdivide runs before info: count from its output
                tris = 52000 * 4 ** level
            add(level, tris, name, "total", wall * 1e3, peak)
            if outdir and os.path.exists(os.path.join(outdir, "manifest.json")):
                m = json.load(open(os.path.join(outdir, "manifest.json")))
                for stage, ms in m.get("timings_ms", {}).items():
                    if isinstance(ms, (int, float)):
                        add(level, tris, name, stage, ms, m.get("peak_rss_mb", {}).get(stage, ""))
        if not a.keep_meshes and level > 0:
            os.remove(mesh)

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
    manifest = {"schema": "ptc-scale/1", "argv": sys.argv, "levels": levels, "commands": commands,
                "ptc_commit": git, "machine": {"cpu": platform.processor() or platform.machine(),
                                               "cores": os.cpu_count(), "kernel": platform.release()},
                "outputs": ["scale.csv"]}
    json.dump(manifest, open(os.path.join(tmp, "manifest.json"), "w"), indent=2)
    if not a.keep_meshes:
        shutil.rmtree(work)
    if os.path.exists(a.out):
        shutil.rmtree(a.out)
    os.rename(tmp, a.out)

    print(f"{'command':<12} {'stage':<20} " + " ".join(f"{'L' + str(l) + ' ms':>11} {'MB':>7}" for l in levels) +
          "  ns/tri growth per 4x")
    keys = []
    for r in rows:
        if (r["command"], r["stage"]) not in keys:
            keys.append((r["command"], r["stage"]))
    for c, s in keys:
        cells, growth = [], []
        for l in levels:
            r = by.get((c, s, l))
            cells.append(f"{r['ms']:>11.1f} {r['peak_mb'] if r['peak_mb'] == '' else round(r['peak_mb']):>7}" if r else
                         f"{'-':>11} {'-':>7}")
            if r and r["per_triangle_growth"] != "":
                flag = r["per_triangle_growth"] > 1.3 and r["ms"] >= 20  # stages under 20 ms are noise
                growth.append(f"{r['per_triangle_growth']:.2f}" + ("!" if flag else ""))
        print(f"{c:<12} {s:<20} " + " ".join(cells) + "  " + " ".join(growth))
    print(f"wrote {a.out}/scale.csv, {a.out}/manifest.json ('!': a stage of 20 ms or more whose per-triangle cost "
          "grew more than 1.3x per 4x)")


if __name__ == "__main__":
    main()
