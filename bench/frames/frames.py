#!/usr/bin/python3
"""Whole frames against Embree over every built-in animated scene of a given size (issue 14): one
table of ours_clusters' whole frame (update + build + primary rays + shadow rays) against Embree
REFIT and LOW, per scene and thread count, from `ptc bench` runs made here.

    /usr/bin/python3 bench/frames/frames.py [--build build] [--threads 1,2] [--frames 0:5 | --frames all]
        [--min-triangles 500000] [--scenes A,B] [--repeat 1] [--single] [--width 1024 --height 1024]
        [--max-count N[,M...]] [--leaf-format auto|blocks|tables] [--shadow-order pixel|morton] --out DIR

Each (repeat, threads, scene, --max-count value) is one `ptc bench SCENE --threads T --frames A:B [--packets]
(`--frames all`: no --frames, so each scene's whole animation, which is what `ptc bench SCENE`
measures by default; the default 0:5 takes the first frames only, where clusters have not yet
swollen or a cloth not yet draped: docs/tracing.md, "Later frames")
[--max-count N] [--leaf-format F] --out DIR/runs/...` (packets on both sides unless --single;
--max-count N: the bench's own clustering at MaxCount = MaxSize = N instead of its default (the
scene's own cluster size, `ptc scenes` lists them, else 32), e.g. 50 for the paper's value; a
list N,M,... sweeps the cluster size: every value gets its own runs and table rows, with the
MaxCount each run used in the table and in runs.csv (`max_count`, `max_count_from`); --leaf-format F: the cluster leaves' format, default the bench's own,
auto; --shadow-order O: the order the shadow rays are traced in, default the bench's own, pixel). Repeats run one after the other over the
whole list, so a slow phase of the machine touches every scene a little rather than one scene a
lot; the table gives, per scene, thread count (and --max-count value), the median over the repeats of each
configuration's whole frame (each run's own median over frames 1..B) and the ratios of those
medians, plus the smallest and largest ratio of single runs, and the lowest ratio of a single
frame in any run (Embree's whole frame / ours on that frame: where along the animation the
method stops paying, which a median over frames hides; runs.csv keeps each run's lowest for
every configuration: 1 for an Embree mode against itself, nan from a build that does not report
it). With more than one thread count, a
second table says how each stage scales: per scene and configuration, the median over the
repeats of every stage (update + build and, for ours_clusters, its conversion, boxes, SAH build, collapse +
link, leaf data and the time two of them overlapped; primary rays, shadow rays, the whole frame)
at the first thread count and at each other one, and the speed-up between them. Writes
DIR/runs.csv (one row per run and configuration, the stages as each run's bench.csv medians over
its frames after the first), DIR/frames.csv (the table), DIR/scaling.csv (the stages' table) and
DIR/manifest.json; every run's own bench.csv, summary.csv and manifest.json stay under DIR/runs/.
DIR must not exist (nothing is overwritten).
Exit 1 when a run fails, 2 for bad usage.
"""
import argparse
import csv
import json
import os
import shutil
import statistics
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
CONFIGS = ("ours_clusters", "embree_refit", "embree_low")


def usage(msg):
    print(f"frames.py: {msg}", file=sys.stderr)
    sys.exit(2)


STAGES = ("vertices_ms", "boxes_ms", "sah_build_ms", "collapse_ms", "leaf_data_ms", "overlap_ms")
MEASURES = ("update_build_ms",) + STAGES + ("trace_ms", "shadow_ms", "whole_frame_ms")


def stage_medians(path):
    """config -> {stage: median over the run's frames, the first left out when there are more}
    (the rule of the bench's own medians)."""
    per = {}
    with open(path, newline="") as f:
        for r in csv.DictReader(f):
            per.setdefault(r["config"], []).append(r)
    out = {}
    for c, rs in per.items():
        rs.sort(key=lambda r: int(r["frame"]))
        use = rs[1:] if len(rs) > 1 else rs
        out[c] = {k: statistics.median(float(r[k]) for r in use) for k in STAGES}
    return out


def lowest(values):
    """The smallest of the values that are not NaN (NaN when none is)."""
    return min((v for v in values if v == v), default=float("nan"))


def ratio_cell(v):
    """A ratio for the printed table ('-' for NaN)."""
    return "-" if v != v else f"{v:.2f}x"


def read_summary(path):
    """config -> row of summary.csv (ptc-bench-summary)."""
    with open(path, newline="") as f:
        return {r["config"]: r for r in csv.DictReader(f)}


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--build", default=os.path.join(ROOT, "build"))
    ap.add_argument("--threads", default="1,2", help="thread counts, comma-separated")
    ap.add_argument("--frames", default="0:5",
                    help="ptc bench --frames A:B (frame A is left out of the medians), or all: each scene's whole "
                         "animation, as ptc bench runs it without --frames")
    ap.add_argument("--min-triangles", type=int, default=500000)
    ap.add_argument("--scenes", default="", help="only these built-in scenes, comma-separated (default: all of the size)")
    ap.add_argument("--repeat", type=int, default=1)
    ap.add_argument("--single", action="store_true", help="single rays on both sides (default: packets on both)")
    ap.add_argument("--width", type=int, default=1024)
    ap.add_argument("--height", type=int, default=1024)
    ap.add_argument("--leaf-format", default=None, choices=("auto", "blocks", "tables"),
                    help="ptc bench --leaf-format F for every run (default: the bench's own, auto)")
    ap.add_argument("--shadow-order", default=None, choices=("pixel", "morton"),
                    help="ptc bench --shadow-order O for every run (default: the bench's own, pixel)")
    ap.add_argument("--max-count", default=None,
                    help="ptc bench --max-count N for every run, or N,M,...: a sweep, each value its own runs and rows "
                         "(default: the bench's own: the scene's cluster size, else 32)")
    ap.add_argument("--out", required=True)
    a = ap.parse_args()
    try:
        threads = [int(t) for t in a.threads.split(",")]
    except ValueError:
        usage(f"--threads: not a comma-separated list of integers: '{a.threads}'")
    if not threads or any(t < 1 for t in threads):
        usage("--threads: every count must be >= 1")
    cores = len(os.sched_getaffinity(0))
    over = [t for t in threads if t > cores]
    if over:  # (ptc bench refuses them: Embree would take fewer threads than ours)
        usage(f"--threads: {','.join(map(str, over))} above the {cores} threads this machine runs at once")
    if a.repeat < 1:
        usage("--repeat must be >= 1")
    # --max-count N[,M...]: each value its own runs and table rows (a sweep of the cluster size);
    # unset: the bench's own choice (the scene's cluster size, else 32), one set of runs ("").
    max_counts = [""]
    if a.max_count is not None:
        max_counts = a.max_count.split(",")
        for m in max_counts:
            if not (m.isdigit() and int(m) <= 1 << 20):
                usage(f"--max-count: '{m}' is not a whole number from 0 to {1 << 20}")
        if len(set(int(m) for m in max_counts)) != len(max_counts):
            usage(f"--max-count: '{a.max_count}' gives a value twice")
    if os.path.exists(a.out):
        usage(f"--out: '{a.out}' exists; give a new directory (nothing is overwritten)")
    ptc = os.path.join(a.build, "bin", "ptc")
    if not os.access(ptc, os.X_OK):
        usage(f"--build: no ptc at '{ptc}'")
    data = os.path.join(a.build, "data")

    # Only the scenes asked for are listed (building the large ones takes seconds each).
    names = a.scenes.split(",") if a.scenes else []
    listed = subprocess.run([ptc, "scenes", "--json", "--data-dir", data, *names], capture_output=True, text=True)
    if listed.returncode != 0:
        if names:
            why = listed.stderr.strip().splitlines()[-1] if listed.stderr.strip() else "refused by ptc scenes"
            usage(f"--scenes: {why.removeprefix('ptc: error: ')}")
        print(f"frames.py: ptc scenes failed: {listed.stderr.strip()}", file=sys.stderr)
        sys.exit(1)
    known = {s["name"]: s for s in json.loads(listed.stdout)["scenes"]}
    if a.scenes:
        scenes = names
        for s in scenes:
            if s not in known:
                usage(f"--scenes: '{s}' is not a built-in scene (ptc scenes)")
    else:
        scenes = [n for n, s in known.items()
                  if s["available"] and s["animated_parts"] > 0 and s["triangles"] >= a.min_triangles]
    if not scenes:
        usage(f"no built-in animated scene has {a.min_triangles} triangles or more")

    tmp = a.out + ".tmp"
    shutil.rmtree(tmp, ignore_errors=True)
    os.makedirs(os.path.join(tmp, "runs"))
    # Each (scene, --max-count value) pair: its runs, its table rows, its scaling rows.
    cells = [(s, mc) for s in scenes for mc in max_counts]
    commands, rows = [], []
    for rep in range(a.repeat):
        for t in threads:
            for s, mc in cells:
                d = os.path.join(tmp, "runs", f"r{rep}_t{t}_{s}" + (f"_m{mc}" if mc else ""))
                cmd = [ptc, "bench", s, "--data-dir", data, "--threads", str(t),
                       *([] if a.frames == "all" else ["--frames", a.frames]),
                       "--width", str(a.width), "--height", str(a.height), "--out", d]
                if not a.single:
                    cmd.append("--packets")
                if mc:
                    cmd += ["--max-count", mc]
                if a.leaf_format is not None:
                    cmd += ["--leaf-format", a.leaf_format]
                if a.shadow_order is not None:
                    cmd += ["--shadow-order", a.shadow_order]
                commands.append(cmd)
                print(f"== {' '.join(cmd)}", file=sys.stderr, flush=True)
                run = subprocess.run(cmd, capture_output=True, text=True)
                if run.returncode != 0:
                    print(f"frames.py: ptc bench {s} --threads {t} failed (exit {run.returncode}): "
                          f"{run.stderr.strip().splitlines()[-1] if run.stderr.strip() else ''}; outputs so far in {tmp}",
                          file=sys.stderr)
                    sys.exit(1)
                summary = read_summary(os.path.join(d, "summary.csv"))
                stages = stage_medians(os.path.join(d, "bench.csv"))
                # the cluster size the run used, and where it came from (--max-count, scene, default)
                params = json.load(open(os.path.join(d, "manifest.json")))["parameters"]
                for c in CONFIGS:
                    r = summary[c]
                    rows.append({"repeat": rep, "threads": t, "scene": s, "config": c, "sweep": mc,
                                 "max_count": params.get("max_count", ""),
                                 "max_count_from": params.get("max_count_from", ""),
                                 "whole_frame_ms": float(r["whole_frame_ms"]),
                                 "update_build_ms": float(r["update_build_ms"]), "trace_ms": float(r["trace_ms"]),
                                 "shadow_ms": float(r["shadow_ms"]), "mismatches": int(r["mismatches"]),
                                 "shadow_mismatches": int(r["shadow_mismatches"]),
                                 # the run's lowest per-frame ratio of Embree's whole frame to this
                                 # configuration's (ptc-bench-summary/3)
                                 # (1 for an Embree mode against itself; nan from a build before /3)
                                 "lowest_frame_vs_refit": float(r.get("whole_frame_speedup_lowest_vs_embree_refit", "nan")),
                                 "lowest_frame_vs_low": float(r.get("whole_frame_speedup_lowest_vs_embree_low", "nan")),
                                 **stages[c]})
    with open(os.path.join(tmp, "runs.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0].keys()), lineterminator="\n")
        w.writeheader()
        w.writerows(rows)

    def runs_of(t, s, mc, c):
        """The rows of configuration c's runs at t threads on scene s with --max-count value mc."""
        return [r for r in rows if r["threads"] == t and r["scene"] == s and r["sweep"] == mc and r["config"] == c]

    table = []
    for t in threads:
        for s, mc in cells:
            by = {c: runs_of(t, s, mc, c) for c in CONFIGS}
            med = {c: statistics.median(r["whole_frame_ms"] for r in by[c]) for c in CONFIGS}
            per_run = {p: [by[p][i]["whole_frame_ms"] / by["ours_clusters"][i]["whole_frame_ms"] for i in range(a.repeat)]
                       for p in ("embree_refit", "embree_low")}
            table.append({
                "threads": t, "scene": s, "triangles": known[s]["triangles"], "repeats": a.repeat,
                "max_count": by["ours_clusters"][0]["max_count"], "max_count_from": by["ours_clusters"][0]["max_count_from"],
                "ours_ms": med["ours_clusters"], "refit_ms": med["embree_refit"], "low_ms": med["embree_low"],
                "ours_update_build_ms": statistics.median(r["update_build_ms"] for r in by["ours_clusters"]),
                "vs_refit": med["embree_refit"] / med["ours_clusters"], "vs_low": med["embree_low"] / med["ours_clusters"],
                "vs_refit_min": min(per_run["embree_refit"]), "vs_refit_max": max(per_run["embree_refit"]),
                "vs_low_min": min(per_run["embree_low"]), "vs_low_max": max(per_run["embree_low"]),
                # the lowest single frame of any run (the medians above are over frames)
                "vs_refit_lowest_frame": lowest(r["lowest_frame_vs_refit"] for r in by["ours_clusters"]),
                "vs_low_lowest_frame": lowest(r["lowest_frame_vs_low"] for r in by["ours_clusters"]),
                "ours_mismatches": sum(r["mismatches"] + r["shadow_mismatches"] for r in by["ours_clusters"]),
            })
    with open(os.path.join(tmp, "frames.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(table[0].keys()), lineterminator="\n")
        w.writeheader()
        w.writerows(table)
    # How each stage scales: the first thread count against each other one (with the MaxCount the
    # runs used: the scene's own when no --max-count was given).
    by_mc = {(r["scene"], r["sweep"]): r["max_count"] for r in rows}
    scaling = []
    for t in threads[1:]:
        for s, mc in cells:
            for c in CONFIGS:
                def med(tt, k):
                    return statistics.median(r[k] for r in runs_of(tt, s, mc, c))
                for k in MEASURES:
                    if c != "ours_clusters" and k in STAGES:
                        continue  # (Embree's commit is one stage)
                    base, now = med(threads[0], k), med(t, k)
                    scaling.append({"scene": s, "sweep": mc, "config": c, "measure": k,
                                    "max_count": by_mc.get((s, mc), ""), "threads_base": threads[0], "threads": t,
                                    "base_ms": base, "ms": now,
                                    # (the overlap is time saved, not a stage: no speed-up; nor for a
                                    # stage that is 0 on one side: on one thread the cluster scene's
                                    # boxes are made in the leaf data, on more in the box pass)
                                    "speedup": base / now if now > 0 and base > 0 and k != "overlap_ms"
                                    else float("nan")})
    with open(os.path.join(tmp, "scaling.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=["scene", "sweep", "max_count", "config", "measure", "threads_base", "threads",
                                          "base_ms", "ms", "speedup"],
                           lineterminator="\n")
        w.writeheader()
        w.writerows(scaling)
    git = subprocess.run(["git", "-C", ROOT, "rev-parse", "HEAD"], capture_output=True, text=True).stdout.strip()
    json.dump({"schema": "ptc-frames/2", "argv": sys.argv, "commands": commands, "ptc_commit": git,
               "parameters": {"threads": threads, "frames": a.frames, "scenes": scenes, "repeat": a.repeat,
                              "packets": not a.single, "width": a.width, "height": a.height,
                              "max_count": [int(m) for m in max_counts] if a.max_count is not None else None,
                              "leaf_format": a.leaf_format, "shadow_order": a.shadow_order},
               "outputs": ["runs.csv", "frames.csv", "scaling.csv"]},
              open(os.path.join(tmp, "manifest.json"), "w"), indent=2)
    os.rename(tmp, a.out)

    print(f"ours_clusters' whole frame against Embree's, medians of {a.repeat} run(s) "
          f"({'packets' if not a.single else 'single rays'} on both sides; ratio > 1: ours is faster)")
    print("| T | scene | MaxCount | ours / REFIT / LOW ms | vs REFIT (runs) | vs LOW (runs) | lowest frame vs REFIT / LOW "
          "| ours mismatches |")
    print("|---|---|---|---|---|---|---|---|")
    for r in table:
        mc_cell = f"{r['max_count']}" + (f" ({r['max_count_from']})" if r["max_count_from"] not in ("", "--max-count") else "")
        print(f"| {r['threads']} | {r['scene']} | {mc_cell} | {r['ours_ms']:.1f} / {r['refit_ms']:.1f} / {r['low_ms']:.1f} | "
              f"{r['vs_refit']:.2f}x ({r['vs_refit_min']:.2f}-{r['vs_refit_max']:.2f}) | "
              f"{r['vs_low']:.2f}x ({r['vs_low_min']:.2f}-{r['vs_low_max']:.2f}) | "
              f"{ratio_cell(r['vs_refit_lowest_frame'])} / {ratio_cell(r['vs_low_lowest_frame'])} | {r['ours_mismatches']} |")
    if scaling:
        print(f"\nhow each stage scales (medians of {a.repeat} run(s), ms at T={threads[0]} -> T; speed-up in brackets)")
        cols = [(k, k.removesuffix("_ms")) for k in MEASURES]
        print("| T | scene | config | " + " | ".join(n for _, n in cols) + " |")
        print("|---|---|---|" + "---|" * len(cols))
        for t in threads[1:]:
            for s, mc in cells:
                for c in CONFIGS:
                    cell = {r["measure"]: r for r in scaling if r["threads"] == t and r["scene"] == s
                            and r["sweep"] == mc and r["config"] == c}
                    vals = []
                    for k, _ in cols:
                        r = cell.get(k)
                        vals.append("-" if r is None else
                                    f"{r['base_ms']:.2f} -> {r['ms']:.2f} ({r['speedup']:.2f}x)" if r["speedup"] == r["speedup"] else
                                    f"{r['base_ms']:.2f} -> {r['ms']:.2f}")
                    print(f"| {t} | {s}{f' (MaxCount {mc})' if mc else ''} | {c} | " + " | ".join(vals) + " |")
    print(f"wrote {a.out}/frames.csv, {a.out}/runs.csv, {a.out}/scaling.csv, {a.out}/manifest.json")


if __name__ == "__main__":
    main()
